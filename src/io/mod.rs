//! File formats: CSV tables through serde rows ([`table`]), JSON, atomic text writes, the VTK writer
//! ([`vtk`]), figures as PNG + SVG ([`figures`]), and the layout of a run folder ([`layout`]: every file
//! name a run writes). Every I/O error names the file it happened on.
//!
//! Not yet moved out (issue 33): the engines' VTK mapping still lives in [`vtk`].

pub mod figures;
pub mod layout;
pub mod table;
pub mod vtk;

use crate::error::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

pub use table::TableWriter;

/// An I/O error with the path it happened on in its message.
pub fn io_error(path: &Path, what: &str, e: std::io::Error) -> Error {
    Error::Io(std::io::Error::new(e.kind(), format!("cannot {what} '{}': {e}", path.display())))
}

/// Creates the output directory `dir` (and its parents) if needed.
pub fn create_output_dir(dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| io_error(dir, "create output directory", e))
}

/// Removes `dir/name` if it exists.
pub fn remove_stale(dir: &Path, name: &str) -> Result<()> {
    let path = dir.join(name);
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(io_error(&path, "remove", e)),
        _ => Ok(()),
    }
}

/// Writes `text` to `dir/name`, returning the path.
pub fn write_text(dir: &Path, name: &str, text: &str) -> Result<PathBuf> {
    let path = dir.join(name);
    std::fs::write(&path, text).map_err(|e| io_error(&path, "write", e))?;
    Ok(path)
}

/// Writes `text` to `path` through a temporary file `path.tmp` renamed over it, so a
/// reader (or a run killed during the write) never sees a half-written file.
pub fn write_atomic(path: &Path, text: &str) -> Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".tmp");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text).map_err(|e| io_error(&tmp, "write", e))?;
    std::fs::rename(&tmp, path).map_err(|e| io_error(path, "write", e))
}

/// Contents of `run.json`: what is needed to reproduce a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RunInfo {
    /// Random seed of the scene.
    pub seed: u64,
    /// Engine name (`"nscd"`, `"md"` or `"md2d"`, the planar MD engine).
    pub engine: String,
    /// Version of `ballast` that made the run.
    pub version: String,
    /// Number of time steps asked for, `round(duration / dt)`.
    pub steps: u64,
    /// Time step (s).
    pub dt: f64,
    /// What the scene resolved to that the scene does not say (the planar MD
    /// engine: its stiffness and time step, [`crate::scene::SoftModelInfo`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<serde_json::Value>,
}

impl RunInfo {
    /// The record of a run on `engine` made by this version of `ballast`: `seed`, `steps` of `dt` (s), the
    /// resolved `model` if any.
    pub fn new(engine: &str, seed: u64, (steps, dt): (u64, f64), model: Option<serde_json::Value>) -> Self {
        Self { seed, engine: engine.into(), version: env!("CARGO_PKG_VERSION").into(), steps, dt, model }
    }

    /// Writes `dir/run.json`.
    pub fn write(&self, dir: &Path) -> Result<PathBuf> {
        write_json(&dir.join("run.json"), self)
    }
}

/// Reads the rows of a CSV file with a header into `T` (columns by name); the
/// error names the file and the line.
pub fn read_csv<T: serde::de::DeserializeOwned>(path: &Path) -> Result<Vec<T>> {
    table::read_named(path)
}

/// Writes `value` as pretty JSON (with a final newline) to `path`.
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<PathBuf> {
    let mut text =
        serde_json::to_string_pretty(value).map_err(|e| io_error(path, "serialize", std::io::Error::other(e)))?;
    text.push('\n');
    std::fs::write(path, text).map_err(|e| io_error(path, "write", e))?;
    Ok(path.to_path_buf())
}

/// Reads the JSON file at `path` into `T`; the error names the file.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| io_error(path, "read", e))?;
    serde_json::from_str(&text).map_err(|e| io_error(path, "read", std::io::Error::other(e)))
}
