//! Validation of a parsed scene: every value is checked (finite, in range,
//! names resolved, shapes convex) and resolved into the data needed to build a
//! system. Each error is one line naming the section or body and the field, e.g.
//! `body[3] 'block': polygon: non-convex polygon: the turn at vertex 2 is clockwise`
//! or, for a compound body, `body[3] 'sleeper': parts[1]: non-convex polygon: …`.

use super::format::{BodySpec, Drive, NscdSection, Scene};
use crate::error::{Error, Result};
use crate::geometry::{rotate, Compound, ConvexPolygon, GeometryError, Shape, Vec2};
use crate::nscd::nlgs::{OnStall, Solver};
use crate::nscd::{Measure, NlgsSettings, NscdParams, Policy};
use crate::scene::SceneFile;
use std::collections::HashMap;

/// Largest number of steps a scene may ask for (2⁵³, where `f64` stops counting exactly).
pub const MAX_STEPS: f64 = 9.007_199_254_740_992e15;

pub use crate::geometry::{MAX_LENGTH, MIN_SIZE};

/// Largest number of sides of a `regular` polygon.
pub const MAX_SIDES: usize = 10_000;

/// A body resolved by validation (its mass and inertia are
/// [`crate::nscd::BodyInfo::new`]'s, checked here).
#[derive(Debug, Clone)]
pub(crate) struct CheckedBody {
    /// Shape centred on its centroid.
    pub shape: Shape,
    /// Centroid in the scene's body frame (m).
    pub centroid: Vec2,
    pub material: usize,
}

/// A spring resolved by validation.
#[derive(Debug, Clone)]
pub(crate) struct CheckedSpring {
    pub a: usize,
    /// Attachment on `a` in the scene's body frame (m).
    pub point_a: [f64; 2],
    pub b: Option<usize>,
    /// Attachment on `b` in its scene body frame, or the world anchor (m).
    pub point_b: [f64; 2],
    pub rest_length: f64,
}

/// Everything validation resolved.
#[derive(Debug, Clone)]
pub(crate) struct Checked {
    pub nlgs: NlgsSettings,
    pub theta: f64,
    pub alert_distance: f64,
    pub bodies: Vec<CheckedBody>,
    pub springs: Vec<CheckedSpring>,
}

/// `v` in plain notation when that is short, else in scientific notation.
pub(crate) fn num(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() || (1e-4..1e15).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A scene error. Its message is made one line of bounded length whatever the
/// scene holds: control characters become `?` and every quoted span (`'…'`,
/// where the messages quote the user's strings) is cut to 64 characters
/// ([`super::clip`]); a safety net under the `clip` of names in the messages of
/// both engines' validation.
pub(crate) fn err<T>(msg: String) -> Result<T> {
    Err(Error::Scene(tidy(&msg)))
}

/// `msg` as [`err`] writes it.
fn tidy(msg: &str) -> String {
    let plain = |s: &str| s.chars().map(|c| if c.is_control() { '?' } else { c }).collect::<String>();
    msg.split('\'')
        .enumerate()
        .map(|(k, s)| if k % 2 == 1 { crate::error::clip(s) } else { plain(s) })
        .collect::<Vec<_>>()
        .join("'")
}

/// `ctx: must be finite, got …` unless `v` is finite.
pub(crate) fn finite(ctx: &str, v: f64) -> Result<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        err(format!("{ctx}: must be finite, got {}", num(v)))
    }
}

fn finite2(ctx: &str, v: [f64; 2]) -> Result<[f64; 2]> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        err(format!("{ctx}: must be finite, got [{}, {}]", num(v[0]), num(v[1])))
    }
}

/// A finite point whose coordinates are within [`MAX_LENGTH`].
fn coordinates(ctx: &str, v: [f64; 2]) -> Result<[f64; 2]> {
    finite2(ctx, v)?;
    if v.iter().all(|x| x.abs() <= MAX_LENGTH) {
        Ok(v)
    } else {
        err(format!("{ctx}: coordinates must be within ±{MAX_LENGTH:e} m, got [{}, {}]", num(v[0]), num(v[1])))
    }
}

