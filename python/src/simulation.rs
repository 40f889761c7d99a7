//! `ballast.Simulation`: a scene opened on its engine, stepped from Python, its state read and written as numpy
//! arrays through the engine contract (`ballast::engine::Engine`: the final state, the contact rows, the
//! configuration write-back).

use crate::errors::to_py;
use crate::running::{to_python, watched, OutFolder, LOOK_EVERY};
use crate::settle::Asked;
use ballast_core::engine::{BodyState, Engine, Spin, StepSummary};
use ballast_core::open::Loaded;
use ballast_core::run::{RunEnd, RunLength, RunOptions, Status};
use ballast_core::scene::SceneFile;
use numpy::{PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::time::Instant;

/// The system of whichever engine `$loaded` holds, bound to `$s`, in `$body`.
macro_rules! with_system {
    ($loaded:expr, $s:ident => $body:expr) => {
        match $loaded {
            Loaded::Nscd(o) => {
                let $s = &mut o.system;
                $body
            }
            Loaded::PlanarMd(o, _) => {
                let $s = &mut o.system;
                $body
            }
            Loaded::Md(o) => {
                let $s = &mut o.system;
                $body
            }
            Loaded::Nscd3(o) => {
                let $s = &mut o.system;
                $body
            }
        }
    };
}

/// A scene opened on its engine: NSCD or planar MD (2D: positions `x, y, θ`), 3D MD or 3D NSCD (positions
/// `x, y, z`).
#[pyclass(module = "ballast")]
pub struct Simulation {
    loaded: Loaded,
}

impl Simulation {
    /// A simulation of what `open` opens with the run options of `engine`.
    pub fn open(
        open: impl FnOnce(&RunOptions) -> ballast_core::Result<Loaded>,
        engine: Option<String>,
    ) -> PyResult<Self> {
        let opts = RunOptions { engine, ..RunOptions::default() };
        Ok(Self { loaded: open(&opts).map_err(to_py)? })
    }
}

/// A step's statistics as a dict (SI units).
fn summary_dict<'py>(py: Python<'py>, s: &StepSummary) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("time", s.time)?;
    d.set_item("kinetic_energy", s.kinetic_energy)?;
    d.set_item("contacts", s.contacts)?;
    d.set_item("mean_overlap", s.mean_overlap)?;
    d.set_item("max_overlap", s.max_overlap)?;
    d.set_item("iterations", s.iterations)?;
    d.set_item("converged", s.converged)?;
    d.set_item("criterion", s.criterion)?;
    Ok(d)
}

/// A body's row of `positions`: `x, y, θ` in 2D, `x, y, z` in 3D.
fn position_row(b: &BodyState) -> [f64; 3] {
    match b.angle {
        Some(theta) => [b.position[0], b.position[1], theta],
        None => [b.position[0], b.position[1], b.position[2]],
    }
}

/// A body's row of `velocities`: `v_x, v_y, ω` in 2D, `v_x, v_y, v_z` in 3D.
fn velocity_row(b: &BodyState) -> [f64; 3] {
    match b.spin {
        Spin::Planar(w) => [b.velocity[0], b.velocity[1], w],
        Spin::Spatial(_) => [b.velocity[0], b.velocity[1], b.velocity[2]],
    }
}

/// An `(n, 3)` float64 array of the rows `rows`.
fn matrix<'py>(py: Python<'py>, rows: Vec<[f64; 3]>) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let n = rows.len();
    PyArray1::from_vec(py, rows.into_iter().flatten().collect()).reshape([n, 3])
}

