//! The output rows of the 2D engines (NSCD and planar MD write the same files), read back with the same
//! types; column names carry their unit (`_s`, `_J`, `_m`, `_N`), counts and ratios have none.
//!
//! `series.csv`, one row every `output.every` steps and at the last step ([`PlaneSeriesRow`]):
//! `time_s`, `kinetic_energy_J`, `contacts` (detected,
//! open ones within the alert distance included), `active_contacts` (carrying a
//! force or overlapping), `iterations` (NLGS sweeps), `criterion` (final value of
//! the convergence norm), `converged` (1, or 0 when the step hit the iteration
//! cap), `mean_overlap_m` (over the active contacts), `max_overlap_m`,
//! `total_overlap_m` (sum over the contacts: the cumulated interpenetration of
//! Saussine et al. 2006, Fig. 2).
//!
//! `cycles.csv`, one row per loading cycle (a cycle of frequency `f` lasts `1/f` from t = 0; the step that
//! ends within half a step of `c/f` or past it closes cycle `c`, [`crate::clock::cycles_at`]):
//! [`PlaneCycleRow`] (Saussine et al. 2006, §4: settlement of the sleeper,
//! Figs. 6, 11, 12; mean grain velocity, Fig. 7), with `y` the vertical position
//! of the followed body's centre of mass and `y0` its value at the start of the
//! run: `cycle`, `time_s` (end of the cycle), `settlement_mean_m` (`y0 − ⟨y⟩`
//! over the steps of the cycle, positive when the body has gone down),
//! `settlement_at_min_load_m` (`y0 − y` at the step of the cycle where the
//! magnitude of the body's load is smallest), `mean_grain_speed_m_s` (speed of
//! the other non-fixed bodies, averaged over bodies and steps), `contacts`,
//! `iterations` (means per step), `max_overlap_m` (largest over the cycle),
//! `mean_overlap_m` (the mean overlap of the force-carrying contacts, the
//! `mean_overlap_m` of `series.csv`, averaged over the cycle's steps) and `coordination` (at the cycle's end: the mean number of
//! force-carrying neighbours of the non-rattler grains other than the followed
//! body, [`crate::plane::outputs::coordination`]). The last two were added on
//! 2026-12-03; an older file reads them as NaN.
//!
//! The per-cycle state is plain data, kept in checkpoints so that a resumed run writes the same rows.

use crate::engine::CycleCheck;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of a 2D engine's `series.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlaneSeriesRow {
    /// Column `time_s`: time at the end of the step (s).
    pub time_s: f64,
    /// Column `kinetic_energy_J`: kinetic energy of the non-fixed bodies, translational plus
    /// rotational, at the end of the step (J).
    #[serde(rename = "kinetic_energy_J")]
    pub kinetic_energy_j: f64,
    /// Column `contacts`: contacts detected, open ones within the alert distance included.
    pub contacts: usize,
    /// Column `active_contacts`: contacts carrying an impulse or overlapping at the end of the step.
    pub active_contacts: usize,
    /// Column `iterations`: NLGS sweeps made in the step.
    pub iterations: usize,
    /// Column `criterion`: final value of the convergence norm of the policy
    /// ([`crate::nscd::criterion::evaluate`]; dimensionless, converged below the tolerance).
    pub criterion: f64,
    /// Column `converged`: 1 if the iterations converged, 0 if they hit the iteration cap.
    pub converged: u8,
    /// Column `mean_overlap_m`: mean overlap over the active contacts at the end of the step (m).
    pub mean_overlap_m: f64,
    /// Column `max_overlap_m`: largest overlap at the end of the step (m).
    pub max_overlap_m: f64,
    /// Column `total_overlap_m`: sum of the overlaps of all contacts (m), the cumulated
    /// interpenetration of Saussine et al. 2006, Fig. 2.
    pub total_overlap_m: f64,
}

/// The columns of [`PlaneSeriesRow`].
pub const PLANE_SERIES_COLUMNS: [&str; 10] = [
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

/// Reads a 2D engine's `series.csv`; the error names the file and the line.
pub fn read_series(path: &Path) -> Result<Vec<PlaneSeriesRow>> {
    Ok(crate::io::table::read(path)?.1)
}

/// What a run of a 2D engine accumulates over the steps of a cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlaneCycleState {
    /// Index of the followed body.
    pub body: usize,
    /// Its initial vertical position (m).
    pub y0: f64,
    /// Steps accumulated so far in the cycle under way (the divisor of the
    /// means of [`PlaneCycleRow`]).
    pub steps: u64,
    /// Sum over those steps of the followed body's vertical position `y` (m).
    pub sum_y: f64,
    /// Smallest load magnitude of the cycle (N); infinite before its first
    /// step, which JSON writes as `null` (a checkpoint at a cycle end).
    #[serde(deserialize_with = "null_is_infinite")]
    pub min_load: f64,
    /// Vertical position `y` of the followed body (m) at the step of [`Self::min_load`].
    pub y_at_min_load: f64,
    /// Sum over the steps of the mean speed `|u|` of the other non-fixed bodies (m/s).
    pub sum_speed: f64,
    /// Sum over the steps of the contacts detected (count).
    pub sum_contacts: f64,
    /// Sum over the steps of the NLGS iterations made.
    pub sum_iterations: f64,
    /// Largest overlap (interpenetration) of any contact over the cycle's steps (m).
    pub max_overlap: f64,
    /// Sum over the steps of the mean overlap of the force-carrying contacts (m);
    /// 0 in a checkpoint written before it existed.
    #[serde(default)]
    pub sum_mean_overlap: f64,
    /// Positions `(x, y, θ)` of every body at the end of the first cycle (for the
    /// displacement field from cycle 1 to the end of the run).
    pub first_cycle_q: Option<Vec<[f64; 3]>>,
}

