//! The tables and the summary of an accelerated run: `settlement.csv` (one row
//! per cycle), `jumps.csv` (one row per jump, kept or rolled back),
//! `summary.json`, and what the progress callback and the caller see.

use super::Law;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// One row of `settlement.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettlementRow {
    /// Cycles since the start of the loading, computed and extrapolated.
    pub cycle: u64,
    /// 1 for a computed cycle, 0 for an extrapolated one.
    pub computed: u8,
    /// Settlement at the cycle's end (m, positive downwards; module doc).
    pub settlement_m: f64,
    /// Coordination number at the cycle's end (computed cycles only).
    pub coordination: Option<f64>,
    /// Largest overlap of the extrapolated configuration (m; the last cycle of a jump).
    pub max_overlap_before_relax_m: Option<f64>,
    /// Largest overlap after its relaxation (m; the last cycle of a jump).
    pub max_overlap_after_relax_m: Option<f64>,
    /// Wall time since the start of the run (s).
    pub wall_time_s: f64,
}

impl SettlementRow {
    /// The header of `settlement.csv`: the fields, in order.
    pub const COLUMNS: &'static [&'static str] = &[
        "cycle",
        "computed",
        "settlement_m",
        "coordination",
        "max_overlap_before_relax_m",
        "max_overlap_after_relax_m",
        "wall_time_s",
    ];
}

/// One row of `jumps.csv`: a fit, its extrapolation and the relaxation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JumpRow {
    /// Jump number (1, 2, …).
    pub jump: u64,
    /// The last computed cycle of the window.
    pub from_cycle: u64,
    /// The cycle the jump lands on.
    pub to_cycle: u64,
    /// `k`: computed cycles of the window.
    pub computed_cycles: u64,
    /// `h`: cycles extrapolated.
    pub extrapolated_cycles: u64,
    /// The computed cycles the Chernoff bound asked for (adaptive runs).
    pub chernoff_cycles: Option<u64>,
    /// Eq. (13) on the window (m).
    pub g_u_m: f64,
    /// Eq. (14) on the window (m).
    pub f_xi_m: f64,
    /// Widest range of one coordinate's error terms (m).
    pub xi_range_m: f64,
    /// The largest overlap the relaxation was asked to reach (m).
    pub relax_tolerance_m: f64,
    /// Iterations of the relaxation.
    pub relax_iterations: u64,
    /// Evaluations of its functional.
    pub relax_evaluations: u64,
    /// Whether it reached the tolerance.
    pub relax_converged: bool,
    /// Largest overlap a stage of the relaxation started from (m; with one
    /// stage, the extrapolated configuration's).
    pub max_overlap_before_relax_m: f64,
    /// Largest overlap after (m).
    pub max_overlap_after_relax_m: f64,
    /// Largest distance of a coordinate from the extrapolated configuration
    /// after the relaxation (m or rad).
    pub relax_largest_move: f64,
    /// Wall time of the relaxation (s).
    pub relax_wall_time_s: f64,
    /// Bodies held where they were (no force-carrying contact at the window's
    /// end: in flight, or loose in their cage; with `hold_anchored`, the
    /// bodies on springs to an anchor too).
    #[serde(default)]
    pub held_bodies: u64,
    /// Bodies moved less than their trend by `extrapolation_limit` (held ones
    /// with a trend included).
    #[serde(default)]
    pub limited_bodies: u64,
    /// Computed cycles after the previous landing left out of this window (the
    /// re-seating: `settle_cycles − 1`, more with `settle_rate`; 0 for the first jump).
    #[serde(default)]
    pub settling_cycles: u64,
    /// The settlement's per-cycle rate the fit predicts at this jump's landing (m per cycle).
    #[serde(default)]
    pub landing_rate_m: f64,
    /// The jump was rolled back: the run went back to the state before it and
    /// retried with half its length, or computed its cycles ([`rollback`](super::rollback)).
    #[serde(default)]
    pub rolled_back: bool,
    /// Why it was rolled back (empty for a jump that stands).
    #[serde(default)]
    pub rollback_reason: String,
    /// Stages of the landing ([`crate::settlement::sweep`]): 1 for the paper's
    /// single relaxation (and in files written before the stages).
    #[serde(default = "one")]
    pub relax_stages: u64,
}

fn one() -> u64 {
    1
}

impl JumpRow {
    /// The header of `jumps.csv`: the fields, in order.
    pub const COLUMNS: &'static [&'static str] = &[
        "jump",
        "from_cycle",
        "to_cycle",
        "computed_cycles",
        "extrapolated_cycles",
        "chernoff_cycles",
        "g_u_m",
        "f_xi_m",
        "xi_range_m",
        "relax_tolerance_m",
        "relax_iterations",
        "relax_evaluations",
        "relax_converged",
        "max_overlap_before_relax_m",
        "max_overlap_after_relax_m",
        "relax_largest_move",
        "relax_wall_time_s",
        "held_bodies",
        "limited_bodies",
        "settling_cycles",
        "landing_rate_m",
        "rolled_back",
        "rollback_reason",
        "relax_stages",
    ];
}

/// `summary.json` of an accelerated run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AccelerationSummary {
    /// `"nscd"` or `"md"`.
    pub engine: String,
    /// `"finished"`, `"stopped"` (to resume) or `"diverged"`.
    pub end: String,
    /// The law fitted.
    pub law: Law,
    /// Cycles computed by the engine.
    pub computed_cycles: u64,
    /// Cycles reached, computed and extrapolated.
    pub total_cycles: u64,
    /// `total_cycles / computed_cycles`.
    pub gained: f64,
    /// Jumps made (and kept).
    pub jumps: u64,
    /// Landings rolled back ([`rollback`](super::rollback)).
    #[serde(default)]
    pub rollbacks: u64,
    /// `k_i`: the initial cycles (errors are measured on what accrues after them).
    pub initial_cycles: u64,
    /// Settlement at the last cycle (m).
    pub settlement_m: f64,
    /// Wall time (s).
    pub wall_time_s: f64,
    /// Steps of the run's kept trajectory (the steps of rolled-back cycles are not counted).
    pub steps: u64,
}

/// What the progress callback sees after each cycle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AccelerationProgress {
    /// Cycles reached (computed and extrapolated).
    pub cycle: u64,
    /// The target.
    pub target: u64,
    /// Cycles computed.
    pub computed: u64,
    /// Settlement (m).
    pub settlement: f64,
}

/// What a call of [`Accelerated::run`](super::Accelerated::run) did.
#[derive(Debug, Clone)]
pub struct AccelerationOutcome<E> {
    /// The summary (also in `summary.json`).
    pub summary: AccelerationSummary,
    /// The system at the end.
    pub system: E,
    /// The output folder.
    pub out: PathBuf,
}
