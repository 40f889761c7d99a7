//! Contact detection of the 2D engines (Saussine et al. 2006, §2.2–2.3; the
//! NSCD engine runs it at the intermediate configuration `q_m`, the 2D MD engine
//! at every force evaluation): places every shape in the world, predetects pairs on the
//! tile grid ([`super::broad_phase`]), and runs the narrow phase
//! ([`super::narrow_phase`]) on each pair. Contacts come out sorted by key
//! (candidate, antagonist, feature), so the solver order — and therefore every
//! result — is reproducible.
//!
//! **Compound bodies** ([`crate::geometry::Compound`]) are placed part by part.
//! The broad phase sees one box per body (the union of its parts); the narrow
//! phase runs on every pair of parts whose boxes (enlarged by the alert
//! distance) overlap: part against polygon, part against part, part against
//! disc. A body never contacts itself, so parts of one body never meet. A plain
//! polygon is a single part, so pairs without a compound are detected exactly as
//! before, with the same feature ids. A pair involving a compound gets the
//! feature id of `compound_feature`, which names both parts, so keys stay
//! unique and stable from step to step and the warm start finds them.

use super::bodies::Bodies;
use super::broad_phase::{Aabb, Grid};
use super::narrow_phase::{detect, Placed};
use super::shadow_overlap::{ContactPoint, PolygonView};
use crate::geometry::{rotate, Shape, Vec2};

/// Identifies a contact across steps: candidate, antagonist, feature pair.
pub type ContactKey = (u32, u32, u32);

