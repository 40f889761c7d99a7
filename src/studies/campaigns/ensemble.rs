//! Saussine et al. (2006) §4.2: the ensemble, samples × sublayer stiffness factors, each loaded for the
//! same cycles (`ballast saussine ensemble`).

use super::*;
use crate::scene::SceneFile;

/// Statistics over the samples of an ensemble.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// Arithmetic mean (unit of the values).
    pub mean: f64,
    /// Sample standard deviation, divisor `n − 1` (unit of the values; 0 for one value).
    pub std: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

impl Spread {
    /// Mean, sample standard deviation (0 for one value), min and max of `xs` (not empty).
    pub fn of(xs: &[f64]) -> Self {
        let e = crate::studies::replicas::Estimate::of(xs);
        Self {
            mean: e.map_or(f64::NAN, |e| e.mean),
            std: e.and_then(|e| e.sd).unwrap_or(0.0),
            min: xs.iter().copied().fold(f64::INFINITY, f64::min),
            max: xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        }
    }
}

/// §4.2: samples that differ only by their seed, each on sublayers of several stiffnesses.
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleSpec {
    /// Number of samples, of seeds `first_seed`, `first_seed + 1`, ….
    pub samples: u64,
    /// Seed of the first sample.
    pub first_seed: u64,
    /// Factors on the sublayer stiffness k_N.
    pub factors: Vec<f64>,
    /// Scale the grading to about this many grains (and the width with it).
    pub grains: Option<usize>,
    /// Time step of the deposits (s).
    pub sample_dt: f64,
    /// The loading of every run (its stiffness factor replaced by each run's).
    pub loading: LoadingSpec,
}

impl EnsembleSpec {
    /// The study's tasks (`--tasks`): the deposits (tasks `0..samples`, seed after seed), then every sample on
    /// every sublayer (tasks `samples..`, seed-major, factor-minor), which need the deposits finished.
    pub fn task_count(&self) -> u64 {
        self.samples * (1 + self.factors.len() as u64)
    }
}

