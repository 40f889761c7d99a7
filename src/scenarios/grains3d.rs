//! Railway ballast grains for the 3D engine: convex hulls of 12–30 random points on random ellipsoids, sized by a
//! ballast grading (issue "3D NSCD": "hulls of 12–30 points on random ellipsoids, a railway ballast grading such
//! as 25–50 mm, a seed"; the grains of Quezada, Breul, Saussine & Radjai 2012 and of LMGC90's own polyhedral
//! ballast are built the same way).
//!
//! Decisions, written down:
//! - **Size.** A grain's sieve size `d` is the side of the square mesh it passes; a grain passes when its two
//!   smaller dimensions fit the mesh, so `d` is taken as its intermediate dimension, `2 b` for semi-axes
//!   `a ≥ b ≥ c`.
//! - **Grading.** The sieve size is spread so that the **mass** passing grows linearly from `d_min` to `d_max`
//!   (a uniform grading by mass, the shape of the EN 13450 / SNCF 25–50 mm envelopes' middle): by number the
//!   density is `∝ d⁻³` on `[d_min, d_max]`, drawn by inverting its distribution.
//! - **Shape.** Elongation `a/b` uniform in `[1, 1.5]`, flatness `c/b` uniform in `[0.6, 1]` (crushed granite
//!   ballast: elongation and flakiness indices of a few per cent exclude more extreme grains); the ellipsoid is
//!   turned by a uniformly random rotation; the points are random directions (normal deviates, normalised) scaled
//!   to its surface, their count uniform in `[points_min, points_max]`.
//! - The hull's faces merge coplanar triangles within [`Polyhedron::MERGE_ANGLE`]. A draw whose hull is
//!   degenerate is redrawn (at most 100 times, which never happens for ≥ 4 points on an ellipsoid, but a loop
//!   must end).

use super::{positive, refuse};
use crate::error::Result;
use crate::geometry::{Polyhedron, Vec3};
use nalgebra::UnitQuaternion;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// What grains to draw.
#[derive(Debug, Clone, PartialEq)]
pub struct GrainSpec {
    /// Smallest sieve size (m). Default 0.025.
    pub d_min: f64,
    /// Largest sieve size (m). Default 0.05.
    pub d_max: f64,
    /// Fewest hull points drawn per grain. Default 12.
    pub points_min: usize,
    /// Most hull points drawn per grain. Default 30.
    pub points_max: usize,
    /// Largest elongation `a/b`. Default 1.5.
    pub elongation_max: f64,
    /// Smallest flatness `c/b`. Default 0.6.
    pub flatness_min: f64,
    /// Seed of the draws.
    pub seed: u64,
}

impl Default for GrainSpec {
    fn default() -> Self {
        Self {
            d_min: 0.025,
            d_max: 0.05,
            points_min: 12,
            points_max: 30,
            elongation_max: 1.5,
            flatness_min: 0.6,
            seed: 1,
        }
    }
}

impl GrainSpec {
    /// Checks the spec: one-line errors naming the field.
    pub fn check(&self) -> Result<()> {
        positive("grains.d_min", self.d_min)?;
        positive("grains.d_max", self.d_max)?;
        if self.d_max < self.d_min {
            return refuse(format!("grains.d_max: must be at least d_min ({}), got {}", self.d_min, self.d_max));
        }
        if self.points_min < 4 {
            return refuse(format!("grains.points_min: a hull needs at least 4 points, got {}", self.points_min));
        }
        if self.points_max < self.points_min {
            return refuse(format!(
                "grains.points_max: must be at least points_min ({}), got {}",
                self.points_min, self.points_max
            ));
        }
        if !(self.elongation_max.is_finite() && self.elongation_max >= 1.0) {
            return refuse(format!("grains.elongation_max: must be at least 1, got {}", self.elongation_max));
        }
        if !(self.flatness_min > 0.0 && self.flatness_min <= 1.0) {
            return refuse(format!("grains.flatness_min: must be in (0, 1], got {}", self.flatness_min));
        }
        Ok(())
    }
}

/// A drawn grain: its hull in its principal frame and its sieve size.
#[derive(Debug, Clone, PartialEq)]
pub struct Grain {
    /// The hull, centroid at the origin, principal axes.
    pub shape: Polyhedron,
    /// Its sieve size `2 b` (m).
    pub sieve: f64,
}

/// Draws `count` grains of `spec` (the same spec and count give the same grains, bit for bit).
pub fn grains(spec: &GrainSpec, count: usize) -> Result<Vec<Grain>> {
    spec.check()?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    (0..count).map(|_| grain(spec, &mut rng)).collect()
}

/// The sieve size of a uniform-by-mass grading: the number density `∝ d⁻³` on `[d_min, d_max]` inverted at
/// `x ∈ [0, 1)`: `d⁻² = d_min⁻² − x (d_min⁻² − d_max⁻²)`.
pub fn sieve_size(d_min: f64, d_max: f64, x: f64) -> f64 {
    let (lo, hi) = (d_min.powi(-2), d_max.powi(-2));
    (lo - x * (lo - hi)).powf(-0.5)
}

