//! NSCD versus soft-contact MD on the same loaded 2D sample (`ballast
//! compare`): the rigid, implicit Moreau–Jean engine ([`crate::nscd`]) and the
//! explicit planar MD engine ([`crate::md::planar`]) at several contact
//! stiffnesses, each given as the overlap ratio of `[soft] max_overlap_ratio`
//! (the overlap of a base contact under the peak load over the smallest
//! inradius, [`crate::md::planar::stiffness`]), `R` replicas each from starts
//! perturbed by ≤ 1e-9 m ([`super::replicas`]).
//!
//! Replica `r` of every setting starts from the same perturbed positions
//! (common random numbers: the engines differ, the starts do not). The NSCD
//! runs keep the loaded scene's time step and solver settings; the MD runs take
//! `dt = "auto"` (a fraction of the contact time of the stiffest pair) and write
//! `series.csv` at the NSCD run's time resolution (`output.every` scaled by the
//! ratio of the steps), so every run's files have the same size per cycle.
//!
//! Outputs in `DIR` (runs in `DIR/runs/<setting>[/replica-<r>]`, their scenes
//! in `DIR/scenes/`, with `--resume` as the other studies):
//! - `compare.csv`: one row per run and cycle, [`CompareRow`];
//! - `compare.md`: the final values per setting, means over the replicas with
//!   their 95 % intervals, and each MD setting's difference from NSCD with
//!   Welch's 95 % interval ([`SettingSummary`]);
//! - `settlement_compare.png|svg`: every run's settlement per cycle (thin grey)
//!   with each setting's mean and 95 % band.
//!
//! Settlements are those at the load minimum of each cycle
//! ([`crate::plane::rows::PlaneCycleRow::settlement_at_min_load_m`]), the accrued
//! settlement is counted from the seating cycle `S` ([`Replicas::seating_cycles`]).

use super::campaigns::{
    cycles_of, label_number, not_summarized, replicate, report, run_jobs, settlement_figure, Job, Outcome, Source,
    StudyOptions, StudyReport,
};
use super::replicas::{welch, Difference, Estimate, Replicas, SettlementSummary};
use super::{write_file, RunDisplay};
use crate::error::{Error, Result};
use crate::io::figures::{self, Series};
use crate::io::table::write_all;
use crate::scenarios::saussine::loaded_scene;
use crate::scenarios::saussine::LoadingSpec;
use crate::scene::SceneFile;
use crate::scene::{Scene, SoftSection};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;
use std::path::PathBuf;

/// The default overlap ratios of the MD settings.
pub const DEFAULT_OVERLAPS: [f64; 3] = [1e-2, 1e-3, 1e-4];

/// What to compare.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareSpec {
    /// A deposited Saussine sample (`sample.toml`, loaded here with
    /// [`Self::loading`]) or a loaded 2D scene with a followed body
    /// (`[output.cycles] body`, its own loading kept; only its duration is set
    /// to [`LoadingSpec::cycles`] cycles).
    pub sample: PathBuf,
    /// The MD settings: `[soft] max_overlap_ratio` of each, in (0, 0.1].
    pub overlaps: Vec<f64>,
    /// The MD contact law: `"linear"` or `"hertz"`.
    pub model: String,
    /// `[soft] dt_fraction` of the MD runs (`None`: the engine's default).
    pub dt_fraction: Option<f64>,
    /// The replicas of each setting.
    pub replicas: Replicas,
    /// The loading of a deposited sample (its `cycles` applies to a loaded scene too).
    pub loading: LoadingSpec,
}

impl CompareSpec {
    /// The study's tasks (`--tasks`): the settings (NSCD and each overlap ratio) × the replicas.
    pub fn task_count(&self) -> u64 {
        (1 + self.overlaps.len() as u64) * self.replicas.count
    }
}

