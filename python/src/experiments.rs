//! The papers' experiments for the Python package (`ballast.saussine`, `ballast.karrech`, `ballast.luding`,
//! `ballast.ensemble`, written in Python over these functions): the scenes of `ballast::scenarios` built as
//! values, the studies of `ballast::studies` run into their folders, the replicas of a settlement run as tasks
//! for any executor (`ballast::studies::replica_tasks`), and the tables the runs write read back as numpy
//! arrays.

use crate::errors::to_py;
use ballast_core::scenarios::saussine::{loaded_scene, Guide, LoadingSpec, SampleSpec};
use ballast_core::scene::{Scene, SceneFile};
use ballast_core::studies::campaigns::{convergence, ConvergenceSpec, StudyOptions, StudyReport};
use ballast_core::studies::compare::CompareSpec;
use ballast_core::studies::replicas::{Perturbation, Replicas};
use ballast_core::studies::saussine::SettleOptions;
use ballast_core::studies::tasks::Tasks;
use ballast_core::studies::{replica_tasks, Quiet};
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// The keyword arguments of `ballast.saussine.load` (the fields of `LoadingSpec`, SI units; `inclination` in
/// degrees), each optional: the paper's value when absent.
#[derive(serde::Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct LoadingArgs {
    cycles: Option<u64>,
    sleeper_width: Option<f64>,
    sleeper_height: Option<f64>,
    sleeper_density: Option<f64>,
    bar_size: Option<f64>,
    bars: Option<usize>,
    mean: Option<f64>,
    amplitude: Option<f64>,
    frequency: Option<f64>,
    phase: Option<f64>,
    inclination: Option<f64>,
    guide: Option<String>,
    stiffness_factor: Option<f64>,
    dt: Option<f64>,
    criterion: Option<String>,
    tolerance: Option<f64>,
    min_iterations: Option<usize>,
    max_iterations: Option<usize>,
    output_every: Option<u64>,
}

/// A `SceneError` whose message leads with the key.
fn scene_error(message: String) -> PyErr {
    to_py(ballast_core::Error::Scene(message))
}

/// The loading of the keyword arguments `args` (a dict, or none): `LoadingSpec::default()` (the paper's, 100
/// cycles) with the given fields replaced.
fn loading(py: Python<'_>, args: Option<&Bound<'_, PyDict>>) -> PyResult<LoadingSpec> {
    let given: LoadingArgs = match args {
        Some(d) => {
            let text: String = py.import("json")?.call_method1("dumps", (d,))?.extract()?;
            serde_json::from_str(&text).map_err(|e| {
                let e = e.to_string();
                // serde: "unknown field `x`, expected one of …": lead with the argument.
                let key = e.split('`').nth(1).unwrap_or("loading").to_string();
                scene_error(format!("{key}: {}", e.replace('\n', " ")))
            })?
        }
        None => LoadingArgs::default(),
    };
    let d = LoadingSpec::default();
    let guide = given.guide.as_deref().map(Guide::from_name).transpose().map_err(to_py)?;
    Ok(LoadingSpec {
        cycles: given.cycles.unwrap_or(d.cycles),
        sleeper_width: given.sleeper_width.or(d.sleeper_width),
        sleeper_height: given.sleeper_height.unwrap_or(d.sleeper_height),
        sleeper_density: given.sleeper_density.unwrap_or(d.sleeper_density),
        bar_size: given.bar_size.unwrap_or(d.bar_size),
        bars: given.bars.unwrap_or(d.bars),
        mean: given.mean.unwrap_or(d.mean),
        amplitude: given.amplitude.unwrap_or(d.amplitude),
        frequency: given.frequency.unwrap_or(d.frequency),
        phase: given.phase.unwrap_or(d.phase),
        inclination_deg: given.inclination.unwrap_or(d.inclination_deg),
        guide,
        stiffness_factor: given.stiffness_factor.unwrap_or(d.stiffness_factor),
        dt: given.dt.unwrap_or(d.dt),
        criterion: given.criterion.unwrap_or(d.criterion),
        tolerance: given.tolerance.unwrap_or(d.tolerance),
        min_iterations: given.min_iterations.unwrap_or(d.min_iterations),
        max_iterations: given.max_iterations.unwrap_or(d.max_iterations),
        output_every: given.output_every.unwrap_or(d.output_every),
    })
}