fn grain(spec: &GrainSpec, rng: &mut ChaCha8Rng) -> Result<Grain> {
    let d = sieve_size(spec.d_min, spec.d_max, rng.random::<f64>());
    let b = 0.5 * d;
    let a = b * (1.0 + (spec.elongation_max - 1.0) * rng.random::<f64>());
    let c = b * (spec.flatness_min + (1.0 - spec.flatness_min) * rng.random::<f64>());
    let turn = random_rotation(rng);
    for _ in 0..100 {
        let n = rng.random_range(spec.points_min..=spec.points_max);
        let points: Vec<[f64; 3]> = (0..n)
            .map(|_| {
                let g = Vec3::new(StandardNormal.sample(rng), StandardNormal.sample(rng), StandardNormal.sample(rng));
                let dir = g / g.norm().max(f64::MIN_POSITIVE);
                let p = turn * Vec3::new(a * dir.x, b * dir.y, c * dir.z);
                [p.x, p.y, p.z]
            })
            .collect();
        if let Ok((shape, _)) = Polyhedron::from_points(&points, Polyhedron::MERGE_ANGLE) {
            return Ok(Grain { shape, sieve: d });
        }
    }
    refuse(format!("grains: 100 draws of {}–{} points gave no hull with a volume", spec.points_min, spec.points_max))
}

/// A uniformly random rotation (a normalised quaternion of four normal deviates).
fn random_rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
    let q: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(rng));
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[0], q[1], q[2], q[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grading by mass: the mass of the grains of sieve size below the median `d_m = (d_min + d_max)/2`
    /// is half the total when the mass ∝ d³ and the number density ∝ d⁻³ (the mass density is flat). With 20 000
    /// draws the fraction's standard error is about 0.004: 0.02 is 5 of them.
    #[test]
    fn the_grading_is_uniform_by_mass() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let (lo, hi) = (0.025, 0.05);
        let sizes: Vec<f64> = (0..20_000).map(|_| sieve_size(lo, hi, rng.random::<f64>())).collect();
        assert!(sizes.iter().all(|d| (lo..=hi).contains(d)));
        let mass = |pred: &dyn Fn(f64) -> bool| sizes.iter().filter(|&&d| pred(d)).map(|d| d.powi(3)).sum::<f64>();
        let below = mass(&|d| d < 0.5 * (lo + hi)) / mass(&|_| true);
        assert!((below - 0.5).abs() < 0.02, "mass fraction below the median sieve size: {below}");
    }

    /// The grains are hulls of at most `points_max` points with the drawn sizes, and the same seed gives the same
    /// grains bit for bit.
    #[test]
    fn grains_are_seeded_hulls_of_the_graded_sizes() {
        let spec = GrainSpec::default();
        let drawn = grains(&spec, 50).unwrap();
        for g in &drawn {
            assert!((spec.d_min..=spec.d_max).contains(&g.sieve));
            assert!(g.shape.vertices.len() >= 4 && g.shape.vertices.len() <= spec.points_max);
            // The hull is inside its ellipsoid (semi-axes at most 0.75 d, 0.5 d, 0.5 d): no vertex is further than
            // its longest axis 1.5 d from the hull's centroid, and the volume is at most the ellipsoid's.
            assert!(g.shape.radius <= 1.5 * g.sieve);
            let ellipsoid = 4.0 / 3.0 * std::f64::consts::PI * 0.75 * 0.5 * 0.5 * g.sieve.powi(3);
            assert!(g.shape.volume > 0.0 && g.shape.volume <= ellipsoid);
        }
        assert_eq!(drawn, grains(&spec, 50).unwrap());
        assert_ne!(drawn, grains(&GrainSpec { seed: 2, ..spec }, 50).unwrap());
    }

    #[test]
    fn a_bad_spec_names_its_field() {
        let bad = |spec: GrainSpec, key: &str| {
            let e = grains(&spec, 1).unwrap_err().to_string();
            assert!(e.starts_with(key), "{e}");
        };
        bad(GrainSpec { d_min: 0.0, ..GrainSpec::default() }, "grains.d_min");
        bad(GrainSpec { d_max: 0.01, ..GrainSpec::default() }, "grains.d_max");
        bad(GrainSpec { points_min: 3, ..GrainSpec::default() }, "grains.points_min");
        bad(GrainSpec { points_max: 5, ..GrainSpec::default() }, "grains.points_max");
        bad(GrainSpec { elongation_max: 0.5, ..GrainSpec::default() }, "grains.elongation_max");
        bad(GrainSpec { flatness_min: 0.0, ..GrainSpec::default() }, "grains.flatness_min");
    }
}
