//! Convex polyhedra and spheres in their body frame for the 3D NSCD engine: the centroid at the origin and the
//! axes along the principal axes of inertia, so that a body's inertia tensor is diagonal in its own frame (as
//! LMGC90's RBDY3 keeps it: the angular velocity is expressed in that frame and the inverse inertia is three
//! numbers).
//!
//! [`Polyhedron::from_points`] makes a grain of a point cloud: the convex hull (parry3d-f64's quickhull, run on the
//! points mapped affinely to an isotropic cloud so that its fixed tolerances do not take a thin grain for a flat
//! one), the adjacent coplanar triangles merged into convex polygonal faces (normals within a stated angle, as
//! LMGC90's POLYR contactor does for its detection), the points that are not corners dropped, the volume, centroid
//! and inertia exact (tetrahedra from the centroid) and the vertices expressed in the principal frame. It takes
//! about 70 µs for 30 points (release build): a scene-loading cost, not a hot loop.

use std::collections::BTreeMap;

use nalgebra::{Matrix3, Rotation3, SymmetricEigen, UnitQuaternion, Vector3};
use parry3d_f64::math::Vector as HullPoint;
use parry3d_f64::transformation::try_convex_hull;
use serde::{Deserialize, Serialize};

use super::MAX_LENGTH;

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
    /// The `merge_angle` of [`Polyhedron::from_points`] (rad) is not finite or outside `[0, MAX_MERGE_ANGLE]`.
    #[error("merge_angle must be finite and in [0, {max}] rad, got {0}", max = Polyhedron::MAX_MERGE_ANGLE)]
    BadMergeAngle(f64),
    /// A point (its index) lies further than [`MAX_LENGTH`] from the origin along an axis.
    #[error("vertex {0} lies beyond {MAX_LENGTH:e} m from the origin")]
    OutOfRange(usize),
    /// parry3d's hull failed or gave a surface that is not a closed convex one (its words).
    #[error("the convex hull failed: {0}")]
    Hull(String),
}

/// A face of a [`Polyhedron`]: a convex polygon of the hull.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Face {
    /// Vertex indices, counter-clockwise seen from outside (along `-normal`).
    pub vertices: Vec<u32>,
    /// Outward unit normal (body frame).
    pub normal: Vec3,
    /// `normal · x` for every point `x` of the face (m): the face's plane is `normal · x = offset`; positive,
    /// the centroid being inside. [`Polyhedron::from_points`] takes the largest `normal · v` over all vertices, so
    /// that the plane supports the hull even where a merged face is flat only to its `merge_angle`.
    pub offset: f64,
}

