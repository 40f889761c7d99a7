//! Opening a scene file: the one registration point of the engines. [`open`] reads a scene, picks its engine
//! (`[simulation] engine`, or the `engine` override of [`RunOptions`]: `nscd`, `md2d` or `md`), applies a length
//! override, and builds the system as a [`Loaded`] value; [`Loaded::run`] runs it through the run loop
//! ([`crate::run::Runner`]) and [`Loaded::settle`] through the settlement driver
//! ([`crate::settlement::Accelerated`], when the scene has a `[settlement]` table), each with its engine's
//! figures ([`crate::report`]); [`run_file`] and [`settle_file`] do both steps. The command line, the studies
//! and library callers all open scenes here.
//!
//! Adding an engine: a variant of [`Loaded`], its arm in [`open`], and its arms in [`Loaded::run`] and
//! [`Loaded::settle`] (ARCHITECTURE.md, "Adding an engine").

use crate::error::{Error, Result};
use crate::md::planar::PlanarSystem;
use crate::md::MdSystem;
use crate::nscd::d3::system::System3;
use crate::nscd::System;
use crate::run::{Figures, Progress, Restart, RunOptions, RunOutcome, Runner};
use crate::scene::common::{AccelerationPlan, SettlementSection};
use crate::scene::SceneFile;
use crate::scene::{planar_length, scene_on, MdScene, Scene, Scene3, SceneKind, SoftModelInfo};
use crate::settlement::{Accelerated, AccelerationOutcome, AccelerationProgress, AccelerationSummary, FolderFigures};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

/// A scene as read: its serde form, the text a run records (`scene.toml`: the file's text, or its serialised
/// form with a length override applied), the system built from it, and its `[settlement]` plan, checked, if
/// it has one.
pub struct Opened<S, E> {
    /// The scene file's path (recorded in the outputs' headers).
    pub path: PathBuf,
    /// The scene.
    pub scene: S,
    /// The text recorded as `scene.toml`.
    pub text: String,
    /// The system built from it.
    pub system: E,
    /// The settlement-acceleration plan of its `[settlement]` table.
    pub acceleration: Option<AccelerationPlan>,
}

/// A scene file opened on its engine.
pub enum Loaded {
    /// Rigid 2D polygons, non-smooth contact dynamics (`engine = "nscd"`).
    Nscd(Box<Opened<Scene, System>>),
    /// A 2D scene on soft contacts (`engine = "md2d"`, or the `engine` override), with the
    /// stiffness and time step its `[soft]` table resolved to (recorded in `run.json`).
    PlanarMd(Box<Opened<Scene, PlanarSystem>>, SoftModelInfo),
    /// Soft 3D spheres, molecular dynamics (`engine = "md"`).
    Md(Box<Opened<MdScene, MdSystem>>),
    /// Rigid 3D polyhedra, spheres and walls, non-smooth contact dynamics (`engine = "nscd"`, `dimension = 3`).
    Nscd3(Box<Opened<Scene3, System3>>),
}

/// Opens the scene file at `path` with the `engine` and `length` overrides of `opts`: its engine, its
/// recorded text, its system and its `[settlement]` plan, if any.
///
/// # Errors
/// [`Error::File`] naming the file if it cannot be read; [`Error::Scene`] (one line naming the key) for an
/// invalid scene or override.
pub fn open(path: &Path, opts: &RunOptions) -> Result<Loaded> {
    open_text(crate::scene::read_text(path)?, path, opts)
}