#[pymethods]
impl Simulation {
    /// The engine: `nscd`, `md2d`, `md` or `nscd3d`.
    #[getter]
    fn engine(&mut self) -> &'static str {
        with_system!(&mut self.loaded, s => name_of(s))
    }

    /// Time (s).
    #[getter]
    fn time(&mut self) -> f64 {
        with_system!(&mut self.loaded, s => s.time())
    }

    /// Steps made.
    #[getter]
    fn steps_done(&mut self) -> u64 {
        with_system!(&mut self.loaded, s => s.steps_done())
    }

    /// Time step (s).
    #[getter]
    fn dt(&mut self) -> f64 {
        with_system!(&mut self.loaded, s => s.dt())
    }

    /// Makes `n` steps (the interpreter's lock released) and returns the last one's statistics: `time` (s),
    /// `kinetic_energy` (J), `contacts`, `mean_overlap` and `max_overlap` (m), `iterations`, `converged` and
    /// `criterion` (the NSCD solver's). A step that blows up raises `DivergedError`, the state being that of
    /// the last good step. Ctrl-C (SIGINT) raises `KeyboardInterrupt` between two steps, within about
    /// 20 ms of wall time, the state being that of the last step made.
    #[pyo3(signature = (n = 1))]
    fn step<'py>(&mut self, py: Python<'py>, n: u64) -> PyResult<Bound<'py, PyDict>> {
        if n == 0 {
            return Err(PyValueError::new_err("n: must be at least 1, got 0"));
        }
        let summary = with_system!(&mut self.loaded, s => {
            let (mut done, mut last) = (0, None);
            while done < n {
                // Steps with the lock released for about LOOK_EVERY, then the signals are looked at.
                let chunk = py.detach(|| {
                    let (start, mut made, mut last) = (Instant::now(), 0, None);
                    // The clock is read after steps 1, 2, … while a step is long beside LOOK_EVERY, at
                    // doubling intervals while it is short (a step of a few spheres lasts less than a
                    // microsecond: reading the clock after each would cost a few per cent of it).
                    let (mut stride, mut next) = (1, 1);
                    while done + made < n {
                        last = Some(s.step()?);
                        made += 1;
                        if made == next {
                            let elapsed = start.elapsed();
                            if elapsed >= LOOK_EVERY {
                                break;
                            }
                            if 4 * elapsed < LOOK_EVERY {
                                stride *= 2;
                            }
                            next = made + stride;
                        }
                    }
                    Ok::<_, ballast_core::Error>((made, last.map(|stats| summary_of(s, &stats))))
                });
                let (made, summary) = chunk.map_err(to_py)?;
                (done, last) = (done + made, summary.or(last));
                py.check_signals()?;
            }
            last
        });
        match summary {
            Some(s) => summary_dict(py, &s),
            None => Err(PyValueError::new_err("n: must be at least 1")),
        }
    }

    /// Runs the simulation through the library's run loop into the folder `out` (the outputs of `ballast run`:
    /// `series.csv`, `final.json`, `contacts.csv`, `summary.json`, checkpoints; `None`: a temporary folder,
    /// removed on return) from the state it holds, and keeps the state the run reached.
    ///
    /// `steps`: steps to make (`None`: the scene's `[simulation] duration`; the run may end earlier at the
    /// scene's equilibrium rule). `checkpoint_every`: wall-clock seconds between checkpoints (`None`: 300 with
    /// `out`, none without). `resume`: continue the run in `out` from its checkpoint (a run started from the
    /// scene's start; the simulation's state before the call does not matter). `progress`: called with a dict
    /// (`step`, `end_step`, `time` in s, `kinetic_energy` in J, `contacts`, `cycles` and `settlement` in m when
    /// the scene follows cycles) after the first step, then at most every 20 ms and after the last; returning
    /// `False` stops the run as Ctrl-C does, without an exception. `stop_after`: stop after this many steps of this
    /// call. `vtk_every`: a VTK snapshot every this many steps (0: none). `figures`: draw the run's figures.
    /// `threads`: threads of a step (1 or 2; `None`: 2 on a machine with 2 cores; the numbers do not depend on
    /// it). `change_solver` (with `resume`): the simulation's scene may differ from the run's in its `[nscd]`
    /// solver keys (tolerance, sweep caps, `anderson`, …), every other key the same; the run goes on with the new
    /// settings and records them in `solver_changes.csv` (docs/scene-format.md). `extend` (with `resume`): the
    /// scene may differ from the run's in its duration (`steps` is such a change), and the run goes on past its
    /// end with the numbers of a run asked for the longer length from the start; a finished run keeps the
    /// checkpoint to extend from only when it ran with `keep_checkpoint`.
    ///
    /// Returns a dict: `status` (`finished`, `equilibrium` or `stopped`), `step`, `end_step`, `time` (s),
    /// `kinetic_energy` (J), `elapsed_s`, `out` (`None` for a temporary folder), `report` (the contents of
    /// `summary.json`) and `solver_changes` (a list of dicts `step`, `time_s`, `key`, `before`, `after`: the
    /// settings `change_solver` changed, empty otherwise). The interpreter's lock is released while stepping. Ctrl-C (SIGINT) stops the run
    /// between two steps, leaves a checkpoint in `out` (resume with `resume=True`) and raises
    /// `KeyboardInterrupt`; an exception of `progress` does the same and is raised. A step that blows up
    /// raises `DivergedError` (the outputs and the simulation hold the last good step).
    #[pyo3(signature = (
        out = None, steps = None, checkpoint_every = None, resume = false, progress = None, stop_after = None,
        vtk_every = 0, figures = false, threads = None, change_solver = false, extend = false,
        keep_checkpoint = false
    ))]
    #[allow(clippy::too_many_arguments)]
    fn run<'py>(
        &mut self,
        py: Python<'py>,
        out: Option<PathBuf>,
        steps: Option<u64>,
        checkpoint_every: Option<f64>,
        resume: bool,
        progress: Option<Py<PyAny>>,
        stop_after: Option<u64>,
        vtk_every: u64,
        figures: bool,
        threads: Option<usize>,
        change_solver: bool,
        extend: bool,
        keep_checkpoint: bool,
    ) -> PyResult<Bound<'py, PyDict>> {
        if resume && out.is_none() {
            return Err(PyValueError::new_err("resume: needs the folder `out` of the run to continue"));
        }
        let folder = OutFolder::new(out);
        let opts = RunOptions {
            vtk_every,
            length: steps.map(RunLength::Steps),
            change_solver,
            extend,
            keep_checkpoint,
            ..options(&folder, checkpoint_every, resume, stop_after, figures, threads)
        };
        let loaded = &mut self.loaded;
        let outcome = watched(py, progress, |watch| {
            loaded.run_on(folder.path(), &opts, &mut |p| {
                watch.look(p.step == p.end_step, |d| {
                    d.set_item("step", p.step)?;
                    d.set_item("end_step", p.end_step)?;
                    d.set_item("time", p.time)?;
                    d.set_item("kinetic_energy", p.kinetic_energy)?;
                    d.set_item("contacts", p.contacts)?;
                    d.set_item("cycles", p.cycles)?;
                    d.set_item("settlement", p.settlement)
                })
            })
        })?;
        let d = PyDict::new(py);
        let status = match outcome.status {
            Status::Stopped => "stopped",
            Status::Ended(RunEnd::Equilibrium) => "equilibrium",
            Status::Ended(_) => "finished",
        };
        d.set_item("status", status)?;
        d.set_item("step", outcome.step)?;
        d.set_item("end_step", outcome.end_step)?;
        d.set_item("time", outcome.time)?;
        d.set_item("kinetic_energy", outcome.kinetic_energy)?;
        d.set_item("elapsed_s", outcome.elapsed_s)?;
        d.set_item("out", folder.shown())?;
        d.set_item("report", to_python(py, &outcome.report)?)?;
        d.set_item("solver_changes", to_python(py, &outcome.solver_changes)?)?;
        Ok(d)
    }

    /// Runs the settlement-acceleration procedure of Karrech et al. (2007, Fig. 10: cycles computed, the
    /// settlement per body fitted to its law, extrapolated by a jump of cycles, the overlaps relaxed, repeated)
    /// into the folder `out` (`settlement.csv`, `jumps.csv`, `summary.json`, checkpoints; `None`: a temporary
    /// folder, removed on return) from the state the simulation holds, and keeps the state reached. The scene
    /// must follow loading cycles (`[output] cycles`).
    ///
    /// `cycles`: the cycles to reach (`None`: those of the scene's duration). The scene's `[settlement]`
    /// table, with in place of its keys: `accelerate = (k_i, k, h)` (cycles computed before the first fit,
    /// computed per fit, extrapolated by the first jump), `law` (`"shenton"` or `"linear"`), `body` (the
    /// settlement body's name; default the mean over the mobile bodies) and `settings` (a dict of any other
    /// keys of the table, e.g. `{"relax_tolerance": 1e-5}`); a scene without a table needs `accelerate`.
    /// `progress`: called with a dict (`cycle`, `target`, `computed`, `settlement` in m, positive downwards)
    /// after the first cycle, then at most every 20 ms and after the last; returning `False` stops the run
    /// (checkpoint, `end` `"stopped"`). `resume`, `checkpoint_every`, `stop_after` (steps), `figures`,
    /// `threads`: as in `run`.
    ///
    /// Returns the run's summary (the contents of `summary.json`: `end`, `total_cycles`, `computed_cycles`,
    /// `gained`, `jumps`, `settlement_m`, …) with `out` added. Ctrl-C stops the run at the end of the cycle in
    /// progress, leaves a checkpoint and raises `KeyboardInterrupt`. A failed run raises (`DivergedError`, …)
    /// and leaves the simulation as it was before the call.
    #[pyo3(signature = (
        cycles = None, accelerate = None, law = None, body = None, settings = None, out = None, progress = None,
        resume = false, checkpoint_every = None, stop_after = None, figures = false, threads = None
    ))]
    #[allow(clippy::too_many_arguments)]
    fn settle<'py>(
        &mut self,
        py: Python<'py>,
        cycles: Option<u64>,
        accelerate: Option<(u64, u64, u64)>,
        law: Option<String>,
        body: Option<String>,
        settings: Option<Bound<'py, PyDict>>,
        out: Option<PathBuf>,
        progress: Option<Py<PyAny>>,
        resume: bool,
        checkpoint_every: Option<f64>,
        stop_after: Option<u64>,
        figures: bool,
        threads: Option<usize>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if resume && out.is_none() {
            return Err(PyValueError::new_err("resume: needs the folder `out` of the run to continue"));
        }
        let asked = Asked { accelerate, law, body, settings: settings.as_ref(), cycles };
        let request = crate::settle::request(py, &self.loaded, asked)?;
        let folder = OutFolder::new(out);
        let opts = options(&folder, checkpoint_every, resume, stop_after, figures, threads);
        let loaded = &mut self.loaded;
        let summary = watched(py, progress, |watch| {
            loaded.settle_on(folder.path(), &opts, &request, &mut |p| {
                watch.look(p.cycle >= p.target, |d| {
                    d.set_item("cycle", p.cycle)?;
                    d.set_item("target", p.target)?;
                    d.set_item("computed", p.computed)?;
                    d.set_item("settlement", p.settlement)
                })
            })
        })?;
        let summary = to_python(py, &summary)?;
        summary.set_item("out", folder.shown())?;
        Ok(summary)
    }

    /// The bodies' names, in scene order.
    #[getter]
    fn names(&mut self) -> Vec<String> {
        with_system!(&mut self.loaded, s => s.final_state().bodies.into_iter().map(|b| b.name).collect())
    }

    /// Which bodies are fixed (or have every velocity component imposed): a bool array, in scene order.
    #[getter]
    fn fixed<'py>(&mut self, py: Python<'py>) -> Bound<'py, PyArray1<bool>> {
        PyArray1::from_vec(py, with_system!(&mut self.loaded, s => fixed_mask(s)))
    }

    /// Positions, `(n, 3)` float64 in scene order: `x, y` (m) and the angle `θ` (rad) in 2D; `x, y, z` (m) in
    /// 3D.
    #[getter]
    fn positions<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let state = with_system!(&mut self.loaded, s => s.final_state());
        matrix(py, state.bodies.iter().map(position_row).collect())
    }

    /// Velocities, `(n, 3)` float64 in scene order: `v_x, v_y` (m/s) and the spin `ω` (rad/s) in 2D;
    /// `v_x, v_y, v_z` (m/s) in 3D.
    #[getter]
    fn velocities<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let state = with_system!(&mut self.loaded, s => s.final_state());
        matrix(py, state.bodies.iter().map(velocity_row).collect())
    }

    /// Writes the positions back (the engine contract's write-back: velocities zeroed, derived state rebuilt):
    /// an `(n, 3)` float64 array as `positions` gives it; the rows of fixed bodies must be unchanged (3D: the
    /// spheres keep their orientation).
    fn set_positions(&mut self, positions: PyReadonlyArray2<'_, f64>) -> PyResult<()> {
        let current = with_system!(&mut self.loaded, s => s.final_state());
        let array = positions.as_array();
        let n = current.bodies.len();
        if array.shape() != [n, 3] {
            return Err(PyValueError::new_err(format!(
                "positions: expected an array of shape ({n}, 3), got {:?}",
                array.shape()
            )));
        }
        if let Some((i, _)) = array.indexed_iter().find(|(_, x)| !x.is_finite()) {
            return Err(PyValueError::new_err(format!("positions[{}, {}]: not finite", i.0, i.1)));
        }
        with_system!(&mut self.loaded, s => {
            let mut c = s.configuration();
            let fixed = fixed_mask(s);
            for (i, b) in current.bodies.iter().enumerate() {
                let now = position_row(b);
                let new = [array[[i, 0]], array[[i, 1]], array[[i, 2]]];
                if fixed[i] && new != now {
                    return Err(PyValueError::new_err(format!(
                        "positions[{i}]: body '{}' is fixed; its row must stay {now:?}",
                        b.name
                    )));
                }
            }
            for k in 0..c.bodies.len() {
                let i = c.bodies[k];
                let q = c.body_mut(k);
                q[..3].copy_from_slice(&[array[[i, 0]], array[[i, 1]], array[[i, 2]]]);
            }
            s.set_configuration(&c).map_err(to_py)
        })
    }

    /// The contacts of the last step as a dict of arrays (SI units; `dim` = 2 or 3): `kind` (list of `pair`,
    /// `wall`, `image`), `bodies` (`(m, 2)` int64: the body the force acts on and the other), `points` and
    /// `normals` (`(m, dim)`, the normal from the other towards the first), `gaps` (m, negative when
    /// overlapping), `normal_forces` (N, positive pushing apart), `tangential_forces` (`(m, dim)`, N).
    fn contacts<'py>(&mut self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let (dim, rows) = with_system!(&mut self.loaded, s => (dim_of(s), s.contact_rows()));
        let m = rows.len();
        let pick = |v: [f64; 3]| v[..dim].to_vec();
        let mut points = Vec::with_capacity(m * dim);
        let mut normals = Vec::with_capacity(m * dim);
        let mut tangential = Vec::with_capacity(m * dim);
        for r in &rows {
            points.extend(pick([r.point_x_m, r.point_y_m, r.point_z_m.unwrap_or(0.0)]));
            normals.extend(pick([r.normal_x, r.normal_y, r.normal_z.unwrap_or(0.0)]));
            tangential.extend(pick([r.f_t_x, r.f_t_y, r.f_t_z.unwrap_or(0.0)]));
        }
        let bodies: Vec<i64> = rows.iter().flat_map(|r| [r.a as i64, r.b as i64]).collect();
        let d = PyDict::new(py);
        let kinds: Vec<String> = rows.iter().map(|r| format!("{:?}", r.kind).to_lowercase()).collect();
        d.set_item("kind", kinds)?;
        d.set_item("bodies", PyArray1::from_vec(py, bodies).reshape([m, 2])?)?;
        d.set_item("points", PyArray1::from_vec(py, points).reshape([m, dim])?)?;
        d.set_item("normals", PyArray1::from_vec(py, normals).reshape([m, dim])?)?;
        d.set_item("gaps", PyArray1::from_vec(py, rows.iter().map(|r| r.gap_m).collect()))?;
        d.set_item("normal_forces", PyArray1::from_vec(py, rows.iter().map(|r| r.f_n).collect()))?;
        d.set_item("tangential_forces", PyArray1::from_vec(py, tangential).reshape([m, dim])?)?;
        Ok(d)
    }

    /// The state the simulation holds as a scene (TOML text): its scene with the bodies where they are now,
    /// at rest or moving as they are (NSCD, 3D MD; the planar MD engine writes positions and velocities), to
    /// save, edit, or open again with `from_toml` (its time restarts at 0).
    fn to_toml(&self) -> PyResult<String> {
        let text = match &self.loaded {
            Loaded::Nscd(o) => o.scene.with_state(&o.system).to_toml_string(),
            Loaded::PlanarMd(o, _) => o.scene.with_bodies(&o.system.bodies).to_toml_string(),
            Loaded::Md(o) => o.scene.with_state(&o.system).to_toml_string(),
            Loaded::Nscd3(o) => o.scene.with_state(&o.system).to_toml_string(),
        };
        text.map_err(to_py)
    }

    fn __repr__(&mut self) -> String {
        let engine = self.engine();
        let (n, t) = with_system!(&mut self.loaded, s => (s.body_count(), s.time()));
        format!("<ballast.Simulation {engine}: {n} bodies, t = {t} s>")
    }
}

