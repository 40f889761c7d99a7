//! The cyclic triaxial box of David, García-Rojo, Herrmann & Luding
//! (`ballast luding …`), on the box of [`crate::scenarios::luding`]:
//!
//! - [`compress`] (§2): isotropic compression of the box at p₀ from all sides
//!   (`compress.toml`, `spec.json`);
//! - [`cycle`] (§3): the cyclic σ_xx on a compressed box (`cycle.toml`), then
//!   `loops.csv` (σ_D, ε_D), `strain.csv` (ε_N per cycle) and the figures of
//!   the paper's Figs. 2–5 for that run;
//! - [`compare`]: several cycled runs (sizes N or frictions μ) on common axes,
//!   as the paper's Figs. 3–5 (`compare.csv`).

use super::md_stage::{chart, columns, curve, final_state, spheres_of, Stage, StageOutcome, TestSpec, SPEC_FILE};
use super::RunDisplay;
use crate::error::{Error, Result};
use crate::md::{MdSystem, V3};
use crate::scenarios::luding::{self, LudingSpec};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// The compression: `spheres` spheres (343, 1000, 1728, 3375 in the paper),
/// friction coefficient μ (0.1, 0.15, 0.2, 0.25, 0.5 in the paper), seed and
/// longest compression (s).
#[derive(Debug, Clone, PartialEq)]
pub struct Compression {
    /// Number of spheres `N` (343, 1000, 1728, 3375 in the paper).
    pub spheres: usize,
    /// Coulomb friction coefficient `μ` of the sphere contacts (dimensionless).
    pub friction: f64,
    /// Seed of the random sphere radii ([`crate::scenarios::luding::radii`]).
    pub seed: u64,
    /// Longest compression (s): the run stops earlier at equilibrium.
    pub duration: f64,
}

impl Default for Compression {
    /// 1728 spheres, μ = 0.1, seed 1, at most 10 s.
    fn default() -> Self {
        Self { spheres: 1728, friction: 0.1, seed: 1, duration: 10.0 }
    }
}

/// One row of `loops.csv` (Pa, dimensionless).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopRow {
    /// Column `time_s`: time of the `series.csv` row (s).
    pub time_s: f64,
    /// Column `sigma_xx_pa`: `σ_xx`, mean of the forces pressing the two x walls over
    /// the face area `L_y L_z` (Pa, positive in compression).
    pub sigma_xx_pa: f64,
    /// Column `sigma_yy_pa`: `σ_yy`, the same for the two y walls over `L_x L_z` (Pa).
    pub sigma_yy_pa: f64,
    /// Column `sigma_d_pa`: deviatoric stress `σ_D = 2 (σ_xx − σ_yy) / 3` (Pa; David et al. §3).
    pub sigma_d_pa: f64,
    /// Column `epsilon_d`: deviatoric strain `ε_D = ε_xx − ε_yy`, `ε = 1 − L/L⁰` with `L⁰`
    /// the box extents at the start of the cycled run (dimensionless, positive in compression).
    pub epsilon_d: f64,
}

/// One row of `strain.csv`: ε_D at the end of a cycle (the nearest row of `series.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StrainRow {
    /// Column `cycle`: the loading cycle (1 for the first).
    pub cycle: u64,
    /// Column `time_s`: time of the `series.csv` row nearest the cycle's end `cycle × t₀` (s).
    pub time_s: f64,
    /// Column `epsilon_n`: accumulated strain `ε_N`, the `ε_D` of that row (dimensionless).
    pub epsilon_n: f64,
}

/// One row of `compare.csv`: ε_N of a run at a cycle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareRow {
    /// Column `run`: the folder of the cycled run.
    pub run: String,
    /// Column `spheres`: its number of spheres `N`.
    pub spheres: usize,
    /// Column `friction`: its friction coefficient `μ` (dimensionless).
    pub friction: f64,
    /// Column `cycle`: the loading cycle (1 for the first).
    pub cycle: u64,
    /// Column `epsilon_n`: accumulated deviatoric strain `ε_N` at the end of that cycle (dimensionless).
    pub epsilon_n: f64,
}

