//! Writing an MD scene back as TOML, laid out like a hand-written scene: the
//! sections in the order of the documentation, one `[[wall]]` and one `[[body]]`
//! table per entry with `equilibrium`, `plane`, `disc`, `cylinder` and `servo` as
//! inline tables, only the keys the scene has, and floats in their shortest form
//! that reads back to the same `f64` (the helpers of the NSCD writer).

use super::format::{MdContact, MdScene, ServoSpec, SphereSpec, WallSpec};
use crate::scene::common::inline;
use crate::scene::write::{float, opt, string};
use std::fmt::Write;

fn triple(v: [f64; 3]) -> String {
    format!("[{}, {}, {}]", float(v[0]), float(v[1]), float(v[2]))
}

fn servo(s: &ServoSpec) -> String {
    inline(&[
        ("mass", Some(float(s.mass))),
        ("viscosity", Some(float(s.viscosity))),
        ("stress", s.stress.map(float)),
        ("force", s.force.map(float)),
        ("amplitude", s.amplitude.map(float)),
        ("period", s.period.map(float)),
        ("area", s.area.map(float)),
    ])
}

fn contact(out: &mut String, c: &MdContact) {
    out.push_str("\n[[contact]]\n");
    let _ = writeln!(out, "between = [{}, {}]", string(&c.between[0]), string(&c.between[1]));
    let _ = writeln!(out, "model = {}", string(&c.model));
    for (key, value) in [
        ("friction", c.friction),
        ("static_friction", c.static_friction),
        ("dynamic_friction", c.dynamic_friction),
        ("restitution", c.restitution),
        ("normal_damping_ratio", c.normal_damping_ratio),
        ("tangential_damping_ratio", c.tangential_damping_ratio),
        ("normal_stiffness", c.normal_stiffness),
        ("tangential_stiffness", c.tangential_stiffness),
        ("normal_damping", c.normal_damping),
        ("tangential_damping", c.tangential_damping),
    ] {
        opt(out, key, value, float);
    }
}

fn wall(out: &mut String, w: &WallSpec) {
    out.push_str("\n[[wall]]\n");
    let _ = writeln!(out, "name = {}", string(&w.name));
    let _ = writeln!(out, "material = {}", string(&w.material));
    opt(out, "plane", w.plane, |p| inline(&[("point", Some(triple(p.point))), ("normal", Some(triple(p.normal)))]));
    opt(out, "disc", w.disc, |d| {
        inline(&[
            ("point", Some(triple(d.point))),
            ("normal", Some(triple(d.normal))),
            ("radius", Some(float(d.radius))),
        ])
    });
    opt(out, "cylinder", w.cylinder, |c| {
        inline(&[
            ("axis_point", Some(triple(c.axis_point))),
            ("axis", Some(triple(c.axis))),
            ("radius", Some(float(c.radius))),
        ])
    });
    opt(out, "servo", w.servo.as_ref(), servo);
}

fn body(out: &mut String, b: &SphereSpec) {
    out.push_str("\n[[body]]\n");
    if !b.name.is_empty() {
        let _ = writeln!(out, "name = {}", string(&b.name));
    }
    let _ = writeln!(out, "material = {}", string(&b.material));
    let _ = writeln!(out, "sphere = {}", float(b.sphere));
    let _ = writeln!(out, "position = {}", triple(b.position));
    opt(out, "velocity", b.velocity, triple);
    opt(out, "spin", b.spin, triple);
}

/// The scene as TOML text.
pub(crate) fn to_toml(scene: &MdScene) -> String {
    let mut out = String::new();
    crate::scene::common::write_simulation(&mut out, &scene.simulation);
    if let Some(m) = &scene.md {
        out.push_str("\n[md]\n");
        opt(&mut out, "integrator", m.integrator.as_deref(), string);
        opt(&mut out, "gear", m.gear.as_deref(), string);
        opt(&mut out, "skin", m.skin, float);
        opt(&mut out, "background_damping", m.background_damping, float);
        opt(&mut out, "background_rotational_damping", m.background_rotational_damping, float);
        opt(&mut out, "threads", m.threads, |t| t.to_string());
    }
    crate::scene::common::write_output(&mut out, scene.output.as_ref());
    crate::scene::common::write_settlement(&mut out, scene.settlement.as_ref());
    for s in &scene.symmetry {
        out.push_str("\n[[symmetry]]\n");
        let _ = writeln!(out, "point = {}", triple(s.point));
        let _ = writeln!(out, "normal = {}", triple(s.normal));
    }
    for m in &scene.materials {
        out.push_str("\n[[material]]\n");
        let _ = writeln!(out, "name = {}", string(&m.name));
        let _ = writeln!(out, "density = {}", float(m.density));
        let _ = writeln!(out, "young = {}", float(m.young));
        let _ = writeln!(out, "poisson = {}", float(m.poisson));
    }
    for c in &scene.contacts {
        contact(&mut out, c);
    }
    for w in &scene.walls {
        wall(&mut out, w);
    }
    for b in &scene.bodies {
        body(&mut out, b);
    }
    out
}
