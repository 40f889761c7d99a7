//! The cyclic triaxial box of David, García-Rojo, Herrmann & Luding, *Hysteresis
//! and creep in powders and grains*, §§2–3: N spheres (radii Gaussian, mean
//! 5 mm, standard deviation 0.7 mm, minimum 3 mm; ρ = 2000 kg/m³), linear
//! contacts (k_n = 5000 N/m, k_t = 1000 N/m, γ₀ = 0.05 kg/s, γ_t = 0.01 kg/s,
//! μ = 0.1 by default), background damping γ_b = 0.2 kg/s and γ_br = 0.05 kg/s
//! (torque −γ_br r² ω), Δt = 2·10⁻⁵ s, no gravity, six stress-controlled walls (mass 2 kg,
//! viscosity 200 kg/s).
//!
//! 1. [`compression_scene`]: spheres on a cubic lattice (no overlap), all six
//!    walls at `p₀ = 1 kN/m²`, until the kinetic energy is much smaller than the
//!    elastic energy (`E_k/E_p ≤ 10⁻⁴`, E_p being the contacts' energy here).
//! 2. [`cyclic_scene`]: from the compressed state, the two x walls follow
//!    `σ_xx = p₀ + Δσ (1 − cos 2πt/t₀)/2`, i.e. `2σ_xx = 2p₀ + Δσ[1 − cos(2πt/t₀)]`
//!    with Δσ = 0.2 p₀, t₀ = 10 s; the other walls stay at p₀.
//!
//! Decisions where the paper is silent (in `data/luding2005/README.md`): the
//! Gaussian is truncated below at 3 mm and, symmetrically, above at 7 mm; the
//! lattice pitch is the largest diameter plus 5 %; the walls are ideal frictionless
//! planes of the sphere material (the paper does not give wall friction) — the
//! wall law is the same linear law with μ = 0.
//!
//! Both stages are [`MdScene`] values, validated like a scene file; save them
//! with [`MdScene::to_toml_string`](crate::scene::SceneFile::to_toml_string).

use super::{md_material, md_plane, md_sphere, non_negative, positive, refuse};
use crate::error::Result;
use crate::md::V3;
use crate::run::Equilibrium;
use crate::scene::md::{MdContact, MdSection, ServoSpec};
use crate::scene::SceneFile;
use crate::scene::{CyclesSpec, MdScene, OutputSection, Simulation};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Parameters of the box.
#[derive(Debug, Clone, PartialEq)]
pub struct LudingSpec {
    /// Number of spheres (343, 1000, 1728, 3375 in the paper: cubes).
    pub spheres: usize,
    /// Coulomb friction coefficient `μ` of sphere–sphere contacts (dimensionless; the
    /// walls are frictionless).
    pub friction: f64,
    /// Confining stress p₀ (Pa).
    pub p0: f64,
    /// Amplitude Δσ of the cyclic stress (Pa): `σ_xx` rises from p₀ to p₀ + Δσ at
    /// half a period.
    pub amplitude: f64,
    /// Period `t₀` of the cyclic stress (s).
    pub period: f64,
    /// Time step (s); the paper's is 2·10⁻⁵ s.
    pub dt: f64,
    /// Seed of the random sphere radii ([`radii`]).
    pub seed: u64,
}

impl LudingSpec {
    /// The paper's values for `spheres` spheres and friction `mu`.
    pub fn paper(spheres: usize, friction: f64, seed: u64) -> Self {
        LudingSpec { spheres, friction, p0: 1000.0, amplitude: 200.0, period: 10.0, dt: 2e-5, seed }
    }

    /// Checks what both stages use; `every` is the steps between rows of `series.csv`.
    fn check(&self, every: u64) -> Result<()> {
        if self.spheres == 0 {
            return refuse("luding: spheres must be at least 1, got 0".into());
        }
        non_negative("luding: friction", self.friction)?;
        positive("luding: p0 (Pa)", self.p0)?;
        super::finite("luding: amplitude (Pa)", self.amplitude)?;
        positive("luding: period (s)", self.period)?;
        positive("luding: dt (s)", self.dt)?;
        if every == 0 {
            return refuse("luding: every (steps between rows of series.csv) must be at least 1, got 0".into());
        }
        Ok(())
    }
}

/// Radii (m), Gaussian, mean 5 mm, sd 0.7 mm, redrawn outside [3, 7] mm
/// (accepted with probability 0.996).
pub fn radii(spec: &LudingSpec) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let normal = Normal::new(5e-3, 0.7e-3).expect("finite sd");
    (0..spec.spheres)
        .map(|_| loop {
            let r: f64 = normal.sample(&mut rng);
            if (3e-3..=7e-3).contains(&r) {
                break r;
            }
        })
        .collect()
}

/// Side of the initial cube lattice, in spheres.
fn side(n: usize) -> usize {
    let mut k = (n as f64).cbrt().floor() as usize;
    while k * k * k < n {
        k += 1;
    }
    k.max(1)
}

/// The servo of a wall (mass 2 kg, viscosity 200 kg/s) at `p₀`, plus with
/// `cyclic` the stress `Δσ (1 − cos 2πt/t₀) / 2`.
fn servo(spec: &LudingSpec, cyclic: bool) -> ServoSpec {
    ServoSpec {
        mass: 2.0,
        viscosity: 200.0,
        stress: Some(spec.p0),
        force: None,
        amplitude: cyclic.then_some(spec.amplitude),
        period: cyclic.then_some(spec.period),
        area: None,
    }
}