/// The loaded scene of the sample whose TOML text is `sample` (read as `name`) under the loading `args`.
fn loaded(py: Python<'_>, sample: &str, name: &str, args: Option<&Bound<'_, PyDict>>) -> PyResult<Scene> {
    let scene = Scene::from_toml_str_named(sample, name).map_err(to_py)?;
    let spec = loading(py, args)?.for_sample(&scene).map_err(to_py)?;
    loaded_scene(&scene, &spec).map_err(to_py)
}

/// Deposits a Saussine sample into `out` (the study `ballast saussine sample`); the path of `sample.toml`.
#[pyfunction]
#[pyo3(signature = (out, grains = None, seed = 1, dt = None, bank = false, resume = false, threads = None))]
#[allow(clippy::too_many_arguments)]
pub fn saussine_sample(
    py: Python<'_>,
    out: PathBuf,
    grains: Option<usize>,
    seed: u64,
    dt: Option<f64>,
    bank: bool,
    resume: bool,
    threads: Option<usize>,
) -> PyResult<String> {
    let mut spec = SampleSpec::saussine(seed);
    if let Some(n) = grains {
        spec = spec.scaled(n);
    }
    spec.dt = dt.unwrap_or(spec.dt);
    spec.bank = bank;
    let threads = threads.unwrap_or_else(ballast_core::run::default_threads);
    let sample = py.detach(|| ballast_core::studies::saussine::sample(&spec, &out, resume, threads, &Quiet));
    Ok(sample.map_err(to_py)?.path.display().to_string())
}

/// The TOML text of the loaded scene of a sample (its text `sample`, read as `name`) under `loading`.
#[pyfunction]
#[pyo3(signature = (sample, name, loading = None))]
pub fn saussine_loaded(
    py: Python<'_>,
    sample: &str,
    name: &str,
    loading: Option<Bound<'_, PyDict>>,
) -> PyResult<String> {
    loaded(py, sample, name, loading.as_ref())?.to_toml_string().map_err(to_py)
}

/// Runs the Karrech deposit study into `out` (`ballast karrech deposit`); the path of the deposited state
/// (`final_scene.toml`).
#[pyfunction]
#[pyo3(signature = (out, spheres, seed, dt, duration, young, every, resume, threads))]
#[allow(clippy::too_many_arguments)]
pub fn karrech_deposit(
    py: Python<'_>,
    out: PathBuf,
    spheres: usize,
    seed: u64,
    dt: f64,
    duration: f64,
    young: f64,
    every: u64,
    resume: bool,
    threads: Option<usize>,
) -> PyResult<String> {
    use ballast_core::studies::karrech::{deposit, Deposit};
    use ballast_core::studies::md_stage::Stage;
    let mut stage = Stage::new(&out);
    stage.every = every;
    stage.run.resume = resume;
    stage.run.threads = threads.unwrap_or(stage.run.threads);
    let spec = Deposit { spheres, seed, dt, duration, young };
    py.detach(|| deposit(&spec, &stage, &Quiet)).map_err(to_py)?;
    Ok(out.join("final_scene.toml").display().to_string())
}

/// The TOML text of the Luding box's isotropic compression (`ballast luding compress`'s scene).
#[pyfunction]
pub fn luding_box(spheres: usize, friction: f64, seed: u64, duration: f64, every: u64) -> PyResult<String> {
    use ballast_core::scenarios::luding::{compression_scene, LudingSpec};
    let spec = LudingSpec::paper(spheres, friction, seed);
    compression_scene(&spec, duration, every).and_then(|s| s.to_toml_string()).map_err(to_py)
}

