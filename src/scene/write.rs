//! Writing a scene back as TOML, laid out like a hand-written scene: one
//! `[[body]]` table per body with `regular`, `imposed` and `load` as inline
//! tables, only the keys the scene has, and floats in their shortest form that
//! reads back to the same `f64`.

use super::format::{BodySpec, Drive, HarmonicSpec, Scene};
use std::fmt::Write;

/// A float as a TOML float that reads back exactly (`nan`, `inf` included).
pub(crate) fn float(x: f64) -> String {
    if x.is_nan() {
        "nan".into()
    } else if x.is_infinite() {
        if x > 0.0 { "inf" } else { "-inf" }.into()
    } else {
        // `Debug` is the shortest round-trip form and always has a `.` or an exponent.
        format!("{x:?}")
    }
}

/// A TOML basic string.
pub(crate) fn string(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            '\r' => out.push_str("\\r"),
            c if c.is_control() => {
                let _ = write!(out, "\\u{:04X}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn pair(p: [f64; 2]) -> String {
    format!("[{}, {}]", float(p[0]), float(p[1]))
}

fn harmonic(h: &HarmonicSpec) -> String {
    format!(
        "{{ mean = {}, amplitude = {}, frequency = {}, phase = {} }}",
        float(h.mean),
        float(h.amplitude),
        float(h.frequency),
        float(h.phase)
    )
}

pub(crate) fn drive(d: &Drive) -> String {
    match d {
        Drive::Constant(v) => float(*v),
        Drive::Harmonic(h) => harmonic(h),
    }
}

/// Appends `key = value` if `value` is present.
pub(crate) fn opt<T>(out: &mut String, key: &str, value: Option<T>, show: impl Fn(T) -> String) {
    if let Some(v) = value {
        let _ = writeln!(out, "{key} = {}", show(v));
    }
}

fn body(out: &mut String, b: &BodySpec) {
    out.push_str("\n[[body]]\n");
    if !b.name.is_empty() {
        let _ = writeln!(out, "name = {}", string(&b.name));
    }
    let _ = writeln!(out, "material = {}", string(&b.material));
    opt(out, "polygon", b.polygon.as_ref(), |p| {
        format!("[{}]", p.iter().map(|&v| pair(v)).collect::<Vec<_>>().join(", "))
    });
    opt(out, "regular", b.regular, |r| format!("{{ sides = {}, radius = {} }}", r.sides, float(r.radius)));
    opt(out, "disc", b.disc, float);
    opt(out, "parts", b.parts.as_ref(), |parts| {
        let part = |p: &Vec<[f64; 2]>| format!("[{}]", p.iter().map(|&v| pair(v)).collect::<Vec<_>>().join(", "));
        format!("[{}]", parts.iter().map(part).collect::<Vec<_>>().join(", "))
    });
    let _ = writeln!(out, "position = {}", pair(b.position));
    opt(out, "angle", b.angle, float);
    opt(out, "velocity", b.velocity, pair);
    opt(out, "spin", b.spin, float);
    opt(out, "fixed", b.fixed, |f| f.to_string());
    opt(out, "imposed", b.imposed, |i| {
        let parts: Vec<String> = [("vx", i.vx), ("vy", i.vy), ("spin", i.spin)]
            .iter()
            .filter_map(|(k, d)| d.as_ref().map(|d| format!("{k} = {}", drive(d))))
            .collect();
        if parts.is_empty() {
            "{}".into()
        } else {
            format!("{{ {} }}", parts.join(", "))
        }
    });
    opt(out, "load", b.load, |l| {
        format!(
            "{{ direction = {}, mean = {}, amplitude = {}, frequency = {}, phase = {} }}",
            pair(l.direction),
            float(l.mean),
            float(l.amplitude),
            float(l.frequency),
            float(l.phase)
        )
    });
}

/// The scene as TOML text.
pub(crate) fn to_toml(scene: &Scene) -> String {
    let mut out = String::new();
    super::common::write_simulation(&mut out, &scene.simulation);
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
    }
    if let Some(soft) = &scene.soft {
        out.push_str("\n[soft]\n");
        opt(&mut out, "model", soft.model.as_deref(), string);
        opt(&mut out, "normal_stiffness", soft.normal_stiffness, float);
        opt(&mut out, "max_overlap_ratio", soft.max_overlap_ratio, float);
        opt(&mut out, "tangential_ratio", soft.tangential_ratio, float);
        opt(&mut out, "dt", soft.dt.as_ref(), |dt| match dt {
            super::soft::SoftDt::Seconds(s) => float(*s),
            super::soft::SoftDt::Word(w) => string(w),
        });
        opt(&mut out, "dt_fraction", soft.dt_fraction, float);
        opt(&mut out, "alert_distance", soft.alert_distance, float);
    }
    super::common::write_output(&mut out, scene.output.as_ref());
    crate::scene::common::write_settlement(&mut out, scene.settlement.as_ref());
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
        opt(&mut out, "point", s.point, pair);
        opt(&mut out, "anchor", s.anchor, pair);
        opt(&mut out, "other", s.other.as_deref(), string);
        opt(&mut out, "other_point", s.other_point, pair);
        let _ = writeln!(out, "k_n = {}", float(s.k_n));
        opt(&mut out, "nu", s.nu, float);
        opt(&mut out, "rest_length", s.rest_length, float);
        opt(&mut out, "prestrain", s.prestrain, float);
        opt(&mut out, "compression_only", s.compression_only, |c| c.to_string());
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floats_and_strings_read_back() {
        for x in [0.0, -0.0, 0.1, 1.0, -3.5, 1e-7, 1e16, 1.2345678901234567e-300, f64::MAX, f64::INFINITY] {
            let text = format!("x = {}", float(x));
            let v: toml::Table = toml::from_str(&text).unwrap();
            assert_eq!(v["x"].as_float().unwrap().to_bits(), x.to_bits(), "{text}");
        }
        for s in ["plain", "quote \" and \\ backslash", "tab\tnew\nline\u{7f}\u{1}", "é ü 漢"] {
            let text = format!("x = {}", string(s));
            let v: toml::Table = toml::from_str(&text).unwrap();
            assert_eq!(v["x"].as_str().unwrap(), s, "{text}");
        }
    }
}
