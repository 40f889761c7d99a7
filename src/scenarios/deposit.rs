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

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write;

/// What to generate.
#[derive(Debug, Clone, PartialEq)]
pub struct DepositSpec {
    /// Number of grains of each circumradius `(radius m, count)`.
    pub grading: Vec<(f64, usize)>,
    /// Inner width of the box (m).
    pub width: f64,
    /// Grain density (kg/m³).
    pub density: f64,
    /// Grain–grain and grain–wall friction.
    pub friction: f64,
    pub seed: u64,
    /// Time step (s) and duration (s) of the deposit run.
    pub dt: f64,
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

/// The scene TOML of a loose deposit (see `docs/scene-format.md`).
pub fn pentagon_deposit(spec: &DepositSpec) -> String {
    let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
    let radii = shuffled_radii(&spec.grading, &mut rng);
    let r_max = radii.iter().copied().fold(0.0, f64::max);
    let pitch = 2.2 * r_max;
    let cols = ((spec.width / pitch).floor() as usize).max(1);
    let wall = 0.05;
    let mut s = String::new();
    let _ = writeln!(s, "# Loose pentagon deposit: {} grains, seed {}.", radii.len(), spec.seed);
    // Equilibrium: a kinetic energy below 1e-11 J per grain (a mean speed of about
    // 1e-5 m/s for these grains) held for 500 steps; `duration` is then an upper bound.
    let _ = writeln!(
        s,
        "[simulation]\nengine = \"nscd\"\ndt = {:e}\nduration = {}\ngravity = [0.0, -9.81]\nseed = {}\n\
         equilibrium = {{ kinetic_energy = {:e}, steps = 500 }}\n",
        spec.dt,
        spec.duration,
        spec.seed,
        1e-11 * radii.len() as f64
    );
    let _ = writeln!(s, "[nscd]\ntheta = 0.5\ncriterion = \"quad_max\"\ntolerance = 1.0e-4\nmin_iterations = 1\nmax_iterations = 2000\n");
    let _ = writeln!(s, "[output]\nevery = 50\n");
    let _ = writeln!(s, "[[material]]\nname = \"grain\"\ndensity = {}\n", spec.density);
    let _ = writeln!(s, "[[material]]\nname = \"wall\"\ndensity = 2700.0\n");
    let _ = writeln!(s, "[[contact]]\nbetween = [\"grain\", \"grain\"]\nfriction = {}\n", spec.friction);
    let _ = writeln!(s, "[[contact]]\nbetween = [\"grain\", \"wall\"]\nfriction = {}\n", spec.friction);
    let rows = radii.len().div_ceil(cols);
    let height = (rows as f64 + 2.0) * pitch;
    let w = spec.width;
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| format!("[[{x0}, {y0}], [{x1}, {y0}], [{x1}, {y1}], [{x0}, {y1}]]");
    for (name, poly) in [
        ("floor", rect(-w / 2.0 - wall, -wall, w / 2.0 + wall, 0.0)),
        ("left_wall", rect(-w / 2.0 - wall, 0.0, -w / 2.0, height)),
        ("right_wall", rect(w / 2.0, 0.0, w / 2.0 + wall, height)),
    ] {
        let _ = writeln!(
            s,
            "[[body]]\nname = \"{name}\"\nmaterial = \"wall\"\npolygon = {poly}\nposition = [0.0, 0.0]\nfixed = true\n"
        );
    }
    let x0 = -w / 2.0 + 0.5 * (w - (cols as f64 - 1.0) * pitch);
    for (k, r) in radii.iter().enumerate() {
        let (i, j) = (k % cols, k / cols);
        let jitter = 0.5 * (pitch - 2.0 * r);
        let x = x0 + i as f64 * pitch + jitter * rng.random_range(-1.0..1.0);
        let y = pitch * (j as f64 + 0.5) + jitter * rng.random_range(-1.0..1.0);
        let angle = std::f64::consts::TAU * rng.random::<f64>();
        let v = [0.05 * rng.random_range(-1.0..1.0), 0.05 * rng.random_range(-1.0..1.0)];
        let _ = writeln!(
            s,
            "[[body]]\nname = \"g{k}\"\nmaterial = \"grain\"\nregular = {{ sides = 5, radius = {r} }}\nposition = [{x:.9}, {y:.9}]\nangle = {angle:.9}\nvelocity = [{:.6}, {:.6}]\n",
            v[0], v[1]
        );
    }
    s
}
