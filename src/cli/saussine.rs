//! `ballast saussine …`: the numerical experiments of Saussine et al. (2006),
//! each from scene files that are written into the output folder and run with
//! the same loop as `ballast run` (progress, checkpoints, `--resume`).
//!
//! - `sample`: generate and deposit the sample (stage 1, and 1b for a free bank),
//!   save it as `sample.toml`, measure its balance, solid fraction and
//!   coordination number (`sample.json`);
//! - `load`: write the loaded scene (sleeper with bars, load, sublayer stiffness,
//!   solver, time step, number of cycles) from a deposited sample;
//! - `settle`: load a sample and run N cycles (§4): `cycles.csv`, `summary.json`,
//!   VTK snapshots every few cycles, figures;
//! - `convergence`, `steps`, `ensemble`: the studies of §3.2, §3.3 and §4.2
//!   (`studies.rs`).
//!
//! A sample scaled to fewer grains (`--grains`) is loaded with the sleeper's width
//! and the load scaled alike (same pressure), unless `--sleeper-width` is given.

use super::studies::{self, loading_for, StudyArgs};
use super::{run_scene, Display, Failure};
use ballast::run::{default_threads, Prior, RunOptions};
use ballast::scenarios::saussine::{
    loaded_scene, measure_sample, open_bank, sample_scene, Guide, LoadingSpec, SampleSpec,
};
use ballast::scene::Scene;
use ballast::Error;
use clap::Subcommand;
use std::path::{Path, PathBuf};

#[derive(Debug, Subcommand)]
pub enum SaussineCommand {
    /// Generates the sample (361 + 242 + 121 pentagons on the viscoelastic sublayer),
    /// deposits it under gravity until equilibrium and saves it as DIR/sample.toml.
    Sample {
        /// Seed of the grains' order, positions, orientations and velocities.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Free bank: deposit in a mould, remove it and let the layer settle again.
        #[arg(long)]
        bank: bool,
        /// Scale the grading to about this many grains (and the width with it).
        #[arg(long)]
        grains: Option<usize>,
        /// Time step of the deposit (s).
        #[arg(long, default_value_t = 2e-4)]
        dt: f64,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Continue an interrupted deposit.
        #[arg(long)]
        resume: bool,
        #[arg(long)]
        quiet: bool,
    },
    /// Writes the loaded scene: the sample with the sleeper (and its bars) on top under
    /// F = A + B cos(2π f t − φ), ready for `ballast run`.
    Load {
        /// A deposited sample (`sample.toml` of `ballast saussine sample`).
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Output scene file.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        #[command(flatten)]
        loading: LoadingArgs,
    },
    /// Loads a deposited sample and runs the cycles (§4): per-cycle settlement, mean
    /// grain speed, contacts and iterations (`cycles.csv`), VTK snapshots, figures.
    Settle {
        /// A deposited sample (`sample.toml` of `ballast saussine sample`).
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Output directory (the loaded scene is written there as `loaded.toml`).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        #[command(flatten)]
        loading: LoadingArgs,
        /// VTK snapshot (bodies and contact forces) every this many cycles; 0: none.
        #[arg(long, value_name = "CYCLES", default_value_t = 10)]
        snapshot_every: u64,
        /// Wall-clock seconds between checkpoints.
        #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
        checkpoint_every: f64,
        /// Continue a killed run from its checkpoint.
        #[arg(long)]
        resume: bool,
        #[arg(long)]
        quiet: bool,
    },
    /// §3.2: the same cycles with each convergence policy and tolerance of the paper's
    /// table; mean NLGS iterations, wall time and interpenetration per run.
    /// (--criterion and --tolerance are replaced by those of each run.)
    Convergence {
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Runs as POLICY:TOLERANCE, comma separated (default: the paper's table).
        #[arg(long, value_delimiter = ',')]
        policies: Vec<String>,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// §3.3: the same cycles with each time step, at each inclination; mean and max
    /// interpenetration over time. (--dt and --inclination are replaced by those of each run.)
    Steps {
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Time steps (s), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "1e-4,2e-4,3e-4,4e-4,5e-4,6e-4,7e-4,8e-4,9e-4,1e-3")]
        dts: Vec<f64>,
        /// Inclinations of the load (degrees), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "0,5")]
        inclinations: Vec<f64>,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// §4.2: samples that differ only by their seed, each on sublayers of several
    /// stiffnesses, run in parallel; mean and spread of the settlement per stiffness.
    /// (--stiffness-factor is replaced by those of each run.)
    Ensemble {
        /// Number of samples (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 8)]
        samples: u64,
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Factors on the sublayer stiffness k_N, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "1,100,1000")]
        factors: Vec<f64>,
        /// Scale the grading to about this many grains (and the width with it).
        #[arg(long)]
        grains: Option<usize>,
        /// Time step of the deposits (s).
        #[arg(long, default_value_t = 2e-4)]
        sample_dt: f64,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
}

