//! Checks of a resolved MD scene against its own dynamics, made at load before
//! anything runs, so that a bad scene is refused instead of exploding (or, worse,
//! running to the end with nonsense):
//!
//! 1. initial overlaps ([`check_overlaps`]): every sphere on the sample's side of
//!    the symmetry planes and on the free side of the walls, inside a cylinder it
//!    fits in, and no overlap (with a sphere, a wall or its own image) deeper than
//!    [`MAX_INITIAL_OVERLAP`] of the smaller radius. Sphere pairs come from the
//!    engine's own linked-cell grid ([`Neighbours`]): O(N);
//! 2. the explicit background damping ([`check_background_damping`]): `γ_b Δt / m`
//!    and `γ_br r² Δt / I = 2.5 γ_br Δt / m` on the lightest sphere within the
//!    integrator's stability limit for a pure damping;
//! 3. the time step ([`check_time_step`]) against the fastest contact of every
//!    pair of materials that can touch, at the characteristic impact speed
//!    ([`characteristic_speed`]).
//!
//! Each refusal is one line naming the bodies (index and name) and the numbers.

use super::format::{MdScene, MAX_INITIAL_OVERLAP, REFERENCE_SPEED};
use crate::error::Result;
use crate::md::neighbours::Neighbours;
use crate::md::{Integrator, LawTable, MdSettings, Model, PairLaw, Shape, SymmetryPlane, Wall, V3};
use crate::scene::validate::{err, label, num};

/// A resolved scene: what [`super::validate::check`] has checked one by one.
pub(super) struct Resolved<'a> {
    pub scene: &'a MdScene,
    pub settings: &'a MdSettings,
    /// Density (kg/m³) of each material.
    pub densities: Vec<f64>,
    /// Material of each sphere.
    pub sphere_materials: &'a [usize],
    pub laws: &'a LawTable,
    pub walls: &'a [Wall],
    pub planes: &'a [SymmetryPlane],
}

/// The spheres' centres (m), radii (m) and masses (kg).
struct Spheres {
    x: Vec<V3>,
    r: Vec<f64>,
    m: Vec<f64>,
}

/// `v` to 3 significant digits: `2.1e-4`, `0.42`, `4.8e8`.
fn sig(v: f64) -> String {
    let r: f64 = format!("{v:.2e}").parse().unwrap_or(v);
    if r == 0.0 {
        "0".into()
    } else if !r.is_finite() || (1e-3..1e4).contains(&r.abs()) {
        format!("{r}")
    } else {
        format!("{r:e}")
    }
}

/// `[x, y, z]` to 3 significant digits.
fn sig3(v: &V3) -> String {
    format!("[{}, {}, {}]", sig(v[0]), sig(v[1]), sig(v[2]))
}

/// Runs the three checks in order (overlaps, background damping, time step).
pub(super) fn check(res: &Resolved) -> Result<()> {
    let spheres = Spheres {
        x: res.scene.bodies.iter().map(|b| V3::from(b.position)).collect(),
        r: res.scene.bodies.iter().map(|b| b.sphere).collect(),
        m: res
            .scene
            .bodies
            .iter()
            .zip(res.sphere_materials)
            .map(|(b, &k)| res.densities[k] * 4.0 / 3.0 * std::f64::consts::PI * b.sphere.powi(3))
            .collect(),
    };
    let release = check_overlaps(res, &spheres)?;
    check_background_damping(res, &spheres)?;
    let speed = characteristic_speed(res, &spheres, release);
    check_time_step(res, &spheres, speed)
}

fn body(res: &Resolved, i: usize) -> String {
    label("body", i, &res.scene.bodies[i].name)
}

fn wall(res: &Resolved, k: usize) -> String {
    label("wall", k, &res.scene.walls[k].name)
}

/// `A and B: initial overlap δ m is P % of the (smaller) radius (at most 10 % allowed)`
/// if the overlap `delta` (m) is deeper than [`MAX_INITIAL_OVERLAP`] of `radius` (m).
fn overlap_limit(pair: impl FnOnce() -> String, delta: f64, radius: f64, smaller: bool) -> Result<()> {
    let fraction = delta / radius;
    if fraction <= MAX_INITIAL_OVERLAP {
        return Ok(());
    }
    err(format!(
        "{}: initial overlap {} m is {:.1} % of the {}radius (at most {} % allowed)",
        pair(),
        sig(delta),
        100.0 * fraction,
        if smaller { "smaller " } else { "" },
        100.0 * MAX_INITIAL_OVERLAP
    ))
}

