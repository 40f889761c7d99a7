//! Resuming a run with other contact-solver settings ([`super::RunOptions::change_solver`], `ballast run
//! --resume --change-solver`).
//!
//! A plain `--resume` continues a run only from the scene it started with (the checkpoint keeps the CRC-32 of
//! its text). The settings of the per-step solve — the stopping rule, the sweep caps, the mixing, the solver —
//! choose how each step's contact problem is solved, not which problem it is: the bodies, laws, loads and time
//! step stay. A run may seat a sample at a cheap tolerance and go on at a tight one, or a study of the solver may
//! start several settings from one state of a long run, keeping the run's clock, its warm start and its files.
//!
//! The checkpoint also keeps [`model_crc32`]: the CRC-32 of the scene with the engine's solver keys
//! ([`crate::engine::Engine::SOLVER_KEYS`]: the NSCD engines' `[nscd]` keys of the solve) taken out. Resuming
//! with a scene whose text differs is accepted when that CRC is the same; the engine then takes the new settings
//! ([`crate::engine::Engine::change_solver`]), each change is appended to `solver_changes.csv` (step, time,
//! scene key, before, after) and a checkpoint with the new settings is written
//! at once, so that the run resumes from then on with the new scene alone.

use super::checkpoint::{check_writer, read_checked, Checkpoint};
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::io::layout;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The CRC-32 of the scene `text` with the `keys` (`table.key`, an engine's
/// [`crate::engine::Engine::SOLVER_KEYS`]) taken out (and a table with them if nothing else is left in it), written
/// back as TOML: comments, spacing and the order of the keys within a table do not count (a table is written
/// sorted), the order of the entries of an array of tables does. `None` if `text` is not a TOML table.
pub fn model_crc32(text: &str, keys: &[&str]) -> Option<u32> {
    let mut table: toml::Table = text.parse().ok()?;
    for (section, key) in keys.iter().filter_map(|k| k.split_once('.')) {
        if let Some(t) = table.get_mut(section).and_then(toml::Value::as_table_mut) {
            t.remove(key);
            if t.is_empty() {
                table.remove(section);
            }
        }
    }
    let model = toml::to_string(&table).ok()?;
    Some(super::checkpoint::crc32(model.as_bytes()))
}

/// Reads `DIR/checkpoint.json` of a run of engine `E` as [`Checkpoint::load`] does, but accepts a scene whose
/// text differs from the run's when its `model` CRC ([`model_crc32`] without `E`'s solver keys; `None` for a
/// system built in code) is the checkpoint's: `crc` is the CRC-32 of the scene's text.
///
/// # Errors
/// [`Error::Checkpoint`] as [`Checkpoint::load`], and naming what stops the change: a scene that differs in more
/// than its solver keys, a run of a system built in code, a checkpoint that does not record its model.
pub fn load<E: Engine, C: Serialize + DeserializeOwned>(
    dir: &Path,
    (crc, model): (u32, Option<u32>),
) -> Result<Checkpoint<E, C>> {
    let (path, cp): (_, Checkpoint<E, C>) = read_checked(dir)?;
    // The engine and the version as a plain resume checks them; the scene below.
    check_writer(&path, (&cp.engine, &cp.version), E::NAME)?;
    if cp.source_crc32 == crc {
        return Ok(cp);
    }
    let refuse = |why: &str| Err(Error::Checkpoint(format!("{}: change_solver: {why}", path.display())));
    match (model, cp.model_crc32) {
        (None, _) => refuse("a run of a system built in code resumes with its own settings only"),
        (Some(_), None) => refuse(
            "the checkpoint does not record its scene without the solver keys (written by an earlier build); \
             resume with the scene the run started from",
        ),
        (Some(m), Some(c)) if m != c => refuse(&format!(
            "the scene differs from the run's in more than the solver keys ({}); resume with the scene the run \
             started from, its solver keys changed",
            E::SOLVER_KEYS.join(", ")
        )),
        _ => Ok(cp),
    }
}

/// One setting a resumed run changed: a row of `solver_changes.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverChange {
    /// The engine's step when the change took effect (the steps after it use the new setting).
    pub step: u64,
    /// The engine's time then (s).
    pub time_s: f64,
    /// The scene key, e.g. `nscd.tolerance`.
    pub key: String,
    /// Its value before, as the scene writes it.
    pub before: String,
    /// Its value after.
    pub after: String,
}

/// Appends `changes` to `DIR/solver_changes.csv` (a header first if the file is new).
///
/// # Errors
/// A file that cannot be written, named.
pub fn record(out: &Path, changes: &[SolverChange]) -> Result<()> {
    crate::io::table::append_all(&out.join(layout::SOLVER_CHANGES), changes)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The NSCD engines' solver keys.
    const K: &[&str] = &crate::nscd::method::NlgsSettings::SCENE_KEYS;

    /// The solver keys do not count, every other key does; comments and spacing do not.
    #[test]
    fn the_model_crc_ignores_the_solver_keys_only() {
        let a = "[simulation]\ndt = 1e-3\n\n[nscd]\ntheta = 0.5\ntolerance = 1e-4\n";
        let b = "# a comment\n[simulation]\ndt   = 1e-3\n[nscd]\ntheta = 0.5\ntolerance = 1e-6\nanderson = 5\n";
        let c = "[simulation]\ndt = 1e-3\n\n[nscd]\ntheta = 1.0\ntolerance = 1e-4\n";
        let d = "[simulation]\ndt = 2e-3\n\n[nscd]\ntheta = 0.5\ntolerance = 1e-4\n";
        let e = "[simulation]\ndt = 1e-3\n";
        let f = "[simulation]\ndt = 1e-3\n[nscd]\ncriterion = 'quad'\ntolerance = 1e-5\n";
        assert_eq!(model_crc32(a, K), model_crc32(b, K));
        assert_ne!(model_crc32(a, K), model_crc32(c, K), "theta is the model's");
        assert_ne!(model_crc32(a, K), model_crc32(d, K));
        assert_eq!(
            model_crc32(e, K),
            model_crc32(f, K),
            "an [nscd] table of solver keys alone is the scene without one"
        );
        assert_eq!(model_crc32("not = [toml", K), None);
    }
}
