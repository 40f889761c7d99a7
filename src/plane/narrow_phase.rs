//! Narrow phase: dispatches a candidate pair to the polygon–polygon shadow
//! overlap test ([`super::shadow_overlap`]) or to the closed-form polygon–disc
//! and disc–disc tests. All normals point from the antagonist to the candidate.

use super::shadow_overlap::{polygon_polygon, ContactPoint, PolygonView};
use crate::geometry::Vec2;

/// A body's shape placed in the world frame.
#[derive(Debug, Clone, Copy)]
pub enum Placed<'a> {
    /// A convex polygon, vertices and edge normals in the world frame.
    Polygon(PolygonView<'a>),
    /// A disc.
    Disc {
        /// Centre in the world frame (m).
        centre: Vec2,
        /// Radius (m).
        radius: f64,
    },
}

/// Contacts between candidate `a` and antagonist `b` with gap below `alert` (m).
pub fn detect(a: Placed, b: Placed, alert: f64, mut emit: impl FnMut(ContactPoint)) {
    match (a, b) {
        (Placed::Polygon(pa), Placed::Polygon(pb)) => polygon_polygon(pa, pb, alert, emit),
        (Placed::Disc { centre: ca, radius: ra }, Placed::Disc { centre: cb, radius: rb }) => {
            let d = ca - cb;
            let dist = d.norm();
            let gap = dist - ra - rb;
            if gap <= alert && dist > 0.0 {
                let n = d / dist;
                emit(ContactPoint { feature: 0, point: cb + n * (rb + 0.5 * gap), normal: n, gap });
            }
        }
        (Placed::Polygon(p), Placed::Disc { centre, radius }) => {
            if let Some(mut c) = polygon_disc(p, centre, radius, alert) {
                c.normal = -c.normal;
                emit(c)
            }
        }
        (Placed::Disc { centre, radius }, Placed::Polygon(p)) => {
            if let Some(c) = polygon_disc(p, centre, radius, alert) {
                emit(c)
            }
        }
    }
}

/// Polygon–disc contact, normal from the polygon to the disc.
fn polygon_disc(p: PolygonView, centre: Vec2, radius: f64, alert: f64) -> Option<ContactPoint> {
    let n = p.vertices.len();
    let (mut k, mut sep) = (0, f64::NEG_INFINITY);
    for (e, (v, nr)) in p.vertices.iter().zip(p.normals).enumerate() {
        let s = (centre - v).dot(nr);
        if s > sep {
            sep = s;
            k = e;
        }
    }
    if sep - radius > alert {
        return None;
    }
    let (v0, v1) = (p.vertices[k], p.vertices[(k + 1) % n]);
    let e = v1 - v0;
    let along = (centre - v0).dot(&e);
    if sep <= 0.0 || (0.0..=e.norm_squared()).contains(&along) {
        // Face region: the normal is the edge normal.
        let nr = p.normals[k];
        let gap = sep - radius;
        return Some(ContactPoint { feature: k as u32, point: centre - nr * (radius + 0.5 * gap), normal: nr, gap });
    }
    // Vertex region.
    let (vi, v) = if along < 0.0 { (k, v0) } else { ((k + 1) % n, v1) };
    let d = centre - v;
    let dist = d.norm();
    let gap = dist - radius;
    if gap > alert {
        return None;
    }
    let nr = d / dist;
    Some(ContactPoint { feature: 0x1_0000 | vi as u32, point: v + nr * (0.5 * gap), normal: nr, gap })
}
