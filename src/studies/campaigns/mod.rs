//! The studies of Saussine et al. (2006) §3.2, §3.3 and §4.2, each one call
//! (`ballast saussine convergence | steps | ensemble`): many loaded runs of the
//! same sample, run side by side on a thread pool (one run per core,
//! [`StudyOptions::jobs`]), each in its own folder with the outputs of
//! `ballast run` (series, cycles, summary, checkpoints, figures), then read back
//! through the row types into one summary CSV and the study's figures.
//!
//! - [`convergence`] (§3.2): one run per policy × tolerance of the paper's table
//!   (energy 1.66e-3/-4/-5, strict 1e-3 and 1e-4, non-strict "quad" 1e-5/-6/-7);
//!   `convergence.csv` (mean NLGS iterations, wall time, interpenetration),
//!   `cumulated_interpenetration` (Fig. 2), `iterations_vs_tolerance`.
//!   The first strict tolerance is illegible in the paper's table ("1 ×"): 1e-3 is
//!   taken, a decade above its other strict value as for the other policies.
//! - [`steps`] (§3.3): one run per time step (1e-4 … 1e-3 s, ten values) × inclination
//!   (0°, 5°); `steps.csv`, `max_interpenetration_<a>deg` (Fig. 3),
//!   `mean_interpenetration_<a>deg` (Fig. 4), `interpenetration_vs_dt`.
//! - [`ensemble`] (§4.2): samples that differ only by their seed, deposited, then
//!   loaded on sublayers of stiffness k_N × 1, × 100, × 1000; `ensemble.csv` (mean,
//!   standard deviation, min and max of the settlement over the samples, per
//!   stiffness and cycle) and `settlement_ensemble` (mean ± one standard deviation).
//!
//! With `R` replicas per setting ([`super::replicas::Replicas`]; convergence
//! and steps), each setting runs from `R` starts, replica 0 the sample as it is,
//! the others perturbed; the summary CSV has one row per run (column
//! `replica`) followed by the ensemble columns of its setting (settlement after
//! the last cycle, seating, accrued: mean, sd, 95 % interval), and for §3.2 the
//! difference of its setting's mean from the reference setting's with Welch's
//! 95 % interval; the figures show the replicas' means with their 95 % bands,
//! and `settlement_ensemble` the mean settlement per cycle of each setting.
//!
//! The runner of the written scenes (`run_written`), the per-run columns and
//! the convergence summary (`convergence_summary`) are generic over the
//! engine's `cycles.csv` row (`StudyCycle`): the 3D track section's studies
//! ([`crate::studies::track3d::convergence`], [`crate::studies::track3d::settle_replicas`])
//! run on them.
//!
//! Layout: `DIR/scenes/<run>.toml` and `DIR/runs/<run>/` (`<run>` is
//! `<setting>/replica-<r>` with several replicas), each run folder with its
//! `replica.json`. A run that diverges is
//! reported in the summary (`status`) and in [`StudyReport::failed`], the others
//! go on. [`StudyOptions::resume`] skips the finished runs and resumes the
//! checkpointed ones.

mod convergence;
mod ensemble;
mod steps;

pub use convergence::{convergence, ConvergenceSpec};
pub(crate) use convergence::{convergence_summary, reference_of};
pub use ensemble::{ensemble, EnsembleRow, EnsembleSpec, Spread};
pub use steps::{steps, StepsSpec};

