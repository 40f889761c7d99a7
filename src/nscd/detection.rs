//! Contact detection at the intermediate configuration `q_m` (Saussine et al.
//! 2006, §2.2–2.3): places every shape in the world, predetects pairs on the
//! tile grid ([`super::broad_phase`]), and runs the narrow phase
//! ([`super::narrow_phase`]) on each pair. Contacts come out sorted by key
//! (candidate, antagonist, feature), so the solver order — and therefore every
//! result — is reproducible.

use super::bodies::Bodies;
use super::broad_phase::{Aabb, Grid};
use super::contact::ContactKey;
use super::narrow_phase::{detect, Placed};
use super::shadow_overlap::{ContactPoint, PolygonView};
use crate::geometry::{rotate, Shape, Vec2};

/// Reused detection buffers.
#[derive(Debug, Clone, Default)]
pub struct Detector {
    vertices: Vec<Vec2>,
    normals: Vec<Vec2>,
    offsets: Vec<usize>,
    boxes: Vec<Aabb>,
    mobile: Vec<bool>,
    grid: Grid,
    pairs: Vec<(u32, u32)>,
    /// Contacts found by the last call, sorted by key.
    pub found: Vec<(ContactKey, ContactPoint)>,
}

impl Detector {
    /// Detects all contacts with gap below `alert` (m) in configuration `q`.
    pub fn run(&mut self, bodies: &Bodies, q: &[[f64; 3]], alert: f64) {
        let n = bodies.len();
        self.offsets.clear();
        self.vertices.clear();
        self.normals.clear();
        self.boxes.clear();
        self.mobile.clear();
        for (i, info) in bodies.info.iter().enumerate() {
            self.offsets.push(self.vertices.len());
            self.mobile.push(bodies.is_mobile(i));
            let g = Vec2::new(q[i][0], q[i][1]);
            let (c, s) = (q[i][2].cos(), q[i][2].sin());
            let (mut lo, mut hi) = (g, g);
            match &info.shape {
                Shape::Polygon(p) => {
                    for (v, nr) in p.vertices.iter().zip(&p.normals) {
                        let w = g + rotate(*v, c, s);
                        lo = lo.inf(&w);
                        hi = hi.sup(&w);
                        self.vertices.push(w);
                        self.normals.push(rotate(*nr, c, s));
                    }
                }
                Shape::Disc(r) => {
                    lo -= Vec2::new(*r, *r);
                    hi += Vec2::new(*r, *r);
                }
            }
            self.boxes.push(Aabb { min: [lo.x - alert, lo.y - alert], max: [hi.x + alert, hi.y + alert] });
        }
        self.offsets.push(self.vertices.len());
        let mobile = &self.mobile;
        self.grid.pairs(&self.boxes, |i, j| !mobile[i] && !mobile[j], &mut self.pairs);
        self.found.clear();
        let (vertices, normals, offsets) = (&self.vertices, &self.normals, &self.offsets);
        let placed = |i: usize| {
            let centre = Vec2::new(q[i][0], q[i][1]);
            match &bodies.info[i].shape {
                Shape::Polygon(p) => {
                    let r = offsets[i]..offsets[i + 1];
                    Placed::Polygon(PolygonView {
                        vertices: &vertices[r.clone()],
                        normals: &normals[r],
                        centre,
                        inradius: p.inradius,
                    })
                }
                Shape::Disc(r) => Placed::Disc { centre, radius: *r },
            }
        };
        for &(i, j) in &self.pairs {
            let found = &mut self.found;
            detect(placed(i as usize), placed(j as usize), alert, |c| found.push(((i, j, c.feature), c)));
        }
        self.found.sort_unstable_by_key(|(k, _)| *k);
        debug_assert!(n + 1 == self.offsets.len());
    }
}
