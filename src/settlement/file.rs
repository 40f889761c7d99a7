//! A scene file's `[settlement]` table run through the procedure
//! ([`super::driver::Accelerated`]), for either engine: what `ballast run` does
//! with a scene that has one.

use super::driver::{Accelerated, AccelerationProgress, AccelerationSummary};
use crate::error::Result;
use crate::run::RunOptions;
use crate::scene::common::RecordedText;
use crate::scene::{scene_on, MdScene, Scene, SceneKind};
use std::path::Path;

/// Runs the settlement-acceleration procedure of the scene file at `path` into
/// `out`, calling `progress` after each cycle; `None` (nothing run) if the scene
/// has no `[settlement]`. `opts.length` replaces the scene's duration (and so the
/// cycles to reach), as for a plain run; an MD scene's `md.threads` wins.
///
/// # Errors
/// [`crate::Error::Scene`] (one line naming the key) for an invalid scene or
/// options; else as [`Accelerated::run`].
pub fn run_file(
    path: &Path,
    out: &Path,
    opts: &RunOptions,
    progress: &mut dyn FnMut(&AccelerationProgress),
) -> Result<Option<AccelerationSummary>> {
    let text = Scene::read_text(path)?;
    let name = path.display().to_string();
    match SceneKind::of(&text, &name, opts.engine.as_deref())? {
        SceneKind::Md => {
            let mut scene = MdScene::from_toml_str_named(&text, &name)?;
            if scene.settlement.is_none() {
                return Ok(None);
            }
            let text = scene.text_with_length(text, opts.length)?;
            let Some(plan) = scene.acceleration()? else { return Ok(None) };
            let opts = RunOptions { threads: scene.threads().unwrap_or(opts.threads), ..opts.clone() };
            let run =
                Accelerated::from_scene(scene.build()?, plan.spec, plan.frequency, plan.cycles, scene.seed(), text)
                    .with_figures(figures());
            Ok(Some(run.run(out, &opts, progress)?.summary))
        }
        SceneKind::PlanarMd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::PlanarMd, opts.engine.is_some())?;
            if scene.settlement.is_none() {
                return Ok(None);
            }
            let (system, info) = scene.build_planar()?;
            let text = scene.text_with_length(text, crate::scene::planar_length(opts.length, system.params.dt))?;
            let Some(plan) = scene.acceleration()? else { return Ok(None) };
            let model = serde_json::to_value(info).map_err(|e| crate::Error::Io(std::io::Error::other(e)))?;
            let run = Accelerated::from_scene(system, plan.spec, plan.frequency, plan.cycles, scene.seed(), text)
                .with_model(model)
                .with_figures(figures());
            Ok(Some(run.run(out, opts, progress)?.summary))
        }
        SceneKind::Nscd => {
            let (mut scene, text) = scene_on(&text, &name, SceneKind::Nscd, opts.engine.is_some())?;
            if scene.settlement.is_none() {
                return Ok(None);
            }
            let text = scene.text_with_length(text, opts.length)?;
            let Some(plan) = scene.acceleration()? else { return Ok(None) };
            let run =
                Accelerated::from_scene(scene.build()?, plan.spec, plan.frequency, plan.cycles, scene.seed(), text)
                    .with_figures(figures());
            Ok(Some(run.run(out, opts, progress)?.summary))
        }
    }
}

/// The figures of an accelerated run, from its folder.
fn figures() -> super::driver::FolderFigures {
    Box::new(|dir| crate::report::settlement::draw(dir, None).map(drop))
}
