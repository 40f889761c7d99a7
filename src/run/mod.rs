//! Running a simulation: the [`Engine`](crate::engine::Engine) trait both engines implement, the run
//! loop over it ([`Runner`]: equilibrium stop, outputs, checkpoints and
//! `--resume`, divergence handling, progress callback) and [`run_file`], which
//! runs a scene file of either engine.
//!
//! A scene file, in a few lines:
//! ```no_run
//! use ballast::run::{run_file, RunOptions};
//! let outcome = run_file("examples/block_on_floor.toml".as_ref(), "out/block".as_ref(), &RunOptions::default(), &mut |_| {})?;
//! println!("{} steps, t = {} s, max overlap {:e} m", outcome.step, outcome.time, outcome.report.max_overlap_m);
//! # Ok::<(), ballast::Error>(())
//! ```
//! A system built in code goes through [`Runner::from_system`] with a
//! [`RunPlan`] (see the crate documentation and `examples/library_run.rs`).

pub mod checkpoint;
mod equilibrium;
pub mod positions;
mod runner;
pub mod summary;

pub use checkpoint::Checkpoint;
pub use equilibrium::{Equilibrium, EquilibriumWatch, DEFAULT_EQUILIBRIUM_STEPS};
pub(crate) use runner::body_names;
pub use runner::{
    check_options, cores, default_threads, CyclePlan, Figures, Prior, Progress, Restart, RunLength, RunOptions,
    RunOutcome, RunPlan, Runner, Status,
};
pub use summary::{RunEnd, RunReport, RunSummary};

use crate::error::Result;
use crate::scene::common::RecordedText;
use crate::scene::{scene_on, MdScene, Scene, SceneKind};
use std::path::Path;

/// Runs the scene file at `scene_path` (either engine: `[simulation] engine`)
/// into the folder `out`, calling `progress` after every step. An MD scene's
/// `md.threads` wins over `opts.threads`.
///
/// # Errors
/// [`crate::Error::Scene`] (one line naming the field) for an invalid scene,
/// options or checkpoint; else as [`Runner::run`].
pub fn run_file(
    scene_path: &Path,
    out: &Path,
    opts: &RunOptions,
    progress: &mut dyn FnMut(&Progress),
) -> Result<RunOutcome> {
    let text = Scene::read_text(scene_path)?;
    let name = scene_path.display().to_string();
    match SceneKind::of(&text, &name, opts.engine.as_deref())? {
        SceneKind::Md => {
            let mut scene = MdScene::from_toml_str_named(&text, &name)?;
            let text = scene.text_with_length(text, opts.length)?;
            let opts = RunOptions { threads: scene.threads().unwrap_or(opts.threads), ..opts.clone() };
            let (system, plan) = (scene.build()?, scene.plan()?);
            let restart: Restart<crate::md::MdSystem> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
            let figures: Figures<crate::md::MdSystem> =
                Box::new(|dir, _| crate::report::draw_run_figures(dir).map(drop));
            Runner::from_scene(system, plan, scene_path, text, Some(restart))
                .with_figures(figures)
                .run(out, &opts, progress)
        }
        SceneKind::PlanarMd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::PlanarMd, opts.engine.is_some())?;
            let (system, info) = scene.build_planar()?;
            let text = scene.text_with_length(text, crate::scene::planar_length(opts.length, system.params.dt))?;
            let plan = scene.plan_planar(system.params.dt)?;
            let model = serde_json::to_value(info).map_err(|e| crate::Error::Io(std::io::Error::other(e)))?;
            let restart: Restart<crate::md::planar::PlanarSystem> =
                Box::new(move |sys| scene.with_bodies(&sys.bodies).to_toml_string());
            Runner::from_scene(system, plan, scene_path, text, Some(restart))
                .with_model(model)
                .with_figures(plane_figures::<crate::md::planar::PlanarSystem>())
                .run(out, opts, progress)
        }
        SceneKind::Nscd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::Nscd, opts.engine.is_some())?;
            let text = scene.text_with_length(text, opts.length)?;
            let (system, plan) = (scene.build()?, scene.plan()?);
            let restart: Restart<crate::nscd::System> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
            Runner::from_scene(system, plan, scene_path, text, Some(restart))
                .with_figures(plane_figures::<crate::nscd::System>())
                .run(out, opts, progress)
        }
    }
}

/// The figures of a run of either 2D engine: from its folder, with the positions at the end of the first
/// cycle kept by its per-cycle state (the reference of the displacement field).
fn plane_figures<E: crate::engine::Engine<CycleState = crate::io::cycles::NscdCycleState>>() -> Figures<E> {
    Box::new(|dir, cycles| {
        let first = cycles.and_then(|c| c.first_cycle_q.as_deref());
        crate::report::plane::nscd_figures(dir, first).map(drop)
    })
}
