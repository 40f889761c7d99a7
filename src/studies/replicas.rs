//! Replicas of a run from perturbed starts, and the statistics of their
//! ensemble (SI units: positions and settlements in m).
//!
//! The seating settlement of the Saussine sample is chaotic: the same run,
//! started with every grain moved by at most 1e-9 m, can settle 15.0 mm after 10
//! cycles instead of 20.6 mm. One run proves nothing; a setting is run as `R`
//! replicas and reported with a 95 % confidence interval of its mean.
//!
//! - **Perturbation** ([`Perturbation`], [`perturb_scene`]): replica 0 is the
//!   unperturbed start; replica `r ≥ 1` moves the position of every mobile
//!   (non-fixed) body by a random displacement uniform in the disc of radius
//!   [`Perturbation::distance_m`] (angle uniform in [0, 2π), radius
//!   `distance·√u`, `u` uniform in [0, 1)). The draws come from ChaCha8 seeded
//!   with [`Perturbation::seed`], on stream `r` ([`Perturbation::rng`]): the
//!   replicas of one seed are independent streams of one generator, and the
//!   same `(seed, r)` always gives the same scene. The bodies draw in the
//!   scene's order, mobile bodies only. The angle and the velocities are not
//!   touched. What was done is recorded in each run folder as
//!   [`REPLICA_FILE`] ([`ReplicaRecord`]). The 3D (MD) scenes have the same
//!   with a displacement uniform in the ball ([`perturb_md_scene`], [`ball_point`]).
//! - **Statistics of the mean** ([`Estimate`]): mean, sample standard deviation
//!   (divisor `R − 1`) and the 95 % confidence interval of the mean,
//!   `mean ± t_{0.975, R−1} · sd / √R` (Student's t quantile from `statrs`,
//!   [`t_quantile_975`]). With one replica there is no standard deviation nor
//!   interval: those fields are `None`, written as empty CSV fields (never NaN).
//! - **Difference of two means** ([`Difference`], [`welch`]): `mean(a) −
//!   mean(b)` with Welch's 95 % interval, `± t_{0.975, ν} · √(s_a²/n_a + s_b²/n_b)`
//!   with the Welch–Satterthwaite degrees of freedom ν; it needs two replicas
//!   or more on each side.
//! - **Seating and accrued settlement** ([`settlement_ensemble`],
//!   [`SettlementSummary`]): from each replica's `cycles.csv`
//!   ([`PlaneCycleRow::settlement_at_min_load_m`], the settlement at the load
//!   minimum of each cycle), the seating is the settlement at cycle `S`
//!   ([`DEFAULT_SEATING_CYCLES`], clipped to the cycles run; `S = 0` is the
//!   start, where the settlement is 0) and the accrued settlement of cycle
//!   `n ≥ S` is `settlement(n) − settlement(S)`, computed per replica and then
//!   averaged. Each has its own [`Estimate`].
//!
//! One replica's start, perturbed:
//! ```no_run
//! use ballast::scene::Scene;
//! use ballast::studies::replicas::{perturb_scene, Perturbation};
//! let mut scene = Scene::load("out/sample1/sample.toml")?;
//! let record = perturb_scene(&mut scene, &Perturbation { distance_m: 1e-9, seed: 7 }, 3)?;
//! assert!(record.largest_displacement_m <= 1e-9);
//! # Ok::<(), ballast::Error>(())
//! ```

use crate::error::{Error, Result};
use crate::plane::rows::PlaneCycleRow;
use crate::scene::{MdScene, Scene};
use crate::settlement::SettlementRow;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, UnitBall};
use serde::{Deserialize, Serialize};
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Default radius of the start perturbation (m): far below any physical length
/// of the sample, far above the rounding of its coordinates (≈ 1e-17 m).
pub const DEFAULT_PERTURBATION_M: f64 = 1e-9;

/// Default seed of the perturbations.
pub const DEFAULT_PERTURB_SEED: u64 = 1;

/// Default number of seating cycles `S`: the first cycles seat the sleeper and
/// its bars, a chaotic rearrangement (BENCHMARKS.md, "the 10-cycle
/// settlements"); the accrued settlement is counted from there.
pub const DEFAULT_SEATING_CYCLES: u64 = 10;