pub(crate) fn positive(ctx: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        err(format!("{ctx}: must be positive and finite, got {}", num(v)))
    }
}

pub(crate) fn non_negative(ctx: &str, v: f64) -> Result<f64> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        err(format!("{ctx}: must be non-negative and finite, got {}", num(v)))
    }
}

fn in_unit(ctx: &str, v: f64) -> Result<f64> {
    if (0.0..=1.0).contains(&v) {
        Ok(v)
    } else {
        err(format!("{ctx}: must be in [0, 1], got {}", num(v)))
    }
}

/// `body[3] 'block'`, or `body[3]` for an unnamed body.
pub(crate) fn body_label(i: usize, b: &BodySpec) -> String {
    label("body", i, &b.name)
}

/// `section[i] 'name'`, or `section[i]` when `name` is empty (the name
/// clipped, [`super::clip`]).
pub(crate) fn label(section: &str, i: usize, name: &str) -> String {
    if name.is_empty() {
        format!("{section}[{i}]")
    } else {
        format!("{section}[{i}] '{}'", crate::error::clip(name))
    }
}

/// The shape of a body (centred on its centroid) and its centroid in the
/// scene's body frame, or the message of why the shape is refused.
pub(crate) fn shape_of(b: &BodySpec) -> std::result::Result<(Shape, Vec2), String> {
    let given = [b.polygon.is_some(), b.regular.is_some(), b.disc.is_some(), b.parts.is_some()];
    match given.iter().filter(|&&x| x).count() {
        0 => return Err("shape: missing, give exactly one of polygon, regular, disc, parts".into()),
        1 => {}
        _ => return Err("shape: give exactly one of polygon, regular, disc, parts, not several".into()),
    }
    if let Some(parts) = &b.parts {
        // Errors about one part read `parts[1]: non-convex polygon: …`.
        Compound::new(parts).map(|(c, g)| (Shape::Compound(c), g)).map_err(|e| match e {
            GeometryError::Part { .. } | GeometryError::PartTooManyVertices(..) | GeometryError::PartsOverlap(..) => {
                e.to_string()
            }
            _ => format!("parts: {e}"),
        })
    } else if let Some(p) = &b.polygon {
        ConvexPolygon::new(p).map(|(p, c)| (Shape::Polygon(p), c)).map_err(|e| format!("polygon: {e}"))
    } else if let Some(r) = &b.regular {
        if r.sides > MAX_SIDES {
            return Err(format!("regular: at most {MAX_SIDES} sides, got {}", r.sides));
        }
        ConvexPolygon::regular(r.sides, r.radius)
            .map(|p| (Shape::Polygon(p), Vec2::zeros()))
            .map_err(|e| format!("regular: {e}"))
    } else {
        let r = b.disc.unwrap_or(0.0);
        Shape::disc(r).map(|s| (s, Vec2::zeros())).map_err(|e| format!("disc: {e}"))
    }
}

/// Checks `simulation.dt` and `simulation.duration` (s): both positive, and
/// `round(duration / dt)` between 1 and [`MAX_STEPS`].
pub(crate) fn check_time(dt: f64, duration: f64) -> Result<()> {
    let dt = positive("simulation.dt", dt)?;
    let duration = positive("simulation.duration", duration)?;
    let steps = (duration / dt).round();
    if steps < 1.0 {
        return err(format!(
            "simulation.duration: {} s is shorter than half a time step (dt = {} s)",
            num(duration),
            num(dt)
        ));
    }
    if steps > MAX_STEPS {
        return err(format!("simulation.duration: duration/dt = {steps:e} steps is too many"));
    }
    Ok(())
}

/// Number of time steps `round(duration / dt)` (0 if that is not a number ≥ 0;
/// at most [`MAX_STEPS`]).
pub(crate) fn steps_of(dt: f64, duration: f64) -> u64 {
    let n = (duration / dt).round();
    if n.is_finite() && n >= 0.0 {
        n.min(MAX_STEPS) as u64
    } else {
        0
    }
}

