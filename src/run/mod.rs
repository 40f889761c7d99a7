//! Running a simulation: the run loop over any [`Engine`](crate::engine::Engine) ([`Runner`]: equilibrium
//! stop, outputs, checkpoints and `--resume`, divergence handling, progress callback) and the run's records
//! ([`summary`], [`checkpoint`], [`positions`], [`cycle_times`]). A scene file of either engine is opened and run by
//! [`crate::open::run_file`]:
//!
//! ```no_run
//! use ballast::open::run_file;
//! use ballast::run::RunOptions;
//! let outcome = run_file("examples/block_on_floor.toml".as_ref(), "out/block".as_ref(), &RunOptions::default(), &mut |_| {})?;
//! println!("{} steps, t = {} s, max overlap {:e} m", outcome.step, outcome.time, outcome.report.max_overlap_m);
//! # Ok::<(), ballast::Error>(())
//! ```
//! A system built in code goes through [`Runner::from_system`] with a
//! [`RunPlan`] (see the crate documentation and `examples/library_run.rs`).

pub mod checkpoint;
pub mod cycle_times;
mod equilibrium;
pub mod extend;
pub mod folder;
pub mod plan;
pub mod positions;
mod runner;
pub mod solver_change;
pub mod summary;

pub use checkpoint::Checkpoint;
pub use equilibrium::{Equilibrium, EquilibriumWatch, DEFAULT_EQUILIBRIUM_STEPS};
pub use plan::{check_built, check_options, cores, default_threads, CyclePlan, Prior, RunLength, RunOptions, RunPlan};
pub(crate) use runner::body_names;
pub use runner::{Figures, Progress, Restart, RunOutcome, Runner, Status};
pub use solver_change::SolverChange;
pub use summary::{RunEnd, RunReport, RunSummary};
