//! Walls: planes, discs (a plate that covers part of a surface), the inside of a
//! cylinder; fixed, or moving along their normal under a prescribed force or
//! stress (servo walls with mass and viscosity).
//!
//! Spheres touch walls with the law of (sphere material, wall material), the wall
//! being the second body: `R* = r` for a plane, `R* = r R / (R − r)` inside a
//! cylinder of radius `R`, `m* = m`. A servo wall (David et al. §2, and the loading
//! plate of Karrech et al. Fig. 2) obeys `m_w s̈ = σ(t) A + F_c − γ_w ṡ`, with `s`
//! its displacement along its normal (which points into the sample), `F_c` the
//! normal component of the contact forces on it (negative when pressed), `A` its
//! area (given, or for a box wall the product of the two other box extents), and
//! `σ(t) = base + amplitude (1 − cos 2π t / period) / 2` (so `2σ = 2p₀ + Δσ[1 −
//! cos 2πt/t₀]` with base `p₀` and amplitude `Δσ`). It is advanced by a
//! semi-implicit Euler step after each force evaluation (its relaxation time
//! `m_w/γ_w` is many steps); gravity does not act on walls (the load is the
//! prescribed one).

use super::particles::V3;
use serde::{Deserialize, Serialize};

/// The shape of a wall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Shape {
    /// Infinite plane through `point`, unit `normal` into the free side.
    Plane {
        /// A point of the plane at the start, `s = 0` (m).
        point: V3,
        /// Unit normal pointing into the free side (the sample); the wall moves along it.
        normal: V3,
    },
    /// The part of a plane within `radius` (m) of `point`.
    Disc {
        /// Centre of the disc at the start, `s = 0` (m).
        point: V3,
        /// Unit normal pointing into the free side (the sample); the wall moves along it.
        normal: V3,
        /// Radius of the disc (m); a sphere whose centre projects outside it does not touch it.
        radius: f64,
    },
    /// The inside of an infinite cylinder (unit `axis`, `radius` m).
    Cylinder {
        /// A point of the axis (m).
        axis_point: V3,
        /// Unit vector along the axis.
        axis: V3,
        /// Inner radius (m); spheres are held inside.
        radius: f64,
    },
}

/// A prescribed history `base + amplitude (1 − cos 2π t / period) / 2`
/// (constant if `period` is 0), in N or Pa.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct History1 {
    /// Value at `t = 0` and at the start of every period (N or Pa): `p₀` of David et al.
    pub base: f64,
    /// Peak-to-base rise reached at half a period (N or Pa): `Δσ` of David et al.
    pub amplitude: f64,
    /// Period (s); 0 for a constant `base`.
    pub period: f64,
}

impl History1 {
    /// The value at time `t` (s).
    pub fn at(&self, t: f64) -> f64 {
        if self.period > 0.0 {
            self.base + 0.5 * self.amplitude * (1.0 - (2.0 * std::f64::consts::PI * t / self.period).cos())
        } else {
            self.base
        }
    }
}

/// What a servo wall follows.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Drive {
    /// A force (N) along the normal.
    Force(History1),
    /// A stress (Pa) on an area (m²); `None`: the box area from the other walls.
    Stress(History1, Option<f64>),
}

/// How a wall moves.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Motion {
    /// Does not move (`s` stays 0).
    Fixed,
    /// Moves along its normal: mass `mass` (kg), viscosity `viscosity` (kg/s).
    Servo {
        /// Wall mass `m_w` (kg) in `m_w s̈ = σ(t) A + F_c − γ_w ṡ`.
        mass: f64,
        /// Wall viscosity `γ_w` (kg/s, i.e. N per m/s) in the same equation.
        viscosity: f64,
        /// The prescribed force or stress `σ(t) A`.
        drive: Drive,
    },
}

/// A wall and its state.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Wall {
    /// Name of the wall in the scene; prefixes its `<wall>_force_N` and
    /// `<wall>_position_m` columns.
    pub name: String,
    /// Index of the wall's material (its row and column in the [`super::LawTable`]).
    pub material: u32,
    /// Geometry at the start (`s = 0`).
    pub shape: Shape,
    /// Fixed, or servo-controlled along the normal.
    pub motion: Motion,
    /// Displacement along the normal since the start (m).
    pub s: f64,
    /// Its rate (m/s).
    pub s_dot: f64,
    /// Total contact force on the wall at the last evaluation (N).
    pub force: V3,
    /// Spheres touching it at the last evaluation.
    pub contacts: usize,
    /// Displacement at the last neighbour build (m).
    pub s_build: f64,
    /// Spheres within the skin at the last build, in increasing order (their
    /// contact memory is kept by the system, per sphere and wall).
    pub candidates: Vec<u32>,
}

impl Wall {
    /// Copies `src` into `self`, reusing `self`'s buffers (no allocation once the sizes match): the backup of
    /// an MD step ([`crate::md::MdSystem`]). The destructuring names every field, so a field added to the
    /// struct does not compile until it is copied here too (a field forgotten would be a silent replay bug).
    pub(crate) fn copy_from(&mut self, src: &Wall) {
        let Wall { name, material, shape, motion, s, s_dot, force, contacts, s_build, candidates } = src;
        self.name.clone_from(name);
        self.material = *material;
        self.shape.clone_from(shape);
        self.motion.clone_from(motion);
        self.s = *s;
        self.s_dot = *s_dot;
        self.force = *force;
        self.contacts = *contacts;
        self.s_build = *s_build;
        self.candidates.clone_from(candidates);
    }

