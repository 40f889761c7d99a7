//! Convex polyhedra and spheres in their body frame for the 3D NSCD engine: the centroid at the origin and the
//! axes along the principal axes of inertia, so that a body's inertia tensor is diagonal in its own frame (as
//! LMGC90's RBDY3 keeps it: the angular velocity is expressed in that frame and the inverse inertia is three
//! numbers).
//!
//! The faces are the convex hull's triangles with the coplanar ones merged (normals within a stated angle), as
//! LMGC90's POLYR contactor does for its detection; the edges are the hull's, each once.

use nalgebra::{UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};

/// A 3D vector in SI units (m, m/s, N, …).
pub type Vec3 = Vector3<f64>;

/// Why a 3D shape was refused.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolidError {
    /// Fewer than 4 points (the count given).
    #[error("a polyhedron needs at least 4 vertices, got {0}")]
    TooFewVertices(usize),
    /// A point (its index) has a non-finite coordinate.
    #[error("vertex {0} is not finite")]
    NonFinite(usize),
    /// The points are coplanar, collinear or coincident: the hull has no volume.
    #[error("degenerate polyhedron: the vertices span no volume (coplanar, collinear or coincident)")]
    Degenerate,
    /// A sphere radius or a box half-size (m) that is not positive and finite.
    #[error("size must be positive and finite, got {0}")]
    BadSize(f64),
}

/// A face of a [`Polyhedron`]: a convex polygon of the hull.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Face {
    /// Vertex indices, counter-clockwise seen from outside (along `-normal`).
    pub vertices: Vec<u32>,
    /// Outward unit normal (body frame).
    pub normal: Vec3,
    /// `normal · x` for every point `x` of the face (m): the face's plane is `normal · x = offset`; positive,
    /// the centroid being inside.
    pub offset: f64,
}

/// A convex polyhedron in its body frame: centroid at the origin, axes the principal axes of inertia.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Polyhedron {
    /// Vertices of the hull (m), body frame; every one is a corner of the hull.
    pub vertices: Vec<Vec3>,
    /// Faces, coplanar triangles merged.
    pub faces: Vec<Face>,
    /// Edges between two faces, each once, lower vertex index first (vertices joined inside a merged face are
    /// not edges).
    pub edges: Vec<[u32; 2]>,
    /// Volume (m³).
    pub volume: f64,
    /// Principal second moments of the volume about the centroid (m⁵): the principal moments of inertia per unit
    /// density, about the body axes x, y, z (ascending).
    pub inertia_per_density: Vec3,
    /// Radius of the sphere about the centroid that holds every vertex (m).
    pub radius: f64,
    /// Distance from the centroid to the nearest face plane (m).
    pub inradius: f64,
}

impl Polyhedron {
    /// Default angle (rad) below which the normals of two adjacent hull triangles are taken as one face: 1e-6,
    /// well under the 1e-3 rad of a real facet's flatness and above the round-off of a hull of 12–30 points.
    pub const MERGE_ANGLE: f64 = 1e-6;

    /// The box of half sizes `half` (m) along the body axes, centred at the origin: 8 vertices, 6 square faces,
    /// 12 edges. Its principal moments per unit density are `V (b² + c²) / 3` and circular permutations, with
    /// `V = 8 a b c` for the half sizes `a, b, c` — exact, so tests may compare with them directly.
    pub fn cuboid(half: [f64; 3]) -> Result<Self, SolidError> {
        if let Some(&h) = half.iter().find(|h| !(h.is_finite() && **h > 0.0)) {
            return Err(SolidError::BadSize(h));
        }
        let [a, b, c] = half;
        // Vertex k has the signs of its bits: x from bit 0, y from bit 1, z from bit 2.
        let vertices: Vec<Vec3> = (0..8)
            .map(|k| {
                let s = |bit: u32| if k & (1 << bit) != 0 { 1.0 } else { -1.0 };
                Vec3::new(s(0) * a, s(1) * b, s(2) * c)
            })
            .collect();
        // Counter-clockwise seen from outside.
        let quad = |v: [u32; 4], normal: Vec3, offset: f64| Face { vertices: v.to_vec(), normal, offset };
        let faces = vec![
            quad([0, 4, 6, 2], -Vec3::x(), a),
            quad([1, 3, 7, 5], Vec3::x(), a),
            quad([0, 1, 5, 4], -Vec3::y(), b),
            quad([2, 6, 7, 3], Vec3::y(), b),
            quad([0, 2, 3, 1], -Vec3::z(), c),
            quad([4, 5, 7, 6], Vec3::z(), c),
        ];
        let mut edges = Vec::with_capacity(12);
        for i in 0..8u32 {
            for bit in 0..3 {
                let j = i | (1 << bit);
                if j != i {
                    edges.push([i, j]);
                }
            }
        }
        edges.sort_unstable();
        let volume = 8.0 * a * b * c;
        let inertia_per_density =
            Vec3::new(volume * (b * b + c * c) / 3.0, volume * (a * a + c * c) / 3.0, volume * (a * a + b * b) / 3.0);
        Ok(Self {
            vertices,
            faces,
            edges,
            volume,
            inertia_per_density,
            radius: (a * a + b * b + c * c).sqrt(),
            inradius: a.min(b).min(c),
        })
    }

    /// The support point: the vertex (its index) furthest along `direction` (body frame); the first of equals.
    pub fn support(&self, direction: &Vec3) -> usize {
        let mut best = (0, f64::NEG_INFINITY);
        for (k, v) in self.vertices.iter().enumerate() {
            let d = v.dot(direction);
            if d > best.1 {
                best = (k, d);
            }
        }
        best.0
    }
}

/// A rigid placement: the body frame's origin in the world (m) and the rotation from the body frame to the world.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position of the centroid (m).
    pub position: Vec3,
    /// Rotation body → world.
    pub rotation: UnitQuaternion<f64>,
}

impl Pose {
    /// A pose at `position` with the body axes along the world's.
    pub fn at(position: Vec3) -> Self {
        Self { position, rotation: UnitQuaternion::identity() }
    }

    /// A body-frame point in the world.
    #[inline]
    pub fn point(&self, x: &Vec3) -> Vec3 {
        self.position + self.rotation * x
    }

    /// A body-frame direction in the world.
    #[inline]
    pub fn vector(&self, x: &Vec3) -> Vec3 {
        self.rotation * x
    }
}

/// The shape of a 3D body.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Solid {
    /// A convex polyhedron.
    Polyhedron(Polyhedron),
    /// A sphere of this radius (m).
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// The half-space `z ≤ 0` of the body frame (a floor or a wall; its outward normal is the body's `+z`). Only a
    /// fixed body may be one.
    HalfSpace,
}

impl Solid {
    /// Volume (m³), principal second moments per unit density (m⁵); infinite for a half-space.
    pub fn mass_properties(&self) -> (f64, Vec3) {
        match self {
            Solid::Polyhedron(p) => (p.volume, p.inertia_per_density),
            Solid::Sphere { radius } => {
                let v = 4.0 / 3.0 * std::f64::consts::PI * radius.powi(3);
                (v, Vec3::repeat(0.4 * v * radius * radius))
            }
            Solid::HalfSpace => (f64::INFINITY, Vec3::repeat(f64::INFINITY)),
        }
    }

    /// Radius of the sphere about the centroid holding the shape (m); infinite for a half-space.
    pub fn radius(&self) -> f64 {
        match self {
            Solid::Polyhedron(p) => p.radius,
            Solid::Sphere { radius } => *radius,
            Solid::HalfSpace => f64::INFINITY,
        }
    }
}
