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
//!   [`REPLICA_FILE`] ([`ReplicaRecord`]). The 3D scenes have the same with a
//!   displacement uniform in the ball ([`ball_point`]): MD scenes
//!   ([`perturb_md_scene`], every sphere) and NSCD scenes of polyhedra
//!   ([`perturb_scene3`], every mobile body; the 3D track section).
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
//!   ([`PlaneCycleRow::settlement_at_min_load_m`] in 2D,
//!   [`CycleRow3::settlement_m`] in 3D: the settlement at the load minimum of
//!   each cycle, [`CycleSettlement`]), the seating is the settlement at cycle `S`
//!   ([`DEFAULT_SEATING_CYCLES`], clipped to the cycles run; `S = 0` is the
//!   start, where the settlement is 0) and the accrued settlement of cycle
//!   `n ≥ S` is `settlement(n) − settlement(S)`, computed per replica and then
//!   averaged. Each has its own [`Estimate`].
//!
//! One replica's start, perturbed:
//! ```no_run
//! use ballast::scene::{Scene, SceneFile};
//! use ballast::studies::replicas::{perturb_scene, Perturbation};
//! let mut scene = Scene::load("out/sample1/sample.toml")?;
//! let record = perturb_scene(&mut scene, &Perturbation { distance_m: 1e-9, seed: 7 }, 3)?;
//! assert!(record.largest_displacement_m <= 1e-9);
//! # Ok::<(), ballast::Error>(())
//! ```

mod ensemble;
mod stats;
mod text;

pub use ensemble::*;
pub use stats::*;
pub use text::perturbed_text;

use crate::error::{Error, Result};
use crate::nscd::d3::rows::CycleRow3;
use crate::plane::rows::PlaneCycleRow;
use crate::scene::{MdScene, Scene, Scene3};
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
    /// [`Error::Scene`] naming `perturbation.distance_m` if the distance is negative or not finite.
    pub fn check(&self) -> Result<()> {
        if self.distance_m.is_finite() && self.distance_m >= 0.0 {
            Ok(())
        } else {
            Err(Error::Scene(format!("perturbation.distance_m: must be a distance ≥ 0 m, got {}", self.distance_m)))
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
    perturb_in_ball(scene.bodies.iter_mut().map(|b| &mut b.position), perturbation, replica)
}

/// [`perturb_scene`] for a 3D NSCD scene (polyhedra, the track section of
/// [`crate::scenarios::track3d`]): replica `r ≥ 1` moves the position of every
/// mobile (not fixed) body by a displacement uniform in the ball of radius
/// [`Perturbation::distance_m`] ([`ball_point`], drawn in the scene's order,
/// mobile bodies only, from [`Perturbation::rng`]); fixed bodies, orientations,
/// velocities and spins are not touched; replica 0 is left as it is. The same
/// `(seed, r)` gives the same scene.
///
/// # Errors
/// [`Error::Scene`] for an invalid perturbation ([`Perturbation::check`]).
pub fn perturb_scene3(scene: &mut Scene3, perturbation: &Perturbation, replica: u64) -> Result<ReplicaRecord> {
    let mobile = scene.bodies.iter_mut().filter(|b| !b.is_fixed()).map(|b| &mut b.position);
    perturb_in_ball(mobile, perturbation, replica)
}

/// Moves each of `positions` (in order) by a displacement uniform in the ball
/// of [`Perturbation::distance_m`] drawn from stream `replica`; none for
/// replica 0. The record of what was done.
fn perturb_in_ball<'a>(
    positions: impl Iterator<Item = &'a mut [f64; 3]>,
    perturbation: &Perturbation,
    replica: u64,
) -> Result<ReplicaRecord> {
    perturbation.check()?;
    let mut record = ReplicaRecord::unmoved(perturbation, replica);
    if replica == 0 {
        return Ok(record);
    }
    let mut rng = perturbation.rng(replica);
    for position in positions {
        let d = ball_point(&mut rng, perturbation.distance_m);
        for (p, d) in position.iter_mut().zip(d) {
            *p += d;
        }
        record.largest_displacement_m = record.largest_displacement_m.max(d[0].hypot(d[1]).hypot(d[2]));
        record.bodies_moved += 1;
    }
    Ok(record)
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
    /// [`Error::Scene`] naming `replicas` or `perturbation.distance_m`.
    pub fn check(&self) -> Result<()> {
        if self.count == 0 {
            return Err(Error::Scene("replicas: must be at least 1".into()));
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
