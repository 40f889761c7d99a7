//! Which engine a scene file runs on ([`SceneKind`]: its own, `[simulation] engine`, or the `engine` override of
//! a run), and the 2D scene set to run on the engine picked ([`scene_on`]); [`crate::open`] dispatches on it.
//! The engines' names are those of [`super::ENGINES`]: `nscd`, `md2d`, `md`.

use super::format::Scene;
use super::validate::err;
use crate::error::Result;
use crate::scene::SceneFile;

/// Which engine a scene file runs on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneKind {
    /// A 2D scene on the NSCD engine ([`Scene`]).
    Nscd,
    /// A 3D MD scene ([`super::MdScene`]).
    Md,
    /// A 2D scene on the planar MD engine ([`Scene`] with `[soft]`).
    PlanarMd,
}

impl SceneKind {
    /// The engine of the scene text `text` (named `name` in messages), or `engine` if given (`"nscd"`,
    /// `"md2d"` or `"md"`, [`super::ENGINES`]): a 2D scene runs on `nscd` or `md2d` (`md` on a 2D scene is read
    /// as `md2d`, its former spelling), a 3D MD scene on `md` only.
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) for a scene whose engine cannot be read, an unknown
    /// `engine`, or a 2D engine asked of a 3D MD scene.
    pub fn of(text: &str, name: &str, engine: Option<&str>) -> Result<SceneKind> {
        let own = super::engine_of_named(text, name)?;
        let spheres = own == "md";
        match engine {
            None if spheres => Ok(SceneKind::Md),
            None if own == "md2d" => Ok(SceneKind::PlanarMd),
            None => Ok(SceneKind::Nscd),
            Some("md") if spheres => Ok(SceneKind::Md),
            Some("md" | "md2d") if !spheres => Ok(SceneKind::PlanarMd),
            Some(e @ ("nscd" | "md2d")) => {
                err(format!("engine: {e} runs 2D scenes, and this is a 3D MD scene (spheres): use md"))
            }
            Some(other) => {
                err(format!("engine: unknown engine '{}', expected 'nscd', 'md2d' or 'md'", crate::error::clip(other)))
            }
        }
    }

    /// The engine's name, as scenes, `--engine` and the outputs write it: `nscd`, `md2d`, `md`.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Nscd => "nscd",
            SceneKind::PlanarMd => "md2d",
            SceneKind::Md => "md",
        }
    }
}

/// The 2D scene of `text` (named `name` in messages) set to run on the engine of
/// `kind` (NSCD or planar MD), and the text to record: the file as read, or, if
/// the engine was `overridden` (`--engine`), the scene rewritten with that engine.
///
/// # Errors
/// [`Error::Scene`](crate::Error::Scene) for an invalid scene, or a 3D `kind`.
pub fn scene_on(text: &str, name: &str, kind: SceneKind, overridden: bool) -> Result<(Scene, String)> {
    let scene = Scene::from_toml_str_named(text, name)?;
    if kind == SceneKind::Md {
        return err("a 3D MD scene is read with scene::MdScene".into());
    }
    if overridden && scene.is_planar_md() != (kind == SceneKind::PlanarMd) {
        let scene = scene.on_engine(kind.name())?;
        let text = scene.to_toml_string()?;
        Ok((scene, text))
    } else {
        Ok((scene, text.to_string()))
    }
}

/// A run length for a planar MD run: a number of steps is of the planar step
/// `dt` (s), so it becomes the duration `steps × dt`.
pub fn planar_length(length: Option<crate::run::RunLength>, dt: f64) -> Option<crate::run::RunLength> {
    match length {
        Some(crate::run::RunLength::Steps(n)) if n > 0 => Some(crate::run::RunLength::Duration(n as f64 * dt)),
        other => other,
    }
}
