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
    /// A 3D NSCD scene ([`super::Scene3`]: `engine = "nscd"` with `dimension = 3`; polyhedra, spheres, walls).
    Nscd3,
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
        if let Some(e @ ("md" | "md2d")) = engine.filter(|_| own == "nscd") {
            if Self::is_nscd3(text, name)? {
                return err(format!("engine: {e} does not run 3D NSCD scenes (polyhedra), use nscd"));
            }
        }
        let nscd3 = own == "nscd" && Self::is_nscd3(text, name)?;
        match engine {
            None | Some("nscd") if nscd3 => Ok(SceneKind::Nscd3),
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

    /// Whether the scene text `text` (named `name` in messages) is a 3D NSCD scene, read with
    /// [`super::Scene3`]: `[simulation] engine = "nscd"` with `dimension = 3` ([`SceneKind::Nscd3`]; an `engine`
    /// override other than `nscd` is refused, and [`scene_on`], the 2D reader, refuses it naming `scene::Scene3`).
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) for a TOML syntax error (`NAME line L: …`); a scene without
    /// `[simulation] engine` is not a 3D NSCD scene (its reader says what is missing).
    ///
    /// ```
    /// use ballast::scene::SceneKind;
    /// let text = "[simulation]\nengine = \"nscd\"\ndimension = 3\ndt = 1e-3\n";
    /// assert!(SceneKind::is_nscd3(text, "scene.toml").unwrap());
    /// assert!(!SceneKind::is_nscd3("[simulation]\nengine = \"nscd\"\ndt = 1e-3\n", "scene.toml").unwrap());
    /// ```
    pub fn is_nscd3(text: &str, name: &str) -> Result<bool> {
        #[derive(serde::Deserialize)]
        struct Probe {
            simulation: Option<ProbeSimulation>,
        }
        #[derive(serde::Deserialize)]
        struct ProbeSimulation {
            engine: Option<toml::Value>,
            dimension: Option<toml::Value>,
        }
        let probe: Probe =
            toml::from_str(text).map_err(|e| crate::Error::Scene(super::parse::one_line(name, text, &e)))?;
        Ok(probe.simulation.is_some_and(|s| {
            s.engine.as_ref().and_then(|e| e.as_str()) == Some("nscd")
                && s.dimension.and_then(|d| d.as_integer()) == Some(3)
        }))
    }

    /// The engine's name, as scenes, `--engine` and the outputs write it: `nscd`, `md2d`, `md`.
    pub fn name(self) -> &'static str {
        match self {
            SceneKind::Nscd | SceneKind::Nscd3 => "nscd",
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
/// [`Error::Scene`](crate::Error::Scene) for an invalid scene, a 3D `kind` or a 3D NSCD scene.
pub fn scene_on(text: &str, name: &str, kind: SceneKind, overridden: bool) -> Result<(Scene, String)> {
    if SceneKind::is_nscd3(text, name)? {
        return err("simulation.dimension: a 3D NSCD scene (dimension = 3) is read with scene::Scene3".into());
    }
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
