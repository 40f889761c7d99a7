//! Measurements on a system at rest or under load: the reaction of the supports
//! (fixed bodies and world-anchored sublayer springs) against the weight, the
//! solid fraction of a window, and the coordination number of the grains.
//!
//! These are the checks of a deposited sample (Saussine et al. 2006, §3: "let to
//! fall down under gravity onto the sublayer until they reach an equilibrium
//! state"): at equilibrium the supports carry the weight, and the packing's solid
//! fraction and coordination number lie in the range known for pentagon packings.
//! All forces are the mean forces of the last step (N).

use super::System;
use crate::geometry::{rotate, Shape, Vec2};

/// Vertical balance of the mobile bodies (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Balance {
    /// Total weight `Σ m |g|` of the non-fixed bodies (N).
    pub weight: f64,
    /// Upward force of the world-anchored springs on their bodies (N).
    pub springs: f64,
    /// Upward force of the fixed bodies through contacts whose normal is closer
    /// to vertical than to horizontal (floors; N).
    pub floors: f64,
    /// Upward force of the fixed bodies through the other contacts (side walls,
    /// by friction; N).
    pub walls: f64,
    /// Upward external loads on the mobile bodies (N; negative when they push down).
    pub loads: f64,
}

impl Balance {
    /// `springs + floors + walls + loads − weight`: zero at static equilibrium (N).
    pub fn residual(&self) -> f64 {
        self.springs + self.floors + self.walls + self.loads - self.weight
    }
}

/// The vertical balance of the non-fixed bodies over the last step. Gravity is
/// taken along −y (`sys.params.gravity[1] < 0`).
pub fn vertical_balance(sys: &System) -> Balance {
    let b = &sys.bodies;
    let g = -sys.params.gravity[1];
    let weight = b.info.iter().filter(|i| !i.fixed).map(|i| i.mass * g).sum();
    let h = sys.params.dt;
    let mut springs = 0.0;
    for s in &sys.springs {
        if s.b.is_none() && !b.info[s.a].fixed {
            springs += s.impulse / h * s.axis(&b.q)[1];
        }
    }
    let (mut floors, mut walls) = (0.0, 0.0);
    for c in sys.contact_forces() {
        let (fa, fb) = (b.info[c.candidate].fixed, b.info[c.antagonist].fixed);
        if fa == fb {
            continue;
        }
        // Force on the candidate: r_n n + r_t t; the mobile body gets it or its opposite.
        let fy = c.r_n * c.normal[1] + c.r_t * c.normal[0];
        let up = if fb { fy } else { -fy };
        if c.normal[1].abs() >= c.normal[0].abs() {
            floors += up;
        } else {
            walls += up;
        }
    }
    let loads = b.info.iter().filter(|i| !i.fixed).flat_map(|i| i.loads.iter()).map(|l| l.at(sys.time)[1]).sum();
    Balance { weight, springs, floors, walls, loads }
}

/// World vertices of the convex pieces of body `i`, each counter-clockwise: one
/// polygon, a disc as a 32-gon, or one polygon per part of a compound.
pub fn world_parts(sys: &System, i: usize) -> Vec<Vec<[f64; 2]>> {
    let q = sys.bodies.q[i];
    let (c, s) = (q[2].cos(), q[2].sin());
    let g = Vec2::new(q[0], q[1]);
    let place = |v: &Vec2| {
        let w = g + rotate(*v, c, s);
        [w.x, w.y]
    };
    match &sys.bodies.info[i].shape {
        Shape::Polygon(p) => vec![p.vertices.iter().map(place).collect()],
        Shape::Disc(r) => vec![(0..32)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 32.0;
                place(&Vec2::new(r * a.cos(), r * a.sin()))
            })
            .collect()],
        Shape::Compound(cmp) => cmp.parts.iter().map(|p| p.vertices.iter().map(place).collect()).collect(),
    }
}

/// All world vertices of body `i` (its parts' vertices one after the other; a
/// single convex polygon for a polygon or a disc).
pub fn world_polygon(sys: &System, i: usize) -> Vec<[f64; 2]> {
    world_parts(sys, i).concat()
}

/// Area (m²) of the convex polygon `poly` (counter-clockwise) inside the
/// rectangle `[x0, x1] × [y0, y1]` (Sutherland–Hodgman clipping).
pub fn clipped_area(poly: &[[f64; 2]], [x0, x1, y0, y1]: [f64; 4]) -> f64 {
    let mut cur: Vec<[f64; 2]> = poly.to_vec();
    // Each half-plane as (axis, bound, keep_greater).
    for (axis, bound, greater) in [(0, x0, true), (0, x1, false), (1, y0, true), (1, y1, false)] {
        if cur.is_empty() {
            break;
        }
        let inside = |p: &[f64; 2]| if greater { p[axis] >= bound } else { p[axis] <= bound };
        let mut next = Vec::with_capacity(cur.len() + 2);
        for k in 0..cur.len() {
            let (p, q) = (cur[k], cur[(k + 1) % cur.len()]);
            let (ip, iq) = (inside(&p), inside(&q));
            if ip {
                next.push(p);
            }
            if ip != iq {
                let t = (bound - p[axis]) / (q[axis] - p[axis]);
                next.push([p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1])]);
            }
        }
        cur = next;
    }
    let n = cur.len();
    (0..n).map(|k| cur[k][0] * cur[(k + 1) % n][1] - cur[(k + 1) % n][0] * cur[k][1]).sum::<f64>() / 2.0
}

/// Solid fraction of the bodies `grains` in the window `[x0, x1, y0, y1]` (m):
/// the area of the grains inside it over its area.
pub fn solid_fraction(sys: &System, grains: &[usize], window: [f64; 4]) -> f64 {
    let area = (window[1] - window[0]) * (window[3] - window[2]);
    let parts = grains.iter().flat_map(|&i| world_parts(sys, i));
    parts.map(|p| clipped_area(&p, window)).sum::<f64>() / area
}

pub use crate::plane::outputs::{coordination, neighbour_counts, Coordination};

#[cfg(test)]
mod tests {
    use super::clipped_area;

    #[test]
    fn clipping_a_square_by_a_window() {
        let sq = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]];
        // Exact areas of simple overlaps: every value is a sum of products of small
        // integers and halves, exact in binary.
        assert_eq!(clipped_area(&sq, [1.0, 3.0, -1.0, 1.0]), 1.0);
        assert_eq!(clipped_area(&sq, [-1.0, 3.0, -1.0, 3.0]), 4.0);
        assert_eq!(clipped_area(&sq, [3.0, 4.0, 0.0, 1.0]), 0.0);
        let tri = [[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]];
        assert_eq!(clipped_area(&tri, [0.0, 1.0, 0.0, 1.0]), 1.0);
        assert_eq!(clipped_area(&tri, [1.0, 2.0, 0.0, 2.0]), 0.5);
    }
}