/// The file of a run folder that says which replica it is ([`ReplicaRecord`]).
pub const REPLICA_FILE: &str = "replica.json";

/// How the starts of the replicas are perturbed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Perturbation {
    /// Largest displacement of a body's position (m), ≥ 0; 0 gives replicas
    /// identical to replica 0.
    pub distance_m: f64,
    /// Seed of the generator (ChaCha8); replica `r` draws from its stream `r`.
    pub seed: u64,
}

/// The start of one run of a sample: replica 0 is the sample as it is,
/// replica `r ≥ 1` the sample with every mobile body moved by `perturbation`
/// (stream `r` of its seed: [`perturb_scene`], [`perturb_md_scene`]), recorded
/// as [`REPLICA_FILE`] in the run's folder. The same `r` and perturbation give
/// the start of replica `r` of an ensemble, so one replica can be run alone.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Start {
    /// The replica: 0 for the sample as it is.
    pub replica: u64,
    /// How replicas `r ≥ 1` are perturbed (default: ≤ 1e-9 m, seed 1).
    pub perturbation: Perturbation,
}

impl Default for Perturbation {
    /// [`DEFAULT_PERTURBATION_M`], [`DEFAULT_PERTURB_SEED`].
    fn default() -> Self {
        Self { distance_m: DEFAULT_PERTURBATION_M, seed: DEFAULT_PERTURB_SEED }
    }
}

impl Perturbation {
    /// Checks the distance.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `--perturb` if the distance is negative or not finite.
    pub fn check(&self) -> Result<()> {
        if self.distance_m.is_finite() && self.distance_m >= 0.0 {
            Ok(())
        } else {
            Err(Error::Scene(format!("--perturb: must be a distance ≥ 0 m, got {}", self.distance_m)))
        }
    }

    /// The generator of replica `replica`: ChaCha8 seeded with [`Self::seed`],
    /// on stream `replica`.
    pub fn rng(&self, replica: u64) -> ChaCha8Rng {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(replica);
        rng
    }

    /// The displacements (m) of `bodies` bodies for replica `replica`, in order:
    /// zero for replica 0, else each uniform in the disc of radius
    /// [`Self::distance_m`] ([`disc_point`]).
    pub fn displacements(&self, replica: u64, bodies: usize) -> Vec<[f64; 2]> {
        if replica == 0 {
            return vec![[0.0; 2]; bodies];
        }
        let mut rng = self.rng(replica);
        (0..bodies).map(|_| disc_point(&mut rng, self.distance_m)).collect()
    }
}

/// A point uniform in the disc of radius `radius` centred on the origin: angle
/// uniform in [0, 2π), distance `radius·√u` with `u` uniform in [0, 1) (the
/// area below a distance grows as its square).
pub fn disc_point(rng: &mut impl RngExt, radius: f64) -> [f64; 2] {
    let angle: f64 = rng.random_range(0.0..std::f64::consts::TAU);
    let u: f64 = rng.random_range(0.0..1.0);
    let r = radius * u.sqrt();
    [r * angle.cos(), r * angle.sin()]
}

/// A point uniform in the ball of radius `radius` centred on the origin
/// (`rand_distr::UnitBall`, by rejection from the cube, scaled).
pub fn ball_point(rng: &mut impl rand::Rng, radius: f64) -> [f64; 3] {
    let u: [f64; 3] = UnitBall.sample(rng);
    u.map(|c| c * radius)
}

/// What a replica's start was: written as [`REPLICA_FILE`] in its run folder.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplicaRecord {
    /// The replica: 0 for the unperturbed start.
    pub replica: u64,
    /// The perturbation's radius (m), as asked (replica 0 is not moved whatever it is).
    pub perturb_m: f64,
    /// The perturbation's seed (the replica draws from its stream `replica`).
    pub perturb_seed: u64,
    /// Bodies moved: the mobile ones, none for replica 0.
    pub bodies_moved: usize,
    /// The largest displacement given to a body (m), ≤ `perturb_m`.
    pub largest_displacement_m: f64,
}

impl ReplicaRecord {
    /// The record of replica `replica` of `perturbation` before any body moved.
    fn unmoved(perturbation: &Perturbation, replica: u64) -> Self {
        Self {
            replica,
            perturb_m: perturbation.distance_m,
            perturb_seed: perturbation.seed,
            bodies_moved: 0,
            largest_displacement_m: 0.0,
        }
    }
}

