//! What a run is asked to do: its plan ([`RunPlan`]: steps, output period, equilibrium stop, loading cycles,
//! seed), the options of one invocation ([`RunOptions`]: checkpoints, `--resume`, a stop, snapshots, threads,
//! figures, the overrides applied when a scene is opened) and their checks, and what an output folder holds
//! for a study's resume ([`Prior`]).

use super::Equilibrium;
use crate::error::{Error, Result};
use crate::io::layout;
use std::path::Path;

/// What a run is asked to do, besides its system.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RunPlan {
    /// Steps to make (the run may end earlier at equilibrium).
    pub steps: u64,
    /// Steps between two rows of `series.csv`, ≥ 1 (the last step always has a row).
    pub output_every: u64,
    /// The equilibrium stop, if any.
    pub equilibrium: Option<Equilibrium>,
    /// The per-cycle output, if any.
    pub cycles: Option<CyclePlan>,
    /// Random seed of the scene, recorded in `run.json`.
    pub seed: u64,
}

impl RunPlan {
    /// `steps` steps with a row of `series.csv` every `output_every` steps.
    pub fn new(steps: u64, output_every: u64) -> Self {
        Self { steps, output_every, equilibrium: None, cycles: None, seed: 0 }
    }
}

/// The per-cycle output of a run (`cycles.csv`, and the positions file).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CyclePlan {
    /// Loading frequency (Hz): a cycle lasts `1/frequency` from t = 0.
    pub frequency: f64,
    /// The followed body (NSCD: the sleeper).
    pub body: Option<usize>,
    /// Write the positions of every mobile body at each cycle end
    /// ([`crate::run::positions`]).
    pub positions: bool,
}

/// How a run is carried out; the numbers do not depend on any of it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunOptions {
    /// Wall-clock seconds between checkpoints (`checkpoint.json`); 0: none.
    pub checkpoint_every_s: f64,
    /// Continue from the checkpoint in the output folder.
    pub resume: bool,
    /// With `resume`: accept a scene whose `[nscd]` solver keys differ from those the run was checkpointed with,
    /// every other key the same ([`super::solver_change`]); the run goes on with the new settings and records
    /// the change in `solver_changes.csv`. A run of a system built in code, or with `[settlement]`, refuses it.
    pub change_solver: bool,
    /// With `resume`: accept a scene whose `[simulation] duration` differs from the run's (a `length` override
    /// is such a change), every other key the same (and the solver keys with `change_solver`): the run goes on
    /// to the new end, which may not come before the step it has reached ([`super::extend`]). A finished run
    /// has no checkpoint unless it ran with `keep_checkpoint`. A run of a system built in code, or with
    /// `[settlement]`, refuses it.
    pub extend: bool,
    /// At the end of a finished run, keep a checkpoint of its last step (`checkpoint.json`) from which `extend`
    /// continues it (refused with `[settlement]`).
    pub keep_checkpoint: bool,
    /// Stop after this many steps in this invocation, leaving a checkpoint.
    pub stop_after: Option<u64>,
    /// A VTK snapshot every this many steps (0: none).
    pub vtk_every: u64,
    /// Threads of a step (1 or 2).
    pub threads: usize,
    /// Draw the run's figures at the end (a run of a scene file, [`crate::open::run_file`], or one given
    /// [`super::Runner::with_figures`]; else the run refuses it).
    pub figures: bool,
    /// A scene file's `[simulation] duration` replaced for this run (for quick
    /// tries); the scene copy in the output folder records it. `None`: the
    /// scene's own.
    pub length: Option<RunLength>,
    /// A 2D scene run on this engine instead of its own (`ballast run --engine`):
    /// `"nscd"` or `"md"` (the planar MD engine); the scene copy in the output
    /// folder records it. `None`: the scene's own.
    pub engine: Option<String>,
}

/// The length of a run that replaces a scene's `[simulation] duration`
/// ([`RunOptions::length`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RunLength {
    /// Simulated duration (s), > 0.
    Duration(f64),
    /// Number of time steps, ≥ 1 (duration = steps · dt).
    Steps(u64),
}

impl Default for RunOptions {
    /// Checkpoints every 5 minutes, no snapshots, no figures, 2 threads on a
    /// machine with 2 cores or more.
    fn default() -> Self {
        Self {
            checkpoint_every_s: 300.0,
            resume: false,
            change_solver: false,
            extend: false,
            keep_checkpoint: false,
            stop_after: None,
            vtk_every: 0,
            threads: default_threads(),
            figures: false,
            length: None,
            engine: None,
        }
    }
}

/// Cores of the machine (1 if unknown).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Threads of a single run: 2 when the machine has 2 cores or more (the split
/// NLGS solver and the MD force evaluation use at most 2).
pub fn default_threads() -> usize {
    cores().min(2)
}

/// Checks the options; the message names the option.
pub fn check_options(opts: &RunOptions) -> Result<()> {
    if !(opts.checkpoint_every_s.is_finite() && opts.checkpoint_every_s >= 0.0) {
        return Err(Error::Scene(format!(
            "checkpoint_every_s: must be a non-negative number of seconds, got {}",
            opts.checkpoint_every_s
        )));
    }
    if opts.figures {
        crate::io::figures::require()?;
    }
    if opts.threads == 0 {
        return Err(Error::Scene("threads: must be at least 1, got 0".into()));
    }
    if opts.change_solver && !opts.resume {
        return Err(Error::Scene("change_solver: changes the solver of a resumed run; set resume too".into()));
    }
    if opts.extend && !opts.resume {
        return Err(Error::Scene("extend: continues a resumed run past its end; set resume too".into()));
    }
    Ok(())
}

/// Refuses the options that change a scene (`length`, `engine`): they are applied when a scene file is opened
/// ([`crate::open::open`]), and a run of a system already built cannot take them.
///
/// # Errors
/// [`Error::Scene`] naming the option.
pub fn check_built(opts: &RunOptions) -> Result<()> {
    if opts.length.is_some() {
        return Err(Error::Scene(
            "length: a built system runs its plan's length; apply it to the scene when opening it (ballast::open)"
                .into(),
        ));
    }
    if let Some(engine) = &opts.engine {
        return Err(Error::Scene(format!(
            "engine: a built system runs on its own engine, not '{}'; choose the engine when opening the scene \
             (ballast::open)",
            crate::error::clip(engine)
        )));
    }
    Ok(())
}

/// What an output folder holds for `--resume`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Prior {
    /// A finished run: `marker` is there and no checkpoint.
    Finished,
    /// A run to continue from its checkpoint.
    Checkpointed,
    /// Nothing to continue: start afresh.
    Nothing,
}

impl Prior {
    /// The state of `dir` as `--resume` (`resume`) sees it; without `--resume`, always `Nothing`.
    pub fn of(dir: &Path, marker: &str, resume: bool) -> Self {
        let checkpoint = dir.join(layout::CHECKPOINT).exists();
        match (resume, checkpoint) {
            (false, _) => Prior::Nothing,
            (true, true) => Prior::Checkpointed,
            (true, false) if dir.join(marker).exists() => Prior::Finished,
            (true, false) => Prior::Nothing,
        }
    }
}
