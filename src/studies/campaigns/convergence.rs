//! Saussine et al. (2006) §3.2: the convergence study, one loaded run per policy × tolerance of the paper's
//! table (`ballast saussine convergence`).

use super::*;
use crate::scene::SceneFile;

/// §3.2: the loaded sample under each convergence policy and tolerance; `L` is
/// the loading: 2D ([`LoadingSpec`], [`convergence`]) or the 3D track section's
/// ([`crate::studies::track3d::ConvergenceSpec`], [`crate::studies::track3d::convergence`]).
#[derive(Debug, Clone, PartialEq)]
pub struct ConvergenceSpec<L = LoadingSpec> {
    /// The deposited sample (`sample.toml` of [`crate::studies::saussine::sample`]
    /// or [`crate::studies::track3d::sample`]).
    pub sample: PathBuf,
    /// The runs as `(policy, tolerance)`; empty: in 2D the paper's table
    /// ([`PAPER_POLICIES`]), in 3D an error.
    pub policies: Vec<(String, f64)>,
    /// The setting the others are compared with, `(policy, tolerance)`: in 2D one
    /// of the runs, in 3D run after them when it is not; `None`: the tightest
    /// tolerance of the `strict` policy among the runs, else the tightest
    /// tolerance of any policy (the first listed of equals).
    pub reference: Option<(String, f64)>,
    /// The replicas of each setting ([`Replicas::default`]: one, today's single run).
    pub replicas: Replicas,
    /// The loading of every run (its criterion and tolerance replaced by each run's).
    pub loading: L,
}

impl ConvergenceSpec {
    /// The runs' settings `(policy, tolerance)`: those given, else the paper's table.
    fn settings(&self) -> Vec<(String, f64)> {
        if self.policies.is_empty() {
            PAPER_POLICIES.iter().map(|&(p, t)| (p.to_string(), t)).collect()
        } else {
            self.policies.clone()
        }
    }

    /// The study's tasks (`--tasks`): the settings × the replicas.
    pub fn task_count(&self) -> u64 {
        self.settings().len() as u64 * self.replicas.count
    }
}

/// The reference setting of [`ConvergenceSpec::reference`] among `runs`: its index.
pub(crate) fn reference_of(runs: &[(String, f64)], given: Option<&(String, f64)>) -> Result<usize> {
    if let Some((p, t)) = given {
        return runs.iter().position(|(q, u)| q == p && u == t).ok_or_else(|| {
            Error::Scene(format!("reference: {p}:{t:e} is not among the runs of the policies asked for"))
        });
    }
    let tightest = |strict: bool| {
        runs.iter()
            .enumerate()
            .filter(|(_, (p, _))| !strict || p == "strict")
            .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1).then(a.0.cmp(&b.0)))
            .map(|(i, _)| i)
    };
    tightest(true).or_else(|| tightest(false)).ok_or_else(|| Error::Scene("policies: no run".into()))
}

/// §3.2 (`ballast saussine convergence`): one run per policy and tolerance,
/// labelled `<policy>_<tolerance>` (with `R` replicas, `R` runs labelled
/// `<policy>_<tolerance>/replica-<r>`, [`crate::studies::replicas`]); `convergence.csv`
/// (one row per run: the setting, `replica`, the [`RunColumns`], the
/// [`EnsembleColumns`] of its setting and the [`ReferenceColumns`] comparing its
/// setting with the reference), `cumulated_interpenetration` (Fig. 2; mean over
/// the replicas with its 95 % band), `iterations_vs_tolerance` and
/// `settlement_ensemble` (mean settlement per cycle of each setting, 95 % band).
///
/// # Errors
/// [`Error::Scene`] for an unreadable sample, an invalid loading or option
/// (before any run) or an invalid checkpoint; a run that fails is reported in
/// the table instead; an output that cannot be written is an [`Error::Io`].
pub fn convergence(spec: &ConvergenceSpec, study: &StudyOptions, display: &dyn RunDisplay) -> Result<StudyReport> {
    crate::io::figures::require()?; // the stage ends with its figures
    spec.replicas.check()?;
    let runs = spec.settings();
    let reference = reference_of(&runs, spec.reference.as_ref())?;
    let sample_path = &spec.sample;
    let sample_scene = Scene::load(sample_path)?;
    let base = spec.loading.for_sample(&sample_scene)?;
    let settings: Vec<Job> = runs
        .iter()
        .map(|(policy, tol)| {
            Job::loaded(
                format!("{policy}_{}", label_number(*tol)),
                LoadingSpec { criterion: policy.clone(), tolerance: *tol, ..base.clone() },
                sample_path,
                spec.replicas.perturbation,
            )
        })
        .collect();
    let jobs = replicate(settings, &spec.replicas);
    let mut failed = Vec::new();
    study.tasks.check(jobs.len() as u64)?;
    let Some(outcomes) = run_jobs(&jobs, 0, study, display, &mut failed)? else {
        return Ok(not_summarized(&study.out, failed));
    };
    let iterations = (base.min_iterations, base.max_iterations);
    let seating = spec.replicas.seating_cycles.min(spec.loading.cycles);
    convergence_summary(&study.out, &runs, reference, &outcomes, &spec.replicas, seating, iterations, failed)
}

