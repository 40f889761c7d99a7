//! The common plane of two convex polyhedra: its normal and the separation of the two along it.
//!
//! LMGC90's mod_PRPRx first runs a *shadow overlap* along the last known separating direction (its
//! `compute_shadow_overlap`: project both vertex sets on the direction; apart by more than the alert distance
//! means no contact, done cheaply), then searches the common plane iteratively (Cundall's method,
//! `compute_cundall_common_plane`: perturb the normal, keep the perturbation that increases the gap, halve
//! the angle). Here the first step is the same, with the previous step's normal; the search is the
//! separating-axis test instead, exact for convex polyhedra: the separation along an axis is
//! `min over a of n·x − max over b of n·x`, and its largest value over the face normals of both shapes and
//! the edge × edge directions is the signed distance when the two overlap (the smallest penetration) and
//! when the closest features are a face and anything or two crossing edges. Edge pairs are kept only when
//! their arcs on the Gauss map cross (they make a face of the Minkowski difference, Gregorius 2013), which
//! makes the separation along their direction a difference of two edge points and skips the other pairs
//! cheaply. A face normal is preferred to an edge direction, and the antagonist's face to the candidate's,
//! unless the other is better by more than [`FACE_PREFERENCE`] of the smaller radius, so face–face and
//! edge–face contacts get the face normal exactly.
//!
//! The search is pruned without projecting vertices: an axis cannot separate the two by more than its
//! component along the line of centres minus the two inradii.
//!
//! When the two are apart and the best axis may not give the distance (the closest features are a vertex
//! and a vertex or an edge, or two parallel edges: [`is_exact`] says whether the witness of the axis lies
//! over the face, or the edges' closest points on both edges), GJK (parry3d, [`refine`]) gives the exact
//! closest points, and their direction is the normal.

use super::placed::PolyhedronView;
use crate::geometry::Vec3;
use parry3d_f64::math::{Pose as PPose, Vector as PVec};
use parry3d_f64::query::gjk::{self, CsoPoint, GJKResult, VoronoiSimplex};
use parry3d_f64::shape::SupportMap;

/// Relative margin (of the smaller radius) by which an edge × edge axis, or a face of the candidate, must beat
/// a face of the antagonist to be taken as the normal.
pub const FACE_PREFERENCE: f64 = 1e-6;

/// Relative margin (of the smaller radius) by which the GJK distance must exceed the best axis's separation
/// for its direction to replace it.
const GJK_MARGIN: f64 = 1e-9;

/// Which axis gave the normal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AxisKind {
    /// The normal of this face of the antagonist.
    FaceB(u32),
    /// Minus the normal of this face of the candidate.
    FaceA(u32),
    /// The cross product of this edge of the candidate and this edge of the antagonist.
    Edges(u32, u32),
    /// The direction of the closest points found by GJK.
    Closest,
}

/// The common plane of a pair within the alert distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CommonPlane {
    /// Unit normal, from the antagonist towards the candidate.
    pub normal: Vec3,
    /// Separation along the normal, `min a·n − max b·n` (m): the signed distance when exact (see the module
    /// doc); at most the alert distance.
    pub separation: f64,
    /// Which axis it is.
    pub kind: AxisKind,
    /// For an edge pair or GJK, a point of the candidate and a point of the antagonist realising the
    /// separation (world, m).
    pub witness: Option<(Vec3, Vec3)>,
}

/// What the search found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Search {
    /// Apart by more than the alert distance along this unit axis (from the antagonist to the candidate): no
    /// contact. The axis is worth trying first at the next step.
    Apart(Vec3),
    /// Within the alert distance.
    Plane(CommonPlane),
}

/// `min over a of n·x − max over b of n·x` (m).
#[inline]
pub fn separation(a: &PolyhedronView, b: &PolyhedronView, n: &Vec3) -> f64 {
    let o = 0.5 * (a.centre + b.centre);
    a.extent(n, &o).0 - b.extent(n, &o).1
}

