//! What a run accumulates from step to step besides the engine state
//! ([`RunSummary`], kept in checkpoints), and `summary.json`, written when the
//! run ends ([`RunReport`]): wall time and speed, mean contacts, overlaps, and
//! for NSCD the mean NLGS iterations and the steps that hit the iteration cap —
//! the statistics of Saussine et al. (2006), §3.2 (computation time, average
//! number of iterations) and §3.3 (interpenetration). One type for both engines.
//!
//! The wall time is a measurement: it is the one output of a run that differs
//! between two runs of the same scene (and it adds up over `--resume`s).

use crate::engine::StepSummary;
use crate::run::EquilibriumWatch;
use serde::{Deserialize, Serialize};

/// Running sums over the steps of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct RunSummary {
    /// Steps made in this run.
    pub steps: u64,
    /// Largest overlap so far, the state before the first step included (m).
    pub max_overlap: f64,
    /// Largest overlap of the last step (or of the state before the first) (m).
    #[serde(default)]
    pub final_max_overlap: f64,
    /// Sum over the steps of the mean overlap of the active contacts (m).
    pub sum_mean_overlap: f64,
    /// Sum over the steps of the contacts.
    pub contacts: f64,
    /// Sum over the steps of the NLGS sweeps (NSCD).
    pub iterations: u64,
    /// Steps that hit the iteration cap (NSCD): the solver stopped at
    /// `max_iterations` before meeting its tolerance.
    pub unconverged: u64,
    /// Largest final convergence norm of those steps (NSCD, dimensionless; 0
    /// when every step converged).
    #[serde(default)]
    pub worst_unconverged_criterion: f64,
    /// State of the equilibrium rule.
    pub equilibrium: EquilibriumWatch,
    /// Wall time spent stepping so far, over every invocation (s).
    pub wall_time_s: f64,
}

impl RunSummary {
    /// Adds one step.
    /// The counters saturate: a resumed summary may carry any value.
    pub fn add(&mut self, s: &StepSummary) {
        self.steps = self.steps.saturating_add(1);
        self.max_overlap = self.max_overlap.max(s.max_overlap);
        self.final_max_overlap = s.max_overlap;
        self.sum_mean_overlap += s.mean_overlap;
        self.contacts += s.contacts;
        self.iterations = self.iterations.saturating_add(s.iterations);
        self.unconverged = self.unconverged.saturating_add(u64::from(!s.converged));
        if !s.converged && s.criterion > self.worst_unconverged_criterion {
            self.worst_unconverged_criterion = s.criterion;
        }
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunEnd {
    /// Every step asked for was made.
    Finished,
    /// The equilibrium rule stopped it early.
    Equilibrium,
    /// A step diverged: the outputs hold the last good step.
    Diverged,
    /// An NSCD step stalled short of its tolerance under `on_stall = "stop"`: the
    /// outputs hold the last good step.
    Stalled,
}

/// Contents of `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunReport {
    /// `"nscd"` or `"md"`.
    pub engine: String,
    /// How the run ended.
    pub end: RunEnd,
    /// Steps made by the run, over all its `--resume`s.
    pub steps: u64,
    /// Simulated time at the end (s).
    pub time_s: f64,
    /// Time step (s).
    pub dt_s: f64,
    /// Bodies (NSCD: bodies; MD: spheres).
    pub bodies: usize,
    /// Threads of the last invocation.
    pub threads: usize,
    /// Wall time spent stepping (s).
    pub wall_time_s: f64,
    /// Wall time per step (s).
    pub wall_time_per_step_s: f64,
    /// Bodies × steps per second of wall time.
    pub body_steps_per_s: f64,
    /// Loading cycles completed (with `output.cycles`; absent otherwise).
    pub cycles: Option<u64>,
    /// Wall time per completed loading cycle (s; with `output.cycles`).
    pub wall_time_per_cycle_s: Option<f64>,
    /// Mean contacts per step.
    pub mean_contacts: f64,
    /// Mean over the steps of the mean overlap of the active contacts (m).
    pub mean_overlap_m: f64,
    /// Largest overlap of the run, the initial state included (m): during a
    /// deposit, the impacts of falling grains.
    pub max_overlap_m: f64,
    /// Largest overlap of the final state (m): what a run leaves to the next.
    pub final_max_overlap_m: f64,
    /// NSCD: mean NLGS sweeps per step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mean_iterations: Option<f64>,
    /// NSCD: steps that hit the iteration cap (the solver stopped at
    /// `max_iterations` before meeting its tolerance).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unconverged_steps: Option<u64>,
    /// NSCD: the largest final convergence norm among those steps
    /// (dimensionless, against the policy's tolerance); absent when every step
    /// converged.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub worst_unconverged_criterion: Option<f64>,
    /// Whether the run stopped on its equilibrium rule.
    pub equilibrium: bool,
}

impl RunReport {
    /// The report of a run of `engine` (`iterations`: whether it has NLGS
    /// iterations) over `bodies` bodies with these sums, ending as `end` at
    /// `time` (s) with time step `dt` (s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        engine: &str,
        iterations: bool,
        s: &RunSummary,
        end: RunEnd,
        bodies: usize,
        threads: usize,
        dt: f64,
        time: f64,
        cycles: Option<u64>,
    ) -> Self {
        let per_step = |x: f64| if s.steps > 0 { x / s.steps as f64 } else { 0.0 };
        let work = bodies as f64 * s.steps as f64;
        Self {
            engine: engine.to_string(),
            end,
            steps: s.steps,
            time_s: time,
            dt_s: dt,
            bodies,
            threads,
            wall_time_s: s.wall_time_s,
            wall_time_per_step_s: per_step(s.wall_time_s),
            body_steps_per_s: if s.wall_time_s > 0.0 { work / s.wall_time_s } else { 0.0 },
            cycles,
            wall_time_per_cycle_s: cycles.filter(|&c| c > 0).map(|c| s.wall_time_s / c as f64),
            mean_contacts: per_step(s.contacts),
            mean_overlap_m: per_step(s.sum_mean_overlap),
            max_overlap_m: s.max_overlap,
            final_max_overlap_m: s.final_max_overlap,
            mean_iterations: iterations.then(|| per_step(s.iterations as f64)),
            unconverged_steps: iterations.then_some(s.unconverged),
            worst_unconverged_criterion: (iterations && s.unconverged > 0).then_some(s.worst_unconverged_criterion),
            equilibrium: end == RunEnd::Equilibrium,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The worst criterion is the largest final norm among the steps that hit
    /// the cap only: a converged step with a larger norm (a looser policy) does
    /// not count.
    #[test]
    fn the_worst_unconverged_criterion_counts_capped_steps_only() {
        let mut run = RunSummary::default();
        let step = |criterion: f64, converged: bool| StepSummary {
            criterion,
            converged,
            iterations: 5,
            ..StepSummary::default()
        };
        run.add(&step(0.5, true));
        assert_eq!((run.unconverged, run.worst_unconverged_criterion), (0, 0.0));
        run.add(&step(2e-4, false));
        run.add(&step(7e-4, false));
        run.add(&step(3e-4, false));
        run.add(&step(0.9, true));
        assert_eq!((run.unconverged, run.worst_unconverged_criterion), (3, 7e-4));
        let report = |run: &RunSummary| RunReport::new("nscd", true, run, RunEnd::Finished, 1, 1, 1e-3, 1.0, None);
        assert_eq!(report(&run).worst_unconverged_criterion, Some(7e-4));
        assert_eq!(report(&RunSummary::default()).worst_unconverged_criterion, None);
    }
}
