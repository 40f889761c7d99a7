//! The experiments of Saussine et al. (2006), §3–4, on one sample (the
//! scenes of [`crate::scenarios::saussine`]), each from scene
//! files written into the output folder and run with the same loop as
//! `ballast run` (progress, checkpoints, `--resume`):
//!
//! - [`sample`]: generate and deposit the sample (stage 1, and 1b for a
//!   free bank), save it as `sample.toml`, measure its balance, solid fraction
//!   and coordination number (`sample.json`);
//! - [`load`]: write the loaded scene (sleeper with bars, load, sublayer
//!   stiffness, solver, time step, number of cycles) from a deposited sample;
//! - [`settle`] (§4): load a sample and run its cycles: `cycles.csv`,
//!   `summary.json`, VTK snapshots every few cycles, figures;
//!   [`settle_replicas`] the same from several perturbed starts side by side
//!   ([`super::replicas`]), with the ensemble's settlement per cycle and its
//!   95 % confidence interval (`settlement_ensemble.csv`).
//!
//! The settings of the loaded stage are a [`LoadingSpec`] (the options of
//! `ballast saussine load`); a sample scaled to fewer grains is loaded with the
//! sleeper's width and the load scaled alike (same pressure,
//! [`LoadingSpec::for_sample`]), unless the sleeper's width is given.

use super::replicas::{
    perturb_scene, settlement_ensemble, CycleSettlement, Replicas, SettlementEnsembleRow, Start, REPLICA_FILE,
};
use super::tasks::{failures_from_folders, Tasks};
use super::{output_error, run_scene, write_scene_file, RunDisplay};
use crate::error::{Error, Result};
use crate::io;
use crate::io::figures::Series;
use crate::io::layout;
use crate::run::{default_threads, Prior, RunOptions, RunOutcome};
use crate::scenarios::saussine::{
    loaded_scene, measure_sample, open_bank, sample_scene, LoadingSpec, SampleReport, SampleSpec,
};
use crate::scene::Scene;
use crate::scene::SceneFile;
use std::path::{Path, PathBuf};

/// Writes `scene` to `path` with a header line saying `what` it is.
///
/// # Errors
/// [`Error::Io`] naming the file.
pub fn write_scene(path: &Path, scene: &Scene, what: &str) -> Result<()> {
    write_scene_file(path, scene, "Saussine et al. 2006 experiments", what)
}

/// A deposited sample: its scene and what `sample.json` records.
#[derive(Debug, Clone)]
pub struct Sample {
    /// `sample.toml`, the deposited sample as a scene.
    pub path: PathBuf,
    /// Its balance, overlaps, solid fraction and coordination (`sample.json`).
    pub report: SampleReport,
}

/// Deposits the sample of `spec` into `out`: `deposit.toml` run in
/// `out/deposit/` until equilibrium, with a bank `bank.toml` run again in
/// `out/bank/`, then `sample.toml` and `sample.json`. Each stage runs on
/// `threads` threads; with `resume`, a finished stage is not run again and a
/// checkpointed one is resumed. The runs are labelled `sample <seed>`.
///
/// # Errors
/// [`Error::Scene`] for an invalid spec (or checkpoint); a stage that fails
/// (divergence) or an output that cannot be written or read back is another
/// error.
pub fn sample(spec: &SampleSpec, out: &Path, resume: bool, threads: usize, display: &dyn RunDisplay) -> Result<Sample> {
    let label = format!("sample {}", spec.seed);
    let scene = sample_scene(spec)?;
    io::create_output_dir(out)?;
    let deposit = out.join("deposit.toml");
    write_scene(&deposit, &scene, &format!("stage 1 (deposit) of the sample, seed {}", spec.seed))?;
    let stage = |scene: &Path, dir: &Path| run_stage(scene, dir, resume, threads, display, &label);
    let mut settled = stage(&deposit, &out.join("deposit"))?;
    if spec.bank {
        let opened = open_bank(&settled).map_err(output_error)?;
        let bank = out.join("bank.toml");
        write_scene(&bank, &opened, "the deposited sample without its mould, to settle into free banks")?;
        settled = stage(&bank, &out.join("bank"))?;
    }
    let path = out.join("sample.toml");
    write_scene(&path, &settled, &format!("deposited sample, seed {}", spec.seed))?;
    let report = measure_sample(&settled).map_err(output_error)?;
    io::write_json(&out.join("sample.json"), &report)?;
    Ok(Sample { path, report })
}