impl PlaneCycleState {
    /// A cycle state following body `body` from the vertical position `y0` (m).
    pub fn new(body: usize, y0: f64) -> Self {
        Self {
            body,
            y0,
            steps: 0,
            sum_y: 0.0,
            min_load: f64::INFINITY,
            y_at_min_load: y0,
            sum_speed: 0.0,
            sum_contacts: 0.0,
            sum_iterations: 0.0,
            max_overlap: 0.0,
            sum_mean_overlap: 0.0,
            first_cycle_q: None,
        }
    }

    /// Starts the accumulators of the next cycle (the followed body, `y0` and the
    /// first cycle's positions stay).
    pub fn restart(&mut self) {
        let first = self.first_cycle_q.take();
        *self = Self { first_cycle_q: first, ..Self::new(self.body, self.y0) };
    }
}

impl CycleCheck for PlaneCycleState {
    fn check(&self, start: &Self, bodies: usize, cycles: u64) -> std::result::Result<(), String> {
        if self.body != start.body || self.y0.to_bits() != start.y0.to_bits() {
            return Err(format!(
                "it follows body {} from y0 = {} m, the scene body {} from {} m",
                self.body, self.y0, start.body, start.y0
            ));
        }
        match (&self.first_cycle_q, cycles) {
            (None, 0) => Ok(()),
            (Some(q), 1..) if q.len() == bodies => Ok(()),
            (q, _) => Err(format!(
                "positions of {} bodies at the end of the first cycle, after {cycles} cycles of {bodies} bodies",
                q.as_ref().map_or(0, Vec::len)
            )),
        }
    }
}

/// One row of a 2D engine's `cycles.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlaneCycleRow {
    /// Column `cycle`: number of the cycle ended (1 for the first).
    pub cycle: u64,
    /// Column `time_s`: time at the end of the cycle (s).
    pub time_s: f64,
    /// Column `settlement_mean_m`: `y0 − ⟨y⟩` of the followed body over the cycle's
    /// steps (m), positive downwards (Saussine et al. 2006, Figs. 6, 11, 12).
    pub settlement_mean_m: f64,
    /// Column `settlement_at_min_load_m`: `y0 − y` (m) at the step of the cycle where
    /// the followed body's load magnitude is smallest; positive downwards.
    pub settlement_at_min_load_m: f64,
    /// Column `mean_grain_speed_m_s`: speed of the non-fixed bodies other than the
    /// followed one, averaged over bodies then steps (m/s; Saussine et al. 2006, Fig. 7).
    pub mean_grain_speed_m_s: f64,
    /// Column `contacts`: contacts detected per step, mean over the cycle.
    pub contacts: f64,
    /// Column `iterations`: NLGS iterations per step, mean over the cycle.
    pub iterations: f64,
    /// Column `max_overlap_m`: largest contact overlap over the cycle (m).
    pub max_overlap_m: f64,
    /// Column `mean_overlap_m`: mean overlap of the force-carrying contacts (NSCD:
    /// those with an impulse or an overlap; MD: the overlapping points), averaged
    /// over the cycle's steps (m); NaN when read from a file without it.
    #[serde(default = "nan")]
    pub mean_overlap_m: f64,
    /// Column `coordination`: at the cycle's end, the mean number of neighbours
    /// pressing on each non-rattler grain (the mobile bodies other than the
    /// followed one; a pair counts once; dimensionless); NaN when read from a
    /// file without it.
    #[serde(default = "nan")]
    pub coordination: f64,
}

/// The columns of [`PlaneCycleRow`].
pub const PLANE_CYCLE_COLUMNS: [&str; 10] = [
    "cycle",
    "time_s",
    "settlement_mean_m",
    "settlement_at_min_load_m",
    "mean_grain_speed_m_s",
    "contacts",
    "iterations",
    "max_overlap_m",
    "mean_overlap_m",
    "coordination",
];

/// Reads a 2D engine's `cycles.csv`; the error names the file and the line.
pub fn read_cycles(path: &Path) -> Result<Vec<PlaneCycleRow>> {
    Ok(crate::io::table::read(path)?.1)
}

/// An `f64` that reads `null` (serde_json's form of a non-finite number) as +∞.
fn null_is_infinite<'de, D: serde::Deserializer<'de>>(d: D) -> std::result::Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

fn nan() -> f64 {
    f64::NAN
}