/// A convex polyhedron in its body frame: centroid at the origin, axes the principal axes of inertia.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Polyhedron {
    /// Vertices of the hull (m), body frame; every one is a corner of the hull.
    pub vertices: Vec<Vec3>,
    /// Faces, coplanar triangles merged.
    pub faces: Vec<Face>,
    /// Edges between two faces, each once, lower vertex index first, sorted (vertices joined inside a merged face
    /// are not edges).
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

    /// Largest `merge_angle` (rad) [`Polyhedron::from_points`] accepts: triangles further apart than that would make
    /// visibly non-planar faces.
    pub const MAX_MERGE_ANGLE: f64 = 0.1;

    /// The convex hull of `points` (m, any frame) in its body frame, and the pose of that frame in the points' frame
    /// (`pose.point(&v)` gives back the input coordinates of every vertex `v`, which are input points).
    ///
    /// Points inside the hull, on its edges or inside its faces are dropped; adjacent hull triangles whose normals
    /// are within `merge_angle` (rad, e.g. [`Polyhedron::MERGE_ANGLE`]) of the face's largest triangle, or whose
    /// corners are within round-off (1e-12 of the largest coordinate) of its plane, make one face. Points closer
    /// than 1e-10 of that size to a point kept are the same point. The vertices keep the input order. When
    /// principal moments are equal (to 1e-12 relative) the frame is the input axes, or the distinct axis and the
    /// input axis most normal to it, projected. Refused: fewer than 4 points, a coordinate not finite or beyond
    /// [`MAX_LENGTH`], a hull of volume under 1e-12 of the bounding box's largest side cubed, a `merge_angle` out of
    /// `[0, MAX_MERGE_ANGLE]`, a hull parry3d fails on; never a panic or a NaN.
    pub fn from_points(points: &[[f64; 3]], merge_angle: f64) -> Result<(Self, Pose), SolidError> {
        if !(0.0..=Self::MAX_MERGE_ANGLE).contains(&merge_angle) {
            return Err(SolidError::BadMergeAngle(merge_angle));
        }
        if points.len() < 4 {
            return Err(SolidError::TooFewVertices(points.len()));
        }
        let mut all = Vec::with_capacity(points.len());
        for (i, p) in points.iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) {
                return Err(SolidError::NonFinite(i));
            }
            if p.iter().any(|x| x.abs() > MAX_LENGTH) {
                return Err(SolidError::OutOfRange(i));
            }
            all.push(Vec3::from(*p));
        }
        let (lo, hi) = all.iter().fold((all[0], all[0]), |(lo, hi), p| (lo.inf(p), hi.sup(p)));
        let extent = (hi - lo).max();
        // Round-off of the input: 1e-12 of the largest coordinate (≈ 4500 ulps), at least of the extent.
        let round = 1e-12 * all.iter().map(|p| p.amax()).fold(extent, f64::max);
        let pts = weld(&all, 100.0 * round);
        if pts.len() < 4 || extent <= 0.0 {
            return Err(SolidError::Degenerate);
        }
        let mid = (lo + hi) / 2.0;
        let tris = hull(&pts, mid, extent)?;
        let flat: f64 = tris.iter().map(|t| tet(pts[t[0]] - mid, pts[t[1]] - mid, pts[t[2]] - mid)).sum();
        if !(flat.is_finite() && flat > 1e-12 * extent.powi(3)) {
            return Err(SolidError::Degenerate);
        }
        let loops = merge_faces(&pts, &tris, merge_angle, round)?;

        // The corners, in the input order, and the faces on them, each from its lowest vertex, sorted.
        let mut corners = loops.concat();
        corners.sort_unstable();
        corners.dedup();
        let mut loops: Vec<Vec<u32>> = loops
            .iter()
            .map(|l| {
                let mut l: Vec<u32> = l.iter().map(|v| corners.partition_point(|c| c < v) as u32).collect();
                let first = l.iter().enumerate().min_by_key(|(_, v)| **v).map_or(0, |(k, _)| k);
                l.rotate_left(first);
                l
            })
            .collect();
        loops.sort();
        let world: Vec<Vec3> = corners.iter().map(|&i| pts[i]).collect();

        // Volume and centroid by tetrahedra from the corners' mean, then the second moment from the centroid:
        // ∫ x xᵀ over the tetrahedron (0, a, b, c) is V/20 (a aᵀ + b bᵀ + c cᵀ + s sᵀ), s = a + b + c.
        let mean = world.iter().sum::<Vec3>() / world.len() as f64;
        let (mut volume, mut first) = (0.0, Vec3::zeros());
        fan(&loops, &world, mean, |a, b, c| {
            let v = tet(a, b, c);
            volume += v;
            first += v * (a + b + c) / 4.0;
        });
        if !(volume.is_finite() && volume > 1e-12 * extent.powi(3)) {
            return Err(SolidError::Degenerate);
        }
        let centroid = mean + first / volume;
        let mut second = Matrix3::zeros();
        fan(&loops, &world, centroid, |a, b, c| {
            let s = a + b + c;
            second +=
                tet(a, b, c) / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
        });
        let inertia = Matrix3::identity() * second.trace() - second;
        let (moments, axes) = principal_frame(&inertia);
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(axes));
        let rotation = UnitQuaternion::new_normalize(q.into_inner());
        let vertices: Vec<Vec3> = world.iter().map(|p| rotation.inverse_transform_vector(&(p - centroid))).collect();

        // Faces: the Newell normal (area-weighted, exact for a planar polygon) and the support along it.
        let mut faces = Vec::with_capacity(loops.len());
        for l in loops {
            let o = vertices[l[0] as usize];
            let area: Vec3 =
                (1..l.len() - 1).map(|k| (vertices[l[k] as usize] - o).cross(&(vertices[l[k + 1] as usize] - o))).sum();
            let normal = area.try_normalize(0.0).ok_or_else(|| SolidError::Hull("a face has no area".into()))?;
            let offset = vertices.iter().map(|v| normal.dot(v)).fold(f64::NEG_INFINITY, f64::max);
            faces.push(Face { vertices: l, normal, offset });
        }
        let mut edges: Vec<[u32; 2]> = faces
            .iter()
            .flat_map(|f| f.vertices.iter().zip(f.vertices.iter().cycle().skip(1)).map(|(&a, &b)| [a.min(b), a.max(b)]))
            .collect();
        edges.sort_unstable();
        edges.dedup();
        let radius = vertices.iter().map(|v| v.norm()).fold(0.0, f64::max);
        let inradius = faces.iter().map(|f| f.offset).fold(f64::INFINITY, f64::min);
        let poly = Self { vertices, faces, edges, volume, inertia_per_density: moments, radius, inradius };
        Ok((poly, Pose { position: centroid, rotation }))
    }

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

