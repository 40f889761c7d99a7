//! Building a [`System3`] from a validated 3D scene, and the inverse: writing a system's current state back into
//! the scene.
//!
//! A scene places each body's frame (the frame its `polyhedron` vertices are given in; a box or a sphere is centred
//! on its origin) by `position` (m) and the rotation `R` of its `orientation`; `velocity` (m/s) is the velocity of
//! that frame's origin and `spin` (rad/s) the angular velocity in world axes. The system keeps each body at its
//! centroid in its principal frame: with `F` the principal frame in the scene frame (centroid `c`, axes `R_F`,
//! from [`Polyhedron::from_points`](crate::geometry::Polyhedron::from_points)), the body's pose is
//! `(position + R c, R R_F)`, its centroid moves at `velocity + spin × R c` and its spin in the principal frame is
//! `(R R_F)ᵀ spin` ([`world_state`]). Bodies are made by [`BodyInfo::mobile`] and [`BodyInfo::fixed`], as in code.

use super::format::{BodySpec3, OrientationSpec, Scene3};
use super::validate::{check, solid_of};
use crate::error::Result;
use crate::geometry::{Pose, Vec3};
use crate::nscd::contact::ContactLaw;
use crate::nscd::d3::system::System3;
use crate::space::bodies::{Bodies, BodyInfo, Dofs6};
use crate::space::springs::Spring3;
use nalgebra::UnitQuaternion;

impl Scene3 {
    /// Validates the scene and builds the 3D NSCD system at time 0.
    ///
    /// # Errors
    /// [`Error::Scene`](crate::Error::Scene) (one line naming the key) for an invalid scene.
    pub fn build(&self) -> Result<System3> {
        let checked = check(self)?;
        let mut sys = System3::new(checked.params, self.materials.len());
        let material = |name: &str| self.materials.iter().position(|m| m.name == name).unwrap_or(0);
        for c in &self.contacts {
            let law = ContactLaw {
                friction: c.friction,
                restitution_n: c.restitution.unwrap_or(0.0),
                restitution_t: c.tangential_restitution.unwrap_or(0.0),
            };
            sys.set_law(material(&c.between[0]), material(&c.between[1]), law);
        }
        for (spec, body) in self.bodies.iter().zip(checked.bodies) {
            let (pose, u) = world_state(spec, &body.frame, body.rotation);
            let m = body.material as u32;
            let info = if spec.is_fixed() {
                BodyInfo::fixed(&spec.name, body.solid, m)
            } else {
                let info = BodyInfo::mobile(&spec.name, body.solid, m, self.materials[body.material].density)?;
                body.loads.into_iter().fold(info.with_imposed(body.imposed), BodyInfo::with_load)
            };
            sys.bodies.push(info, pose, u);
        }
        for (spec, c) in self.springs.iter().zip(&checked.springs) {
            sys.springs.push(Spring3 {
                a: c.a,
                point_a: c.point_a,
                b: c.b,
                point_b: c.point_b,
                k_n: spec.k_n,
                nu: spec.nu.unwrap_or(0.0),
                rest_length: c.rest_length,
                prestrain: spec.prestrain.unwrap_or(0.0),
                compression_only: spec.compression_only.unwrap_or(false),
                impulse: 0.0,
            });
        }
        Ok(sys)
    }

    /// The same scene with every non-fixed body's `position`, `orientation` (as a quaternion), `velocity` and
    /// `spin` replaced by the current state of `sys` (body `i` of the system is `self.bodies[i]`), so that a
    /// settled state can be saved and restarted. Fixed bodies are left as they are (they never move). The restart
    /// begins at time 0 and the warm-start impulses are not kept. If `sys` has fewer bodies than the scene, only
    /// the first ones are updated. Every spring's `rest_length` is written out (a default one is the length at
    /// the start of the run, which the restart's start would not reproduce), so the restarted springs keep their
    /// law.
    pub fn with_state(&self, sys: &System3) -> Scene3 {
        let mut out = self.with_bodies(&sys.bodies);
        for (spec, spring) in out.springs.iter_mut().zip(&sys.springs) {
            spec.rest_length.get_or_insert(spring.rest_length);
        }
        out
    }

    /// As [`Scene3::with_state`], from the bodies alone.
    pub fn with_bodies(&self, bodies: &Bodies) -> Scene3 {
        let mut out = self.clone();
        for (i, body) in out.bodies.iter_mut().enumerate() {
            if body.is_fixed() || i >= bodies.len() {
                continue;
            }
            let Ok((_, frame)) = solid_of(body) else { continue };
            let (pose, u) = (&bodies.pose[i], &bodies.u[i]);
            // The scene frame's rotation R = R_body R_F⁻¹, written with w ≥ 0 (q and −q are the same rotation).
            let r = pose.rotation * frame.rotation.inverse();
            let q = r.quaternion();
            let s = if q.w < 0.0 { -1.0 } else { 1.0 };
            let rc = r * frame.position;
            let spin = pose.rotation * Vec3::new(u[3], u[4], u[5]);
            let velocity = Vec3::new(u[0], u[1], u[2]) - spin.cross(&rc);
            body.position = (pose.position - rc).into();
            body.orientation =
                Some(OrientationSpec { quaternion: Some([s * q.w, s * q.i, s * q.j, s * q.k]), rotation_vector: None });
            body.velocity = Some(velocity.into());
            body.spin = Some(spin.into());
        }
        out
    }
}

/// The pose (centroid, principal axes → world) and generalised velocity ([`Dofs6`]: centroid velocity, spin in the
/// principal frame) of a body of `spec` whose principal frame in its scene frame is `frame` and whose scene frame
/// is turned by `rotation` (module doc).
pub(crate) fn world_state(spec: &BodySpec3, frame: &Pose, rotation: UnitQuaternion<f64>) -> (Pose, Dofs6) {
    let rc = rotation * frame.position;
    let turned = rotation * frame.rotation;
    let pose =
        Pose { position: Vec3::from(spec.position) + rc, rotation: UnitQuaternion::new_normalize(turned.into_inner()) };
    let spin = Vec3::from(spec.spin());
    let v = Vec3::from(spec.velocity()) + spin.cross(&rc);
    let w = pose.rotation.inverse_transform_vector(&spin);
    (pose, [v.x, v.y, v.z, w.x, w.y, w.z])
}
