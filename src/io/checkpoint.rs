//! Checkpoints of a long run (`DIR/checkpoint.json`), so that `ballast run --resume`
//! continues a killed run with the same numbers as an uninterrupted one.
//!
//! A checkpoint holds the whole engine state (the serde form of
//! [`crate::nscd::System`], warm-start impulses and clock included, or of
//! [`crate::md::MdSystem`], contact memory and neighbour list included; floats are
//! written so that they read back bit for bit), the text of the scene it was
//! started from (a resume with another scene is refused), the length of
//! `series.csv` at that moment (rows written after it by the killed run are cut
//! off) and the running summary of the run. It is written to a temporary file and
//! renamed, so a kill during the write leaves the previous checkpoint intact.

use super::io_error;
use super::RunSummary;
use crate::error::{Error, Result};
use crate::nscd::System;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// File name of the checkpoint in the output directory.
pub const CHECKPOINT_FILE: &str = "checkpoint.json";

/// Everything needed to continue a run: of the NSCD engine by default, of the MD
/// engine as `Checkpoint<MdSystem, MdRunSummary>`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint<S = System, R = RunSummary> {
    /// Crate version that wrote it.
    pub version: String,
    /// Text of the scene file the run started from.
    pub scene: String,
    /// Length of `series.csv` (bytes) and rows in it when the checkpoint was written.
    pub series_bytes: u64,
    pub series_rows: u64,
    /// Running summary of the run so far.
    pub summary: R,
    /// The engine state.
    pub system: S,
    /// Snapshots listed in `run.pvd` so far (empty without `--vtk-every`).
    #[serde(default)]
    pub snapshots: super::vtk::PvdCollection,
    /// The per-cycle recorder (with `output.cycles`).
    #[serde(default)]
    pub cycles: Option<super::cycles::CycleRecorder>,
}

impl<S: Serialize + DeserializeOwned, R: Serialize + DeserializeOwned> Checkpoint<S, R> {
    /// Writes `DIR/checkpoint.json` atomically.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        let path = dir.join(CHECKPOINT_FILE);
        let text = serde_json::to_string(self).map_err(|e| Error::Io(std::io::Error::other(e)))?;
        super::write_atomic(&path, &text)?;
        Ok(path)
    }

    /// Reads `DIR/checkpoint.json` and checks that it belongs to `scene_text`.
    pub fn load(dir: &Path, scene_text: &str) -> Result<Self> {
        let path = dir.join(CHECKPOINT_FILE);
        let text = std::fs::read_to_string(&path).map_err(|e| io_error(&path, "read checkpoint", e))?;
        let cp: Self = serde_json::from_str(&text)
            .map_err(|e| Error::Scene(format!("{}: not a valid checkpoint: {e}", path.display())))?;
        if cp.scene != scene_text {
            return Err(Error::Scene(format!(
                "{}: the checkpoint was written for another scene; run without --resume to start again",
                path.display()
            )));
        }
        Ok(cp)
    }
}
