//! The sample of Karrech et al. (2007), Table 1 and §2.3: diorite spheres
//! (radii Gaussian, mean 3.2 mm, standard deviation 0.565 mm; ρ = 2710 kg/m³,
//! E = 46.9 GPa, ν = 0.25, μ = 0.5, α_n = α_t = 0.44, Hertz–Mindlin) in a quarter
//! of a steel cylinder (R = 75 mm, E = 210 GPa, ν = 0.3) with the symmetry planes
//! `x = 0` and `y = 0`, placed at random with a packing fraction of about 0.05 and
//! deposited under gravity until `E_c / E_p ≤ 10⁻⁶`; then loaded cyclically by a
//! plate on its top.
//!
//! Decisions where the paper is silent (also in `data/karrech2007/README.md`):
//! - the number of spheres: the paper's apparent weight, 13.6 N, is the whole
//!   cylinder's; a quarter holds 3.4 N, about 850 spheres of the Table 1 sizes
//!   (their height at φ = 0.5615 is then ≈ 56 mm ≈ H = 60 mm);
//! - radii are drawn from the Gaussian and redrawn outside mean ± 3 sd (no
//!   negative or vanishing radius);
//! - the loading plate is a steel disc moving along `z` (servo wall, mass of a
//!   10 mm steel plate over the quarter disc, no viscosity), pressed by
//!   `σ(t) = Δσ (1 − cos 2π f t) / 2` on a quarter disc: fully confined, the whole
//!   top (radius R, Δσ = 14.15 kPa, f = 50 Hz); partially confined, 80 % of the
//!   top's area (radius R √0.8, Δσ = 5.87 kPa, f = 10 Hz);
//! - the time step: 1e-7 s (the paper's order of magnitude, §2.3).
//!
//! [`deposit_scene`] and [`loading_scene`] build [`MdScene`] values, validated
//! like a scene file; save them with [`MdScene::to_toml_string`](crate::scene::SceneFile::to_toml_string).

use super::{md_material, md_plane, md_sphere, non_negative, positive, refuse, xyz};
use crate::error::Result;
use crate::md::V3;
use crate::run::Equilibrium;
use crate::scene::md::{CylinderSpec, DiscSpec, MdContact, MdSection, ServoSpec, SymmetrySpec, WallSpec};
use crate::scene::SceneFile;
use crate::scene::{CyclesSpec, MdScene, OutputSection, Simulation};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Parameters of a Karrech sample.
#[derive(Debug, Clone, PartialEq)]
pub struct KarrechSpec {
    /// Number of spheres in the quarter sample ([`PAPER_SPHERES`] = 850 for the paper's).
    pub spheres: usize,
    /// Mean of the Gaussian of the radii (m), > 0.
    pub radius_mean: f64,
    /// Standard deviation of the radii (m); draws beyond mean ± 3 sd are redrawn.
    pub radius_sd: f64,
    /// Container radius (m).
    pub container_radius: f64,
    /// Density of the spheres (kg/m³; diorite, 2710).
    pub density: f64,
    /// Young's modulus `E` of the spheres (Pa; diorite, 46.9 GPa); the walls are steel.
    pub young: f64,
    /// Poisson's ratio `ν` of the spheres (dimensionless, in (−1, 0.5)).
    pub poisson: f64,
    /// Coulomb friction coefficient `μ` of sphere–sphere and sphere–wall contacts (dimensionless).
    pub friction: f64,
    /// Damping ratios α_n = α_t of eq. (7), `γ = 2 α √(m* k)` (dimensionless).
    pub alpha: f64,
    /// Initial packing fraction of the loose placement (dimensionless, in (0, 1)).
    pub loose_fraction: f64,
    /// Seed of the random radii and loose positions.
    pub seed: u64,
    /// Time step (s).
    pub dt: f64,
    /// Longest deposit (s); it ends earlier at `E_c/E_p ≤ energy_ratio`.
    pub duration: f64,
    /// Equilibrium threshold on `E_c / E_p` (dimensionless; 10⁻⁶ in §2.3), held for 1000 steps.
    pub energy_ratio: f64,
}

