//! The campaigns of Saussine et al. (2006) as single commands: many loaded runs
//! of the same sample, run side by side (one run per core, `--jobs`), each in its
//! own folder with the outputs of `ballast run` (series, cycles, summary,
//! checkpoints, figures), then one summary CSV and the study's figures.
//!
//! - `convergence` (§3.2): one run per policy × tolerance of the paper's table
//!   (energy 1.66e-3/-4/-5, strict 1e-3 and 1e-4, non-strict "quad" 1e-5/-6/-7);
//!   `convergence.csv` (mean NLGS iterations, wall time, interpenetration),
//!   `cumulated_interpenetration` (Fig. 2), `iterations_vs_tolerance`.
//!   The first strict tolerance is illegible in the paper's table ("1 ×"): 1e-3 is
//!   taken, a decade above its other strict value as for the other policies.
//! - `steps` (§3.3): one run per time step (1e-4 … 1e-3 s, ten values) × inclination
//!   (0°, 5°); `steps.csv`, `max_interpenetration_<a>deg` (Fig. 3),
//!   `mean_interpenetration_<a>deg` (Fig. 4), `interpenetration_vs_dt`.
//! - `ensemble` (§4.2): samples that differ only by their seed, deposited, then
//!   loaded on sublayers of stiffness k_N × 1, × 100, × 1000; `ensemble.csv` (mean,
//!   standard deviation, min and max of the settlement over the samples, per
//!   stiffness and cycle) and `settlement_ensemble` (mean ± one standard deviation).
//!
//! Layout: `DIR/scenes/<run>.toml` and `DIR/runs/<run>/`. A run that diverges is
//! reported in the summary (`status`), the others go on. `--resume` skips the
//! finished runs and resumes the checkpointed ones.

use super::saussine::{sample, LoadingArgs};
use super::{run_scene, Display, Failure};
use ballast::io::cycles::NscdCycleRow as CycleRow;
use ballast::io::figures::{self, Axes, Series};
use ballast::io::series::NscdSeriesRow as SeriesRow;
use ballast::io::table::TableWriter;
use ballast::io::{self, RunReport};
use ballast::run::{cores, default_threads, Prior, RunOptions};
use ballast::scenarios::saussine::{loaded_scene, LoadingSpec, SampleSpec, GRAIN_PREFIX};
use ballast::scene::Scene;
use ballast::Error;
use indicatif::MultiProgress;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Settings shared by the studies.
#[derive(Debug, Clone, clap::Args)]
pub struct StudyArgs {
    /// Output directory of the study.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Runs at once, each on one core (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Skip the finished runs and resume the checkpointed ones of an interrupted study.
    #[arg(long)]
    pub resume: bool,
    /// Wall-clock seconds between checkpoints of each run.
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
    pub checkpoint_every: f64,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
}

/// The convergence policies and tolerances of the table of §3.2.
pub const PAPER_POLICIES: [(&str, f64); 8] = [
    ("energy", 1.66e-3),
    ("energy", 1.66e-4),
    ("energy", 1.66e-5),
    ("strict", 1e-3),
    ("strict", 1e-4),
    ("quad", 1e-5),
    ("quad", 1e-6),
    ("quad", 1e-7),
];

/// One run of a study: its label, the loading and where it goes.
struct Job {
    label: String,
    spec: LoadingSpec,
    sample: PathBuf,
}

impl Job {
    fn scene(&self, study: &Path) -> PathBuf {
        study.join("scenes").join(format!("{}.toml", self.label))
    }
    fn dir(&self, study: &Path) -> PathBuf {
        study.join("runs").join(&self.label)
    }
}

/// What a finished (or diverged) run left: its report, series and cycles.
struct Outcome {
    status: String,
    report: Option<RunReport>,
    series: Vec<SeriesRow>,
    cycles: Vec<CycleRow>,
}

fn input(msg: String) -> Failure {
    Failure::Input(Error::Scene(msg))
}

/// The number of grains of the reference sample (361 + 242 + 121).
fn reference_grains() -> usize {
    SampleSpec::saussine(0).grading.iter().map(|g| g.1).sum()
}

