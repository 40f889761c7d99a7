//! `series.csv`: one row of [`StepStats`] per output step.
//!
//! Columns ([`SERIES_HEADER`], units in the names): `time_s`, `kinetic_energy_J`,
//! `contacts`, `active_contacts`, `iterations` (NLGS sweeps), `criterion` (final
//! value of the convergence norm), `converged` (1 or 0), `mean_overlap_m` (mean
//! over the active contacts), `max_overlap_m`, `total_overlap_m` (sum over the
//! contacts: the cumulated interpenetration of Saussine et al. 2006, Fig. 2). Floats are written with `{:e}`, the shortest text that
//! reads back to the same `f64`.
//!
//! The writer itself (buffering, cutting back on `--resume`, counting rows) does
//! not depend on the columns: [`SeriesWriter::with_header`] and
//! [`SeriesWriter::write_row`] serve the MD series too ([`super::md_series`]).

use super::io_error;
use crate::error::Result;
use crate::nscd::StepStats;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Header line of `series.csv` (without the newline).
pub const SERIES_HEADER: &str =
    "time_s,kinetic_energy_J,contacts,active_contacts,iterations,criterion,converged,mean_overlap_m,max_overlap_m,\
total_overlap_m";

/// Buffered writer of `series.csv`.
#[derive(Debug)]
pub struct SeriesWriter {
    path: PathBuf,
    out: BufWriter<File>,
    rows: u64,
}

impl SeriesWriter {
    /// Creates (truncates) the file at `path` and writes the header.
    pub fn create(path: &Path) -> Result<Self> {
        Self::with_header(path, SERIES_HEADER)
    }

    /// Creates (truncates) the file at `path` and writes the header line `header`
    /// (without its newline), for rows written with [`SeriesWriter::write_row`].
    pub fn with_header(path: &Path, header: &str) -> Result<Self> {
        let file = File::create(path).map_err(|e| io_error(path, "create", e))?;
        let mut w = Self { path: path.to_path_buf(), out: BufWriter::new(file), rows: 0 };
        writeln!(w.out, "{header}").map_err(|e| io_error(path, "write", e))?;
        Ok(w)
    }

    /// Appends one row given as its text (without the newline).
    pub fn write_row(&mut self, row: &str) -> Result<()> {
        writeln!(self.out, "{row}").map_err(|e| io_error(&self.path, "write", e))?;
        self.rows += 1;
        Ok(())
    }

    /// Reopens `series.csv` to continue a run from a checkpoint: the file is cut
    /// back to `bytes` (its length when the checkpoint was written, so rows of
    /// the killed run after it disappear) and `rows` rows are counted as written.
    pub fn resume(path: &Path, bytes: u64, rows: u64) -> Result<Self> {
        let file = std::fs::OpenOptions::new().write(true).open(path).map_err(|e| io_error(path, "open", e))?;
        let len = file.metadata().map_err(|e| io_error(path, "read", e))?.len();
        if len < bytes {
            return Err(crate::Error::Io(std::io::Error::other(format!(
                "'{}' is shorter ({len} bytes) than at the checkpoint ({bytes} bytes)",
                path.display()
            ))));
        }
        file.set_len(bytes).map_err(|e| io_error(path, "truncate", e))?;
        let mut out = BufWriter::new(file);
        use std::io::Seek;
        out.seek(std::io::SeekFrom::End(0)).map_err(|e| io_error(path, "seek", e))?;
        Ok(Self { path: path.to_path_buf(), out, rows })
    }

    /// Flushes what is buffered and returns the length of the file (bytes), for a checkpoint.
    pub fn sync(&mut self) -> Result<u64> {
        self.out.flush().map_err(|e| io_error(&self.path, "write", e))?;
        let f = self.out.get_ref();
        f.sync_data().map_err(|e| io_error(&self.path, "sync", e))?;
        Ok(f.metadata().map_err(|e| io_error(&self.path, "read", e))?.len())
    }

    /// Appends the row of one step.
    pub fn write(&mut self, s: &StepStats) -> Result<()> {
        writeln!(
            self.out,
            "{:e},{:e},{},{},{},{:e},{},{:e},{:e},{:e}",
            s.time,
            s.kinetic_energy,
            s.contacts,
            s.active_contacts,
            s.iterations,
            s.criterion,
            u8::from(s.converged),
            s.mean_overlap,
            s.max_overlap,
            s.total_overlap
        )
        .map_err(|e| io_error(&self.path, "write", e))?;
        self.rows += 1;
        Ok(())
    }

    /// Number of rows written (header excluded).
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Flushes the file.
    pub fn finish(mut self) -> Result<()> {
        self.out.flush().map_err(|e| io_error(&self.path, "write", e))
    }
}

/// One row of `series.csv`, as read back by [`read`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
pub struct SeriesRow {
    pub time_s: f64,
    #[serde(rename = "kinetic_energy_J")]
    pub kinetic_energy_j: f64,
    pub contacts: usize,
    pub active_contacts: usize,
    pub iterations: usize,
    pub criterion: f64,
    pub converged: u8,
    pub mean_overlap_m: f64,
    pub max_overlap_m: f64,
    pub total_overlap_m: f64,
}

/// Reads a `series.csv` written by [`SeriesWriter`]; the error names the file and the row.
pub fn read(path: &Path) -> Result<Vec<SeriesRow>> {
    super::read_csv(path)
}