/// One row of `compare.csv`: one run (an engine, a stiffness, a replica) at
/// the end of one cycle (SI units).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareRow {
    /// Column `engine`: `nscd` or `md2d` (the planar MD engine).
    pub engine: String,
    /// Column `overlap_ratio`: the MD setting's `max_overlap_ratio`; empty for NSCD.
    pub overlap_ratio: Option<f64>,
    /// Column `replica`: 0 for the unperturbed start.
    pub replica: u64,
    /// Column `normal_stiffness_N_m`: the MD pair stiffness per metre of
    /// thickness (N/m per m for `linear`, N/m^{3/2} per m for `hertz`); empty for NSCD.
    #[serde(rename = "normal_stiffness_N_m")]
    pub normal_stiffness_n_m: Option<f64>,
    /// Column `dt_s`: the run's time step (s).
    pub dt_s: f64,
    /// Column `steps_per_cycle`: loading period over the time step.
    pub steps_per_cycle: f64,
    /// Column `cycle`: the cycle ended (1 for the first).
    pub cycle: u64,
    /// Column `settlement_m`: the followed body's settlement at the cycle's load minimum (m, positive downwards).
    pub settlement_m: f64,
    /// Column `wall_time_s`: the run's whole stepping wall-clock time (s, over
    /// all its invocations), the same on each of its rows (the one column that
    /// differs between two runs of the same study).
    pub wall_time_s: f64,
    /// Column `mean_overlap_m`: the cycle's mean overlap of the force-carrying contacts (m).
    pub mean_overlap_m: f64,
    /// Column `max_overlap_m`: the cycle's largest overlap (m).
    pub max_overlap_m: f64,
    /// Column `coordination`: at the cycle's end, neighbours pressing on each non-rattler grain.
    pub coordination: f64,
}

/// One setting of a comparison over its replicas (the values after the last
/// cycle every replica reached).
#[derive(Debug, Clone, PartialEq)]
pub struct SettingSummary {
    /// `nscd` or `md_<ratio>`.
    pub label: String,
    /// `nscd` or `md`.
    pub engine: String,
    /// The MD setting's overlap ratio.
    pub overlap_ratio: Option<f64>,
    /// The MD pair stiffness per metre of thickness.
    pub normal_stiffness: Option<f64>,
    /// Time step (s).
    pub dt_s: f64,
    /// LoadingSpec period over the time step.
    pub steps_per_cycle: f64,
    /// The settlement statistics of its replicas (`None` if one completed no cycle).
    pub settlement: Option<SettlementSummary>,
    /// Replicas that ended with an error.
    pub failed: usize,
    /// Mean over the replicas of the wall-clock time per cycle (s).
    pub wall_time_per_cycle_s: Option<Estimate>,
    /// Mean over the replicas of the run's mean overlap (m).
    pub mean_overlap_m: Option<Estimate>,
    /// Largest overlap of any replica (m).
    pub max_overlap_m: f64,
    /// Mean over the replicas of the coordination at the last cycle.
    pub coordination: Option<Estimate>,
    /// This setting's mean settlement after the last cycle minus NSCD's, Welch's 95 % interval.
    pub settlement_vs_nscd: Option<Difference>,
    /// The same for the settlement accrued after the seating.
    pub accrued_vs_nscd: Option<Difference>,
}

/// What a comparison wrote: `compare.csv` read back as text, the runs, the
/// failures, and the per-setting summary (NSCD first, then the MD settings in
/// the order given).
#[derive(Debug, Clone, PartialEq)]
pub struct CompareReport {
    /// `compare.csv`, the runs' folder and the runs that failed.
    pub study: StudyReport,
    /// One per setting; empty when the invocation ran tasks without the summary.
    pub settings: Vec<SettingSummary>,
}

/// A setting: its label, engine, overlap ratio and unperturbed scene.
struct Setting {
    label: String,
    engine: &'static str,
    ratio: Option<f64>,
    stiffness: Option<f64>,
    dt: f64,
    steps_per_cycle: f64,
    scene: Scene,
}

