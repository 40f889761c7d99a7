//! Validation of a parsed 3D NSCD scene: every value is checked (finite, in range, names resolved, hulls with a
//! volume, unit quaternions) and resolved into what building a [`System3`](crate::nscd::d3::system::System3)
//! needs. Each error is one line naming the section or body and the key, as in 2D scenes, e.g.
//! `body[2] 'rock': polyhedron.vertices: degenerate polyhedron: the vertices span no volume (…)` or
//! `body[1] 'cube': orientation.quaternion: must be a unit quaternion [w, x, y, z] (|q| = 1 to 1e-6), got |q| = 2`.
//!
//! The sections the 3D scene shares with the 2D one — `[nscd]`, `[[material]]`, `[[contact]]` — are checked by the
//! 2D scene's own validation ([`crate::scene::Scene`]) on a probe scene that carries them and one disc, so that
//! their keys, defaults and messages are the 2D scene's word for word; then what the 3D engine does not build is
//! refused: `nscd.solver = "interior_point"`. Imposed velocities, loads and springs
//! are checked by [`super::drives`].

use super::drives::{check_drives, check_springs, CheckedSpring3};
use super::format::{BodySpec3, Scene3};
use crate::error::{clip, Error, Result};
use crate::geometry::{Polyhedron, Pose, Solid, SolidError, Vec3, MAX_LENGTH, MIN_SIZE};
use crate::nscd::d3::overlaps::Overlaps;
use crate::nscd::d3::system::Params3;
use crate::nscd::nlgs::{NlgsSettings, Solver};
use crate::scene::common::{check_output, check_simulation};
use crate::scene::validate::{err, label, num};
use crate::scene::{Material, Scene, SceneFile};
use crate::space::detection::FaceGaps;
use crate::space::loads::{Imposed3, Load3};
use nalgebra::{Quaternion, UnitQuaternion};
use std::collections::HashMap;

/// A `quaternion` is accepted when its norm is 1 to this (a quaternion written with 7 significant digits passes);
/// it is then normalised.
pub const QUATERNION_TOLERANCE: f64 = 1e-6;

/// A body resolved by validation.
#[derive(Debug, Clone)]
pub(crate) struct CheckedBody3 {
    /// Shape in its principal frame.
    pub solid: Solid,
    /// The principal frame in the scene's body frame (the hull's centroid and axes; the identity for a box or a
    /// sphere; for a plane the rotation taking `+z` to its normal).
    pub frame: Pose,
    /// Rotation of the scene's body frame (`orientation`).
    pub rotation: UnitQuaternion<f64>,
    pub material: usize,
    /// Imposed velocity components.
    pub imposed: Imposed3,
    /// Forces and moments.
    pub loads: Vec<Load3>,
}

/// Everything validation resolved.
#[derive(Debug, Clone)]
pub(crate) struct Checked3 {
    pub params: Params3,
    pub bodies: Vec<CheckedBody3>,
    pub springs: Vec<CheckedSpring3>,
}

/// A 2D scene with one disc, into which the shared sections are copied ([`check_shared`]).
const PROBE: &str = "[simulation]\nengine = \"nscd\"\ndt = 1.0\nduration = 1.0\n\
                     [[body]]\nmaterial = \"\"\ndisc = 1.0\nposition = [0.0, 0.0]\n";