/// Signed volume of the tetrahedron (0, a, b, c).
fn tet(a: Vec3, b: Vec3, c: Vec3) -> f64 {
    a.dot(&b.cross(&c)) / 6.0
}

/// Calls `f` on the triangles of each face's fan from its first vertex, corners relative to `origin`.
fn fan(loops: &[Vec<u32>], pts: &[Vec3], origin: Vec3, mut f: impl FnMut(Vec3, Vec3, Vec3)) {
    for l in loops {
        let a = pts[l[0] as usize] - origin;
        for k in 1..l.len() - 1 {
            f(a, pts[l[k] as usize] - origin, pts[l[k + 1] as usize] - origin);
        }
    }
}

/// The points, those within `distance` of one kept before them in the order of x dropped, in the input order.
fn weld(pts: &[Vec3], distance: f64) -> Vec<Vec3> {
    let mut by_x: Vec<usize> = (0..pts.len()).collect();
    by_x.sort_by(|&a, &b| pts[a].x.total_cmp(&pts[b].x).then(a.cmp(&b)));
    let mut gone = vec![false; pts.len()];
    for (k, &i) in by_x.iter().enumerate() {
        if gone[i] {
            continue;
        }
        for &j in &by_x[k + 1..] {
            if pts[j].x - pts[i].x > distance {
                break;
            }
            gone[j] |= (pts[j] - pts[i]).norm() <= distance;
        }
    }
    pts.iter().zip(&gone).filter(|(_, g)| !**g).map(|(p, _)| *p).collect()
}

/// parry3d's hull of `pts`: triangles of indices into `pts`, counter-clockwise seen from outside. It runs on the
/// points centred on `mid`, scaled by `extent` and whitened (unit covariance, anisotropy capped at 1e9), because its
/// dimension test (a covariance eigenvalue under 1e-7 of the squared diagonal) takes a slab thinner than ~5e-4
/// of its width for a flat one; the hull of an affine image (det > 0) is the image of the hull, same orientation.
fn hull(pts: &[Vec3], mid: Vec3, extent: f64) -> Result<Vec<[usize; 3]>, SolidError> {
    let q: Vec<Vec3> = pts.iter().map(|p| (p - mid) / extent).collect();
    let mean = q.iter().sum::<Vec3>() / q.len() as f64;
    let eig = SymmetricEigen::new(q.iter().fold(Matrix3::zeros(), |c, p| c + (p - mean) * (p - mean).transpose()));
    let mut axes = eig.eigenvectors;
    if axes.determinant() < 0.0 {
        axes.column_mut(2).neg_mut();
    }
    let floor = 1e-18 * eig.eigenvalues.max();
    if !(floor.is_finite() && floor > 0.0) {
        return Err(SolidError::Degenerate);
    }
    let scale = eig.eigenvalues.map(|l| 1.0 / l.max(floor).sqrt());
    let white: Vec<HullPoint> = q
        .iter()
        .map(|p| axes.tr_mul(&(p - mean)).component_mul(&scale))
        .map(|w| HullPoint::new(w.x, w.y, w.z))
        .collect();
    // parry returns copies of the points it keeps (reordered by swap_remove): find them back by their bits.
    let key = |w: &HullPoint| [w.x.to_bits(), w.y.to_bits(), w.z.to_bits()];
    let mut index: Vec<([u64; 3], usize)> = white.iter().map(key).zip(0..).collect();
    index.sort_unstable();
    let failed = |why: &str| SolidError::Hull(format!("parry3d {why}"));
    let (vertices, tris) = std::panic::catch_unwind(|| try_convex_hull(&white))
        .map_err(|_| failed("panicked"))?
        .map_err(|e| SolidError::Hull(e.to_string()))?;
    let ids = vertices
        .iter()
        .map(|w| {
            let j = index.partition_point(|e| e.0 < key(w));
            index.get(j).filter(|e| e.0 == key(w)).map(|e| e.1).ok_or_else(|| failed("returned a point not given"))
        })
        .collect::<Result<Vec<usize>, _>>()?;
    let id = |v: u32| ids.get(v as usize).copied().ok_or_else(|| failed("returned a bad index"));
    tris.iter().map(|t| Ok([id(t[0])?, id(t[1])?, id(t[2])?])).collect()
}

