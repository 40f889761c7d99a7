//! `cycles.csv`: per-cycle statistics of a cyclically loaded run (Saussine et al.
//! 2006, §4: settlement of the sleeper, Fig. 6, 11, 12; mean grain velocity, Fig. 7).
//!
//! A cycle lasts `1/f` from t = 0. For each cycle, with `y` the vertical position
//! of the followed body's centre of mass and `y0` its value at the start of the run:
//! - `settlement_mean_m`: `y0 − ⟨y⟩`, the mean over the steps of the cycle (m,
//!   positive when the body has gone down);
//! - `settlement_at_min_load_m`: `y0 − y` at the step of the cycle where the
//!   magnitude of the body's external load is smallest (m);
//! - `mean_grain_speed_m_s`: the speed `|v|` of the other non-fixed bodies,
//!   averaged over bodies and over the steps of the cycle (m/s);
//! - `contacts`, `iterations`: means per step; `max_overlap_m`: the largest over the cycle.
//!
//! The recorder is plain data, kept in checkpoints so that a resumed run writes
//! the same rows.

use super::io_error;
use crate::error::Result;
use crate::nscd::{StepStats, System};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

/// Header line of `cycles.csv` (without the newline).
pub const CYCLES_HEADER: &str = "cycle,time_s,settlement_mean_m,settlement_at_min_load_m,mean_grain_speed_m_s,\
contacts,iterations,max_overlap_m";

/// Accumulates the steps of the current cycle and emits one row per cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CycleRecorder {
    /// Loading frequency (Hz).
    pub frequency: f64,
    /// Index of the followed body.
    pub body: usize,
    /// Its initial vertical position (m).
    pub y0: f64,
    /// Cycles completed.
    pub cycle: u64,
    steps: u64,
    sum_y: f64,
    min_load: f64,
    y_at_min_load: f64,
    sum_speed: f64,
    sum_contacts: f64,
    sum_iterations: f64,
    max_overlap: f64,
    /// Positions of every body at the end of the first cycle (for the
    /// displacement field from cycle 1 to the end of the run).
    #[serde(default)]
    pub first_cycle_q: Option<Vec<[f64; 3]>>,
}

impl CycleRecorder {
    /// Starts following body `body` of `sys` for cycles of `frequency` (Hz).
    pub fn new(sys: &System, frequency: f64, body: usize) -> Self {
        Self {
            frequency,
            body,
            y0: sys.bodies.q[body][1],
            cycle: 0,
            steps: 0,
            sum_y: 0.0,
            min_load: f64::INFINITY,
            y_at_min_load: 0.0,
            sum_speed: 0.0,
            sum_contacts: 0.0,
            sum_iterations: 0.0,
            max_overlap: 0.0,
            first_cycle_q: None,
        }
    }

    /// Records the step just made; returns the row of the cycle it completes, if any.
    pub fn record(&mut self, sys: &System, stats: &StepStats) -> Option<String> {
        let y = sys.bodies.q[self.body][1];
        let load: [f64; 2] = sys.bodies.info[self.body].loads.iter().fold([0.0, 0.0], |f, l| {
            let g = l.at(sys.time);
            [f[0] + g[0], f[1] + g[1]]
        });
        let magnitude = load[0].hypot(load[1]);
        if magnitude < self.min_load {
            self.min_load = magnitude;
            self.y_at_min_load = y;
        }
        self.steps += 1;
        self.sum_y += y;
        let (mut speed, mut n) = (0.0, 0usize);
        for (i, (info, u)) in sys.bodies.info.iter().zip(&sys.bodies.u).enumerate() {
            if i != self.body && !info.fixed {
                speed += u[0].hypot(u[1]);
                n += 1;
            }
        }
        self.sum_speed += if n > 0 { speed / n as f64 } else { 0.0 };
        self.sum_contacts += stats.contacts as f64;
        self.sum_iterations += stats.iterations as f64;
        self.max_overlap = self.max_overlap.max(stats.max_overlap);
        // This step closes the cycle if it ends within half a step of the cycle's
        // end or past it (the half step absorbs the round-off of the clock).
        let end = (self.cycle + 1) as f64 / self.frequency;
        if sys.time + 0.5 * sys.params.dt < end {
            return None;
        }
        let k = self.steps as f64;
        let row = format!(
            "{},{:e},{:e},{:e},{:e},{:e},{:e},{:e}",
            self.cycle + 1,
            sys.time,
            self.y0 - self.sum_y / k,
            self.y0 - self.y_at_min_load,
            self.sum_speed / k,
            self.sum_contacts / k,
            self.sum_iterations / k,
            self.max_overlap
        );
        let (y0, cycle) = (self.y0, self.cycle + 1);
        let first_cycle_q = self.first_cycle_q.take().or_else(|| Some(sys.bodies.q.clone()));
        *self = Self { y0, cycle, first_cycle_q, ..Self::new(sys, self.frequency, self.body) };
        Some(row)
    }
}

/// Cuts `path` back to its header and first `rows` rows (a resumed run rewrites the rest).
pub fn truncate_rows(path: &Path, rows: u64) -> Result<()> {
    if !path.exists() {
        return Ok(());
    }
    let text = std::fs::read_to_string(path).map_err(|e| io_error(path, "read", e))?;
    let kept: Vec<&str> = text.lines().take(rows as usize + 1).collect();
    let mut out = kept.join("\n");
    out.push('\n');
    std::fs::write(path, out).map_err(|e| io_error(path, "write", e))
}

/// Appends `row` (and the header first if the file is new) to `path`.
pub fn append_row(path: &Path, row: &str) -> Result<()> {
    append_with_header(path, CYCLES_HEADER, row)
}

/// Appends `row` to `path`, writing `header` first if the file is new (the
/// per-cycle files of both engines).
pub fn append_with_header(path: &Path, header: &str, row: &str) -> Result<()> {
    let new = !path.exists();
    let mut f =
        std::fs::OpenOptions::new().create(true).append(true).open(path).map_err(|e| io_error(path, "open", e))?;
    if new {
        writeln!(f, "{header}").map_err(|e| io_error(path, "write", e))?;
    }
    writeln!(f, "{row}").map_err(|e| io_error(path, "write", e))
}

/// One row of `cycles.csv`, as read back by [`read`].
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct CycleRow {
    pub cycle: u64,
    pub time_s: f64,
    pub settlement_mean_m: f64,
    pub settlement_at_min_load_m: f64,
    pub mean_grain_speed_m_s: f64,
    pub contacts: f64,
    pub iterations: f64,
    pub max_overlap_m: f64,
}

/// Reads a `cycles.csv`; the error names the file and the row.
pub fn read(path: &Path) -> Result<Vec<CycleRow>> {
    super::read_csv(path)
}