/// The loaded scene of `spec`: a loaded scene as it is (for `cycles` cycles),
/// or the deposited sample loaded with `spec.loading`.
fn loaded(spec: &CompareSpec) -> Result<(Scene, f64)> {
    if spec.loading.cycles == 0 {
        return Err(Error::Scene("cycles: must be at least 1".into()));
    }
    let scene = Scene::load(&spec.sample)?;
    if scene.simulation.dimension == Some(3) || (scene.simulation.engine == "md" && !scene.is_planar_md()) {
        return Err(Error::Scene(format!("sample: {} is not a 2D scene", spec.sample.display())));
    }
    let followed = scene.output.as_ref().and_then(|o| o.cycles.as_ref()).filter(|c| c.body.is_some()).cloned();
    let mut scene = match followed {
        Some(cycles) => {
            let mut s = scene;
            s.simulation.duration = spec.loading.cycles as f64 / cycles.frequency;
            s.simulation.equilibrium = None;
            s
        }
        None => loaded_scene(&scene, &spec.loading.for_sample(&scene)?)?,
    };
    scene = scene.on_engine("nscd")?;
    let frequency =
        scene.output.as_ref().and_then(|o| o.cycles.as_ref()).map(|c| c.frequency).ok_or_else(|| {
            Error::Scene(format!("sample: {} has no [output.cycles] once loaded", spec.sample.display()))
        })?;
    Ok((scene, 1.0 / frequency))
}

/// The settings of `spec`: NSCD, then MD at each overlap ratio.
fn settings(spec: &CompareSpec) -> Result<Vec<Setting>> {
    if spec.overlaps.is_empty() {
        return Err(Error::Scene("overlaps: give at least one overlap ratio".into()));
    }
    let (nscd, period) = loaded(spec)?;
    let dt = nscd.simulation.dt;
    let every = nscd.output_every();
    let mut out = vec![Setting {
        label: "nscd".into(),
        engine: "nscd",
        ratio: None,
        stiffness: None,
        dt,
        steps_per_cycle: period / dt,
        scene: nscd.clone(),
    }];
    for &ratio in &spec.overlaps {
        if out.iter().any(|s| s.ratio == Some(ratio)) {
            return Err(Error::Scene(format!("overlaps: {ratio:e} is given twice")));
        }
        let mut md = nscd.clone();
        md.soft = Some(SoftSection {
            model: Some(spec.model.clone()),
            normal_stiffness: None,
            max_overlap_ratio: Some(ratio),
            dt: None,
            dt_fraction: spec.dt_fraction,
            ..nscd.soft.clone().unwrap_or_default()
        });
        let mut md = md.on_engine("md2d").map_err(|e| match e {
            Error::Scene(m) if m.starts_with("soft.max_overlap_ratio") => {
                Error::Scene(format!("overlaps: {ratio:e}: {m}"))
            }
            Error::Scene(m) if m.starts_with("soft.model") => Error::Scene(m.replacen("soft.model", "model", 1)),
            Error::Scene(m) if m.starts_with("soft.dt_fraction") => {
                Error::Scene(m.replacen("soft.dt_fraction", "dt_fraction", 1))
            }
            e => e,
        })?;
        let (_, info) = md.build_planar()?;
        // The same time resolution of series.csv as the NSCD run's.
        let md_every = ((every as f64) * dt / info.dt_s).round().max(1.0) as u64;
        md.output.get_or_insert_with(Default::default).every = Some(md_every);
        out.push(Setting {
            label: format!("md_{}", label_number(ratio)),
            engine: "md2d",
            ratio: Some(ratio),
            stiffness: Some(info.normal_stiffness),
            dt: info.dt_s,
            steps_per_cycle: period / info.dt_s,
            scene: md,
        });
    }
    Ok(out)
}