use super::replicas::{
    perturb_scene, settlement_ensemble, CycleSettlement, EnsembleColumns, Estimate, Perturbation, ReferenceColumns,
    Replicas, SettlementSummary, ENSEMBLE_COLUMNS, REFERENCE_COLUMNS, REPLICA_FILE,
};
use super::saussine::sample;
use super::tasks::{failures_from_folders, record, Tasks};
use super::{axes, output_error, run_scene, RunDisplay, SummaryTable};
use crate::error::{Error, Result};
use crate::io;
use crate::io::figures::{self, Series};
use crate::io::layout;
use crate::io::table::TableWriter;
use crate::plane::rows::PlaneCycleRow as CycleRow;
use crate::plane::rows::PlaneSeriesRow as SeriesRow;
use crate::run::RunReport;
use crate::run::{cores, default_threads, Prior, RunOptions};
use crate::scenarios::saussine::{loaded_scene, LoadingSpec, SampleSpec};
use crate::scene::Scene;
use crate::scene::SceneFile;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Settings shared by the studies.
#[derive(Debug, Clone)]
pub struct StudyOptions {
    /// Output directory of the study.
    pub out: PathBuf,
    /// Runs at once, each on one core (`None`: the number of cores).
    pub jobs: Option<usize>,
    /// Skip the finished runs and resume the checkpointed ones of an interrupted study.
    pub resume: bool,
    /// Wall-clock seconds between checkpoints of each run.
    pub checkpoint_every_s: f64,
    /// Which of the study's tasks this invocation runs, and whether it writes the summary (default: every
    /// task, then the summary). A study's tasks are its runs in the order of its summary (settings ×
    /// replicas; for [`ensemble`], the deposits first, then samples × stiffnesses).
    pub tasks: Tasks,
    /// Called, with [`Tasks::Share`], by a study of two stages ([`ensemble`]: the deposits, then the loaded
    /// runs that need them) once this process is done with its tasks of the first: it must return only once
    /// every process sharing the tasks is done with them too (an MPI barrier). Default: returns at once.
    pub stage_done: fn(),
}

/// A [`StudyOptions::stage_done`] that returns at once.
fn no_wait() {}

impl StudyOptions {
    /// A fresh study in `out`: every task, one run per core, checkpoints every 5 minutes.
    pub fn new(out: impl Into<PathBuf>) -> Self {
        Self {
            out: out.into(),
            jobs: None,
            resume: false,
            checkpoint_every_s: 300.0,
            tasks: Tasks::All,
            stage_done: no_wait,
        }
    }

    /// Checks the options (as every study does before its first run).
    ///
    /// # Errors
    /// [`Error::Scene`] naming `checkpoint_every_s` (negative or not finite) or `jobs` (0).
    pub fn check(&self) -> Result<()> {
        self.threads().map(drop)
    }

    /// The runs at once (the pool's threads).
    pub(super) fn threads(&self) -> Result<usize> {
        if !(self.checkpoint_every_s.is_finite() && self.checkpoint_every_s >= 0.0) {
            return Err(Error::Scene(format!(
                "checkpoint_every_s: must be non-negative, got {}",
                self.checkpoint_every_s
            )));
        }
        match self.jobs.unwrap_or_else(cores) {
            0 => Err(Error::Scene("jobs: must be at least 1".into())),
            n => Ok(n),
        }
    }
}