/// Runs `scene_path` into `dir` unless a finished run is there already; the
/// state it ends in.
fn run_stage(
    scene_path: &Path,
    dir: &Path,
    resume: bool,
    threads: usize,
    display: &dyn RunDisplay,
    label: &str,
) -> Result<Scene> {
    let prior = Prior::of(dir, layout::FINAL_SCENE, resume);
    if prior != Prior::Finished {
        let resume = prior == Prior::Checkpointed;
        let opts = RunOptions { checkpoint_every_s: 300.0, resume, threads, ..RunOptions::default() };
        run_scene(scene_path, dir, &opts, display, label)?;
    }
    Scene::load(dir.join(layout::FINAL_SCENE)).map_err(output_error)
}

/// The loaded scene of the sample at `sample` under `loading` (the sample's
/// own scaling, [`LoadingSpec::for_sample`]), and the loading spec it was made with.
fn loaded(sample: &Path, loading: &LoadingSpec) -> Result<(Scene, LoadingSpec)> {
    let scene = Scene::load(sample)?;
    let spec = loading.for_sample(&scene)?;
    Ok((loaded_scene(&scene, &spec)?, spec))
}

/// Writes the loaded scene of the sample at `sample` (a `sample.toml` of
/// [`sample`]) to `out`: the sleeper (and its bars) on top under
/// F = A + B cos(2π f t − φ), ready for `ballast run`.
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample or an invalid loading;
/// [`Error::Io`] if `out` cannot be written.
pub fn load(sample: &Path, loading: &LoadingSpec, out: &Path) -> Result<()> {
    let (scene, _) = loaded(sample, loading)?;
    write_scene(out, &scene, &format!("loaded from {}", sample.display()))
}

/// How [`settle`] runs.
#[derive(Debug, Clone, PartialEq)]
pub struct SettleOptions {
    /// A VTK snapshot (bodies and contact forces) every this many cycles; 0: none.
    pub snapshot_every: u64,
    /// Wall-clock seconds between checkpoints.
    pub checkpoint_every_s: f64,
    /// Continue a killed run from its checkpoint.
    pub resume: bool,
    /// Of a replica study ([`settle_replicas`], [`super::accelerated::settle_accelerated_replicas`]): which
    /// replicas this invocation runs, and whether it writes the summary ([`Tasks`]; a single run ignores it).
    pub tasks: Tasks,
}

/// §4: loads the sample at `sample` and runs its cycles in `out` (the loaded
/// scene written there as `loaded.toml`, kept on `resume`): per-cycle
/// settlement, mean grain speed, contacts and iterations (`cycles.csv`), VTK
/// snapshots, figures. The run is labelled `settle`. It starts where replica
/// `start.replica` of [`settle_replicas`] with the same perturbation starts (0:
/// the sample as it is; `r ≥ 1`: perturbed, recorded as [`REPLICA_FILE`]).
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample, an invalid loading, perturbation
/// or checkpoint; else as [`crate::run::Runner::run`].
pub fn settle(
    sample: &Path,
    loading: &LoadingSpec,
    start: &Start,
    out: &Path,
    opts: &SettleOptions,
    display: &dyn RunDisplay,
) -> Result<RunOutcome> {
    let (scene, spec) = loaded(sample, loading)?;
    let path = write_start(sample, scene, start, out, opts.resume, false, "")?;
    let per_cycle = steps_per_cycle(spec.frequency, spec.dt);
    run_settle(&path, out, per_cycle, opts, default_threads(), opts.resume, display, "settle")
}

/// Writes the loaded `scene` of `sample` as `out/loaded.toml` from `start`,
/// unless `resume` keeps the one there; `what` is added to the file's note. A
/// perturbed start, or any start of an ensemble (`in_ensemble`, replica 0
/// too), is named in the note and recorded as [`REPLICA_FILE`]. Its path.
pub(crate) fn write_start(
    sample: &Path,
    mut scene: Scene,
    start: &Start,
    out: &Path,
    resume: bool,
    in_ensemble: bool,
    what: &str,
) -> Result<PathBuf> {
    let record = perturb_scene(&mut scene, &start.perturbation, start.replica)?;
    io::create_output_dir(out)?;
    let path = out.join("loaded.toml");
    if !resume {
        let labelled = in_ensemble || start.replica > 0;
        let replica = match start.replica {
            _ if !labelled => String::new(),
            r => format!(
                ", replica {r} (start perturbed by at most {} m, seed {})",
                if r == 0 { 0.0 } else { start.perturbation.distance_m },
                start.perturbation.seed
            ),
        };
        write_scene(&path, &scene, &format!("loaded from {}{replica}{what}", sample.display()))?;
        if labelled {
            io::write_json(&out.join(REPLICA_FILE), &record)?;
        }
    }
    Ok(path)
}