/// Perturbs the start of `scene` for replica `replica` (see the module
/// documentation): the position of every body that is not fixed moves by its
/// displacement of [`Perturbation::displacements`]; replica 0 is left as it is.
///
/// # Errors
/// [`Error::Scene`] for an invalid perturbation ([`Perturbation::check`]).
pub fn perturb_scene(scene: &mut Scene, perturbation: &Perturbation, replica: u64) -> Result<ReplicaRecord> {
    perturbation.check()?;
    let mobile: Vec<usize> = (0..scene.bodies.len()).filter(|&i| !scene.bodies[i].is_fixed()).collect();
    let mut record = ReplicaRecord::unmoved(perturbation, replica);
    if replica == 0 {
        return Ok(record);
    }
    for (&i, d) in mobile.iter().zip(perturbation.displacements(replica, mobile.len())) {
        let p = &mut scene.bodies[i].position;
        p[0] += d[0];
        p[1] += d[1];
        record.largest_displacement_m = record.largest_displacement_m.max(d[0].hypot(d[1]));
    }
    record.bodies_moved = mobile.len();
    Ok(record)
}

/// [`perturb_scene`] for an MD (3D) scene: replica `r ≥ 1` moves every sphere
/// by a displacement uniform in the ball of radius [`Perturbation::distance_m`]
/// ([`ball_point`], drawn in the scene's order from [`Perturbation::rng`]);
/// walls, velocities and spins are not touched; replica 0 is left as it is.
///
/// # Errors
/// [`Error::Scene`] for an invalid perturbation ([`Perturbation::check`]).
pub fn perturb_md_scene(scene: &mut MdScene, perturbation: &Perturbation, replica: u64) -> Result<ReplicaRecord> {
    perturbation.check()?;
    let mut record = ReplicaRecord::unmoved(perturbation, replica);
    if replica == 0 {
        return Ok(record);
    }
    let mut rng = perturbation.rng(replica);
    for body in &mut scene.bodies {
        let d = ball_point(&mut rng, perturbation.distance_m);
        for (p, d) in body.position.iter_mut().zip(d) {
            *p += d;
        }
        record.largest_displacement_m = record.largest_displacement_m.max(d[0].hypot(d[1]).hypot(d[2]));
    }
    record.bodies_moved = scene.bodies.len();
    Ok(record)
}

/// The 0.975 quantile of Student's t distribution with `dof` degrees of
/// freedom (> 0, not necessarily whole): the factor of a two-sided 95 %
/// interval (`statrs`; 12.706 for 1, 2.776445 for 4, → 1.959964 as `dof` → ∞).
/// NaN for `dof` ≤ 0 or NaN.
///
/// `statrs` inverts the regularised incomplete beta function: within 1e-9 of
/// the tables up to 1e4 degrees of freedom, but 7e-6 off at 1e5 and 0.13 at 1e7.
/// Above [`T_EXPANSION_DOF`] the Cornish–Fisher expansion of the t quantile
/// about the normal one is taken instead (`z + (z³ + z)/4ν + (5z⁵ + 16z³ +
/// 3z)/96ν² + (3z⁷ + 19z⁵ + 17z³ − 15z)/384ν³`, Abramowitz & Stegun 26.7.5),
/// whose first omitted term is below 1e-14 there. Replicas give far fewer
/// degrees of freedom; this only keeps the function right everywhere.
pub fn t_quantile_975(dof: f64) -> f64 {
    if dof > T_EXPANSION_DOF {
        let z = Z_975;
        let (z3, z5, z7) = (z.powi(3), z.powi(5), z.powi(7));
        return z
            + (z3 + z) / (4.0 * dof)
            + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * dof * dof)
            + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * dof.powi(3));
    }
    match StudentsT::new(0.0, 1.0, dof) {
        Ok(t) if dof > 0.0 => t.inverse_cdf(0.975),
        _ => f64::NAN,
    }
}

/// Degrees of freedom above which [`t_quantile_975`] is an expansion about the
/// normal quantile rather than `statrs`.
pub const T_EXPANSION_DOF: f64 = 1e4;

/// The 0.975 quantile of the standard normal distribution.
const Z_975: f64 = 1.959_963_984_540_054;