    /// A wall at rest.
    pub fn new(name: &str, material: u32, shape: Shape, motion: Motion) -> Self {
        Wall {
            name: name.to_string(),
            material,
            shape,
            motion,
            s: 0.0,
            s_dot: 0.0,
            force: V3::zeros(),
            contacts: 0,
            s_build: 0.0,
            candidates: Vec::new(),
        }
    }

    /// The normal of a plane or disc wall (None for a cylinder).
    pub fn normal(&self) -> Option<V3> {
        match self.shape {
            Shape::Plane { normal, .. } | Shape::Disc { normal, .. } => Some(normal),
            Shape::Cylinder { .. } => None,
        }
    }

    /// Current point of a plane or disc wall (moved by `s`).
    pub fn point(&self) -> Option<V3> {
        match self.shape {
            Shape::Plane { point, normal } | Shape::Disc { point, normal, .. } => Some(point + normal * self.s),
            Shape::Cylinder { .. } => None,
        }
    }

    /// Velocity of the wall (m/s).
    #[inline]
    pub fn velocity(&self) -> V3 {
        self.normal().map_or(V3::zeros(), |n| n * self.s_dot)
    }

    /// Gap (m, negative when overlapping), unit normal from the wall to the
    /// sphere, and `R*` for a sphere of radius `r` at `x`; `None` if the sphere is
    /// beside a disc.
    #[inline]
    pub fn gap(&self, x: &V3, r: f64) -> Option<(f64, V3, f64)> {
        match self.shape {
            Shape::Plane { point, normal } => {
                let d = (x - point).dot(&normal) - self.s;
                Some((d - r, normal, r))
            }
            Shape::Disc { point, normal, radius } => {
                let rel = x - point;
                let d = rel.dot(&normal) - self.s;
                let lateral = rel - normal * rel.dot(&normal);
                if lateral.norm_squared() > radius * radius {
                    return None;
                }
                Some((d - r, normal, r))
            }
            Shape::Cylinder { axis_point, axis, radius } => {
                let rel = x - axis_point;
                let rho = rel - axis * rel.dot(&axis);
                let dist = rho.norm();
                let n = if dist > 0.0 { -rho / dist } else { V3::zeros() };
                let r_star = if radius > r { r * radius / (radius - r) } else { r };
                Some((radius - dist - r, n, r_star))
            }
        }
    }

    /// The prescribed normal force (N) at time `t`, given the box area `box_area` (m²).
    pub fn drive_force(&self, t: f64, box_area: f64) -> f64 {
        match self.motion {
            Motion::Fixed => 0.0,
            Motion::Servo { drive: Drive::Force(h), .. } => h.at(t),
            Motion::Servo { drive: Drive::Stress(h, area), .. } => h.at(t) * area.unwrap_or(box_area),
        }
    }

    /// Normal component of the contact force on the wall (N; negative when pressed).
    pub fn normal_force(&self) -> f64 {
        self.normal().map_or(0.0, |n| self.force.dot(&n))
    }
}

/// Extent of the box along `axis` (m): the distance between the plane walls of
/// normals `+e_axis` and `−e_axis`; `None` without such a pair.
pub fn box_extent(walls: &[Wall], axis: usize) -> Option<f64> {
    let mut lo = None;
    let mut hi = None;
    for w in walls {
        if let (Some(n), Some(p)) = (w.normal(), w.point()) {
            if (n[axis] - 1.0).abs() < 1e-9 {
                lo = Some(p[axis]);
            } else if (n[axis] + 1.0).abs() < 1e-9 {
                hi = Some(p[axis]);
            }
        }
    }
    Some(hi? - lo?)
}

/// Area of the box face normal to `axis` (m²), 0 if the box is incomplete.
pub fn box_area(walls: &[Wall], axis: usize) -> f64 {
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    match (box_extent(walls, a), box_extent(walls, b)) {
        (Some(x), Some(y)) => x * y,
        _ => 0.0,
    }
}

/// Advances the servo walls by `dt` (s) at time `t` (s) after a force
/// evaluation; returns the work of their drives over the step in absolute value
/// (J), `Σ |F_drive Δs|`.
pub fn advance(walls: &mut [Wall], t: f64, dt: f64) -> f64 {
    let mut work = 0.0;
    for k in 0..walls.len() {
        if let Motion::Servo { mass, viscosity, .. } = walls[k].motion {
            let axis = walls[k].normal().map(|n| n.iamax()).unwrap_or(0);
            let area = box_area(walls, axis);
            let w = &mut walls[k];
            let drive = w.drive_force(t, area);
            let f = drive + w.normal_force();
            // Semi-implicit in the viscosity: stable for any γ_w dt / m_w.
            w.s_dot = (w.s_dot + dt * f / mass) / (1.0 + dt * viscosity / mass);
            w.s += dt * w.s_dot;
            work += (drive * dt * w.s_dot).abs();
        }
    }
    work
}
