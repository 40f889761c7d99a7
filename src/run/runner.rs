//! The run loop, one for both engines: steps an [`Engine`] to the end of its
//! plan or to equilibrium, writes the outputs of the run folder, checkpoints
//! every few minutes and resumes from a checkpoint with the same numbers.
//!
//! Data flow of a run: the system (built from a scene, or in code) → for each
//! step: `step()` → running summary → equilibrium rule → a row of `series.csv`
//! every `output_every` steps (and at the last) → per-cycle state, a row of
//! `cycles.csv` and the positions of the mobile bodies when a loading cycle ends
//! → a VTK snapshot every `vtk_every` steps → the progress callback → a
//! checkpoint when the wall clock says so. At the end: `final.json`,
//! `contacts.csv`, `summary.json`, the figures if asked, the state as a
//! restartable scene. A step that diverges stops the run with the step and body
//! named; the engine then holds its last good step, whose row, `final.json`,
//! `contacts.csv`, `summary.json` (and figures, if asked) are written before the
//! error is returned.

use super::folder::{self, Source};
use super::plan::{check_built, check_options, RunOptions, RunPlan};
use crate::clock::cycles_at;
use crate::engine::CycleCheck;
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::io::layout;
use crate::io::table::TableWriter;
use crate::io::vtk::PvdCollection;
use crate::io::{self, RunInfo};
use crate::run::checkpoint::Checkpoint;
use crate::run::cycle_times::CycleTimes;
use crate::run::extend;
use crate::run::positions::PositionsWriter;
use crate::run::solver_change::{self, SolverChange};
use crate::run::summary::{RunEnd, RunReport, RunSummary};
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What the progress callback sees after each step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    /// Steps made by the engine (counted from its step origin).
    pub step: u64,
    /// The step the run ends at if no equilibrium stops it first.
    pub end_step: u64,
    /// Time at the end of the step (s).
    pub time: f64,
    /// Kinetic energy of the step (J).
    pub kinetic_energy: f64,
    /// Contacts of the step (as [`crate::engine::StepSummary::contacts`] counts them).
    pub contacts: f64,
    /// Loading cycles completed, and in the whole run.
    pub cycles: Option<(u64, u64)>,
    /// Settlement of the followed body (m, positive downwards).
    pub settlement: Option<f64>,
}

/// How a call of [`Runner::run`] ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status {
    /// The run ended ([`RunEnd::Finished`] or [`RunEnd::Equilibrium`]).
    Ended(RunEnd),
    /// Stopped on request (`stop_after`), with a checkpoint to resume from.
    Stopped,
}

/// What a call of [`Runner::run`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOutcome {
    /// Ended or stopped (to resume).
    pub status: Status,
    /// Steps made by the engine at the end of the call.
    pub step: u64,
    /// The engine's time at the end of the call (s).
    pub time: f64,
    /// The step the run ends at.
    pub end_step: u64,
    /// Kinetic energy (J) of the last step.
    pub kinetic_energy: f64,
    /// The report of the run so far (written to `summary.json` once the run has
    /// ended; while it is only stopped, its `end` is not yet meaningful).
    pub report: RunReport,
    /// Wall time of this call (s).
    pub elapsed_s: f64,
    /// The output folder.
    pub out: PathBuf,
    /// The solver settings this call changed on resuming ([`RunOptions::change_solver`]; empty otherwise), as
    /// appended to `solver_changes.csv`.
    pub solver_changes: Vec<SolverChange>,
}

/// Writes the final state of a system as a scene text.
pub type Restart<E> = Box<dyn Fn(&E) -> Result<String> + Send + Sync>;

/// Draws the figures of a finished run from its folder (`ballast figures`); the per-cycle state the run
/// ended with, if it had one, gives what the files do not hold (NSCD: the positions at the end of the first
/// cycle). Given by whoever opens the scene ([`crate::open::run_file`]), which knows the engine's figures; the run
/// loop only calls it when [`RunOptions::figures`] asks.
pub type Figures<E> = Box<dyn Fn(&Path, Option<&<E as Engine>::CycleState>) -> Result<()> + Send + Sync>;