/// The loading of `args` for `sample`: the sleeper's width and the load scaled
/// with a sample scaled by `SampleSpec::scaled` (same pressure under the sleeper),
/// unless `--sleeper-width` is given.
pub fn loading_for(sample: &Scene, args: &LoadingArgs) -> Result<LoadingSpec, Failure> {
    let spec = args.spec()?;
    let grains = sample.bodies.iter().filter(|b| b.name.starts_with(GRAIN_PREFIX)).count();
    let f = grains as f64 / reference_grains() as f64;
    if grains == 0 || (f - 1.0).abs() < 1e-3 {
        return Ok(spec);
    }
    let mut scaled = spec.clone().scaled(f);
    if let Some(w) = args.sleeper_width {
        // The given sleeper keeps its bars.
        scaled.sleeper_width = w;
        scaled.bar_size = spec.bar_size;
    }
    Ok(scaled)
}

fn label_number(x: f64) -> String {
    format!("{x:e}").replace('.', "p")
}

/// A pool of `threads` threads for runs side by side.
fn pool(threads: usize) -> Result<rayon::ThreadPool, Failure> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Failure::Run(Error::Io(std::io::Error::other(e))))
}

/// Writes the scenes of `jobs`, runs them `study.jobs` at a time and reads back their outcomes.
fn run_jobs(jobs: &[Job], study: &StudyArgs) -> Result<Vec<Outcome>, Failure> {
    let out = &study.out;
    if !(study.checkpoint_every.is_finite() && study.checkpoint_every >= 0.0) {
        return Err(input(format!("--checkpoint-every: must be non-negative, got {}", study.checkpoint_every)));
    }
    let threads = study.jobs.unwrap_or_else(cores);
    if threads == 0 {
        return Err(input("--jobs: must be at least 1".into()));
    }
    for dir in ["scenes", "runs"] {
        io::create_output_dir(&out.join(dir)).map_err(Failure::Run)?;
    }
    // All scenes first, so that an invalid one stops the study before any run.
    let mut samples: Vec<(PathBuf, Scene)> = Vec::new();
    for job in jobs {
        let sample = match samples.iter().find(|(p, _)| p == &job.sample) {
            Some((_, s)) => s.clone(),
            None => {
                let s = Scene::load(&job.sample).map_err(Failure::Input)?;
                samples.push((job.sample.clone(), s.clone()));
                s
            }
        };
        let loaded = loaded_scene(&sample, &job.spec).map_err(Failure::Input)?;
        let what = format!("{} of the study in {}, from {}", job.label, out.display(), job.sample.display());
        super::saussine::write_scene(&job.scene(out), &loaded, &what)?;
    }
    let group = MultiProgress::new();
    let pool = pool(threads)?;
    let results: Vec<Result<(), Failure>> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let dir = job.dir(out);
                // summary.json: a diverged run is finished too (and reported as such).
                let prior = Prior::of(&dir, "summary.json", study.resume);
                if prior == Prior::Finished {
                    return Ok(());
                }
                let opts = RunOptions {
                    checkpoint_every_s: study.checkpoint_every,
                    resume: prior == Prior::Checkpointed,
                    figures: true,
                    // Several runs at once: one sweep thread each, unless one job.
                    threads: if threads == 1 { default_threads() } else { 1 },
                    ..RunOptions::default()
                };
                let display =
                    if study.quiet { Display::Quiet } else { Display::Group(group.clone(), job.label.clone()) };
                run_scene(&job.scene(out), &dir, &opts, &display).map(|_| ())
            })
            .collect()
    });
    let mut outcomes = Vec::with_capacity(jobs.len());
    for (job, result) in jobs.iter().zip(results) {
        let dir = job.dir(out);
        let status = match result {
            // Skipped on --resume, but diverged in an earlier invocation (no final scene).
            Ok(()) if !dir.join("final_scene.toml").exists() => "failed in an earlier invocation".to_string(),
            Ok(()) => "ok".to_string(),
            Err(Failure::Input(e)) => return Err(Failure::Input(e)),
            // A diverged run still wrote its series and summary: keep it in the study.
            Err(Failure::Run(e)) => {
                eprintln!("run {} failed: {e}", job.label);
                format!("failed: {}", super::one_line(&e))
            }
        };
        let report = std::fs::read_to_string(dir.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<RunReport>(&t).ok());
        let series = io::series::read_nscd(&dir.join("series.csv")).unwrap_or_default();
        let cycles_path = dir.join("cycles.csv");
        let cycles =
            if cycles_path.exists() { io::cycles::read_nscd(&cycles_path).map_err(Failure::Run)? } else { vec![] };
        outcomes.push(Outcome { status, report, series, cycles });
    }
    Ok(outcomes)
}

