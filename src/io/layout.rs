//! The layout of a run folder: every file name a run writes, in one place, for the run loop
//! ([`crate::run::Runner`]), the settlement driver ([`crate::settlement`]), the figures drawn from a folder and
//! the studies that read folders back. The same files for every engine:
//!
//! - [`SERIES`]: one row of step statistics every `output.every` steps (the engine's row type);
//! - [`CYCLES`]: per-cycle statistics with `output.cycles`, and with `output.cycles.positions` the reference
//!   coordinates of every followed body ([`CYCLE_BODIES`]) and their displacement at each cycle end
//!   ([`CYCLE_DISPLACEMENTS`], `.npy`; [`crate::run::positions`]), and the wall-clock time of each cycle
//!   ([`CYCLE_TIMES`], [`crate::run::cycle_times`]);
//! - [`FINAL`]: the state of every body (and wall) at the end ([`crate::engine::FinalState`]);
//! - [`CONTACTS`]: every contact at the end with its point, normal and forces ([`crate::engine::contacts`]);
//! - [`SUMMARY`]: wall time and speed, mean contacts, overlaps, NLGS iterations
//!   ([`crate::run::RunReport`]; an accelerated run's own summary);
//! - [`SCENE`]: a copy of the input scene (the text the run read), or [`INITIAL_STATE`] for a system built
//!   in code;
//! - [`FINAL_SCENE`]: the input scene with the final state, to restart from;
//! - [`RUN_INFO`]: seed, engine, crate version, number of steps, time step ([`super::RunInfo`]);
//! - [`CHECKPOINT`]: the whole state, every few minutes, for `--resume` ([`crate::run::Checkpoint`]);
//! - a study's task that failed: [`FAILED`], its one-line error ([`crate::studies::tasks`]);
//! - with `vtk_every`: [`VTK_DIR`]`/*.vtp` and [`PVD`], snapshots that ParaView opens and animates
//!   ([`super::vtk`]);
//! - an accelerated run (Karrech et al. 2007, Fig. 10): [`SETTLEMENT`] per cycle, [`JUMPS`] per jump, and
//!   [`ERRORS`] against a full run when one is given;
//! - figures as `<stem>.png` + `<stem>.svg`.

/// Step statistics.
pub const SERIES: &str = "series.csv";
/// Per-cycle statistics.
pub const CYCLES: &str = "cycles.csv";
/// State at the end.
pub const FINAL: &str = "final.json";
/// Statistics of the run.
pub const SUMMARY: &str = "summary.json";
/// Seed, engine, version, steps.
pub const RUN_INFO: &str = "run.json";
/// Copy of the scene the run read (the file's text, or its serialised form with a
/// [`crate::run::RunOptions::length`] applied).
pub const SCENE: &str = "scene.toml";
/// Serde form of the initial system of a run built in code.
pub const INITIAL_STATE: &str = "initial_state.json";
/// The final state as a scene to restart from.
pub const FINAL_SCENE: &str = "final_scene.toml";
/// The contacts at the end, with their forces.
pub const CONTACTS: &str = "contacts.csv";
/// ParaView collection of the snapshots.
pub const PVD: &str = "run.pvd";
/// Folder of the snapshots.
pub const VTK_DIR: &str = "vtk";
/// The checkpoint to resume from.
pub const CHECKPOINT: &str = "checkpoint.json";
/// The solver settings a resumed run changed (`crate::run::solver_change`).
pub const SOLVER_CHANGES: &str = "solver_changes.csv";
/// The one-line error of a study's run that failed (a diverged run), which the study's summary reports
/// however the run was launched; removed when the run is run again and ends.
pub const FAILED: &str = "failed.txt";
/// The reference coordinates of the bodies whose positions are followed cycle by cycle.
pub const CYCLE_BODIES: &str = "cycle_bodies.csv";
/// Their displacements at each cycle end.
pub const CYCLE_DISPLACEMENTS: &str = "cycle_displacements.npy";
/// The wall-clock time of each cycle (`crate::run::cycle_times`).
pub const CYCLE_TIMES: &str = "cycle_times.csv";
/// The per-cycle table of an accelerated run.
pub const SETTLEMENT: &str = "settlement.csv";
/// The per-jump table of an accelerated run.
pub const JUMPS: &str = "jumps.csv";
/// The errors of an accelerated run against a full run.
pub const ERRORS: &str = "errors.csv";
