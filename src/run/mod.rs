//! Running a simulation: the [`Engine`] trait both engines implement, the run
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

mod engine;
mod equilibrium;
mod runner;

pub use engine::{Boundary, Configuration, Energies, Engine};
pub use equilibrium::{Equilibrium, EquilibriumWatch, DEFAULT_EQUILIBRIUM_STEPS};
pub(crate) use runner::body_names;
pub use runner::{
    check_options, cores, default_threads, files, CyclePlan, Prior, Progress, Restart, RunLength, RunOptions,
    RunOutcome, RunPlan, Runner, Status,
};

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
            Runner::from_scene(system, plan, scene_path, text, Some(restart)).run(out, &opts, progress)
        }
        SceneKind::PlanarMd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::PlanarMd, opts.engine.is_some())?;
            let (system, info) = scene.build_planar()?;
            let text = scene.text_with_length(text, crate::scene::planar_length(opts.length, system.params.dt))?;
            let plan = scene.plan_planar(system.params.dt)?;
            let model = serde_json::to_value(info).map_err(|e| crate::Error::Io(std::io::Error::other(e)))?;
            let restart: Restart<crate::md::planar::PlanarSystem> =
                Box::new(move |sys| scene.with_bodies(&sys.bodies).to_toml_string());
            Runner::from_scene(system, plan, scene_path, text, Some(restart)).with_model(model).run(out, opts, progress)
        }
        SceneKind::Nscd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::Nscd, opts.engine.is_some())?;
            let text = scene.text_with_length(text, opts.length)?;
            let (system, plan) = (scene.build()?, scene.plan()?);
            let restart: Restart<crate::nscd::System> = Box::new(move |sys| scene.with_state(sys).to_toml_string());
            Runner::from_scene(system, plan, scene_path, text, Some(restart)).run(out, opts, progress)
        }
    }
}