pub use super::Accelerate;

/// §4 accelerated: [`settle`]'s loaded scene from `start` (written as
/// `OUT/loaded.toml`, with its `[settlement]` table, the sleeper as the
/// settlement body) run through
/// [`crate::open::settle_file`]: `settlement.csv`, `jumps.csv`, `summary.json`,
/// the figures; with a reference, `errors.csv` ([`crate::report::settlement`]).
///
/// The run sweeps on `threads` threads (the numbers do not depend on them).
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample, an invalid loading or settings;
/// else as [`crate::settlement::Accelerated::run`].
#[allow(clippy::too_many_arguments)]
pub fn settle_accelerated(
    sample: &Path,
    loading: &LoadingSpec,
    start: &Start,
    accelerate: &Accelerate,
    out: &Path,
    opts: &SettleOptions,
    threads: usize,
    progress: &mut dyn FnMut(&crate::settlement::AccelerationProgress),
) -> Result<crate::settlement::AccelerationSummary> {
    let (mut scene, _) = loaded(sample, loading)?;
    let sys = scene.build()?;
    let smallest = (0..sys.bodies.len())
        .filter(|&i| !sys.bodies.info[i].fixed)
        .map(|i| sys.bodies.info[i].shape.inner_radius())
        .fold(f64::INFINITY, f64::min);
    let sleeper = scene.output.as_ref().and_then(|o| o.cycles.as_ref()).and_then(|c| c.body.clone());
    scene.settlement = Some(accelerate.section(sleeper, Some(0.01 * smallest)));
    scene.validate()?;
    let path = write_start(sample, scene, start, out, opts.resume, false, ", accelerated")?;
    let run = RunOptions {
        checkpoint_every_s: opts.checkpoint_every_s,
        resume: opts.resume,
        figures: true,
        threads,
        ..RunOptions::default()
    };
    accelerate.run_scene(&path, out, &run, progress)
}

/// Steps of a loading cycle at `frequency` (Hz) with the time step `dt` (s), at least 1.
pub(crate) fn steps_per_cycle(frequency: f64, dt: f64) -> u64 {
    (1.0 / (frequency * dt)).round().max(1.0) as u64
}

/// Runs the loaded scene at `path` into `out` as [`settle`] does (`steps_per_cycle`: of its loading, for the
/// snapshots' period).
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_settle(
    path: &Path,
    out: &Path,
    steps_per_cycle: u64,
    opts: &SettleOptions,
    threads: usize,
    resume: bool,
    display: &dyn RunDisplay,
    label: &str,
) -> Result<RunOutcome> {
    let run = RunOptions {
        checkpoint_every_s: opts.checkpoint_every_s,
        resume,
        vtk_every: opts.snapshot_every.saturating_mul(steps_per_cycle),
        figures: true,
        threads,
        ..RunOptions::default()
    };
    run_scene(path, out, &run, display, label)
}

/// What [`settle_replicas`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct SettleReplicas {
    /// The folder of the replicas' runs, `OUT/runs` (each in `replica-<r>/`).
    pub runs: PathBuf,
    /// `OUT/settlement_ensemble.csv`.
    pub table: PathBuf,
    /// Its rows: the ensemble per cycle.
    pub rows: Vec<SettlementEnsembleRow>,
    /// `(label, error)` of each replica that failed (its cycles, if any, are still in the ensemble, which
    /// stops at the last cycle every replica reached): with the summary, every one, as recorded in its folder
    /// ([`super::tasks::folder_end`], also by earlier invocations); without it, those of this invocation.
    pub failed: Vec<(String, String)>,
    /// Whether the summary was written (not by a [`Tasks::One`] or [`Tasks::Share`] invocation, whose `rows`
    /// are empty).
    pub summarized: bool,
}

/// The folder of replica `r` of a settlement run in `out`.
pub fn replica_dir(out: &Path, r: u64) -> PathBuf {
    out.join("runs").join(format!("replica-{r}"))
}

