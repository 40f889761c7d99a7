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

use super::md_text::{material, plane, sphere};
use crate::md::V3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use std::fmt::Write;

/// Parameters of the box.
#[derive(Debug, Clone, PartialEq)]
pub struct LudingSpec {
    /// Number of spheres (343, 1000, 1728, 3375 in the paper: cubes).
    pub spheres: usize,
    pub friction: f64,
    /// Confining stress p₀ (Pa).
    pub p0: f64,
    /// Amplitude Δσ (Pa) and period t₀ (s) of the cyclic stress.
    pub amplitude: f64,
    pub period: f64,
    pub dt: f64,
    pub seed: u64,
}

impl LudingSpec {
    /// The paper's values for `spheres` spheres and friction `mu`.
    pub fn paper(spheres: usize, friction: f64, seed: u64) -> Self {
        LudingSpec { spheres, friction, p0: 1000.0, amplitude: 200.0, period: 10.0, dt: 2e-5, seed }
    }
}

/// Radii (m), Gaussian, mean 5 mm, sd 0.7 mm, redrawn outside [3, 7] mm.
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

fn common(out: &mut String, spec: &LudingSpec, duration: f64, title: &str) {
    let _ = writeln!(
        out,
        "# David, García-Rojo, Herrmann, Luding: cyclic triaxial box, {} spheres, μ = {} ({title}).\n\n\
         [simulation]\nengine = \"md\"\ndimension = 3\ndt = {:?}\nduration = {duration:?}\ngravity = [0.0, 0.0, 0.0]\nseed = {}",
        spec.spheres, spec.friction, spec.dt, spec.seed
    );
}

fn laws(out: &mut String, spec: &LudingSpec) {
    let _ = writeln!(out, "\n[md]\nintegrator = \"verlet\"\nskin = 0.001\nbackground_damping = 0.2\nbackground_rotational_damping = 0.05\n");
    material(out, "grain", 2000.0, 1e8, 0.3);
    material(out, "wall", 2000.0, 1e8, 0.3);
    for (other, mu) in [("grain", spec.friction), ("wall", 0.0)] {
        let _ = writeln!(
            out,
            "[[contact]]\nbetween = [\"grain\", \"{other}\"]\nmodel = \"linear\"\nfriction = {mu:?}\nnormal_stiffness = 5000.0\n\
             tangential_stiffness = 1000.0\nnormal_damping = 0.05\ntangential_damping = 0.01\n"
        );
    }
}

/// The six walls of the box `[lo, hi]`, the x walls with stress `sx`, the others `p₀`.
fn walls(out: &mut String, spec: &LudingSpec, lo: V3, hi: V3, sx: &str) {
    let p0 = format!("stress = {:?}", spec.p0);
    for axis in 0..3 {
        let mut n = V3::zeros();
        n[axis] = 1.0;
        let stress = if axis == 0 { sx.to_string() } else { p0.clone() };
        let servo = format!("mass = 2.0, viscosity = 200.0, {stress}");
        let names = ["x", "y", "z"];
        plane(out, &format!("{}0", names[axis]), "wall", lo, n, Some(&servo));
        plane(out, &format!("{}1", names[axis]), "wall", hi, -n, Some(&servo));
    }
}

/// Isotropic compression from a lattice; `every` steps per row of `series.csv`.
pub fn compression_scene(spec: &LudingSpec, duration: f64, every: u64) -> String {
    let radii = radii(spec);
    let k = side(spec.spheres);
    let pitch = 2.0 * radii.iter().cloned().fold(0.0, f64::max) * 1.05;
    let mut out = String::new();
    common(&mut out, spec, duration, "isotropic compression: ballast luding compress");
    let _ = writeln!(out, "equilibrium = {{ energy_ratio = 1e-4, steps = 1000 }}");
    laws(&mut out, spec);
    let _ = writeln!(out, "[output]\nevery = {every}\n");
    walls(&mut out, spec, V3::zeros(), V3::repeat(pitch * k as f64), &format!("stress = {:?}", spec.p0));
    for (m, r) in radii.iter().enumerate() {
        let (i, j, l) = (m % k, (m / k) % k, m / (k * k));
        let x = V3::new(i as f64 + 0.5, j as f64 + 0.5, l as f64 + 0.5) * pitch;
        sphere(&mut out, &format!("s{m}"), "grain", *r, x, None);
    }
    out
}

/// The cyclic test from a compressed state: spheres `(radius, position)` and the
/// box corners `lo`, `hi` (m) at the end of the compression; `cycles` periods.
pub fn cyclic_scene(spec: &LudingSpec, spheres: &[(f64, V3)], lo: V3, hi: V3, cycles: u32, every: u64) -> String {
    let mut out = String::new();
    common(&mut out, spec, cycles as f64 * spec.period, "cyclic loading: ballast luding cycle");
    laws(&mut out, spec);
    let _ = writeln!(out, "[output]\nevery = {every}\n\n[output.cycles]\nfrequency = {:?}\n", 1.0 / spec.period);
    let sx = format!("stress = {:?}, amplitude = {:?}, period = {:?}", spec.p0, spec.amplitude, spec.period);
    walls(&mut out, spec, lo, hi, &sx);
    for (m, (r, x)) in spheres.iter().enumerate() {
        sphere(&mut out, &format!("s{m}"), "grain", *r, *x, None);
    }
    out
}
