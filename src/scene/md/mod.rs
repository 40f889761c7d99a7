//! TOML scene files of the MD engine (`[simulation] engine = "md"`): parsing,
//! validation, building an [`MdSystem`](crate::md::MdSystem) and saving a
//! system's state back as a scene. The format is documented in the section "MD
//! scenes" of `docs/scene-format.md`; all quantities are SI. Errors read like
//! those of NSCD scenes (one line naming the field; `scene.toml line L: …` for
//! syntax errors, unknown and missing keys). [`crate::scene::engine_of`] tells
//! which of the two formats a file is in.
//!
//! ```
//! let scene = ballast::scene::MdScene::from_toml_str(r#"
//!     [simulation]
//!     engine = "md"
//!     dt = 1e-6
//!     duration = 1e-4
//!     [[material]]
//!     name = "glass"
//!     density = 2500.0
//!     young = 6e10
//!     poisson = 0.22
//!     [[contact]]
//!     between = ["glass", "glass"]
//!     model = "hertz"
//!     friction = 0.3
//!     [[wall]]
//!     name = "floor"
//!     material = "glass"
//!     plane = { point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }
//!     [[body]]
//!     material = "glass"
//!     sphere = 0.001
//!     position = [0.0, 0.0, 0.002]
//! "#).unwrap();
//! assert_eq!(scene.steps(), 100);
//! let sys = scene.build().unwrap();
//! assert_eq!(sys.particles.len(), 1);
//! ```

mod build;
mod format;
mod safety;
mod validate;
mod write;

pub use format::*;

use crate::error::{Error, Result};
use crate::scene::{parse, Scene, DEFAULT_OUTPUT_EVERY};
use std::path::Path;

impl crate::scene::common::RecordedText for MdScene {
    fn simulation_mut(&mut self) -> &mut crate::scene::common::Simulation {
        &mut self.simulation
    }

    fn to_text(&self) -> Result<String> {
        self.to_toml_string()
    }
}

impl MdScene {
    /// Parses and fully validates an MD scene. Errors are [`Error::Scene`] with a
    /// single-line message; TOML syntax errors, unknown keys and missing fields
    /// read `scene.toml line L: …`.
    pub fn from_toml_str(text: &str) -> Result<MdScene> {
        Self::from_toml_str_named(text, "scene.toml")
    }

    /// As [`MdScene::from_toml_str`], with `name` in place of `scene.toml` in the
    /// messages of syntax errors.
    pub fn from_toml_str_named(text: &str, name: &str) -> Result<MdScene> {
        let scene: MdScene = toml::from_str(text).map_err(|e| Error::Scene(parse::one_line(name, text, &e)))?;
        validate::check(&scene)?;
        Ok(scene)
    }

    /// Reads, parses and validates the MD scene file at `path`; syntax errors name
    /// the file as given. A file that cannot be read is an [`Error::File`].
    pub fn load(path: impl AsRef<Path>) -> Result<MdScene> {
        let path = path.as_ref();
        Self::from_toml_str_named(&Scene::read_text(path)?, &path.display().to_string())
    }

    /// Validates a scene built as a value (e.g. by a generator of
    /// [`crate::scenarios`]) exactly as [`MdScene::from_toml_str`] validates a
    /// file: the same one-line [`Error::Scene`] messages.
    pub fn validate(&self) -> Result<()> {
        validate::check(self).map(|_| ())
    }

    /// The scene as TOML text that [`MdScene::from_toml_str`] reads back to an
    /// equal scene (only the keys the scene has; floats in their shortest exact
    /// form). It does not fail at present; the `Result` leaves room for formats
    /// that might.
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
        let cycles = crate::scene::common::check_output(self.output.as_ref(), false, |_| None)?;
        Ok(crate::scene::common::run_plan(&self.simulation, self.output.as_ref(), cycles))
    }

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    pub fn acceleration(&self) -> Result<Option<crate::scene::common::AccelerationPlan>> {
        let plan = self.plan()?;
        let sim = &self.simulation;
        use crate::scene::common::SettlementRef;
        crate::scene::common::check_settlement(self.settlement.as_ref(), plan.cycles.as_ref(), sim, |name| {
            if let Some(i) = self.bodies.iter().position(|b| b.name == name && !name.is_empty()) {
                return Ok(SettlementRef::Body(i));
            }
            let servo: Vec<&str> = self.walls.iter().filter(|w| w.servo.is_some()).map(|w| w.name.as_str()).collect();
            match servo.iter().position(|w| *w == name) {
                Some(j) => Ok(SettlementRef::Boundary(j)),
                None if self.walls.iter().any(|w| w.name == name) => Err(format!(
                    "wall '{}' does not move (only a servo wall, like the plate, can)",
                    crate::error::clip(name)
                )),
                None => Err(format!("unknown sphere or servo wall '{}'", crate::error::clip(name))),
            }
        })
    }

    /// Force-evaluation threads the scene asks for (`md.threads`), if any.
    pub fn threads(&self) -> Option<usize> {
        self.md.as_ref().and_then(|m| m.threads)
    }
}
