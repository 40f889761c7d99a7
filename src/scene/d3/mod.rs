//! TOML scenes of the 3D NSCD engine (`[simulation] engine = "nscd"` with `dimension = 3`): parsing
//! ([`mod@format`]), validation with one-line errors naming the key, building a
//! [`System3`](crate::nscd::d3::system::System3) and saving a system's state back as a scene. All quantities are
//! SI. [`crate::scene::SceneKind::is_nscd3`] tells a 3D NSCD scene from a 2D one.
//!
//! ```toml
//! [simulation]
//! engine = "nscd"
//! dimension = 3                   # required: without it the file is a 2D scene
//! dt = 1.0e-3
//! duration = 0.5
//! gravity = [0.0, 0.0, -9.81]     # 3 components; this is the default
//! seed = 1
//! equilibrium = { kinetic_energy = 1e-9 }
//!
//! [nscd]                          # the 2D scene's [nscd]: theta, criterion, tolerance, min/max_iterations,
//! theta = 0.5                     # max_factor, symmetric, relaxation, anderson, measure, on_stall ("accept",
//! criterion = "quad"              # "extend" or "stop"), stall_max_iterations, alert_distance, solver
//! tolerance = 1e-6                # ("nlgs" or "apgd"); "interior_point" (2D only) is refused
//! alert_distance = 1e-3
//!
//! [output]                        # as in 2D; cycles = { frequency, body, positions }
//! every = 10
//!
//! [[material]]                    # as in 2D
//! name = "grain"
//! density = 2700.0
//!
//! [[contact]]                     # as in 2D: a pair of materials without one is frictionless and plastic
//! between = ["grain", "grain"]
//! friction = 0.5
//! restitution = 0.0
//!
//! [[body]]
//! name = "floor"
//! material = "grain"
//! plane = { normal = [0.0, 0.0, 1.0] }        # the half-space behind the plane through `position`
//! position = [0.0, 0.0, 0.0]
//! fixed = true                                 # a plane must be fixed
//!
//! [[body]]
//! name = "rock"
//! material = "grain"
//! polyhedron = { vertices = [[0.0, 0.0, 0.0], [0.05, 0.0, 0.0], [0.0, 0.04, 0.0], [0.01, 0.01, 0.03]] }
//! position = [0.1, 0.0, 0.01]                  # where the vertices' frame is put
//! orientation = { rotation_vector = [0.0, 0.0, 0.5] }   # or { quaternion = [w, x, y, z] }, unit
//! velocity = [0.0, 0.0, -0.1]                  # of the frame's origin (m/s)
//! spin = [0.0, 0.0, 1.0]                       # world axes (rad/s)
//!
//! [[body]]
//! material = "grain"
//! box = { half = [0.05, 0.05, 0.05] }          # or sphere = { radius = 0.03 }
//! position = [0.0, 0.0, 0.05]
//! ```
//!
//! Decisions:
//! - **A body's frame, as 2D polygons.** `polyhedron.vertices` are given in the body's own frame, and
//!   `position` and `orientation` place that frame in the world (`position` is required, as in 2D): the hull's
//!   centroid `c` (in the vertices' frame) ends at `position + R c`, its principal axes at `R R_F`
//!   (the doc of `build.rs`). Vertices written in world coordinates with `position = [0, 0, 0]` and no
//!   orientation stay where they are. A box and a sphere are centred on the frame's origin; a box's edges are
//!   along its axes. `velocity` is the velocity of the frame's origin (as in 2D) and `spin` the angular velocity
//!   in world axes; the centroid then moves at `velocity + spin × R c`.
//! - **Orientation**: a table with exactly one of `quaternion = [w, x, y, z]` (scalar first, of norm 1 to
//!   [`QUATERNION_TOLERANCE`], then normalised) and `rotation_vector = [rx, ry, rz]` (rad, the rotation by its
//!   length about its direction). A state written back ([`Scene3::with_state`]) is a quaternion with `w ≥ 0`.
//! - **Planes** (`plane = { normal }`): the half-space behind the plane through `position`, `normal` pointing
//!   out of it; fixed only, oriented by its normal alone (`orientation` refused).
//! - **Fixed bodies do not move**: a non-zero `velocity` or `spin` on one is refused; a moving wall is a
//!   non-fixed body with `imposed` velocities.
//! - **Drives** (`drives.rs`): `imposed = { vx, vy, vz, spin = [wx, wy, wz] }` — the centroid's world velocity
//!   components each on its own, the spin (world axes) all three together (`crate::space::loads` says why), each a
//!   number or a harmonic table as in 2D; `load = { direction = [dx, dy, dz], mean, amplitude, frequency, phase }`
//!   a force at the centroid and `torque = { … }` the same table for a moment about the axis `direction` through
//!   it (N·m). `[[spring]]`: the 2D table with 3 coordinates (`point` and `other_point` in the body's scene
//!   frame, `anchor` in the world), law (17).
//! - **Shared sections** (`[simulation]`, `[output]`, `[settlement]`, `[nscd]`, `[[material]]`, `[[contact]]`)
//!   are the 2D scene's types, checked by the 2D rules with the same messages; `output.cycles.body` names the
//!   followed body and `settlement.settlement_body` a non-fixed body, as in 2D. The default alert distance is the
//!   2D rule's on the bodies' inner radii (a polyhedron's inradius, a sphere's radius).
//!
//! ```
//! use ballast::scene::{d3::Scene3, SceneFile};
//! let scene = Scene3::from_toml_str(r#"
//!     [simulation]
//!     engine = "nscd"
//!     dimension = 3
//!     dt = 1e-3
//!     duration = 0.01
//!     [[material]]
//!     name = "grain"
//!     density = 2700.0
//!     [[body]]
//!     material = "grain"
//!     plane = { normal = [0.0, 0.0, 1.0] }
//!     position = [0.0, 0.0, 0.0]
//!     fixed = true
//!     [[body]]
//!     material = "grain"
//!     box = { half = [0.01, 0.01, 0.01] }
//!     position = [0.0, 0.0, 0.01]
//! "#).unwrap();
//! assert_eq!(scene.steps(), 10);
//! let sys = scene.build().unwrap();
//! assert_eq!(sys.bodies.len(), 2);
//! ```