/// The faces of the closed hull `tris` over `pts`: loops of corners, counter-clockwise seen from outside. A face
/// grows from its largest triangle over the neighbours whose normal is within `angle` of its normal or whose
/// corners are within `round` of its plane (a sliver's normal means nothing); a vertex is a corner when on three
/// faces or more (on two: inside an edge; on none: inside a face). A face that is not a single convex loop is split
/// back into its triangles.
fn merge_faces(pts: &[Vec3], tris: &[[usize; 3]], angle: f64, round: f64) -> Result<Vec<Vec<usize>>, SolidError> {
    let bad = |why: &str| SolidError::Hull(format!("parry3d's hull {why}"));
    let mut across = BTreeMap::new();
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            if tri[k] == tri[(k + 1) % 3] || across.insert((tri[k], tri[(k + 1) % 3]), t).is_some() {
                return Err(bad("has an edge on more than two triangles"));
            }
        }
    }
    let mut next = vec![[0; 3]; tris.len()];
    for (t, tri) in tris.iter().enumerate() {
        for k in 0..3 {
            next[t][k] = *across.get(&(tri[(k + 1) % 3], tri[k])).ok_or_else(|| bad("is not closed"))?;
        }
    }
    let area: Vec<Vec3> = tris.iter().map(|t| (pts[t[1]] - pts[t[0]]).cross(&(pts[t[2]] - pts[t[0]]))).collect();
    let mut order: Vec<usize> = (0..tris.len()).collect();
    order.sort_by(|&a, &b| area[b].norm().total_cmp(&area[a].norm()));
    let mut owner = vec![usize::MAX; tris.len()];
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for &s in &order {
        if owner[s] != usize::MAX {
            continue;
        }
        owner[s] = groups.len();
        let mut members = vec![s];
        if let Some(n) = area[s].try_normalize(0.0) {
            let on_plane = |u: usize| tris[u].iter().all(|&i| n.dot(&(pts[i] - pts[tris[s][0]])).abs() <= round);
            let close = |u: usize| area[u] != Vec3::zeros() && n.cross(&area[u]).norm().atan2(n.dot(&area[u])) <= angle;
            let mut i = 0;
            while let Some(&t) = members.get(i) {
                i += 1;
                for u in next[t] {
                    if owner[u] == usize::MAX && (close(u) || on_plane(u)) {
                        owner[u] = groups.len();
                        members.push(u);
                    }
                }
            }
        }
        groups.push(members);
    }
    // A triangle that fails sits in a notch of a merged neighbour: split that one.
    loop {
        let g = match face_loops(pts, tris, &next, &owner, &groups) {
            Ok(loops) => return Ok(loops),
            Err(g) => g,
        };
        let mut split: Vec<usize> = match groups[g][..] {
            [t] => next[t].iter().map(|&u| owner[u]).filter(|&h| groups[h].len() > 1).collect(),
            _ => vec![g],
        };
        split.sort_unstable();
        split.dedup();
        if split.is_empty() {
            return Err(bad("has a face that is not a convex polygon"));
        }
        for h in split {
            for t in groups[h].split_off(1) {
                owner[t] = groups.len();
                groups.push(vec![t]);
            }
        }
    }
}

/// The corner loops of the triangle groups, or the first group that is not a single convex loop.
fn face_loops(
    pts: &[Vec3],
    tris: &[[usize; 3]],
    next: &[[usize; 3]],
    owner: &[usize],
    groups: &[Vec<usize>],
) -> Result<Vec<Vec<usize>>, usize> {
    let mut loops = Vec::with_capacity(groups.len());
    for (g, members) in groups.iter().enumerate() {
        let mut after = BTreeMap::new();
        for &t in members {
            for k in 0..3 {
                if owner[next[t][k]] != g && after.insert(tris[t][k], tris[t][(k + 1) % 3]).is_some() {
                    return Err(g);
                }
            }
        }
        let Some((&start, &second)) = after.first_key_value() else { return Err(g) };
        let mut l = vec![start];
        let mut v = second;
        while v != start && l.len() < after.len() {
            l.push(v);
            v = *after.get(&v).ok_or(g)?;
        }
        if v != start || l.len() != after.len() {
            return Err(g);
        }
        loops.push(l);
    }
    let mut faces_at = vec![0; pts.len()];
    loops.iter().flatten().for_each(|&v| faces_at[v] += 1);
    for (g, l) in loops.iter_mut().enumerate() {
        l.retain(|&v| faces_at[v] >= 3);
        let n = l.len();
        let o = pts[l.first().copied().unwrap_or(0)];
        let normal: Vec3 = (1..n.max(2) - 1).map(|k| (pts[l[k]] - o).cross(&(pts[l[k + 1]] - o))).sum();
        // Every turn to the left about the normal, up to a sine of 1e-9 (corners on a straight line).
        let convex = (0..n).all(|k| {
            let (a, b) = (pts[l[(k + 1) % n]] - pts[l[k]], pts[l[(k + 2) % n]] - pts[l[(k + 1) % n]]);
            a.cross(&b).dot(&normal) >= -1e-9 * a.norm() * b.norm() * normal.norm()
        });
        if n < 3 || normal == Vec3::zeros() || !convex {
            return Err(g);
        }
    }
    Ok(loops)
}

