//! Shapes placed in the world for the narrow phase, as LMGC90's POLYR contactor keeps its vertices and face
//! normals in the world frame once per step (mod_PRPRx's `coor_prediction`): world vertices, face planes
//! (outward unit normal and offset) and the edges with their two faces, which the separating-axis search
//! needs for its Gauss-map test of edge pairs. [`PolyhedronView`] borrows these from reused buffers (the
//! [`super::Detector`]'s) or from a [`PlacedPolyhedron`] that owns them (tests, single queries).
//!
//! Also here: the height of a polyhedron's surface along a line (Cyrus–Beck clipping of the line by the face
//! planes), which gives each contact point its own gap.

use crate::geometry::{Face, Polyhedron, Pose, Vec3};

/// An edge of a polyhedron: its two vertices (lower index first) and its two faces, `faces[0]` being the one
/// that runs along it from `vertices[0]` to `vertices[1]` (counter-clockwise seen from outside).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct Edge3 {
    /// Vertex indices, lower first.
    pub vertices: [u32; 2],
    /// The two faces meeting at the edge.
    pub faces: [u32; 2],
}

/// The edges of `p` with their faces, from the face loops (each edge is walked once in each direction by the
/// two faces of a closed hull), sorted by vertex pair, appended to `out`; `scratch` is reused. An edge walked
/// by a single face (an open or inconsistent hull) is kept with that face twice.
pub fn edge_topology(p: &Polyhedron, scratch: &mut Vec<(u32, u32, u32)>, out: &mut Vec<Edge3>) {
    scratch.clear();
    for (f, face) in p.faces.iter().enumerate() {
        let k = face.vertices.len();
        for i in 0..k {
            let (u, v) = (face.vertices[i], face.vertices[(i + 1) % k]);
            // The face walking u → v with u < v comes first in its pair.
            let key = if u < v { (u, v, 2 * f as u32) } else { (v, u, 2 * f as u32 + 1) };
            scratch.push(key);
        }
    }
    scratch.sort_unstable_by_key(|&(u, v, f)| (u, v, f & 1, f));
    let mut i = 0;
    while i < scratch.len() {
        let (u, v, f) = scratch[i];
        let twin = scratch.get(i + 1).filter(|t| t.0 == u && t.1 == v);
        let g = twin.map_or(f, |t| t.2);
        out.push(Edge3 { vertices: [u, v], faces: [f >> 1, g >> 1] });
        i += if twin.is_some() { 2 } else { 1 };
    }
}

/// A half-space wall placed in the world: the points `x` with `normal · (x − point) ≤ 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// A point of the boundary plane (the body's origin, m).
    pub point: Vec3,
    /// Outward unit normal (the body's `+z` in the world).
    pub normal: Vec3,
}

impl Plane {
    /// The half-space `z ≤ 0` of a body at `pose`.
    pub fn from_pose(pose: &Pose) -> Self {
        Self { point: pose.position, normal: pose.vector(&Vec3::z()) }
    }
}

/// A convex polyhedron placed in the world, borrowed from buffers.
#[derive(Debug, Clone, Copy)]
pub struct PolyhedronView<'a> {
    /// Vertices (world, m).
    pub vertices: &'a [Vec3],
    /// Outward unit normal of each face (world).
    pub normals: &'a [Vec3],
    /// Offset of each face plane, `normals[f] · x` for `x` on face `f` (m, world).
    pub offsets: &'a [f64],
    /// The faces' vertex loops (the shape's own faces: indices into `vertices`).
    pub faces: &'a [Face],
    /// Edges with their faces (see [`edge_topology`]).
    pub edges: &'a [Edge3],
    /// For each edge, `normals[faces[1]] × normals[faces[0]]`: along the edge, of length the sine of the
    /// angle between the faces' normals (the arc of the edge on the Gauss map).
    pub arcs: &'a [Vec3],
    /// Centroid (world, m).
    pub centre: Vec3,
    /// Radius of the sphere about the centroid holding every vertex (m).
    pub radius: f64,
    /// Radius of the sphere about the centroid inside every face plane (m): the smallest face offset.
    pub inradius: f64,
}

