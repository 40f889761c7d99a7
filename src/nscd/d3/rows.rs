//! The output rows of the 3D NSCD engine, read back with the same types; column names carry their unit (`_s`,
//! `_J`, `_m`), counts and ratios have none. The columns the 2D engines also write have their names and
//! meanings ([`crate::plane::rows`]), so a table read by column name compares across the engines.
//!
//! `series.csv`, one row every `output.every` steps and at the last step ([`SeriesRow3`]): `time_s`,
//! `kinetic_energy_J` (translational plus rotational, the mobile bodies), `contacts` (contact points detected,
//! open ones within the alert distance included), `active_contacts` (carrying an impulse or overlapping),
//! `iterations` (NLGS sweeps), `criterion` (final value of the policy's norm), `converged` (1, or 0 when the
//! step hit the sweep cap), `mean_overlap_m` (over the active points), `max_overlap_m`, `total_overlap_m` (sum
//! over the points). The overlaps are those at the end of the step, `max(0, −(g + θ h U_N))` with `g` the gap at
//! the intermediate configuration and `U_N` the new normal velocity. The wall times of the step are not in the
//! rows (they differ between two runs of the same numbers).
//!
//! `cycles.csv`, one row per loading cycle ([`crate::clock::cycles_at`]; [`CycleRow3`]), with `h` the height of
//! the followed body's centroid along `−g` (`h = x · up`, `up = −g/|g|`, `+z` without gravity) and `h0` its value
//! when the per-cycle output started (the run's start): `cycle`, `time_s` (end of the cycle), `settlement_m`
//! (`h0 − h` at the cycle's end, positive when the body has gone down), `settlement_mean_m` (`h0 − ⟨h⟩` over the
//! cycle's steps, the 2D engines' column), `mean_grain_speed_m_s` (speed of the other mobile bodies' centroids,
//! averaged over bodies then steps), `contacts`, `iterations` (means per step), `max_overlap_m` (largest over
//! the cycle), `mean_overlap_m` (the series' `mean_overlap_m` averaged over the cycle's steps) and
//! `coordination` (at the cycle's end, over the mobile bodies other than the followed one:
//! [`super::measure::coordination`]).
//!
//! The per-cycle state ([`CycleState3`]) is plain data, kept in checkpoints so that a resumed run writes the
//! same rows.

use crate::engine::CycleCheck;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of the 3D NSCD engine's `series.csv` (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SeriesRow3 {
    /// Column `time_s`: time at the end of the step (s).
    pub time_s: f64,
    /// Column `kinetic_energy_J`: kinetic energy of the mobile bodies at the end of the step (J).
    #[serde(rename = "kinetic_energy_J")]
    pub kinetic_energy_j: f64,
    /// Column `contacts`: contact points detected.
    pub contacts: usize,
    /// Column `active_contacts`: contact points carrying an impulse or overlapping.
    pub active_contacts: usize,
    /// Column `iterations`: NLGS sweeps of the step.
    pub iterations: usize,
    /// Column `criterion`: final value of the policy's norm (dimensionless).
    pub criterion: f64,
    /// Column `converged`: 1 if the sweeps met the tolerance, 0 at the cap.
    pub converged: u8,
    /// Column `mean_overlap_m`: mean overlap over the active points at the end of the step (m).
    pub mean_overlap_m: f64,
    /// Column `max_overlap_m`: largest overlap at the end of the step (m).
    pub max_overlap_m: f64,
    /// Column `total_overlap_m`: sum of the overlaps (m).
    pub total_overlap_m: f64,
}

/// The columns of [`SeriesRow3`].
pub const SERIES3_COLUMNS: [&str; 10] = [
    "time_s",
    "kinetic_energy_J",
    "contacts",
    "active_contacts",
    "iterations",
    "criterion",
    "converged",
    "mean_overlap_m",
    "max_overlap_m",
    "total_overlap_m",
];

/// Reads a 3D NSCD `series.csv`; the error names the file and the line.
pub fn read_series(path: &Path) -> Result<Vec<SeriesRow3>> {
    Ok(crate::io::table::read(path)?.1)
}

