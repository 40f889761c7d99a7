//! Saussine et al. (2006) §3.3: the time-step study, one loaded run per time step and load inclination
//! (`ballast saussine steps`).

use super::*;
use crate::scene::SceneFile;

/// §3.3: the loaded sample with each time step, at each inclination.
#[derive(Debug, Clone, PartialEq)]
pub struct StepsSpec {
    /// The deposited sample (`sample.toml` of [`crate::studies::saussine::sample`]).
    pub sample: PathBuf,
    /// Time steps (s).
    pub dts: Vec<f64>,
    /// Inclinations of the load (degrees).
    pub inclinations: Vec<f64>,
    /// The replicas of each setting ([`Replicas::default`]: one, today's single run).
    pub replicas: Replicas,
    /// The loading of every run (its time step and inclination replaced by each run's).
    pub loading: LoadingSpec,
}

impl StepsSpec {
    /// The study's tasks (`--tasks`): inclinations × time steps × replicas.
    pub fn task_count(&self) -> u64 {
        (self.inclinations.len() * self.dts.len()) as u64 * self.replicas.count
    }
}

/// §3.3 (`ballast saussine steps`): one run per inclination and time step,
/// labelled `incl_<a>_dt_<dt>` (with `R` replicas, `R` runs labelled
/// `incl_<a>_dt_<dt>/replica-<r>`, [`crate::studies::replicas`]); `steps.csv` (one row
/// per run: the setting, `replica`, the [`RunColumns`] and the
/// [`EnsembleColumns`] of its setting), `max_interpenetration_<a>deg`,
/// `mean_interpenetration_<a>deg` (means over the replicas with their 95 %
/// bands), `interpenetration_vs_dt` and `settlement_ensemble` (mean settlement
/// per cycle of each setting, 95 % band).
///
/// # Errors
/// As [`convergence`]; a time step that is not positive is an [`Error::Scene`].
pub fn steps(spec: &StepsSpec, study: &StudyOptions, display: &dyn RunDisplay) -> Result<StudyReport> {
    crate::io::figures::require()?; // the stage ends with its figures
    spec.replicas.check()?;
    let (dts, inclinations) = (&spec.dts, &spec.inclinations);
    if let Some(dt) = dts.iter().find(|dt| !(dt.is_finite() && **dt > 0.0)) {
        return Err(Error::Scene(format!("dts: every time step must be positive, got {dt}")));
    }
    let sample_path = &spec.sample;
    let sample_scene = Scene::load(sample_path)?;
    let mut settings = Vec::new();
    let mut keys = Vec::new();
    for &a in inclinations {
        let base = LoadingSpec { inclination_deg: a, ..spec.loading.clone() }.for_sample(&sample_scene)?;
        for &dt in dts {
            settings.push(Job::loaded(
                format!("incl_{}_dt_{}", label_number(a), label_number(dt)),
                LoadingSpec { dt, ..base.clone() },
                sample_path,
                spec.replicas.perturbation,
            ));
            keys.push((a, dt));
        }
    }
    let jobs = replicate(settings, &spec.replicas);
    let mut failed = Vec::new();
    study.tasks.check(jobs.len() as u64)?;
    let Some(outcomes) = run_jobs(&jobs, 0, study, display, &mut failed)? else {
        return Ok(not_summarized(&study.out, failed));
    };
    let r = spec.replicas.count as usize;
    let seating = spec.replicas.seating_cycles.min(spec.loading.cycles);
    let per_setting: Vec<Vec<&Outcome>> = outcomes.chunks(r).map(|c| c.iter().collect()).collect();
    let out = &study.out;
    let mut rows = Vec::new();
    for (&(a, dt), runs) in keys.iter().zip(&per_setting) {
        let ensemble = ensemble_columns(runs, seating);
        for (k, o) in runs.iter().enumerate() {
            rows.push(((a, dt, k), run_columns(o), ensemble.clone()));
        }
    }
    let rest: Vec<&str> = RUN_COLUMNS.iter().chain(&ENSEMBLE_COLUMNS).copied().collect();
    write_table(&out.join("steps.csv"), &["inclination_deg", "dt_s", "replica"], &rest, &rows)?;
    let mut vs_dt = Vec::new();
    for &a in inclinations {
        let runs: Vec<_> = keys.iter().zip(&per_setting).filter(|((b, _), _)| *b == a).collect();
        let tag = format!("{a}").replace('.', "p").replace('-', "m");
        for (name, what, f) in [
            ("max", "Maximal", (|s: &SeriesRow| s.max_overlap_m) as fn(&SeriesRow) -> f64),
            ("mean", "Average", |s: &SeriesRow| s.mean_overlap_m),
        ] {
            let curves: Vec<Series> =
                runs.iter().map(|((_, dt), o)| mean_curve(o, format!("dt = {dt:e} s"), f, 1e6)).collect();
            figures::line_chart(
                &out.join(format!("{name}_interpenetration_{tag}deg")),
                &axes(&format!("{what} interpenetration, load at {a}°"), "time (s)", "overlap (µm)", false, false),
                &curves,
            )?;
        }
        for (name, f) in [
            ("mean", (|r: &RunReport| r.mean_overlap_m) as fn(&RunReport) -> f64),
            ("max", |r: &RunReport| r.max_overlap_m),
        ] {
            let mut series = Series { label: format!("{name}, {a}°"), ..Series::default() };
            for ((_, dt), o) in &runs {
                let values: Vec<f64> = o.iter().filter_map(|o| o.report.as_ref().map(|r| 1e6 * f(r))).collect();
                let Some(e) = Estimate::of(&values) else { continue };
                series.points.push((*dt, e.mean));
                if let Some((lo, hi)) = e.ci95 {
                    series.band.push((*dt, lo, hi));
                }
            }
            vs_dt.push(series);
        }
    }
    figures::line_chart(
        &out.join("interpenetration_vs_dt"),
        &axes("Interpenetration over the run vs time step", "dt (s)", "overlap (µm)", true, true),
        &vs_dt,
    )?;
    let labelled: Vec<(String, Vec<&Outcome>)> =
        keys.iter().zip(per_setting).map(|((a, dt), o)| (format!("{a}°, dt = {dt:e} s"), o)).collect();
    settlement_figure(
        out,
        "settlement_ensemble",
        "Settlement of the sleeper per time step and inclination",
        &labelled,
        seating,
        &[],
    )?;
    report(out, "steps.csv", failed)
}
