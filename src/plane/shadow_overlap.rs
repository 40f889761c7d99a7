//! Moreau's *shadow overlap* detection between two convex polygons
//! (Saussine et al. 2006, §2.3).
//!
//! With `V` a unit vector such that `G_A G_B · V > 0` (first `V = G_A G_B / |G_A G_B|`),
//! the shadow overlap is
//! `shov(V) = max{a · V : a vertex of A} − min{b · V : b vertex of B}`.
//! `shov` is the support function of `A − B`; between two changes of critical
//! vertex it is a sinusoid `(a* − b*) · V`, so its positive minima sit at the
//! directions where a critical vertex changes (edge normals). We rotate `V` in the
//! direction of decreasing `shov` from one change of critical vertex to the next
//! until `shov` stops decreasing:
//! - `shov ≤ −alert` on the way: no contact;
//! - the sinusoid reaches its minimum `−|a* − b*|` inside an arc: the polygons are
//!   separated vertex to vertex; a contact is kept if that distance is below the alert;
//! - otherwise the final `V` is the normal of an edge of one polygon, crossed by the
//!   critical (intruding) corner of the other: the edge direction is the tangent and
//!   the depth is `shov`; the contact point lies half-way between the corner and its
//!   projection on the edge. The second intruding corner is looked for on the
//!   incident edge (the intruding corner and its neighbour nearer the edge): the
//!   contact segment is the overlap of the reference and incident edges projected on
//!   the tangent of their bisector, and its two ends are the contact points when
//!   both lie within the alert distance (double intrusion, edge-to-edge). Each end
//!   is a corner of one polygon facing the other's edge (a corner of either
//!   polygon); it takes that corner's gap and that edge's normal, so its gap
//!   changes exactly at the rate `U_N` even for tilted, sliding edges (a common
//!   bisector normal lets such ends drift into overlap by slip × tilt per step);
//!   for parallel edges both normals are the common normal.
//!
//! The descent finds the local minimum reached from the line of centres, which is
//! the physical contact for grains of comparable size. When a small body touches
//! a large one (a wall) far from its centre, that local minimum can be a
//! far face with a huge "depth"; when the local depth exceeds the smaller
//! inradius, the global minimum over all edge normals is taken instead.
//!
//! Normals point from the antagonist `B` to the candidate `A`; `gap < 0` is an overlap.

use crate::geometry::{cross, perp, Vec2};

/// A contact point found by the narrow phase.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Identifies the feature pair, to match the contact across steps.
    pub feature: u32,
    /// Contact point (world, m).
    pub point: Vec2,
    /// Unit normal, from the antagonist towards the candidate.
    pub normal: Vec2,
    /// Signed gap (m), negative when overlapping.
    pub gap: f64,
}

/// A convex polygon in the world frame.
#[derive(Debug, Clone, Copy)]
pub struct PolygonView<'a> {
    /// Vertices, counter-clockwise.
    pub vertices: &'a [Vec2],
    /// Outward unit normal of edge `k` (vertex `k` to `k + 1`).
    pub normals: &'a [Vec2],
    /// Centre of mass.
    pub centre: Vec2,
    /// Inradius (m).
    pub inradius: f64,
}

const SLOT_FLAG: u32 = 0x8000;
const VERTEX_VERTEX: u32 = 0x4000;

#[inline]
fn feature(ref_is_b: bool, edge: usize, tag: u32) -> u32 {
    ((ref_is_b as u32) << 31) | ((edge as u32 & 0x7fff) << 16) | (tag & 0xffff)
}

/// Angle (rad, in `[0, π)`) to rotate `v` in direction `sgn` (+1 CCW, −1 CW) to reach `w`.
#[inline]
fn rotation_to(v: Vec2, w: Vec2, sgn: f64) -> f64 {
    (sgn * cross(v, w)).atan2(v.dot(&w)).max(0.0)
}

