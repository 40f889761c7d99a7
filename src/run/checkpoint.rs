//! Checkpoints of a long run (`DIR/checkpoint.json`), from which `--resume`
//! continues a killed run with the same numbers as an uninterrupted one.
//!
//! A checkpoint holds the whole engine state (its serde form: warm-start
//! impulses, contact memory, neighbour list, clock; floats written so that they
//! read back bit for bit), the run's counters (steps, rows and bytes of
//! `series.csv` and `cycles.csv`, cycles of the positions file), its running
//! summary, the VTK snapshots listed so far and the per-cycle state. The file is
//! a first line `ballast-checkpoint crc32=XXXXXXXX` (the CRC-32 of the rest)
//! followed by the JSON; it is written to a temporary file and renamed, so a
//! kill during the write leaves the previous checkpoint intact.
//!
//! [`Checkpoint::load`] refuses, with one line starting `not a valid
//! checkpoint:`, a file that is truncated or edited (checksum), of another
//! engine, version or scene (the CRC-32 of the scene text is recorded), or whose
//! state does not hold together; the run loop then checks the state against the
//! scene and the counters against the files (`crate::run`).

use super::RunSummary;
use crate::error::{Error, Result};
use crate::io::io_error;
use crate::io::layout;
use crate::io::vtk::PvdCollection;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The first word of a checkpoint file.
const MAGIC: &str = "ballast-checkpoint";

/// Everything needed to continue a run of engine state `S` with per-cycle state `C`.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Checkpoint<S, C> {
    /// Crate version that wrote it.
    pub version: String,
    /// Engine name.
    pub engine: String,
    /// CRC-32 of the text of the scene the run started from (of the serde form
    /// of the initial system for a system built in code).
    pub source_crc32: u32,
    /// CRC-32 of that scene without its `[nscd]` solver keys ([`super::solver_change::model_crc32`]), which a run
    /// resumed with other solver settings must share; `None` for a system built in code (and in checkpoints
    /// written before it was kept).
    #[serde(default)]
    pub model_crc32: Option<u32>,
    /// Step of the engine when the run started (0 from a scene).
    pub first_step: u64,
    /// Steps made by the engine when the checkpoint was written.
    pub step: u64,
    /// Length of `series.csv` when the checkpoint was written (bytes); a resumed
    /// run truncates the file to it.
    pub series_bytes: u64,
    /// Data rows in those `series_bytes` bytes of `series.csv` (header excluded).
    pub series_rows: u64,
    /// CRC-32 of those `series_bytes` bytes of `series.csv`.
    pub series_crc32: u32,
    /// Length of `cycles.csv` when the checkpoint was written (bytes; 0 without
    /// `output.cycles`).
    pub cycles_bytes: u64,
    /// Data rows in those `cycles_bytes` bytes of `cycles.csv` (0 without cycles).
    pub cycles_rows: u64,
    /// CRC-32 of those `cycles_bytes` bytes of `cycles.csv` (0 without cycles).
    pub cycles_crc32: u32,
    /// Running summary of the run so far.
    pub summary: RunSummary,
    /// The engine state.
    pub system: S,
    /// Snapshots listed in `run.pvd` so far (empty without `--vtk-every`).
    pub snapshots: PvdCollection,
    /// The per-cycle state (with `output.cycles`).
    pub cycles: Option<C>,
    /// Cycles completed.
    pub cycles_done: u64,
    /// The followed bodies and their coordinates at the start (with
    /// `output.cycles.positions`).
    pub positions: Option<crate::engine::Configuration>,
    /// CRC-32 of the records of `cycle_displacements.npy` (0 without positions).
    pub positions_crc32: u32,
    /// The run's wall time ([`RunSummary::wall_time_s`]) when its last completed cycle ended, from which the cycle
    /// under way is timed in `cycle_times.csv` ([`super::cycle_times`]); `None` without cycles (and in
    /// checkpoints written before it was kept).
    #[serde(default)]
    pub cycle_wall_start_s: Option<f64>,
}

/// CRC-32 (IEEE) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// `PATH: not a valid checkpoint: MSG`, on one line: `msg` may quote the
/// file (a serde error quotes an unknown variant as it is), so its control
/// characters become `?` and it is cut to 200 characters.
fn invalid(path: &Path, msg: impl std::fmt::Display) -> Error {
    const MAX: usize = 200;
    let msg = msg.to_string();
    let mut short: String = msg.chars().take(MAX).map(|c| if c.is_control() { '?' } else { c }).collect();
    if msg.chars().count() > MAX {
        short.push('…');
    }
    Error::Checkpoint(format!("{}: not a valid checkpoint: {short}", path.display()))
}