/// [`open`] of a scene given as its TOML `text`, recorded as read from `path` (the name syntax errors give, and
/// the path the outputs' headers record; nothing is read from it).
///
/// # Errors
/// [`Error::Scene`] (one line naming the key) for an invalid scene or override.
pub fn open_text(text: String, path: &Path, opts: &RunOptions) -> Result<Loaded> {
    let name = path.display().to_string();
    match SceneKind::of(&text, &name, opts.engine.as_deref())? {
        SceneKind::Md => {
            let mut scene = MdScene::from_toml_str_named(&text, &name)?;
            let text = scene.text_with_length(text, opts.length)?;
            let acceleration = if scene.settlement.is_some() { scene.acceleration()? } else { None };
            let system = scene.build()?;
            Ok(Loaded::Md(Box::new(Opened { path: path.to_path_buf(), scene, text, system, acceleration })))
        }
        SceneKind::PlanarMd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::PlanarMd, opts.engine.is_some())?;
            let (system, info) = scene.build_planar()?;
            let text = scene.text_with_length(text, planar_length(opts.length, system.params.dt))?;
            let acceleration = if scene.settlement.is_some() { scene.acceleration()? } else { None };
            Ok(Loaded::PlanarMd(Box::new(Opened { path: path.to_path_buf(), scene, text, system, acceleration }), info))
        }
        SceneKind::Nscd3 => {
            let mut scene = Scene3::from_toml_str_named(&text, &name)?;
            let text = scene.text_with_length(text, opts.length)?;
            let acceleration = if scene.settlement.is_some() { scene.acceleration()? } else { None };
            let system = scene.build()?;
            Ok(Loaded::Nscd3(Box::new(Opened { path: path.to_path_buf(), scene, text, system, acceleration })))
        }
        SceneKind::Nscd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::Nscd, opts.engine.is_some())?;
            let text = scene.text_with_length(text, opts.length)?;
            let acceleration = if scene.settlement.is_some() { scene.acceleration()? } else { None };
            let system = scene.build()?;
            Ok(Loaded::Nscd(Box::new(Opened { path: path.to_path_buf(), scene, text, system, acceleration })))
        }
    }
}

impl Loaded {
    /// Whether the scene has a `[settlement]` table that asks for an accelerated run.
    pub fn settles(&self) -> bool {
        match self {
            Loaded::Nscd(o) => o.acceleration.is_some(),
            Loaded::PlanarMd(o, _) => o.acceleration.is_some(),
            Loaded::Md(o) => o.acceleration.is_some(),
            Loaded::Nscd3(o) => o.acceleration.is_some(),
        }
    }

