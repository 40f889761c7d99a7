//! Resuming a run with other contact-solver settings ([`super::RunOptions::change_solver`], `ballast run
//! --resume --change-solver`).
//!
//! A plain `--resume` continues a run only from the scene it started with (the checkpoint keeps the CRC-32 of
//! its text). The settings of the per-step solve — the stopping rule, the sweep caps, the mixing, the solver —
//! choose how each step's contact problem is solved, not which problem it is: the bodies, laws, loads and time
//! step stay. A run may seat a sample at a cheap tolerance and go on at a tight one, or a study of the solver may
//! start several settings from one state of a long run, keeping the run's clock, its warm start and its files.
//!
//! The checkpoint also keeps [`model_crc32`]: the CRC-32 of the scene with the [`SOLVER_KEYS`] taken out of its
//! `[nscd]` table. Resuming with a scene whose text differs is accepted when that CRC is the same; the engine then
//! takes the new settings ([`crate::engine::Engine::change_solver`]), each change is appended to
//! `solver_changes.csv` (step, time, scene key, before, after) and a checkpoint with the new settings is written
//! at once, so that the run resumes from then on with the new scene alone.

use super::checkpoint::{check_writer, read_checked, Checkpoint};
use crate::error::{Error, Result};
use crate::io::layout;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The `[nscd]` keys of the per-step solve (`docs/scene-format.md`): the ones a resumed run may change.
pub const SOLVER_KEYS: [&str; 12] = [
    "criterion",
    "tolerance",
    "min_iterations",
    "max_iterations",
    "max_factor",
    "symmetric",
    "relaxation",
    "anderson",
    "measure",
    "solver",
    "on_stall",
    "stall_max_iterations",
];

/// The CRC-32 of the scene `text` with the [`SOLVER_KEYS`] taken out of its `[nscd]` table (and the table with
/// them if nothing else is in it), written back as TOML: comments and spacing do not count, the order of the keys
/// does. `None` if `text` is not a TOML table.
pub fn model_crc32(text: &str) -> Option<u32> {
    let mut table: toml::Table = text.parse().ok()?;
    if let Some(nscd) = table.get_mut("nscd").and_then(toml::Value::as_table_mut) {
        for key in SOLVER_KEYS {
            nscd.remove(key);
        }
        if nscd.is_empty() {
            table.remove("nscd");
        }
    }
    let model = toml::to_string(&table).ok()?;
    Some(super::checkpoint::crc32(model.as_bytes()))
}

/// Reads `DIR/checkpoint.json` as [`Checkpoint::load`] does, but accepts a scene whose text differs from the
/// run's when its `model` CRC ([`model_crc32`]; `None` for a system built in code) is the checkpoint's: `crc` is
/// the CRC-32 of the scene's text.
///
/// # Errors
/// [`Error::Checkpoint`] as [`Checkpoint::load`], and naming what stops the change: a scene that differs in more
/// than its solver keys, a run of a system built in code, a checkpoint that does not record its model.
pub fn load<S: Serialize + DeserializeOwned, C: Serialize + DeserializeOwned>(
    dir: &Path,
    engine: &str,
    (crc, model): (u32, Option<u32>),
) -> Result<Checkpoint<S, C>> {
    let (path, cp): (_, Checkpoint<S, C>) = read_checked(dir)?;
    // The engine and the version as a plain resume checks them; the scene below.
    check_writer(&path, (&cp.engine, &cp.version), engine)?;
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
            "the scene differs from the run's in more than the [nscd] solver keys ({}); resume with the scene \
             the run started from, its solver keys changed",
            SOLVER_KEYS.join(", ")
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

    /// The solver keys do not count, every other key does; comments and spacing do not.
    #[test]
    fn the_model_crc_ignores_the_solver_keys_only() {
        let a = "[simulation]\ndt = 1e-3\n\n[nscd]\ntheta = 0.5\ntolerance = 1e-4\n";
        let b = "# a comment\n[simulation]\ndt   = 1e-3\n[nscd]\ntheta = 0.5\ntolerance = 1e-6\nanderson = 5\n";
        let c = "[simulation]\ndt = 1e-3\n\n[nscd]\ntheta = 1.0\ntolerance = 1e-4\n";
        let d = "[simulation]\ndt = 2e-3\n\n[nscd]\ntheta = 0.5\ntolerance = 1e-4\n";
        let e = "[simulation]\ndt = 1e-3\n";
        let f = "[simulation]\ndt = 1e-3\n[nscd]\ncriterion = 'quad'\ntolerance = 1e-5\n";
        assert_eq!(model_crc32(a), model_crc32(b));
        assert_ne!(model_crc32(a), model_crc32(c), "theta is the model's");
        assert_ne!(model_crc32(a), model_crc32(d));
        assert_eq!(model_crc32(e), model_crc32(f), "an [nscd] table of solver keys alone is the scene without one");
        assert_eq!(model_crc32("not = [toml"), None);
    }
}
