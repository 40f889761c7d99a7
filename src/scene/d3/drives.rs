//! Validation of what drives the bodies of a 3D NSCD scene besides gravity: imposed velocities (`imposed`),
//! external forces and moments (`load`, `torque`) and the sublayer springs of law (17) (`[[spring]]`), resolved
//! into what the engine takes ([`crate::space::loads`], [`crate::space::springs`]). Errors are one line naming the
//! body or spring and the key, with the 2D scene's wording.

use super::format::{BodySpec3, LoadSpec3, Scene3};
use super::validate::CheckedBody3;
use crate::error::{clip, Result};
use crate::geometry::Vec3;
use crate::scene::validate::{check_drive, err, finite, non_negative, num, positive};
use crate::space::loads::{Imposed3, Load3};
use std::collections::HashMap;

/// Checks a body's `imposed`, `load` and `torque` (`label` names the body in messages) and resolves them.
pub(crate) fn check_drives(label: &str, b: &BodySpec3) -> Result<(Imposed3, Vec<Load3>)> {
    let ctx = |field: &str| format!("{label}: {field}");
    let mut imposed = Imposed3::default();
    if let Some(imp) = &b.imposed {
        if b.is_fixed() {
            return err(format!("{}: a fixed body cannot have imposed velocities", ctx("imposed")));
        }
        for (k, (name, d)) in [("vx", imp.vx), ("vy", imp.vy), ("vz", imp.vz)].into_iter().enumerate() {
            if let Some(d) = d {
                check_drive(&ctx(&format!("imposed.{name}")), d)?;
                imposed.velocity[k] = Some(d.to_harmonic());
            }
        }
        if let Some(spin) = imp.spin {
            for (k, d) in spin.iter().enumerate() {
                check_drive(&ctx(&format!("imposed.spin[{k}]")), *d)?;
            }
            imposed.spin = Some(spin.map(|d| d.to_harmonic()));
        }
    }
    let mut loads = Vec::new();
    for (key, spec) in [("load", &b.load), ("torque", &b.torque)] {
        let Some(l) = spec else { continue };
        if b.is_fixed() {
            return err(format!("{}: a fixed body cannot carry a {key}", ctx(key)));
        }
        let direction = check_load(&ctx(key), l)?;
        loads.push(if key == "load" {
            Load3::force(direction, l.value())
        } else {
            Load3::moment(direction, l.value())
        });
    }
    Ok((imposed, loads))
}

/// A load's direction (finite, non-zero) and finite harmonic coefficients; the direction.
fn check_load(ctx: &str, l: &LoadSpec3) -> Result<Vec3> {
    let d = Vec3::from(l.direction);
    if !(d.iter().all(|x| x.is_finite()) && d.norm() > 0.0 && d.norm().is_finite()) {
        let show = l.direction.iter().map(|&x| num(x)).collect::<Vec<_>>().join(", ");
        return err(format!("{ctx}.direction: must be a finite non-zero vector, got [{show}]"));
    }
    finite(&format!("{ctx}.mean"), l.mean)?;
    finite(&format!("{ctx}.amplitude"), l.amplitude)?;
    finite(&format!("{ctx}.frequency"), l.frequency)?;
    finite(&format!("{ctx}.phase"), l.phase)?;
    Ok(d)
}

/// A spring resolved by validation: bodies, attachment points in the principal frames (a world anchor as it is)
/// and the rest length.
#[derive(Debug, Clone, Copy)]
pub(crate) struct CheckedSpring3 {
    pub a: usize,
    pub point_a: Vec3,
    pub b: Option<usize>,
    pub point_b: Vec3,
    pub rest_length: f64,
}

/// Checks `[[spring]]`: bodies, attachments, law coefficients, rest length (default: the initial length).
pub(crate) fn check_springs(
    scene: &Scene3,
    names: &HashMap<&str, usize>,
    bodies: &[CheckedBody3],
) -> Result<Vec<CheckedSpring3>> {
    let finite3 = |ctx: &str, p: [f64; 3]| -> Result<Vec3> {
        for (k, &x) in p.iter().enumerate() {
            finite(&format!("{ctx}[{k}]"), x)?;
        }
        Ok(Vec3::from(p))
    };
    // A point given in body i's scene frame: in the world, and in the principal frame about the centroid.
    let place = |i: usize, p: Vec3| -> (Vec3, Vec3) {
        let (spec, body) = (&scene.bodies[i], &bodies[i]);
        let world = Vec3::from(spec.position) + body.rotation * p;
        (world, body.frame.rotation.inverse_transform_vector(&(p - body.frame.position)))
    };
    let mut springs = Vec::with_capacity(scene.springs.len());
    for (i, s) in scene.springs.iter().enumerate() {
        let ctx = |field: &str| format!("spring[{i}].{field}");
        let Some(&a) = names.get(s.body.as_str()) else {
            return err(format!("{}: unknown body '{}'", ctx("body"), clip(&s.body)));
        };
        let (end_a, point_a) = place(a, finite3(&ctx("point"), s.point.unwrap_or([0.0; 3]))?);
        let (b, point_b, end_b) = match (&s.anchor, &s.other) {
            (Some(_), Some(_)) => return err(format!("{}: give either anchor or other, not both", ctx("anchor"))),
            (None, None) => return err(format!("{}: missing, give either anchor or other", ctx("anchor"))),
            (Some(anchor), None) => {
                if s.other_point.is_some() {
                    return err(format!("{}: only allowed with other", ctx("other_point")));
                }
                let p = finite3(&ctx("anchor"), *anchor)?;
                (None, p, p)
            }
            (None, Some(other)) => {
                let Some(&b) = names.get(other.as_str()) else {
                    return err(format!("{}: unknown body '{}'", ctx("other"), clip(other)));
                };
                if b == a {
                    return err(format!("{}: the spring joins body '{}' to itself", ctx("other"), clip(other)));
                }
                let (end, p) = place(b, finite3(&ctx("other_point"), s.other_point.unwrap_or([0.0; 3]))?);
                (Some(b), p, end)
            }
        };
        non_negative(&ctx("k_n"), s.k_n)?;
        non_negative(&ctx("nu"), s.nu.unwrap_or(0.0))?;
        finite(&ctx("prestrain"), s.prestrain.unwrap_or(0.0))?;
        let length = (end_a - end_b).norm();
        let rest_length = match s.rest_length {
            Some(l) => positive(&ctx("rest_length"), l)?,
            None if length > 0.0 && length.is_finite() => length,
            None => {
                return err(format!(
                    "{}: the initial length is {}, give a positive rest_length",
                    ctx("rest_length"),
                    num(length)
                ))
            }
        };
        springs.push(CheckedSpring3 { a, point_a, b, point_b, rest_length });
    }
    Ok(springs)
}