mod build;
mod drives;
pub mod format;
mod validate;
mod write;

pub use format::*;
pub use validate::QUATERNION_TOLERANCE;

use crate::error::{clip, Result};
use crate::nscd::NlgsSettings;
use crate::scene::common::{self, AccelerationPlan, SettlementRef, Simulation};
use crate::scene::{OutputSection, SceneFile};

impl Scene3 {
    /// The solver settings a run of the scene takes (`[nscd]` with the defaults filled in), the scene checked
    /// whole as [`SceneFile::validate`] checks it.
    ///
    /// # Errors
    /// As [`SceneFile::validate`].
    pub(crate) fn nlgs_settings(&self) -> Result<NlgsSettings> {
        validate::check(self).map(|c| c.params.nlgs)
    }
}

impl SceneFile for Scene3 {
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

    /// The run plan of the scene: steps, output, equilibrium stop, cycles (following a named body, as in 2D), seed.
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) if the scene is invalid.
    fn plan(&self) -> Result<crate::run::RunPlan> {
        let body = |name: &str| self.bodies.iter().position(|b| b.name == name);
        let cycles = common::check_output(self.output.as_ref(), true, body)?;
        Ok(common::run_plan(&self.simulation, self.output.as_ref(), cycles))
    }

    /// The settlement-acceleration procedure the scene asks for (`[settlement]`), if any: the settlement body is a
    /// non-fixed body, as in 2D.
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) if the scene is invalid.
    fn acceleration(&self) -> Result<Option<AccelerationPlan>> {
        let plan = self.plan()?;
        common::check_settlement(self.settlement.as_ref(), plan.cycles.as_ref(), &self.simulation, |name| {
            match self.bodies.iter().position(|b| b.name == name && !name.is_empty()) {
                Some(i) if self.bodies[i].is_fixed() => Err(format!("body '{}' is fixed", clip(name))),
                Some(i) => Ok(SettlementRef::Body(i)),
                None => Err(format!("unknown body '{}'", clip(name))),
            }
        })
    }
}