/// Simulation header, laws, output and the six walls of the box `[lo, hi]`, the
/// x walls with the servo `sx`, the others at `p₀`; no sphere.
fn common(spec: &LudingSpec, duration: f64, every: u64, lo: V3, hi: V3, sx: ServoSpec) -> MdScene {
    let contact = |other: &str, friction: f64| MdContact {
        between: ["grain".into(), other.into()],
        model: "linear".into(),
        friction: Some(friction),
        static_friction: None,
        dynamic_friction: None,
        restitution: None,
        normal_damping_ratio: None,
        tangential_damping_ratio: None,
        normal_stiffness: Some(5000.0),
        tangential_stiffness: Some(1000.0),
        normal_damping: Some(0.05),
        tangential_damping: Some(0.01),
    };
    let p0 = servo(spec, false);
    let mut walls = Vec::with_capacity(6);
    for (axis, name) in ["x", "y", "z"].into_iter().enumerate() {
        let mut n = V3::zeros();
        n[axis] = 1.0;
        let servo = if axis == 0 { sx } else { p0 };
        walls.push(md_plane(format!("{name}0"), "wall", lo, n, Some(servo)));
        walls.push(md_plane(format!("{name}1"), "wall", hi, -n, Some(servo)));
    }
    MdScene {
        simulation: Simulation {
            engine: "md".into(),
            dimension: Some(3),
            dt: spec.dt,
            duration,
            gravity: Some(vec![0.0, 0.0, 0.0]),
            thickness: None,
            seed: Some(spec.seed),
            equilibrium: None,
        },
        md: Some(MdSection {
            integrator: Some("verlet".into()),
            skin: Some(0.001),
            background_damping: Some(0.2),
            background_rotational_damping: Some(0.05),
            ..MdSection::default()
        }),
        output: Some(OutputSection { every: Some(every), cycles: None }),
        settlement: None,
        symmetry: Vec::new(),
        materials: vec![md_material("grain", 2000.0, 1e8, 0.3), md_material("wall", 2000.0, 1e8, 0.3)],
        contacts: vec![contact("grain", spec.friction), contact("wall", 0.0)],
        walls,
        bodies: Vec::new(),
    }
}

/// Isotropic compression from a lattice for at most `duration` (s); `every`
/// steps per row of `series.csv`. Validated like a scene file.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: no sphere, a
/// negative friction, a `p0`, period, time step or `duration` that is not
/// positive and finite, an amplitude that is not finite, `every` = 0.
pub fn compression_scene(spec: &LudingSpec, duration: f64, every: u64) -> Result<MdScene> {
    spec.check(every)?;
    positive("luding: duration (s)", duration)?;
    let radii = radii(spec);
    let k = side(spec.spheres);
    let pitch = 2.0 * radii.iter().cloned().fold(0.0, f64::max) * 1.05;
    let mut scene = common(spec, duration, every, V3::zeros(), V3::repeat(pitch * k as f64), servo(spec, false));
    scene.simulation.equilibrium =
        Some(Equilibrium { kinetic_energy: None, energy_ratio: Some(1e-4), steps: Some(1000) });
    scene.bodies = radii
        .iter()
        .enumerate()
        .map(|(m, &r)| {
            let (i, j, l) = (m % k, (m / k) % k, m / (k * k));
            let x = V3::new(i as f64 + 0.5, j as f64 + 0.5, l as f64 + 0.5) * pitch;
            md_sphere(format!("s{m}"), "grain", r, x)
        })
        .collect();
    scene.validate()?;
    Ok(scene)
}

/// The cyclic test from a compressed state: spheres `(radius, position)` and the
/// box corners `lo`, `hi` (m) at the end of the compression; `cycles` periods.
/// Validated like a scene file.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: those of
/// [`compression_scene`], no sphere, no cycle, a box whose `hi` corner is not
/// above `lo` on every axis, and a sphere the scene validation refuses.
pub fn cyclic_scene(
    spec: &LudingSpec,
    spheres: &[(f64, V3)],
    lo: V3,
    hi: V3,
    cycles: u32,
    every: u64,
) -> Result<MdScene> {
    spec.check(every)?;
    if spheres.is_empty() {
        return refuse("luding: cyclic_scene: the compressed sample has no sphere".into());
    }
    if cycles == 0 {
        return refuse("luding: cycles must be at least 1, got 0".into());
    }
    if !(0..3).all(|a| lo[a].is_finite() && hi[a].is_finite() && hi[a] > lo[a]) {
        return refuse(format!(
            "luding: box corners: hi {:?} must be above lo {:?} on every axis",
            super::xyz(hi),
            super::xyz(lo)
        ));
    }
    let mut scene = common(spec, cycles as f64 * spec.period, every, lo, hi, servo(spec, true));
    scene.output.get_or_insert_with(OutputSection::default).cycles =
        Some(CyclesSpec { frequency: 1.0 / spec.period, body: None, positions: None });
    scene.bodies = spheres.iter().enumerate().map(|(m, &(r, x))| md_sphere(format!("s{m}"), "grain", r, x)).collect();
    scene.validate()?;
    Ok(scene)
}
