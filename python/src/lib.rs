//! The Python module `ballast`: scene files opened on their engine ([`load`], [`from_toml`]) as a
//! [`Simulation`] that steps and exposes its state as numpy arrays, and the library's errors as Python
//! exceptions ([`errors`]). SI units throughout (m, s, kg, rad, N).
//!
//! The binding holds the library's own values (`ballast::open::Loaded`); stepping runs the engines' code with
//! the interpreter's lock released.

mod errors;
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

/// The module.
#[pymodule]
fn ballast(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(from_toml, m)?)?;
    m.add_class::<Simulation>()?;
    errors::register(m)?;
    Ok(())
}