/// What a study wrote: its summary table (read back), where its runs are, and
/// the runs that failed (reported in the table's `status`; the others went on).
#[derive(Debug, Clone, PartialEq)]
pub struct StudyReport {
    /// The summary CSV: `convergence.csv`, `steps.csv` or `runs.csv`; `None` when the invocation ran tasks
    /// without the summary ([`StudyOptions::tasks`]).
    pub table: Option<SummaryTable>,
    /// The folder of the runs, `DIR/runs`.
    pub runs: PathBuf,
    /// `(label, error)` of each run that failed: with the summary, every failed run of the study (also those
    /// of earlier invocations, read from their folders); without it, those of this invocation.
    pub failed: Vec<(String, String)>,
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

/// Where the scene of a study's run comes from.
#[derive(Clone)]
pub(super) enum Source {
    /// The deposited sample at `sample`, loaded by [`loaded_scene`] with `spec`.
    Loaded {
        /// The loading.
        spec: Box<LoadingSpec>,
        /// The sample's scene file.
        sample: PathBuf,
    },
    /// A scene made by the study (the unperturbed start of its setting).
    Ready(Box<Scene>),
}

/// One run of a study: its label, its scene and which replica of its setting it is.
pub(super) struct Job {
    pub(super) label: String,
    pub(super) source: Source,
    pub(super) replica: u64,
    pub(super) perturbation: Perturbation,
}

impl Job {
    /// Replica 0 of the sample at `sample` loaded with `spec`.
    fn loaded(label: String, spec: LoadingSpec, sample: &Path, perturbation: Perturbation) -> Self {
        Self {
            label,
            source: Source::Loaded { spec: Box::new(spec), sample: sample.to_path_buf() },
            replica: 0,
            perturbation,
        }
    }
}

/// The runs of `settings` (replica 0 each): unchanged for one replica, else
/// `replicas.count` runs per setting labelled `<setting>/replica-<r>`, setting
/// after setting.
pub(super) fn replicate(settings: Vec<Job>, replicas: &Replicas) -> Vec<Job> {
    if replicas.count == 1 {
        return settings;
    }
    settings
        .into_iter()
        .flat_map(|job| {
            replica_labels(&job.label, replicas).into_iter().enumerate().map(move |(r, label)| Job {
                label,
                source: job.source.clone(),
                replica: r as u64,
                perturbation: replicas.perturbation,
            })
        })
        .collect()
}

/// The labels of `replicas.count` runs of the setting `label`: the label alone
/// for one replica, else `<label>/replica-<r>`.
pub(crate) fn replica_labels(label: &str, replicas: &Replicas) -> Vec<String> {
    match replicas.count {
        1 => vec![label.to_string()],
        n => (0..n).map(|r| format!("{label}/replica-{r}")).collect(),
    }
}

impl Job {
    pub(super) fn scene(&self, study: &Path) -> PathBuf {
        scene_path(study, &self.label)
    }
    pub(super) fn dir(&self, study: &Path) -> PathBuf {
        run_dir(study, &self.label)
    }
}

/// The scene of the run `label` of the study in `study`: `DIR/scenes/<label>.toml`.
pub(crate) fn scene_path(study: &Path, label: &str) -> PathBuf {
    study.join("scenes").join(format!("{label}.toml"))
}

/// The folder of the run `label` of the study in `study`: `DIR/runs/<label>`.
pub(crate) fn run_dir(study: &Path, label: &str) -> PathBuf {
    study.join("runs").join(label)
}

/// What a finished (or diverged) run left: its report, series and cycles
/// (`C`: the row of its engine's `cycles.csv`, 2D by default).
pub(crate) struct Outcome<C = CycleRow> {
    pub(super) status: String,
    pub(super) report: Option<RunReport>,
    /// `series.csv`, read by column name: the 3D engine's has the 2D one's
    /// columns with their meanings ([`crate::nscd::d3::rows`]).
    pub(super) series: Vec<SeriesRow>,
    pub(super) cycles: Vec<C>,
}

/// A row of `cycles.csv` as the studies' summaries read it: the settlement at
/// the load minimum ([`CycleSettlement`]) and averaged over the cycle.
pub(crate) trait StudyCycle: CycleSettlement + serde::de::DeserializeOwned {
    /// The settlement averaged over the cycle's steps (m, positive downwards).
    fn settlement_mean(&self) -> f64;
}

impl StudyCycle for CycleRow {
    fn settlement_mean(&self) -> f64 {
        self.settlement_mean_m
    }
}

impl StudyCycle for crate::nscd::d3::rows::CycleRow3 {
    fn settlement_mean(&self) -> f64 {
        self.settlement_mean_m
    }
}

/// The cycles of the runs `outcomes`.
pub(super) fn cycles_of<'a, C>(outcomes: &[&'a Outcome<C>]) -> Vec<&'a [C]> {
    outcomes.iter().map(|o| o.cycles.as_slice()).collect()
}

/// The ensemble columns of the replicas `outcomes` of one setting.
fn ensemble_columns<C: CycleSettlement>(outcomes: &[&Outcome<C>], seating: u64) -> EnsembleColumns {
    SettlementSummary::of(&cycles_of(outcomes), seating)
        .map_or(EnsembleColumns { replicas: outcomes.len(), ..EnsembleColumns::default() }, |s| s.columns())
}