    /// Runs the scene into the folder `out` through the run loop, calling `progress` after every step (a
    /// `[settlement]` table is not read: see [`Loaded::settle`]). `opts` are those the scene was opened with
    /// (its `length` and `engine` are already applied); an MD scene's `md.threads` wins over `opts.threads`.
    ///
    /// # Errors
    /// [`Error::Scene`] (one line naming the field) for invalid options or checkpoint; else as
    /// [`Runner::run`].
    pub fn run(mut self, out: &Path, opts: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<RunOutcome> {
        let opts = RunOptions { length: None, engine: None, ..opts.clone() };
        self.run_on(out, &opts, &mut |p| {
            progress(p);
            ControlFlow::Continue(())
        })
    }

    /// Runs the system from the state it holds into the folder `out` through the run loop
    /// ([`Runner::run_with`]: `control` after every step may stop the run, leaving a checkpoint) and keeps the
    /// state the run left (its last step; the last good one if a step diverged). `opts.length` sets the steps
    /// of this run (counted from the state held; `None`: the scene's `[simulation] duration`); `opts.engine`
    /// is not read (the engine is chosen when the scene is opened). An MD scene's `md.threads` wins over
    /// `opts.threads`.
    ///
    /// The run's record of its input is the scene's text (`scene.toml`) when the system holds the start the
    /// scene builds (no step made, the same bodies, positions and velocities), and otherwise the state's serde
    /// form (`initial_state.json`, as for a system built in code). `opts.resume` continues the run in `out`
    /// from its checkpoint: a run that started from the scene's start, whatever state the system holds now.
    ///
    /// # Errors
    /// [`Error::Scene`] (one line naming the field) for invalid options or a refused length; else as
    /// [`Runner::run`].
    pub fn run_on(
        &mut self,
        out: &Path,
        opts: &RunOptions,
        control: &mut dyn FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<RunOutcome> {
        // The length is applied to the scene here; the runner refuses one.
        let (length, opts) = (opts.length, &RunOptions { length: None, engine: None, ..opts.clone() });
        match self {
            Loaded::Md(o) => {
                let mut scene = o.scene.clone();
                let text = scene.text_with_length(o.text.clone(), length)?;
                let opts = RunOptions { threads: scene.threads().unwrap_or(opts.threads), ..opts.clone() };
                let plan = scene.plan()?;
                let fresh = o.scene.build()?;
                let restart: Restart<MdSystem> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
                let figures: Figures<MdSystem> = Box::new(|dir, _| crate::report::draw_run_figures(dir).map(drop));
                let runner = runner(&o.system, fresh, plan, (&o.path, text), restart, opts.resume)?;
                keep(&mut o.system, runner.with_figures(figures).run_with(out, &opts, control))
            }
            Loaded::PlanarMd(o, info) => {
                let mut scene = o.scene.clone();
                let text = scene.text_with_length(o.text.clone(), planar_length(length, o.system.params.dt))?;
                let plan = scene.plan_planar(o.system.params.dt)?;
                let model = serde_json::to_value(*info).map_err(|e| Error::Io(std::io::Error::other(e)))?;
                let (fresh, _) = o.scene.build_planar()?;
                let restart: Restart<PlanarSystem> =
                    Box::new(move |sys| scene.with_bodies(&sys.bodies).to_toml_string());
                let runner = runner(&o.system, fresh, plan, (&o.path, text), restart, opts.resume)?;
                let runner = runner.with_model(model).with_figures(plane_figures::<PlanarSystem>());
                keep(&mut o.system, runner.run_with(out, opts, control))
            }
            Loaded::Nscd(o) => {
                let mut scene = o.scene.clone();
                let text = scene.text_with_length(o.text.clone(), length)?;
                let plan = scene.plan()?;
                let fresh = o.scene.build()?;
                let restart: Restart<System> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
                let runner = runner(&o.system, fresh, plan, (&o.path, text), restart, opts.resume)?;
                keep(&mut o.system, runner.with_figures(plane_figures::<System>()).run_with(out, opts, control))
            }
            Loaded::Nscd3(o) => {
                let mut scene = o.scene.clone();
                let text = scene.text_with_length(o.text.clone(), length)?;
                let plan = scene.plan()?;
                let fresh = o.scene.build()?;
                let restart: Restart<System3> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
                let figures: Figures<System3> = Box::new(|dir, _| crate::report::draw_run_figures(dir).map(drop));
                let runner = runner(&o.system, fresh, plan, (&o.path, text), restart, opts.resume)?;
                keep(&mut o.system, runner.with_figures(figures).run_with(out, opts, control))
            }
        }
    }

    /// Runs the scene's settlement-acceleration procedure into `out`, calling `progress` after each cycle;
    /// `None` (nothing run) if the scene has no `[settlement]`. `opts` are those the scene was opened with (its
    /// `length`, which sets the cycles to reach, and `engine` are already applied); an MD scene's
    /// `md.threads` wins.
    ///
    /// # Errors
    /// [`Error::Scene`] (one line naming the key) for invalid options; else as [`Accelerated::run`].
    pub fn settle(
        mut self,
        out: &Path,
        opts: &RunOptions,
        progress: &mut dyn FnMut(&AccelerationProgress),
    ) -> Result<Option<AccelerationSummary>> {
        if !self.settles() {
            return Ok(None);
        }
        if opts.change_solver || opts.extend {
            let key = if opts.change_solver { "change_solver" } else { "extend" };
            return Err(Error::Scene(format!(
                "{key}: a run with [settlement] resumes only with the scene it started from"
            )));
        }
        if opts.keep_checkpoint {
            return Err(Error::Scene(
                "keep_checkpoint: a run with [settlement] ends without a checkpoint; ask for the cycles it should reach"
                    .into(),
            ));
        }
        let opts = RunOptions { length: None, engine: None, ..opts.clone() };
        let request = SettleRequest::default();
        let summary = self.settle_on(out, &opts, &request, &mut |p| {
            progress(p);
            ControlFlow::Continue(())
        })?;
        Ok(Some(summary))
    }

    /// Runs the settlement-acceleration procedure ([`Accelerated::run_with`]: `control` after each cycle may
    /// stop it, leaving a checkpoint) from the state the system holds into `out`, with the scene's
    /// `[settlement]` table or `request`'s, to the cycles the scene's duration holds or `request.cycles`; the
    /// system then holds the state reached (unchanged if the run fails). The record of the input, `resume` and
    /// `opts.length` (not read: the cycles are `request`'s) are as in [`Loaded::run_on`]; an MD scene's
    /// `md.threads` wins over `opts.threads`.
    ///
    /// # Errors
    /// [`Error::Scene`] naming the key for a scene without a `[settlement]` table and no
    /// `request.settlement`, a table or cycle count the scene refuses; else as [`Accelerated::run`].
    pub fn settle_on(
        &mut self,
        out: &Path,
        opts: &RunOptions,
        request: &SettleRequest,
        control: &mut dyn FnMut(&AccelerationProgress) -> ControlFlow<()>,
    ) -> Result<AccelerationSummary> {
        let opts = &RunOptions { length: None, engine: None, ..opts.clone() };
        match self {
            Loaded::Md(o) => {
                let mut scene = o.scene.clone();
                let text = request.apply(&mut scene, &o.text, |s| &mut s.settlement)?;
                let opts = RunOptions { threads: scene.threads().unwrap_or(opts.threads), ..opts.clone() };
                let plan = settlement_plan(&scene)?;
                let fresh = o.scene.build()?;
                let run = accelerated(&o.system, fresh, plan, (scene.seed(), text), opts.resume)?;
                keep_settled(&mut o.system, run.with_figures(settlement_figures()).run_with(out, &opts, control))
            }
            Loaded::PlanarMd(o, info) => {
                let mut scene = o.scene.clone();
                let text = request.apply(&mut scene, &o.text, |s| &mut s.settlement)?;
                let plan = settlement_plan(&scene)?;
                let model = serde_json::to_value(*info).map_err(|e| Error::Io(std::io::Error::other(e)))?;
                let (fresh, _) = o.scene.build_planar()?;
                let run = accelerated(&o.system, fresh, plan, (scene.seed(), text), opts.resume)?;
                let run = run.with_model(model).with_figures(settlement_figures());
                keep_settled(&mut o.system, run.run_with(out, opts, control))
            }
            Loaded::Nscd(o) => {
                let mut scene = o.scene.clone();
                let text = request.apply(&mut scene, &o.text, |s| &mut s.settlement)?;
                let plan = settlement_plan(&scene)?;
                let fresh = o.scene.build()?;
                let run = accelerated(&o.system, fresh, plan, (scene.seed(), text), opts.resume)?;
                keep_settled(&mut o.system, run.with_figures(settlement_figures()).run_with(out, opts, control))
            }
            Loaded::Nscd3(o) => {
                let mut scene = o.scene.clone();
                let text = request.apply(&mut scene, &o.text, |s| &mut s.settlement)?;
                let plan = settlement_plan(&scene)?;
                let fresh = o.scene.build()?;
                let run = accelerated(&o.system, fresh, plan, (scene.seed(), text), opts.resume)?;
                keep_settled(&mut o.system, run.with_figures(settlement_figures()).run_with(out, opts, control))
            }
        }
    }
}

/// What [`Loaded::settle_on`] changes in the scene for its run.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SettleRequest {
    /// The `[settlement]` table to run with instead of the scene's (`None`: the scene's).
    pub settlement: Option<SettlementSection>,
    /// Loading cycles to reach, ≥ 1 (the scene's duration set to `cycles / frequency`; `None`: the scene's).
    pub cycles: Option<u64>,
}

impl SettleRequest {
    /// Applies the request to `scene` (its `[settlement]` table at `table`) whose text is `text`; the text to
    /// record: `text` itself when nothing changes, else the scene's serialised form.
    fn apply<S: SceneFile>(
        &self,
        scene: &mut S,
        text: &str,
        table: impl Fn(&mut S) -> &mut Option<SettlementSection>,
    ) -> Result<String> {
        if let Some(section) = &self.settlement {
            *table(scene) = Some(section.clone());
        }
        if let Some(cycles) = self.cycles {
            let frequency = scene.plan()?.cycles.map(|c| c.frequency).ok_or_else(|| {
                Error::Scene(
                    "output.cycles: the scene has no loading cycles to count (give [output] cycles = { frequency \
                     = … })"
                        .into(),
                )
            })?;
            if cycles == 0 {
                return Err(Error::Scene("cycles: must be at least 1, got 0".into()));
            }
            scene.simulation_mut().set_length(crate::run::RunLength::Duration(cycles as f64 / frequency))?;
        }
        if self.settlement.is_none() && self.cycles.is_none() {
            return Ok(text.to_string());
        }
        scene.validate()?;
        scene.to_toml_string()
    }
}

/// The settlement plan of `scene`, or the error that it has none.
fn settlement_plan<S: SceneFile>(scene: &S) -> Result<AccelerationPlan> {
    scene.acceleration()?.ok_or_else(|| {
        Error::Scene(
            "settlement: the scene has no [settlement] table (add one, or give the acceleration settings)".into(),
        )
    })
}

/// The accelerated run of `current`, as [`runner`] chooses its record (`fresh`: the start the scene builds;
/// the scene's seed and text).
fn accelerated<E: crate::engine::Engine>(
    current: &E,
    fresh: E,
    plan: AccelerationPlan,
    (seed, text): (u64, String),
    resume: bool,
) -> Result<Accelerated<E>> {
    let AccelerationPlan { spec, frequency, cycles } = plan;
    match scene_start(current, fresh, resume) {
        Some(system) => Ok(Accelerated::from_scene(system, spec, frequency, cycles, seed, text)),
        None => Accelerated::from_system(current.clone(), spec, frequency, cycles),
    }
}

/// The summary of an accelerated run, its final system kept in `system`.
fn keep_settled<E>(system: &mut E, outcome: Result<AccelerationOutcome<E>>) -> Result<AccelerationSummary> {
    let outcome = outcome?;
    *system = outcome.system;
    Ok(outcome.summary)
}

/// The system a run of `current` starts from when it is recorded as its scene: the scene's start `fresh` for a
/// resumed run (its checkpoint's run started there), `current` itself when it holds that start (no step made,
/// the same bodies, positions and velocities); `None` when the run is to record the state instead.
fn scene_start<E: crate::engine::Engine>(current: &E, fresh: E, resume: bool) -> Option<E> {
    if resume {
        Some(fresh)
    } else if current.steps_done() == 0 && current.final_state() == fresh.final_state() {
        Some(current.clone())
    } else {
        None
    }
}

/// Runs the scene file at `scene_path` (either engine: `[simulation] engine`) into the folder `out` through
/// the run loop ([`open`], then [`Loaded::run`]), calling `progress` after every step.
///
/// # Errors
/// As [`open`] and [`Loaded::run`].
pub fn run_file(
    scene_path: &Path,
    out: &Path,
    opts: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome> {
    open(scene_path, opts)?.run(out, opts, progress)
}

/// Runs the settlement-acceleration procedure of the scene file at `path` into `out` ([`open`], then
/// [`Loaded::settle`]); `None` (nothing run) if the scene has no `[settlement]`.
///
/// # Errors
/// As [`open`] and [`Loaded::settle`].
pub fn settle_file(
    path: &Path,
    out: &Path,
    opts: &RunOptions,
    progress: &mut dyn FnMut(&AccelerationProgress),
) -> Result<Option<AccelerationSummary>> {
    open(path, opts)?.settle(out, opts, progress)
}

/// The run of `current`, a system of the scene at `path` with the text `text` (`fresh`: the start that scene
/// builds), with `restart` writing its final state as a scene: recorded as the scene when `current` holds
/// that start or the run is `resume`d (a resumed run starts where its checkpoint's run started: the scene's
/// start), else as the state's serde form.
///
/// # Errors
/// [`Error::Io`] if the state cannot be serialised.
fn runner<E: crate::engine::Engine>(
    current: &E,
    fresh: E,
    plan: crate::run::RunPlan,
    (path, text): (&Path, String),
    restart: Restart<E>,
    resume: bool,
) -> Result<Runner<E>> {
    match scene_start(current, fresh, resume) {
        Some(system) => Ok(Runner::from_scene(system, plan, path, text, Some(restart))),
        None => Ok(Runner::from_system(current.clone(), plan)?.with_restart(path, restart)),
    }
}

/// The outcome of a run, its final system kept in `system`.
fn keep<E>(system: &mut E, (outcome, end): (Result<RunOutcome>, Option<E>)) -> Result<RunOutcome> {
    if let Some(end) = end {
        *system = end;
    }
    outcome
}

/// The figures of a run of either 2D engine: from its folder, with the positions at the end of the first
/// cycle kept by its per-cycle state (the reference of the displacement field).
fn plane_figures<E: crate::engine::Engine<CycleState = crate::plane::rows::PlaneCycleState>>() -> Figures<E> {
    Box::new(|dir, cycles| {
        let first = cycles.and_then(|c| c.first_cycle_q.as_deref());
        crate::report::plane::nscd_figures(dir, first).map(drop)
    })
}

/// The figures of an accelerated run, from its folder.
fn settlement_figures() -> FolderFigures {
    Box::new(|dir| crate::report::settlement::draw(dir, None).map(drop))
}
