//! What a run accumulates from step to step besides the engine state
//! ([`RunSummary`], kept in checkpoints), and `summary.json`, written when the
//! run ends ([`RunReport`]): wall time, mean NLGS iterations and contacts per
//! step, interpenetration — the statistics of Saussine et al. (2006), §3.2
//! (computation time, average number of iterations) and §3.3.
//!
//! The same for MD runs: [`MdRunSummary`] and [`MdRunReport`] (wall time,
//! particle-steps per second, contacts and overlaps).
//!
//! The wall time is a measurement: it is the one output of a run that differs
//! between two runs of the same scene (and it adds up over `--resume`s).

use crate::md::MdStepStats;
use crate::nscd::StepStats;
use serde::{Deserialize, Serialize};

/// Running sums over the steps of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Largest overlap so far (m).
    pub max_overlap: f64,
    /// Steps that hit the iteration cap.
    pub unconverged: u64,
    /// Consecutive steps so far with the kinetic energy below the equilibrium threshold.
    pub calm_steps: u64,
    /// Steps made.
    #[serde(default)]
    pub steps: u64,
    /// Sum over the steps of the NLGS sweeps.
    #[serde(default)]
    pub iterations: u64,
    /// Sum over the steps of the contacts detected.
    #[serde(default)]
    pub contacts: u64,
    /// Sum over the steps of the mean overlap of the active contacts (m).
    #[serde(default)]
    pub sum_mean_overlap: f64,
    /// Wall time spent stepping so far, over every invocation (s).
    #[serde(default)]
    pub wall_time_s: f64,
}

impl RunSummary {
    /// Adds one step.
    pub fn add(&mut self, s: &StepStats) {
        self.max_overlap = self.max_overlap.max(s.max_overlap);
        self.unconverged += u64::from(!s.converged);
        self.steps += 1;
        self.iterations += s.iterations as u64;
        self.contacts += s.contacts as u64;
        self.sum_mean_overlap += s.mean_overlap;
    }
}

/// Contents of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    /// Steps made and simulated time at the end (s).
    pub steps: u64,
    pub time_s: f64,
    /// Time step (s).
    pub dt_s: f64,
    /// Wall time spent stepping (s), and per step.
    pub wall_time_s: f64,
    pub wall_time_per_step_s: f64,
    /// Loading cycles completed (with `output.cycles`) and wall time per cycle (s).
    pub cycles: Option<u64>,
    pub wall_time_per_cycle_s: Option<f64>,
    /// Mean NLGS sweeps per step.
    pub mean_iterations: f64,
    /// Mean contacts detected per step.
    pub mean_contacts: f64,
    /// Mean over the steps of the mean overlap of the active contacts (m).
    pub mean_overlap_m: f64,
    /// Largest overlap of the run (m).
    pub max_overlap_m: f64,
    /// Steps that hit the iteration cap.
    pub unconverged_steps: u64,
    /// Whether the run stopped on its equilibrium criterion.
    pub equilibrium: bool,
}

impl RunReport {
    /// The report of a run with these sums, `dt` (s) and end time (s).
    pub fn new(s: &RunSummary, dt: f64, time: f64, cycles: Option<u64>, equilibrium: bool) -> Self {
        let per_step = |x: f64| if s.steps > 0 { x / s.steps as f64 } else { 0.0 };
        Self {
            steps: s.steps,
            time_s: time,
            dt_s: dt,
            wall_time_s: s.wall_time_s,
            wall_time_per_step_s: per_step(s.wall_time_s),
            cycles,
            wall_time_per_cycle_s: cycles.filter(|&c| c > 0).map(|c| s.wall_time_s / c as f64),
            mean_iterations: per_step(s.iterations as f64),
            mean_contacts: per_step(s.contacts as f64),
            mean_overlap_m: per_step(s.sum_mean_overlap),
            max_overlap_m: s.max_overlap,
            unconverged_steps: s.unconverged,
            equilibrium,
        }
    }
}

/// Running sums over the steps of an MD run (kept in its checkpoints).
///
/// The overlaps of a step are those the engine measured: with
/// [`crate::md::MdSystem::measure_every`] above 1, the statistics of the steps in
/// between repeat the last measured ones (`ballast run` measures every step).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MdRunSummary {
    /// Steps made.
    pub steps: u64,
    /// Largest overlap so far (m).
    pub max_overlap: f64,
    /// Sum over the steps of the mean overlap (m).
    pub sum_mean_overlap: f64,
    /// Sum over the steps of the sphere–sphere contacts (a contact with a symmetry image counts half).
    pub contacts: f64,
    /// Sum over the steps of the sphere–wall contacts.
    pub wall_contacts: u64,
    /// Consecutive steps so far that met the equilibrium condition.
    pub calm_steps: u64,
    /// Whether some step so far failed the equilibrium condition: only then do
    /// calm steps count (a sample released from rest has not settled yet).
    #[serde(default)]
    pub moved: bool,
    /// Wall time spent stepping so far, over every invocation (s).
    pub wall_time_s: f64,
}

impl MdRunSummary {
    /// Adds one step.
    pub fn add(&mut self, s: &MdStepStats) {
        self.steps += 1;
        self.contacts += s.contacts;
        self.wall_contacts += s.wall_contacts as u64;
        self.max_overlap = self.max_overlap.max(s.max_overlap);
        self.sum_mean_overlap += s.mean_overlap;
    }
}

/// Contents of `summary.json` of an MD run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MdRunReport {
    /// Steps made and simulated time at the end (s).
    pub steps: u64,
    pub time_s: f64,
    /// Time step (s).
    pub dt_s: f64,
    /// Number of spheres.
    pub spheres: usize,
    /// Force-evaluation threads of the last invocation.
    pub threads: usize,
    /// Wall time spent stepping (s), and per step.
    pub wall_time_s: f64,
    pub wall_time_per_step_s: f64,
    /// Spheres × steps per second of wall time.
    pub particle_steps_per_s: f64,
    /// Mean sphere–sphere and sphere–wall contacts per step.
    pub mean_contacts: f64,
    pub mean_wall_contacts: f64,
    /// Mean over the steps of the mean overlap over the contacts (m).
    pub mean_overlap_m: f64,
    /// Largest overlap of the run (m).
    pub max_overlap_m: f64,
    /// Whether the run stopped on its equilibrium criterion.
    pub equilibrium: bool,
}

impl MdRunReport {
    /// The report of a run of `spheres` spheres on `threads` threads with these
    /// sums, `dt` (s) and end time (s).
    pub fn new(s: &MdRunSummary, spheres: usize, threads: usize, dt: f64, time: f64, equilibrium: bool) -> Self {
        let per_step = |x: f64| if s.steps > 0 { x / s.steps as f64 } else { 0.0 };
        let work = spheres as f64 * s.steps as f64;
        Self {
            steps: s.steps,
            time_s: time,
            dt_s: dt,
            spheres,
            threads,
            wall_time_s: s.wall_time_s,
            wall_time_per_step_s: per_step(s.wall_time_s),
            particle_steps_per_s: if s.wall_time_s > 0.0 { work / s.wall_time_s } else { 0.0 },
            mean_contacts: per_step(s.contacts),
            mean_wall_contacts: per_step(s.wall_contacts as f64),
            mean_overlap_m: per_step(s.sum_mean_overlap),
            max_overlap_m: s.max_overlap,
            equilibrium,
        }
    }
}