/// Detects the contacts between polygons `a` (candidate) and `b` (antagonist)
/// whose gap is below `alert` (m); calls `emit` for each (at most two).
pub fn polygon_polygon(a: PolygonView, b: PolygonView, alert: f64, mut emit: impl FnMut(ContactPoint)) {
    let (na, nb) = (a.vertices.len(), b.vertices.len());
    let mut v = b.centre - a.centre;
    let len = v.norm();
    v = if len > 0.0 { v / len } else { Vec2::new(1.0, 0.0) };
    let mut ia = argmax(a.vertices, v);
    let mut ib = argmax(b.vertices, -v);
    let mut h = (a.vertices[ia] - b.vertices[ib]).dot(&v);
    if h < -alert {
        return;
    }
    // Which polygon holds the reference edge at the minimum, and which edge.
    let mut reference: Option<(bool, usize)> = None;
    let limit = 0.5 * a.inradius.min(b.inradius);
    for _ in 0..na + nb + 2 {
        let d = a.vertices[ia] - b.vertices[ib];
        let slope = d.dot(&perp(v)); // dshov/dφ for a counter-clockwise rotation
        let sgn = if slope <= 0.0 { 1.0 } else { -1.0 };
        // Next change of critical vertex of A and of B in that direction.
        let (wa, ia_next, ea) = if sgn > 0.0 {
            (a.normals[ia], (ia + 1) % na, ia)
        } else {
            let e = (ia + na - 1) % na;
            (a.normals[e], e, e)
        };
        let (wb, ib_next, eb) = if sgn > 0.0 {
            (-b.normals[ib], (ib + 1) % nb, ib)
        } else {
            let e = (ib + nb - 1) % nb;
            (-b.normals[e], e, e)
        };
        let (phi_a, phi_b) = (rotation_to(v, wa, sgn), rotation_to(v, wb, sgn));
        let phi = phi_a.min(phi_b);
        // Does the sinusoid reach its minimum −|d| (at V = −d/|d|) before the change?
        let dn = d.norm();
        if dn > 0.0 && rotation_to(v, -d / dn, sgn) < phi && slope != 0.0 {
            if dn <= alert {
                let n = d / dn;
                emit(ContactPoint {
                    feature: feature(false, ia, VERTEX_VERTEX | ib as u32),
                    point: b.vertices[ib] + 0.5 * d,
                    normal: n,
                    gap: dn,
                });
            }
            return;
        }
        let tie = (phi_a - phi_b).abs() <= 1e-12;
        if phi_a <= phi_b || tie {
            ia = ia_next;
            reference = Some((false, ea));
            v = wa;
        }
        if phi_b < phi_a || tie {
            ib = ib_next;
            reference = Some((true, eb));
            v = wb;
        }
        h = (a.vertices[ia] - b.vertices[ib]).dot(&v);
        if h < -alert {
            return;
        }
        let d = a.vertices[ia] - b.vertices[ib];
        if sgn * d.dot(&perp(v)) >= 0.0 {
            break; // shov increases beyond: local minimum
        }
    }
    match reference {
        Some((ref_is_b, edge)) if h <= limit => {
            manifold(a, b, ref_is_b, edge, if ref_is_b { ia } else { ib }, alert, emit)
        }
        _ => {
            // Deep overlap (a large body touched far from its centre) or no local
            // minimum found: take the smallest overlap over all edge normals.
            let (ref_is_b, edge, inc, h) = global_minimum(a, b);
            if h >= -alert {
                manifold(a, b, ref_is_b, edge, inc, alert, emit)
            }
        }
    }
}

#[inline]
fn argmax(p: &[Vec2], v: Vec2) -> usize {
    let mut best = 0;
    let mut m = f64::NEG_INFINITY;
    for (k, q) in p.iter().enumerate() {
        let s = q.dot(&v);
        if s > m {
            m = s;
            best = k;
        }
    }
    best
}

/// Smallest shadow overlap over all edge normals: `(ref_is_b, edge, incident vertex, shov)`.
fn global_minimum(a: PolygonView, b: PolygonView) -> (bool, usize, usize, f64) {
    let mut best = (false, 0, 0, f64::INFINITY);
    for (k, &n) in a.normals.iter().enumerate() {
        let j = argmax(b.vertices, -n);
        let h = (a.vertices[k] - b.vertices[j]).dot(&n);
        if h < best.3 {
            best = (false, k, j, h);
        }
    }
    for (k, &n) in b.normals.iter().enumerate() {
        let j = argmax(a.vertices, -n);
        let h = (b.vertices[k] - a.vertices[j]).dot(&n);
        if h < best.3 {
            best = (true, k, j, h);
        }
    }
    best
}

