//! The run folder that the run loop ([`super::Runner`]) and the settlement driver
//! ([`crate::settlement::Accelerated`]) both drive: where a run's input came from and its record
//! ([`Source`]: `scene.toml` or `initial_state.json`, and `run.json`), the files an earlier run would leave
//! to pass for this one's, and the checks of a checkpoint to resume from. The file names are
//! [`crate::io::layout`]'s.

use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::io::layout::{self, CHECKPOINT};
use crate::io::{self, RunInfo};
use std::path::{Path, PathBuf};

/// Where the system of a run comes from.
#[derive(Debug, Clone)]
pub enum Source {
    /// A scene: its text (recorded as `scene.toml`).
    Scene {
        /// The text the run read (or its serialised form with a length override applied).
        text: String,
    },
    /// A system built in code: the serde form of its input (recorded as `initial_state.json`).
    Code {
        /// The JSON of the initial system and of the settings it runs with.
        json: String,
    },
}

impl Source {
    /// The CRC-32 of the recorded input, which a checkpoint keeps so that `--resume` refuses another input.
    pub fn crc32(&self) -> u32 {
        match self {
            Source::Scene { text } => super::checkpoint::crc32(text.as_bytes()),
            Source::Code { json } => super::checkpoint::crc32(json.as_bytes()),
        }
    }

    /// Writes the record of the input (`scene.toml` or `initial_state.json`) and `info` (`run.json`) into
    /// `out`.
    ///
    /// # Errors
    /// A failed write, naming the file.
    pub fn write_records(&self, out: &Path, info: &RunInfo) -> Result<()> {
        match self {
            Source::Scene { text } => io::write_text(out, layout::SCENE, text)?,
            Source::Code { json } => io::write_text(out, layout::INITIAL_STATE, json)?,
        };
        info.write(out)?;
        Ok(())
    }
}

/// Creates the folder `out` if needed and removes the files of `stale` that an earlier run left there (they
/// would pass for this run's).
///
/// # Errors
/// A folder that cannot be created or a file that cannot be removed, named.
pub fn prepare(out: &Path, stale: &[&str]) -> Result<()> {
    io::create_output_dir(out)?;
    for name in stale {
        io::remove_stale(out, name)?;
    }
    Ok(())
}

/// The path of the checkpoint in `out` to resume from.
///
/// # Errors
/// [`Error::Scene`] if there is none (nothing to continue).
pub fn checkpoint_to_resume(out: &Path) -> Result<PathBuf> {
    let path = out.join(CHECKPOINT);
    if path.is_file() {
        Ok(path)
    } else {
        Err(Error::Checkpoint(format!(
            "resume: no {CHECKPOINT} in '{}' (nothing to continue: start a fresh run)",
            out.display()
        )))
    }
}

/// `PATH: not a valid checkpoint: MSG`, the one-line refusal of a checkpoint at `path`.
pub fn invalid_checkpoint(path: &Path, msg: impl std::fmt::Display) -> Error {
    Error::Checkpoint(format!("{}: not a valid checkpoint: {msg}", path.display()))
}

/// Checks an engine state read from the checkpoint at `path` ([`Engine::check_state`]) and that it is a
/// state of the model `fresh`, built from the scene ([`Engine::check_same_model`]); `what` prefixes the
/// message (empty, or the part of the checkpoint that holds it).
///
/// # Errors
/// [`invalid_checkpoint`] with the engine's message.
pub fn check_resumed<E: Engine>(path: &Path, what: &str, sys: &E, fresh: &E) -> Result<()> {
    sys.check_state().map_err(|e| invalid_checkpoint(path, format!("{what}{e}")))?;
    sys.check_same_model(fresh).map_err(|e| invalid_checkpoint(path, format!("{what}{e}")))
}