/// The value of an optional named key of `[nscd]`: `default` when absent, else
/// the value `from_name` finds, or the error "`key`: unknown `what` '…', expected
/// `expected`".
pub(crate) fn named<T>(
    key: &str,
    what: &str,
    given: Option<&str>,
    default: T,
    from_name: fn(&str) -> Option<T>,
    expected: &str,
) -> Result<T> {
    match given {
        None => Ok(default),
        Some(name) => from_name(name).map_or_else(
            || err(format!("{key}: unknown {what} '{}', expected {expected}", crate::error::clip(name))),
            Ok,
        ),
    }
}

pub(crate) fn check_drive(ctx: &str, d: Drive) -> Result<()> {
    match d {
        Drive::Constant(v) => finite(ctx, v).map(|_| ()),
        Drive::Harmonic(h) => {
            finite(&format!("{ctx}.mean"), h.mean)?;
            finite(&format!("{ctx}.amplitude"), h.amplitude)?;
            finite(&format!("{ctx}.frequency"), h.frequency)?;
            finite(&format!("{ctx}.phase"), h.phase)?;
            Ok(())
        }
    }
}

/// Checks the whole scene, one section after the other, and resolves names,
/// shapes and defaults.
pub(crate) fn check(scene: &Scene) -> Result<Checked> {
    // The 2D format's engines: nscd, md2d, and md2d's former spelling `engine = "md"` with `dimension = 2`.
    let engine = match scene.simulation.engine.as_str() {
        "md2d" => "md2d",
        "md" if scene.is_planar_md() => "md",
        _ => "nscd",
    };
    super::common::check_simulation(&scene.simulation, engine, 2)?;
    if let Some(soft) = &scene.soft {
        super::soft::check_soft(soft)?;
    }
    let ns = scene.nscd.clone().unwrap_or_default();
    let (theta, nlgs) = check_nscd(&ns)?;
    let materials = check_materials(scene)?;
    check_contacts(scene, &materials)?;
    let (bodies, names) = check_bodies(scene, &materials, scene.simulation.thickness())?;
    let springs = check_springs(scene, &names)?;
    let alert_distance = alert_distance(scene, &ns, &bodies);
    super::common::check_output(scene.output.as_ref(), true, |name| names.get(name).copied())?;
    if scene.settlement.is_some() {
        scene.acceleration()?;
    }
    Ok(Checked { nlgs, theta, alert_distance, bodies, springs })
}