/// The principal moments (ascending) of a symmetric inertia tensor and its principal axes (the columns, a
/// right-handed frame): each eigenvector with its largest component positive; with three equal moments (to 1e-12
/// relative) the input axes, with two the distinct axis `u` and, for the pair, the input axis most normal to `u`
/// projected normal to it, then their cross product — so that the frame is the same for the same input.
fn principal_frame(inertia: &Matrix3<f64>) -> (Vec3, Matrix3<f64>) {
    let eig = SymmetricEigen::new(*inertia);
    let mut order = [0, 1, 2];
    order.sort_by(|&i, &j| eig.eigenvalues[i].total_cmp(&eig.eigenvalues[j]));
    let moments = Vec3::from_fn(|k, _| eig.eigenvalues[order[k]]);
    let mut axes = order.map(|k| eig.eigenvectors.column(k).into_owned()).map(|e: Vec3| e * e[e.iamax()].signum());
    let pair = |u: Vec3| {
        let k = u.iamin();
        let e = (Vec3::ith(k, 1.0) - u[k] * u).normalize();
        (e, u.cross(&e))
    };
    let same = 1e-12 * moments.z.abs();
    if moments.z - moments.x <= same {
        axes = [Vec3::x(), Vec3::y(), Vec3::z()];
    } else if moments.y - moments.x <= same {
        let (e, f) = pair(axes[2]);
        axes = [e, f, axes[2]];
    } else if moments.z - moments.y <= same {
        let (e, f) = pair(axes[0]);
        axes = [axes[0], e, f];
    }
    if axes[0].cross(&axes[1]).dot(&axes[2]) < 0.0 {
        axes[2] = -axes[2];
    }
    (moments, Matrix3::from_columns(&axes))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Quaternion;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::f64::consts::PI;

    // Tolerances: every quantity is a sum of at most a few hundred products of coordinates exact to round-off
    // (ε = 2.2e-16, sizes ~1, positions ~10), so 1e-12 relative leaves a margin of ~100 over the accumulated
    // round-off; the eigenvectors are good to ~1e-15, hence off-diagonals under 1e-10 of the largest moment.

    fn rotation(rng: &mut ChaCha8Rng) -> UnitQuaternion<f64> {
        let mut c = || rng.random::<f64>() * 2.0 - 1.0;
        UnitQuaternion::from_quaternion(Quaternion::new(c(), c(), c(), c() + 0.1))
    }

    fn placed(q: &UnitQuaternion<f64>, t: Vec3, local: &[Vec3]) -> Vec<[f64; 3]> {
        local.iter().map(|p| (q * p + t).into()).collect()
    }

    fn close(a: f64, b: f64, rel: f64) -> bool {
        (a - b).abs() <= rel * a.abs().max(b.abs())
    }

    fn build(input: &[[f64; 3]]) -> (Polyhedron, Pose) {
        Polyhedron::from_points(input, Polyhedron::MERGE_ANGLE).expect("a valid hull")
    }

    /// Volume, first moment and second moment ∫ x xᵀ about the body origin, by tetrahedra from the origin.
    fn moments(p: &Polyhedron) -> (f64, Vec3, Matrix3<f64>) {
        let (mut v, mut m1, mut m2) = (0.0, Vec3::zeros(), Matrix3::zeros());
        let loops: Vec<Vec<u32>> = p.faces.iter().map(|f| f.vertices.clone()).collect();
        fan(&loops, &p.vertices, Vec3::zeros(), |a, b, c| {
            let (dv, s) = (a.dot(&b.cross(&c)) / 6.0, a + b + c);
            (v, m1) = (v + dv, m1 + dv * s / 4.0);
            m2 += dv / 20.0 * (a * a.transpose() + b * b.transpose() + c * c.transpose() + s * s.transpose());
        });
        (v, m1, Matrix3::identity() * m2.trace() - m2)
    }

    /// Topology, planes, every input point inside, centroid at the origin and the inertia diagonal, ascending.
    fn check(p: &Polyhedron, pose: &Pose, input: &[[f64; 3]]) -> (usize, usize, usize) {
        let (nv, nf, ne) = (p.vertices.len(), p.faces.len(), p.edges.len());
        assert_eq!(nv + nf, ne + 2, "Euler");
        let tol = 1e-12 * p.radius;
        let inside = |x: &Vec3| p.faces.iter().all(|f| f.normal.dot(x) <= f.offset + tol);
        assert!(p.vertices.iter().all(inside));
        assert!(input
            .iter()
            .all(|x| inside(&pose.rotation.inverse_transform_vector(&(Vec3::from(*x) - pose.position)))));
        let (mut directed, mut faces_at) = (Vec::new(), vec![0; nv]);
        for f in &p.faces {
            let n = f.vertices.len();
            assert!(n >= 3 && close(f.normal.norm(), 1.0, 1e-12) && f.offset > 0.0);
            for k in 0..n {
                let [a, b, c] = [0, 1, 2].map(|j| p.vertices[f.vertices[(k + j) % n] as usize]);
                assert!((b - a).cross(&(c - b)).dot(&f.normal) > 0.0, "not counter-clockwise from outside");
                assert!((f.normal.dot(&a) - f.offset).abs() <= tol, "a vertex off its face's plane");
                directed.push((f.vertices[k], f.vertices[(k + 1) % n]));
                faces_at[f.vertices[k] as usize] += 1;
            }
        }
        // Each edge on two faces, once each way; every vertex a corner (on three faces or more).
        directed.sort_unstable();
        assert!(directed.windows(2).all(|w| w[0] != w[1]));
        assert!(directed.iter().all(|&(a, b)| directed.binary_search(&(b, a)).is_ok()));
        let edges: Vec<[u32; 2]> = directed.iter().filter(|(a, b)| a < b).map(|&(a, b)| [a, b]).collect();
        assert!(edges == p.edges && faces_at.iter().all(|&k| k >= 3));
        assert_eq!(p.radius, p.vertices.iter().map(|v| v.norm()).fold(0.0, f64::max));
        assert_eq!(p.inradius, p.faces.iter().map(|f| f.offset).fold(f64::INFINITY, f64::min));
        let (v, m1, i) = moments(p);
        let j = p.inertia_per_density;
        assert!(close(v, p.volume, 1e-12) && m1.norm() <= 1e-12 * p.radius.powi(4), "first moment {m1}");
        assert!((0..9).all(|k| k % 4 == 0 || i[k].abs() < 1e-10 * j.z), "not diagonal: {i}");
        assert!((0..3).all(|k| close(i[(k, k)], j[k], 1e-10)) && j.x <= j.y && j.y <= j.z);
        (nv, nf, ne)
    }

    #[test]
    fn box_rotated_with_inner_and_boundary_points() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let (a, b, c) = (3.0, 2.0, 1.2);
        let h = Vec3::new(a, b, c) / 2.0;
        let corners: Vec<Vec3> =
            (0..8).map(|k| Vec3::from_fn(|i, _| if k >> i & 1 == 1 { h[i] } else { -h[i] })).collect();
        let mut local: Vec<Vec3> = (0..20).map(|_| h.map(|h| h * (rng.random::<f64>() * 1.8 - 0.9))).collect();
        local.extend(&corners);
        let on_faces_and_edges =
            [[h.x, 0.0, 0.0], [h.x, 0.3, -0.2], [h.x, h.y, 0.1], [-h.x, 0.2, h.z], [0.0, -h.y, -h.z]];
        local.extend(on_faces_and_edges.map(Vec3::from));
        let (q, t) = (rotation(&mut rng), Vec3::new(10.0, -4.0, 7.0));
        let input = placed(&q, t, &local);
        let (p, pose) = build(&input);
        assert_eq!(check(&p, &pose, &input), (8, 6, 12));
        assert!(p.faces.iter().all(|f| f.vertices.len() == 4));
        let expected = [b * b + c * c, a * a + c * c, a * a + b * b].map(|s| a * b * c * s / 12.0);
        assert!(
            close(p.volume, a * b * c, 1e-12) && (0..3).all(|k| close(p.inertia_per_density[k], expected[k], 1e-12))
        );
        let size = 2.0 * h.norm();
        for v in &p.vertices {
            assert!(corners.iter().any(|c| (q * c + t - pose.point(v)).norm() <= 1e-12 * size));
            assert!((0..3).all(|k| (v[k].abs() - h[k]).abs() <= 1e-12 * size), "body axes along the box's: {v}");
        }
        // Unrotated: the exact cuboid, up to the vertex order.
        let input: Vec<[f64; 3]> = corners.iter().rev().map(|c| (*c).into()).collect();
        let (p, pose) = Polyhedron::from_points(&input, 0.0).expect("a box");
        let cube = Polyhedron::cuboid(h.into()).expect("a box");
        let to_cube = |v: &u32| cube.vertices.iter().position(|w| (p.vertices[*v as usize] - w).norm() <= 1e-12);
        let canon = |l: Vec<u32>| (0..l.len()).map(|k| [&l[k..], &l[..k]].concat()).min();
        for f in &p.faces {
            let mapped = canon(f.vertices.iter().map(|v| to_cube(v).expect("a cube vertex") as u32).collect());
            let g = cube.faces.iter().find(|g| canon(g.vertices.clone()) == mapped).expect("the cube's face");
            assert!((f.normal - g.normal).norm() <= 1e-12 && close(f.offset, g.offset, 1e-12));
        }
        let mut edges: Vec<[u32; 2]> = p.edges.iter().map(|e| e.map(|v| to_cube(&v).unwrap_or(9) as u32)).collect();
        edges.iter_mut().for_each(|e| e.sort_unstable());
        edges.sort_unstable();
        assert!(edges == cube.edges && close(p.volume, cube.volume, 1e-12) && close(p.radius, cube.radius, 1e-12));
        assert!((0..3).all(|k| close(p.inertia_per_density[k], cube.inertia_per_density[k], 1e-12)));
        assert!(pose.position.norm() <= 1e-12 && pose.rotation.angle() <= 1e-12);
    }

    #[test]
    fn tetrahedra() {
        // Regular, edge e: V = e³/(6√2), three equal principal moments V e²/20 (so the frame is the input axes).
        let (e, s) = (0.7, 0.7 / 8f64.sqrt());
        let input = [[s, s, s], [s, -s, -s], [-s, s, -s], [-s, -s, s]].map(|p| p.map(|x| x + 0.25));
        let (p, pose) = build(&input);
        let v = e * e * e / (6.0 * 2f64.sqrt());
        assert_eq!(check(&p, &pose, &input), (4, 4, 6));
        assert!(close(p.volume, v, 1e-12) && (0..3).all(|k| close(p.inertia_per_density[k], v * e * e / 20.0, 1e-12)));
        assert_eq!(pose.rotation, UnitQuaternion::identity());
        // Right, (0, l₁e₁, l₂e₂, l₃e₃): the covariance C = V/20 (Σ vᵢvᵢᵀ + (Σ vᵢ)(Σ vᵢ)ᵀ), shifted to the centroid.
        let l = Vec3::new(1.0, 0.6, 0.3);
        let corners = [Vec3::zeros(), Vec3::x() * l.x, Vec3::y() * l.y, Vec3::z() * l.z];
        let input: Vec<[f64; 3]> = corners.iter().map(|c| (*c).into()).collect();
        let (p, pose) = build(&input);
        check(&p, &pose, &input);
        let (v, sum) = (l.x * l.y * l.z / 6.0, corners.iter().sum::<Vec3>());
        let cov = v / 20.0 * (corners.iter().map(|c| c * c.transpose()).sum::<Matrix3<f64>>() + sum * sum.transpose());
        let cov = cov - v * (sum / 4.0) * (sum / 4.0).transpose();
        let i = Matrix3::identity() * cov.trace() - cov;
        assert!(close(p.volume, v, 1e-12) && (pose.position - sum / 4.0).norm() <= 1e-12);
        let r = pose.rotation.to_rotation_matrix().into_inner();
        assert!((r * Matrix3::from_diagonal(&p.inertia_per_density) * r.transpose() - i).norm() <= 1e-12 * i.norm());
        let mut eigen: Vec<f64> = i.symmetric_eigenvalues().iter().copied().collect();
        eigen.sort_by(f64::total_cmp);
        assert!((0..3).all(|k| close(p.inertia_per_density[k], eigen[k], 1e-12)));
    }

    #[test]
    fn hexagonal_prism() {
        let (r, h) = (1.0, 0.8);
        let at = |k: usize, z: f64| Vec3::new(r * (k as f64 * PI / 3.0).cos(), r * (k as f64 * PI / 3.0).sin(), z);
        let mut local: Vec<Vec3> = (0..12).map(|k| at(k, if k < 6 { h / 2.0 } else { -h / 2.0 })).collect();
        local.extend([
            Vec3::z() * h / 2.0,
            -Vec3::z() * h / 2.0,
            (local[0] + local[1]) / 2.0,
            Vec3::new(0.1, 0.2, 0.0),
        ]);
        let input = placed(&rotation(&mut ChaCha8Rng::seed_from_u64(2)), Vec3::new(-3.0, 2.0, 0.5), &local);
        let (p, pose) = build(&input);
        assert_eq!(check(&p, &pose, &input), (12, 8, 18));
        let mut sizes: Vec<usize> = p.faces.iter().map(|f| f.vertices.len()).collect();
        sizes.sort_unstable();
        assert_eq!(sizes, [4, 4, 4, 4, 4, 4, 6, 6]);
        // V = (3√3/2) r² h; about the axis V 5r²/12, about a diameter V (5r²/24 + h²/12).
        let v = 1.5 * 3f64.sqrt() * r * r * h;
        let [d, z] = [v * (5.0 * r * r / 24.0 + h * h / 12.0), v * 5.0 * r * r / 12.0];
        assert!(close(p.volume, v, 1e-12) && (0..3).all(|k| close(p.inertia_per_density[k], [d, d, z][k], 1e-12)));
    }

    fn ellipsoid(rng: &mut ChaCha8Rng, n: usize) -> Vec<[f64; 3]> {
        let axes = Vec3::from_fn(|_, _| 0.3 + 1.2 * rng.random::<f64>());
        let (q, t) = (rotation(rng), Vec3::from_fn(|_, _| 4.0 * rng.random::<f64>() - 2.0));
        let mut local = Vec::with_capacity(n);
        while local.len() < n {
            let u = Vec3::from_fn(|_, _| 2.0 * rng.random::<f64>() - 1.0);
            if (0.1..1.0).contains(&u.norm()) {
                local.push(u.normalize().component_mul(&axes));
            }
        }
        placed(&q, t, &local)
    }

    #[test]
    fn random_hulls_on_ellipsoids() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for case in 0..40 {
            let input = ellipsoid(&mut rng, 12 + case % 19);
            let (p, pose) = build(&input);
            assert!(check(&p, &pose, &input).0 <= input.len());
            let from_input = |x: Vec3| input.iter().any(|y| (Vec3::from(*y) - x).norm() <= 1e-12 * p.radius);
            assert!(p.vertices.iter().all(|v| from_input(pose.point(v))));
        }
    }

    #[test]
    fn thin_slab_is_kept() {
        // 1e-4 thick: parry's hull alone takes it for flat (a covariance eigenvalue under 1e-7), not once whitened.
        let input: Vec<[f64; 3]> = (0..8)
            .map(|k| [k & 1, k >> 1 & 1, k >> 2 & 1].map(|b| 2.0 * b as f64 - 1.0))
            .map(|[x, y, z]| [x, y, 1e-4 * z])
            .collect();
        let (p, pose) = build(&input);
        assert_eq!(check(&p, &pose, &input), (8, 6, 12));
        assert!(close(p.volume, 8e-4, 1e-12));
    }

    #[test]
    fn refusals() {
        let ok = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        let run = |p: &[[f64; 3]], a: f64| Polyhedron::from_points(p, a).map(|_| ()).unwrap_err();
        let (mut nan, mut far) = (ok.to_vec(), ok.to_vec());
        nan.push([0.5, f64::NAN, 0.0]);
        far[2][1] = 2e9;
        let q = rotation(&mut ChaCha8Rng::seed_from_u64(4));
        let plane: Vec<Vec3> = (0..10).map(|k| Vec3::new((k as f64).sin(), (k as f64 * 1.7).cos(), 0.0)).collect();
        let line: Vec<Vec3> = (0..6).map(|k| Vec3::new(1.0, 2.0, 3.0) * k as f64).collect();
        let errors = [
            (run(&ok[..3], 1e-6), SolidError::TooFewVertices(3)),
            (run(&nan, 1e-6), SolidError::NonFinite(4)),
            (run(&far, 1e-6), SolidError::OutOfRange(2)),
            (run(&placed(&q, Vec3::new(1.0, 2.0, 3.0), &plane), 1e-6), SolidError::Degenerate),
            (run(&placed(&q, Vec3::zeros(), &line), 1e-6), SolidError::Degenerate),
            (run(&[[0.3, 0.2, 0.1]; 6], 1e-6), SolidError::Degenerate),
            (run(&ok, -1e-3), SolidError::BadMergeAngle(-1e-3)),
            (run(&ok, 0.2), SolidError::BadMergeAngle(0.2)),
        ];
        for (got, expected) in errors {
            assert!(got == expected && !got.to_string().contains('\n'), "{got}");
        }
        assert!(run(&ok, f64::NAN).to_string().contains("merge_angle"));
    }

    #[test]
    fn deterministic() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let q = rotation(&mut rng);
        let cube: Vec<[f64; 3]> =
            Polyhedron::cuboid([0.5; 3]).expect("a cube").vertices.iter().map(|v| (q * v).into()).collect();
        for input in [ellipsoid(&mut rng, 30), cube] {
            let one = format!("{:?}", Polyhedron::from_points(&input, Polyhedron::MERGE_ANGLE));
            assert_eq!(one, format!("{:?}", Polyhedron::from_points(&input, Polyhedron::MERGE_ANGLE)));
        }
    }

    #[test]
    #[ignore = "timing: cargo test --release --lib geometry::polyhedron -- --ignored --nocapture"]
    fn timing() {
        let input = ellipsoid(&mut ChaCha8Rng::seed_from_u64(6), 30);
        let (runs, start) = (2000, std::time::Instant::now());
        for _ in 0..runs {
            std::hint::black_box(build(std::hint::black_box(&input)));
        }
        println!("from_points, 30 points: {:.1} µs", start.elapsed().as_secs_f64() / runs as f64 * 1e6);
    }
}
