//! What every scene format is: TOML text parsed and validated into a value, written back, and the run it asks for
//! ([`SceneFile`]). [`crate::scene::Scene`] (NSCD and planar MD) and [`crate::scene::MdScene`] (3D MD) implement it;
//! the reading, the checks of a file and the plan's common keys are written once here.

use super::common::{AccelerationPlan, Simulation};
use super::{parse, OutputSection, DEFAULT_OUTPUT_EVERY};
use crate::error::{Error, Result};
use serde::de::DeserializeOwned;
use std::path::Path;

/// A scene format: a TOML file of `[simulation]`, `[output]` and the engine's sections.
///
/// ```
/// use ballast::scene::{MdScene, Scene, SceneFile};
/// let scene = Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/block_on_floor.toml"))?;
/// assert_eq!(scene.steps(), Scene::from_toml_str(&scene.to_toml_string()?)?.steps());
/// # Ok::<(), ballast::Error>(())
/// ```
pub trait SceneFile: Sized + DeserializeOwned {
    /// Validates the scene as a file is validated (every field, the bodies, the laws…), also a scene built as a
    /// value (e.g. by a generator of [`crate::scenarios`]): the one-line [`Error::Scene`] messages naming the key.
    fn validate(&self) -> Result<()>;

    /// The scene as TOML text, laid out like a hand-written scene (only the keys the scene has; floats in their
    /// shortest exact form), which [`SceneFile::from_toml_str`] reads back to an equal scene. It does not fail
    /// at present; the `Result` leaves room for formats that might.
    fn to_toml_string(&self) -> Result<String>;

    /// `[simulation]`.
    fn simulation(&self) -> &Simulation;

    /// `[simulation]`, to change.
    fn simulation_mut(&mut self) -> &mut Simulation;

    /// `[output]`, if the scene has one.
    fn output(&self) -> Option<&OutputSection>;

    /// The run plan of the scene: steps, output, equilibrium stop, cycles, seed.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    fn plan(&self) -> Result<crate::run::RunPlan>;

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    fn acceleration(&self) -> Result<Option<AccelerationPlan>>;

    /// Parses and fully validates a scene. Errors are [`Error::Scene`] with a single-line message; TOML syntax
    /// errors, unknown keys and missing fields read `scene.toml line L: …`.
    fn from_toml_str(text: &str) -> Result<Self> {
        Self::from_toml_str_named(text, "scene.toml")
    }

    /// As [`SceneFile::from_toml_str`], with `name` in place of `scene.toml` in the messages of syntax errors.
    fn from_toml_str_named(text: &str, name: &str) -> Result<Self> {
        let scene: Self = toml::from_str(text).map_err(|e| Error::Scene(parse::one_line(name, text, &e)))?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads, parses and validates the scene file at `path`; syntax errors name the file as given. A file that
    /// cannot be read is an [`Error::File`].
    fn load(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        Self::from_toml_str_named(&read_text(path)?, &path.display().to_string())
    }

    /// Number of time steps of the run, `round(duration / dt)` (0 if `dt` is not positive).
    fn steps(&self) -> u64 {
        self.simulation().steps()
    }

    /// Random seed recorded in the outputs (default 0).
    fn seed(&self) -> u64 {
        self.simulation().seed()
    }

    /// Number of steps between two rows of `series.csv` (default 1, never 0).
    fn output_every(&self) -> u64 {
        self.output().and_then(|o| o.every).unwrap_or(DEFAULT_OUTPUT_EVERY).max(1)
    }

    /// The scene as a run records it (`scene.toml`): `text` (the file as read) if `length` is `None`; else the
    /// scene with its duration replaced by `length` (the scene itself changed too), as text.
    ///
    /// # Errors
    /// [`Error::Scene`] for a length that does not fit the scene's time step.
    fn text_with_length(&mut self, text: String, length: Option<crate::run::RunLength>) -> Result<String> {
        match length {
            Some(length) => {
                self.simulation_mut().set_length(length)?;
                self.to_toml_string()
            }
            None => Ok(text),
        }
    }
}

/// The text of a scene file, or [`Error::File`] naming it if it cannot be read.
///
/// # Errors
/// [`Error::File`] with the operating system's error.
pub fn read_text(path: impl AsRef<Path>) -> Result<String> {
    let path = path.as_ref();
    std::fs::read_to_string(path).map_err(|source| Error::File { what: "scene file", path: path.to_path_buf(), source })
}
