//! The settlement of an ensemble of replicas cycle by cycle, seating and accrued apart
//! ([`settlement_ensemble`] over any [`CycleSettlement`] table: a run's `cycles.csv` or an accelerated run's
//! `settlement.csv`), its summary ([`SettlementSummary`]) and the ensemble and reference columns of the studies'
//! CSVs.

use super::*;

/// One row of `settlement_ensemble.csv`: the settlement at the load minimum of
/// one cycle over the replicas (m, positive downwards), total and accrued since
/// the seating cycle. Empty fields: no spread or interval with one replica; no
/// accrued settlement before the seating cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SettlementEnsembleRow {
    /// Column `cycle`: the loading cycle (1 for the first).
    pub cycle: u64,
    /// Column `replicas`: the replicas averaged (the table stops at the last
    /// cycle that every replica reached).
    pub replicas: usize,
    /// Column `settlement_mean_m`: mean over the replicas of `settlement_at_min_load_m` (m).
    pub settlement_mean_m: f64,
    /// Column `settlement_sd_m`: its sample standard deviation (m).
    pub settlement_sd_m: Option<f64>,
    /// Column `settlement_ci95_low_m`: lower end of the 95 % interval of the mean (m).
    pub settlement_ci95_low_m: Option<f64>,
    /// Column `settlement_ci95_high_m`: upper end of the 95 % interval of the mean (m).
    pub settlement_ci95_high_m: Option<f64>,
    /// Column `seating_cycle`: the cycle `S` the accrued settlement counts from.
    pub seating_cycle: u64,
    /// Column `accrued_mean_m`: mean over the replicas of `settlement(cycle) −
    /// settlement(S)` (m); empty before `S`.
    pub accrued_mean_m: Option<f64>,
    /// Column `accrued_sd_m`: its sample standard deviation (m).
    pub accrued_sd_m: Option<f64>,
    /// Column `accrued_ci95_low_m`: lower end of the 95 % interval of its mean (m).
    pub accrued_ci95_low_m: Option<f64>,
    /// Column `accrued_ci95_high_m`: upper end of the 95 % interval of its mean (m).
    pub accrued_ci95_high_m: Option<f64>,
}

/// A row of a run's per-cycle table with the settlement at the cycle's end, the
/// load minimum: `cycles.csv` of a plain 2D run ([`PlaneCycleRow`]) or of a 3D
/// NSCD run ([`CycleRow3`]), `settlement.csv` of an accelerated one
/// ([`SettlementRow`]: computed cycles measured there, the extrapolated ones on
/// the fitted law).
pub trait CycleSettlement {
    /// The loading cycle (1 for the first).
    fn cycle(&self) -> u64;
    /// The settlement at the cycle's load minimum (m, positive downwards).
    fn settlement_at_min_load(&self) -> f64;
}

impl CycleSettlement for PlaneCycleRow {
    fn cycle(&self) -> u64 {
        self.cycle
    }
    fn settlement_at_min_load(&self) -> f64 {
        self.settlement_at_min_load_m
    }
}

/// The 3D engine writes the settlement at the cycle's end (`settlement_m`). On
/// the 3D track section ([`crate::scenarios::track3d::LoadingSpec`]) the load is
/// `F = A + B cos(2π f t − φ)` with `A = −4 kPa`, `B = −2 kPa` (times the
/// sleeper's area, downwards) and `φ = −π` by default, so that at the end of
/// cycle `n` (`t = n / f`, the cycles counted from the loaded run's start) `F = A
/// − B = −2 kPa`: the load's smallest magnitude (its largest, `A + B`, is at
/// mid-cycle). With that default phase the cycle's end is the load minimum, as
/// the trait asks; with another phase it is only the cycle's end.
impl CycleSettlement for CycleRow3 {
    fn cycle(&self) -> u64 {
        self.cycle
    }
    fn settlement_at_min_load(&self) -> f64 {
        self.settlement_m
    }
}

impl CycleSettlement for SettlementRow {
    fn cycle(&self) -> u64 {
        self.cycle
    }
    fn settlement_at_min_load(&self) -> f64 {
        self.settlement_m
    }
}

/// The cycles every run reached (the shortest table).
fn common_cycles<T>(runs: &[&[T]]) -> usize {
    runs.iter().map(|r| r.len()).min().unwrap_or(0)
}

/// The settlement of `run` at the load minimum of cycle `s` (0: the start, 0 m);
/// its rows are cycles 1, 2, … in order.
fn settlement_at<T: CycleSettlement>(run: &[T], s: u64) -> f64 {
    match s {
        0 => 0.0,
        s => run[s as usize - 1].settlement_at_min_load(),
    }
}