/// The columns of a study's summary CSVs that describe one run, from its report
/// and cycles (NaN where the run left nothing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunColumns {
    pub mean_iterations: f64,
    pub mean_contacts: f64,
    pub wall_time_s: f64,
    pub wall_time_per_cycle_s: f64,
    pub unconverged_steps: u64,
    pub mean_overlap_m: f64,
    pub max_overlap_m: f64,
    pub final_total_overlap_m: f64,
    pub cycles: u64,
    pub settlement_mean_m: f64,
    pub settlement_at_min_load_m: f64,
    pub status: String,
}

/// The names of the [`RunColumns`].
const RUN_COLUMNS: [&str; 12] = [
    "mean_iterations",
    "mean_contacts",
    "wall_time_s",
    "wall_time_per_cycle_s",
    "unconverged_steps",
    "mean_overlap_m",
    "max_overlap_m",
    "final_total_overlap_m",
    "cycles",
    "settlement_mean_m",
    "settlement_at_min_load_m",
    "status",
];

fn run_columns(o: &Outcome) -> RunColumns {
    let nan = f64::NAN;
    let r = o.report.as_ref();
    let last = o.cycles.last();
    RunColumns {
        mean_iterations: r.and_then(|r| r.mean_iterations).unwrap_or(nan),
        mean_contacts: r.map_or(nan, |r| r.mean_contacts),
        wall_time_s: r.map_or(nan, |r| r.wall_time_s),
        wall_time_per_cycle_s: r.and_then(|r| r.wall_time_per_cycle_s).unwrap_or(nan),
        unconverged_steps: r.and_then(|r| r.unconverged_steps).unwrap_or(0),
        mean_overlap_m: r.map_or(nan, |r| r.mean_overlap_m),
        max_overlap_m: r.map_or(nan, |r| r.max_overlap_m),
        final_total_overlap_m: o.series.last().map_or(nan, |s| s.total_overlap_m),
        cycles: last.map_or(0, |c| c.cycle),
        settlement_mean_m: last.map_or(nan, |c| c.settlement_mean_m),
        settlement_at_min_load_m: last.map_or(nan, |c| c.settlement_at_min_load_m),
        status: o.status.clone(),
    }
}

/// Writes a study table: the columns `key` then `rest`, one row per item.
fn write_table<R: Serialize>(path: &Path, key: &[&str], rest: &[&str], rows: &[R]) -> Result<(), Failure> {
    let header: Vec<&str> = key.iter().chain(rest).copied().collect();
    let mut t = TableWriter::create(path, &header).map_err(Failure::Run)?;
    for r in rows {
        t.write(r).map_err(Failure::Run)?;
    }
    t.finish().map_err(Failure::Run)
}

fn curve(o: &Outcome, label: String, f: fn(&SeriesRow) -> f64, scale: f64) -> Series {
    Series { label, points: o.series.iter().map(|s| (s.time_s, scale * f(s))).collect(), band: vec![] }
}

fn axes(title: &str, x: &str, y: &str, log_x: bool, log_y: bool) -> Axes {
    Axes { title: title.into(), x_label: x.into(), y_label: y.into(), log_x, log_y }
}