impl PolyhedronView<'_> {
    /// Smallest and largest of `n · (v − origin)` over the vertices.
    #[inline]
    pub fn extent(&self, n: &Vec3, origin: &Vec3) -> (f64, f64) {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for v in self.vertices {
            let h = n.dot(&(v - origin));
            lo = lo.min(h);
            hi = hi.max(h);
        }
        (lo, hi)
    }

    /// Where the line `q + t n` (`n` unit) enters the polyhedron: the largest `t` over the faces facing `−n`
    /// (Cyrus–Beck clipping). Faces within 1e-9 of parallel to `n` are left out, so that a point on a
    /// silhouette made by such a face does not take a height from rounding.
    pub fn entry(&self, q: &Vec3, n: &Vec3) -> f64 {
        let mut t = f64::NEG_INFINITY;
        for (m, d) in self.normals.iter().zip(self.offsets) {
            let c = m.dot(n);
            if c < -1e-9 {
                t = t.max((d - m.dot(q)) / c);
            }
        }
        t
    }

    /// Where the line `q + t n` leaves the polyhedron: the smallest `t` over the faces facing `+n`.
    pub fn exit(&self, q: &Vec3, n: &Vec3) -> f64 {
        let mut t = f64::INFINITY;
        for (m, d) in self.normals.iter().zip(self.offsets) {
            let c = m.dot(n);
            if c > 1e-9 {
                t = t.min((d - m.dot(q)) / c);
            }
        }
        t
    }
}

/// What [`place`] measures of a polyhedron.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Bounds {
    /// World bounding box of the vertices (m).
    pub lo: Vec3,
    pub hi: Vec3,
    /// Largest distance of a vertex from the centroid, and smallest face offset (m), from the body-frame data
    /// (not from the shape's own `radius` and `inradius` fields).
    pub radius: f64,
    pub inradius: f64,
}

/// Appends the world placement of `p` at `pose` to the buffers (vertices, face normals, offsets, edges and
/// their Gauss-map arcs) and returns its [`Bounds`].
#[allow(clippy::too_many_arguments)]
pub(crate) fn place(
    p: &Polyhedron,
    pose: &Pose,
    scratch: &mut Vec<(u32, u32, u32)>,
    vertices: &mut Vec<Vec3>,
    normals: &mut Vec<Vec3>,
    offsets: &mut Vec<f64>,
    edges: &mut Vec<Edge3>,
    arcs: &mut Vec<Vec3>,
) -> Bounds {
    let rot = pose.rotation.to_rotation_matrix();
    let (mut lo, mut hi) = (pose.position, pose.position);
    let mut radius: f64 = 0.0;
    for v in &p.vertices {
        radius = radius.max(v.norm());
        let w = pose.position + rot * v;
        lo = lo.inf(&w);
        hi = hi.sup(&w);
        vertices.push(w);
    }
    let n0 = normals.len();
    let mut inradius = f64::INFINITY;
    for f in &p.faces {
        inradius = inradius.min(f.offset);
        let n = rot * f.normal;
        normals.push(n);
        offsets.push(f.offset + n.dot(&pose.position));
    }
    let e0 = edges.len();
    edge_topology(p, scratch, edges);
    for e in &edges[e0..] {
        let (f0, f1) = (n0 + e.faces[0] as usize, n0 + e.faces[1] as usize);
        arcs.push(normals[f1].cross(&normals[f0]));
    }
    Bounds { lo, hi, radius, inradius }
}

/// A polyhedron placed in the world with its own buffers.
#[derive(Debug, Clone, Default)]
pub struct PlacedPolyhedron {
    vertices: Vec<Vec3>,
    normals: Vec<Vec3>,
    offsets: Vec<f64>,
    faces: Vec<Face>,
    edges: Vec<Edge3>,
    arcs: Vec<Vec3>,
    centre: Vec3,
    radius: f64,
    inradius: f64,
}

impl PlacedPolyhedron {
    /// `p` placed at `pose`.
    pub fn new(p: &Polyhedron, pose: &Pose) -> Self {
        let mut s = Self { centre: pose.position, faces: p.faces.clone(), ..Self::default() };
        let (v, n, o, e, a) = (&mut s.vertices, &mut s.normals, &mut s.offsets, &mut s.edges, &mut s.arcs);
        let bounds = place(p, pose, &mut Vec::new(), v, n, o, e, a);
        (s.radius, s.inradius) = (bounds.radius, bounds.inradius);
        s
    }

    /// The view the narrow phase reads.
    pub fn view(&self) -> PolyhedronView<'_> {
        PolyhedronView {
            vertices: &self.vertices,
            normals: &self.normals,
            offsets: &self.offsets,
            faces: &self.faces,
            edges: &self.edges,
            arcs: &self.arcs,
            centre: self.centre,
            radius: self.radius,
            inradius: self.inradius,
        }
    }
}