/// Writes the replicas' starts into `out` (`ballast saussine settle --replicas`): of the sample whose text is
/// `sample` loaded under `loading`, or of a cyclic 2D scene as it is; the replica count and the ensemble's
/// seating cycle.
#[pyfunction]
#[pyo3(signature = (
    sample, name, out, replicas, perturbation, perturbation_seed, seating_cycles, resume, loading = None
))]
#[allow(clippy::too_many_arguments)]
pub fn replica_starts(
    py: Python<'_>,
    sample: &str,
    name: &str,
    out: PathBuf,
    replicas: u64,
    perturbation: f64,
    perturbation_seed: u64,
    seating_cycles: u64,
    resume: bool,
    loading: Option<Bound<'_, PyDict>>,
) -> PyResult<(u64, u64)> {
    // A cyclic scene (with `[output] cycles`: a sample loaded already, any scene under a cyclic load) is
    // replicated as it is; a sample is loaded first.
    let scene = Scene::from_toml_str_named(sample, name).map_err(to_py)?;
    let cyclic = scene.plan().map_err(to_py)?.cycles.is_some();
    let scene = match (cyclic, &loading) {
        (false, _) => loaded(py, sample, name, loading.as_ref())?,
        (true, Some(d)) if !d.is_empty() => {
            return Err(scene_error(format!(
                "loading: {name} is a cyclic scene already (it has [output] cycles); the loading arguments are for \
                 a deposited sample"
            )))
        }
        (true, _) => scene,
    };
    let replicas = self::replicas((replicas, perturbation, perturbation_seed, seating_cycles));
    let tasks =
        replica_tasks::write_starts(&scene, name.as_ref(), &out, &replicas, resume, Tasks::All).map_err(to_py)?;
    Ok((tasks.count, tasks.seating))
}

/// Runs replica `r` of the study in `out` from its folder; `None`, or the one-line error of a run that failed
/// (an invalid start or checkpoint raises).
#[pyfunction]
#[pyo3(signature = (out, r, threads = 1, resume = false, checkpoint_every = 300.0, snapshot_every = 0))]
pub fn replica_run(
    py: Python<'_>,
    out: PathBuf,
    r: u64,
    threads: usize,
    resume: bool,
    checkpoint_every: f64,
    snapshot_every: u64,
) -> PyResult<Option<String>> {
    let opts = SettleOptions { snapshot_every, checkpoint_every_s: checkpoint_every, resume, tasks: Tasks::All };
    match py.detach(|| replica_tasks::run_replica(&out, r, &opts, threads, &Quiet)) {
        Ok(()) => Ok(None),
        Err(e) if e.is_input() => Err(to_py(e)),
        Err(e) => Ok(Some(e.one_line())),
    }
}

/// The ensemble of the replicas in `out` (`failures[r]`: replica `r`'s error, or `None`): writes
/// `settlement_ensemble.csv` and its figure; the table's path and the failed replicas as `(label, error)`.
#[pyfunction]
pub fn replica_finish(
    out: PathBuf,
    failures: Vec<Option<String>>,
    seating: u64,
) -> PyResult<(String, Vec<(String, String)>)> {
    let done = replica_tasks::finish(&out, &failures, seating).map_err(to_py)?;
    Ok((done.table.display().to_string(), done.failed))
}

/// A CSV table the runs and studies write (`series.csv`, `cycles.csv`, `settlement_ensemble.csv`, …) as a dict
/// of its columns, in order: int64 arrays for columns of integers, float64 arrays for numbers (empty cells are
/// NaN), lists of str otherwise.
#[pyfunction]
pub fn table<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let t = ballast_core::studies::SummaryTable::read(&path).map_err(to_py)?;
    let d = PyDict::new(py);
    for (j, name) in t.header.iter().enumerate() {
        let cells: Vec<&str> = t.rows.iter().map(|r| r.get(j).map_or("", String::as_str)).collect();
        if let Some(ints) = cells.iter().map(|c| c.parse::<i64>().ok()).collect::<Option<Vec<i64>>>() {
            d.set_item(name, PyArray1::from_vec(py, ints))?;
        } else if let Some(xs) = cells
            .iter()
            .map(|c| if c.is_empty() { Some(f64::NAN) } else { c.parse::<f64>().ok() })
            .collect::<Option<Vec<f64>>>()
        {
            d.set_item(name, PyArray1::from_vec(py, xs))?;
        } else {
            d.set_item(name, cells)?;
        }
    }
    Ok(d)
}

