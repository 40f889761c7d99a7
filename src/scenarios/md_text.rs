//! Writing MD scenes as TOML text (the format of `docs/scene-format.md`, "MD
//! scenes"), for the ready-made MD tests: floats in their shortest exact form so
//! a generated scene reads back to the same numbers.

use crate::md::V3;
use std::fmt::Write;

/// `[x, y, z]`.
pub fn v3(v: V3) -> String {
    format!("[{:?}, {:?}, {:?}]", v[0], v[1], v[2])
}

/// One `[[body]]` sphere.
pub fn sphere(out: &mut String, name: &str, material: &str, radius: f64, position: V3, velocity: Option<V3>) {
    let _ = writeln!(
        out,
        "[[body]]\nname = \"{name}\"\nmaterial = \"{material}\"\nsphere = {radius:?}\nposition = {}",
        v3(position)
    );
    if let Some(v) = velocity {
        let _ = writeln!(out, "velocity = {}", v3(v));
    }
    out.push('\n');
}

/// One `[[material]]`.
pub fn material(out: &mut String, name: &str, density: f64, young: f64, poisson: f64) {
    let _ = writeln!(
        out,
        "[[material]]\nname = \"{name}\"\ndensity = {density:?}\nyoung = {young:?}\npoisson = {poisson:?}\n"
    );
}

/// A plane `[[wall]]`, with an optional `servo = {...}` inline table body.
pub fn plane(out: &mut String, name: &str, material: &str, point: V3, normal: V3, servo: Option<&str>) {
    let _ = writeln!(
        out,
        "[[wall]]\nname = \"{name}\"\nmaterial = \"{material}\"\nplane = {{ point = {}, normal = {} }}",
        v3(point),
        v3(normal)
    );
    if let Some(s) = servo {
        let _ = writeln!(out, "servo = {{ {s} }}");
    }
    out.push('\n');
}
