//! TOML scene files of the MD engine (`[simulation] engine = "md"`): parsing,
//! validation, building an [`MdSystem`](crate::md::MdSystem) and saving a
//! system's state back as a scene. The format is documented in the section "MD
//! scenes" of `docs/scene-format.md`; all quantities are SI. Errors read like
//! those of NSCD scenes (one line naming the field; `scene.toml line L: …` for
//! syntax errors, unknown and missing keys). [`crate::scene::engine_of`] tells
//! which of the two formats a file is in.
//!
//! ```
//! use ballast::scene::{MdScene, SceneFile};
//! let scene = MdScene::from_toml_str(r#"
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

use crate::error::Result;
use crate::scene::common::Simulation;
use crate::scene::{OutputSection, SceneFile};

impl SceneFile for MdScene {
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
    /// [`Error::Scene`](crate::Error::Scene) if the scene is invalid.
    fn plan(&self) -> Result<crate::run::RunPlan> {
        let cycles = crate::scene::common::check_output(self.output.as_ref(), false, |_| None)?;
        Ok(crate::scene::common::run_plan(&self.simulation, self.output.as_ref(), cycles))
    }

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any.
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) if the scene is invalid.
    fn acceleration(&self) -> Result<Option<crate::scene::common::AccelerationPlan>> {
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
}

impl MdScene {
    /// Force-evaluation threads the scene asks for (`md.threads`), if any.
    pub fn threads(&self) -> Option<usize> {
        self.md.as_ref().and_then(|m| m.threads)
    }
}
