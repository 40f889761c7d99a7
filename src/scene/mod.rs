//! TOML scene files: parsing, validation, building an [`nscd::System`](crate::nscd::System)
//! and saving a system's state back as a scene. The format is documented in
//! `docs/scene-format.md`; all quantities are SI. Scenes of the MD engine
//! (`engine = "md"`) have their own format, in [`md`] ([`MdScene`]); [`engine_of`]
//! tells which engine a file is for.
//!
//! ```
//! let scene = ballast::scene::Scene::from_toml_str(r#"
//!     [simulation]
//!     engine = "nscd"
//!     dt = 1e-3
//!     duration = 0.01
//!     [[material]]
//!     name = "grain"
//!     density = 2700.0
//!     [[body]]
//!     material = "grain"
//!     disc = 0.01
//!     position = [0.0, 0.0]
//! "#).unwrap();
//! assert_eq!(scene.steps(), 10);
//! let sys = scene.build().unwrap();
//! assert_eq!(sys.bodies.len(), 1);
//! ```

mod build;
pub mod common;
mod format;
pub mod md;
mod parse;
mod soft;
mod validate;
mod write;

pub use format::*;
pub use md::MdScene;
pub use soft::{
    planar_length, scene_on, SceneKind, SoftDt, SoftModelInfo, SoftSection, DEFAULT_OVERLAP_RATIO,
    DEFAULT_TANGENTIAL_RATIO,
};
pub use validate::{MAX_LENGTH, MAX_SIDES, MAX_STEPS, MIN_SIZE};

use crate::error::{clip, Error, Result};
use serde::Deserialize;
use std::path::Path;

/// The engines a scene file can be for: `"nscd"` ([`Scene`]) and `"md"` ([`MdScene`]).
pub const ENGINES: [&str; 2] = ["nscd", "md"];

/// The engine a scene file is for, `"nscd"` or `"md"`: the value of
/// `[simulation] engine`, read without validating the rest of the file. Load an
/// `"nscd"` scene with [`Scene`], an `"md"` one with [`MdScene`].
///
/// # Errors
/// [`Error::Scene`] with a one-line message: TOML syntax errors and a missing or
/// mistyped `engine` as `scene.toml line L: …`, any other engine as
/// `simulation.engine: unknown engine 'x', expected 'nscd' or 'md'`.
///
/// ```
/// let text = "[simulation]\nengine = \"md\"\ndt = 1e-5\n";
/// assert_eq!(ballast::scene::engine_of(text).unwrap(), "md");
/// ```
pub fn engine_of(text: &str) -> Result<String> {
    engine_of_named(text, "scene.toml")
}

/// As [`engine_of`], with `name` in place of `scene.toml` in the messages.
pub fn engine_of_named(text: &str, name: &str) -> Result<String> {
    #[derive(Deserialize)]
    struct Probe {
        simulation: ProbeSimulation,
    }
    #[derive(Deserialize)]
    struct ProbeSimulation {
        engine: String,
    }
    let probe: Probe = toml::from_str(text).map_err(|e| Error::Scene(parse::one_line(name, text, &e)))?;
    let engine = probe.simulation.engine;
    if ENGINES.contains(&engine.as_str()) {
        Ok(engine)
    } else {
        Err(Error::Scene(format!("simulation.engine: unknown engine '{}', expected 'nscd' or 'md'", clip(&engine))))
    }
}

impl common::RecordedText for Scene {
    fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.simulation
    }

    fn to_text(&self) -> Result<String> {
        self.to_toml_string()
    }
}

impl Scene {
    /// Parses and fully validates a scene. Errors are [`Error::Scene`] with a
    /// single-line message; TOML syntax errors, unknown keys and missing fields
    /// read `scene.toml line L: …`.
    pub fn from_toml_str(text: &str) -> Result<Scene> {
        Self::from_toml_str_named(text, "scene.toml")
    }

    /// As [`Scene::from_toml_str`], with `name` in place of `scene.toml` in the
    /// messages of syntax errors.
    pub fn from_toml_str_named(text: &str, name: &str) -> Result<Scene> {
        let scene: Scene = toml::from_str(text).map_err(|e| Error::Scene(parse::one_line(name, text, &e)))?;
        validate::check(&scene)?;
        Ok(scene)
    }

    /// Reads, parses and validates the scene file at `path`; syntax errors name
    /// the file as given. A file that cannot be read is an [`Error::File`].
    pub fn load(path: impl AsRef<Path>) -> Result<Scene> {
        let path = path.as_ref();
        Self::from_toml_str_named(&Self::read_text(path)?, &path.display().to_string())
    }

    /// The text of a scene file, or [`Error::File`] naming it if it cannot be read.
    pub fn read_text(path: impl AsRef<Path>) -> Result<String> {
        let path = path.as_ref();
        std::fs::read_to_string(path).map_err(|source| Error::File {
            what: "scene file",
            path: path.to_path_buf(),
            source,
        })
    }

    /// Validates a scene built as a value (e.g. by a generator of
    /// [`crate::scenarios`]) exactly as [`Scene::from_toml_str`] validates a file:
    /// the same one-line [`Error::Scene`] messages.
    pub fn validate(&self) -> Result<()> {
        validate::check(self).map(|_| ())
    }

    /// The scene as TOML text, laid out like a hand-written scene (only the keys
    /// the scene has, inline tables for `regular`, `imposed` and `load`), which
    /// [`Scene::from_toml_str`] reads back to an equal scene: floats are written
    /// in their shortest exact form. It does not fail at present; the `Result`
    /// leaves room for formats that might.
    pub fn to_toml_string(&self) -> Result<String> {
        Ok(write::to_toml(self))
    }

    /// Number of time steps of the run, `round(duration / dt)` (0 if `dt` is not positive).
    pub fn steps(&self) -> u64 {
        self.simulation.steps()
    }

    /// Random seed recorded in the outputs (default 0).
    pub fn seed(&self) -> u64 {
        self.simulation.seed()
    }

    /// Number of steps between two rows of `series.csv` (default 1, never 0).
    pub fn output_every(&self) -> u64 {
        self.output.as_ref().and_then(|o| o.every).unwrap_or(DEFAULT_OUTPUT_EVERY).max(1)
    }

    /// The run plan of the scene: steps, output, equilibrium stop, cycles, seed.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    pub fn plan(&self) -> Result<crate::run::RunPlan> {
        let body = |name: &str| self.bodies.iter().position(|b| b.name == name);
        let cycles = common::check_output(self.output.as_ref(), true, body)?;
        Ok(common::run_plan(&self.simulation, self.output.as_ref(), cycles))
    }

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    pub fn acceleration(&self) -> Result<Option<common::AccelerationPlan>> {
        let plan = self.plan()?;
        common::check_settlement(self.settlement.as_ref(), plan.cycles.as_ref(), &self.simulation, |name| {
            match self.bodies.iter().position(|b| b.name == name && !name.is_empty()) {
                Some(i) if self.bodies[i].is_fixed() => Err(format!("body '{}' is fixed", clip(name))),
                Some(i) => Ok(common::SettlementRef::Body(i)),
                None => Err(format!("unknown body '{}'", clip(name))),
            }
        })
    }
}