/// Settings of the loaded stage shared by the subcommands.
#[derive(Debug, Clone, clap::Args)]
pub struct LoadingArgs {
    /// Number of loading cycles.
    #[arg(long, default_value_t = 100)]
    pub cycles: u64,
    /// Angle of the load from the vertical (degrees).
    #[arg(long, default_value_t = 0.0)]
    pub inclination: f64,
    /// Sleeper guide: vertical (vx, spin imposed), level (spin imposed) or free;
    /// default: vertical for a vertical load, level otherwise.
    #[arg(long)]
    pub guide: Option<String>,
    /// Factor on the sublayer stiffness k_N (§4.2: 1, 100, 1000).
    #[arg(long, default_value_t = 1.0)]
    pub stiffness_factor: f64,
    /// Time step (s).
    #[arg(long, default_value_t = 2e-4)]
    pub dt: f64,
    /// Convergence policy: strict, quad, quad_max, energy (default: the cheapest measured to
    /// keep the max overlap below 1 % of the smallest grain over 1000 cycles, BENCHMARKS.md).
    #[arg(long, default_value = "energy")]
    pub criterion: String,
    /// Tolerance of the policy.
    #[arg(long, default_value_t = 1.66e-5)]
    pub tolerance: f64,
    #[arg(long, default_value_t = 1)]
    pub min_iterations: usize,
    #[arg(long, default_value_t = 2000)]
    pub max_iterations: usize,
    /// Square bars under the sleeper (0: a flat sleeper).
    #[arg(long, default_value_t = 2)]
    pub bars: usize,
    /// Width of the sleeper (m).
    #[arg(long)]
    pub sleeper_width: Option<f64>,
}

impl LoadingArgs {
    pub fn spec(&self) -> Result<LoadingSpec, Failure> {
        let guide = match self.guide.as_deref() {
            None if self.inclination == 0.0 => Guide::Vertical,
            None => Guide::Level,
            Some("vertical") => Guide::Vertical,
            Some("level") => Guide::Level,
            Some("free") => Guide::Free,
            Some(g) => return Err(input(format!("--guide: expected vertical, level or free, got '{g}'"))),
        };
        if !(self.stiffness_factor.is_finite() && self.stiffness_factor > 0.0) {
            return Err(input(format!("--stiffness-factor: must be positive, got {}", self.stiffness_factor)));
        }
        if !(self.inclination.is_finite() && self.inclination.abs() < 90.0) {
            return Err(input(format!("--inclination: must be in (-90, 90) degrees, got {}", self.inclination)));
        }
        if self.cycles == 0 {
            return Err(input("--cycles: must be at least 1".into()));
        }
        let base = LoadingSpec::saussine(self.cycles);
        Ok(LoadingSpec {
            inclination_deg: self.inclination,
            guide,
            stiffness_factor: self.stiffness_factor,
            dt: self.dt,
            criterion: self.criterion.clone(),
            tolerance: self.tolerance,
            min_iterations: self.min_iterations,
            max_iterations: self.max_iterations,
            bars: self.bars,
            sleeper_width: self.sleeper_width.unwrap_or(base.sleeper_width),
            ..base
        })
    }
}

fn input(msg: String) -> Failure {
    Failure::Input(Error::Scene(msg))
}

/// Writes `text` to `path`; the error names the file.
fn write(path: &Path, text: &str) -> Result<(), Failure> {
    std::fs::write(path, text).map_err(|e| Failure::Run(ballast::io::io_error(path, "write", e)))
}