/// Mean over the runs `outcomes` of `f` of their series rows (row by row, up to
/// the shortest run), against time, and its 95 % band (none for one run).
fn mean_curve<C>(outcomes: &[&Outcome<C>], label: String, f: fn(&SeriesRow) -> f64, scale: f64) -> Series {
    let n = outcomes.iter().map(|o| o.series.len()).min().unwrap_or(0);
    let mut series = Series { label, ..Series::default() };
    for k in 0..n {
        let values: Vec<f64> = outcomes.iter().map(|o| scale * f(&o.series[k])).collect();
        let Some(e) = Estimate::of(&values) else { continue };
        let t = outcomes[0].series[k].time_s;
        series.points.push((t, e.mean));
        if let Some((lo, hi)) = e.ci95 {
            series.band.push((t, lo, hi));
        }
    }
    series
}

/// The mean settlement per cycle of each setting (`(label, its runs)`), each
/// with its 95 % band, in `DIR/<name>` (PNG and SVG), behind them the curves
/// `behind` (e.g. every replica, thin).
pub(super) fn settlement_figure<C: CycleSettlement>(
    out: &Path,
    name: &str,
    title: &str,
    settings: &[(String, Vec<&Outcome<C>>)],
    seating: u64,
    behind: &[Series],
) -> Result<()> {
    let curves: Vec<Series> = settings
        .iter()
        .map(|(label, runs)| {
            let rows = settlement_ensemble(&cycles_of(runs), seating);
            Series {
                label: if runs.len() > 1 {
                    format!("{label} (mean of {}, 95 % CI)", runs.len())
                } else {
                    label.clone()
                },
                points: rows.iter().map(|r| (r.cycle as f64, 1e3 * r.settlement_mean_m)).collect(),
                band: rows
                    .iter()
                    .filter_map(|r| {
                        Some((r.cycle as f64, 1e3 * r.settlement_ci95_low_m?, 1e3 * r.settlement_ci95_high_m?))
                    })
                    .collect(),
                thin: false,
                points_only: false,
            }
        })
        .collect();
    let all: Vec<Series> = behind.iter().cloned().chain(curves).collect();
    figures::line_chart(
        &out.join(name),
        &axes(title, "cycles", "settlement at the load minimum (mm)", false, false),
        &all,
    )
}

pub(super) fn label_number(x: f64) -> String {
    format!("{x:e}").replace('.', "p")
}

/// A pool of `threads` threads for runs side by side.
pub(crate) fn pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new().num_threads(threads).build().map_err(|e| Error::Io(std::io::Error::other(e)))
}

/// Threads of each run on a pool of `pool` threads: one sweep thread each when
/// several go side by side, else those of a single run.
pub(crate) fn run_threads(pool: usize) -> usize {
    if pool == 1 {
        default_threads()
    } else {
        1
    }
}

/// Runs the `jobs` (task `first + j` is job `j`) that `study.tasks` selects, `study.jobs` at a time, each
/// from its scene (written first); the failed runs are added to `failed`. Then, for an invocation that
/// writes the summary, reads back the outcome of every job from its folder (`None` for one that does not).
///
/// # Errors
/// An invalid scene or checkpoint (before any run for a scene); with the summary, a job without a finished
/// run (named).
pub(super) fn run_jobs(
    jobs: &[Job],
    first: u64,
    study: &StudyOptions,
    display: &dyn RunDisplay,
    failed: &mut Vec<(String, String)>,
) -> Result<Option<Vec<Outcome>>> {
    let out = &study.out;
    study.threads()?; // the options checked before any scene is written
    let runs = |j: usize| study.tasks.runs(first + j as u64);
    for dir in ["scenes", "runs"] {
        io::create_output_dir(&out.join(dir))?;
    }
    // Every scene first, so that an invalid one stops the study before any run; written for the runs this
    // invocation makes (processes running other tasks write theirs).
    let mut samples: Vec<(PathBuf, Scene)> = Vec::new();
    for (j, job) in jobs.iter().enumerate() {
        let (mut loaded, from) = match &job.source {
            Source::Loaded { spec, sample: path } => {
                let sample = match samples.iter().find(|(p, _)| p == path) {
                    Some((_, s)) => s.clone(),
                    None => {
                        let s = Scene::load(path)?;
                        samples.push((path.clone(), s.clone()));
                        s
                    }
                };
                (loaded_scene(&sample, spec)?, format!(", from {}", path.display()))
            }
            Source::Ready(scene) => ((**scene).clone(), String::new()),
        };
        let record = perturb_scene(&mut loaded, &job.perturbation, job.replica)?;
        if !runs(j) {
            continue;
        }
        let what = format!("{} of the study in {}{from}", job.label, out.display());
        let scene = job.scene(out);
        if let Some(parent) = scene.parent() {
            io::create_output_dir(parent)?;
        }
        super::saussine::write_scene(&scene, &loaded, &what)?;
        io::create_output_dir(&job.dir(out))?;
        io::write_json(&job.dir(out).join(REPLICA_FILE), &record)?;
    }
    let labels: Vec<String> = jobs.iter().map(|j| j.label.clone()).collect();
    run_written(&labels, first, study, 0, display, failed, crate::plane::rows::read_cycles)
}

