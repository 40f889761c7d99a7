//! The library's errors (`ballast::Error`) as Python exceptions: a bad scene or argument is `SceneError` (a
//! `ValueError`, with `key`: the scene key or argument it names, or `None`), a refused checkpoint
//! `CheckpointError` (a `ValueError`), a run that blew up `DivergedError` (a `RuntimeError`, with `step`, `body`
//! and `name`), a step that stalled with `on_stall = "stop"` `StalledError` (a `RuntimeError`, with `step`), an
//! unreadable file `FileNotFoundError` or `OSError`, a refused shape `ValueError`.

use ballast_core::Error;
use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::IntoPyObjectExt;

pyo3::create_exception!(ballast, SceneError, PyValueError, "An invalid scene or argument; `key` names it.");
pyo3::create_exception!(
    ballast,
    CheckpointError,
    PyValueError,
    "A checkpoint to resume from was refused or is missing."
);
pyo3::create_exception!(
    ballast,
    DivergedError,
    PyRuntimeError,
    "A run blew up (a non-finite value, a runaway overlap); `step`, `body` and `name` say where. The simulation \
     keeps the state of the last good step."
);
pyo3::create_exception!(
    ballast,
    StalledError,
    PyRuntimeError,
    "A step reached its sweep cap short of the tolerance under `[nscd] on_stall = \"stop\"`; `step` says which."
);

/// Adds the exception types to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("CheckpointError", py.get_type::<CheckpointError>())?;
    m.add("DivergedError", py.get_type::<DivergedError>())?;
    m.add("StalledError", py.get_type::<StalledError>())?;
    Ok(())
}

/// `err` with the attributes `names` set to `values` on its instance.
fn with_attributes<'py>(py: Python<'py>, err: PyErr, attributes: &[(&str, Bound<'py, PyAny>)]) -> PyErr {
    let value = err.value(py);
    for (name, v) in attributes {
        if let Err(e) = value.setattr(*name, v) {
            return e;
        }
    }
    err
}

/// The Python exception of a library error (its message on one line).
pub fn to_py(e: Error) -> PyErr {
    Python::attach(|py| exception(py, e).unwrap_or_else(|err| err))
}

/// [`to_py`], or the error met while setting the exception's attributes.
fn exception(py: Python<'_>, e: Error) -> PyResult<PyErr> {
    let message = e.one_line();
    Ok(match &e {
        Error::Scene(_) => {
            let key = e.key().into_bound_py_any(py)?;
            with_attributes(py, SceneError::new_err(message), &[("key", key)])
        }
        Error::Checkpoint(_) => CheckpointError::new_err(message),
        Error::File { source, .. } if source.kind() == std::io::ErrorKind::NotFound => {
            PyFileNotFoundError::new_err(message)
        }
        Error::File { .. } | Error::Io(_) => PyOSError::new_err(message),
        Error::Geometry(_) => PyValueError::new_err(message),
        Error::Diverged { step, body, name, .. } => {
            let attributes = [
                ("step", step.into_bound_py_any(py)?),
                ("body", body.into_bound_py_any(py)?),
                ("name", name.into_bound_py_any(py)?),
            ];
            with_attributes(py, DivergedError::new_err(message), &attributes)
        }
        Error::Stalled { step, .. } => {
            with_attributes(py, StalledError::new_err(message), &[("step", step.into_bound_py_any(py)?)])
        }
    })
}