/// The summary of a convergence study in `out` (2D or 3D: [`StudyCycle`]) once its runs ended: `outcomes`
/// are the runs of the settings `runs` (`(policy, tolerance)`, each `replicas.count` runs in a row), the
/// setting `reference` the one the others are compared with, `seating` the seating cycle, `iterations` the
/// runs' `(min_iterations, max_iterations)`: `convergence.csv` and the figures of [`convergence`].
///
/// # Errors
/// An output that cannot be written.
#[allow(clippy::too_many_arguments)]
pub(crate) fn convergence_summary<C: StudyCycle>(
    out: &Path,
    runs: &[(String, f64)],
    reference: usize,
    outcomes: &[Outcome<C>],
    replicas: &Replicas,
    seating: u64,
    (min_iterations, max_iterations): (usize, usize),
    failed: Vec<(String, String)>,
) -> Result<StudyReport> {
    let r = replicas.count as usize;
    let per_setting: Vec<Vec<&Outcome<C>>> = outcomes.chunks(r).map(|c| c.iter().collect()).collect();
    let summaries: Vec<Option<SettlementSummary>> =
        per_setting.iter().map(|o| SettlementSummary::of(&cycles_of(o), seating)).collect();
    let (rp, rt) = &runs[reference];
    let reference_name = format!("{rp}:{rt:e}");

    let mut rows = Vec::new();
    for (i, (policy, tol)) in runs.iter().enumerate() {
        let ensemble = ensemble_columns(&per_setting[i], seating);
        let versus = ReferenceColumns::of(&reference_name, summaries[i].as_ref(), summaries[reference].as_ref());
        for (k, o) in per_setting[i].iter().enumerate() {
            let key = (policy.clone(), *tol, min_iterations, max_iterations, k);
            rows.push((key, run_columns(o), ensemble.clone(), versus.clone()));
        }
    }
    let key = ["policy", "tolerance", "min_iterations", "max_iterations", "replica"];
    let rest: Vec<&str> = RUN_COLUMNS.iter().chain(&ENSEMBLE_COLUMNS).chain(&REFERENCE_COLUMNS).copied().collect();
    write_table(&out.join("convergence.csv"), &key, &rest, &rows)?;

    let cumulated: Vec<Series> = runs
        .iter()
        .zip(&per_setting)
        .map(|((p, t), o)| mean_curve(o, format!("{p} {t:e}"), |s| s.total_overlap_m, 1e6))
        .collect();
    figures::line_chart(
        &out.join("cumulated_interpenetration"),
        &axes("Cumulated interpenetration (sum over the contacts)", "time (s)", "cumulated overlap (µm)", false, true),
        &cumulated,
    )?;
    let mut per_policy: Vec<Series> = Vec::new();
    for ((p, t), o) in runs.iter().zip(&per_setting) {
        let values: Vec<f64> =
            o.iter().filter_map(|o| o.report.as_ref()).map(|r| r.mean_iterations.unwrap_or(f64::NAN)).collect();
        let Some(e) = Estimate::of(&values) else { continue };
        let s = match per_policy.iter_mut().find(|s| &s.label == p) {
            Some(s) => s,
            None => {
                per_policy.push(Series { label: p.clone(), ..Series::default() });
                per_policy.last_mut().expect("just pushed")
            }
        };
        s.points.push((*t, e.mean));
        if let Some((lo, hi)) = e.ci95 {
            s.band.push((*t, lo, hi));
        }
    }
    for s in &mut per_policy {
        s.points.sort_by(|a, b| a.0.total_cmp(&b.0));
        s.band.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    figures::line_chart(
        &out.join("iterations_vs_tolerance"),
        &axes("NLGS iterations per step vs tolerance", "tolerance", "mean sweeps per step", true, false),
        &per_policy,
    )?;
    let labelled: Vec<(String, Vec<&Outcome<C>>)> =
        runs.iter().zip(per_setting).map(|((p, t), o)| (format!("{p} {t:e}"), o)).collect();
    settlement_figure(
        out,
        "settlement_ensemble",
        "Settlement of the sleeper per convergence setting",
        &labelled,
        seating,
        &[],
    )?;
    report(out, "convergence.csv", failed)
}
