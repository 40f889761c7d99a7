//! Writing a 3D NSCD scene back as TOML, laid out like a hand-written scene: the sections in the order of the 2D
//! writer, one `[[body]]` table per body with its shape and `orientation` as inline tables, only the keys the
//! scene has, and floats in their shortest form that reads back to the same `f64` (the 2D writer's helpers).

use super::format::{BodySpec3, LoadSpec3, Scene3};
use crate::scene::common::{inline, write_output, write_settlement, write_simulation};
use crate::scene::write::{drive, float, opt, string};
use std::fmt::Write;

/// `[x, y, …]` of floats that read back exactly.
fn list(v: &[f64]) -> String {
    format!("[{}]", v.iter().map(|&x| float(x)).collect::<Vec<_>>().join(", "))
}

fn body(out: &mut String, b: &BodySpec3) {
    out.push_str("\n[[body]]\n");
    if !b.name.is_empty() {
        let _ = writeln!(out, "name = {}", string(&b.name));
    }
    let _ = writeln!(out, "material = {}", string(&b.material));
    opt(out, "polyhedron", b.polyhedron.as_ref(), |p| {
        let vertices = format!("[{}]", p.vertices.iter().map(|v| list(v)).collect::<Vec<_>>().join(", "));
        inline(&[("vertices", Some(vertices)), ("merge_angle", p.merge_angle.map(float))])
    });
    opt(out, "box", b.cuboid, |c| inline(&[("half", Some(list(&c.half)))]));
    opt(out, "sphere", b.sphere, |s| inline(&[("radius", Some(float(s.radius)))]));
    opt(out, "plane", b.plane, |p| inline(&[("normal", Some(list(&p.normal)))]));
    let _ = writeln!(out, "position = {}", list(&b.position));
    opt(out, "orientation", b.orientation, |o| {
        inline(&[
            ("quaternion", o.quaternion.map(|q| list(&q))),
            ("rotation_vector", o.rotation_vector.map(|r| list(&r))),
        ])
    });
    opt(out, "velocity", b.velocity, |v| list(&v));
    opt(out, "spin", b.spin, |w| list(&w));
    opt(out, "fixed", b.fixed, |f| f.to_string());
    opt(out, "imposed", b.imposed, |i| {
        let spin = i.spin.map(|w| format!("[{}]", w.iter().map(drive).collect::<Vec<_>>().join(", ")));
        let d = |x: Option<crate::scene::Drive>| x.as_ref().map(drive);
        inline(&[("vx", d(i.vx)), ("vy", d(i.vy)), ("vz", d(i.vz)), ("spin", spin)])
    });
    let load = |l: LoadSpec3| {
        inline(&[
            ("direction", Some(list(&l.direction))),
            ("mean", Some(float(l.mean))),
            ("amplitude", Some(float(l.amplitude))),
            ("frequency", Some(float(l.frequency))),
            ("phase", Some(float(l.phase))),
        ])
    };
    opt(out, "load", b.load, load);
    opt(out, "torque", b.torque, load);
}

/// The scene as TOML text.
pub(crate) fn to_toml(scene: &Scene3) -> String {
    let mut out = String::new();
    write_simulation(&mut out, &scene.simulation);
    if let Some(n) = &scene.nscd {
        out.push_str("\n[nscd]\n");
        opt(&mut out, "theta", n.theta, float);
        opt(&mut out, "criterion", n.criterion.as_deref(), string);
        opt(&mut out, "tolerance", n.tolerance, float);
        opt(&mut out, "min_iterations", n.min_iterations, |i| i.to_string());
        opt(&mut out, "max_iterations", n.max_iterations, |i| i.to_string());
        opt(&mut out, "max_factor", n.max_factor, float);
        opt(&mut out, "symmetric", n.symmetric, |b| b.to_string());
        opt(&mut out, "relaxation", n.relaxation, float);
        opt(&mut out, "anderson", n.anderson, |i| i.to_string());
        opt(&mut out, "measure", n.measure.as_deref(), string);
        opt(&mut out, "solver", n.solver.as_deref(), string);
        opt(&mut out, "on_stall", n.on_stall.as_deref(), string);
        opt(&mut out, "stall_max_iterations", n.stall_max_iterations, |i| i.to_string());
        opt(&mut out, "alert_distance", n.alert_distance, float);
        opt(&mut out, "face_gaps", n.face_gaps.as_deref(), string);
        opt(&mut out, "overlaps", n.overlaps.as_deref(), string);
    }
    write_output(&mut out, scene.output.as_ref());
    write_settlement(&mut out, scene.settlement.as_ref());
    for m in &scene.materials {
        out.push_str("\n[[material]]\n");
        let _ = writeln!(out, "name = {}", string(&m.name));
        let _ = writeln!(out, "density = {}", float(m.density));
    }
    for c in &scene.contacts {
        out.push_str("\n[[contact]]\n");
        let _ = writeln!(out, "between = [{}, {}]", string(&c.between[0]), string(&c.between[1]));
        let _ = writeln!(out, "friction = {}", float(c.friction));
        opt(&mut out, "restitution", c.restitution, float);
        opt(&mut out, "tangential_restitution", c.tangential_restitution, float);
    }
    for b in &scene.bodies {
        body(&mut out, b);
    }
    for s in &scene.springs {
        out.push_str("\n[[spring]]\n");
        let _ = writeln!(out, "body = {}", string(&s.body));
        opt(&mut out, "point", s.point, |p| list(&p));
        opt(&mut out, "anchor", s.anchor, |p| list(&p));
        opt(&mut out, "other", s.other.as_deref(), string);
        opt(&mut out, "other_point", s.other_point, |p| list(&p));
        let _ = writeln!(out, "k_n = {}", float(s.k_n));
        opt(&mut out, "nu", s.nu, float);
        opt(&mut out, "rest_length", s.rest_length, float);
        opt(&mut out, "prestrain", s.prestrain, float);
        opt(&mut out, "compression_only", s.compression_only, |c| c.to_string());
    }
    out
}