/// `ballast saussine convergence`: §3.2.
pub fn convergence(
    sample_path: &Path,
    policies: &[String],
    loading: &LoadingArgs,
    study: &StudyArgs,
) -> Result<(), Failure> {
    let mut runs: Vec<(String, f64)> = Vec::new();
    if policies.is_empty() {
        runs.extend(PAPER_POLICIES.iter().map(|&(p, t)| (p.to_string(), t)));
    }
    for p in policies {
        let (name, tol) = p
            .split_once(':')
            .ok_or_else(|| input(format!("--policies: expected POLICY:TOLERANCE (e.g. quad:1e-6), got '{p}'")))?;
        let tol: f64 = tol.parse().map_err(|_| input(format!("--policies: '{tol}' in '{p}' is not a number")))?;
        runs.push((name.to_string(), tol));
    }
    let sample_scene = Scene::load(sample_path).map_err(Failure::Input)?;
    let base = loading_for(&sample_scene, loading)?;
    let jobs: Vec<Job> = runs
        .iter()
        .map(|(policy, tol)| Job {
            label: format!("{policy}_{}", label_number(*tol)),
            spec: LoadingSpec { criterion: policy.clone(), tolerance: *tol, ..base.clone() },
            sample: sample_path.to_path_buf(),
        })
        .collect();
    let outcomes = run_jobs(&jobs, study)?;

    let rows: Vec<_> = runs
        .iter()
        .zip(&outcomes)
        .map(|((policy, tol), o)| ((policy.clone(), *tol, base.min_iterations, base.max_iterations), run_columns(o)))
        .collect();
    let out = &study.out;
    let key = ["policy", "tolerance", "min_iterations", "max_iterations"];
    write_table(&out.join("convergence.csv"), &key, &RUN_COLUMNS, &rows)?;

    let cumulated: Vec<Series> = runs
        .iter()
        .zip(&outcomes)
        .map(|((p, t), o)| curve(o, format!("{p} {t:e}"), |s| s.total_overlap_m, 1e6))
        .collect();
    figures::line_chart(
        &out.join("cumulated_interpenetration"),
        &axes("Cumulated interpenetration (sum over the contacts)", "time (s)", "cumulated overlap (µm)", false, true),
        &cumulated,
    )
    .map_err(Failure::Run)?;
    let mut per_policy: Vec<Series> = Vec::new();
    for ((p, t), o) in runs.iter().zip(&outcomes) {
        let Some(r) = &o.report else { continue };
        match per_policy.iter_mut().find(|s| &s.label == p) {
            Some(s) => s.points.push((*t, r.mean_iterations.unwrap_or(f64::NAN))),
            None => per_policy.push(Series {
                label: p.clone(),
                points: vec![(*t, r.mean_iterations.unwrap_or(f64::NAN))],
                band: vec![],
            }),
        }
    }
    per_policy.iter_mut().for_each(|s| s.points.sort_by(|a, b| a.0.total_cmp(&b.0)));
    figures::line_chart(
        &out.join("iterations_vs_tolerance"),
        &axes("NLGS iterations per step vs tolerance", "tolerance", "mean sweeps per step", true, false),
        &per_policy,
    )
    .map_err(Failure::Run)?;
    print_table(out, "convergence.csv")?;
    Ok(())
}