/// Relative speed (m/s) at which a pair overlapping by `delta` (m) separates
/// once released: its elastic energy `E(δ)` ([`PairLaw::normal_energy`]) turned
/// into `m* v² / 2`.
fn release_speed(law: Option<&PairLaw>, m_star: f64, r_star: f64, delta: f64) -> f64 {
    law.map_or(0.0, |l| (2.0 * l.normal_energy(r_star, delta) / m_star).sqrt())
}

/// Checks the initial overlaps (see the module doc) and returns the fastest
/// release speed (m/s) of the overlapping pairs.
fn check_overlaps(res: &Resolved, s: &Spheres) -> Result<f64> {
    let mut release = 0.0f64;
    let mat = res.sphere_materials;
    // Symmetry planes: the centre strictly on the sample's side; the overlap with
    // the image, 2 (r − d), as a sphere pair (m* = m/2, R* = r/2). Images of other
    // spheres are farther than the spheres themselves.
    for (i, x) in s.x.iter().enumerate() {
        for (k, plane) in res.planes.iter().enumerate() {
            let d = plane.distance(x);
            if d <= 0.0 {
                return err(format!(
                    "{} and symmetry[{k}]: the centre is {} m on the wrong side of the plane (its normal {} points \
                     into the sample)",
                    body(res, i),
                    sig(-d),
                    sig3(&plane.normal)
                ));
            }
            let delta = 2.0 * (s.r[i] - d);
            if delta > 0.0 {
                overlap_limit(|| format!("{} and its image across symmetry[{k}]", body(res, i)), delta, s.r[i], false)?;
                let law = res.laws.get(mat[i], mat[i]);
                release = release.max(release_speed(law, 0.5 * s.m[i], 0.5 * s.r[i], delta));
            }
        }
    }
    // Walls: the centre strictly on the free side (in front of a plane or disc,
    // inside a cylinder), the sphere narrower than a cylinder.
    for (k, w) in res.walls.iter().enumerate() {
        for (i, x) in s.x.iter().enumerate() {
            if let Shape::Cylinder { radius, .. } = w.shape {
                if s.r[i] >= radius {
                    return err(format!(
                        "{} and {}: the sphere's radius {} m does not fit in the cylinder of radius {} m",
                        body(res, i),
                        wall(res, k),
                        sig(s.r[i]),
                        sig(radius)
                    ));
                }
            }
            let Some((gap, _, r_star)) = w.gap(x, s.r[i]) else { continue };
            // Distance of the centre to the wall's surface, positive on the free side.
            let free = gap + s.r[i];
            if free <= 0.0 {
                let side = match w.shape {
                    Shape::Cylinder { .. } => "outside the cylinder",
                    _ => "behind the wall (its normal points to the free side)",
                };
                return err(format!("{} and {}: the centre is {} m {side}", body(res, i), wall(res, k), sig(-free)));
            }
            if gap < 0.0 {
                overlap_limit(|| format!("{} and {}", body(res, i), wall(res, k)), -gap, s.r[i], false)?;
                let law = res.laws.get(mat[i], w.material as usize);
                release = release.max(release_speed(law, s.m[i], r_star, -gap));
            }
        }
    }
    // Sphere pairs: the grid of the engine with a zero skin lists exactly the
    // overlapping pairs, in increasing order.
    let n = s.x.len();
    let mut nb = Neighbours::new(0.0);
    nb.build(&s.x, &s.r, n, &[]);
    for i in 0..n {
        for &j in &nb.j[nb.start[i] as usize..nb.start[i + 1] as usize] {
            let j = j as usize;
            let delta = s.r[i] + s.r[j] - (s.x[i] - s.x[j]).norm();
            if delta <= 0.0 {
                continue;
            }
            let pair = || format!("{} and {}", body(res, i), body(res, j));
            overlap_limit(pair, delta, s.r[i].min(s.r[j]), true)?;
            let m_star = s.m[i] * s.m[j] / (s.m[i] + s.m[j]);
            let r_star = s.r[i] * s.r[j] / (s.r[i] + s.r[j]);
            release = release.max(release_speed(res.laws.get(mat[i], mat[j]), m_star, r_star, delta));
        }
    }
    Ok(release)
}

/// The lightest sphere (index).
fn lightest(s: &Spheres) -> usize {
    (0..s.m.len()).min_by(|&a, &b| s.m[a].total_cmp(&s.m[b])).unwrap_or(0)
}

