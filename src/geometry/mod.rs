//! Shared 2D geometry: convex polygons, discs and compounds (rigid unions of
//! convex polygons) in their body frame, their validation (convexity,
//! orientation, degeneracy, non-overlapping parts) and their mass properties.
//!
//! 2D bodies stand for prisms of out-of-plane `thickness` (m), so a body of
//! area `A` (m²) and density `ρ` (kg/m³) has mass `ρ A t` (kg) and polar inertia
//! `ρ t J` (kg·m²), `J` being the polar second moment of area about the centroid.
//! Mass properties come from `parry2d-f64`.
//!
//! The 3D engine's shapes ([`polyhedron`]: convex polyhedra, spheres, half-spaces) are in their principal
//! frame; hulls and mass properties come from `parry3d-f64`.

mod polygon;
pub mod polyhedron;

pub use polygon::{Compound, ConvexPolygon, GeometryError, Shape};
pub use polyhedron::{Face, Polyhedron, Pose, Solid, SolidError, Vec3};

/// A 2D vector in SI units (m, m/s, N, …).
pub type Vec2 = nalgebra::Vector2<f64>;

/// 2D cross product `a × b` (the z component of the 3D product).
#[inline(always)]
pub fn cross(a: Vec2, b: Vec2) -> f64 {
    a.x * b.y - a.y * b.x
}

/// `a` rotated by +90°: `(-a.y, a.x)`.
#[inline(always)]
pub fn perp(a: Vec2) -> Vec2 {
    Vec2::new(-a.y, a.x)
}

/// `v` rotated by the angle whose cosine and sine are `c` and `s`.
#[inline(always)]
pub fn rotate(v: Vec2, c: f64, s: f64) -> Vec2 {
    Vec2::new(c * v.x - s * v.y, s * v.x + c * v.y)
}

/// Largest coordinate or size (m) a scene may use, so that the contact
/// detection grid stays finite.
pub const MAX_LENGTH: f64 = 1.0e9;
/// Smallest size (radius of the enclosing circle, m) of a body.
pub const MIN_SIZE: f64 = 1.0e-9;