/// Checks the whole scene, one section after the other, and resolves shapes, frames and defaults.
pub(crate) fn check(scene: &Scene3) -> Result<Checked3> {
    let sim = &scene.simulation;
    match sim.dimension {
        Some(3) => {}
        Some(d) => return err(format!("simulation.dimension: must be 3 for a 3D NSCD scene, got {d}")),
        None => return err("simulation.dimension: a 3D NSCD scene says dimension = 3".into()),
    }
    check_simulation(sim, "nscd", 3)?;
    let (theta, nlgs) = check_shared(scene)?;
    let face_gaps = crate::scene::validate::named(
        "nscd.face_gaps",
        "rule",
        scene.nscd.as_ref().and_then(|n| n.face_gaps.as_deref()),
        FaceGaps::default(),
        FaceGaps::from_name,
        "'exact' or 'common_plane'",
    )?;
    let overlaps = crate::scene::validate::named(
        "nscd.overlaps",
        "rule",
        scene.nscd.as_ref().and_then(|n| n.overlaps.as_deref()),
        Overlaps::default(),
        Overlaps::from_name,
        "'kept' or 'held'",
    )?;
    let materials: HashMap<&str, usize> =
        scene.materials.iter().enumerate().map(|(i, m)| (m.name.as_str(), i)).collect();
    let (bodies, names) = check_bodies(scene, &materials)?;
    let springs = check_springs(scene, &names, &bodies)?;
    check_output(scene.output.as_ref(), true, |name| names.get(name).copied())?;
    if scene.settlement.is_some() {
        scene.acceleration()?;
    }
    let gravity = sim.gravity_or(Params3::default().gravity.into());
    let params = Params3 {
        dt: sim.dt,
        theta,
        gravity: Vec3::from(gravity),
        alert_distance: alert_distance(scene, &bodies),
        face_gaps,
        overlaps,
        nlgs,
    };
    Ok(Checked3 { params, bodies, springs })
}

/// `[nscd]`, `[[material]]` and `[[contact]]` by the 2D scene's validation (module doc): θ and the solver's
/// settings, then the refusal of the settings the 3D engine does not build. The probe's disc is of a material of
/// its own (density 1, a name none of the scene's has), appended after the scene's so that their indices in the
/// messages are the scene's.
fn check_shared(scene: &Scene3) -> Result<(f64, NlgsSettings)> {
    let mut probe: Scene = toml::from_str(PROBE).map_err(|e| Error::Scene(format!("probe scene: {e}")))?;
    let mut own = String::from("probe");
    while scene.materials.iter().any(|m| m.name == own) {
        own.push('_');
    }
    // The 3D-only keys are read by `check`.
    probe.nscd = scene.nscd.clone().map(|n| crate::scene::format::NscdSection { face_gaps: None, overlaps: None, ..n });
    probe.contacts = scene.contacts.clone();
    probe.materials = scene.materials.clone();
    probe.materials.push(Material { name: own.clone(), density: 1.0 });
    probe.bodies[0].material = own.clone();
    let checked = crate::scene::validate::check(&probe)?;
    for (i, c) in scene.contacts.iter().enumerate() {
        if let Some(name) = c.between.iter().find(|name| **name == own) {
            return err(format!("contact[{i}].between: unknown material '{}'", clip(name)));
        }
    }
    let nlgs = checked.nlgs;
    if nlgs.solver == Solver::InteriorPoint {
        return err(
            "nscd.solver: 'interior_point' solves the step as a linear complementarity problem, which only the 2D \
             friction cone allows: use 'nlgs' or 'apgd' in 3D"
                .into(),
        );
    }
    Ok((checked.theta, nlgs))
}

/// `ctx: must be finite, got [x, y, z]` unless every component is finite.
fn finite3(ctx: &str, v: [f64; 3]) -> Result<Vec3> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from(v))
    } else {
        err(format!("{ctx}: must be finite, got {}", show(&v)))
    }
}

/// `[x, y, …]` in the messages' notation.
fn show(v: &[f64]) -> String {
    format!("[{}]", v.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", "))
}

