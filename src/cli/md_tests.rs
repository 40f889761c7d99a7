//! `ballast karrech …` and `ballast luding …`: the ready-made MD tests.
//!
//! - `karrech deposit --out DIR`: the Table 1 sample of Karrech et al. (2007)
//!   deposited under gravity until `E_c/E_p ≤ 10⁻⁶` (scene `DIR/deposit.toml`,
//!   run in `DIR`), then the Fig. 3 figures from `series.csv`: apparent weight,
//!   coordination number, packing fraction, kinetic and potential energy.
//! - `karrech load --from DEPOSIT --out DIR --mode full|partial --cycles K`: the
//!   deposited sample under the cyclic plate (§4), then `cycles.csv` (residual
//!   displacement per cycle) and its figures.
//! - `luding compress --out DIR --spheres N --friction μ`: isotropic compression of
//!   the triaxial box of David et al.; `luding cycle --from COMPRESSED --out DIR
//!   --cycles K`: the cyclic σ_xx, then `loops.csv` (σ_D, ε_D), `strain.csv`
//!   (ε_N per cycle) and the figures of the paper's Figs. 2–5 for that run;
//!   `luding compare --runs DIR… --out DIR`: several cycled runs (sizes N or
//!   frictions μ) on common axes, as the paper's Figs. 3–5.
//!
//! Every run is an ordinary `ballast run` of a written scene: progress bar,
//! checkpoints, `--resume`, `--vtk-every` and the outputs of `ballast run`.

use super::{input, run_scene, Display, Failure};
use ballast::io::figures::{line_chart, Axes, Series};
use ballast::md::V3;
use ballast::run::{default_threads, RunOptions};
use ballast::scenarios::karrech::{self, KarrechSpec, Loading};
use ballast::scenarios::luding::{self, LudingSpec};
use ballast::scene::MdScene;
use clap::{Args, Subcommand, ValueEnum};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Options shared by every MD test run.
#[derive(Debug, Args, Clone)]
pub struct RunArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Steps between rows of `series.csv`.
    #[arg(long, default_value_t = 1000)]
    every: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Continue a run from its checkpoint.
    #[arg(long)]
    resume: bool,
    /// Wall-clock seconds between checkpoints.
    #[arg(long, default_value_t = 300.0)]
    checkpoint_every: f64,
    /// VTK snapshots every N steps (0: none).
    #[arg(long, default_value_t = 0)]
    vtk_every: u64,
    /// Force-evaluation threads (default: the cores, at most 2).
    #[arg(long)]
    threads: Option<usize>,
}

impl RunArgs {
    fn options(&self) -> RunOptions {
        RunOptions {
            checkpoint_every_s: self.checkpoint_every,
            resume: self.resume,
            vtk_every: self.vtk_every,
            threads: self.threads.unwrap_or_else(default_threads),
            ..RunOptions::default()
        }
    }

