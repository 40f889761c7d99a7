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

use super::md_text::{material, plane, sphere, v3};
use crate::md::V3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::fmt::Write;

/// Parameters of a Karrech sample.
#[derive(Debug, Clone, PartialEq)]
pub struct KarrechSpec {
    pub spheres: usize,
    pub radius_mean: f64,
    pub radius_sd: f64,
    /// Container radius (m).
    pub container_radius: f64,
    pub density: f64,
    pub young: f64,
    pub poisson: f64,
    pub friction: f64,
    /// Damping ratios α_n = α_t.
    pub alpha: f64,
    /// Initial packing fraction of the loose placement.
    pub loose_fraction: f64,
    pub seed: u64,
    /// Time step (s).
    pub dt: f64,
    /// Longest deposit (s); it ends earlier at `E_c/E_p ≤ energy_ratio`.
    pub duration: f64,
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
}

/// The paper's number of spheres in the quarter sample.
pub const PAPER_SPHERES: usize = 850;

/// Radii and loose positions, drawn from the seed: random sequential placement
/// without overlap in the quarter cylinder, up to the height that gives the
/// loose packing fraction.
pub fn loose_spheres(spec: &KarrechSpec) -> Vec<(f64, V3)> {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let normal = Normal::new(spec.radius_mean, spec.radius_sd).expect("finite sd");
    let (lo, hi) = (spec.radius_mean - 3.0 * spec.radius_sd, spec.radius_mean + 3.0 * spec.radius_sd);
    let radii: Vec<f64> = (0..spec.spheres)
        .map(|_| loop {
            let r: f64 = normal.sample(&mut rng);
            if r > lo.max(0.1 * spec.radius_mean) && r < hi {
                break r;
            }
        })
        .collect();
    let volume: f64 = radii.iter().map(|r| 4.0 / 3.0 * std::f64::consts::PI * r * r * r).sum();
    let section = std::f64::consts::PI * spec.container_radius.powi(2) / 4.0;
    let height = volume / (spec.loose_fraction * section);
    let mut placed: Vec<(f64, V3)> = Vec::with_capacity(radii.len());
    for &r in &radii {
        loop {
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
    placed
}

/// The common part of the Karrech scenes: simulation header, materials, law,
/// symmetry planes, base and cylinder.
fn header(out: &mut String, spec: &KarrechSpec, duration: f64, equilibrium: bool, every: u64) {
    let _ = writeln!(
        out,
        "[simulation]\nengine = \"md\"\ndimension = 3\ndt = {:?}\nduration = {duration:?}\ngravity = [0.0, 0.0, -9.81]\nseed = {}",
        spec.dt, spec.seed
    );
    if equilibrium {
        let _ = writeln!(out, "equilibrium = {{ energy_ratio = {:?}, steps = 1000 }}", spec.energy_ratio);
    }
    let _ = writeln!(out, "\n[md]\nintegrator = \"gear\"\ngear = \"karrech\"\nskin = {:?}\n", 0.2 * spec.radius_mean);
    let _ = writeln!(out, "[output]\nevery = {every}\n");
    for normal in [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        let _ = writeln!(out, "[[symmetry]]\npoint = [0.0, 0.0, 0.0]\nnormal = {}\n", v3(V3::from(normal)));
    }
    material(out, "diorite", spec.density, spec.young, spec.poisson);
    material(out, "steel", 7850.0, 210e9, 0.3);
    for other in ["diorite", "steel"] {
        let _ = writeln!(
            out,
            "[[contact]]\nbetween = [\"diorite\", \"{other}\"]\nmodel = \"hertz\"\nfriction = {:?}\nnormal_damping_ratio = {:?}\ntangential_damping_ratio = {:?}\n",
            spec.friction, spec.alpha, spec.alpha
        );
    }
    plane(out, "base", "steel", V3::zeros(), V3::new(0.0, 0.0, 1.0), None);
    let _ = writeln!(
        out,
        "[[wall]]\nname = \"cylinder\"\nmaterial = \"steel\"\ncylinder = {{ axis_point = [0.0, 0.0, 0.0], axis = [0.0, 0.0, 1.0], radius = {:?} }}\n",
        spec.container_radius
    );
}

/// The deposit scene: loose spheres falling in the quarter cylinder, run until
/// `E_c/E_p ≤ energy_ratio` (or `duration`); a row of `series.csv` every `every` steps.
pub fn deposit_scene(spec: &KarrechSpec, every: u64) -> String {
    let mut out =
        String::from("# Karrech et al. (2007) sample, Table 1: deposit under gravity (ballast karrech deposit).\n\n");
    header(&mut out, spec, spec.duration, true, every);
    for (k, (r, x)) in loose_spheres(spec).into_iter().enumerate() {
        sphere(&mut out, &format!("g{k}"), "diorite", r, x, None);
    }
    out
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
pub fn loading_scene(spec: &KarrechSpec, spheres: &[(f64, V3)], loading: Loading, cycles: u32, every: u64) -> String {
    let mut out = format!(
        "# Karrech et al. (2007) sample under a cyclic plate load: coverage {}, Δσ = {} Pa, f = {} Hz \
         (ballast karrech load).\n\n",
        loading.coverage, loading.amplitude, loading.frequency
    );
    let duration = cycles as f64 / loading.frequency;
    header(&mut out, spec, duration, false, every);
    let top = spheres.iter().map(|(r, x)| x[2] + r).fold(0.0, f64::max);
    let radius = spec.container_radius * loading.coverage.sqrt();
    let area = std::f64::consts::PI * radius * radius / 4.0;
    let mass = 7850.0 * 0.01 * area;
    let _ = writeln!(
        out,
        "[[wall]]\nname = \"plate\"\nmaterial = \"steel\"\ndisc = {{ point = {}, normal = [0.0, 0.0, -1.0], radius = {radius:?} }}\n\
         servo = {{ mass = {mass:?}, viscosity = 0.0, stress = 0.0, amplitude = {:?}, period = {:?}, area = {area:?} }}\n",
        v3(V3::new(0.0, 0.0, top)),
        loading.amplitude,
        1.0 / loading.frequency
    );
    let _ = writeln!(out, "[output.cycles]\nfrequency = {:?}\n", loading.frequency);
    for (k, (r, x)) in spheres.iter().enumerate() {
        sphere(&mut out, &format!("g{k}"), "diorite", *r, *x, None);
    }
    out
}
