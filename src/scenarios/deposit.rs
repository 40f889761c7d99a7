//! A loose pentagon sample above a floor between two side walls, to be deposited
//! under gravity (Saussine et al. 2006, §3: pentagons of 1, 1.5 and 2 cm
//! "diameter" in the numbers 361 : 242 : 121, ρ = 2367 kg/m³, μ = 0.5, e = 0).
//!
//! "Diameter" is read as the diameter of the circumscribed circle, so the
//! circumradii are 5, 7.5 and 10 mm. Grains start on a jittered lattice of pitch
//! `2.2 r_max` with random orientations and small random velocities, all drawn
//! from a ChaCha8 generator seeded with `seed`: the same spec always gives the
//! same scene. The run ends at equilibrium (`simulation.equilibrium`: kinetic
//! energy below 1e-11 J per grain for 500 steps) or after `duration`.
//!
//! [`pentagon_deposit`] builds the [`Scene`] value (validated like a scene file);
//! save it with [`Scene::to_toml_string`](crate::scene::SceneFile::to_toml_string).

use super::{body, non_negative, positive, rect, refuse, validated};
use crate::error::Result;
use crate::run::Equilibrium;
use crate::scene::{ContactEntry, Material, NscdSection, OutputSection, RegularSpec, Scene, Simulation};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct DepositSpec {
    /// Number of grains of each circumradius `(radius m, count)`.
    pub grading: Vec<(f64, usize)>,
    /// Inner width of the box (m), at least one lattice column (`2.2 r_max`).
    pub width: f64,
    /// Grain density (kg/m³).
    pub density: f64,
    /// Coulomb friction coefficient `μ` of grain–grain and grain–wall contacts (dimensionless).
    pub friction: f64,
    /// Seed of the ChaCha8 generator of the grain order, lattice jitter, orientations
    /// and initial velocities; recorded in the scene.
    pub seed: u64,
    /// Time step of the deposit run (s).
    pub dt: f64,
    /// Longest deposit (s): the run ends earlier at equilibrium.
    pub duration: f64,
}

impl DepositSpec {
    /// The paper's grading scaled to `n` grains (proportions 361 : 242 : 121), in a
    /// box of `width` (m).
    pub fn saussine(n: usize, width: f64, seed: u64) -> Self {
        let total = 361.0 + 242.0 + 121.0;
        let n2 = (n as f64 * 121.0 / total).round() as usize;
        let n15 = (n as f64 * 242.0 / total).round() as usize;
        Self {
            grading: vec![(0.005, n - n2 - n15), (0.0075, n15), (0.01, n2)],
            width,
            density: 2367.0,
            friction: 0.5,
            seed,
            dt: 2e-4,
            duration: 1.5,
        }
    }
}

/// The radii of a grading `(radius m, count)` in a random order drawn from `rng`
/// (Fisher–Yates), so that the sizes are mixed through the height of a deposit.
pub(crate) fn shuffled_radii(grading: &[(f64, usize)], rng: &mut ChaCha8Rng) -> Vec<f64> {
    let mut radii: Vec<f64> = grading.iter().flat_map(|&(r, n)| std::iter::repeat_n(r, n)).collect();
    for i in (1..radii.len()).rev() {
        let j = rng.random_range(0..=i);
        radii.swap(i, j);
    }
    radii
}

/// `x` rounded to `decimals` decimals: the nearest `f64` to the decimal that
/// `format!("{x:.decimals$}")` writes (exact round-half-even of the binary
/// value, which `(x * 10^d).round() / 10^d` does not always reproduce). The
/// deposit keeps its positions and angles to 9 decimals (1 nm, 1 nrad) and its
/// velocities to 6 (1 µm/s), the numbers its scenes have always had.
fn round_to(x: f64, decimals: usize) -> f64 {
    format!("{x:.decimals$}").parse().unwrap_or(x)
}