/// The replicas of a study's settings: `(count, perturbation distance (m), perturbation seed, seating cycles)`.
fn replicas((count, distance_m, seed, seating_cycles): (u64, f64, u64, u64)) -> Replicas {
    Replicas { count, perturbation: Perturbation { distance_m, seed }, seating_cycles }
}

/// Runs a study (`run`, with the interpreter's lock released) into `out` on the local pool, `jobs` runs at a
/// time: the path of its summary table and its failed runs as `(label, error)`.
fn run_study(
    py: Python<'_>,
    (out, jobs, resume, checkpoint_every): (PathBuf, Option<usize>, bool, f64),
    run: impl FnOnce(&StudyOptions) -> ballast_core::Result<StudyReport> + Send,
) -> PyResult<(String, Vec<(String, String)>)> {
    let study = StudyOptions { jobs, resume, checkpoint_every_s: checkpoint_every, ..StudyOptions::new(out) };
    let report = py.detach(|| run(&study)).map_err(to_py)?;
    // Every task runs here (StudyOptions::new), so the summary is written.
    let table = report.table.ok_or_else(|| pyo3::exceptions::PyRuntimeError::new_err("the study wrote no summary"))?;
    Ok((table.path.display().to_string(), report.failed))
}

/// Saussine §3.2 (`ballast saussine convergence`) into `out`; the path of `convergence.csv` and the failed
/// runs as `(label, error)`.
#[pyfunction]
#[pyo3(signature = (sample, out, policies, reference, replicas, jobs, resume, checkpoint_every, loading = None))]
#[allow(clippy::too_many_arguments)]
pub fn saussine_convergence(
    py: Python<'_>,
    sample: PathBuf,
    out: PathBuf,
    policies: Vec<(String, f64)>,
    reference: Option<(String, f64)>,
    replicas: (u64, f64, u64, u64),
    jobs: Option<usize>,
    resume: bool,
    checkpoint_every: f64,
    loading: Option<Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<(String, String)>)> {
    let spec = ConvergenceSpec {
        sample,
        policies,
        reference,
        replicas: self::replicas(replicas),
        loading: self::loading(py, loading.as_ref())?,
    };
    run_study(py, (out, jobs, resume, checkpoint_every), |study| convergence(&spec, study, &Quiet))
}

/// `ballast compare` (the loaded sample on NSCD and on planar MD at each overlap ratio) into `out`; the path of
/// `compare.csv` and the failed runs as `(label, error)`.
#[pyfunction]
#[pyo3(signature = (
    sample, out, overlaps, model, dt_fraction, replicas, jobs, resume, checkpoint_every, loading = None
))]
#[allow(clippy::too_many_arguments)]
pub fn compare(
    py: Python<'_>,
    sample: PathBuf,
    out: PathBuf,
    overlaps: Vec<f64>,
    model: String,
    dt_fraction: Option<f64>,
    replicas: (u64, f64, u64, u64),
    jobs: Option<usize>,
    resume: bool,
    checkpoint_every: f64,
    loading: Option<Bound<'_, PyDict>>,
) -> PyResult<(String, Vec<(String, String)>)> {
    let spec = CompareSpec {
        sample,
        overlaps,
        model,
        dt_fraction,
        replicas: self::replicas(replicas),
        loading: self::loading(py, loading.as_ref())?,
    };
    let run = |study: &StudyOptions| ballast_core::studies::compare::compare(&spec, study, &Quiet).map(|r| r.study);
    run_study(py, (out, jobs, resume, checkpoint_every), run)
}