/// Compresses the box of `spec` in `stage.out` (`compress.toml`, `spec.json`,
/// the run's outputs) until equilibrium.
///
/// # Errors
/// [`Error::Scene`] naming the parameters if there is no sphere, a negative
/// friction or a duration that is not positive, or for an invalid scene or
/// checkpoint; else as [`crate::run::Runner::run`].
pub fn compress(spec: &Compression, stage: &Stage, display: &dyn RunDisplay) -> Result<StageOutcome> {
    crate::io::figures::require()?; // the stage ends with its figures
    let Compression { spheres, friction, seed, duration } = *spec;
    if spheres == 0 || !(friction >= 0.0 && duration > 0.0) {
        return Err(Error::Scene(format!(
            "luding compress: need spheres > 0, friction ≥ 0, duration > 0; got {spheres}, {friction}, {duration}"
        )));
    }
    let box_spec = LudingSpec::paper(spheres, friction, seed);
    let (scene, written) =
        stage.write_scene("compress.toml", || luding::compression_scene(&box_spec, duration, stage.every))?;
    if written {
        TestSpec { spheres, seed, friction: Some(friction), ..TestSpec::default() }.write(&stage.out)?;
    }
    let run = stage.run(&scene, display, "luding compress")?;
    Ok(StageOutcome { run, written: Vec::new() })
}

/// Cycles the box compressed in `from` (its `final_scene.toml` and
/// `spec.json`) `cycles` times in `stage.out` (`cycle.toml`, `spec.json` with
/// the period and cycles), then writes `loops.csv`, `strain.csv` and the
/// figures `stress_strain_loops` and `strain_accumulation`.
///
/// # Errors
/// [`Error::Scene`] if `from` holds no finished compression of a box, or for an
/// invalid scene or checkpoint; else as [`crate::run::Runner::run`], or an
/// output that cannot be written or read back.
pub fn cycle(from: &Path, cycles: u32, stage: &Stage, display: &dyn RunDisplay) -> Result<StageOutcome> {
    crate::io::figures::require()?; // the stage ends with its figures
    let sys = final_state(from)?;
    let v = TestSpec::read(from)?;
    let spec = LudingSpec::paper(sys.particles.len(), v.friction.unwrap_or(0.1), v.seed);
    let (lo, hi) =
        box_corners(&sys).ok_or_else(|| Error::Scene("luding cycle: the compressed scene has no box".into()))?;
    let (scene, _) = stage
        .write_scene("cycle.toml", || luding::cyclic_scene(&spec, &spheres_of(&sys), lo, hi, cycles, stage.every))?;
    if !(stage.run.resume && stage.out.join(SPEC_FILE).exists()) {
        let json = TestSpec {
            spheres: spec.spheres,
            seed: spec.seed,
            friction: Some(spec.friction),
            period: Some(spec.period),
            cycles: Some(cycles),
            ..TestSpec::default()
        };
        json.write(&stage.out)?;
    }
    let run = stage.run(&scene, display, "luding cycle")?;
    Ok(StageOutcome { run, written: cycle_figures(&stage.out, &spec, hi - lo)? })
}

/// Figs. 3–5 of David et al. from several `luding cycle` runs (their folders
/// `runs`), in `out`: `compare.csv` (ε_N per run and cycle),
/// `strain_accumulation` and `first_cycle_loops`. Returns what it wrote.
///
/// # Errors
/// [`Error::Scene`] naming a folder that is not the output of [`cycle`];
/// [`Error::Io`] if a run's tables cannot be read or an output written.
pub fn compare(runs: &[PathBuf], out: &Path) -> Result<Vec<String>> {
    crate::io::figures::require()?; // the stage ends with its figures
    crate::io::create_output_dir(out)?;
    let mut table = Vec::new();
    let (mut strain, mut loops) = (Vec::new(), Vec::new());
    for dir in runs {
        let v = TestSpec::read(dir)?;
        let (n, Some(mu), Some(period)) = (v.spheres, v.friction, v.period) else {
            return Err(Error::Scene(format!(
                "{}: spec.json has no spheres, friction or period (not a `luding cycle` output)",
                dir.display()
            )));
        };
        let label = format!("N = {n}, μ = {mu}");
        let s = columns(&dir.join("strain.csv"), &["cycle", "epsilon_n"])?;
        for (&cycle, &epsilon_n) in s[0].iter().zip(&s[1]) {
            let cycle = cycle as u64;
            table.push(CompareRow { run: dir.display().to_string(), spheres: n, friction: mu, cycle, epsilon_n });
        }
        strain.push(curve(&label, &s[0], &s[1]));
        let l = columns(&dir.join("loops.csv"), &["time_s", "sigma_d_pa", "epsilon_d"])?;
        let first: Vec<usize> = (0..l[0].len()).filter(|&k| l[0][k] <= period).collect();
        let e: Vec<f64> = first.iter().map(|&k| l[2][k]).collect();
        let sd: Vec<f64> = first.iter().map(|&k| l[1][k] / 1e3).collect();
        loops.push(curve(&label, &e, &sd));
    }
    crate::io::table::write_all(&out.join("compare.csv"), &table)?;
    chart(out, "strain_accumulation", "Accumulated strain ε_N (Figs. 3, 5)", "cycle", "ε_N", false, strain)?;
    chart(out, "first_cycle_loops", "First cycle, σ_D vs ε_D (Fig. 4)", "ε_D", "σ_D (kPa)", false, loops)?;
    Ok(["compare.csv", "strain_accumulation", "first_cycle_loops"].map(String::from).to_vec())
}