/// §4 with replicas: [`settle`] from `replicas.count` starts, replica 0 the
/// sample as it is and replica `r ≥ 1` perturbed by
/// [`super::replicas::perturb_scene`]; the runs go side by side, `jobs` at a
/// time (`None`: one per core), each in `OUT/runs/replica-<r>/` with the
/// outputs of [`settle`], its (perturbed) `loaded.toml` and
/// [`super::replicas::REPLICA_FILE`]; `opts.resume` skips the finished
/// replicas and resumes the checkpointed ones. Then `OUT/settlement_ensemble.csv`
/// ([`SettlementEnsembleRow`]: per cycle, mean, standard deviation and 95 %
/// interval of the settlement at the load minimum, and of the settlement
/// accrued since cycle `replicas.seating_cycles`) and the figure
/// `settlement_ensemble` (the replicas thin, their mean with its interval). The
/// runs are labelled `replica-<r>`. `opts.tasks` runs one replica alone or a share
/// of them (their starts written, no summary), or none (the summary from the
/// replicas' folders).
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample, an invalid loading, replicas,
/// `jobs`, task or checkpoint (before any run), or a summary asked for while a
/// replica has no finished run (named); a replica that fails is reported in
/// [`SettleReplicas::failed`]; an output that cannot be written is an
/// [`Error::Io`].
pub fn settle_replicas(
    sample: &Path,
    loading: &LoadingSpec,
    out: &Path,
    opts: &SettleOptions,
    replicas: &Replicas,
    jobs: Option<usize>,
    display: &dyn RunDisplay,
) -> Result<SettleReplicas> {
    crate::io::figures::require()?; // the runs end with their figures
    replicas.check()?;
    opts.tasks.check(replicas.count)?;
    let threads = replica_jobs(jobs, replicas.count)?;
    let (scene, _) = loaded(sample, loading)?;
    // Every replica's scene first, so that an invalid one stops before any run.
    let tasks = super::replica_tasks::write_starts(&scene, sample, out, replicas, opts.resume, opts.tasks)?;
    let pool = super::campaigns::pool(threads)?;
    let results: Vec<Result<()>> = pool.install(|| {
        use rayon::prelude::*;
        (0..replicas.count)
            .into_par_iter()
            .map(|r| match opts.tasks.runs(r) {
                true => {
                    let threads = super::campaigns::run_threads(if opts.tasks.side_by_side() { threads } else { 1 });
                    super::replica_tasks::run_replica(out, r, opts, threads, display)
                }
                false => Ok(()),
            })
            .collect()
    });
    end_replicas(out, replicas.count, opts.tasks, results, |failures| {
        super::replica_tasks::finish(out, failures, tasks.seating)
    })
}

/// The end of an invocation of a replica study in `out` of `count` replicas, once the runs it made ended
/// (`results`, replica by replica; `Ok` for those it did not run): without the summary (`tasks`), the failures
/// of this invocation; with it, `summarize` given every replica's end as recorded in its folder (also those an
/// earlier invocation or another process ran).
///
/// # Errors
/// The first input error of `results`; with the summary, a replica without a finished run (named), or
/// `summarize`'s.
pub(crate) fn end_replicas(
    out: &Path,
    count: u64,
    tasks: Tasks,
    results: Vec<Result<()>>,
    summarize: impl FnOnce(&[Option<String>]) -> Result<SettleReplicas>,
) -> Result<SettleReplicas> {
    let failures = failures(results)?;
    if !tasks.summarizes() {
        return Ok(not_summarized(out, &failures));
    }
    let folders: Vec<(String, PathBuf)> = (0..count).map(|r| (format!("replica-{r}"), replica_dir(out, r))).collect();
    summarize(&failures_from_folders(&folders)?)
}

/// What a replica study in `out` that ran a task without its summary reports: the failures of this invocation.
fn not_summarized(out: &Path, failures: &[Option<String>]) -> SettleReplicas {
    let failed = failures.iter().enumerate().filter_map(|(r, f)| Some((format!("replica-{r}"), f.clone()?))).collect();
    SettleReplicas {
        runs: out.join("runs"),
        table: out.join("settlement_ensemble.csv"),
        rows: Vec::new(),
        failed,
        summarized: false,
    }
}