/// The separating-axis common plane of candidate `a` and antagonist `b`, or an axis along which they are
/// apart by more than `alert` (m). `hint` (unit, from `b` to `a`) is tried first: the previous step's normal.
///
/// An axis `n` cannot separate the two by more than `n·(c_a − c_b) − r_a − r_b` (centroids, inradii:
/// each shape holds the ball of its inradius about its centroid), so a face whose bound is below the best
/// separation so far, and an edge whose Gauss-map arc holds no direction with a bound above it, are skipped
/// without projecting any vertex. When the result is apart (a positive separation), it is exact only if the
/// closest features are a face and anything or two crossing edges: see [`refine`].
pub fn common_plane(a: &PolyhedronView, b: &PolyhedronView, alert: f64, hint: Option<&Vec3>) -> Search {
    common_plane_in(&mut Dots::default(), a, b, alert, hint)
}

/// The buffers of [`common_plane`], kept from pair to pair (only the entries a pair writes are read): the
/// dot products of the two shapes' face normals with the line of centres that it reads more than once, in
/// place up to [`FACES`] faces (no small allocation a thread writes at every pair next to another thread's),
/// beyond in vectors; and the antagonist's edges that can make an edge pair.
#[derive(Debug, Clone)]
pub struct Dots {
    inline: [[f64; FACES]; 4],
    heap: [Vec<f64>; 4],
    viable: Vec<EdgeB>,
}

impl Default for Dots {
    fn default() -> Self {
        Dots { inline: [[0.0; FACES]; 4], heap: Default::default(), viable: Vec::new() }
    }
}

/// An edge of the antagonist that can make an edge pair, with what the pair loop reads of it, in one place:
/// its index, its faces' normals, its arc and its first vertex.
#[derive(Debug, Clone, Copy)]
struct EdgeB {
    j: u32,
    nb0: Vec3,
    nb1: Vec3,
    arc: Vec3,
    q: Vec3,
}

/// Faces whose dot products [`Dots`] keeps in place.
pub const FACES: usize = 64;

/// `n · u` of each normal, in `inline` if they fit, else in `heap`.
#[inline]
fn dots<'a>(normals: &[Vec3], u: &Vec3, inline: &'a mut [f64; FACES], heap: &'a mut Vec<f64>) -> &'a [f64] {
    let out: &mut [f64] = if normals.len() <= FACES {
        &mut inline[..normals.len()]
    } else {
        heap.resize(normals.len(), 0.0);
        heap
    };
    for (o, n) in out.iter_mut().zip(normals) {
        *o = n.dot(u);
    }
    out
}