    /// Runs `scene` into the output directory.
    fn run(&self, scene: &Path) -> Result<(), Failure> {
        let display = if self.quiet { Display::Quiet } else { Display::Bar };
        run_scene(scene, &self.out, &self.options(), &display).map(|_| ())
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// The whole top under the plate, Δσ = 14.15 kPa, 50 Hz.
    Full,
    /// 80 % of the top's area, Δσ = 5.87 kPa, 10 Hz.
    Partial,
}

#[derive(Debug, Subcommand)]
pub enum KarrechCommand {
    /// Deposits the Table 1 sample in a quarter cylinder under gravity.
    Deposit {
        /// Number of spheres (850: the paper's 13.6 N sample, a quarter of it).
        #[arg(long, default_value_t = karrech::PAPER_SPHERES)]
        spheres: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Time step (s).
        #[arg(long, default_value_t = 1e-7)]
        dt: f64,
        /// Longest deposit (s); at Table 1's stiffness the full sample reaches
        /// E_c/E_p = 1.9e-6 at 1 s, hence 2 s.
        #[arg(long, default_value_t = 2.0)]
        duration: f64,
        /// Young's modulus of the spheres (Pa); lower it only for quick looks.
        #[arg(long, default_value_t = 46.9e9)]
        young: f64,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Loads a deposited sample cyclically by a plate.
    Load {
        /// The deposit's output directory (its `final_scene.toml`).
        #[arg(long, value_name = "DIR")]
        from: PathBuf,
        #[arg(long, value_enum, default_value_t = Mode::Full)]
        mode: Mode,
        #[arg(long, default_value_t = 10)]
        cycles: u32,
        #[command(flatten)]
        run: RunArgs,
    },
}

#[derive(Debug, Subcommand)]
pub enum LudingCommand {
    /// Isotropic compression of the triaxial box at p₀ from all sides.
    Compress {
        /// Number of spheres (343, 1000, 1728, 3375 in the paper).
        #[arg(long, default_value_t = 1728)]
        spheres: usize,
        /// Friction coefficient μ (0.1, 0.15, 0.2, 0.25, 0.5 in the paper).
        #[arg(long, default_value_t = 0.1)]
        friction: f64,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Longest compression (s).
        #[arg(long, default_value_t = 10.0)]
        duration: f64,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Cyclic σ_xx on a compressed box.
    Cycle {
        /// The compression's output directory (its `final_scene.toml` and `spec.json`).
        #[arg(long, value_name = "DIR")]
        from: PathBuf,
        #[arg(long, default_value_t = 10)]
        cycles: u32,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Several cycled runs on common axes (the paper's Figs. 3–5): ε_N per cycle
    /// and the first cycle's σ_D–ε_D loop of each, labelled by N and μ.
    Compare {
        /// Output directories of `luding cycle` runs.
        #[arg(long, value_name = "DIR", num_args = 1.., required = true)]
        runs: Vec<PathBuf>,
        /// Where the figures and `compare.csv` go.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
}

fn write(path: &Path, text: &str) -> Result<(), Failure> {
    if let Some(dir) = path.parent() {
        ballast::io::create_output_dir(dir).map_err(Failure::Run)?;
    }
    std::fs::write(path, text).map_err(|e| Failure::Run(ballast::io::io_error(path, "write", e)))
}

/// `spec.json`: what a first stage was made with, read by the stages after it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
struct TestSpec {
    spheres: usize,
    seed: u64,
    /// Time step (s), Karrech.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    dt: Option<f64>,
    /// Young's modulus (Pa), Karrech.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    young: Option<f64>,
    /// Friction coefficient, Luding.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    friction: Option<f64>,
    /// Loading period (s) and cycles, `luding cycle`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    period: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    cycles: Option<u32>,
}

fn write_spec(dir: &Path, spec: &TestSpec) -> Result<(), Failure> {
    ballast::io::create_output_dir(dir).map_err(Failure::Run)?;
    ballast::io::write_json(&dir.join("spec.json"), spec).map(|_| ()).map_err(Failure::Run)
}

/// One row of `loops.csv` (Pa, dimensionless).
#[derive(Debug, Clone, Serialize, Deserialize)]
struct LoopRow {
    time_s: f64,
    sigma_xx_pa: f64,
    sigma_yy_pa: f64,
    sigma_d_pa: f64,
    epsilon_d: f64,
}

/// One row of `strain.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct StrainRow {
    cycle: u64,
    time_s: f64,
    epsilon_n: f64,
}

/// One row of `compare.csv`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct CompareRow {
    run: String,
    spheres: usize,
    friction: f64,
    cycle: u64,
    epsilon_n: f64,
}

/// The TOML text of a generated scene (invalid parameters are input errors).
fn text(scene: ballast::Result<MdScene>) -> Result<String, Failure> {
    scene.map_err(Failure::Input)?.to_toml_string().map_err(Failure::Run)
}

/// Spheres `(radius, position)` and the built system of a finished run's final scene.
fn final_state(dir: &Path) -> Result<ballast::md::MdSystem, Failure> {
    let path = dir.join("final_scene.toml");
    if !path.exists() {
        return Err(input(format!("--from: no finished run in '{}' (no final_scene.toml)", dir.display())));
    }
    MdScene::load(&path).and_then(|s| s.build()).map_err(Failure::Input)
}

/// The `spec.json` a first stage left in its output directory.
fn spec_json(dir: &Path) -> Result<TestSpec, Failure> {
    ballast::io::read_json(&dir.join("spec.json")).map_err(Failure::Input)
}

fn spheres_of(sys: &ballast::md::MdSystem) -> Vec<(f64, V3)> {
    (0..sys.particles.len()).map(|i| (sys.particles.r[i], sys.particles.x[i])).collect()
}

pub(crate) fn karrech_main(cmd: KarrechCommand) -> Result<(), Failure> {
    match cmd {
        KarrechCommand::Deposit { spheres, seed, dt, duration, young, run: args } => {
            if spheres == 0 || !(dt > 0.0 && duration > 0.0 && young > 0.0) {
                return Err(input(format!(
                    "karrech deposit: need spheres > 0, dt > 0, duration > 0, young > 0; got {spheres}, {dt}, {duration}, {young}"
                )));
            }
            let spec = KarrechSpec { dt, duration, young, ..KarrechSpec::table1(spheres, seed) };
            let scene = args.out.join("deposit.toml");
            if !(args.resume && scene.exists()) {
                write(&scene, &text(karrech::deposit_scene(&spec, args.every))?)?;
                write_spec(
                    &args.out,
                    &TestSpec { spheres, seed, dt: Some(dt), young: Some(young), ..TestSpec::default() },
                )?;
            }
            args.run(&scene)?;
            deposit_figures(&args.out)
        }
        KarrechCommand::Load { from, mode, cycles, run: args } => {
            let sys = final_state(&from)?;
            let v = spec_json(&from)?;
            let spec = KarrechSpec {
                dt: v.dt.unwrap_or(1e-7),
                young: v.young.unwrap_or(46.9e9),
                ..KarrechSpec::table1(sys.particles.len(), v.seed)
            };
            let loading = if mode == Mode::Full { Loading::FULL } else { Loading::PARTIAL };
            let scene = args.out.join("load.toml");
            if !(args.resume && scene.exists()) {
                write(&scene, &text(karrech::loading_scene(&spec, &spheres_of(&sys), loading, cycles, args.every))?)?;
            }
            args.run(&scene)?;
            load_figures(&args.out)
        }
    }
}

pub(crate) fn luding_main(cmd: LudingCommand) -> Result<(), Failure> {
    match cmd {
        LudingCommand::Compress { spheres, friction, seed, duration, run: args } => {
            if spheres == 0 || !(friction >= 0.0 && duration > 0.0) {
                return Err(input(format!(
                    "luding compress: need spheres > 0, friction ≥ 0, duration > 0; got {spheres}, {friction}, {duration}"
                )));
            }
            let spec = LudingSpec::paper(spheres, friction, seed);
            let scene = args.out.join("compress.toml");
            if !(args.resume && scene.exists()) {
                write(&scene, &text(luding::compression_scene(&spec, duration, args.every))?)?;
                write_spec(&args.out, &TestSpec { spheres, seed, friction: Some(friction), ..TestSpec::default() })?;
            }
            args.run(&scene)
        }
        LudingCommand::Cycle { from, cycles, run: args } => {
            let sys = final_state(&from)?;
            let v = spec_json(&from)?;
            let spec = LudingSpec::paper(sys.particles.len(), v.friction.unwrap_or(0.1), v.seed);
            let (lo, hi) =
                box_corners(&sys).ok_or_else(|| input("luding cycle: the compressed scene has no box".into()))?;
            let scene = args.out.join("cycle.toml");
            if !(args.resume && scene.exists()) {
                write(&scene, &text(luding::cyclic_scene(&spec, &spheres_of(&sys), lo, hi, cycles, args.every))?)?;
            }
            if !(args.resume && args.out.join("spec.json").exists()) {
                let json = TestSpec {
                    spheres: spec.spheres,
                    seed: spec.seed,
                    friction: Some(spec.friction),
                    period: Some(spec.period),
                    cycles: Some(cycles),
                    ..TestSpec::default()
                };
                write_spec(&args.out, &json)?;
            }
            args.run(&scene)?;
            cycle_figures(&args.out, &spec, hi - lo)
        }
        LudingCommand::Compare { runs, out } => compare_figures(&runs, &out),
    }
}

/// Figs. 3–5 of David et al. from several `luding cycle` runs.
fn compare_figures(runs: &[PathBuf], out: &Path) -> Result<(), Failure> {
    ballast::io::create_output_dir(out).map_err(Failure::Run)?;
    let mut table = Vec::new();
    let (mut strain, mut loops) = (Vec::new(), Vec::new());
    for dir in runs {
        let v = spec_json(dir)?;
        let (n, Some(mu), Some(period)) = (v.spheres, v.friction, v.period) else {
            return Err(input(format!(
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
    ballast::io::table::write_all(&out.join("compare.csv"), &table).map_err(Failure::Run)?;
    chart(out, "strain_accumulation", "Accumulated strain ε_N (Figs. 3, 5)", "cycle", "ε_N", false, strain)?;
    chart(out, "first_cycle_loops", "First cycle, σ_D vs ε_D (Fig. 4)", "ε_D", "σ_D (kPa)", false, loops)?;
    println!("compare.csv, strain_accumulation and first_cycle_loops written in {}", out.display());
    Ok(())
}

/// Lower and upper corners of the box of axis-aligned plane walls.
fn box_corners(sys: &ballast::md::MdSystem) -> Option<(V3, V3)> {
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

/// The named columns of a CSV file of numbers.
fn columns(path: &Path, names: &[&str]) -> Result<Vec<Vec<f64>>, Failure> {
    ballast::io::table::read_columns(path, names).map_err(Failure::Run)
}

fn chart(
    dir: &Path,
    stem: &str,
    title: &str,
    x: &str,
    y: &str,
    log_y: bool,
    series: Vec<Series>,
) -> Result<(), Failure> {
    let axes = Axes { title: title.into(), x_label: x.into(), y_label: y.into(), log_x: false, log_y };
    line_chart(&dir.join(stem), &axes, &series).map_err(Failure::Run)
}

fn curve(label: &str, x: &[f64], y: &[f64]) -> Series {
    Series {
        label: label.into(),
        points: x.iter().zip(y).filter(|(a, b)| a.is_finite() && b.is_finite()).map(|(a, b)| (*a, *b)).collect(),
        band: Vec::new(),
    }
}

/// Karrech et al. Fig. 3 from a deposit's `series.csv`.
fn deposit_figures(dir: &Path) -> Result<(), Failure> {
    let c = columns(
        &dir.join("series.csv"),
        &["time_s", "base_force_N", "coordination", "packing_fraction", "kinetic_energy_J", "potential_energy_J"],
    )?;
    let weight = final_state(dir)?.weight();
    let t = &c[0];
    let flat: Vec<f64> = t.iter().map(|_| weight).collect();
    chart(
        dir,
        "fig3a_apparent_weight",
        "Apparent weight on the base",
        "time (s)",
        "force (N)",
        false,
        vec![curve("apparent weight", t, &c[1]), curve("weight of the spheres", t, &flat)],
    )?;
    chart(dir, "fig3b_coordination", "Coordination number", "time (s)", "z", false, vec![curve("z", t, &c[2])])?;
    chart(dir, "fig3c_packing_fraction", "Packing fraction", "time (s)", "φ", false, vec![curve("φ", t, &c[3])])?;
    let ek: Vec<f64> = c[4].iter().map(|v| v.max(1e-30)).collect();
    let ep: Vec<f64> = c[5].iter().map(|v| v.max(1e-30)).collect();
    chart(
        dir,
        "fig3d_energies",
        "Kinetic and potential energy",
        "time (s)",
        "energy (J)",
        true,
        vec![curve("kinetic E_c", t, &ek), curve("potential E_p", t, &ep)],
    )?;
    println!("figures fig3a–d written in {}", dir.display());
    Ok(())
}

/// Residual displacement per cycle and the plate's motion.
fn load_figures(dir: &Path) -> Result<(), Failure> {
    let c = columns(&dir.join("cycles.csv"), &["cycle", "mean_displacement_z_m", "max_displacement_m"])?;
    let down: Vec<f64> = c[1].iter().map(|v| -v).collect();
    chart(
        dir,
        "residual_displacement",
        "Residual displacement at the end of each cycle",
        "cycle",
        "displacement (m)",
        false,
        vec![curve("mean settlement of the spheres (−u_z)", &c[0], &down), curve("largest displacement", &c[0], &c[2])],
    )?;
    let s = columns(&dir.join("series.csv"), &["time_s", "plate_position_m", "plate_force_N"])?;
    chart(
        dir,
        "plate",
        "Loading plate",
        "time (s)",
        "displacement (m)",
        false,
        vec![curve("plate displacement (down)", &s[0], &s[1])],
    )?;
    println!("figures residual_displacement, plate written in {}", dir.display());
    Ok(())
}

/// σ_D–ε_D loops and ε_N per cycle (David et al. Figs. 2–5).
fn cycle_figures(dir: &Path, spec: &LudingSpec, l0: V3) -> Result<(), Failure> {
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
        let (s, e) = ballast::md::measure::deviatoric(sxx, syy, l, l0);
        loops.push(LoopRow { time_s: c[0][k], sigma_xx_pa: sxx, sigma_yy_pa: syy, sigma_d_pa: s, epsilon_d: e });
        sd.push(s);
        ed.push(e);
    }
    ballast::io::table::write_all(&dir.join("loops.csv"), &loops).map_err(Failure::Run)?;
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
    ballast::io::table::write_all(&dir.join("strain.csv"), &strain).map_err(Failure::Run)?;
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
    println!("loops.csv, strain.csv and figures written in {}", dir.display());
    Ok(())
}