/// Checks `[nscd]`: θ and the NLGS settings, defaults from [`NscdParams::default`].
fn check_nscd(ns: &NscdSection) -> Result<(f64, NlgsSettings)> {
    let defaults = NscdParams::default();
    let theta = ns.theta.unwrap_or(defaults.theta);
    if !(0.5..=1.0).contains(&theta) {
        return err(format!("nscd.theta: must be in [0.5, 1], got {}", num(theta)));
    }
    let policy = named(
        "nscd.criterion",
        "criterion",
        ns.criterion.as_deref(),
        defaults.nlgs.policy,
        Policy::from_name,
        "one of 'strict', 'quad', 'quad_max', 'energy', 'velocity'",
    )?;
    let tolerance = ns.tolerance.unwrap_or(defaults.nlgs.tolerance);
    if !(tolerance > 0.0 && tolerance < 1.0) {
        return err(format!("nscd.tolerance: must be in (0, 1), got {}", num(tolerance)));
    }
    let min_iterations = ns.min_iterations.unwrap_or(defaults.nlgs.min_iterations);
    if min_iterations < 1 {
        return err(format!("nscd.min_iterations: must be at least 1, got {min_iterations}"));
    }
    let max_iterations = ns.max_iterations.unwrap_or(defaults.nlgs.max_iterations.max(min_iterations));
    if max_iterations < min_iterations {
        return err(format!(
            "nscd.max_iterations: must be at least min_iterations = {min_iterations}, got {max_iterations}"
        ));
    }
    let max_factor = ns.max_factor.unwrap_or(defaults.nlgs.max_factor);
    if !(max_factor.is_finite() && max_factor >= 1.0) {
        return err(format!("nscd.max_factor: must be finite and at least 1, got {}", num(max_factor)));
    }
    let measure = named(
        "nscd.measure",
        "value",
        ns.measure.as_deref(),
        defaults.nlgs.measure,
        Measure::from_name,
        "'sweep' or 'check'",
    )?;
    if ns.measure.is_some() && measure == Measure::Check && policy.over_sweeps() {
        return err(format!(
            "nscd.measure: 'check' measures a residual (strict, quad, quad_max); the {} criterion is a change \
             from sweep to sweep, measured during the sweeps: remove the key or use 'sweep'",
            policy.name()
        ));
    }
    let solver = named(
        "nscd.solver",
        "solver",
        ns.solver.as_deref(),
        defaults.nlgs.solver,
        Solver::from_name,
        "'nlgs', 'apgd' or 'interior_point'",
    )?;
    if let Some(why) = solver.refusal(policy) {
        return err(why);
    }
    let on_stall = named(
        "nscd.on_stall",
        "value",
        ns.on_stall.as_deref(),
        defaults.nlgs.on_stall,
        OnStall::from_name,
        "'accept', 'extend' or 'stop'",
    )?;
    let stall_max_iterations =
        ns.stall_max_iterations.unwrap_or(defaults.nlgs.stall_max_iterations.max(max_iterations));
    if stall_max_iterations < max_iterations {
        return err(format!(
            "nscd.stall_max_iterations: must be at least max_iterations = {max_iterations}, got {stall_max_iterations}"
        ));
    }
    if ns.stall_max_iterations.is_some() && on_stall != OnStall::Extend {
        return err("nscd.stall_max_iterations: only used with on_stall = \"extend\"".to_string());
    }
    let relaxation = ns.relaxation.unwrap_or(defaults.nlgs.relaxation);
    if !(relaxation > 0.0 && relaxation < 2.0) {
        return err(format!("nscd.relaxation: must be in (0, 2), got {}", num(relaxation)));
    }
    let anderson = ns.anderson.unwrap_or(defaults.nlgs.anderson);
    if anderson > crate::nscd::method::anderson::MAX_DEPTH {
        return err(format!(
            "nscd.anderson: the depth of the mixing must be 0 to {}, got {anderson}",
            crate::nscd::method::anderson::MAX_DEPTH
        ));
    }
    if anderson > 0 && solver != Solver::Nlgs {
        return err(format!("nscd.anderson: mixes the NLGS sweeps, not solver = '{}': remove one key", solver.name()));
    }
    if ns.face_gaps.is_some() {
        return err("nscd.face_gaps: the gap rule of two polyhedra's face–face contacts is a 3D setting; a 2D \
                    scene's polygons have their own detection: remove the key"
            .to_string());
    }
    if ns.overlaps.is_some() {
        return err("nscd.overlaps: the held-overlap law is a 3D setting; a 2D scene's contacts keep the \
                    velocity-level law: remove the key"
            .to_string());
    }
    if let Some(a) = ns.alert_distance {
        non_negative("nscd.alert_distance", a)?;
        if a > MAX_LENGTH {
            return err(format!("nscd.alert_distance: must be at most {MAX_LENGTH:e} m, got {}", num(a)));
        }
    }
    let nlgs = NlgsSettings {
        policy,
        tolerance,
        min_iterations,
        max_iterations,
        max_factor,
        symmetric: ns.symmetric.unwrap_or(false),
        relaxation,
        split_min_rows: defaults.nlgs.split_min_rows,
        measure,
        solver,
        on_stall,
        stall_max_iterations,
        anderson,
    };

    Ok((theta, nlgs))
}

/// Checks `[[material]]`: unique non-empty names, positive densities; the index of each name.
fn check_materials(scene: &Scene) -> Result<HashMap<&str, usize>> {
    let mut materials: HashMap<&str, usize> = HashMap::new();
    for (i, m) in scene.materials.iter().enumerate() {
        if m.name.is_empty() {
            return err(format!("material[{i}].name: must not be empty"));
        }
        if let Some(j) = materials.insert(m.name.as_str(), i) {
            return err(format!(
                "material[{i}].name: duplicate material '{}' (also material[{j}])",
                crate::error::clip(&m.name)
            ));
        }
        positive(&format!("{}: density", label("material", i, &m.name)), m.density)?;
    }

    Ok(materials)
}