/// `ballast saussine steps`: §3.3.
pub fn steps(
    sample_path: &Path,
    dts: &[f64],
    inclinations: &[f64],
    loading: &LoadingArgs,
    study: &StudyArgs,
) -> Result<(), Failure> {
    if let Some(dt) = dts.iter().find(|dt| !(dt.is_finite() && **dt > 0.0)) {
        return Err(input(format!("--dts: every time step must be positive, got {dt}")));
    }
    let sample_scene = Scene::load(sample_path).map_err(Failure::Input)?;
    let mut jobs = Vec::new();
    let mut keys = Vec::new();
    for &a in inclinations {
        let args = LoadingArgs { inclination: a, ..loading.clone() };
        let base = loading_for(&sample_scene, &args)?;
        for &dt in dts {
            jobs.push(Job {
                label: format!("incl_{}_dt_{}", label_number(a), label_number(dt)),
                spec: LoadingSpec { dt, ..base.clone() },
                sample: sample_path.to_path_buf(),
            });
            keys.push((a, dt));
        }
    }
    let outcomes = run_jobs(&jobs, study)?;
    let out = &study.out;
    let rows: Vec<_> = keys.iter().zip(&outcomes).map(|(&(a, dt), o)| ((a, dt), run_columns(o))).collect();
    write_table(&out.join("steps.csv"), &["inclination_deg", "dt_s"], &RUN_COLUMNS, &rows)?;
    let mut vs_dt = Vec::new();
    for &a in inclinations {
        let runs: Vec<_> = keys.iter().zip(&outcomes).filter(|((b, _), _)| *b == a).collect();
        let tag = format!("{a}").replace('.', "p").replace('-', "m");
        for (name, what, f) in [
            ("max", "Maximal", (|s: &SeriesRow| s.max_overlap_m) as fn(&SeriesRow) -> f64),
            ("mean", "Average", |s: &SeriesRow| s.mean_overlap_m),
        ] {
            let curves: Vec<Series> =
                runs.iter().map(|((_, dt), o)| curve(o, format!("dt = {dt:e} s"), f, 1e6)).collect();
            figures::line_chart(
                &out.join(format!("{name}_interpenetration_{tag}deg")),
                &axes(&format!("{what} interpenetration, load at {a}°"), "time (s)", "overlap (µm)", false, false),
                &curves,
            )
            .map_err(Failure::Run)?;
        }
        for (name, f) in [
            ("mean", (|r: &RunReport| r.mean_overlap_m) as fn(&RunReport) -> f64),
            ("max", |r: &RunReport| r.max_overlap_m),
        ] {
            let points = runs.iter().filter_map(|((_, dt), o)| o.report.as_ref().map(|r| (*dt, 1e6 * f(r)))).collect();
            vs_dt.push(Series { label: format!("{name}, {a}°"), points, band: vec![] });
        }
    }
    figures::line_chart(
        &out.join("interpenetration_vs_dt"),
        &axes("Interpenetration over the run vs time step", "dt (s)", "overlap (µm)", true, true),
        &vs_dt,
    )
    .map_err(Failure::Run)?;
    print_table(out, "steps.csv")?;
    Ok(())
}

/// Statistics over the samples of an ensemble.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    pub mean: f64,
    pub std: f64,
    pub min: f64,
    pub max: f64,
}

