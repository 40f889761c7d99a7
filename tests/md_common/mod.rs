//! Builders and probes shared by the MD physics tests (`tests/md_contact.rs`,
//! `tests/md_mechanics.rs`): systems assembled directly through the public API of
//! `ballast::md` (`Particles::push`, `Wall::new`, `LawTable`, `MdSystem::new`).
#![allow(dead_code)]

use ballast::md::{
    Ghosts, Integrator, LawTable, Material, MdSettings, MdSystem, Motion, PairLaw, Particles, Shape, Wall, V3,
};

/// Standard gravity (m/s²).
pub const G: f64 = 9.81;

/// A soft rock-like material: density 2000 kg/m³ (David et al. §3), Young's
/// modulus `young` (Pa), Poisson's ratio 0.25 (Karrech et al. Table 1).
pub fn material(young: f64) -> Material {
    Material { density: 2000.0, young, poisson: 0.25 }
}

/// Run settings without background damping.
pub fn settings(dt: f64, gravity: V3, integrator: Integrator, skin: f64) -> MdSettings {
    MdSettings { dt, gravity, integrator, skin, background_damping: 0.0, background_rotational_damping: 0.0 }
}

/// A fixed infinite plane through `point` with unit normal `normal` (into the free side).
pub fn plane(name: &str, material: u32, point: V3, normal: V3) -> Wall {
    Wall::new(name, material, Shape::Plane { point, normal: normal.normalize() }, Motion::Fixed)
}

/// A law table with sphere material 0 and wall material 1: `sphere` between
/// spheres, `wall` between a sphere and a wall.
pub fn laws(sphere: PairLaw, wall: PairLaw) -> LawTable {
    let mut t = LawTable::new(2);
    t.set(0, 0, sphere);
    t.set(0, 1, wall);
    t
}

/// A system without symmetry planes.
pub fn system(settings: MdSettings, particles: Particles, walls: Vec<Wall>, laws: LawTable) -> MdSystem {
    MdSystem::new(settings, particles, walls, laws, Ghosts::new(Vec::new()))
        .expect("a law for every pair that can touch")
}

/// Mass of a sphere of radius `r` (m) and density `rho` (kg/m³).
pub fn sphere_mass(rho: f64, r: f64) -> f64 {
    rho * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3)
}

/// What a binary (or sphere–wall) impact measured.
#[derive(Debug, Clone, Copy, Default)]
pub struct Impact {
    /// Largest overlap reported by the steps (m).
    pub delta_max: f64,
    /// Largest contact force on the first sphere (N).
    pub force_max: f64,
    /// Time between the gap crossing zero inwards and outwards (s), each crossing
    /// located by linear interpolation of the gap between two steps.
    pub contact_time: f64,
    /// Normal relative speed after / before (the restitution coefficient).
    pub restitution: f64,
}

/// Runs `sys` through one impact. `gap` is the gap (m, negative when
/// overlapping) of the colliding pair, `vn` their normal approach speed
/// (positive when approaching). Stops a few steps after the pair separated.
pub fn impact(sys: &mut MdSystem, gap: impl Fn(&MdSystem) -> f64, vn: impl Fn(&MdSystem) -> f64) -> Impact {
    let v_in = vn(sys);
    let dt = sys.settings.dt;
    let mut out = Impact::default();
    let mut g_prev = gap(sys);
    assert!(g_prev > 0.0, "the impact must start with a gap");
    let mut t_in = None;
    let mut t_out = None;
    for _ in 0..10_000_000 {
        let t0 = sys.time;
        let st = sys.step().expect("step");
        out.delta_max = out.delta_max.max(st.max_overlap);
        out.force_max = out.force_max.max(sys.particles.f[0].norm());
        let g = gap(sys);
        if t_in.is_none() && g <= 0.0 {
            t_in = Some(t0 + dt * g_prev / (g_prev - g));
        }
        if t_in.is_some() && t_out.is_none() && g > 0.0 && g_prev <= 0.0 {
            t_out = Some(t0 + dt * g_prev / (g_prev - g));
        }
        g_prev = g;
        // A few more steps so that no contact force is left.
        if let Some(t) = t_out {
            if sys.time > t + 3.0 * dt {
                break;
            }
        }
    }
    out.contact_time = t_out.expect("the pair separated") - t_in.expect("the pair touched");
    out.restitution = -vn(sys) / v_in;
    out
}

/// Gap (m) between spheres 0 and 1.
pub fn pair_gap(s: &MdSystem) -> f64 {
    let p = &s.particles;
    (p.x[0] - p.x[1]).norm() - p.r[0] - p.r[1]
}

/// Approach speed (m/s) of spheres 0 and 1 along their line of centres.
pub fn pair_approach(s: &MdSystem) -> f64 {
    let p = &s.particles;
    let n = (p.x[0] - p.x[1]).normalize();
    -(p.v[0] - p.v[1]).dot(&n)
}

/// Relative difference `|a − b| / |b|`.
pub fn rel(a: f64, b: f64) -> f64 {
    ((a - b) / b).abs()
}