/// `ballast compare`: the loaded sample of `spec` with NSCD and with MD at
/// each overlap ratio, `R` replicas each, side by side (module doc).
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample, an invalid option (named as the
/// command line spells it) or an MD setting whose scene is invalid, before any
/// run; a run that fails is reported in [`StudyReport::failed`] and the others
/// go on; an output that cannot be written is an [`Error::Io`].
pub fn compare(spec: &CompareSpec, study: &StudyOptions, display: &dyn RunDisplay) -> Result<CompareReport> {
    figures::require()?; // the study ends with its figure
    spec.replicas.check()?;
    let settings = settings(spec)?;
    let jobs: Vec<Job> = replicate(
        settings
            .iter()
            .map(|s| Job {
                label: s.label.clone(),
                source: Source::Ready(Box::new(s.scene.clone())),
                replica: 0,
                perturbation: spec.replicas.perturbation,
            })
            .collect(),
        &spec.replicas,
    );
    let mut failed = Vec::new();
    study.tasks.check(jobs.len() as u64)?;
    let Some(outcomes) = run_jobs(&jobs, 0, study, display, &mut failed)? else {
        return Ok(CompareReport { study: not_summarized(&study.out, failed), settings: vec![] });
    };
    let r = spec.replicas.count as usize;
    let seating = spec.replicas.seating_cycles.min(spec.loading.cycles);
    let per_setting: Vec<Vec<&Outcome>> = outcomes.chunks(r).map(|c| c.iter().collect()).collect();

    let mut rows = Vec::new();
    for (s, runs) in settings.iter().zip(&per_setting) {
        for (k, o) in runs.iter().enumerate() {
            let wall = o.report.as_ref().map_or(f64::NAN, |r| r.wall_time_s);
            rows.extend(o.cycles.iter().map(|c| CompareRow {
                engine: s.engine.into(),
                overlap_ratio: s.ratio,
                replica: k as u64,
                normal_stiffness_n_m: s.stiffness,
                dt_s: s.dt,
                steps_per_cycle: s.steps_per_cycle,
                cycle: c.cycle,
                settlement_m: c.settlement_at_min_load_m,
                wall_time_s: wall,
                mean_overlap_m: c.mean_overlap_m,
                max_overlap_m: c.max_overlap_m,
                coordination: c.coordination,
            }));
        }
    }
    let out = &study.out;
    write_all(&out.join("compare.csv"), &rows)?;

    let nscd = SettlementSummary::of(&cycles_of(&per_setting[0]), seating);
    let summaries: Vec<SettingSummary> = settings
        .iter()
        .zip(&per_setting)
        .map(|(s, runs)| {
            let settlement = SettlementSummary::of(&cycles_of(runs), seating);
            let versus = |f: fn(&SettlementSummary) -> &[f64]| match (&settlement, &nscd) {
                (Some(a), Some(b)) if s.engine == "md2d" => welch(f(a), f(b)),
                _ => None,
            };
            let reports: Vec<_> = runs.iter().filter_map(|o| o.report.as_ref()).collect();
            let estimate = |f: &dyn Fn(&crate::run::RunReport) -> Option<f64>| {
                Estimate::of(&reports.iter().filter_map(|r| f(r)).filter(|x| x.is_finite()).collect::<Vec<_>>())
            };
            SettingSummary {
                label: s.label.clone(),
                engine: s.engine.into(),
                overlap_ratio: s.ratio,
                normal_stiffness: s.stiffness,
                dt_s: s.dt,
                steps_per_cycle: s.steps_per_cycle,
                failed: runs.iter().filter(|o| o.status != "ok").count(),
                wall_time_per_cycle_s: estimate(&|r| r.wall_time_per_cycle_s),
                mean_overlap_m: estimate(&|r| Some(r.mean_overlap_m)),
                max_overlap_m: reports.iter().map(|r| r.max_overlap_m).fold(0.0, f64::max),
                coordination: Estimate::of(
                    &runs.iter().filter_map(|o| o.cycles.last()).map(|c| c.coordination).collect::<Vec<_>>(),
                ),
                settlement_vs_nscd: versus(|s| &s.settlement),
                accrued_vs_nscd: versus(|s| &s.accrued),
                settlement,
            }
        })
        .collect();
    write_file(&out.join("compare.md"), &markdown(&summaries, spec))?;

    let labelled: Vec<(String, Vec<&Outcome>)> = summaries
        .iter()
        .zip(&per_setting)
        .map(|(s, o)| {
            let mut name = match s.overlap_ratio {
                None => "NSCD".to_string(),
                Some(r) => format!("MD, overlap ratio {r:e}"),
            };
            if s.failed > 0 {
                name.push_str(&format!(", {} of {} failed", s.failed, o.len()));
            }
            (name, o.clone())
        })
        .collect();
    let replicas: Vec<Series> = if r > 1 {
        per_setting
            .iter()
            .flatten()
            .map(|o| Series {
                points: o.cycles.iter().map(|c| (c.cycle as f64, 1e3 * c.settlement_at_min_load_m)).collect(),
                thin: true,
                ..Series::default()
            })
            .collect()
    } else {
        Vec::new()
    };
    settlement_figure(
        out,
        "settlement_compare",
        "Settlement of the sleeper: NSCD and MD at each stiffness",
        &labelled,
        seating,
        &replicas,
    )?;
    Ok(CompareReport { study: report(out, "compare.csv", failed)?, settings: summaries })
}

/// `mean [low, high]` of `e` scaled by `scale`, with `digits` decimals.
fn cell(e: Option<Estimate>, scale: f64, digits: usize) -> String {
    match e {
        None => "—".into(),
        Some(e) => match e.ci95 {
            Some((lo, hi)) => format!("{:.d$} [{:.d$}, {:.d$}]", scale * e.mean, scale * lo, scale * hi, d = digits),
            None => format!("{:.d$}", scale * e.mean, d = digits),
        },
    }
}

/// `diff [low, high]` of a difference scaled by `scale`.
fn diff_cell(d: Option<Difference>, scale: f64) -> String {
    d.map_or("—".into(), |d| format!("{:+.2} [{:+.2}, {:+.2}]", scale * d.diff, scale * d.ci95.0, scale * d.ci95.1))
}

/// The table of `compare.md`.
fn markdown(settings: &[SettingSummary], spec: &CompareSpec) -> String {
    let mut t = String::new();
    let n = settings.iter().filter_map(|s| s.settlement.as_ref()).map(|s| s.cycle).min().unwrap_or(0);
    let s = settings.iter().filter_map(|s| s.settlement.as_ref()).map(|s| s.seating_cycle).min().unwrap_or(0);
    let _ = writeln!(
        t,
        "# NSCD versus MD on {}\n\n{} replica(s) per setting from starts perturbed by ≤ {:e} m (seed {}); \
         settlement at the load minimum after N = {n} cycles, accrued after the seating cycle S = {s}; \
         means with their 95 % intervals; MD − NSCD with Welch's 95 % interval. MD law: {}.\n",
        spec.sample.display(),
        spec.replicas.count,
        spec.replicas.perturbation.distance_m,
        spec.replicas.perturbation.seed,
        spec.model,
    );
    t.push_str(
        "| setting | k_n (N/m per m) | dt (s) | steps/cycle | settlement (mm) | accrued (mm) | MD − NSCD settlement (mm) \
         | MD − NSCD accrued (mm) | wall/cycle (s) | mean overlap (µm) | max overlap (µm) | coordination | failed |\n",
    );
    t.push_str("|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for x in settings {
        let est = |f: fn(&SettlementSummary) -> &[f64]| x.settlement.as_ref().and_then(|s| Estimate::of(f(s)));
        let _ = writeln!(
            t,
            "| {} | {} | {:.3e} | {:.0} | {} | {} | {} | {} | {} | {} | {:.1} | {} | {} |",
            x.label,
            x.normal_stiffness.map_or("rigid".into(), |k| format!("{k:.3e}")),
            x.dt_s,
            x.steps_per_cycle,
            cell(est(|s| &s.settlement), 1e3, 3),
            cell(est(|s| &s.accrued), 1e3, 3),
            diff_cell(x.settlement_vs_nscd, 1e3),
            diff_cell(x.accrued_vs_nscd, 1e3),
            cell(x.wall_time_per_cycle_s, 1.0, 3),
            cell(x.mean_overlap_m, 1e6, 2),
            1e6 * x.max_overlap_m,
            cell(x.coordination, 1.0, 2),
            x.failed,
        );
    }
    t
}