/// The per-cycle ensemble of the replicas' `cycles.csv` rows `runs` (each in
/// cycle order from cycle 1), with the seating cycle `seating_cycles` (clipped
/// to the cycles every replica reached): one row per cycle that every replica
/// reached.
pub fn settlement_ensemble<T: CycleSettlement>(runs: &[&[T]], seating_cycles: u64) -> Vec<SettlementEnsembleRow> {
    let n = common_cycles(runs);
    let s = seating_cycles.min(n as u64);
    (0..n)
        .filter_map(|c| {
            let total: Vec<f64> = runs.iter().map(|r| r[c].settlement_at_min_load()).collect();
            let t = Estimate::of(&total)?;
            let cycle = runs[0][c].cycle();
            let a = if (c as u64) + 1 >= s {
                let accrued: Vec<f64> =
                    runs.iter().map(|r| r[c].settlement_at_min_load() - settlement_at(r, s)).collect();
                Estimate::of(&accrued)
            } else {
                None
            };
            Some(SettlementEnsembleRow {
                cycle,
                replicas: runs.len(),
                settlement_mean_m: t.mean,
                settlement_sd_m: t.sd,
                settlement_ci95_low_m: t.low(),
                settlement_ci95_high_m: t.high(),
                seating_cycle: s,
                accrued_mean_m: a.map(|a| a.mean),
                accrued_sd_m: a.and_then(|a| a.sd),
                accrued_ci95_low_m: a.and_then(|a| a.low()),
                accrued_ci95_high_m: a.and_then(|a| a.high()),
            })
        })
        .collect()
}

/// The settlement of an ensemble of replicas after its last common cycle `N`:
/// total, seating (at cycle `S`) and accrued (`N` minus `S`), per replica and
/// as estimates of the mean.
#[derive(Debug, Clone, PartialEq)]
pub struct SettlementSummary {
    /// `N`: the last cycle every replica reached.
    pub cycle: u64,
    /// `S`: the seating cycle, clipped to `N`.
    pub seating_cycle: u64,
    /// Per replica: settlement at the load minimum of cycle `N` (m).
    pub settlement: Vec<f64>,
    /// Per replica: settlement at cycle `S` (m).
    pub seating: Vec<f64>,
    /// Per replica: settlement(N) − settlement(S) (m).
    pub accrued: Vec<f64>,
}

impl SettlementSummary {
    /// The summary of the replicas' cycles `runs` with `seating_cycles` (see
    /// [`settlement_ensemble`]); `None` if there is no replica or some replica
    /// completed no cycle.
    pub fn of<T: CycleSettlement>(runs: &[&[T]], seating_cycles: u64) -> Option<Self> {
        let n = common_cycles(runs);
        if runs.is_empty() || n == 0 {
            return None;
        }
        let s = seating_cycles.min(n as u64);
        let settlement: Vec<f64> = runs.iter().map(|r| r[n - 1].settlement_at_min_load()).collect();
        let seating: Vec<f64> = runs.iter().map(|r| settlement_at(r, s)).collect();
        let accrued = settlement.iter().zip(&seating).map(|(t, s)| t - s).collect();
        Some(Self { cycle: runs[0][n - 1].cycle(), seating_cycle: s, settlement, seating, accrued })
    }

    /// The columns of a study's summary CSV.
    pub fn columns(&self) -> EnsembleColumns {
        let (t, s, a) = (Estimate::of(&self.settlement), Estimate::of(&self.seating), Estimate::of(&self.accrued));
        EnsembleColumns {
            replicas: self.settlement.len(),
            ensemble_cycle: Some(self.cycle),
            settlement_ens_mean_m: t.map(|e| e.mean),
            settlement_ens_sd_m: t.and_then(|e| e.sd),
            settlement_ens_ci95_low_m: t.and_then(|e| e.low()),
            settlement_ens_ci95_high_m: t.and_then(|e| e.high()),
            seating_cycle: Some(self.seating_cycle),
            seating_mean_m: s.map(|e| e.mean),
            seating_sd_m: s.and_then(|e| e.sd),
            seating_ci95_low_m: s.and_then(|e| e.low()),
            seating_ci95_high_m: s.and_then(|e| e.high()),
            accrued_mean_m: a.map(|e| e.mean),
            accrued_sd_m: a.and_then(|e| e.sd),
            accrued_ci95_low_m: a.and_then(|e| e.low()),
            accrued_ci95_high_m: a.and_then(|e| e.high()),
        }
    }
}