/// Writes `value` as `DIR/checkpoint.json`, atomically: a first line
/// `ballast-checkpoint crc32=XXXXXXXX` (the CRC-32 of the rest), then its JSON.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_checked<T: Serialize>(dir: &Path, value: &T) -> Result<PathBuf> {
    let path = dir.join(layout::CHECKPOINT);
    let json = serde_json::to_string(value).map_err(|e| io_error(&path, "serialize", std::io::Error::other(e)))?;
    let text = format!("{MAGIC} crc32={:08x}\n{json}", crc32(json.as_bytes()));
    crate::io::write_atomic(&path, &text)?;
    Ok(path)
}

/// Reads `DIR/checkpoint.json` written by [`write_checked`], checking its first
/// line and checksum; returns its path and value.
///
/// # Errors
/// [`Error::Io`] if it cannot be read; [`Error::Checkpoint`] `PATH: not a valid
/// checkpoint: …` if it is not one.
pub fn read_checked<T: DeserializeOwned>(dir: &Path) -> Result<(PathBuf, T)> {
    let path = dir.join(layout::CHECKPOINT);
    let bytes = std::fs::read(&path).map_err(|e| io_error(&path, "read checkpoint", e))?;
    let text = String::from_utf8(bytes).map_err(|_| invalid(&path, "not UTF-8 text"))?;
    let (first, json) = text.split_once('\n').ok_or_else(|| invalid(&path, "no header line"))?;
    // The header exactly as written: 8 lower-case hex digits, nothing else.
    let crc = first
        .strip_prefix(MAGIC)
        .and_then(|s| s.strip_prefix(" crc32="))
        .filter(|s| s.len() == 8 && s.bytes().all(|b| b.is_ascii_digit() || (b'a'..=b'f').contains(&b)))
        .and_then(|s| u32::from_str_radix(s, 16).ok())
        .ok_or_else(|| invalid(&path, format!("the first line is not '{MAGIC} crc32=XXXXXXXX'")))?;
    if crc32(json.as_bytes()) != crc {
        return Err(invalid(&path, "checksum mismatch (the file was edited or cut short)"));
    }
    let value = serde_json::from_str(json).map_err(|e| invalid(&path, e))?;
    Ok((path, value))
}

/// Checks the engine and version a checkpoint at `path` was written by, and
/// the CRC-32 of the scene it belongs to.
///
/// # Errors
/// [`Error::Checkpoint`] naming what differs.
pub fn check_origin(path: &Path, (engine, version, source_crc32): (&str, &str, u32), want: (&str, u32)) -> Result<()> {
    check_writer(path, (engine, version), want.0)?;
    if source_crc32 != want.1 {
        return Err(Error::Checkpoint(format!(
            "{}: the checkpoint was written for another scene; start a fresh run instead of resuming",
            path.display()
        )));
    }
    Ok(())
}

/// Checks the engine and version a checkpoint at `path` was written by against the engine `want` and this
/// build ([`check_origin`] without the scene).
///
/// # Errors
/// [`Error::Checkpoint`] naming what differs.
pub fn check_writer(path: &Path, (engine, version): (&str, &str), want: &str) -> Result<()> {
    if engine != want {
        return Err(invalid(
            path,
            format!("written by the {} engine, the scene is for {want}", crate::error::clip(engine)),
        ));
    }
    let this = env!("CARGO_PKG_VERSION");
    if version != this {
        return Err(invalid(
            path,
            format!(
                "written by ballast {}, this is {this}; start a fresh run instead of resuming",
                crate::error::clip(version)
            ),
        ));
    }
    Ok(())
}

impl<S: Serialize + DeserializeOwned, C: Serialize + DeserializeOwned> Checkpoint<S, C> {
    /// Writes `DIR/checkpoint.json` atomically.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        write_checked(dir, self)
    }

    /// Reads `DIR/checkpoint.json` and checks its checksum, its engine `engine`,
    /// its version and that it belongs to the scene whose text has CRC-32 `source_crc32`.
    pub fn load(dir: &Path, engine: &str, source_crc32: u32) -> Result<Self> {
        let (path, cp): (PathBuf, Self) = read_checked(dir)?;
        check_origin(&path, (&cp.engine, &cp.version, cp.source_crc32), (engine, source_crc32))?;
        Ok(cp)
    }
}