/// The mean of some replicas' values and its 95 % confidence interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// Number of values (replicas).
    pub n: usize,
    /// Arithmetic mean (unit of the values).
    pub mean: f64,
    /// Sample standard deviation, divisor `n − 1`; `None` for one value.
    pub sd: Option<f64>,
    /// 95 % confidence interval of the mean, `(low, high)` =
    /// `mean ∓ t_{0.975, n−1} · sd / √n`; `None` for one value.
    pub ci95: Option<(f64, f64)>,
}

impl Estimate {
    /// The estimate of the mean of `values`; `None` if there are none.
    pub fn of(values: &[f64]) -> Option<Self> {
        let n = values.len();
        if n == 0 {
            return None;
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        if n == 1 {
            return Some(Self { n, mean, sd: None, ci95: None });
        }
        let var = values.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let sd = var.sqrt();
        let half = t_quantile_975((n - 1) as f64) * sd / (n as f64).sqrt();
        Some(Self { n, mean, sd: Some(sd), ci95: Some((mean - half, mean + half)) })
    }

    /// The lower end of the interval.
    pub fn low(&self) -> Option<f64> {
        self.ci95.map(|c| c.0)
    }

    /// The upper end of the interval.
    pub fn high(&self) -> Option<f64> {
        self.ci95.map(|c| c.1)
    }
}

/// The difference of two means, `mean(a) − mean(b)`, with Welch's 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Difference {
    /// `mean(a) − mean(b)` (unit of the values).
    pub diff: f64,
    /// Its standard error `√(s_a²/n_a + s_b²/n_b)`.
    pub se: f64,
    /// Welch–Satterthwaite degrees of freedom; when both samples have a zero
    /// spread (`se = 0`) it is undefined and `n_a + n_b − 2` is taken (the
    /// interval has zero width whatever it is).
    pub dof: f64,
    /// 95 % interval `(low, high)` = `diff ∓ t_{0.975, dof} · se`.
    pub ci95: (f64, f64),
}

impl Difference {
    /// Whether 0 is inside the interval: the two means cannot be told apart at 95 %.
    pub fn contains_zero(&self) -> bool {
        self.ci95.0 <= 0.0 && 0.0 <= self.ci95.1
    }
}

/// The difference of the means of `a` and `b` with Welch's 95 % interval
/// (unequal variances); `None` unless each has two values or more.
pub fn welch(a: &[f64], b: &[f64]) -> Option<Difference> {
    let (ea, eb) = (Estimate::of(a)?, Estimate::of(b)?);
    let (sa, sb) = (ea.sd?, eb.sd?);
    let (na, nb) = (a.len() as f64, b.len() as f64);
    let (va, vb) = (sa * sa / na, sb * sb / nb);
    let se = (va + vb).sqrt();
    let dof = if se > 0.0 { (va + vb).powi(2) / (va * va / (na - 1.0) + vb * vb / (nb - 1.0)) } else { na + nb - 2.0 };
    let diff = ea.mean - eb.mean;
    let half = t_quantile_975(dof) * se;
    Some(Difference { diff, se, dof, ci95: (diff - half, diff + half) })
}

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
/// load minimum: `cycles.csv` of a plain run ([`PlaneCycleRow`]), `settlement.csv`
/// of an accelerated one ([`SettlementRow`]: computed cycles measured there, the
/// extrapolated ones on the fitted law).
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

/// How a setting is replicated: the number of replicas, their perturbation and
/// the seating cycles of their statistics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Replicas {
    /// Replicas per setting, ≥ 1 (1: replica 0 alone, the unperturbed run).
    pub count: u64,
    /// How the starts of replicas 1, 2, … are perturbed.
    pub perturbation: Perturbation,
    /// `S`, the seating cycles ([`DEFAULT_SEATING_CYCLES`]); clipped to the cycles run.
    pub seating_cycles: u64,
}

impl Default for Replicas {
    /// One replica (today's single run), the default perturbation and seating.
    fn default() -> Self {
        Self { count: 1, perturbation: Perturbation::default(), seating_cycles: DEFAULT_SEATING_CYCLES }
    }
}

impl Replicas {
    /// Checks the count and the perturbation.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `--replicas` or `--perturb`.
    pub fn check(&self) -> Result<()> {
        if self.count == 0 {
            return Err(Error::Scene("--replicas: must be at least 1".into()));
        }
        self.perturbation.check()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) {
        assert!((a - b).abs() <= tol, "{a} vs {b}");
    }