/// Runs the study's runs `labels` (task `first + j` is run `j`) that `study.tasks` selects, `study.jobs` at a
/// time, each from its scene `DIR/scenes/<label>.toml` (written by the caller) in `DIR/runs/<label>/`; the
/// failed runs are added to `failed`. Then, for an invocation that writes the summary, reads back the outcome
/// of every run from its folder (its `cycles.csv` by `read_cycles`). A VTK snapshot every `vtk_every` steps of
/// each run (0: none).
///
/// # Errors
/// An invalid scene or checkpoint; with the summary, a run without a finished run (named).
pub(crate) fn run_written<C: StudyCycle>(
    labels: &[String],
    first: u64,
    study: &StudyOptions,
    vtk_every: u64,
    display: &dyn RunDisplay,
    failed: &mut Vec<(String, String)>,
    read_cycles: fn(&Path) -> Result<Vec<C>>,
) -> Result<Option<Vec<Outcome<C>>>> {
    let out = &study.out;
    let threads = study.threads()?;
    let runs = |j: usize| study.tasks.runs(first + j as u64);
    let pool = pool(threads)?;
    let side_by_side = if study.tasks.side_by_side() { threads } else { 1 };
    let results: Vec<Result<()>> = pool.install(|| {
        labels
            .par_iter()
            .enumerate()
            .map(|(j, label)| {
                let dir = run_dir(out, label);
                // summary.json: a diverged run is finished too (and reported as such).
                let prior = Prior::of(&dir, layout::SUMMARY, study.resume);
                if !runs(j) || prior == Prior::Finished {
                    return Ok(());
                }
                let opts = RunOptions {
                    checkpoint_every_s: study.checkpoint_every_s,
                    resume: prior == Prior::Checkpointed,
                    vtk_every,
                    figures: true,
                    threads: run_threads(side_by_side),
                    ..RunOptions::default()
                };
                let result = run_scene(&scene_path(out, label), &dir, &opts, display, label).map(|_| ());
                record(&dir, &result)?;
                result
            })
            .collect()
    });
    for (label, result) in labels.iter().zip(results) {
        match result {
            Ok(()) => {}
            Err(e) if e.is_input() => return Err(e),
            // A diverged run still wrote its series and summary: kept in the study.
            Err(e) => failed.push((label.clone(), e.to_string())),
        }
    }
    if !study.tasks.summarizes() {
        return Ok(None);
    }
    // The ends recorded in the folders, whichever invocation ran each job.
    let folders: Vec<(String, PathBuf)> = labels.iter().map(|l| (l.clone(), run_dir(out, l))).collect();
    let ends = failures_from_folders(&folders)?;
    failed.clear();
    let mut outcomes = Vec::with_capacity(labels.len());
    for ((label, dir), end) in folders.into_iter().zip(ends) {
        let status = match end {
            None => "ok".to_string(),
            Some(e) => {
                failed.push((label, e.clone()));
                format!("failed: {e}")
            }
        };
        let report = std::fs::read_to_string(dir.join(layout::SUMMARY))
            .ok()
            .and_then(|t| serde_json::from_str::<RunReport>(&t).ok());
        let series = crate::plane::rows::read_series(&dir.join(layout::SERIES)).unwrap_or_default();
        let cycles_path = dir.join(layout::CYCLES);
        let cycles = if cycles_path.exists() { read_cycles(&cycles_path)? } else { vec![] };
        outcomes.push(Outcome { status, report, series, cycles });
    }
    Ok(Some(outcomes))
}