/// The ensemble columns of a study's summary CSV (`convergence.csv`,
/// `steps.csv`): the settlement at the load minimum of the last cycle every
/// replica of the setting reached, over its replicas (m). Empty fields: no
/// spread nor interval with one replica, nothing when a replica completed no
/// cycle.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct EnsembleColumns {
    /// Column `replicas`: the replicas of the setting.
    pub replicas: usize,
    /// Column `ensemble_cycle`: `N`, the last cycle every replica reached.
    pub ensemble_cycle: Option<u64>,
    /// Column `settlement_ens_mean_m`: mean over the replicas of the settlement after `N` cycles (m).
    pub settlement_ens_mean_m: Option<f64>,
    /// Column `settlement_ens_sd_m`: its sample standard deviation (m).
    pub settlement_ens_sd_m: Option<f64>,
    /// Column `settlement_ens_ci95_low_m`: lower end of the 95 % interval of the mean (m).
    pub settlement_ens_ci95_low_m: Option<f64>,
    /// Column `settlement_ens_ci95_high_m`: upper end (m).
    pub settlement_ens_ci95_high_m: Option<f64>,
    /// Column `seating_cycle`: `S`, clipped to `N`.
    pub seating_cycle: Option<u64>,
    /// Column `seating_mean_m`: mean over the replicas of the settlement after `S` cycles (m).
    pub seating_mean_m: Option<f64>,
    /// Column `seating_sd_m`: its sample standard deviation (m).
    pub seating_sd_m: Option<f64>,
    /// Column `seating_ci95_low_m`: lower end of the 95 % interval of the mean (m).
    pub seating_ci95_low_m: Option<f64>,
    /// Column `seating_ci95_high_m`: upper end (m).
    pub seating_ci95_high_m: Option<f64>,
    /// Column `accrued_mean_m`: mean over the replicas of settlement(N) − settlement(S) (m).
    pub accrued_mean_m: Option<f64>,
    /// Column `accrued_sd_m`: its sample standard deviation (m).
    pub accrued_sd_m: Option<f64>,
    /// Column `accrued_ci95_low_m`: lower end of the 95 % interval of the mean (m).
    pub accrued_ci95_low_m: Option<f64>,
    /// Column `accrued_ci95_high_m`: upper end (m).
    pub accrued_ci95_high_m: Option<f64>,
}

/// The names of the [`EnsembleColumns`].
pub const ENSEMBLE_COLUMNS: [&str; 15] = [
    "replicas",
    "ensemble_cycle",
    "settlement_ens_mean_m",
    "settlement_ens_sd_m",
    "settlement_ens_ci95_low_m",
    "settlement_ens_ci95_high_m",
    "seating_cycle",
    "seating_mean_m",
    "seating_sd_m",
    "seating_ci95_low_m",
    "seating_ci95_high_m",
    "accrued_mean_m",
    "accrued_sd_m",
    "accrued_ci95_low_m",
    "accrued_ci95_high_m",
];

/// The columns of `convergence.csv` that compare a setting with the reference
/// setting: the differences of the ensemble means (this setting's minus the
/// reference's) of the settlement after `N` cycles and of the accrued
/// settlement, each with Welch's 95 % interval and whether 0 is inside it
/// (`true`: the setting cannot be told from the reference at 95 %). Empty
/// unless both settings have two replicas or more.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ReferenceColumns {
    /// Column `reference`: the reference setting, `POLICY:TOLERANCE`.
    pub reference: String,
    /// Column `settlement_diff_m`: difference of the mean settlements after `N` cycles (m).
    pub settlement_diff_m: Option<f64>,
    /// Column `settlement_diff_ci95_low_m`: lower end of its Welch 95 % interval (m).
    pub settlement_diff_ci95_low_m: Option<f64>,
    /// Column `settlement_diff_ci95_high_m`: upper end (m).
    pub settlement_diff_ci95_high_m: Option<f64>,
    /// Column `settlement_same_as_reference`: 0 is inside that interval.
    pub settlement_same_as_reference: Option<bool>,
    /// Column `accrued_diff_m`: difference of the mean accrued settlements (m).
    pub accrued_diff_m: Option<f64>,
    /// Column `accrued_diff_ci95_low_m`: lower end of its Welch 95 % interval (m).
    pub accrued_diff_ci95_low_m: Option<f64>,
    /// Column `accrued_diff_ci95_high_m`: upper end (m).
    pub accrued_diff_ci95_high_m: Option<f64>,
    /// Column `accrued_same_as_reference`: 0 is inside that interval.
    pub accrued_same_as_reference: Option<bool>,
}

/// The names of the [`ReferenceColumns`].
pub const REFERENCE_COLUMNS: [&str; 9] = [
    "reference",
    "settlement_diff_m",
    "settlement_diff_ci95_low_m",
    "settlement_diff_ci95_high_m",
    "settlement_same_as_reference",
    "accrued_diff_m",
    "accrued_diff_ci95_low_m",
    "accrued_diff_ci95_high_m",
    "accrued_same_as_reference",
];

impl ReferenceColumns {
    /// The comparison of `setting` with `reference` (named `name`); the fields
    /// are empty when either is missing or has fewer than two replicas.
    pub fn of(name: &str, setting: Option<&SettlementSummary>, reference: Option<&SettlementSummary>) -> Self {
        let pair = setting.zip(reference);
        let t = pair.and_then(|(s, r)| welch(&s.settlement, &r.settlement));
        let a = pair.and_then(|(s, r)| welch(&s.accrued, &r.accrued));
        Self {
            reference: name.to_string(),
            settlement_diff_m: t.map(|d| d.diff),
            settlement_diff_ci95_low_m: t.map(|d| d.ci95.0),
            settlement_diff_ci95_high_m: t.map(|d| d.ci95.1),
            settlement_same_as_reference: t.map(|d| d.contains_zero()),
            accrued_diff_m: a.map(|d| d.diff),
            accrued_diff_ci95_low_m: a.map(|d| d.ci95.0),
            accrued_diff_ci95_high_m: a.map(|d| d.ci95.1),
            accrued_same_as_reference: a.map(|d| d.contains_zero()),
        }
    }
}