    #[test]
    fn t_quantiles_are_the_tables() {
        // Tables of Student's t, two-sided 95 %.
        close(t_quantile_975(1.0), 12.706_204_736, 1e-6);
        close(t_quantile_975(2.0), 4.302_652_730, 1e-7);
        close(t_quantile_975(4.0), 2.776_445_105, 1e-6);
        close(t_quantile_975(9.0), 2.262_157_163, 1e-7);
        close(t_quantile_975(30.0), 2.042_272_456, 1e-7);
        close(t_quantile_975(1000.0), 1.962_339_081, 1e-8);
        // Both sides of the switch to the expansion, and far beyond.
        close(t_quantile_975(1e4), 1.960_201_240, 1e-9);
        close(t_quantile_975(1.0001e4), 1.960_201_216, 1e-9);
        close(t_quantile_975(1e5), 1.959_987_708, 1e-9);
        close(t_quantile_975(1e7), 1.959_964_222, 1e-9);
        assert!(t_quantile_975(0.0).is_nan() && t_quantile_975(f64::NAN).is_nan());
    }

    #[test]
    fn estimate_by_hand() {
        // 1, 2, 3, 4, 5: mean 3, variance 10/4 = 2.5, half width t_{.975,4} √2.5 / √5.
        let e = Estimate::of(&[1.0, 2.0, 3.0, 4.0, 5.0]).unwrap();
        assert_eq!((e.n, e.mean), (5, 3.0));
        close(e.sd.unwrap(), 2.5f64.sqrt(), 1e-15);
        let half = 2.776_445_105 * (0.5f64).sqrt();
        close(e.low().unwrap(), 3.0 - half, 1e-8);
        close(e.high().unwrap(), 3.0 + half, 1e-8);
        // Two values a, b: sd = |a − b|/√2, half width 12.706 · |a − b| / 2.
        let e = Estimate::of(&[0.010, 0.014]).unwrap();
        close(e.sd.unwrap(), 0.004 / 2f64.sqrt(), 1e-15);
        close(e.high().unwrap() - e.mean, 12.706_204_736 * 0.002, 1e-10);
        // One value: a mean, no spread nor interval.
        let e = Estimate::of(&[0.02]).unwrap();
        assert_eq!((e.mean, e.sd, e.ci95), (0.02, None, None));
        assert_eq!(Estimate::of(&[]), None);
        // Equal values: a zero spread, an interval of zero width.
        let e = Estimate::of(&[0.5; 4]).unwrap();
        assert_eq!((e.sd, e.ci95), (Some(0.0), Some((0.5, 0.5))));
    }

    #[test]
    fn welch_by_hand() {
        // a = 1, 2, 3 (mean 2, s² = 1), b = 2, 4, 6, 8 (mean 5, s² = 20/3):
        // va = 1/3, vb = 5/3, se = √2, ν = 4 / ((1/9)/2 + (25/9)/3) = 4 / (1/18 + 25/27).
        let d = welch(&[1.0, 2.0, 3.0], &[2.0, 4.0, 6.0, 8.0]).unwrap();
        close(d.diff, -3.0, 1e-15);
        close(d.se, 2f64.sqrt(), 1e-15);
        let nu = 4.0 / (1.0 / 18.0 + 25.0 / 27.0);
        close(d.dof, nu, 1e-12);
        let half = t_quantile_975(nu) * 2f64.sqrt();
        close(d.ci95.0, -3.0 - half, 1e-12);
        close(d.ci95.1, -3.0 + half, 1e-12);
        // ν ≈ 4.07: the quantile lies between those of 4 and 5 dof.
        assert!(t_quantile_975(nu) < 2.776_445 && t_quantile_975(nu) > 2.570_581);
        // |diff| = 3 < half ≈ 2.76 · 1.41: the means cannot be told apart.
        assert!(half > 3.0 && d.contains_zero());
        assert!(!welch(&[1.0, 1.1, 0.9], &[5.0, 5.2, 4.8]).unwrap().contains_zero());
        // Fewer than two values on a side: no interval.
        assert_eq!(welch(&[1.0], &[1.0, 2.0]), None);
        // Zero spreads: a zero-width interval.
        let d = welch(&[1.0, 1.0], &[2.0, 2.0, 2.0]).unwrap();
        assert_eq!((d.diff, d.ci95, d.dof), (-1.0, (-1.0, -1.0), 3.0));
    }