/// The shape of a body in its principal frame and that frame in the scene's body frame, or the message (naming
/// the key) of why the shape is refused.
pub(crate) fn solid_of(b: &BodySpec3) -> std::result::Result<(Solid, Pose), String> {
    let given = [b.polyhedron.is_some(), b.cuboid.is_some(), b.sphere.is_some(), b.plane.is_some()];
    match given.iter().filter(|&&x| x).count() {
        0 => return Err("shape: missing, give exactly one of polyhedron, box, sphere, plane".into()),
        1 => {}
        _ => return Err("shape: give exactly one of polyhedron, box, sphere, plane, not several".into()),
    }
    let origin = Pose::at(Vec3::zeros());
    if let Some(p) = &b.polyhedron {
        let angle = p.merge_angle.unwrap_or(Polyhedron::MERGE_ANGLE);
        let key = |e: &SolidError| match e {
            SolidError::BadMergeAngle(_) => "polyhedron.merge_angle",
            _ => "polyhedron.vertices",
        };
        Polyhedron::from_points(&p.vertices, angle)
            .map(|(p, frame)| (Solid::Polyhedron(p), frame))
            .map_err(|e| format!("{}: {e}", key(&e)))
    } else if let Some(c) = &b.cuboid {
        Polyhedron::cuboid(c.half).map(|p| (Solid::Polyhedron(p), origin)).map_err(|e| format!("box.half: {e}"))
    } else if let Some(s) = &b.sphere {
        if s.radius.is_finite() && s.radius > 0.0 {
            Ok((Solid::Sphere { radius: s.radius }, origin))
        } else {
            Err(format!("sphere.radius: must be positive and finite, got {}", num(s.radius)))
        }
    } else {
        let n = b.plane.map_or([0.0, 0.0, 1.0], |p| p.normal);
        let normal = Vec3::from(n)
            .try_normalize(0.0)
            .filter(|v| v.iter().all(|x| x.is_finite()))
            .ok_or_else(|| format!("plane.normal: must be a finite non-zero vector, got {}", show(&n)))?;
        // The half-space is z ≤ 0 of its frame: the frame's +z is the normal.
        let rotation = UnitQuaternion::rotation_between(&Vec3::z(), &normal)
            .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vec3::x_axis(), std::f64::consts::PI));
        Ok((Solid::HalfSpace, Pose { position: Vec3::zeros(), rotation }))
    }
}

/// The rotation of a body's scene frame (`orientation`; the identity without one), or the message naming the key.
pub(crate) fn rotation_of(b: &BodySpec3) -> std::result::Result<UnitQuaternion<f64>, String> {
    let Some(o) = b.orientation else { return Ok(UnitQuaternion::identity()) };
    if b.plane.is_some() {
        return Err("orientation: a plane is oriented by its normal, remove orientation".into());
    }
    match (o.quaternion, o.rotation_vector) {
        (Some(_), Some(_)) => Err("orientation: give one of quaternion, rotation_vector, not both".into()),
        (None, None) => Err("orientation: give quaternion = [w, x, y, z] or rotation_vector = [rx, ry, rz]".into()),
        (Some(q), None) => {
            if !q.iter().all(|x| x.is_finite()) {
                return Err(format!("orientation.quaternion: must be finite, got {}", show(&q)));
            }
            let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
            if (norm - 1.0).abs() > QUATERNION_TOLERANCE {
                return Err(format!(
                    "orientation.quaternion: must be a unit quaternion [w, x, y, z] (|q| = 1 to {QUATERNION_TOLERANCE:e}), \
                     got |q| = {}",
                    num(norm)
                ));
            }
            Ok(UnitQuaternion::new_normalize(Quaternion::new(q[0], q[1], q[2], q[3])))
        }
        (None, Some(r)) => {
            if !r.iter().all(|x| x.is_finite()) {
                return Err(format!("orientation.rotation_vector: must be finite, got {}", show(&r)));
            }
            Ok(crate::space::bodies::rotation(Vec3::from(r)))
        }
    }
}

