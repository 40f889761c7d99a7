//! Building an [`MdSystem`] from a validated MD scene, and the inverse: writing a
//! system's current state back into the scene.
//!
//! Sphere `i` of the system is `bodies[i]` of the scene, wall `k` is `walls[k]`,
//! material `m` is `materials[m]`. The laws come resolved from validation
//! (which needs them for the initial overlaps and the time step).

use super::format::MdScene;
use super::validate::check;
use crate::error::Result;
use crate::md::{Ghosts, MdSystem, Particles, Shape, V3};

impl MdScene {
    /// Validates the scene and builds the MD system at time 0 (forces evaluated
    /// once), with `md.threads` force threads if the scene gives them (else 1;
    /// `ballast run` sets its own, see [`MdSystem::set_threads`]).
    pub fn build(&self) -> Result<MdSystem> {
        let c = check(self)?;
        let mut particles = Particles::default();
        for (b, &m) in self.bodies.iter().zip(&c.sphere_materials) {
            particles.push(
                &b.name,
                m as u32,
                c.materials[m].density,
                b.sphere,
                V3::from(b.position),
                V3::from(b.velocity()),
                V3::from(b.spin()),
            );
        }
        let mut sys = MdSystem::new(c.settings, particles, c.walls, c.laws, Ghosts::new(c.planes))?;
        if let Some(t) = c.threads {
            sys.set_threads(t);
        }
        Ok(sys)
    }

    /// The same scene with every sphere's `position`, `velocity` and `spin`
    /// replaced by the current state of `sys`, and every servo wall moved to its
    /// current place (its `point` shifted by its displacement along its normal),
    /// so that a settled sample can be saved and run again.
    ///
    /// The restart begins at time 0 with the servo walls at rest: their stress or
    /// force histories start again from `t = 0`, and the contact memory
    /// (tangential springs) is not kept. If `sys` has fewer spheres or walls than
    /// the scene, only the first ones are updated.
    pub fn with_state(&self, sys: &MdSystem) -> MdScene {
        let mut out = self.clone();
        let p = &sys.particles;
        for (i, b) in out.bodies.iter_mut().enumerate().take(p.len()) {
            b.position = p.x[i].into();
            b.velocity = Some(p.v[i].into());
            b.spin = Some(p.w[i].into());
        }
        for (spec, wall) in out.walls.iter_mut().zip(&sys.walls) {
            if wall.s == 0.0 {
                continue;
            }
            let moved = match wall.shape {
                Shape::Plane { point, normal } | Shape::Disc { point, normal, .. } => point + normal * wall.s,
                Shape::Cylinder { .. } => continue,
            };
            if let Some(plane) = spec.plane.as_mut() {
                plane.point = moved.into();
            }
            if let Some(disc) = spec.disc.as_mut() {
                disc.point = moved.into();
            }
        }
        out
    }
}