/// The background damping is applied explicitly (`f = −γ_b v`, `τ = −γ_br r² ω`
/// with the velocities of the step): as a pure damping `v̇ = −c v` it is stable
/// for `c Δt` up to the integrator's limit (2 for velocity Verlet, where
/// `v ← (1 − c Δt) v` each step; 0.16–1 for the Gear sets), computed by
/// [`Integrator::stability_limit`]. `c = γ_b / m` and `γ_br r² / I = 2.5 γ_br / m`
/// (`I = 2/5 m r²`) are largest on the lightest sphere.
fn check_background_damping(res: &Resolved, s: &Spheres) -> Result<()> {
    let set = res.settings;
    let i = lightest(s);
    let m = s.m[i];
    let terms = [
        ("md.background_damping", "γ_b Δt / m", set.background_damping),
        (
            "md.background_rotational_damping",
            "γ_br r² Δt / I = 2.5 γ_br Δt / m",
            2.5 * set.background_rotational_damping,
        ),
    ];
    for (key, what, gamma) in terms {
        if gamma == 0.0 {
            continue;
        }
        let c = gamma / m;
        let limit = set.integrator.stability_limit(0.0, c);
        if set.dt > limit {
            return err(format!(
                "{key}: {what} = {} for the lightest sphere, {} (m = {} kg), is above the explicit stability limit {} \
                 of {} (this damping needs dt ≤ {} s)",
                sig(c * set.dt),
                body(res, i),
                sig(m),
                sig(c * limit),
                set.integrator.describe(),
                sig(limit)
            ));
        }
    }
    Ok(())
}

/// Approach speed (m/s) at which the contact times are taken: the fastest
/// impact the initial state can produce, at least [`REFERENCE_SPEED`]: two
/// spheres head on at the fastest surface speed `|v| + r |ω|`, plus the speed
/// `√(2 |g| H)` of a fall through the height `H` the spheres can fall
/// ([`fall_height`]), or `release` (the separation speed of the initial
/// overlaps), whichever is largest. Servo walls are not counted: they are driven
/// by forces, not speeds.
fn characteristic_speed(res: &Resolved, s: &Spheres, release: f64) -> f64 {
    let surface = res
        .scene
        .bodies
        .iter()
        .map(|b| V3::from(b.velocity()).norm() + b.sphere * V3::from(b.spin()).norm())
        .fold(0.0, f64::max);
    let g = res.settings.gravity.norm();
    let fall = if g > 0.0 { (2.0 * g * fall_height(res, s, -res.settings.gravity / g)).sqrt() } else { 0.0 };
    (2.0 * surface + fall).max(release).max(REFERENCE_SPEED)
}

/// Height (m) the spheres can fall along `up` (unit vector against gravity):
/// from the highest centre to the lowest sphere bottom, or for a sphere above a
/// plane or disc wall facing up, its normal distance to the wall times `n · up`
/// (the part of a vertical fall that reaches the wall along its normal).
fn fall_height(res: &Resolved, s: &Spheres, up: V3) -> f64 {
    let heights = s.x.iter().map(|x| x.dot(&up));
    let top = heights.clone().fold(f64::NEG_INFINITY, f64::max);
    let bottom = heights.zip(&s.r).map(|(h, r)| h - r).fold(f64::INFINITY, f64::min);
    let mut fall = (top - bottom).max(0.0);
    for w in res.walls {
        let (Some(n), Some(p)) = (w.normal(), w.point()) else { continue };
        let facing = n.dot(&up);
        if facing > 0.0 {
            for (x, r) in s.x.iter().zip(&s.r) {
                fall = fall.max(((x - p).dot(&n) - r) * facing);
            }
        }
    }
    fall
}

/// A contact whose stability bounds the time step: a pair of materials that can
/// touch, between the smallest spheres of those materials or the smallest sphere
/// and a wall.
struct Contact {
    /// What it is, for the message.
    what: String,
    law: PairLaw,
    /// Reduced mass (kg), effective radius (m), mass of the lighter sphere (kg).
    m_star: f64,
    r_star: f64,
    m_light: f64,
}