impl Spread {
    /// Mean, sample standard deviation (0 for one value), min and max of `xs` (not empty).
    pub fn of(xs: &[f64]) -> Self {
        let n = xs.len() as f64;
        let mean = xs.iter().sum::<f64>() / n;
        let var = if xs.len() > 1 { xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
        Self {
            mean,
            std: var.sqrt(),
            min: xs.iter().copied().fold(f64::INFINITY, f64::min),
            max: xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// `ballast saussine ensemble`: §4.2.
#[allow(clippy::too_many_arguments)]
pub fn ensemble(
    samples: u64,
    first_seed: u64,
    factors: &[f64],
    grains: Option<usize>,
    sample_dt: f64,
    loading: &LoadingArgs,
    study: &StudyArgs,
) -> Result<(), Failure> {
    if samples == 0 {
        return Err(input("--samples: must be at least 1".into()));
    }
    if let Some(f) = factors.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(input(format!("--factors: every stiffness factor must be positive, got {f}")));
    }
    let out = &study.out;
    let seeds: Vec<u64> = (0..samples).map(|k| first_seed + k).collect();
    // 1. The samples, deposited side by side.
    let pool = pool(study.jobs.unwrap_or_else(cores).max(1))?;
    let group = MultiProgress::new();
    let deposited: Vec<Result<(), Failure>> = pool.install(|| {
        seeds
            .par_iter()
            .map(|&seed| {
                let mut spec = SampleSpec { dt: sample_dt, ..SampleSpec::saussine(seed) };
                if let Some(n) = grains {
                    spec = spec.scaled(n);
                }
                let dir = out.join("samples").join(format!("seed_{seed}"));
                if study.resume && dir.join("sample.toml").exists() {
                    return Ok(());
                }
                let display =
                    if study.quiet { Display::Quiet } else { Display::Group(group.clone(), format!("sample {seed}")) };
                sample(&spec, &dir, study.resume, &display)
            })
            .collect()
    });
    deposited.into_iter().collect::<Result<Vec<()>, Failure>>()?;
    // 2. Every sample on every sublayer.
    let mut jobs = Vec::new();
    let mut keys = Vec::new();
    for &seed in &seeds {
        let sample_path = out.join("samples").join(format!("seed_{seed}")).join("sample.toml");
        let sample_scene = Scene::load(&sample_path).map_err(Failure::Run)?;
        for &k in factors {
            let args = LoadingArgs { stiffness_factor: k, ..loading.clone() };
            jobs.push(Job {
                label: format!("seed_{seed}_k_{}", label_number(k)),
                spec: loading_for(&sample_scene, &args)?,
                sample: sample_path.clone(),
            });
            keys.push((seed, k));
        }
    }
    let outcomes = run_jobs(&jobs, study)?;
    // 3. Per run, and mean and spread per stiffness and cycle.
    let rows: Vec<_> = keys.iter().zip(&outcomes).map(|(&(seed, k), o)| ((seed, k), run_columns(o))).collect();
    write_table(&out.join("runs.csv"), &["seed", "stiffness_factor"], &RUN_COLUMNS, &rows)?;
    let mut table = Vec::new();
    let mut curves = Vec::new();
    for &k in factors {
        let runs: Vec<&Outcome> = keys.iter().zip(&outcomes).filter(|((_, f), _)| *f == k).map(|(_, o)| o).collect();
        // Cycles that every sample reached (a failed run shortens the ensemble's curve).
        let n = runs.iter().map(|o| o.cycles.len()).min().unwrap_or(0);
        let mut points = Vec::new();
        let mut band = Vec::new();
        for c in 0..n {
            let mean: Vec<f64> = runs.iter().map(|o| o.cycles[c].settlement_mean_m).collect();
            let at_min: Vec<f64> = runs.iter().map(|o| o.cycles[c].settlement_at_min_load_m).collect();
            let (s, m) = (Spread::of(&mean), Spread::of(&at_min));
            let cycle = runs[0].cycles[c].cycle;
            table.push(EnsembleRow {
                stiffness_factor: k,
                cycle,
                samples: runs.len(),
                settlement_mean_m: s.mean,
                settlement_std_m: s.std,
                settlement_min_m: s.min,
                settlement_max_m: s.max,
                settlement_at_min_load_mean_m: m.mean,
                settlement_at_min_load_std_m: m.std,
            });
            points.push((cycle as f64, 1e3 * s.mean));
            band.push((cycle as f64, 1e3 * (s.mean - s.std), 1e3 * (s.mean + s.std)));
        }
        curves.push(Series { label: format!("k_N × {k} ({} samples, mean ± 1 sd)", runs.len()), points, band });
    }
    io::table::write_all(&out.join("ensemble.csv"), &table).map_err(Failure::Run)?;
    figures::line_chart(
        &out.join("settlement_ensemble"),
        &axes("Settlement of the sleeper vs sublayer stiffness", "cycles", "settlement (mm)", false, false),
        &curves,
    )
    .map_err(Failure::Run)?;
    print_table(out, "runs.csv")?;
    Ok(())
}

/// One row of `ensemble.csv`: the settlement over the samples of one sublayer
/// stiffness at one cycle (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsembleRow {
    pub stiffness_factor: f64,
    pub cycle: u64,
    pub samples: usize,
    pub settlement_mean_m: f64,
    pub settlement_std_m: f64,
    pub settlement_min_m: f64,
    pub settlement_max_m: f64,
    pub settlement_at_min_load_mean_m: f64,
    pub settlement_at_min_load_std_m: f64,
}

/// Prints a summary CSV of the study as a table, and where the outputs are.
fn print_table(out: &Path, name: &str) -> Result<(), Failure> {
    let path = out.join(name);
    let mut reader = csv::Reader::from_path(&path).map_err(|e| Failure::Run(Error::Io(std::io::Error::other(e))))?;
    let header = reader.headers().map_err(|e| Failure::Run(Error::Io(std::io::Error::other(e))))?.clone();
    println!("{}", header.iter().collect::<Vec<_>>().join("  "));
    for rec in reader.records().flatten() {
        println!("{}", rec.iter().collect::<Vec<_>>().join("  "));
    }
    println!("summary: {}; runs in {}", path.display(), out.join("runs").display());
    Ok(())
}