/// Checks `[[contact]]`: known materials, one law per pair, friction and restitutions in range.
fn check_contacts(scene: &Scene, materials: &HashMap<&str, usize>) -> Result<()> {
    let mut pairs: HashMap<(usize, usize), usize> = HashMap::new();
    for (i, c) in scene.contacts.iter().enumerate() {
        let mut ids = [0; 2];
        for (k, name) in c.between.iter().enumerate() {
            match materials.get(name.as_str()) {
                Some(&m) => ids[k] = m,
                None => return err(format!("contact[{i}].between: unknown material '{}'", crate::error::clip(name))),
            }
        }
        let key = (ids[0].min(ids[1]), ids[0].max(ids[1]));
        if let Some(j) = pairs.insert(key, i) {
            return err(format!(
                "contact[{i}].between: duplicate law for materials '{}' and '{}' (also contact[{j}])",
                crate::error::clip(&c.between[0]),
                crate::error::clip(&c.between[1])
            ));
        }
        non_negative(&format!("contact[{i}].friction"), c.friction)?;
        in_unit(&format!("contact[{i}].restitution"), c.restitution.unwrap_or(0.0))?;
        in_unit(&format!("contact[{i}].tangential_restitution"), c.tangential_restitution.unwrap_or(0.0))?;
    }

    Ok(())
}

/// Checks `[[body]]`: names, materials, shapes, sizes, state, imposed velocities, loads, mass;
/// the resolved bodies and the index of each name.
fn check_bodies<'a>(
    scene: &'a Scene,
    materials: &HashMap<&str, usize>,
    thickness: f64,
) -> Result<(Vec<CheckedBody>, HashMap<&'a str, usize>)> {
    if scene.bodies.is_empty() {
        return err("body: the scene has no [[body]]".into());
    }
    let mut names: HashMap<&str, usize> = HashMap::new();
    let mut bodies = Vec::with_capacity(scene.bodies.len());
    for (i, b) in scene.bodies.iter().enumerate() {
        let label = body_label(i, b);
        let ctx = |field: &str| format!("{label}: {field}");
        if !b.name.is_empty() {
            if let Some(j) = names.insert(b.name.as_str(), i) {
                return err(format!("{}: duplicate body name (also body[{j}])", ctx("name")));
            }
        }
        let Some(&material) = materials.get(b.material.as_str()) else {
            return err(format!("{}: unknown material '{}'", ctx("material"), crate::error::clip(&b.material)));
        };
        let (shape, centroid) = shape_of(b).map_err(|e| Error::Scene(format!("{label}: {e}")))?;
        let size = shape.bounding_radius() + centroid.norm();
        if !(MIN_SIZE..=MAX_LENGTH).contains(&shape.bounding_radius()) || size > MAX_LENGTH {
            return err(format!(
                "{}: the body's size {:e} m is outside [{MIN_SIZE:e}, {MAX_LENGTH:e}] m",
                ctx("shape"),
                shape.bounding_radius()
            ));
        }
        coordinates(&ctx("position"), b.position)?;
        finite(&ctx("angle"), b.angle())?;
        finite2(&ctx("velocity"), b.velocity())?;
        finite(&ctx("spin"), b.spin())?;
        if let Some(imp) = &b.imposed {
            if b.is_fixed() {
                return err(format!("{}: a fixed body cannot have imposed velocities", ctx("imposed")));
            }
            for (name, d) in [("vx", imp.vx), ("vy", imp.vy), ("spin", imp.spin)] {
                if let Some(d) = d {
                    check_drive(&ctx(&format!("imposed.{name}")), d)?;
                }
            }
        }
        if let Some(l) = &b.load {
            if b.is_fixed() {
                return err(format!("{}: a fixed body cannot carry a load", ctx("load")));
            }
            let d = finite2(&ctx("load.direction"), l.direction)?;
            let norm = d[0].hypot(d[1]);
            if !(norm > 0.0 && norm.is_finite()) {
                return err(format!(
                    "{}: must be a non-zero vector, got [{}, {}]",
                    ctx("load.direction"),
                    num(d[0]),
                    num(d[1])
                ));
            }
            finite(&ctx("load.mean"), l.mean)?;
            finite(&ctx("load.amplitude"), l.amplitude)?;
            finite(&ctx("load.frequency"), l.frequency)?;
            finite(&ctx("load.phase"), l.phase)?;
        }
        let (mass, inertia) = shape.mass_properties(scene.materials[material].density, thickness);
        if !(mass.is_finite() && mass > 0.0 && inertia.is_finite() && inertia > 0.0) {
            return err(format!("{}: {}", ctx("shape"), crate::nscd::bodies::mass_error(mass, inertia)));
        }
        bodies.push(CheckedBody { shape, centroid, material });
    }

    Ok((bodies, names))
}

