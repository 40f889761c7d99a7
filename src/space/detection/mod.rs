//! Contact detection between 3D solids — convex polyhedra, spheres and half-space walls — for the 3D NSCD
//! engine, after LMGC90's 3D detection modules (mod_PRPRx polyhedron–polyhedron by a common plane, mod_PRPLx
//! polyhedron–plane, mod_SPPRx sphere–polyhedron, mod_SPSPx sphere–sphere, mod_SPPLx sphere–plane).
//!
//! Conventions, as in the 2D detection of [`crate::plane`]: a contact is between a *candidate* `a` and an
//! *antagonist* `b`; the unit normal points from the antagonist towards the candidate; the gap is positive when
//! the two are apart and negative when they overlap (m); everything is in the world frame.
//!
//! - [`placed`]: the shapes placed in the world (world vertices, face planes, edges with their two faces),
//!   computed once per detection; [`PolyhedronView`] is the placed polyhedron the narrow phase reads.
//! - [`axis`]: the common-plane normal of two polyhedra: the previous step's normal first (shadow overlap),
//!   then the separating-axis search over face normals and edge × edge directions, refined by GJK
//!   (parry3d) when the pair is apart.
//! - [`polygon`]: the two features nearest the common plane projected on it, their convex intersection and
//!   its reduction to at most four points.
//! - [`narrow`]: the pair functions, each returning an [`Option<Manifold>`].
//! - [`broad`]: a uniform grid of boxes enlarged by the alert distance.
//! - [`detector`]: [`Detector`], the per-step driver with reused buffers and the per-pair memory of the normal.
//!
//! A [`Manifold`] holds up to four points sharing one normal and one tangent frame; each point sits on the
//! mid-plane between the two surfaces along the normal and has its own gap ([`FaceGaps::Exact`], the default),
//! or, with [`FaceGaps::CommonPlane`], the points of a face–face contact share the smallest gap as in LMGC90.
//! The tangent frame is built from the normal alone by [`tangent_frame`].

pub mod axis;
pub mod broad;
pub mod detector;
pub mod narrow;
pub mod placed;
pub mod polygon;

#[cfg(test)]
mod tests;
#[cfg(test)]
mod tests_detector;
#[cfg(test)]
mod tests_reference;

pub use detector::{Detector, Found, Times};
pub use narrow::{
    polyhedron_half_space, polyhedron_polyhedron, polyhedron_polyhedron_with, polyhedron_sphere, sphere_half_space,
    sphere_polyhedron, sphere_sphere,
};
pub use placed::{Edge3, PlacedPolyhedron, Plane, PolyhedronView};

use crate::geometry::Vec3;
use serde::{Deserialize, Serialize};

/// How the points of a face–face contact of two polyhedra get their gaps (scene key `[nscd] face_gaps`).
///
/// The two rules differ only between nearly parallel faces. There `Exact` lets a grain rock about the points that
/// touch, while `CommonPlane` holds the faces flush. On the seated 2 000-grain track section, one loading cycle
/// (`quad` 1e-3) takes the sleeper down to −153 µm with `Exact` and to −55 µm with `CommonPlane`; LMGC90 gives
/// −64 µm (`docs/lmgc90-3d.md`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FaceGaps {
    /// Every point has its own gap, measured along the normal between the two surfaces: the rigid shapes'
    /// geometry (the default, `"exact"`).
    #[default]
    Exact,
    /// LMGC90 PRPRx's face–face rule (`"common_plane"`; `DETECTION_COMMON_PLANE` after Cundall's common plane,
    /// which assigns the plane's gap to every point of a face–face contact). Let `ref` be the smaller distance
    /// from a polyhedron's centroid to its vertex nearest the plane, measured along the normal, and let `band`
    /// be [`COMMON_PLANE_BAND`] `× ref + max(0, −g)/2`, with `g` the plane's separation. When each polyhedron
    /// has at least three vertices within `band` of its vertex nearest the plane, the contact is face–face. Its
    /// points come from the projections of those vertices and are kept whatever their gap. Every point then
    /// takes the smallest of their gaps, so the faces count as flush. Other contacts (vertex or edge on one
    /// side) keep their exact gaps, as LMGC90's vertex and edge cases do.
    CommonPlane,
}

/// The face–face band of [`FaceGaps::CommonPlane`] as a fraction of the reference size: LMGC90's
/// `cundall_neighbor` default, 0.1.
pub const COMMON_PLANE_BAND: f64 = 0.1;

impl FaceGaps {
    /// The rule named `name` (`"exact"` or `"common_plane"`).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "exact" => Some(Self::Exact),
            "common_plane" => Some(Self::CommonPlane),
            _ => None,
        }
    }

    /// The rule's name in scenes.
    pub fn name(self) -> &'static str {
        match self {
            Self::Exact => "exact",
            Self::CommonPlane => "common_plane",
        }
    }
}

/// One contact point of a [`Manifold`].
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ContactPoint3 {
    /// Position (world, m): half-way between the two surfaces along the normal.
    pub position: Vec3,
    /// Signed gap (m) along the normal between the two surfaces at this point; negative when overlapping.
    pub gap: f64,
}

/// The contact between two solids: up to four points sharing one normal and one tangent frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Manifold {
    /// Unit normal, from the antagonist towards the candidate.
    pub normal: Vec3,
    /// First unit tangent (see [`tangent_frame`]).
    pub t1: Vec3,
    /// Second unit tangent, `normal × t1`: `(t1, t2, normal)` is right-handed and orthonormal.
    pub t2: Vec3,
    /// The points; only the first `len` are meaningful.
    pub points: [ContactPoint3; 4],
    /// Number of points, 1 to 4.
    pub len: usize,
}

impl Manifold {
    /// A manifold of normal `normal` (unit) and no point yet, its frame from [`tangent_frame`].
    pub fn new(normal: Vec3) -> Self {
        let (t1, t2) = tangent_frame(&normal);
        Self { normal, t1, t2, points: [ContactPoint3::default(); 4], len: 0 }
    }

    /// The points found.
    pub fn points(&self) -> &[ContactPoint3] {
        &self.points[..self.len]
    }

    /// Appends a point (at most four).
    pub(crate) fn push(&mut self, position: Vec3, gap: f64) {
        debug_assert!(self.len < 4);
        self.points[self.len] = ContactPoint3 { position, gap };
        self.len += 1;
    }

    /// The same contact seen from the other side: candidate and antagonist swapped (normal reversed, frame
    /// rebuilt from it, points unchanged).
    pub fn reversed(&self) -> Self {
        Self { points: self.points, len: self.len, ..Self::new(-self.normal) }
    }
}

/// The tangent frame of a unit normal `n`: `e` is the world axis least aligned with `n` (the first of x, y, z
/// of smallest `|n_k|`), `t1 = normalize(e − (e·n) n)` and `t2 = n × t1`, so `(t1, t2, n)` is right-handed and
/// orthonormal, and a normal along `+z` gives `(x, y)`. A pure function of `n`: it jumps by a quarter turn
/// when the least aligned axis changes.
pub fn tangent_frame(n: &Vec3) -> (Vec3, Vec3) {
    let a = n.abs();
    let k = if a.x <= a.y && a.x <= a.z {
        0
    } else if a.y <= a.z {
        1
    } else {
        2
    };
    let mut e = Vec3::zeros();
    e[k] = 1.0;
    let t1 = (e - n * n[k]).normalize();
    (t1, n.cross(&t1))
}
