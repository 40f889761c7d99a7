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
    let (v0, f0, e0) = (vertices.len(), normals.len(), edges.len());
    edge_topology(p, scratch, edges);
    vertices.resize(v0 + p.vertices.len(), Vec3::zeros());
    normals.resize(f0 + p.faces.len(), Vec3::zeros());
    offsets.resize(f0 + p.faces.len(), 0.0);
    arcs.resize(edges.len(), Vec3::zeros());
    place_into(p, pose, &edges[e0..], &mut vertices[v0..], &mut normals[f0..], &mut offsets[f0..], &mut arcs[e0..])
}

/// The world placement of `p` at `pose` written into `vertices` (as many as the shape's), `normals` and
/// `offsets` (one per face) and `arcs` (one per edge of `edges`, the shape's [`edge_topology`]).
pub(crate) fn place_into(
    p: &Polyhedron,
    pose: &Pose,
    edges: &[Edge3],
    vertices: &mut [Vec3],
    normals: &mut [Vec3],
    offsets: &mut [f64],
    arcs: &mut [Vec3],
) -> Bounds {
    let rot = pose.rotation.to_rotation_matrix();
    let (mut lo, mut hi) = (pose.position, pose.position);
    // The largest squared norm, then its root: the root is monotonic and correctly rounded, so this is the
    // largest norm to the bit.
    let mut radius2: f64 = 0.0;
    for (v, w) in p.vertices.iter().zip(vertices.iter_mut()) {
        radius2 = radius2.max(v.norm_squared());
        *w = pose.position + rot * v;
        lo = lo.inf(w);
        hi = hi.sup(w);
    }
    let mut inradius = f64::INFINITY;
    for ((f, n), o) in p.faces.iter().zip(normals.iter_mut()).zip(offsets.iter_mut()) {
        inradius = inradius.min(f.offset);
        *n = rot * f.normal;
        *o = f.offset + n.dot(&pose.position);
    }
    for (e, arc) in edges.iter().zip(arcs.iter_mut()) {
        *arc = normals[e.faces[1] as usize].cross(&normals[e.faces[0] as usize]);
    }
    Bounds { lo, hi, radius: radius2.sqrt(), inradius }
}

/// The edge topology ([`edge_topology`]) of each distinct set of face loops met, made once and kept: every
/// polyhedron of a detection looks its loops up here instead of sorting its edges again (cuboids all share
/// one entry). An entry is found by a hash of the loops and always checked against the loops themselves, so
/// a shape dropped and another made at the same address cannot take a stale entry.
#[derive(Debug, Clone, Default)]
pub(crate) struct Topologies {
    /// The loops of every entry, flattened: for each face its vertex count, then its vertices.
    loops: Vec<u32>,
    entries: Vec<Topology>,
    /// Edges of every entry.
    pub(crate) edges: Vec<Edge3>,
    /// First entry of each hash; later ones are chained by [`Topology::next`].
    index: std::collections::HashMap<u64, u32>,
    scratch: Vec<(u32, u32, u32)>,
}

#[derive(Debug, Clone, Copy)]
struct Topology {
    loops: (u32, u32),
    edges: (u32, u32),
    next: u32,
}

/// The most entries kept; beyond, the cache starts again (shapes that keep changing).
const MAX_TOPOLOGIES: usize = 1 << 16;

impl Topologies {
    /// The entry of `p`'s face loops, trying `last` (an entry index from an earlier call) first.
    pub(crate) fn entry(&mut self, p: &Polyhedron, last: u32) -> u32 {
        if (last as usize) < self.entries.len() && self.matches(last, p) {
            return last;
        }
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |x: u32| h = (h ^ u64::from(x)).wrapping_mul(0x0100_0000_01b3);
        for f in &p.faces {
            eat(f.vertices.len() as u32);
            f.vertices.iter().for_each(|&v| eat(v));
        }
        let mut k = self.index.get(&h).copied().unwrap_or(u32::MAX);
        while k != u32::MAX {
            if self.matches(k, p) {
                return k;
            }
            k = self.entries[k as usize].next;
        }
        if self.entries.len() >= MAX_TOPOLOGIES {
            self.loops.clear();
            self.entries.clear();
            self.edges.clear();
            self.index.clear();
        }
        let (l0, e0) = (self.loops.len() as u32, self.edges.len() as u32);
        for f in &p.faces {
            self.loops.push(f.vertices.len() as u32);
            self.loops.extend_from_slice(&f.vertices);
        }
        edge_topology(p, &mut self.scratch, &mut self.edges);
        let k = self.entries.len() as u32;
        let next = self.index.insert(h, k).unwrap_or(u32::MAX);
        self.entries.push(Topology {
            loops: (l0, self.loops.len() as u32),
            edges: (e0, self.edges.len() as u32),
            next,
        });
        k
    }

    /// Number of entries.
    pub(crate) fn len(&self) -> usize {
        self.entries.len()
    }

    /// The range of entry `k`'s edges in [`Self::edges`].
    pub(crate) fn edges_of(&self, k: u32) -> (u32, u32) {
        self.entries[k as usize].edges
    }

    fn matches(&self, k: u32, p: &Polyhedron) -> bool {
        let (l0, l1) = self.entries[k as usize].loops;
        let loops = &self.loops[l0 as usize..l1 as usize];
        let mut at = 0;
        for f in &p.faces {
            let n = f.vertices.len();
            if loops.len() < at + 1 + n || loops[at] as usize != n {
                return false;
            }
            // Element by element: the loops are short, a call to `memcmp` costs more.
            if loops[at + 1..at + 1 + n].iter().zip(&f.vertices).any(|(a, b)| a != b) {
                return false;
            }
            at += 1 + n;
        }
        at == loops.len()
    }
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