/// Checks `[[body]]`: names, refused keys, materials, shapes, sizes, placement, state, mass; the resolved bodies
/// and the index of each name.
fn check_bodies<'a>(
    scene: &'a Scene3,
    materials: &HashMap<&str, usize>,
) -> Result<(Vec<CheckedBody3>, HashMap<&'a str, usize>)> {
    if scene.bodies.is_empty() {
        return err("body: the scene has no [[body]]".into());
    }
    let mut names: HashMap<&str, usize> = HashMap::new();
    let mut bodies = Vec::with_capacity(scene.bodies.len());
    for (i, b) in scene.bodies.iter().enumerate() {
        let label = label("body", i, &b.name);
        let ctx = |field: &str| format!("{label}: {field}");
        let scene_err = |e: String| Error::Scene(format!("{label}: {e}"));
        if !b.name.is_empty() {
            if let Some(j) = names.insert(b.name.as_str(), i) {
                return err(format!("{}: duplicate body name (also body[{j}])", ctx("name")));
            }
        }
        let (imposed, loads) = check_drives(&label, b)?;
        let Some(&material) = materials.get(b.material.as_str()) else {
            return err(format!("{}: unknown material '{}'", ctx("material"), clip(&b.material)));
        };
        let (solid, frame) = solid_of(b).map_err(scene_err)?;
        if let Solid::HalfSpace = solid {
            if !b.is_fixed() {
                return err(format!("{}: a half-space can only be a fixed body, add fixed = true", ctx("plane")));
            }
        } else {
            let size = solid.radius();
            if !(MIN_SIZE..=MAX_LENGTH).contains(&size) || size + frame.position.norm() > MAX_LENGTH {
                return err(format!(
                    "{}: the body's size {size:e} m is outside [{MIN_SIZE:e}, {MAX_LENGTH:e}] m",
                    ctx("shape")
                ));
            }
        }
        let position = finite3(&ctx("position"), b.position)?;
        if position.amax() > MAX_LENGTH {
            return err(format!(
                "{}: coordinates must be within ±{MAX_LENGTH:e} m, got {}",
                ctx("position"),
                show(&b.position)
            ));
        }
        let rotation = rotation_of(b).map_err(scene_err)?;
        let velocity = finite3(&ctx("velocity"), b.velocity())?;
        let spin = finite3(&ctx("spin"), b.spin())?;
        if b.is_fixed() && velocity != Vec3::zeros() {
            return err(format!(
                "{}: a fixed body does not move (give a moving wall fixed = false and imposed velocities)",
                ctx("velocity")
            ));
        }
        if b.is_fixed() && spin != Vec3::zeros() {
            return err(format!(
                "{}: a fixed body does not turn (give a moving wall fixed = false and imposed velocities)",
                ctx("spin")
            ));
        }
        if !b.is_fixed() {
            let density = scene.materials[material].density;
            let (volume, second) = solid.mass_properties();
            let (mass, inertia) = (density * volume, second * density);
            if !(mass.is_finite() && mass > 0.0 && inertia.iter().all(|x| x.is_finite() && *x > 0.0)) {
                return err(format!(
                    "{}: mass {mass:e} kg or principal inertia {} kg m^2 (density × volume) is not positive and finite",
                    ctx("shape"),
                    show(inertia.as_slice())
                ));
            }
        }
        bodies.push(CheckedBody3 { solid, frame, rotation, material, imposed, loads });
    }
    Ok((bodies, names))
}

/// The alert distance (m): `nscd.alert_distance`, else [`crate::nscd::system::DEFAULT_ALERT_FRACTION`] × the
/// smallest inner radius (a polyhedron's inradius, a sphere's radius) of the non-fixed bodies (of all finite bodies
/// if none moves), as in 2D; [`crate::nscd::bodies::EMPTY_ALERT_DISTANCE`] if no body is finite.
fn alert_distance(scene: &Scene3, bodies: &[CheckedBody3]) -> f64 {
    if let Some(a) = scene.nscd.as_ref().and_then(|n| n.alert_distance) {
        return a;
    }
    let inner = |s: &Solid| match s {
        Solid::Polyhedron(p) => p.inradius,
        Solid::Sphere { radius } => *radius,
        Solid::HalfSpace => f64::INFINITY,
    };
    let a = crate::nscd::system::default_alert_distance(
        scene.bodies.iter().zip(bodies).map(|(s, b)| (s.is_fixed(), inner(&b.solid))),
    );
    if a.is_finite() {
        a
    } else {
        crate::nscd::bodies::EMPTY_ALERT_DISTANCE
    }
}
