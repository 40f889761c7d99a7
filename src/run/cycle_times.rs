//! The wall-clock cost of each loading cycle of a run (`cycle_times.csv`, with `output.cycles`).
//!
//! `cycles.csv` holds the physics of each cycle, the same bytes on one thread or two and after any resume; the
//! time a cycle took is none of that, so it goes to a file of its own, written and flushed as each cycle ends:
//! the cost of a long settlement run can be read while it runs (the target is in seconds per cycle).
//!
//! A row is `cycle`, `wall_s` (wall-clock seconds from the end of the cycle before, checkpoint writes and
//! outputs included) and `threads` (those the contact solve or force evaluation used,
//! [`crate::engine::Engine::threads_used`]). A checkpoint keeps the run's wall clock at the last cycle end
//! ([`super::Checkpoint::cycle_wall_start_s`]), so a cycle that a kill and `--resume` split counts its time
//! before the checkpoint and after the resume: the steps made again after the checkpoint are counted once, as
//! the resumed run made them. The rows of cycles after the checkpoint are dropped on resuming, as in
//! `cycles.csv`. The first cycle resumed from a checkpoint written before this file existed has no `wall_s`.

use crate::error::Result;
use crate::io::layout;
use crate::io::table;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// A row of `cycle_times.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CycleTime {
    /// The cycle (from 1).
    pub cycle: u64,
    /// Wall-clock seconds the run spent on it (empty when unknown: the first cycle resumed from a checkpoint of
    /// an earlier build).
    pub wall_s: Option<f64>,
    /// Threads the run used then.
    pub threads: usize,
}

/// The writer of `cycle_times.csv` and the run's wall clock at the last cycle end.
#[derive(Debug, Clone)]
pub struct CycleTimes {
    path: PathBuf,
    /// The run's wall time (s, counted over its invocations as [`super::RunSummary::wall_time_s`]) when the last
    /// completed cycle ended; `None` if unknown.
    start_wall_s: Option<f64>,
    /// Threads the run uses.
    threads: usize,
}

impl CycleTimes {
    /// A new table in `out` (the caller removes an earlier run's file: rows are appended), the first cycle
    /// starting at wall time 0.
    pub fn create(out: &Path) -> Self {
        Self { path: out.join(layout::CYCLE_TIMES), start_wall_s: Some(0.0), threads: 1 }
    }

    /// The table of a run resumed after `cycles_done` cycles, whose last cycle ended at the run's wall time
    /// `start_wall_s`: rows of later cycles (written after the checkpoint) are dropped.
    ///
    /// # Errors
    /// A file that cannot be read or written, named.
    pub fn resume(out: &Path, cycles_done: u64, start_wall_s: Option<f64>) -> Result<Self> {
        let path = out.join(layout::CYCLE_TIMES);
        if path.is_file() {
            let rows: Vec<CycleTime> = table::read_named(&path)?;
            if rows.iter().any(|r| r.cycle > cycles_done) {
                let kept: Vec<CycleTime> = rows.into_iter().filter(|r| r.cycle <= cycles_done).collect();
                table::write_all(&path, &kept)?;
            }
        }
        Ok(Self { path, start_wall_s, threads: 1 })
    }

    /// Sets the threads the rows record.
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads;
    }

    /// The run's wall time when the last completed cycle ended (s), for a checkpoint.
    pub fn start_wall_s(&self) -> Option<f64> {
        self.start_wall_s
    }

    /// Records that `cycle` ended at the run's wall time `wall_s` (a row, flushed), which starts the next.
    ///
    /// # Errors
    /// A file that cannot be written, named.
    pub fn record(&mut self, cycle: u64, wall_s: f64) -> Result<()> {
        let row = CycleTime { cycle, wall_s: self.start_wall_s.map(|s| (wall_s - s).max(0.0)), threads: self.threads };
        table::append_all(&self.path, &[row])?;
        self.start_wall_s = Some(wall_s);
        Ok(())
    }
}

/// The rows of `cycle_times.csv` in the run folder `dir`.
///
/// # Errors
/// A missing or unreadable file, named.
pub fn read(dir: &Path) -> Result<Vec<CycleTime>> {
    table::read_named(&dir.join(layout::CYCLE_TIMES))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rows count from the last cycle end; a resume drops the rows after its checkpoint and counts the cycle
    /// under way from the wall time the checkpoint kept.
    #[test]
    fn rows_count_from_the_last_cycle_end_and_survive_a_resume() {
        let dir = std::env::temp_dir().join(format!("ballast-cycle-times-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let _ = std::fs::remove_file(dir.join(layout::CYCLE_TIMES));
        let mut t = CycleTimes::create(&dir);
        t.set_threads(2);
        t.record(1, 3.0).unwrap();
        t.record(2, 7.5).unwrap();
        // A checkpoint at wall 9 keeps 7.5; the run goes on to cycle 3 at 12, then is killed.
        let kept = t.start_wall_s();
        t.record(3, 12.0).unwrap();
        let mut r = CycleTimes::resume(&dir, 2, kept).unwrap();
        // Resumed at the checkpoint's wall 9 (summary.wall_time_s), cycle 3 ends again at 9 + 4.
        r.record(3, 13.0).unwrap();
        let rows = read(&dir).unwrap();
        let got: Vec<(u64, Option<f64>, usize)> = rows.iter().map(|r| (r.cycle, r.wall_s, r.threads)).collect();
        assert_eq!(got, vec![(1, Some(3.0), 2), (2, Some(4.5), 2), (3, Some(5.5), 1)]);
        // Unknown start (a checkpoint of an earlier build): an empty field, then the next cycle counts again.
        let mut r = CycleTimes::resume(&dir, 3, None).unwrap();
        r.record(4, 20.0).unwrap();
        r.record(5, 21.0).unwrap();
        let rows = read(&dir).unwrap();
        assert_eq!((rows[3].wall_s, rows[4].wall_s), (None, Some(1.0)));
        let _ = std::fs::remove_dir_all(&dir);
    }
}