/// Checks `[[spring]]`: bodies, attachments, law coefficients, rest length.
fn check_springs(scene: &Scene, names: &HashMap<&str, usize>) -> Result<Vec<CheckedSpring>> {
    let world = |i: usize, p: [f64; 2]| -> Vec2 {
        let b = &scene.bodies[i];
        let (s, c) = b.angle().sin_cos();
        Vec2::new(b.position[0], b.position[1]) + rotate(Vec2::new(p[0], p[1]), c, s)
    };
    let mut springs = Vec::with_capacity(scene.springs.len());
    for (i, s) in scene.springs.iter().enumerate() {
        let ctx = |field: &str| format!("spring[{i}].{field}");
        let Some(&a) = names.get(s.body.as_str()) else {
            return err(format!("{}: unknown body '{}'", ctx("body"), crate::error::clip(&s.body)));
        };
        let point_a = coordinates(&ctx("point"), s.point.unwrap_or([0.0, 0.0]))?;
        let (b, point_b, end_b) = match (&s.anchor, &s.other) {
            (Some(_), Some(_)) => return err(format!("{}: give either anchor or other, not both", ctx("anchor"))),
            (None, None) => return err(format!("{}: missing, give either anchor or other", ctx("anchor"))),
            (Some(anchor), None) => {
                if s.other_point.is_some() {
                    return err(format!("{}: only allowed with other", ctx("other_point")));
                }
                let p = coordinates(&ctx("anchor"), *anchor)?;
                (None, p, Vec2::new(p[0], p[1]))
            }
            (None, Some(other)) => {
                let Some(&b) = names.get(other.as_str()) else {
                    return err(format!("{}: unknown body '{}'", ctx("other"), crate::error::clip(other)));
                };
                if b == a {
                    return err(format!(
                        "{}: the spring joins body '{}' to itself",
                        ctx("other"),
                        crate::error::clip(other)
                    ));
                }
                let p = coordinates(&ctx("other_point"), s.other_point.unwrap_or([0.0, 0.0]))?;
                (Some(b), p, world(b, p))
            }
        };
        non_negative(&ctx("k_n"), s.k_n)?;
        non_negative(&ctx("nu"), s.nu.unwrap_or(0.0))?;
        finite(&ctx("prestrain"), s.prestrain.unwrap_or(0.0))?;
        let length = (world(a, point_a) - end_b).norm();
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
        springs.push(CheckedSpring { a, point_a, b, point_b, rest_length });
    }

    Ok(springs)
}

/// The alert distance (m): `nscd.alert_distance`, else [`crate::nscd::system::DEFAULT_ALERT_FRACTION`]
/// × the smallest inner radius of the non-fixed bodies (of all bodies if none moves).
fn alert_distance(scene: &Scene, ns: &NscdSection, bodies: &[CheckedBody]) -> f64 {
    match ns.alert_distance {
        Some(a) => a,
        None => crate::nscd::system::default_alert_distance(
            scene.bodies.iter().zip(bodies).map(|(s, b)| (s.is_fixed(), b.shape.inner_radius())),
        ),
    }
}