pub fn main(cmd: SaussineCommand) -> Result<(), Failure> {
    match cmd {
        SaussineCommand::Sample { seed, bank, grains, dt, out, resume, quiet } => {
            let mut spec = SampleSpec { bank, dt, ..SampleSpec::saussine(seed) };
            if let Some(n) = grains {
                if n == 0 {
                    return Err(input("--grains: must be at least 1".into()));
                }
                spec = spec.scaled(n);
            }
            sample(&spec, &out, resume, if quiet { &Display::Quiet } else { &Display::Bar })
        }
        SaussineCommand::Load { sample, out, loading } => {
            let scene = Scene::load(&sample).map_err(Failure::Input)?;
            let loaded = loaded_scene(&scene, &loading_for(&scene, &loading)?).map_err(Failure::Input)?;
            write_scene(&out, &loaded, &format!("loaded from {}", sample.display()))?;
            println!("wrote {}", out.display());
            Ok(())
        }
        SaussineCommand::Settle { sample, out, loading, snapshot_every, checkpoint_every, resume, quiet } => {
            let scene = Scene::load(&sample).map_err(Failure::Input)?;
            let spec = loading_for(&scene, &loading)?;
            let loaded = loaded_scene(&scene, &spec).map_err(Failure::Input)?;
            ballast::io::create_output_dir(&out).map_err(Failure::Run)?;
            let path = out.join("loaded.toml");
            if !resume {
                write_scene(&path, &loaded, &format!("loaded from {}", sample.display()))?;
            }
            let steps_per_cycle = (1.0 / (spec.frequency * spec.dt)).round().max(1.0) as u64;
            let opts = RunOptions {
                checkpoint_every_s: checkpoint_every,
                resume,
                vtk_every: snapshot_every.saturating_mul(steps_per_cycle),
                figures: true,
                threads: default_threads(),
                ..RunOptions::default()
            };
            let display = if quiet { Display::Quiet } else { Display::Bar };
            run_scene(&path, &out, &opts, &display).map(|_| ())
        }
        SaussineCommand::Convergence { sample, policies, loading, study } => {
            studies::convergence(&sample, &policies, &loading, &study)
        }
        SaussineCommand::Steps { sample, dts, inclinations, loading, study } => {
            studies::steps(&sample, &dts, &inclinations, &loading, &study)
        }
        SaussineCommand::Ensemble { samples, first_seed, factors, grains, sample_dt, loading, study } => {
            studies::ensemble(samples, first_seed, &factors, grains, sample_dt, &loading, &study)
        }
    }
}

/// Writes `scene` to `path` with a header line.
pub(crate) fn write_scene(path: &Path, scene: &Scene, what: &str) -> Result<(), Failure> {
    let text = format!(
        "# Written by ballast {} (Saussine et al. 2006 experiments): {}.\n\n{}",
        env!("CARGO_PKG_VERSION"),
        what.replace(char::is_control, "?"),
        scene.to_toml_string().map_err(Failure::Run)?
    );
    write(path, &text)
}

/// Runs `scene_path` into `dir` unless a finished run is there already.
fn run_stage(scene_path: &Path, dir: &Path, resume: bool, display: &Display) -> Result<Scene, Failure> {
    let final_scene = dir.join("final_scene.toml");
    let prior = Prior::of(dir, "final_scene.toml", resume);
    if prior != Prior::Finished {
        let resume = prior == Prior::Checkpointed;
        // One sweep thread per run when deposits run side by side (an ensemble).
        let threads = if matches!(display, Display::Group(..)) { 1 } else { default_threads() };
        let opts = RunOptions { checkpoint_every_s: 300.0, resume, threads, ..RunOptions::default() };
        run_scene(scene_path, dir, &opts, display)?;
    }
    Scene::load(&final_scene).map_err(Failure::Run)
}

/// Deposits the sample of `spec` into `out` (`sample.toml`, `sample.json`).
pub(crate) fn sample(spec: &SampleSpec, out: &Path, resume: bool, display: &Display) -> Result<(), Failure> {
    let scene = sample_scene(spec).map_err(Failure::Input)?;
    ballast::io::create_output_dir(out).map_err(Failure::Run)?;
    let deposit = out.join("deposit.toml");
    write_scene(&deposit, &scene, &format!("stage 1 (deposit) of the sample, seed {}", spec.seed))?;
    let mut settled = run_stage(&deposit, &out.join("deposit"), resume, display)?;
    if spec.bank {
        let opened = open_bank(&settled).map_err(Failure::Run)?;
        let bank = out.join("bank.toml");
        write_scene(&bank, &opened, "the deposited sample without its mould, to settle into free banks")?;
        settled = run_stage(&bank, &out.join("bank"), resume, display)?;
    }
    let path = out.join("sample.toml");
    write_scene(&path, &settled, &format!("deposited sample, seed {}", spec.seed))?;
    let report = measure_sample(&settled).map_err(Failure::Run)?;
    ballast::io::write_json(&out.join("sample.json"), &report).map_err(Failure::Run)?;
    println!(
        "sample {}: {} grains, layer {:.1} mm thick; weight {:.2} N, sublayer {:.2} N, walls {:.2} N (balance error \
         {:.2e}); mean overlap {:.2e} m, max {:.2e} m; solid fraction {:.3}, coordination {:.2} ({:.0} % rattlers)",
        path.display(),
        report.grains,
        1e3 * report.thickness_m,
        report.weight_n,
        report.sublayer_reaction_n,
        report.wall_friction_n,
        report.balance_error,
        report.mean_overlap_m,
        report.max_overlap_m,
        report.solid_fraction,
        report.coordination,
        100.0 * report.rattler_fraction
    );
    Ok(())
}