/// Checks `spec`; returns the number of grains and the largest circumradius (m).
fn check(spec: &DepositSpec) -> Result<(usize, f64)> {
    let (n, _, r_max) = super::grading("deposit", &spec.grading)?;
    let width = positive("deposit: width (m)", spec.width)?;
    let pitch = 2.2 * r_max;
    if width < pitch {
        return refuse(format!(
            "deposit: width {width} m is narrower than one lattice column (2.2 × the largest circumradius = {pitch} m)"
        ));
    }
    positive("deposit: density (kg/m³)", spec.density)?;
    non_negative("deposit: friction", spec.friction)?;
    positive("deposit: dt (s)", spec.dt)?;
    positive("deposit: duration (s)", spec.duration)?;
    Ok((n, r_max))
}

/// The scene of a loose deposit (see `docs/scene-format.md`), validated like a
/// scene file.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: a grading without
/// grains or with a radius that is not positive, a width narrower than one
/// lattice column, a density, time step or duration that is not positive and
/// finite, a negative friction.
pub fn pentagon_deposit(spec: &DepositSpec) -> Result<Scene> {
    let (n, r_max) = check(spec)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let radii = shuffled_radii(&spec.grading, &mut rng);
    let pitch = 2.2 * r_max;
    let cols = ((spec.width / pitch).floor() as usize).max(1);
    let wall = 0.05;
    let rows = n.div_ceil(cols);
    let height = (rows as f64 + 2.0) * pitch;
    let w = spec.width;
    let mut bodies = Vec::with_capacity(n + 3);
    for (name, poly) in [
        ("floor", rect(-w / 2.0 - wall, -wall, w / 2.0 + wall, 0.0)),
        ("left_wall", rect(-w / 2.0 - wall, 0.0, -w / 2.0, height)),
        ("right_wall", rect(w / 2.0, 0.0, w / 2.0 + wall, height)),
    ] {
        bodies.push(crate::scene::BodySpec {
            polygon: Some(poly),
            fixed: Some(true),
            ..body(name, "wall", [0.0, 0.0])
        });
    }
    let x0 = -w / 2.0 + 0.5 * (w - (cols as f64 - 1.0) * pitch);
    for (k, &r) in radii.iter().enumerate() {
        let (i, j) = (k % cols, k / cols);
        let jitter = 0.5 * (pitch - 2.0 * r);
        let x = x0 + i as f64 * pitch + jitter * rng.random_range(-1.0..1.0);
        let y = pitch * (j as f64 + 0.5) + jitter * rng.random_range(-1.0..1.0);
        let angle = std::f64::consts::TAU * rng.random::<f64>();
        let v = [0.05 * rng.random_range(-1.0..1.0), 0.05 * rng.random_range(-1.0..1.0)];
        bodies.push(crate::scene::BodySpec {
            regular: Some(RegularSpec { sides: 5, radius: r }),
            angle: Some(round_to(angle, 9)),
            velocity: Some([round_to(v[0], 6), round_to(v[1], 6)]),
            ..body(format!("g{k}"), "grain", [round_to(x, 9), round_to(y, 9)])
        });
    }
    let contact = |other: &str| ContactEntry {
        between: ["grain".into(), other.into()],
        friction: spec.friction,
        restitution: None,
        tangential_restitution: None,
    };
    validated(Scene {
        soft: None,
        simulation: Simulation {
            engine: "nscd".into(),
            dt: spec.dt,
            duration: spec.duration,
            gravity: Some(vec![0.0, -9.81]),
            dimension: None,
            thickness: None,
            seed: Some(spec.seed),
            // Equilibrium: a kinetic energy below 1e-11 J per grain (a mean speed of about
            // 1e-5 m/s for these grains) held for 500 steps; `duration` is then an upper bound.
            equilibrium: Some(Equilibrium {
                kinetic_energy: Some(1e-11 * n as f64),
                energy_ratio: None,
                steps: Some(500),
            }),
        },
        nscd: Some(NscdSection {
            theta: Some(0.5),
            criterion: Some("quad_max".into()),
            tolerance: Some(1.0e-4),
            min_iterations: Some(1),
            max_iterations: Some(2000),
            ..NscdSection::default()
        }),
        output: Some(OutputSection { every: Some(50), cycles: None }),
        settlement: None,
        materials: vec![
            Material { name: "grain".into(), density: spec.density },
            Material { name: "wall".into(), density: 2700.0 },
        ],
        contacts: vec![contact("grain"), contact("wall")],
        bodies,
        springs: Vec::new(),
    })
}