/// The run options of `run` and `settle` into `folder` (checkpoints every 300 s by default, none into a
/// temporary folder).
fn options(
    folder: &OutFolder,
    checkpoint_every: Option<f64>,
    resume: bool,
    stop_after: Option<u64>,
    figures: bool,
    threads: Option<usize>,
) -> RunOptions {
    let default_every = if folder.is_temporary() { 0.0 } else { RunOptions::default().checkpoint_every_s };
    RunOptions {
        checkpoint_every_s: checkpoint_every.unwrap_or(default_every),
        resume,
        stop_after,
        threads: threads.unwrap_or_else(ballast_core::run::default_threads),
        figures,
        ..RunOptions::default()
    }
}

/// The engine's name (`nscd`, `md2d`, `md`: the one its outputs record).
fn name_of<E: Engine>(_sys: &E) -> &'static str {
    E::NAME
}

/// The engine's space dimension (2 or 3).
fn dim_of<E: Engine>(_sys: &E) -> usize {
    E::DIM
}

/// Which bodies are fixed (or have every velocity component imposed): not among the engine's mobile bodies.
fn fixed_mask<E: Engine>(sys: &E) -> Vec<bool> {
    let mut fixed = vec![true; sys.body_count()];
    sys.mobile_bodies().into_iter().for_each(|i| fixed[i] = false);
    fixed
}

/// The engine-neutral summary of a step's statistics.
fn summary_of<E: Engine>(_sys: &E, stats: &E::Stats) -> StepSummary {
    E::summary(stats)
}