/// A run of an engine: its initial system, its plan and where it came from.
pub struct Runner<E: Engine> {
    system: E,
    plan: RunPlan,
    /// The scene's text or the system's serde form ([`Source`]).
    source: Source,
    /// [`solver_change::model_crc32`] of the scene's text (`None` for a system built in code), computed when a
    /// checkpoint first needs it (a parse of the whole scene).
    model_crc32: std::sync::OnceLock<Option<u32>>,
    /// The scene file's path, for the header of `final_scene.toml`.
    scene_path: Option<PathBuf>,
    restart: Option<Restart<E>>,
    /// What the scene resolved to that the system does not say, for `run.json`.
    model: Option<serde_json::Value>,
    /// The figures drawn at the end when [`RunOptions::figures`] asks.
    figures: Option<Figures<E>>,
}

/// How the loop ended: the last step's statistics and whether its series row was written, the failure that
/// stopped it, whether it stopped at equilibrium.
struct Ending<S> {
    last_stats: Option<(S, bool)>,
    diverged: Option<Error>,
    at_equilibrium: bool,
}

/// The state of a run in progress.
struct Live<E: Engine> {
    sys: E,
    summary: RunSummary,
    series: TableWriter,
    snapshots: PvdCollection,
    cycles: Option<(E::CycleState, TableWriter)>,
    cycles_done: u64,
    /// The wall time of each cycle (with cycles).
    cycle_times: Option<CycleTimes>,
    positions: Option<PositionsWriter>,
    first_step: u64,
    /// The solver settings changed on resuming.
    solver_changes: Vec<SolverChange>,
}

impl<E: Engine> Runner<E> {
    /// A run of `system`, built from the scene file at `path` whose text is
    /// `text`; `restart` writes a system's state as a scene to restart from
    /// (`final_scene.toml`).
    pub fn from_scene(system: E, plan: RunPlan, path: &Path, text: String, restart: Option<Restart<E>>) -> Self {
        Self {
            system,
            plan,
            model_crc32: std::sync::OnceLock::new(),
            source: Source::Scene { text },
            scene_path: Some(path.to_path_buf()),
            restart,
            model: None,
            figures: None,
        }
    }

    /// The same run, with `model` (what the scene resolved to: the planar MD
    /// engine's derived stiffness and time step) recorded in `run.json`.
    pub fn with_model(mut self, model: serde_json::Value) -> Self {
        self.model = Some(model);
        self
    }

    /// The same run, drawing its figures with `figures` at the end when [`RunOptions::figures`] asks
    /// ([`crate::open::run_file`] gives each engine's).
    pub fn with_figures(mut self, figures: Figures<E>) -> Self {
        self.figures = Some(figures);
        self
    }

    /// The same run, writing its final state as a scene with `restart` (`final_scene.toml`, its header
    /// naming the scene file at `path`).
    pub fn with_restart(mut self, path: &Path, restart: Restart<E>) -> Self {
        self.scene_path = Some(path.to_path_buf());
        self.restart = Some(restart);
        self
    }

