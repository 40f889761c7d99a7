//! The narrow phase: one function per pair of shapes, each pure, on shapes placed in the world, returning
//! the contact [`Manifold`] when the gap is at most the alert distance.
//!
//! - polyhedron–polyhedron after LMGC90 mod_PRPRx's common-plane detection: the common plane
//!   ([`super::axis`]), then the contact points on it ([`super::polygon`]);
//! - polyhedron–half-space after mod_PRPLx: the vertices within the alert distance of the wall, at most four
//!   (the deepest, then the extreme ones, as for two polyhedra; LMGC90 keeps the four deepest);
//! - sphere–polyhedron after mod_SPPRx: the closest point of the polyhedron to the centre, exactly (face,
//!   edge or vertex region), or the face of least penetration when the centre is inside;
//! - sphere–sphere and sphere–half-space after mod_SPSPx and mod_SPPLx: closed forms.
//!
//! Every point lies half-way between the two surfaces along the normal.

use super::axis::{common_plane_in, is_exact, refine, AxisKind, CommonPlane, Dots, Search};
use super::placed::{Plane, PolyhedronView};
use super::polygon::{self, contact_points_in, reduce_points, Frame, Label, Labelled, CAP};
use super::{FaceGaps, Manifold, COMMON_PLANE_BAND};
use crate::geometry::{Vec2, Vec3};

/// Length tolerance of the polygon work, relative to the smaller radius of the pair.
pub const EPS: f64 = 1e-9;

/// The buffers of the narrow phase of two polyhedra, reused from pair to pair.
#[derive(Debug, Clone, Default)]
pub struct Scratch {
    dots: Dots,
    polygon: polygon::Scratch,
}

/// Contact of candidate polyhedron `a` and antagonist polyhedron `b` with a gap at most `alert` (m); `hint`
/// is the previous step's normal of the pair, if any (a cheap first test, see [`super::axis`]).
pub fn polyhedron_polyhedron(
    a: &PolyhedronView,
    b: &PolyhedronView,
    alert: f64,
    hint: Option<&Vec3>,
) -> Option<Manifold> {
    polyhedron_polyhedron_with(a, b, alert, hint, FaceGaps::Exact)
}

/// [`polyhedron_polyhedron`] with the face–face gap rule `face_gaps`.
pub fn polyhedron_polyhedron_with(
    a: &PolyhedronView,
    b: &PolyhedronView,
    alert: f64,
    hint: Option<&Vec3>,
    face_gaps: FaceGaps,
) -> Option<Manifold> {
    let mut m = Manifold::new(Vec3::z());
    polyhedron_polyhedron_into(a, b, alert, hint, face_gaps, &mut Scratch::default(), &mut m).0.then_some(m)
}

/// [`polyhedron_polyhedron`] into `m` (meaningful when the first value returned is true: a contact), with
/// the axis to remember for the next step: the normal when in contact, else the axis found to separate the
/// two; `face_gaps` is the face–face gap rule; `scratch` holds the polygon work's buffers.
pub(crate) fn polyhedron_polyhedron_into(
    a: &PolyhedronView,
    b: &PolyhedronView,
    alert: f64,
    hint: Option<&Vec3>,
    face_gaps: FaceGaps,
    scratch: &mut Scratch,
    m: &mut Manifold,
) -> (bool, Vec3) {
    let mut plane = match common_plane_in(&mut scratch.dots, a, b, alert, hint) {
        Search::Apart(axis) => return (false, axis),
        Search::Plane(p) => p,
    };
    // Apart along an axis that may not be the closest direction: GJK first.
    if plane.separation > 0.0 && !is_exact(a, b, &plane) {
        match refine(a, b, alert, plane) {
            Search::Apart(axis) => return (false, axis),
            Search::Plane(p) => plane = p,
        }
    }
    let met = on_plane(a, b, alert, &plane, face_gaps, &mut scratch.polygon, m);
    if !met && plane.separation > 0.0 && plane.kind != AxisKind::Closest {
        // The projections missed each other although the axis looked exact: ask GJK.
        match refine(a, b, alert, plane) {
            Search::Apart(axis) => return (false, axis),
            Search::Plane(p) if p.kind == AxisKind::Closest => {
                on_plane(a, b, alert, &p, face_gaps, &mut scratch.polygon, m);
                return (m.len > 0, p.normal);
            }
            Search::Plane(_) => {}
        }
    }
    (m.len > 0, plane.normal)
}