impl KarrechSpec {
    /// Table 1 with `spheres` spheres (850 for the paper's quarter sample).
    pub fn table1(spheres: usize, seed: u64) -> Self {
        KarrechSpec {
            spheres,
            radius_mean: 3.2e-3,
            radius_sd: 0.565e-3,
            container_radius: 0.075,
            density: 2710.0,
            young: 46.9e9,
            poisson: 0.25,
            friction: 0.5,
            alpha: 0.44,
            loose_fraction: 0.05,
            seed,
            dt: 1e-7,
            duration: 2.0,
            energy_ratio: 1e-6,
        }
    }

    /// The largest radius a sphere can draw (m): mean + 3 sd.
    pub fn max_radius(&self) -> f64 {
        self.radius_mean + 3.0 * self.radius_sd
    }

    /// Checks what every Karrech scene uses: materials, law, container, step.
    fn check_common(&self, every: u64) -> Result<()> {
        positive("karrech: radius_mean (m)", self.radius_mean)?;
        positive("karrech: radius_sd (m)", self.radius_sd)?;
        positive("karrech: container_radius (m)", self.container_radius)?;
        positive("karrech: density (kg/m³)", self.density)?;
        positive("karrech: young (Pa)", self.young)?;
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return refuse(format!("karrech: poisson must be in (-1, 0.5), got {}", self.poisson));
        }
        non_negative("karrech: friction", self.friction)?;
        non_negative("karrech: alpha", self.alpha)?;
        positive("karrech: dt (s)", self.dt)?;
        if every == 0 {
            return refuse("karrech: every (steps between rows of series.csv) must be at least 1, got 0".into());
        }
        Ok(())
    }

    /// Checks the parameters of the deposit.
    fn check_deposit(&self, every: u64) -> Result<()> {
        if self.spheres == 0 {
            return refuse("karrech: spheres must be at least 1, got 0".into());
        }
        self.check_common(every)?;
        // The largest sphere must fit off both symmetry planes inside the cylinder:
        // at 45°, its centre at (r, r) is r √2 from the axis, at most R − r.
        let r = self.max_radius();
        let need = (1.0 + std::f64::consts::SQRT_2) * r;
        if self.container_radius < need {
            return refuse(format!(
                "karrech: container_radius {} m is too small for the largest sphere (radius_mean + 3 radius_sd = {r} m \
                 needs at least (1 + √2) × {r} = {need} m)",
                self.container_radius
            ));
        }
        if !(self.loose_fraction > 0.0 && self.loose_fraction < 1.0) {
            return refuse(format!("karrech: loose_fraction must be in (0, 1), got {}", self.loose_fraction));
        }
        positive("karrech: duration (s)", self.duration)?;
        positive("karrech: energy_ratio", self.energy_ratio)?;
        Ok(())
    }
}

/// The paper's number of spheres in the quarter sample.
pub const PAPER_SPHERES: usize = 850;

/// Draws of a position per sphere before [`loose_spheres`] gives up.
pub const MAX_DRAWS: usize = 100_000;