/// [`common_plane`] with the buffers `dots`.
pub(crate) fn common_plane_in(
    dots_in: &mut Dots,
    a: &PolyhedronView,
    b: &PolyhedronView,
    alert: f64,
    hint: Option<&Vec3>,
) -> Search {
    let d = a.centre - b.centre;
    let dist = d.norm();
    let centres = if dist > 0.0 { d / dist } else { Vec3::z() };
    if dist - a.radius - b.radius > alert {
        return Search::Apart(centres);
    }
    if let Some(n) = hint {
        if apart_along(a, b, n, alert) {
            return Search::Apart(*n);
        }
    }
    let tol = FACE_PREFERENCE * a.radius.min(b.radius);
    let inner = a.inradius + b.inradius;
    // `n · d` of every face normal of each shape, computed once.
    let Dots { inline: [da, db, ca, cb], heap: [ha, hb, hca, hcb], viable } = dots_in;
    let db = dots(b.normals, &d, db, hb);
    let da = dots(a.normals, &d, da, ha);
    let dot_b = |f: usize| db[f];
    let dot_a = |f: usize| da[f];
    // Faces of the antagonist: its vertices are all below the plane, the candidate's lowest is `s` above.
    // The face facing the candidate most is tried first, so that its separation bounds out the others.
    let mut best = (f64::NEG_INFINITY, Vec3::z(), AxisKind::FaceB(0));
    let first_b = most(b.normals.len(), dot_b);
    for f in std::iter::once(first_b).chain((0..b.normals.len()).filter(|&f| f != first_b)) {
        if dot_b(f) - inner <= best.0 {
            continue;
        }
        let n = b.normals[f];
        let s = lowest(a.vertices, &n) - b.offsets[f];
        if s > alert {
            return Search::Apart(n);
        }
        // Ties between faces go to the lower index, whichever was tried first.
        if s > best.0 || (s == best.0 && matches!(best.2, AxisKind::FaceB(g) if (f as u32) < g)) {
            best = (s, n, AxisKind::FaceB(f as u32));
        }
    }
    // `−(m · d)` is `m · (−d)` but for the sign of a zero, which no comparison sees.
    let first_a = most(a.normals.len(), |f| -dot_a(f));
    let mut best_a = (f64::NEG_INFINITY, Vec3::z(), AxisKind::FaceA(0));
    for f in std::iter::once(first_a).chain((0..a.normals.len()).filter(|&f| f != first_a)) {
        if -dot_a(f) - inner <= best.0.max(best_a.0 - tol) + tol {
            continue;
        }
        let m = a.normals[f];
        let s = lowest(b.vertices, &m) - a.offsets[f];
        if s > alert {
            return Search::Apart(-m);
        }
        if s > best_a.0 || (s == best_a.0 && matches!(best_a.2, AxisKind::FaceA(g) if (f as u32) < g)) {
            best_a = (s, -m, AxisKind::FaceA(f as u32));
        }
    }
    if best_a.0 > best.0 + tol {
        best = best_a;
    }
    // An edge pair's axis m (outward of A, towards B) must reach `need` along the centres' line to beat the
    // best face by the preference margin.
    let need = (best.0 + tol + inner) / dist.max(f64::MIN_POSITIVE);
    let u = -centres;
    // `n · u` of the faces: for A's normals `−(n · centres)`, for B's negated normals `n · centres`
    // (exactly: `(−x)(−y) = xy`), up to the sign of a zero.
    let cb = dots(b.normals, &centres, cb, hcb);
    let ca = dots(a.normals, &centres, ca, hca);
    let up_b = |f: u32| cb[f as usize];
    let up_a = |f: u32| -ca[f as usize];
    let mut edge = (f64::NEG_INFINITY, Vec3::z(), (0, 0));
    // The antagonist's edges that can (all of them beyond 128 edges), listed on first need.
    let mut listed = false;
    for (i, (ea, arc_a)) in a.edges.iter().zip(a.arcs).enumerate() {
        let [fa0, fa1] = ea.faces;
        let (na0, na1) = (&a.normals[fa0 as usize], &a.normals[fa1 as usize]);
        if !arc_reaches(up_a(fa0), up_a(fa1), || (*na0, *na1), arc_a, &u, need) {
            continue;
        }
        if !listed {
            listed = true;
            viable.clear();
            let all = b.edges.len() > 128;
            for (j, (eb, arc_b)) in b.edges.iter().zip(b.arcs).enumerate() {
                let [fb0, fb1] = eb.faces;
                let ends = || (-b.normals[fb0 as usize], -b.normals[fb1 as usize]);
                if all || arc_reaches(up_b(fb0), up_b(fb1), ends, arc_b, &u, need) {
                    viable.push(EdgeB {
                        j: j as u32,
                        nb0: b.normals[fb0 as usize],
                        nb1: b.normals[fb1 as usize],
                        arc: *arc_b,
                        q: b.vertices[eb.vertices[0] as usize],
                    });
                }
            }
        }
        let pa = a.vertices[ea.vertices[0] as usize];
        for e in viable.iter() {
            // Arcs (na0, na1) of A and (−nb0, −nb1) of B on the Gauss map of A − B.
            let (nb0, nb1, arc_b) = (&e.nb0, &e.nb1, &e.arc);
            let cba = -nb0.dot(arc_a);
            let dba = -nb1.dot(arc_a);
            let adc = na0.dot(arc_b);
            let bdc = na1.dot(arc_b);
            if !(cba * dba < 0.0 && adc * bdc < 0.0 && cba * bdc > 0.0) {
                continue;
            }
            let axis = arc_a.cross(arc_b);
            let len = axis.norm();
            if len <= 1e-9 * arc_a.norm() * arc_b.norm() {
                continue; // parallel edges: no face of the Minkowski difference
            }
            // Outward of A along the axis: A's edge is A's support there; the normal points the other way.
            let mut m = axis / len;
            if m.dot(&(pa - a.centre)) < 0.0 {
                m = -m;
            }
            let s = m.dot(&(e.q - pa));
            if s > alert {
                return Search::Apart(-m);
            }
            if s > edge.0 {
                edge = (s, -m, (i as u32, e.j));
            }
        }
    }
    if edge.0 > best.0 + tol {
        let (i, j) = edge.2;
        let (wa, wb, _) = line_closest(a, b, i as usize, j as usize);
        return Search::Plane(CommonPlane {
            normal: edge.1,
            separation: edge.0,
            kind: AxisKind::Edges(i, j),
            witness: Some((wa, wb)),
        });
    }
    Search::Plane(CommonPlane { normal: best.1, separation: best.0, kind: best.2, witness: None })
}

