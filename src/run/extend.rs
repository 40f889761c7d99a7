//! Resuming a run past the end its scene set ([`super::RunOptions::extend`], `ballast run --resume --extend`).
//!
//! A settlement run is often judged as it goes: a researcher runs 200 cycles, reads the curve, and wants 800
//! more. A new run from `final_scene.toml` would start cold (no warm start: its first steps cost more and are
//! not the steps the longer run would have made), count its cycles from 1 and measure settlement from a new
//! origin. Extending the run instead goes on from its checkpoint with the same numbers as a run that had asked
//! for the longer duration from the start: `series.csv`, `cycles.csv`, the positions and `final.json` are those
//! of the uninterrupted run (tested in `tests/run_loop.rs`).
//!
//! The duration is not part of the model: the steps made do not depend on where the run will stop. So the
//! scene may differ from the run's in `[simulation] duration` alone (a `length` override, `--steps` or
//! `--duration`, is such a change), and with [`super::RunOptions::change_solver`] also in the solver keys. The
//! run's scene is its copy in the folder (`scene.toml`, which must still be the text the checkpoint was
//! written for: its CRC-32); both are compared as TOML tables without those keys ([`model_crc32`]), so
//! comments, spacing and the order of keys do not count. The new end may not come before the steps already
//! made.
//!
//! A finished run removes its checkpoint; one run with [`super::RunOptions::keep_checkpoint`] keeps a
//! checkpoint of its last step, written before the last off-grid row of `series.csv`, so that an extended run
//! writes the rows the longer run would have.

use super::checkpoint::{check_writer, read_checked, Checkpoint};
use super::solver_change::model_crc32;
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::io::layout;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

/// The scene key that sets a run's length.
pub const LENGTH_KEY: &str = "simulation.duration";

/// Reads `DIR/checkpoint.json` of a run of engine `E` as [`Checkpoint::load`] does, but accepts a scene `text`
/// that differs from the run's (its copy `DIR/scene.toml`) in [`LENGTH_KEY`] and, with `change_solver`, in
/// `E`'s solver keys ([`crate::engine::Engine::SOLVER_KEYS`]).
///
/// # Errors
/// [`Error::Checkpoint`] as [`Checkpoint::load`], and naming what stops the extension: a run folder without
/// `scene.toml` or whose copy is not the text the checkpoint was written for, a scene that differs in more
/// than those keys.
pub fn load<E: Engine, C: Serialize + DeserializeOwned>(
    dir: &Path,
    text: &str,
    change_solver: bool,
) -> Result<Checkpoint<E, C>> {
    let (path, cp): (_, Checkpoint<E, C>) = read_checked(dir)?;
    check_writer(&path, (&cp.engine, &cp.version), E::NAME)?;
    if cp.source_crc32 == super::checkpoint::crc32(text.as_bytes()) {
        return Ok(cp);
    }
    let refuse = |why: String| Err(Error::Checkpoint(format!("{}: extend: {why}", path.display())));
    let copy = dir.join(layout::SCENE);
    let Ok(run_text) = std::fs::read_to_string(&copy) else {
        return refuse(format!("no readable {} beside it: the run's scene is unknown", layout::SCENE));
    };
    if super::checkpoint::crc32(run_text.as_bytes()) != cp.source_crc32 {
        return refuse(format!(
            "{} is not the scene the checkpoint was written for (edited or replaced); resume with the scene the \
             run started from",
            layout::SCENE
        ));
    }
    let mut keys = vec![LENGTH_KEY];
    if change_solver {
        keys.extend_from_slice(E::SOLVER_KEYS);
    }
    match (model_crc32(&run_text, &keys), model_crc32(text, &keys)) {
        (Some(a), Some(b)) if a == b => Ok(cp),
        _ => refuse(format!(
            "the scene differs from the run's ({}) in more than {}; resume with the run's scene, only those keys \
             changed",
            layout::SCENE,
            keys.join(", ")
        )),
    }
}

/// `err`, a plain resume's refusal of the scene `text` as another scene, with a hint when `text` differs from the
/// run's copy in `dir` (`scene.toml`) only in [`LENGTH_KEY`]: an extension is what was meant.
pub fn hint(err: Error, dir: &Path, text: &str) -> Error {
    let Error::Checkpoint(msg) = &err else { return err };
    if !msg.contains("another scene") {
        return err;
    }
    let run = std::fs::read_to_string(dir.join(layout::SCENE)).ok();
    let run_model = run.and_then(|t| model_crc32(&t, &[LENGTH_KEY]));
    match (run_model, model_crc32(text, &[LENGTH_KEY])) {
        (Some(a), Some(b)) if a == b => Error::Checkpoint(format!(
            "{msg} (it differs from the run's only in {LENGTH_KEY}: resume with extend to run it longer)"
        )),
        _ => err,
    }
}

/// The refusal of an extension whose new end (`end` steps of the engine) comes before the step `step` the run has
/// reached.
pub fn too_short(path: &Path, (step, end): (u64, u64), dt: f64) -> Error {
    Error::Checkpoint(format!(
        "{}: extend: {LENGTH_KEY} ends the run at step {end} (t = {} s), before the step it has reached ({step}, \
         t = {} s); ask for a longer run",
        path.display(),
        end as f64 * dt,
        step as f64 * dt
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The duration does not count, nor comments, spacing or the order of keys within a table; any other key
    /// and the order of the entries of an array of tables do.
    #[test]
    fn only_the_duration_is_left_out() {
        let keys = [LENGTH_KEY];
        let a = "[simulation]\ndt = 1e-3\nduration = 1.0\n\n[[body]]\nname = 'a'\n[[body]]\nname = 'b'\n";
        let b = "# longer\n[simulation]\nduration = 5.0\ndt   = 0.001\n[[body]]\nname = 'a'\n[[body]]\nname = 'b'\n";
        let c = "[simulation]\ndt = 2e-3\nduration = 1.0\n\n[[body]]\nname = 'a'\n[[body]]\nname = 'b'\n";
        let d = "[simulation]\ndt = 1e-3\nduration = 1.0\n\n[[body]]\nname = 'b'\n[[body]]\nname = 'a'\n";
        assert_eq!(model_crc32(a, &keys), model_crc32(b, &keys));
        assert_ne!(model_crc32(a, &keys), model_crc32(c, &keys));
        assert_ne!(model_crc32(a, &keys), model_crc32(d, &keys));
    }
}