/// Radii and loose positions, drawn from the seed: random sequential placement
/// without overlap in the quarter cylinder, up to the height that gives the
/// loose packing fraction.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: one out of range
/// (see [`deposit_scene`]), a loose layer lower than the largest sphere's
/// diameter (too few spheres for `loose_fraction`), or a sphere with no free
/// place after [`MAX_DRAWS`] draws (`loose_fraction` too high to place at random).
pub fn loose_spheres(spec: &KarrechSpec) -> Result<Vec<(f64, V3)>> {
    spec.check_deposit(1)?;
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let normal = Normal::new(spec.radius_mean, spec.radius_sd)
        .map_err(|e| crate::Error::Scene(format!("karrech: radius_mean, radius_sd: {e}")))?;
    let (lo, hi) = (spec.radius_mean - 3.0 * spec.radius_sd, spec.radius_mean + 3.0 * spec.radius_sd);
    let mut radii = Vec::with_capacity(spec.spheres);
    for _ in 0..spec.spheres {
        // Accepted with probability > 0.49 (at least the half above the mean, to
        // mean + 3 sd): the bound is never reached in practice.
        let r = (0..MAX_DRAWS)
            .map(|_| normal.sample(&mut rng))
            .find(|&r: &f64| r > lo.max(0.1 * spec.radius_mean) && r < hi);
        match r {
            Some(r) => radii.push(r),
            None => return refuse(format!("karrech: radius_sd: no radius in range after {MAX_DRAWS} draws")),
        }
    }
    let volume: f64 = radii.iter().map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r).sum();
    let section = std::f64::consts::PI * spec.container_radius.powi(2) / 4.0;
    let height = volume / (spec.loose_fraction * section);
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    if height < 2.0 * r_max {
        return refuse(format!(
            "karrech: spheres: the loose layer of {} spheres at loose_fraction {} is {height} m high, lower than the \
             largest sphere's diameter {} m; use more spheres or a lower loose_fraction",
            spec.spheres,
            spec.loose_fraction,
            2.0 * r_max
        ));
    }
    let mut placed: Vec<(f64, V3)> = Vec::with_capacity(radii.len());
    for (k, &r) in radii.iter().enumerate() {
        let mut draws = 0;
        loop {
            if draws == MAX_DRAWS {
                return refuse(format!(
                    "karrech: loose_fraction {}: no free place for sphere {k} of {} after {MAX_DRAWS} draws; lower \
                     loose_fraction",
                    spec.loose_fraction, spec.spheres
                ));
            }
            draws += 1;
            let rho = (spec.container_radius - r) * rng.random::<f64>().sqrt();
            let phi = 0.5 * std::f64::consts::PI * rng.random::<f64>();
            let z = r + (height - 2.0 * r) * rng.random::<f64>();
            let x = V3::new(rho * phi.cos(), rho * phi.sin(), z);
            // Off the symmetry planes by a radius (no initial contact with an image).
            if x[0] < r || x[1] < r {
                continue;
            }
            if placed.iter().all(|(q, y)| (x - y).norm() > r + q) {
                placed.push((r, x));
                break;
            }
        }
    }
    Ok(placed)
}

/// The common part of the Karrech scenes: simulation header, materials, law,
/// symmetry planes, base and cylinder; no sphere.
fn common(spec: &KarrechSpec, duration: f64, equilibrium: bool, every: u64) -> MdScene {
    let contact = |other: &str| MdContact {
        between: ["diorite".into(), other.into()],
        model: "hertz".into(),
        friction: Some(spec.friction),
        static_friction: None,
        dynamic_friction: None,
        restitution: None,
        normal_damping_ratio: Some(spec.alpha),
        tangential_damping_ratio: Some(spec.alpha),
        normal_stiffness: None,
        tangential_stiffness: None,
        normal_damping: None,
        tangential_damping: None,
    };
    MdScene {
        simulation: Simulation {
            engine: "md".into(),
            dimension: Some(3),
            dt: spec.dt,
            duration,
            gravity: Some(vec![0.0, 0.0, -9.81]),
            thickness: None,
            seed: Some(spec.seed),
            equilibrium: equilibrium.then_some(Equilibrium {
                kinetic_energy: None,
                energy_ratio: Some(spec.energy_ratio),
                steps: Some(1000),
            }),
        },
        md: Some(MdSection {
            integrator: Some("gear".into()),
            gear: Some("karrech".into()),
            skin: Some(0.2 * spec.radius_mean),
            ..MdSection::default()
        }),
        output: Some(OutputSection { every: Some(every), cycles: None }),
        settlement: None,
        symmetry: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
            .into_iter()
            .map(|normal| SymmetrySpec { point: [0.0; 3], normal })
            .collect(),
        materials: vec![
            md_material("diorite", spec.density, spec.young, spec.poisson),
            md_material("steel", 7850.0, 210e9, 0.3),
        ],
        contacts: vec![contact("diorite"), contact("steel")],
        walls: vec![
            md_plane("base".into(), "steel", V3::zeros(), V3::new(0.0, 0.0, 1.0), None),
            WallSpec {
                name: "cylinder".into(),
                material: "steel".into(),
                plane: None,
                disc: None,
                cylinder: Some(CylinderSpec {
                    axis_point: [0.0; 3],
                    axis: [0.0, 0.0, 1.0],
                    radius: spec.container_radius,
                }),
                servo: None,
            },
        ],
        bodies: Vec::new(),
    }
}