/// The index of the largest of `value(0..len)` (the first of equals; 0 when none is above −∞).
#[inline]
fn most(len: usize, value: impl Fn(usize) -> f64) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for f in 0..len {
        let c = value(f);
        if c > best.1 {
            best = (f, c);
        }
    }
    best.0
}

/// The smallest `n · v` over `vertices` (`+∞` when none).
#[inline]
fn lowest(vertices: &[Vec3], n: &Vec3) -> f64 {
    vertices.iter().map(|v| n.dot(v)).fold(f64::INFINITY, f64::min)
}

/// Whether [`separation`] along `n` exceeds `alert`, stopping at the first vertex of `b` that shows it does
/// not: `fl(lo − h)` only decreases as `h` grows, so it exceeds `alert` at the highest `h` exactly when it
/// does at every `h` (a NaN, which the highest leaves out, is left out here too).
#[inline]
fn apart_along(a: &PolyhedronView, b: &PolyhedronView, n: &Vec3, alert: f64) -> bool {
    let o = 0.5 * (a.centre + b.centre);
    let lo = a.extent(n, &o).0;
    b.vertices.iter().all(|v| {
        let h = n.dot(&(v - o));
        lo - h > alert || h.is_nan()
    })
}

/// Whether some `m` on the arc of unit directions from `n0` to `n1` (shorter than a half turn) on the unit
/// sphere has `m · u > need`; `arc = n1 × n0`, `e0 = n0 · u` and `e1 = n1 · u` (the ends are only asked for
/// when these do not settle it).
#[inline(always)]
fn arc_reaches(e0: f64, e1: f64, ends: impl FnOnce() -> (Vec3, Vec3), arc: &Vec3, u: &Vec3, need: f64) -> bool {
    if e0 > need || e1 > need {
        return true;
    }
    if need < 0.0 {
        return true; // a bound too weak to skip anything
    }
    // Inside the arc m is a positive combination of n0 and n1: nowhere above 0 if neither end is.
    if e0 <= 0.0 && e1 <= 0.0 {
        return false;
    }
    // Over the whole great circle, m · u is at most the length of u projected on its plane.
    let (w2, wu) = (arc.norm_squared(), arc.dot(u));
    if w2 <= 0.0 || u.norm_squared() - wu * wu / w2 <= need * need {
        return false;
    }
    // That maximum is reached on the arc when the projection lies between n0 and n1 (turning about
    // n0 × n1 = −arc).
    let (n0, n1) = ends();
    let p = u - arc * (wu / w2);
    n0.cross(&p).dot(arc) <= 0.0 && p.cross(&n1).dot(arc) <= 0.0
}

/// The closest points of the lines of edge `i` of `a` and edge `j` of `b` (not parallel), clamped to the segments), and whether they lie on both segments (within 1e-9 of their lengths).
fn line_closest(a: &PolyhedronView, b: &PolyhedronView, i: usize, j: usize) -> (Vec3, Vec3, bool) {
    let (ea, eb) = (a.edges[i].vertices, b.edges[j].vertices);
    let (p, q) = (a.vertices[ea[0] as usize], b.vertices[eb[0] as usize]);
    let (u, v) = (a.vertices[ea[1] as usize] - p, b.vertices[eb[1] as usize] - q);
    let w = p - q;
    let (uu, uv, vv, uw, vw) = (u.dot(&u), u.dot(&v), v.dot(&v), u.dot(&w), v.dot(&w));
    let den = uu * vv - uv * uv;
    let (s, t) = ((uv * vw - vv * uw) / den, (uu * vw - uv * uw) / den);
    let on = |x: f64| (-1e-9..=1.0 + 1e-9).contains(&x);
    (p + s.clamp(0.0, 1.0) * u, q + t.clamp(0.0, 1.0) * v, on(s) && on(t))
}