/// The failure of each replica of `results` (`None`: it ran), or the first input error ([`Error::is_input`]:
/// an invalid scene or checkpoint, which stops the study).
///
/// # Errors
/// That input error.
fn failures(results: Vec<Result<()>>) -> Result<Vec<Option<String>>> {
    results
        .into_iter()
        .map(|r| match r {
            Ok(()) => Ok(None),
            Err(e) if e.is_input() => Err(e),
            Err(e) => Ok(Some(e.one_line())),
        })
        .collect()
}

/// The runs of a replica study at once: `jobs` (`None`: one per core), at most
/// `count`.
///
/// # Errors
/// [`Error::Scene`] for `jobs` = 0.
pub(crate) fn replica_jobs(jobs: Option<usize>, count: u64) -> Result<usize> {
    match jobs.unwrap_or_else(crate::run::cores) {
        0 => Err(Error::Scene("jobs: must be at least 1".into())),
        n => Ok(n.min(count as usize)),
    }
}

/// The end of a replica study in `out`: the failures of its replicas (`failures[r]`: the one-line error of
/// replica `r`, `None` if it ran), each replica's table `file` read by `read` (empty when absent),
/// `OUT/settlement_ensemble.csv` with the seating cycle `seating` and its figure titled `title`.
///
/// # Errors
/// A table that cannot be read or written.
pub(crate) fn finish_replicas<T: CycleSettlement>(
    out: &Path,
    failures: &[Option<String>],
    file: &str,
    read: impl Fn(&Path) -> Result<Vec<T>>,
    seating: u64,
    title: &str,
) -> Result<SettleReplicas> {
    let mut failed = Vec::new();
    let mut tables = Vec::new();
    for (r, failure) in failures.iter().enumerate() {
        if let Some(e) = failure {
            failed.push((format!("replica-{r}"), e.clone()));
        }
        let path = replica_dir(out, r as u64).join(file);
        tables.push(if path.exists() { read(&path)? } else { vec![] });
    }
    let runs: Vec<&[T]> = tables.iter().map(Vec::as_slice).collect();
    let rows = settlement_ensemble(&runs, seating);
    let table = out.join("settlement_ensemble.csv");
    io::table::write_all(&table, &rows)?;
    ensemble_figure(&out.join("settlement_ensemble"), title, &runs, &rows)?;
    Ok(SettleReplicas { runs: out.join("runs"), table, rows, failed, summarized: true })
}

/// The figure of an ensemble of settlement runs at `stem`: each replica's
/// settlement at the load minimum as a thin line, the mean of the total and of
/// the accrued settlement with their 95 % intervals (mm vs cycles).
pub(crate) fn ensemble_figure(
    stem: &Path,
    title: &str,
    runs: &[&[impl CycleSettlement]],
    rows: &[SettlementEnsembleRow],
) -> Result<()> {
    let mm = |x: f64| 1e3 * x;
    let mut curves: Vec<Series> = runs
        .iter()
        .map(|r| Series {
            label: String::new(),
            points: r.iter().map(|c| (c.cycle() as f64, mm(c.settlement_at_min_load()))).collect(),
            band: vec![],
            thin: true,
            points_only: false,
        })
        .collect();
    if let Some(first) = curves.first_mut() {
        first.label = "each replica".into();
    }
    let n = runs.len();
    let band = |lo: fn(&SettlementEnsembleRow) -> Option<f64>, hi: fn(&SettlementEnsembleRow) -> Option<f64>| {
        rows.iter().filter_map(|r| Some((r.cycle as f64, mm(lo(r)?), mm(hi(r)?)))).collect::<Vec<_>>()
    };
    curves.push(Series {
        label: format!("mean of {n} replicas, 95 % CI"),
        points: rows.iter().map(|r| (r.cycle as f64, mm(r.settlement_mean_m))).collect(),
        band: band(|r| r.settlement_ci95_low_m, |r| r.settlement_ci95_high_m),
        thin: false,
        points_only: false,
    });
    let s = rows.first().map_or(0, |r| r.seating_cycle);
    curves.push(Series {
        label: format!("accrued since cycle {s}: mean, 95 % CI"),
        points: rows.iter().filter_map(|r| Some((r.cycle as f64, mm(r.accrued_mean_m?)))).collect(),
        band: band(|r| r.accrued_ci95_low_m, |r| r.accrued_ci95_high_m),
        thin: false,
        points_only: false,
    });
    let title = format!("{title}: {n} replicas (at the load minimum)");
    crate::io::figures::line_chart(stem, &super::axes(&title, "cycles", "settlement (mm)", false, false), &curves)
}