/// Reused detection buffers.
#[derive(Debug, Clone, Default)]
pub struct Detector {
    /// World vertices and outward normals of every polygon part, part after part.
    vertices: Vec<Vec2>,
    normals: Vec<Vec2>,
    /// Start of each part in `vertices`, plus the end.
    part_start: Vec<usize>,
    /// World centroid of each part (the body centre for a plain polygon).
    part_centre: Vec<Vec2>,
    /// Each part's own inradius (m).
    part_inradius: Vec<f64>,
    /// Each part's box, enlarged by the alert distance.
    part_boxes: Vec<Aabb>,
    /// First part of each body, plus the end: a polygon has one part, a compound
    /// several, a disc none.
    body_parts: Vec<usize>,
    /// Whether each body is a compound.
    compound: Vec<bool>,
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
        self.vertices.clear();
        self.normals.clear();
        self.part_start.clear();
        self.part_centre.clear();
        self.part_inradius.clear();
        self.part_boxes.clear();
        self.body_parts.clear();
        self.compound.clear();
        self.boxes.clear();
        self.mobile.clear();
        let enlarge =
            |lo: Vec2, hi: Vec2| Aabb { min: [lo.x - alert, lo.y - alert], max: [hi.x + alert, hi.y + alert] };
        for (i, info) in bodies.info.iter().enumerate() {
            self.body_parts.push(self.part_start.len());
            self.mobile.push(bodies.is_mobile(i));
            let g = Vec2::new(q[i][0], q[i][1]);
            let (c, s) = (q[i][2].cos(), q[i][2].sin());
            let (mut lo, mut hi) = (g, g);
            let mut place = |p: &crate::geometry::ConvexPolygon, centre: Vec2| {
                let (mut plo, mut phi) = (centre, centre);
                self.part_start.push(self.vertices.len());
                for (v, nr) in p.vertices.iter().zip(&p.normals) {
                    let w = g + rotate(*v, c, s);
                    plo = plo.inf(&w);
                    phi = phi.sup(&w);
                    self.vertices.push(w);
                    self.normals.push(rotate(*nr, c, s));
                }
                self.part_centre.push(centre);
                self.part_inradius.push(p.inradius);
                self.part_boxes.push(enlarge(plo, phi));
                lo = lo.inf(&plo);
                hi = hi.sup(&phi);
            };
            match &info.shape {
                Shape::Polygon(p) => place(p, g),
                Shape::Compound(cp) => {
                    for (p, off) in cp.parts.iter().zip(&cp.offsets) {
                        place(p, g + rotate(*off, c, s));
                    }
                }
                Shape::Disc(r) => {
                    lo -= Vec2::new(*r, *r);
                    hi += Vec2::new(*r, *r);
                }
            }
            self.compound.push(matches!(info.shape, Shape::Compound(_)));
            self.boxes.push(enlarge(lo, hi));
        }
        self.body_parts.push(self.part_start.len());
        self.part_start.push(self.vertices.len());
        let mobile = &self.mobile;
        self.grid.pairs(&self.boxes, |i, j| !mobile[i] && !mobile[j], &mut self.pairs);
        self.found.clear();
        let (vertices, normals, part_start) = (&self.vertices, &self.normals, &self.part_start);
        let (part_centre, part_inradius) = (&self.part_centre, &self.part_inradius);
        // Body `i`'s part `k` (global part index), or the disc itself.
        let placed = |i: usize, k: Option<usize>| match k {
            Some(k) => {
                let r = part_start[k]..part_start[k + 1];
                Placed::Polygon(PolygonView {
                    vertices: &vertices[r.clone()],
                    normals: &normals[r],
                    centre: part_centre[k],
                    inradius: part_inradius[k],
                })
            }
            None => match &bodies.info[i].shape {
                Shape::Disc(r) => Placed::Disc { centre: Vec2::new(q[i][0], q[i][1]), radius: *r },
                _ => unreachable!("only discs have no polygon part"),
            },
        };
        for &(i, j) in &self.pairs {
            let (iu, ju) = (i as usize, j as usize);
            let parts = |b: usize| self.body_parts[b]..self.body_parts[b + 1];
            let (ri, rj) = (parts(iu), parts(ju));
            let found = &mut self.found;
            if !(self.compound[iu] || self.compound[ju]) {
                // Polygons (one part) and discs (none): one test, the narrow phase's ids.
                let (pa, pb) = (placed(iu, ri.clone().next()), placed(ju, rj.clone().next()));
                detect(pa, pb, alert, |c| found.push(((i, j, c.feature), c)));
                continue;
            }
            // A disc is one "part" with no polygon (None).
            let list = |r: std::ops::Range<usize>| {
                let disc = r.is_empty();
                r.map(Some).chain(disc.then_some(None))
            };
            let box_of = |b: usize, k: Option<usize>| k.map_or(&self.boxes[b], |k| &self.part_boxes[k]);
            // The part index within its compound, `None` for a plain polygon.
            let side = |b: usize, k: Option<usize>, r: &std::ops::Range<usize>| {
                k.map(|k| Side { part: self.compound[b].then_some(k - r.start) })
            };
            for ka in list(ri.clone()) {
                for kb in list(rj.clone()) {
                    if !box_of(iu, ka).overlaps(box_of(ju, kb)) {
                        continue;
                    }
                    let (pa, pb) = (placed(iu, ka), placed(ju, kb));
                    let disc_pair = ka.is_none() || kb.is_none();
                    let (sa, sb) = (side(iu, ka, &ri), side(ju, kb, &rj));
                    detect(pa, pb, alert, |mut c| {
                        c.feature = compound_feature(c.feature, disc_pair, sa, sb);
                        found.push(((i, j, c.feature), c))
                    });
                }
            }
        }
        self.found.sort_unstable_by_key(|(k, _)| *k);
        debug_assert!(n + 1 == self.body_parts.len());
    }
}

/// One side of a contact in a pair involving a compound: a polygon (a part of
/// a compound, `part` being its index in the compound, or a plain polygon,
/// `part = None`); a disc is no `Side` at all.
#[derive(Debug, Clone, Copy)]
struct Side {
    part: Option<usize>,
}

impl Side {
    /// The 14-bit field naming vertex or edge `index` of this side: `part << 6 | index`
    /// for a part (at most 256 parts of at most 64 vertices), `index` for a plain polygon.
    fn field(self, index: u32) -> u32 {
        match self.part {
            Some(p) => ((p as u32) << 6) | (index & 0x3f),
            None => index & 0x3fff,
        }
    }
}