    /// A run of a system built in code. Its serde form and the plan's are written
    /// to the output folder (`initial_state.json`) as the record of the run's input.
    pub fn from_system(system: E, plan: RunPlan) -> Result<Self> {
        #[derive(serde::Serialize)]
        struct Input<'a, E> {
            plan: &'a RunPlan,
            system: &'a E,
        }
        let json = serde_json::to_string(&Input { plan: &plan, system: &system })
            .map_err(|e| Error::Io(std::io::Error::other(e)))?;
        Ok(Self {
            system,
            plan,
            source: Source::Code { json },
            model_crc32: std::sync::OnceLock::new(),
            scene_path: None,
            restart: None,
            model: None,
            figures: None,
        })
    }

    /// The plan of the run.
    pub fn plan(&self) -> &RunPlan {
        &self.plan
    }

    /// Runs into the folder `out` (created if needed; existing output files of an
    /// earlier run are replaced), calling `progress` after every step.
    ///
    /// # Errors
    /// [`Error::Scene`] for invalid options; [`Error::Checkpoint`] for a checkpoint to resume from that is
    /// refused or missing; [`Error::Io`] naming the file if an output cannot be
    /// written; [`Error::Diverged`] if a step diverges, after the last good
    /// state has been written (`series.csv` row, `final.json`, `summary.json`).
    pub fn run(&self, out: &Path, opts: &RunOptions, progress: &mut dyn FnMut(&Progress)) -> Result<RunOutcome> {
        let mut control = |p: &Progress| {
            progress(p);
            ControlFlow::Continue(())
        };
        self.run_with(out, opts, &mut control).0
    }

    /// [`Runner::run`] with a `control` callback after every step that may stop the run: its
    /// [`ControlFlow::Break`] ends the call as [`RunOptions::stop_after`] does (a checkpoint to resume from,
    /// [`Status::Stopped`]) unless that step was the run's last. Returns the outcome and the system as the run
    /// left it (its last step, the last good one if a step diverged; `None` if the run did not start: invalid
    /// options, a refused checkpoint, an output folder that cannot be prepared). A caller that steps the
    /// system on after the run (the Python binding) keeps it.
    ///
    /// # Errors
    /// As [`Runner::run`].
    pub fn run_with(
        &self,
        out: &Path,
        opts: &RunOptions,
        control: &mut dyn FnMut(&Progress) -> ControlFlow<()>,
    ) -> (Result<RunOutcome>, Option<E>) {
        let mut live = match self.begin(out, opts) {
            Ok(live) => live,
            Err(e) => return (Err(e), None),
        };
        let started = Instant::now();
        let end_step = live.first_step.saturating_add(self.plan.steps);
        let result = self
            .steps(out, opts, &mut live, control, (end_step, &started))
            .and_then(|ending| self.finish(out, opts, &mut live, ending, (end_step, &started)));
        (result, Some(live.sys))
    }

    /// The checks of the options and the run in progress, started or resumed.
    fn begin(&self, out: &Path, opts: &RunOptions) -> Result<Live<E>> {
        check_options(opts)?;
        check_built(opts)?;
        if opts.figures && self.figures.is_none() {
            return Err(Error::Scene(
                "figures: this run has no figure drawer (a run of a scene file draws its engine's; a system built \
                 in code draws them after the run with ballast::report::draw_run_figures)"
                    .into(),
            ));
        }
        if self.plan.output_every == 0 {
            return Err(Error::Scene("output.every: must be at least 1, got 0".into()));
        }
        let mut live = if opts.resume { self.resume(out, opts)? } else { self.start(out, opts)? };
        live.sys.set_threads(opts.threads.max(1));
        let threads = live.sys.threads_used(opts.threads.max(1));
        if let Some(t) = live.cycle_times.as_mut() {
            t.set_threads(threads);
        }
        Ok(live)
    }

    /// The steps of the run up to `end_step` (or `opts.stop_after`, a stop asked by `control`, equilibrium, a
    /// step that fails), with their outputs and checkpoints; the wall time counted from `started`.
    fn steps(
        &self,
        out: &Path,
        opts: &RunOptions,
        live: &mut Live<E>,
        control: &mut dyn FnMut(&Progress) -> ControlFlow<()>,
        (end_step, started): (u64, &Instant),
    ) -> Result<Ending<E::Stats>> {
        let plan = &self.plan;
        let last = opts.stop_after.map_or(end_step, |n| end_step.min(live.sys.steps_done().saturating_add(n)));
        let cycles_total = plan.cycles.map(|c| {
            let total = end_step.saturating_sub(live.first_step) as f64 * self.system.dt();
            (c.frequency * total).round() as u64
        });
        let (vtk_dir, pvd_path) = (out.join(layout::VTK_DIR), out.join(layout::PVD));
        let wall0 = live.summary.wall_time_s;
        let mut checkpointed = Instant::now();
        let mut last_stats: Option<(E::Stats, bool)> = None;
        let mut diverged = None;
        let mut at_equilibrium = false;
        let potential = plan.equilibrium.is_some_and(|e| e.needs_potential());
        while live.sys.steps_done() < last {
            let stats = match live.sys.step() {
                Ok(s) => s,
                Err(e) => {
                    diverged = Some(e);
                    break;
                }
            };
            let k = live.sys.steps_done();
            let common = E::summary(&stats);
            live.summary.add(&common);
            if let Some(rule) = &plan.equilibrium {
                let en = live.sys.energies(&stats, potential);
                at_equilibrium = live.summary.equilibrium.observe(rule, rule.holds(en.kinetic, en.potential));
            }
            // The last step's row comes after a kept checkpoint (`finish`) when it is off the output grid.
            let last_row = k == end_step && !opts.keep_checkpoint;
            let written = k.is_multiple_of(plan.output_every) || last_row || at_equilibrium;
            let wall = wall0 + started.elapsed().as_secs_f64();
            self.record_step(live, &stats, (written, wall), opts.vtk_every, (&vtk_dir, &pvd_path))?;
            last_stats = Some((stats, written));
            let flow = control(&Progress {
                step: k,
                end_step,
                time: common.time,
                kinetic_energy: common.kinetic_energy,
                contacts: common.contacts,
                cycles: cycles_total.map(|t| (live.cycles_done, t)),
                settlement: live.cycles.as_ref().and_then(|(s, _)| live.sys.settlement(s)),
            });
            if opts.checkpoint_every_s > 0.0 && checkpointed.elapsed().as_secs_f64() >= opts.checkpoint_every_s {
                live.summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
                self.checkpoint(out, live)?;
                checkpointed = Instant::now();
            }
            if at_equilibrium || flow.is_break() {
                break;
            }
        }
        live.summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
        Ok(Ending { last_stats, diverged, at_equilibrium })
    }

    /// The outputs of step `k` (made, with its statistics `stats`, at the run's wall time `wall_s`): its series
    /// row when `written`, the cycle table's row (flushed), the cycle's wall time and positions at a cycle's end, a
    /// VTK snapshot every `vtk_every` steps (into `vtk_dir`, listed in the `.pvd` file).
    fn record_step(
        &self,
        live: &mut Live<E>,
        stats: &E::Stats,
        (written, wall_s): (bool, f64),
        vtk_every: u64,
        (vtk_dir, pvd_path): (&Path, &Path),
    ) -> Result<()> {
        let k = live.sys.steps_done();
        if written {
            live.series.write(&live.sys.series_row(stats))?;
        }
        if let (Some(c), Some((state, table))) = (self.plan.cycles, live.cycles.as_mut()) {
            live.sys.cycle_step(state, stats);
            let done = cycles_at(live.sys.time(), c.frequency, live.sys.dt());
            if done > live.cycles_done {
                table.write(&live.sys.cycle_end(state, done))?;
                table.flush()?;
                live.cycles_done = done;
                if let Some(t) = live.cycle_times.as_mut() {
                    t.record(done, wall_s)?;
                }
                if let Some(p) = live.positions.as_mut() {
                    let bodies = p.reference().bodies.clone();
                    p.append(&live.sys.configuration_of(&bodies))?;
                }
            }
        }
        if vtk_every > 0 && k.is_multiple_of(vtk_every) {
            io::create_output_dir(vtk_dir)?;
            live.sys.snapshot(vtk_dir, &mut live.snapshots)?;
            live.snapshots.write(pvd_path)?;
        }
        Ok(())
    }

    /// The end of a run (the last step's statistics and whether its row was written, the failure, whether it
    /// ended at equilibrium): on a stop, a checkpoint; otherwise the last row, `final.json`, `contacts.csv`,
    /// `summary.json`, the figures, `final_scene.toml`, and the failure returned.
    fn finish(
        &self,
        out: &Path,
        opts: &RunOptions,
        live: &mut Live<E>,
        Ending { last_stats, diverged, at_equilibrium }: Ending<E::Stats>,
        (end_step, started): (u64, &Instant),
    ) -> Result<RunOutcome> {
        let plan = &self.plan;
        let end = match (&diverged, at_equilibrium) {
            (Some(Error::Stalled { .. }), _) => RunEnd::Stalled,
            (Some(_), _) => RunEnd::Diverged,
            (None, true) => RunEnd::Equilibrium,
            (None, false) => RunEnd::Finished,
        };
        let report = RunReport::new(
            E::NAME,
            E::ITERATIVE,
            &live.summary,
            end,
            live.sys.body_count(),
            live.sys.threads_used(opts.threads.max(1)),
            live.sys.dt(),
            live.sys.time(),
            plan.cycles.map(|_| live.cycles_done),
        );
        let kinetic_energy = last_stats.map_or(0.0, |(s, _)| E::summary(&s).kinetic_energy);
        let (step, time) = (live.sys.steps_done(), live.sys.time());
        let solver_changes = live.solver_changes.clone();
        let outcome = |status| RunOutcome {
            status,
            step,
            time,
            end_step,
            kinetic_energy,
            report: report.clone(),
            elapsed_s: started.elapsed().as_secs_f64(),
            out: out.to_path_buf(),
            solver_changes: solver_changes.clone(),
        };
        if diverged.is_none() && !at_equilibrium && step < end_step {
            // Stopped on request: a checkpoint and nothing that looks final.
            self.checkpoint(out, live)?;
            live.series.flush()?;
            return Ok(outcome(Status::Stopped));
        }
        let keep = opts.keep_checkpoint && diverged.is_none() && !at_equilibrium;
        if keep {
            // Before the last off-grid row: a run extended from it writes the rows of the longer run.
            self.checkpoint(out, live)?;
        }
        if let Some((stats, false)) = last_stats {
            // The run stopped off the output grid: its last good step gets a row.
            live.series.write(&live.sys.series_row(&stats))?;
        }
        live.series.flush()?;
        let state = live.cycles.take().map(|(state, table)| (state, table.finish()));
        if let Some((_, Err(e))) = state {
            return Err(e);
        }
        let cycle_state = state.map(|(s, _)| s);
        live.sys.final_state().write(&out.join(layout::FINAL))?;
        crate::engine::contacts::write(&out.join(layout::CONTACTS), &live.sys.contact_rows())?;
        io::write_json(&out.join(layout::SUMMARY), &report)?;
        if let (true, Some(draw)) = (opts.figures, &self.figures) {
            draw(out, cycle_state.as_ref())?;
        }
        if let Some(e) = diverged {
            return Err(e);
        }
        if !keep {
            io::remove_stale(out, layout::CHECKPOINT)?;
        }
        if let (Some(restart), Some(path)) = (&self.restart, &self.scene_path) {
            let text = format!(
                "# Written by ballast {}: the state of {} at t = {} s (step {}).\n\
                 # Rerun it with `ballast run`; time restarts at 0.\n\n{}",
                env!("CARGO_PKG_VERSION"),
                path.display().to_string().replace(char::is_control, "?"),
                live.sys.time(),
                live.sys.steps_done(),
                restart(&live.sys)?
            );
            io::write_text(out, layout::FINAL_SCENE, &text)?;
        }
        Ok(outcome(Status::Ended(end)))
    }

    /// A fresh run: the output folder prepared, the first rows and snapshot written.
    fn start(&self, out: &Path, opts: &RunOptions) -> Result<Live<E>> {
        let sys = self.system.clone();
        folder::prepare(
            out,
            &[
                layout::FINAL_SCENE,
                layout::CHECKPOINT,
                layout::SOLVER_CHANGES,
                layout::CYCLES,
                layout::FINAL,
                layout::CONTACTS,
                layout::SUMMARY,
                layout::CYCLE_BODIES,
                layout::CYCLE_DISPLACEMENTS,
                layout::CYCLE_TIMES,
                layout::SCENE,
                layout::INITIAL_STATE,
            ],
        )?;
        self.write_records(out)?;
        let series = TableWriter::create(&out.join(layout::SERIES), &sys.series_header())?;
        let mut snapshots = PvdCollection::new();
        if opts.vtk_every > 0 {
            // The initial state is the first snapshot.
            let vtk_dir = out.join(layout::VTK_DIR);
            io::create_output_dir(&vtk_dir)?;
            sys.snapshot(&vtk_dir, &mut snapshots)?;
            snapshots.write(&out.join(layout::PVD))?;
        }
        let mut summary = RunSummary::default();
        if let Some(s) = sys.initial_summary() {
            summary.max_overlap = s.max_overlap;
            summary.final_max_overlap = s.max_overlap;
        }
        let (cycles, positions) = match self.plan.cycles {
            Some(c) => {
                let state = sys.cycle_start(c.body)?;
                let table = TableWriter::create(&out.join(layout::CYCLES), &sys.cycle_header())?;
                let positions = if c.positions {
                    let reference = sys.configuration();
                    let names = body_names(&sys, &reference.bodies);
                    Some(PositionsWriter::create(out, reference, &names)?)
                } else {
                    None
                };
                (Some((state, table)), positions)
            }
            None => (None, None),
        };
        let first_step = sys.steps_done();
        Ok(Live {
            sys,
            summary,
            series,
            snapshots,
            cycle_times: cycles.as_ref().map(|_| CycleTimes::create(out)),
            cycles,
            cycles_done: 0,
            positions,
            first_step,
            solver_changes: vec![],
        })
    }

    /// Writes the record of the run's input: the copy of the scene (or the
    /// initial state of a system built in code) and `run.json`.
    fn write_records(&self, out: &Path) -> Result<()> {
        let info = RunInfo::new(E::NAME, self.plan.seed, (self.plan.steps, self.system.dt()), self.model.clone());
        self.source.write_records(out, &info)
    }

    /// The run continued from the checkpoint in `out`, checked against the plan,
    /// the initial system and the files. The record of the input is written
    /// again (the checkpoint holds the CRC-32 of the scene text: it is the same, or with `change_solver` the
    /// same but for the solver keys, whose changes are recorded and checkpointed at once; with `extend` it may
    /// differ in its duration too). The outputs of an earlier end (`final.json`, `contacts.csv`,
    /// `summary.json`, `final_scene.toml`) are removed.
    fn resume(&self, out: &Path, opts: &RunOptions) -> Result<Live<E>> {
        let change_solver = opts.change_solver;
        let path = folder::checkpoint_to_resume(out)?;
        let mut cp = match (&self.source, opts.extend) {
            (Source::Scene { text }, true) => extend::load(out, text, change_solver)?,
            (Source::Code { .. }, true) => {
                return Err(Error::Scene(
                    "extend: a run of a system built in code runs its plan's length; extend a run of a scene".into(),
                ))
            }
            _ if change_solver => solver_change::load(out, (self.source.crc32(), self.model_crc32()))?,
            (source, false) => {
                Checkpoint::<E, E::CycleState>::load(out, E::NAME, self.source.crc32()).map_err(|e| match source {
                    Source::Scene { text } => extend::hint(e, out, text),
                    Source::Code { .. } => e,
                })?
            }
        };
        let bad = |msg: String| folder::invalid_checkpoint(&path, msg);
        let changed = if change_solver { cp.system.change_solver(&self.system)? } else { Vec::new() };
        folder::check_resumed(&path, "", &cp.system, &self.system)?;
        let plan = &self.plan;
        let first = self.system.steps_done();
        let end = first.saturating_add(plan.steps);
        let step = cp.system.steps_done();
        if opts.extend && cp.first_step == first && step > end {
            return Err(extend::too_short(&path, (step, end), self.system.dt()));
        }
        if cp.first_step != first || cp.step != step || !(first..=end).contains(&step) {
            return Err(bad(format!(
                "its step {} (engine at {step}, started at {}) is not within this run's steps {first}..={end}",
                cp.step, cp.first_step
            )));
        }
        if cp.summary.steps != step - first {
            return Err(bad(format!(
                "its summary counts {} steps, the engine made {}",
                cp.summary.steps,
                step - first
            )));
        }
        let every = plan.output_every.max(1);
        let rows = step / every - first / every;
        if cp.series_rows != rows {
            return Err(bad(format!("{} rows of series.csv, {rows} expected after step {step}", cp.series_rows)));
        }
        let series = TableWriter::resume(&out.join(layout::SERIES), cp.series_bytes, cp.series_rows, cp.series_crc32)?;
        let (cycles, positions) = match (plan.cycles, cp.cycles) {
            (Some(c), Some(state)) => {
                let done = cycles_at(cp.system.time(), c.frequency, cp.system.dt());
                if cp.cycles_done != done || cp.cycles_rows != done {
                    return Err(bad(format!(
                        "{} cycles recorded ({} rows), {done} completed at t = {} s",
                        cp.cycles_done,
                        cp.cycles_rows,
                        cp.system.time()
                    )));
                }
                // The per-cycle state must start where this run's does.
                let start = self.system.cycle_start(c.body)?;
                state.check(&start, cp.system.body_count(), done).map_err(|e| bad(format!("per-cycle state: {e}")))?;
                let table =
                    TableWriter::resume(&out.join(layout::CYCLES), cp.cycles_bytes, cp.cycles_rows, cp.cycles_crc32)?;
                let positions = match (c.positions, cp.positions) {
                    (true, Some(reference)) => {
                        reference.check(E::DOF, cp.system.body_count()).map_err(|e| bad(e.to_string()))?;
                        if reference != self.system.configuration() {
                            return Err(bad("the followed bodies or their start differ from the scene's".into()));
                        }
                        let names = body_names(&self.system, &reference.bodies);
                        Some(PositionsWriter::resume(out, reference, &names, done, cp.positions_crc32)?)
                    }
                    (false, None) if cp.positions_crc32 == 0 => None,
                    _ => return Err(bad("the positions output does not match the scene's".into())),
                };
                (Some((state, table)), positions)
            }
            (None, None) => {
                let counts = [cp.cycles_bytes, cp.cycles_rows, cp.cycles_done, cp.cycles_crc32.into()];
                if counts != [0; 4] || cp.positions.is_some() || cp.positions_crc32 != 0 {
                    return Err(bad("per-cycle counters or positions in a run without per-cycle output".into()));
                }
                (None, None)
            }
            _ => return Err(bad("the per-cycle output does not match the scene's".into())),
        };
        if cp.snapshots.entries().iter().any(|e| !e.parts.iter().all(|p| out.join(&p.file).is_file())) {
            return Err(bad("a snapshot it lists is missing".into()));
        }
        for stale in [layout::FINAL_SCENE, layout::FINAL, layout::CONTACTS, layout::SUMMARY] {
            io::remove_stale(out, stale)?;
        }
        self.write_records(out)?;
        let (step, time_s) = (cp.system.steps_done(), cp.system.time());
        let solver_changes: Vec<SolverChange> =
            changed.into_iter().map(|[key, before, after]| SolverChange { step, time_s, key, before, after }).collect();
        let mut live = Live {
            sys: cp.system,
            summary: cp.summary,
            series,
            snapshots: cp.snapshots,
            cycle_times: match &cycles {
                Some(_) => Some(CycleTimes::resume(out, cp.cycles_done, cp.cycle_wall_start_s)?),
                None => None,
            },
            cycles,
            cycles_done: cp.cycles_done,
            positions,
            first_step: first,
            solver_changes,
        };
        if !live.solver_changes.is_empty() {
            // The change is recorded, then the checkpoint takes the new scene: a later plain resume goes on.
            solver_change::record(out, &live.solver_changes)?;
            self.checkpoint(out, &mut live)?;
        }
        Ok(live)
    }

    /// [`solver_change::model_crc32`] of the scene's text, `None` for a system built in code.
    fn model_crc32(&self) -> Option<u32> {
        *self.model_crc32.get_or_init(|| match &self.source {
            Source::Scene { text } => solver_change::model_crc32(text, E::SOLVER_KEYS),
            Source::Code { .. } => None,
        })
    }

    /// Writes `checkpoint.json` for the run in progress.
    fn checkpoint(&self, out: &Path, live: &mut Live<E>) -> Result<()> {
        let series_bytes = live.series.sync()?;
        let (cycles_bytes, cycles_rows, cycles_crc32) = match live.cycles.as_mut() {
            Some((_, t)) => (t.sync()?, t.rows(), t.crc32()),
            None => (0, 0, 0),
        };
        if let Some(p) = live.positions.as_mut() {
            p.sync()?;
        }
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            engine: E::NAME.to_string(),
            source_crc32: self.source.crc32(),
            model_crc32: self.model_crc32(),
            first_step: live.first_step,
            step: live.sys.steps_done(),
            series_bytes,
            series_rows: live.series.rows(),
            series_crc32: live.series.crc32(),
            cycles_bytes,
            cycles_rows,
            cycles_crc32,
            summary: live.summary,
            system: live.sys.clone(),
            snapshots: live.snapshots.clone(),
            cycles: live.cycles.as_ref().map(|(s, _)| s.clone()),
            cycles_done: live.cycles_done,
            positions: live.positions.as_ref().map(|p| p.reference().clone()),
            positions_crc32: live.positions.as_ref().map_or(0, |p| p.crc32()),
            cycle_wall_start_s: live.cycle_times.as_ref().and_then(CycleTimes::start_wall_s),
        }
        .write(out)?;
        Ok(())
    }
}

/// The names of `bodies` of `sys` (empty where a body has none).
pub(crate) fn body_names<E: Engine>(sys: &E, bodies: &[usize]) -> Vec<String> {
    let state = sys.final_state();
    bodies.iter().map(|&i| state.bodies.get(i).map(|b| b.name.clone()).unwrap_or_default()).collect()
}
