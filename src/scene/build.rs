//! Building an [`nscd::System`](crate::nscd::System) from a validated scene, and
//! the inverse: writing a system's current state back into a scene.
//!
//! A scene places each body by its body-frame origin (`position`, m) and
//! `angle` (rad), with `velocity` (m/s) the velocity of that origin. The
//! system works with the centre of mass: with `c` the centroid in the body
//! frame and `R` the rotation by `angle`,
//! `q = (position + R c, angle)` and `u = (velocity + spin × R c, spin)`
//! ([`centroid_state`]). Bodies are made by [`BodyInfo::new`], as in code.

use super::format::Scene;
use super::validate::{check, shape_of, Checked};
use crate::error::Result;
use crate::geometry::{perp, rotate, Vec2};
use crate::nscd::bodies::centroid_state;
use crate::nscd::{Bodies, BodyInfo, ContactLaw, Imposed, NscdParams, Spring, System};

impl Scene {
    /// Validates the scene and builds the NSCD system at time 0.
    pub fn build(&self) -> Result<System> {
        let checked = check(self)?;
        let params = NscdParams {
            dt: self.simulation.dt,
            theta: checked.theta,
            gravity: self.simulation.gravity_or(NscdParams::default().gravity),
            alert_distance: checked.alert_distance,
            nlgs: checked.nlgs,
        };
        let mut sys = System::new(params, self.materials.len());
        let material = |name: &str| self.materials.iter().position(|m| m.name == name).unwrap_or(0);
        for c in &self.contacts {
            let law = ContactLaw {
                friction: c.friction,
                restitution_n: c.restitution.unwrap_or(0.0),
                restitution_t: c.tangential_restitution.unwrap_or(0.0),
            };
            sys.set_law(material(&c.between[0]), material(&c.between[1]), law);
        }
        (sys.bodies, sys.springs) = self.build_bodies(&checked)?;
        Ok(sys)
    }

    /// The bodies and springs of a validated scene (`checked`), as both 2D engines take them.
    pub(crate) fn build_bodies(&self, checked: &Checked) -> Result<(Bodies, Vec<Spring>)> {
        let (mut bodies, mut springs) = (Bodies::default(), Vec::new());
        let centroids: Vec<Vec2> = checked.bodies.iter().map(|b| b.centroid).collect();
        let thickness = self.simulation.thickness();
        for (spec, body) in self.bodies.iter().zip(checked.bodies.iter().cloned()) {
            let density = self.materials[body.material].density;
            let mut info = BodyInfo::new(spec.name.clone(), body.shape, body.material, density, thickness)?;
            if let Some(imp) = &spec.imposed {
                let [vx, vy, spin] = [imp.vx, imp.vy, imp.spin].map(|d| d.map(|x| x.to_harmonic()));
                info = info.with_imposed(Imposed::new(vx, vy, spin));
            }
            if let Some(load) = &spec.load {
                info = info.with_load(load.to_load());
            }
            if spec.is_fixed() {
                info = info.into_fixed();
            }
            let (q, u) = centroid_state(body.centroid, spec.position, spec.angle(), spec.velocity(), spec.spin());
            bodies.push(info, q, u);
        }
        for (spec, s) in self.springs.iter().zip(checked.springs.iter()) {
            let rel = |i: usize, p: [f64; 2]| [p[0] - centroids[i].x, p[1] - centroids[i].y];
            springs.push(Spring {
                a: s.a,
                point_a: rel(s.a, s.point_a),
                b: s.b,
                point_b: match s.b {
                    Some(b) => rel(b, s.point_b),
                    None => s.point_b,
                },
                k_n: spec.k_n,
                nu: spec.nu.unwrap_or(0.0),
                rest_length: s.rest_length,
                prestrain: spec.prestrain.unwrap_or(0.0),
                compression_only: spec.compression_only.unwrap_or(false),
                impulse: 0.0,
            });
        }
        Ok((bodies, springs))
    }

    /// The same scene with every non-fixed body's `position`, `angle`,
    /// `velocity` and `spin` replaced by the current state of `sys` (body `i`
    /// of the system is `self.bodies[i]`), so that a settled deposit can be
    /// saved and restarted. Fixed bodies are left as they are (they never move).
    /// Springs without a `rest_length` get their original rest length written
    /// out, so the restarted springs keep their law.
    ///
    /// The restart begins at time 0: harmonic loads and imposed velocities
    /// start again from their phase at `t = 0`, and the contact impulses of the
    /// warm start are not kept. If `sys` has fewer bodies than the scene, only
    /// the first ones are updated.
    pub fn with_state(&self, sys: &System) -> Scene {
        self.with_bodies(&sys.bodies)
    }

    /// As [`Scene::with_state`], from the bodies of either 2D engine.
    pub fn with_bodies(&self, bodies: &Bodies) -> Scene {
        let mut out = self.clone();
        let rest: Vec<Option<f64>> = match check(self) {
            Ok(c) => c.springs.iter().map(|s| Some(s.rest_length)).collect(),
            Err(_) => vec![None; self.springs.len()],
        };
        for (spring, rest) in out.springs.iter_mut().zip(rest) {
            if spring.rest_length.is_none() {
                spring.rest_length = rest;
            }
        }
        for (i, body) in out.bodies.iter_mut().enumerate() {
            if body.is_fixed() || i >= bodies.len() {
                continue;
            }
            let (q, u) = (bodies.q[i], bodies.u[i]);
            let (s, c) = q[2].sin_cos();
            let rc = rotate(centroid(body), c, s);
            let v = Vec2::new(u[0], u[1]) - u[2] * perp(rc);
            body.position = [q[0] - rc.x, q[1] - rc.y];
            body.angle = Some(q[2]);
            body.velocity = Some([v.x, v.y]);
            body.spin = Some(u[2]);
        }
        out
    }
}

/// Centroid of a body's shape in its scene body frame (m); zero if the shape is invalid.
fn centroid(b: &super::format::BodySpec) -> Vec2 {
    shape_of(b).map(|(_, c)| c).unwrap_or_else(|_| Vec2::zeros())
}