/// The columns of a study's summary CSVs that describe one run, from its report
/// and cycles (NaN where the run left nothing).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunColumns {
    /// Column `mean_iterations`: NLGS sweeps per step, mean over the run.
    pub mean_iterations: f64,
    /// Column `mean_contacts`: contacts detected per step, mean over the run.
    pub mean_contacts: f64,
    /// Column `wall_time_s`: wall-clock time spent stepping, over all invocations (s).
    pub wall_time_s: f64,
    /// Column `wall_time_per_cycle_s`: wall-clock time per loading cycle (s).
    pub wall_time_per_cycle_s: f64,
    /// Column `unconverged_steps`: steps whose NLGS hit `max_iterations` before the tolerance.
    pub unconverged_steps: u64,
    /// Column `mean_overlap_m`: mean over the steps of the mean overlap of the active
    /// contacts (m; Saussine et al. 2006, Fig. 4).
    pub mean_overlap_m: f64,
    /// Column `max_overlap_m`: largest overlap of the run (m; Saussine et al. 2006, Fig. 3).
    pub max_overlap_m: f64,
    /// Column `final_total_overlap_m`: sum of the overlaps of all contacts at the last
    /// row of `series.csv` (m), the end of the cumulated interpenetration curve (Fig. 2).
    pub final_total_overlap_m: f64,
    /// Column `cycles`: loading cycles completed (the last row of `cycles.csv`; 0 if none).
    pub cycles: u64,
    /// Column `settlement_mean_m`: the sleeper's settlement averaged over the last
    /// completed cycle (m, positive downwards; see
    /// [`crate::plane::rows::PlaneCycleRow::settlement_mean_m`]).
    pub settlement_mean_m: f64,
    /// Column `settlement_at_min_load_m`: the sleeper's settlement at the smallest load of
    /// the last completed cycle (m, positive downwards).
    pub settlement_at_min_load_m: f64,
    /// Column `status`: `ok`, or `failed: <error>` (the run's one-line error, recorded in its folder).
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

fn run_columns<C: StudyCycle>(o: &Outcome<C>) -> RunColumns {
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
        cycles: last.map_or(0, |c| c.cycle()),
        settlement_mean_m: last.map_or(nan, |c| c.settlement_mean()),
        settlement_at_min_load_m: last.map_or(nan, |c| c.settlement_at_min_load()),
        status: o.status.clone(),
    }
}

/// Writes a study table: the columns `key` then `rest`, one row per item.
pub(super) fn write_table<R: Serialize>(path: &Path, key: &[&str], rest: &[&str], rows: &[R]) -> Result<()> {
    let header: Vec<&str> = key.iter().chain(rest).copied().collect();
    let mut t = TableWriter::create(path, &header)?;
    for r in rows {
        t.write(r)?;
    }
    t.finish()
}

/// The report of a study whose summary table is `DIR/name`.
pub(super) fn report(out: &Path, name: &str, failed: Vec<(String, String)>) -> Result<StudyReport> {
    Ok(StudyReport { table: Some(SummaryTable::read(&out.join(name))?), runs: out.join("runs"), failed })
}

/// The report of an invocation that ran tasks of the study in `out` without its summary.
pub(super) fn not_summarized(out: &Path, failed: Vec<(String, String)>) -> StudyReport {
    StudyReport { table: None, runs: out.join("runs"), failed }
}