/// Lower and upper corners of the box of axis-aligned plane walls.
fn box_corners(sys: &MdSystem) -> Option<(V3, V3)> {
    let mut lo = V3::repeat(f64::NAN);
    let mut hi = V3::repeat(f64::NAN);
    for w in &sys.walls {
        let (n, p) = (w.normal()?, w.point()?);
        let a = n.iamax();
        if n[a] > 0.0 {
            lo[a] = p[a];
        } else {
            hi[a] = p[a];
        }
    }
    (lo.iter().chain(hi.iter()).all(|c| c.is_finite())).then_some((lo, hi))
}

/// σ_D–ε_D loops and ε_N per cycle (David et al. Figs. 2–5) of the cycled run
/// in `dir`, whose box measured `l0` at the start.
fn cycle_figures(dir: &Path, spec: &LudingSpec, l0: V3) -> Result<Vec<String>> {
    let c = columns(
        &dir.join("series.csv"),
        &[
            "time_s",
            "x0_force_N",
            "x1_force_N",
            "y0_force_N",
            "y1_force_N",
            "z0_position_m",
            "z1_position_m",
            "x0_position_m",
            "x1_position_m",
            "y0_position_m",
            "y1_position_m",
        ],
    )?;
    let n = c[0].len();
    let mut loops = Vec::with_capacity(n);
    let (mut sd, mut ed) = (Vec::with_capacity(n), Vec::with_capacity(n));
    #[allow(clippy::needless_range_loop)]
    for k in 0..n {
        let l = V3::new(l0[0] - c[7][k] - c[8][k], l0[1] - c[9][k] - c[10][k], l0[2] - c[5][k] - c[6][k]);
        let sxx = 0.5 * (c[1][k] + c[2][k]) / (l[1] * l[2]);
        let syy = 0.5 * (c[3][k] + c[4][k]) / (l[0] * l[2]);
        let (s, e) = crate::md::measure::deviatoric(sxx, syy, l, l0);
        loops.push(LoopRow { time_s: c[0][k], sigma_xx_pa: sxx, sigma_yy_pa: syy, sigma_d_pa: s, epsilon_d: e });
        sd.push(s);
        ed.push(e);
    }
    crate::io::table::write_all(&dir.join("loops.csv"), &loops)?;
    // ε_N: ε_D at the ends of the cycles (nearest row).
    let mut strain = Vec::new();
    let (mut cyc, mut en) = (Vec::new(), Vec::new());
    let total = c[0].last().copied().unwrap_or(0.0);
    let mut k = 0;
    for cycle in 1.. {
        let t = cycle as f64 * spec.period;
        if t > total + 0.5 * spec.period {
            break;
        }
        while k + 1 < n && (c[0][k + 1] - t).abs() <= (c[0][k] - t).abs() {
            k += 1;
        }
        strain.push(StrainRow { cycle, time_s: c[0][k], epsilon_n: ed[k] });
        cyc.push(cycle as f64);
        en.push(ed[k]);
    }
    crate::io::table::write_all(&dir.join("strain.csv"), &strain)?;
    let sd_kpa: Vec<f64> = sd.iter().map(|s| s / 1e3).collect();
    chart(
        dir,
        "stress_strain_loops",
        &format!("σ_D vs ε_D, N = {}, μ = {}", spec.spheres, spec.friction),
        "ε_D",
        "σ_D (kPa)",
        false,
        vec![curve("", &ed, &sd_kpa)],
    )?;
    chart(
        dir,
        "strain_accumulation",
        "Accumulated strain ε_N",
        "cycle",
        "ε_N",
        false,
        vec![curve(&format!("N = {}", spec.spheres), &cyc, &en)],
    )?;
    Ok(["loops.csv", "strain.csv", "stress_strain_loops", "strain_accumulation"].map(String::from).to_vec())
}