/// §4.2 (`ballast saussine ensemble`): the samples deposited side by side in
/// `DIR/samples/seed_<seed>/` ([`crate::studies::saussine::sample`], each told to
/// [`RunDisplay::sample`]), then one run per sample and stiffness, labelled
/// `seed_<seed>_k_<factor>`; `runs.csv`, `ensemble.csv` (mean, standard
/// deviation, min and max of the settlement over the samples, per stiffness and
/// cycle) and `settlement_ensemble`.
///
/// # Errors
/// As [`convergence`]; no sample or a stiffness factor that is not positive is
/// an [`Error::Scene`], and so is an invalid loading or option, before any
/// deposit. A deposit that fails stops the study. With [`StudyOptions::tasks`], the deposits are tasks
/// `0..samples` and the loaded runs the next ones ([`EnsembleSpec::task_count`]); a [`Tasks::Share`]
/// invocation calls [`StudyOptions::stage_done`] between the two stages, and a loaded run asked for while a
/// sample is not deposited is an [`Error::Scene`] naming the deposit's task.
pub fn ensemble(spec: &EnsembleSpec, study: &StudyOptions, display: &dyn RunDisplay) -> Result<StudyReport> {
    crate::io::figures::require()?; // the stage ends with its figures
    let factors = &spec.factors;
    if spec.samples == 0 {
        return Err(Error::Scene("samples: must be at least 1".into()));
    }
    if let Some(f) = factors.iter().find(|f| !(f.is_finite() && **f > 0.0)) {
        return Err(Error::Scene(format!("factors: every stiffness factor must be positive, got {f}")));
    }
    // The loading and the options are checked before the deposits.
    let loadings: Vec<LoadingSpec> =
        factors.iter().map(|&k| LoadingSpec { stiffness_factor: k, ..spec.loading.clone() }).collect();
    for loading in &loadings {
        loading.check()?;
    }
    let threads = study.threads()?;
    study.tasks.check(spec.task_count())?;
    let out = &study.out;
    let seeds: Vec<u64> = (0..spec.samples).map(|k| spec.first_seed + k).collect();
    // 1. The samples, deposited side by side (tasks 0..samples).
    let pool = pool(threads)?;
    let side_by_side = if study.tasks.side_by_side() { threads } else { 1 };
    let deposited: Vec<Result<()>> = pool.install(|| {
        seeds
            .par_iter()
            .enumerate()
            .filter(|(i, _)| study.tasks.runs(*i as u64))
            .map(|(_, &seed)| {
                let mut sample_spec = SampleSpec { dt: spec.sample_dt, ..SampleSpec::saussine(seed) };
                if let Some(n) = spec.grains {
                    sample_spec = sample_spec.scaled(n);
                }
                let dir = out.join("samples").join(format!("seed_{seed}"));
                if study.resume && dir.join("sample.toml").exists() {
                    return Ok(());
                }
                let s = sample(&sample_spec, &dir, study.resume, run_threads(side_by_side), display)?;
                display.sample(&s);
                Ok(())
            })
            .collect()
    });
    deposited.into_iter().collect::<Result<Vec<()>>>()?;
    if let Tasks::Share { .. } = study.tasks {
        (study.stage_done)(); // every sharing process, and only they, meet here
    }
    let loads = spec.samples..spec.task_count();
    if !loads.clone().any(|k| study.tasks.runs(k)) && !study.tasks.summarizes() {
        return Ok(not_summarized(out, Vec::new()));
    }
    // 2. Every sample on every sublayer (tasks samples..).
    let mut jobs = Vec::new();
    let mut keys = Vec::new();
    for (i, &seed) in seeds.iter().enumerate() {
        let sample_path = out.join("samples").join(format!("seed_{seed}")).join("sample.toml");
        if !sample_path.is_file() {
            return Err(Error::Scene(format!(
                "task: the loaded runs need every sample deposited first: seed_{seed} is not (task {i}; \
                 deposits are tasks 0 to {})",
                spec.samples - 1
            )));
        }
        let sample_scene = Scene::load(&sample_path).map_err(output_error)?;
        for (&k, loading) in factors.iter().zip(&loadings) {
            jobs.push(Job::loaded(
                format!("seed_{seed}_k_{}", label_number(k)),
                loading.for_sample(&sample_scene)?,
                &sample_path,
                Perturbation::default(),
            ));
            keys.push((seed, k));
        }
    }
    let mut failed = Vec::new();
    let Some(outcomes) = run_jobs(&jobs, spec.samples, study, display, &mut failed)? else {
        return Ok(not_summarized(out, failed));
    };
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
        curves.push(Series {
            label: format!("k_N × {k} ({} samples, mean ± 1 sd)", runs.len()),
            points,
            band,
            thin: false,
            points_only: false,
        });
    }
    io::table::write_all(&out.join("ensemble.csv"), &table)?;
    figures::line_chart(
        &out.join("settlement_ensemble"),
        &axes("Settlement of the sleeper vs sublayer stiffness", "cycles", "settlement (mm)", false, false),
        &curves,
    )?;
    report(out, "runs.csv", failed)
}

/// One row of `ensemble.csv`: the settlement over the samples of one sublayer
/// stiffness at one cycle (m).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EnsembleRow {
    /// Column `stiffness_factor`: the factor on the sublayer's `k_N` (dimensionless).
    pub stiffness_factor: f64,
    /// Column `cycle`: the loading cycle (1 for the first).
    pub cycle: u64,
    /// Column `samples`: the samples averaged, all those of this stiffness (the
    /// table stops at the last cycle every one of their runs reached).
    pub samples: usize,
    /// Column `settlement_mean_m`: mean over the samples of the cycle's mean settlement (m).
    pub settlement_mean_m: f64,
    /// Column `settlement_std_m`: its sample standard deviation over the samples (m).
    pub settlement_std_m: f64,
    /// Column `settlement_min_m`: its smallest value over the samples (m).
    pub settlement_min_m: f64,
    /// Column `settlement_max_m`: its largest value over the samples (m).
    pub settlement_max_m: f64,
    /// Column `settlement_at_min_load_mean_m`: mean over the samples of the settlement at
    /// the cycle's smallest load (m).
    pub settlement_at_min_load_mean_m: f64,
    /// Column `settlement_at_min_load_std_m`: its sample standard deviation over the samples (m).
    pub settlement_at_min_load_std_m: f64,
}
