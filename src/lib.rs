//! `ballast`: granular mechanics under cyclic loading, for railway ballast settlement.
//!
//! Two engines behind one interface ([`engine::Engine`]):
//! - [`nscd`]: non-smooth contact dynamics of rigid 2D polygons and discs
//!   (Moreau–Jean θ-method, nonlinear Gauss–Seidel with exact Coulomb friction,
//!   shadow-overlap detection, viscoelastic sublayer; Saussine et al. 2006);
//! - [`md`]: soft-contact molecular dynamics of 3D spheres (Hertz–Mindlin and
//!   linear spring–dashpot laws, Verlet and Gear integrators, walls, servo walls,
//!   symmetry planes; Karrech et al. 2007, David et al.).
//!
//! Around them, bottom to top (ARCHITECTURE.md draws the layers):
//! - [`engine`]: the engine contract (the trait, what a step reports, contacts, final state, the
//!   generalised positions a cyclic driver reads and writes back, the relaxation service);
//! - [`run`]: the run loop shared by the engines (equilibrium stop, outputs,
//!   checkpoints and resume, divergence handling, progress callback);
//! - [`settlement`]: the settlement-acceleration driver (Karrech et al. 2007, Fig. 10) over any engine;
//! - [`scene`]: TOML scene files of either engine, their validation (one-line
//!   errors naming the field), building a system, saving a state as a scene;
//! - [`report`]: the figures of a run drawn from its folder;
//! - [`open`]: a scene file opened on its engine and run (the one registration point of the engines);
//! - [`io`]: file formats (CSV through serde row types, JSON, VTK for ParaView, PNG + SVG figures) and the
//!   layout of a run folder;
//! - [`scenarios`]: ready-made scenes (the Saussine pentagon sample and its
//!   loading, the Karrech sphere sample, the Luding triaxial box, the peers' bed);
//! - [`studies`]: the papers' experiments run end to end (the Saussine sample,
//!   settlement and the §3.2/§3.3/§4.2 studies with runs side by side, the
//!   Karrech and Luding tests), writing their scenes, runs, tables and figures,
//!   with progress through a [`studies::RunDisplay`];
//! - [`geometry`]: convex polygons, discs and compounds; [`clock`]: the exact
//!   simulation and cycle clocks; [`team`]: the two-thread team of a step;
//!   [`error`]: the crate's error type.
//!
//! All quantities are SI and `f64`.
//!
//! A scene file, run into an output folder (as `ballast run` does):
//! ```no_run
//! use ballast::open::run_file;
//! use ballast::run::RunOptions;
//! let out = run_file("examples/sleeper_load.toml".as_ref(), "out/sleeper".as_ref(), &RunOptions::default(), &mut |_| {})?;
//! println!("{} steps, t = {} s, max overlap {:e} m", out.step, out.time, out.report.max_overlap_m);
//! # Ok::<(), ballast::Error>(())
//! ```
//! A system built in code (here from a scene, then changed), stepped through the
//! same loop, with its generalised positions read and written back:
//! ```
//! use ballast::engine::Engine;
//! use ballast::run::{RunOptions, RunPlan, Runner};
//! use ballast::scene::{Scene, SceneFile}; // SceneFile: reading and writing a scene file
//! let scene = Scene::load("examples/block_on_floor.toml")?;
//! let mut sys = scene.build()?; // nscd::System: plain serde data
//! let mut c = sys.configuration(); // (x, y, θ) of every mobile body
//! c.q[1] += 1e-3; // the first one 1 mm higher
//! sys.set_configuration(&c)?; // velocities zeroed, warm start forgotten
//! let out = std::env::temp_dir().join(format!("ballast-doc-{}", std::process::id()));
//! let plan = RunPlan::new(200, 10); // 200 steps, a row of series.csv every 10
//! let run = Runner::from_system(sys, plan)?.run(&out, &RunOptions::default(), &mut |_| {})?;
//! assert_eq!(run.step, 200);
//! assert!(run.report.max_overlap_m < 1e-6);
//! # std::fs::remove_dir_all(&out).ok();
//! # Ok::<(), ballast::Error>(())
//! ```
//! Steps can also be made one at a time ([`nscd::System::step`],
//! [`md::MdSystem::step`]); `examples/library_run.rs` shows both engines.

#![deny(missing_docs)]

pub mod clock;
pub mod engine;
pub mod error;
pub mod geometry;
pub mod io;
pub mod md;
pub mod nscd;
pub mod open;
pub mod plane;
pub mod report;
pub mod run;
pub mod scenarios;
pub mod scene;
pub mod settlement;
pub mod space;
pub mod studies;
pub mod team;

pub use error::{Error, Result};
