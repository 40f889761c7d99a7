//! What `Simulation.run` and `Simulation.settle` share: the output folder (a temporary one when none is given),
//! the callback the library's loops call after each step or cycle with the interpreter's lock released (it
//! looks at the signals and calls the Python `progress` at most every [`LOOK_EVERY`] of wall time, and stops the
//! loop on Ctrl-C, on an exception of `progress` or when it returns `False`), and library values as Python dicts.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

/// Wall time between two looks at the interpreter's signals (Ctrl-C) and two calls of `progress` while a loop
/// runs: short beside a person's reaction, long beside the ~1 µs a look costs.
pub const LOOK_EVERY: Duration = Duration::from_millis(20);

/// The folder a run writes into: the one given, or a fresh temporary folder removed when this is dropped.
pub struct OutFolder {
    path: PathBuf,
    temporary: bool,
}

impl OutFolder {
    /// `out`, or a new folder under the system's temporary directory.
    pub fn new(out: Option<PathBuf>) -> Self {
        static COUNT: AtomicU64 = AtomicU64::new(0);
        match out {
            Some(path) => Self { path, temporary: false },
            None => {
                let n = COUNT.fetch_add(1, Ordering::Relaxed);
                let name = format!("ballast-python-{}-{n}", std::process::id());
                Self { path: std::env::temp_dir().join(name), temporary: true }
            }
        }
    }

    /// Its path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The path as a Python value: `None` for a temporary folder (gone when the call returns).
    pub fn shown(&self) -> Option<String> {
        (!self.temporary).then(|| self.path.display().to_string())
    }

    /// Whether it is temporary.
    pub fn is_temporary(&self) -> bool {
        self.temporary
    }
}

impl Drop for OutFolder {
    fn drop(&mut self) {
        if self.temporary {
            let _ = std::fs::remove_dir_all(&self.path);
        }
    }
}

/// The callback of a library loop: at its first step, then every [`LOOK_EVERY`] and at its last step (`last`),
/// with the lock taken, the signals looked at and `progress` called with a dict of the loop's report. A
/// signal's exception, or `progress`'s, is kept in `failure` and stops the loop; so does `progress` returning
/// `False`.
pub struct Watch {
    progress: Option<Py<PyAny>>,
    /// When the last look was (`None`: none yet; the first step is looked at).
    looked: Option<Instant>,
    /// The exception that stopped the loop.
    pub failure: Option<PyErr>,
}

impl Watch {
    /// A watch calling `progress`, if any.
    pub fn new(progress: Option<Py<PyAny>>) -> Self {
        Self { progress, looked: None, failure: None }
    }

    /// The look after a step or cycle: `last` whether it was the loop's last; `fill` writes its report into
    /// the dict given to `progress`.
    pub fn look(&mut self, last: bool, fill: impl FnOnce(&Bound<'_, PyDict>) -> PyResult<()>) -> ControlFlow<()> {
        if !last && self.looked.is_some_and(|t| t.elapsed() < LOOK_EVERY) {
            return ControlFlow::Continue(());
        }
        self.looked = Some(Instant::now());
        let progress = self.progress.as_ref();
        let flow = Python::attach(|py| -> PyResult<bool> {
            py.check_signals()?;
            let Some(f) = progress else { return Ok(true) };
            let report = PyDict::new(py);
            fill(&report)?;
            let answer = f.bind(py).call1((report,))?;
            // Only `False` itself stops the loop (a callback returning nothing goes on).
            Ok(!answer.is_instance_of::<pyo3::types::PyBool>() || answer.is_truthy()?)
        });
        match flow {
            Ok(true) => ControlFlow::Continue(()),
            Ok(false) => ControlFlow::Break(()),
            Err(e) => {
                self.failure = Some(e);
                ControlFlow::Break(())
            }
        }
    }
}

/// Runs `f` with the interpreter's lock released and a [`Watch`] calling `progress`: the exception that
/// stopped the loop, if one did, else `f`'s result (its error as the Python exception, `crate::errors`).
pub fn watched<T: Send>(
    py: Python<'_>,
    progress: Option<Py<PyAny>>,
    f: impl FnOnce(&mut Watch) -> ballast_core::Result<T> + Send,
) -> PyResult<T> {
    let mut watch = Watch::new(progress);
    let result = py.detach(|| f(&mut watch));
    if let Some(e) = watch.failure {
        return Err(e);
    }
    result.map_err(crate::errors::to_py)
}

/// A serde value as a Python object (through `json`).
pub fn to_python<'py, T: serde::Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value).map_err(|e| pyo3::exceptions::PyValueError::new_err(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}
