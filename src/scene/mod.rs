//! TOML scene files: parsing, validation, building an [`nscd::System`](crate::nscd::System)
//! and saving a system's state back as a scene. The format is documented in
//! `docs/scene-format.md`; all quantities are SI. Scenes of the MD engine
//! (`engine = "md"`) have their own format, in [`md`] ([`MdScene`]); [`engine_of`]
//! tells which engine a file is for.
//!
//! ```
//! use ballast::scene::{Scene, SceneFile};
//! let scene = Scene::from_toml_str(r#"
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
pub mod d3;
mod file;
mod format;
mod kind;
pub mod md;
mod parse;
mod soft;
mod validate;
mod write;

pub use d3::Scene3;
pub use file::{read_text, SceneFile};
pub use format::*;
pub use kind::{planar_length, scene_on, SceneKind};
pub use md::MdScene;
pub use soft::{SoftDt, SoftModelInfo, SoftSection, DEFAULT_OVERLAP_RATIO, DEFAULT_TANGENTIAL_RATIO};
pub use validate::{MAX_LENGTH, MAX_SIDES, MAX_STEPS, MIN_SIZE};

use crate::error::{clip, Error, Result};
use serde::Deserialize;

/// The engines a scene file can be for: `"nscd"` and `"md2d"` ([`Scene`]), `"md"` ([`MdScene`]).
pub const ENGINES: [&str; 3] = ["nscd", "md2d", "md"];

/// The engine a scene file is for, as the scenes, the command line (`--engine`) and the outputs (`run.json`,
/// `summary.json`) name it: `"nscd"` (rigid contacts, 2D), `"md2d"` (soft contacts, the same 2D format) or
/// `"md"` (soft contacts, 3D spheres). Read from `[simulation] engine` without validating the rest of the file;
/// the former spelling of the planar engine, `engine = "md"` with `dimension = 2`, reads as `"md2d"`. Load an
/// `"nscd"` or `"md2d"` scene with [`Scene`], an `"md"` one with [`MdScene`].
///
/// # Errors
/// [`Error::Scene`] with a one-line message: TOML syntax errors and a missing or
/// mistyped `engine` as `scene.toml line L: …`, any other engine as
/// `simulation.engine: unknown engine 'x', expected 'nscd', 'md2d' or 'md'`.
///
/// ```
/// let text = "[simulation]\nengine = \"md\"\ndt = 1e-5\n";
/// assert_eq!(ballast::scene::engine_of(text).unwrap(), "md");
/// let planar = "[simulation]\nengine = \"md\"\ndimension = 2\ndt = 1e-5\n";
/// assert_eq!(ballast::scene::engine_of(planar).unwrap(), "md2d");
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
        dimension: Option<toml::Value>,
    }
    let probe: Probe = toml::from_str(text).map_err(|e| Error::Scene(parse::one_line(name, text, &e)))?;
    let sim = probe.simulation;
    if !ENGINES.contains(&sim.engine.as_str()) {
        return Err(Error::Scene(format!(
            "simulation.engine: unknown engine '{}', expected 'nscd', 'md2d' or 'md'",
            clip(&sim.engine)
        )));
    }
    let planar = sim.engine == "md" && sim.dimension.and_then(|d| d.as_integer()) == Some(2);
    Ok(if planar { "md2d".into() } else { sim.engine })
}

impl SceneFile for Scene {
    fn validate(&self) -> Result<()> {
        validate::check(self).map(|_| ())
    }

    fn to_toml_string(&self) -> Result<String> {
        Ok(write::to_toml(self))
    }

    fn simulation(&self) -> &Simulation {
        &self.simulation
    }

    fn simulation_mut(&mut self) -> &mut Simulation {
        &mut self.simulation
    }

    fn output(&self) -> Option<&OutputSection> {
        self.output.as_ref()
    }

    /// The run plan of the scene: steps, output, equilibrium stop, cycles, seed.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    fn plan(&self) -> Result<crate::run::RunPlan> {
        let body = |name: &str| self.bodies.iter().position(|b| b.name == name);
        let cycles = common::check_output(self.output.as_ref(), true, body)?;
        Ok(common::run_plan(&self.simulation, self.output.as_ref(), cycles))
    }

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    fn acceleration(&self) -> Result<Option<common::AccelerationPlan>> {
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
