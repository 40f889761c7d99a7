//! The MD benchmark bed of `../shared/peers/md-bed` (LAMMPS and LIGGGHTS inputs):
//! N Hertz–Mindlin spheres, diameters uniform in 8–12 mm, ρ = 2000 kg/m³,
//! E = 10⁸ Pa, ν = 0.3, restitution 0.5, μ = 0.5 (spheres and walls), in an
//! L × L box of planes (x = 0, L; y = 0, L; z = 0), started on a simple cubic
//! lattice of spacing 12.1 mm (the peers' `lattice sc 0.0121 origin 0.4959`,
//! region 6 mm inside the walls, filled x fastest, then y, then z) with random
//! horizontal velocities in ±2.5 cm/s, settling under gravity with velocity
//! Verlet at Δt = 5 µs and a 1 mm skin. The random numbers are ours (ChaCha8
//! from `seed`), the distributions the peers'.
//!
//! The bed is built directly as an [`MdSystem`] (it is a benchmark of the
//! engine, with no scene file); a spec with no sphere or a box too narrow for
//! one lattice site is an [`Error::Scene`](crate::Error::Scene).

use super::refuse;
use crate::error::Result;
use crate::md::{self, Ghosts, LawTable, Material, MdSettings, MdSystem, Particles, Shape, Wall, V3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One sphere of a generated sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SphereSpec {
    /// Radius (m), uniform in 4–6 mm.
    pub radius: f64,
    /// Centre at the start (m), a lattice site.
    pub position: V3,
    /// Initial velocity (m/s): horizontal components uniform in ±2.5 cm/s, vertical 0.
    pub velocity: V3,
}

/// Parameters of the bed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BedSpec {
    /// Number of spheres.
    pub n: usize,
    /// Box side (m): 0.1 for N = 2000, 0.2 for N = 8000.
    pub side: f64,
    /// Seed of the ChaCha8 generator of the radii and initial velocities.
    pub seed: u64,
}

impl BedSpec {
    /// The peers' bed of `n` spheres with its box side (0.1 m per 2000 spheres
    /// at the same depth: `side = 0.1 √(n / 2000)`).
    pub fn peers(n: usize, seed: u64) -> Self {
        BedSpec { n, side: 0.1 * (n as f64 / 2000.0).sqrt(), seed }
    }
}

/// Lattice spacing (m).
pub const SPACING: f64 = 0.0121;
/// Sphere material of the bed.
pub const MATERIAL: Material = Material { density: 2000.0, young: 1e8, poisson: 0.3 };
/// Restitution coefficient.
pub const RESTITUTION: f64 = 0.5;
/// Friction coefficient.
pub const FRICTION: f64 = 0.5;
/// Time step (s).
pub const DT: f64 = 5e-6;
/// Neighbour skin (m).
pub const SKIN: f64 = 1e-3;

/// Distance (m) of the first lattice site from the walls `x = 0`, `y = 0`.
const ORIGIN: f64 = 0.4959 * SPACING;

/// The narrowest box (m) that holds one lattice site 6 mm (the largest radius)
/// inside its walls, as the peers' region.
pub const MIN_SIDE: f64 = ORIGIN + 0.006;

/// The spheres of the bed on their lattice.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene): no sphere, or a side that is not finite
/// or below [`MIN_SIDE`].
pub fn bed_spheres(spec: &BedSpec) -> Result<Vec<SphereSpec>> {
    if spec.n == 0 {
        return refuse("md_bed: n (spheres) must be at least 1, got 0".into());
    }
    if !(spec.side.is_finite() && spec.side >= MIN_SIDE) {
        return refuse(format!("md_bed: side must be at least {MIN_SIDE} m (one lattice site), got {} m", spec.side));
    }
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let origin = ORIGIN;
    let per_row = ((spec.side - 0.006 - origin) / SPACING).floor() as usize + 1;
    let mut out = Vec::with_capacity(spec.n);
    'fill: for k in 0.. {
        for j in 0..per_row {
            for i in 0..per_row {
                if out.len() == spec.n {
                    break 'fill;
                }
                let d = 0.008 + 0.004 * rng.random::<f64>();
                let vx = 0.05 * (rng.random::<f64>() - 0.5);
                let vy = 0.05 * (rng.random::<f64>() - 0.5);
                let at = |m: usize| origin + SPACING * m as f64;
                out.push(SphereSpec {
                    radius: 0.5 * d,
                    position: V3::new(at(i), at(j), at(k)),
                    velocity: V3::new(vx, vy, 0.0),
                });
            }
        }
    }
    Ok(out)
}

/// The five walls of the bed: `(name, shape)`.
pub fn bed_walls(side: f64) -> Vec<(&'static str, Shape)> {
    let plane = |p: [f64; 3], n: [f64; 3]| Shape::Plane { point: V3::from(p), normal: V3::from(n) };
    vec![
        ("base", plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])),
        ("x0", plane([0.0, 0.0, 0.0], [1.0, 0.0, 0.0])),
        ("x1", plane([side, 0.0, 0.0], [-1.0, 0.0, 0.0])),
        ("y0", plane([0.0, 0.0, 0.0], [0.0, 1.0, 0.0])),
        ("y1", plane([0.0, side, 0.0], [0.0, -1.0, 0.0])),
    ]
}

/// The bed as a system ready to settle.
///
/// # Errors
/// Those of [`bed_spheres`].
pub fn bed_system(spec: &BedSpec) -> Result<MdSystem> {
    let mut p = Particles::default();
    for (k, s) in bed_spheres(spec)?.iter().enumerate() {
        p.push(&format!("s{k}"), 0, MATERIAL.density, s.radius, s.position, s.velocity, V3::zeros());
    }
    let mut laws = LawTable::new(1);
    let alpha = md::law::hertz_alpha_for_restitution(RESTITUTION);
    laws.set(0, 0, md::PairLaw::hertz(&MATERIAL, &MATERIAL, alpha, alpha, FRICTION));
    let walls =
        bed_walls(spec.side).into_iter().map(|(name, shape)| Wall::new(name, 0, shape, md::Motion::Fixed)).collect();
    let settings = MdSettings {
        dt: DT,
        gravity: V3::new(0.0, 0.0, -9.81),
        integrator: md::Integrator::Verlet,
        skin: SKIN,
        background_damping: 0.0,
        background_rotational_damping: 0.0,
    };
    MdSystem::new(settings, p, walls, laws, Ghosts::new(Vec::new()))
}

/// Height of the highest sphere centre (m): the peers' settled-bed figure.
pub fn top_centre(sys: &MdSystem) -> f64 {
    sys.particles.x.iter().map(|x| x[2]).fold(f64::NEG_INFINITY, f64::max)
}