    fn row(cycle: u64, s: f64) -> PlaneCycleRow {
        PlaneCycleRow {
            cycle,
            time_s: cycle as f64 * 0.05,
            settlement_mean_m: s,
            settlement_at_min_load_m: s,
            mean_grain_speed_m_s: 0.0,
            contacts: 0.0,
            iterations: 0.0,
            max_overlap_m: 0.0,
            mean_overlap_m: 0.0,
            coordination: 0.0,
        }
    }

    #[test]
    fn seating_and_accrued_per_replica() {
        let a: Vec<_> = [1.0, 2.0, 2.5, 3.0].iter().enumerate().map(|(i, &s)| row(i as u64 + 1, s)).collect();
        let b: Vec<_> = [2.0, 3.0, 4.0, 4.5, 9.0].iter().enumerate().map(|(i, &s)| row(i as u64 + 1, s)).collect();
        let runs = [&a[..], &b[..]];
        let rows = settlement_ensemble(&runs, 2);
        assert_eq!(rows.len(), 4, "the cycles both reached");
        assert_eq!(rows[0].accrued_mean_m, None);
        assert_eq!(rows[1].accrued_mean_m, Some(0.0));
        // Cycle 4: a accrued 1.0, b 1.5 → mean 1.25; totals 3 and 4.5.
        assert_eq!((rows[3].settlement_mean_m, rows[3].accrued_mean_m), (3.75, Some(1.25)));
        close(rows[3].accrued_sd_m.unwrap(), 0.5 / 2f64.sqrt(), 1e-15);
        let s = SettlementSummary::of(&runs, 2).unwrap();
        assert_eq!((s.cycle, s.seating_cycle, s.accrued.clone()), (4, 2, vec![1.0, 1.5]));
        // S beyond the cycles run: clipped (accrued 0), S = 0: the total.
        assert_eq!(SettlementSummary::of(&runs, 50).unwrap().accrued, vec![0.0, 0.0]);
        assert_eq!(SettlementSummary::of(&runs, 0).unwrap().accrued, vec![3.0, 4.5]);
        // One replica: no spread fields.
        let one = settlement_ensemble(&runs[..1], 2);
        assert_eq!((one[3].settlement_sd_m, one[3].accrued_ci95_low_m), (None, None));
        let c = SettlementSummary::of(&runs[..1], 2).unwrap().columns();
        assert_eq!((c.replicas, c.settlement_ens_mean_m, c.settlement_ens_sd_m), (1, Some(3.0), None));
    }

    #[test]
    fn disc_points_fill_the_disc() {
        let mut rng = Perturbation { distance_m: 2.0, seed: 5 }.rng(1);
        let points: Vec<_> = (0..20_000).map(|_| disc_point(&mut rng, 2.0)).collect();
        assert!(points.iter().all(|p| p[0].hypot(p[1]) <= 2.0));
        // Uniform in the disc: a quarter of the points within half the radius,
        // mean x and y ≈ 0 (binomial sd of the fraction ≈ 0.003).
        let inner = points.iter().filter(|p| p[0].hypot(p[1]) < 1.0).count() as f64 / points.len() as f64;
        close(inner, 0.25, 0.015);
        let mx = points.iter().map(|p| p[0]).sum::<f64>() / points.len() as f64;
        close(mx, 0.0, 0.03);
    }

    #[test]
    fn replica_streams_differ_and_repeat() {
        let p = Perturbation { distance_m: 1e-9, seed: 3 };
        assert_eq!(p.displacements(0, 3), vec![[0.0; 2]; 3]);
        assert_eq!(p.displacements(2, 5), p.displacements(2, 5));
        assert_ne!(p.displacements(1, 5), p.displacements(2, 5));
        assert_ne!(p.displacements(1, 5), Perturbation { seed: 4, ..p }.displacements(1, 5));
        assert!(Perturbation { distance_m: -1.0, seed: 0 }.check().is_err());
        assert!(Perturbation { distance_m: f64::NAN, seed: 0 }.check().is_err());
    }
}
