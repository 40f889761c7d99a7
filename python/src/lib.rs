//! The extension module of the Python package `ballast` (`ballast._ballast`): scene files opened on their
//! engine (`load`, `from_toml`) as a `Simulation` that steps, runs through the run loop and the
//! settlement driver and exposes its state as numpy arrays; the experiments' building blocks
//! (`experiments`: scenarios, studies, replica tasks, tables); the library's errors as Python exceptions
//! (`errors`). SI units throughout (m, s, kg, rad, N). The package's Python code (python/ballast/) builds
//! `ballast.saussine`, `ballast.karrech`, `ballast.luding` and `ballast.ensemble` on these.
//!
//! The binding holds the library's own values (`ballast::open::Loaded`); stepping runs the engines' code with
//! the interpreter's lock released.

mod errors;
mod experiments;
mod running;
mod settle;
mod simulation;

use pyo3::prelude::*;
use simulation::Simulation;
use std::path::PathBuf;

/// Opens the scene file at `path` on its engine (`[simulation] engine`: `nscd`, `md2d` or `md`), or on `engine`
/// if given (a 2D scene runs on `nscd` or `md2d`).
///
/// Raises `FileNotFoundError` for a missing file and `SceneError` (whose `key` names the scene key) for an
/// invalid scene.
#[pyfunction]
#[pyo3(signature = (path, engine = None))]
fn load(path: PathBuf, engine: Option<String>) -> PyResult<Simulation> {
    Simulation::open(|opts| ballast_core::open::open(&path, opts), engine)
}

/// Opens a scene given as TOML `text` (as `load` does a file; `name` is what syntax errors call it).
#[pyfunction]
#[pyo3(signature = (text, engine = None, name = "scene.toml"))]
fn from_toml(text: String, engine: Option<String>, name: &str) -> PyResult<Simulation> {
    Simulation::open(|opts| ballast_core::open::open_text(text, name.as_ref(), opts), engine)
}

/// The extension module `ballast._ballast`, which the package `ballast` (python/ballast/) re-exports and builds
/// its experiment modules and ensembles on.
#[pymodule]
fn _ballast(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(from_toml, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::table, m)?)?;
    m.add("DEFAULT_PERTURBATION_M", ballast_core::studies::replicas::DEFAULT_PERTURBATION_M)?;
    m.add("DEFAULT_PERTURB_SEED", ballast_core::studies::replicas::DEFAULT_PERTURB_SEED)?;
    m.add("DEFAULT_SEATING_CYCLES", ballast_core::studies::replicas::DEFAULT_SEATING_CYCLES)?;
    m.add("PAPER_POLICIES", ballast_core::studies::campaigns::PAPER_POLICIES.to_vec())?;
    m.add_function(wrap_pyfunction!(experiments::saussine_sample, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::saussine_loaded, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::karrech_deposit, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::luding_box, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::replica_starts, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::replica_run, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::replica_finish, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::saussine_convergence, m)?)?;
    m.add_function(wrap_pyfunction!(experiments::compare, m)?)?;
    m.add_class::<Simulation>()?;
    errors::register(m)?;
    Ok(())
}