/// The contacts that can occur: every pair of sphere materials that can touch
/// (two spheres, or one and its symmetry image) between their smallest spheres,
/// and the smallest sphere of every material with every wall.
fn contacts(res: &Resolved, s: &Spheres) -> Vec<Contact> {
    let n = res.densities.len();
    let mut smallest: Vec<Option<usize>> = vec![None; n];
    let mut count = vec![0usize; n];
    for (i, &k) in res.sphere_materials.iter().enumerate() {
        count[k] += 1;
        if smallest[k].is_none_or(|j| s.r[i] < s.r[j]) {
            smallest[k] = Some(i);
        }
    }
    let name = |k: usize| &res.scene.materials[k].name;
    let mut out = Vec::new();
    for a in 0..n {
        let Some(i) = smallest[a] else { continue };
        for (b, &j) in smallest.iter().enumerate().skip(a) {
            let Some(j) = j else { continue };
            let touch = a != b || count[a] > 1 || !res.planes.is_empty();
            let Some(&law) = res.laws.get(a, b).filter(|_| touch) else { continue };
            let what = if a == b {
                format!("'{}'–'{}' contacts (two of the smallest sphere, {})", name(a), name(a), body(res, i))
            } else {
                format!(
                    "'{}'–'{}' contacts (the smallest spheres, {} and {})",
                    name(a),
                    name(b),
                    body(res, i),
                    body(res, j)
                )
            };
            out.push(Contact {
                what,
                law,
                m_star: s.m[i] * s.m[j] / (s.m[i] + s.m[j]),
                r_star: s.r[i] * s.r[j] / (s.r[i] + s.r[j]),
                m_light: s.m[i].min(s.m[j]),
            });
        }
        for (k, w) in res.walls.iter().enumerate() {
            let Some(&law) = res.laws.get(a, w.material as usize) else { continue };
            let r_star = match w.shape {
                Shape::Cylinder { radius, .. } => s.r[i] * radius / (radius - s.r[i]),
                _ => s.r[i],
            };
            let wall_name = name(w.material as usize);
            let what = format!(
                "'{}'–'{wall_name}' contacts (the smallest sphere, {}, on {})",
                name(a),
                body(res, i),
                wall(res, k)
            );
            out.push(Contact { what, law, m_star: s.m[i], r_star, m_light: s.m[i] });
        }
    }
    out
}

/// Largest stable time step (s) of `contact` hit at `speed` (m/s) by
/// `integrator`, with background damping `gamma_b` (kg/s).
///
/// The contact is linearised at the largest overlap of the impact
/// ([`PairLaw::impact_overlap`]): normal stiffness `k` (the tangent one for
/// Hertz) and dashpot `γ_n`. A sphere pressed between two such contacts (a chain
/// of spheres, the fastest mode of a packing's contact network: `ω² = 4k/m` for
/// equal spheres against `2k/m` for one pair) doubles both, so the test equation
/// of [`Integrator::stability_limit`] is `ẍ = −(2k/m*) x − (2γ_n/m* + γ_b/m) ẋ`.
/// Undamped with velocity Verlet this gives `Δt < √2 / ω = (√2/π) t_c`
/// (`t_c = π √(m*/k)`); the dashpots make it smaller.
fn stable_step(contact: &Contact, speed: f64, integrator: Integrator, gamma_b: f64) -> f64 {
    let (law, m, r) = (&contact.law, contact.m_star, contact.r_star);
    let delta = law.impact_overlap(m, r, speed);
    let k = law.normal_stiffness(r, delta);
    let gamma = law.normal_dashpot(m, r, delta);
    integrator.stability_limit(2.0 * k / m, 2.0 * gamma / m + gamma_b / contact.m_light)
}

/// Refuses a time step above the stability limit of the fastest contact (see
/// [`stable_step`]), naming both and the contact time of that contact
/// ([`PairLaw::contact_time`]) at `speed` (m/s).
fn check_time_step(res: &Resolved, s: &Spheres, speed: f64) -> Result<()> {
    let set = res.settings;
    let limits =
        contacts(res, s).into_iter().map(|c| (stable_step(&c, speed, set.integrator, set.background_damping), c));
    let Some((limit, c)) = limits.min_by(|a, b| a.0.total_cmp(&b.0)) else { return Ok(()) };
    if set.dt <= limit {
        return Ok(());
    }
    let t_c = c.law.contact_time(c.m_star, c.r_star, speed);
    let time = match c.law.model {
        Model::Hertz => format!("Hertz contact time {} s at {} m/s", sig(t_c), sig(speed)),
        Model::Linear if t_c.is_finite() => format!("linear contact time {} s", sig(t_c)),
        Model::Linear => "linear contact overdamped".into(),
    };
    err(format!(
        "simulation.dt: {} s is above the stability limit {} s of {} for the {}: {time}",
        num(set.dt),
        sig(limit),
        set.integrator.describe(),
        c.what
    ))
}