// Layout of the feature ids made by `shadow_overlap.rs` and `narrow_phase.rs`
// (read here, not changed): polygon–polygon ids are either
// `ref_is_b << 31 | edge << 16 | inc` (one intruding corner),
// `ia << 16 | VERTEX_VERTEX | ib` (vertex to vertex), or
// `edge_a << 16 | SLOT_FLAG | edge_b << 1 | slot` (an end of an edge-to-edge segment);
// polygon–disc ids are `edge` (face region) or `DISC_VERTEX | vertex`.
const SLOT_FLAG: u32 = 0x8000;
const VERTEX_VERTEX: u32 = 0x4000;
const DISC_VERTEX: u32 = 0x1_0000;

/// Feature id of a contact in a pair involving a compound, from the id `inner`
/// the narrow phase gave for the two polygons (or polygon and disc) `a`, `b`.
///
/// `inner` always names one feature (vertex or edge) of each polygon side and a
/// kind; the result is `kind << 28 | field_a << 14 | field_b`, with `kind` in
/// 0..=6 (corner of B on an edge of A, corner of A on an edge of B, vertex to
/// vertex, segment end 0 or 1, disc on a face, disc on a vertex) and each field
/// 14 bits: `part << 6 | index` on a compound, the index on a plain polygon, 0
/// on a disc. Unique for compounds within [`crate::geometry::Compound::MAX_PARTS`]
/// parts of [`crate::geometry::Compound::MAX_PART_VERTICES`] vertices against
/// polygons of fewer than 2¹⁴ vertices.
fn compound_feature(inner: u32, disc_pair: bool, a: Option<Side>, b: Option<Side>) -> u32 {
    let field = |s: Option<Side>, index: u32| s.map_or(0, |s| s.field(index));
    let (kind, ia, ib) = if disc_pair {
        // One side is a disc: the index belongs to the polygon side.
        let kind = if inner & DISC_VERTEX != 0 { 6 } else { 5 };
        let idx = inner & 0xffff;
        (kind, idx, idx)
    } else if inner & SLOT_FLAG != 0 {
        (3 + (inner & 1), (inner >> 16) & 0x7fff, (inner >> 1) & 0x1fff)
    } else if inner & VERTEX_VERTEX != 0 {
        (2, (inner >> 16) & 0x7fff, inner & 0x3fff)
    } else if inner >> 31 == 1 {
        // Reference edge on B, intruding corner of A.
        (1, inner & 0x3fff, (inner >> 16) & 0x7fff)
    } else {
        (0, (inner >> 16) & 0x7fff, inner & 0x3fff)
    };
    (kind << 28) | (field(a, ia) << 14) | field(b, ib)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compound_features_name_both_parts() {
        let part = |p| Some(Side { part: Some(p) });
        let plain = Some(Side { part: None });
        // Same inner feature, different parts: different ids.
        let inner = (1u32 << 31) | (3 << 16) | 2;
        let f = compound_feature(inner, false, part(0), part(1));
        let g = compound_feature(inner, false, part(1), part(0));
        assert_ne!(f, g);
        assert_eq!(f >> 28, 1);
        assert_eq!((f >> 14) & 0x3fff, 2, "corner 2 of part 0 of A");
        assert_eq!(f & 0x3fff, (1 << 6) | 3, "edge 3 of part 1 of B");
        // Slot ends differ.
        let s0 = (2u32 << 16) | SLOT_FLAG | (1 << 1);
        assert_ne!(compound_feature(s0, false, part(5), plain), compound_feature(s0 | 1, false, part(5), plain));
        // Disc on a face or a vertex of the same index.
        assert_ne!(compound_feature(4, true, part(2), None), compound_feature(DISC_VERTEX | 4, true, part(2), None));
        assert_eq!(compound_feature(4, true, None, part(2)) & 0x3fff, (2 << 6) | 4);
    }
}