/// The deposit scene: loose spheres falling in the quarter cylinder, run until
/// `E_c/E_p ≤ energy_ratio` (or `duration`); a row of `series.csv` every `every`
/// steps. Validated like a scene file.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: no sphere, a
/// radius mean or spread, container radius, material constant, time step,
/// duration or energy ratio that is not positive and finite (Poisson's ratio
/// outside (−1, 0.5), a negative friction or damping ratio), a container too
/// small for the largest sphere (mean + 3 sd), `every` = 0, and the placement
/// errors of [`loose_spheres`].
pub fn deposit_scene(spec: &KarrechSpec, every: u64) -> Result<MdScene> {
    spec.check_deposit(every)?;
    let mut scene = common(spec, spec.duration, true, every);
    scene.bodies = loose_spheres(spec)?
        .into_iter()
        .enumerate()
        .map(|(k, (r, x))| md_sphere(format!("g{k}"), "diorite", r, x))
        .collect();
    scene.validate()?;
    Ok(scene)
}

/// Loading modes of §4.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loading {
    /// Fraction of the top's area under the plate.
    pub coverage: f64,
    /// Stress amplitude Δσ (Pa).
    pub amplitude: f64,
    /// Frequency (Hz).
    pub frequency: f64,
}

impl Loading {
    /// Fully confined: the whole top, Δσ = 14.15 kPa, 50 Hz.
    pub const FULL: Loading = Loading { coverage: 1.0, amplitude: 14.15e3, frequency: 50.0 };
    /// Partially confined: 80 % of the top, Δσ = 5.87 kPa, 10 Hz.
    pub const PARTIAL: Loading = Loading { coverage: 0.8, amplitude: 5.87e3, frequency: 10.0 };
}

/// The loading scene: the deposited spheres `(radius, position)` under a plate
/// resting on the highest sphere top, pressed by `σ(t)` for `cycles` cycles.
/// Validated like a scene file.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) naming the parameter: no sphere, a
/// coverage outside (0, 1], an amplitude that is not finite, a frequency that is
/// not positive, no cycle, `every` = 0, the material, law and step parameters of
/// `spec` as in [`deposit_scene`], and a sphere the scene validation refuses.
pub fn loading_scene(
    spec: &KarrechSpec,
    spheres: &[(f64, V3)],
    loading: Loading,
    cycles: u32,
    every: u64,
) -> Result<MdScene> {
    spec.check_common(every)?;
    if spheres.is_empty() {
        return refuse("karrech: loading_scene: the sample has no sphere".into());
    }
    if !(loading.coverage > 0.0 && loading.coverage <= 1.0) {
        return refuse(format!("karrech: loading coverage must be in (0, 1], got {}", loading.coverage));
    }
    super::finite("karrech: loading amplitude (Pa)", loading.amplitude)?;
    positive("karrech: loading frequency (Hz)", loading.frequency)?;
    if cycles == 0 {
        return refuse("karrech: cycles must be at least 1, got 0".into());
    }
    let duration = cycles as f64 / loading.frequency;
    let mut scene = common(spec, duration, false, every);
    let top = spheres.iter().map(|(r, x)| x[2] + r).fold(0.0, f64::max);
    let radius = spec.container_radius * loading.coverage.sqrt();
    let area = std::f64::consts::PI * radius * radius / 4.0;
    let mass = 7850.0 * 0.01 * area;
    scene.walls.push(WallSpec {
        name: "plate".into(),
        material: "steel".into(),
        plane: None,
        disc: Some(DiscSpec { point: xyz(V3::new(0.0, 0.0, top)), normal: [0.0, 0.0, -1.0], radius }),
        cylinder: None,
        servo: Some(ServoSpec {
            mass,
            viscosity: 0.0,
            stress: Some(0.0),
            force: None,
            amplitude: Some(loading.amplitude),
            period: Some(1.0 / loading.frequency),
            area: Some(area),
        }),
    });
    // The spheres' positions at every cycle end (20 kB a cycle for 850 spheres):
    // what the settlement driver fits, and the configuration error of eq. (22).
    scene.output.get_or_insert_with(OutputSection::default).cycles =
        Some(CyclesSpec { frequency: loading.frequency, body: None, positions: Some(true) });
    scene.bodies = spheres.iter().enumerate().map(|(k, &(r, x))| md_sphere(format!("g{k}"), "diorite", r, x)).collect();
    scene.validate()?;
    Ok(scene)
}