/// The contact points of `a` and `b` on the common plane `plane`, into `m`, under the face–face gap rule
/// `face_gaps`, and whether the features' projections met.
fn on_plane(
    a: &PolyhedronView,
    b: &PolyhedronView,
    alert: f64,
    plane: &CommonPlane,
    face_gaps: FaceGaps,
    scratch: &mut polygon::Scratch,
    m: &mut Manifold,
) -> bool {
    let n = plane.normal;
    *m = Manifold::new(n);
    let eps = EPS * a.radius.min(b.radius);
    let frame = Frame { o: 0.5 * (a.centre + b.centre), t1: m.t1, t2: m.t2, n, eps };
    if face_gaps == FaceGaps::CommonPlane {
        if let Some(band) = face_face_band(a, b, &n, plane.separation, eps) {
            let met =
                contact_points_in(scratch, a, b, &frame, band, f64::INFINITY, plane.witness, |x, gap| m.push(x, gap));
            // The points are kept whatever their gap; the contact is, as the exact rule's, only within the alert.
            let g = m.points().iter().map(|p| p.gap).fold(f64::INFINITY, f64::min);
            if g > alert {
                m.len = 0;
            }
            for p in &mut m.points[..m.len] {
                p.gap = g;
            }
            return met;
        }
    }
    // Every vertex that could have a gap within the alert distance against a flat opposite surface.
    let band = (alert - plane.separation).max(0.0) + eps;
    contact_points_in(scratch, a, b, &frame, band, alert, plane.witness, |x, gap| m.push(x, gap))
}

/// [`FaceGaps::CommonPlane`]'s test: the band (m) when both `a` (on the `+n` side) and `b` have at least three
/// vertices within it of their vertex nearest the plane, else `None`; `separation` is the plane's (m).
fn face_face_band(a: &PolyhedronView, b: &PolyhedronView, n: &Vec3, separation: f64, eps: f64) -> Option<f64> {
    let (lo_a, _) = a.extent(n, &a.centre);
    let (_, hi_b) = b.extent(n, &b.centre);
    let reference = (-lo_a).min(hi_b).max(0.0);
    let band = COMMON_PLANE_BAND * reference + 0.5 * (-separation).max(0.0) + eps;
    let near = |v: &PolyhedronView, extreme: f64, sign: f64| {
        v.vertices.iter().filter(|x| sign * (n.dot(&(*x - v.centre)) - extreme) <= band).take(3).count() == 3
    };
    (near(a, lo_a, 1.0) && near(b, hi_b, -1.0)).then_some(band)
}

/// A vertex near a wall.
#[derive(Debug, Clone, Copy)]
struct WallPoint {
    id: u32,
    p: Vec2,
    h: f64,
    x: Vec3,
}

impl Labelled for WallPoint {
    fn label(&self) -> Label {
        (0, self.id, 0, 0, 0)
    }
}

/// Contact of polyhedron `a` (candidate) with the half-space `wall` (antagonist): the vertices of `a` within
/// `alert` (m) of the wall's plane, at most four, in vertex order.
pub fn polyhedron_half_space(a: &PolyhedronView, wall: &Plane, alert: f64) -> Option<Manifold> {
    let n = wall.normal;
    if n.dot(&(a.centre - wall.point)) - a.radius > alert {
        return None;
    }
    let mut m = Manifold::new(n);
    let mut c = [WallPoint { id: 0, p: Vec2::zeros(), h: 0.0, x: Vec3::zeros() }; CAP];
    let mut len = 0;
    for (k, v) in a.vertices.iter().enumerate() {
        let h = n.dot(&(v - wall.point));
        if h > alert {
            continue;
        }
        let d = v - wall.point;
        let q = WallPoint { id: k as u32, p: Vec2::new(m.t1.dot(&d), m.t2.dot(&d)), h, x: *v };
        if len < CAP {
            c[len] = q;
            len += 1;
        } else if let Some(w) = (0..CAP).filter(|&i| c[i].h > h).max_by(|&i, &j| c[i].h.total_cmp(&c[j].h)) {
            c[w] = q; // full: the deepest are kept
        }
    }
    if len == 0 {
        return None;
    }
    let sel = reduce_points(&mut c[..len], EPS * a.radius, |q| q.p, |q| q.h);
    let chosen = &mut c[..sel];
    chosen.sort_unstable_by_key(|q| q.id);
    for q in chosen.iter() {
        m.push(q.x - 0.5 * q.h * n, q.h);
    }
    Some(m)
}