/// Whether the (positive) separation of `plane` is the distance of `a` and `b`: for a face axis, the other
/// shape's nearest vertex lies over the face; for an edge pair, the closest points of the two lines lie
/// on both edges. Otherwise the closest features may be a vertex and a vertex or an edge, or two parallel
/// edges, and [`refine`] gives the distance.
pub fn is_exact(a: &PolyhedronView, b: &PolyhedronView, plane: &CommonPlane) -> bool {
    // Whether `x` lies over face `f` of `p` (normal `n`), within 1e-9 of the smaller radius.
    let over = |p: &PolyhedronView, f: usize, x: &Vec3, n: &Vec3| {
        let tol = 1e-9 * a.radius.min(b.radius);
        let loop_ = &p.faces[f].vertices;
        (0..loop_.len()).all(|k| {
            let (u, v) = (p.vertices[loop_[k] as usize], p.vertices[loop_[(k + 1) % loop_.len()] as usize]);
            let e = v - u;
            e.cross(&(x - u)).dot(n) >= -tol * e.norm()
        })
    };
    let lowest = |p: &PolyhedronView, n: &Vec3| {
        p.vertices.iter().fold((f64::INFINITY, Vec3::zeros()), |m, v| if n.dot(v) < m.0 { (n.dot(v), *v) } else { m }).1
    };
    match plane.kind {
        AxisKind::FaceB(f) => {
            let n = b.normals[f as usize];
            over(b, f as usize, &lowest(a, &n), &n)
        }
        AxisKind::FaceA(f) => {
            let m = a.normals[f as usize];
            over(a, f as usize, &lowest(b, &m), &m)
        }
        AxisKind::Edges(i, j) => line_closest(a, b, i as usize, j as usize).2,
        AxisKind::Closest => true,
    }
}

/// A vertex set as a parry support map, shifted by `origin` to keep its coordinates small.
struct Cloud<'a> {
    points: &'a [Vec3],
    origin: Vec3,
}

impl SupportMap for Cloud<'_> {
    fn local_support_point(&self, dir: PVec) -> PVec {
        let d = Vec3::new(dir.x, dir.y, dir.z);
        let mut best = (0, f64::NEG_INFINITY);
        for (k, p) in self.points.iter().enumerate() {
            let s = p.dot(&d);
            if s > best.1 {
                best = (k, s);
            }
        }
        let p = self.points[best.0] - self.origin;
        PVec::new(p.x, p.y, p.z)
    }
}

/// For a pair apart along the best axis when that separation may not be the distance ([`is_exact`]): the
/// exact distance by GJK;
/// its direction replaces the axis when it separates the two by more, and a distance beyond `alert` means no
/// contact.
pub fn refine(a: &PolyhedronView, b: &PolyhedronView, alert: f64, plane: CommonPlane) -> Search {
    let origin = 0.5 * (a.centre + b.centre);
    let (ga, gb) = (Cloud { points: a.vertices, origin }, Cloud { points: b.vertices, origin });
    let n = plane.normal;
    let mut simplex = VoronoiSimplex::new();
    let id = PPose::IDENTITY;
    simplex.reset(CsoPoint::from_shapes(&id, &ga, &gb, PVec::new(-n.x, -n.y, -n.z)));
    match gjk::closest_points(&id, &ga, &gb, alert.max(0.0), true, &mut simplex) {
        GJKResult::ClosestPoints(pa, pb, _) => {
            let (pa, pb) = (Vec3::new(pa.x, pa.y, pa.z) + origin, Vec3::new(pb.x, pb.y, pb.z) + origin);
            let d = pa - pb;
            let dist = d.norm();
            if dist > alert {
                return Search::Apart(d / dist);
            }
            if dist > plane.separation + GJK_MARGIN * a.radius.min(b.radius) {
                return Search::Plane(CommonPlane {
                    normal: d / dist,
                    separation: dist,
                    kind: AxisKind::Closest,
                    witness: Some((pa, pb)),
                });
            }
            Search::Plane(plane)
        }
        // `dir` points from the candidate to the antagonist; the separation along its opposite exceeds `alert`.
        GJKResult::NoIntersection(dir) => Search::Apart(-Vec3::new(dir.x, dir.y, dir.z)),
        _ => Search::Plane(plane),
    }
}