/// Builds the one or two contact points once the reference edge and intruding corner are known.
fn manifold(
    a: PolygonView,
    b: PolygonView,
    ref_is_b: bool,
    edge: usize,
    inc: usize,
    alert: f64,
    mut emit: impl FnMut(ContactPoint),
) {
    let (rp, ip) = if ref_is_b { (b, a) } else { (a, b) };
    let (nr_len, ni_len) = (rp.vertices.len(), ip.vertices.len());
    let r0 = rp.vertices[edge];
    let r1 = rp.vertices[(edge + 1) % nr_len];
    let nr = rp.normals[edge]; // outward of the reference polygon, towards the incident one
                               // Sign turning "from reference to incident" into "from antagonist B to candidate A".
    let to_a = if ref_is_b { 1.0 } else { -1.0 };
    let pen = |p: Vec2| (r0 - p).dot(&nr);
    let (prev, next) = ((inc + ni_len - 1) % ni_len, (inc + 1) % ni_len);
    let (w, inc_edge) = if pen(ip.vertices[prev]) > pen(ip.vertices[next]) { (prev, prev) } else { (next, inc) };
    let pk = ip.vertices[inc];
    let pw = ip.vertices[w];
    let ni = ip.normals[inc_edge]; // outward of the incident polygon, towards the reference one
                                   // Contact segment: the overlap of both edges projected on the tangent of their
                                   // bisector. Each end is a corner of one polygon facing the other's edge: a
                                   // corner of the incident edge against the reference edge, or a corner of the
                                   // reference edge against the incident edge. Its gap and normal are those of
                                   // that corner and edge, so the gap of each end changes exactly at the rate
                                   // `U_N` even when the edges are tilted and slide; for parallel edges both
                                   // normals are the common normal of the paper's averaging.
    let nb = (nr - ni).normalize();
    let t = perp(nb);
    let (sr0, sr1) = (t.dot(&r0), t.dot(&r1));
    let (sk, sw) = (t.dot(&pk), t.dot(&pw));
    let lo = sr0.min(sr1).max(sk.min(sw));
    let hi = sr0.max(sr1).min(sk.max(sw));
    let size = (r1 - r0).norm().min((pw - pk).norm());
    if hi - lo > 1e-9 * size {
        // The key must not depend on which polygon holds the reference edge (a tie
        // for parallel faces): it names both edges and the end along the tangent.
        let (edge_a, edge_b) = if ref_is_b { (inc_edge, edge) } else { (edge, inc_edge) };
        let mut emitted = false;
        for (end, s) in [lo, hi].into_iter().enumerate() {
            // Which corner makes this end: the nearest endpoint projection
            // (an incident corner wins a tie).
            let inc_corner = if (s - sk).abs() <= (s - sw).abs() { pk } else { pw };
            let ref_corner = if (s - sr0).abs() <= (s - sr1).abs() { r0 } else { r1 };
            let from_incident = (t.dot(&inc_corner) - s).abs() <= (t.dot(&ref_corner) - s).abs();
            let (corner, n_edge, gap) = if from_incident {
                (inc_corner, nr, (inc_corner - r0).dot(&nr))
            } else {
                (ref_corner, ni, (ref_corner - pk).dot(&ni))
            };
            if gap <= alert {
                // Normal from B to A: the reference normal points to the incident
                // polygon, the incident normal to the reference one.
                let normal = if from_incident { to_a * nr } else { -to_a * ni };
                let slot = if to_a > 0.0 { end } else { 1 - end } as u32;
                emit(ContactPoint {
                    feature: ((edge_a as u32 & 0x7fff) << 16) | SLOT_FLAG | ((edge_b as u32 & 0x1fff) << 1) | slot,
                    point: corner - 0.5 * gap * n_edge,
                    normal,
                    gap,
                });
                emitted = true;
            }
        }
        if emitted {
            return;
        }
    }
    let depth = pen(pk);
    emit(ContactPoint {
        feature: feature(ref_is_b, edge, inc as u32),
        point: pk + 0.5 * depth * nr,
        normal: to_a * nr,
        gap: -depth,
    });
}