/// Contact of sphere `a` (centre `ca`, radius `ra`, m) and sphere `b`; coincident centres take the normal `+z`.
pub fn sphere_sphere(ca: &Vec3, ra: f64, cb: &Vec3, rb: f64, alert: f64) -> Option<Manifold> {
    let d = ca - cb;
    let dist = d.norm();
    let gap = dist - ra - rb;
    if gap > alert {
        return None;
    }
    let n = if dist > 0.0 { d / dist } else { Vec3::z() };
    let mut m = Manifold::new(n);
    m.push(cb + n * (rb + 0.5 * gap), gap);
    Some(m)
}

/// Contact of sphere `a` (candidate) with the half-space `wall` (antagonist).
pub fn sphere_half_space(c: &Vec3, r: f64, wall: &Plane, alert: f64) -> Option<Manifold> {
    let n = wall.normal;
    let gap = n.dot(&(c - wall.point)) - r;
    if gap > alert {
        return None;
    }
    let mut m = Manifold::new(n);
    m.push(c - n * (r + 0.5 * gap), gap);
    Some(m)
}

/// Contact of sphere `a` (candidate, centre `c`, radius `r`) with polyhedron `b` (antagonist): the closest
/// point of `b` to the centre (the normal from it to the centre), or, the centre inside `b`, the face of
/// least penetration (its normal).
pub fn sphere_polyhedron(c: &Vec3, r: f64, b: &PolyhedronView, alert: f64) -> Option<Manifold> {
    if (c - b.centre).norm() - r - b.radius > alert {
        return None;
    }
    // The face whose plane the centre is farthest above (or least below).
    let (mut face, mut s) = (0, f64::NEG_INFINITY);
    for (f, (nf, d)) in b.normals.iter().zip(b.offsets).enumerate() {
        let sf = nf.dot(c) - d;
        if sf > s {
            (face, s) = (f, sf);
        }
    }
    let nf = b.normals[face];
    let q = c - s * nf;
    let eps = EPS * b.radius;
    // The centre inside, or its projection on that face inside the polyhedron: the face is closest.
    let (q, n, dist) = if s <= 0.0 || b.normals.iter().zip(b.offsets).all(|(m, d)| m.dot(&q) - d <= eps) {
        (q, nf, s)
    } else {
        // Otherwise the closest point is on an edge (or at its end, a vertex).
        let mut best = (f64::INFINITY, q);
        for e in b.edges {
            let (u, v) = (b.vertices[e.vertices[0] as usize], b.vertices[e.vertices[1] as usize]);
            let w = v - u;
            let t = ((c - u).dot(&w) / w.norm_squared()).clamp(0.0, 1.0);
            let p = u + t * w;
            let d = (c - p).norm_squared();
            if d < best.0 {
                best = (d, p);
            }
        }
        let d = c - best.1;
        let dist = d.norm();
        (best.1, if dist > 0.0 { d / dist } else { nf }, dist)
    };
    let gap = dist - r;
    if gap > alert {
        return None;
    }
    let mut m = Manifold::new(n);
    m.push(q + 0.5 * gap * n, gap);
    Some(m)
}

/// Contact of polyhedron `a` (candidate) with sphere `b` (antagonist): [`sphere_polyhedron`] reversed.
pub fn polyhedron_sphere(a: &PolyhedronView, c: &Vec3, r: f64, alert: f64) -> Option<Manifold> {
    sphere_polyhedron(c, r, a, alert).map(|m| m.reversed())
}