/// What a 3D NSCD run accumulates over the steps of a cycle (module doc).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CycleState3 {
    /// Index of the followed body.
    pub body: usize,
    /// The unit vector against gravity (`+z` without gravity).
    pub up: [f64; 3],
    /// The followed body's height `x · up` when the per-cycle output started (m).
    pub h0: f64,
    /// Steps accumulated in the cycle under way.
    pub steps: u64,
    /// Sum over those steps of the followed body's height (m).
    pub sum_h: f64,
    /// Sum over the steps of the mean speed of the other mobile bodies (m/s).
    pub sum_speed: f64,
    /// Sum over the steps of the contact points detected.
    pub sum_contacts: f64,
    /// Sum over the steps of the NLGS sweeps.
    pub sum_iterations: f64,
    /// Largest overlap over the cycle's steps (m).
    pub max_overlap: f64,
    /// Sum over the steps of the mean overlap of the active points (m).
    pub sum_mean_overlap: f64,
}

impl CycleState3 {
    /// A cycle state following body `body` from height `h0` (m) along `up`.
    pub fn new(body: usize, up: [f64; 3], h0: f64) -> Self {
        Self {
            body,
            up,
            h0,
            steps: 0,
            sum_h: 0.0,
            sum_speed: 0.0,
            sum_contacts: 0.0,
            sum_iterations: 0.0,
            max_overlap: 0.0,
            sum_mean_overlap: 0.0,
        }
    }

    /// Starts the accumulators of the next cycle (the followed body, `up` and `h0` stay).
    pub fn restart(&mut self) {
        *self = Self::new(self.body, self.up, self.h0);
    }
}

impl CycleCheck for CycleState3 {
    fn check(&self, start: &Self, bodies: usize, _cycles: u64) -> std::result::Result<(), String> {
        let same_up = self.up.iter().zip(&start.up).all(|(a, b)| a.to_bits() == b.to_bits());
        if self.body != start.body || self.body >= bodies || !same_up || self.h0.to_bits() != start.h0.to_bits() {
            return Err(format!(
                "it follows body {} from h0 = {} m along {:?}, the scene body {} from {} m along {:?}",
                self.body, self.h0, self.up, start.body, start.h0, start.up
            ));
        }
        Ok(())
    }
}

/// One row of the 3D NSCD engine's `cycles.csv` (module doc).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CycleRow3 {
    /// Column `cycle`: number of the cycle ended (1 for the first).
    pub cycle: u64,
    /// Column `time_s`: time at the end of the cycle (s).
    pub time_s: f64,
    /// Column `settlement_m`: `h0 − h` of the followed body at the cycle's end (m), positive downwards.
    pub settlement_m: f64,
    /// Column `settlement_mean_m`: `h0 − ⟨h⟩` over the cycle's steps (m), positive downwards.
    pub settlement_mean_m: f64,
    /// Column `mean_grain_speed_m_s`: speed of the other mobile bodies' centroids, averaged over bodies then
    /// steps (m/s).
    pub mean_grain_speed_m_s: f64,
    /// Column `contacts`: contact points detected per step, mean over the cycle.
    pub contacts: f64,
    /// Column `iterations`: NLGS sweeps per step, mean over the cycle.
    pub iterations: f64,
    /// Column `max_overlap_m`: largest overlap over the cycle (m).
    pub max_overlap_m: f64,
    /// Column `mean_overlap_m`: mean overlap of the active points, averaged over the cycle's steps (m).
    pub mean_overlap_m: f64,
    /// Column `coordination`: at the cycle's end, the mean number of force-carrying neighbours of the non-rattler
    /// mobile bodies other than the followed one ([`super::measure::coordination`]).
    pub coordination: f64,
}

/// The columns of [`CycleRow3`].
pub const CYCLE3_COLUMNS: [&str; 10] = [
    "cycle",
    "time_s",
    "settlement_m",
    "settlement_mean_m",
    "mean_grain_speed_m_s",
    "contacts",
    "iterations",
    "max_overlap_m",
    "mean_overlap_m",
    "coordination",
];

/// Reads a 3D NSCD `cycles.csv`; the error names the file and the line.
pub fn read_cycles(path: &Path) -> Result<Vec<CycleRow3>> {
    Ok(crate::io::table::read(path)?.1)
}
