//! The world placement of the bodies cut in blocks of consecutive bodies, each block with its own slices
//! of the detector's buffers, so that the caller and the team's helper can place blocks side by side.

use super::super::broad::Aabb3;
use super::super::placed::{place_into, Edge3};
use super::Placed;
use crate::geometry::{Pose, Solid, Vec3};
use std::borrow::Borrow;

/// Most blocks the placement is cut in, and fewest bodies in a block.
pub(super) const PLACE_BLOCKS: usize = 32;
pub(super) const PLACE_MIN: usize = 32;

/// A block of consecutive bodies to place: their entries and their parts of the buffers, which start at
/// `base` (vertices, faces, arcs, finite bodies) in the whole buffers.
pub(super) struct PlaceBlock<'a> {
    pub(super) first: usize,
    pub(super) base: (u32, u32, u32, u32),
    pub(super) placed: &'a mut [Placed],
    pub(super) vertices: &'a mut [Vec3],
    pub(super) normals: &'a mut [Vec3],
    pub(super) offsets: &'a mut [f64],
    pub(super) arcs: &'a mut [Vec3],
    pub(super) boxes: &'a mut [Aabb3],
}

impl PlaceBlock<'_> {
    /// Places the block's bodies and makes the boxes of the finite ones, enlarged by `half` (m).
    pub(super) fn fill<S: Borrow<Solid>>(self, solids: &[S], poses: &[Pose], edges: &[Edge3], half: f64) {
        let (v0, f0, a0) = (self.base.0 as usize, self.base.1 as usize, self.base.2 as usize);
        let mut boxes = self.boxes.iter_mut();
        let bodies = solids[self.first..].iter().zip(&poses[self.first..]);
        for ((solid, pose), placed) in bodies.zip(self.placed.iter_mut()) {
            let (lo, hi) = match (solid.borrow(), placed) {
                (
                    Solid::Polyhedron(p),
                    Placed::Polyhedron { vertices: v, faces: f, edges: e, arcs, radius, inradius, .. },
                ) => {
                    let (v, f, a) = (
                        v.0 as usize - v0..v.1 as usize - v0,
                        f.0 as usize - f0..f.1 as usize - f0,
                        *arcs as usize - a0,
                    );
                    let bounds = place_into(
                        p,
                        pose,
                        &edges[e.0 as usize..e.1 as usize],
                        &mut self.vertices[v],
                        &mut self.normals[f.clone()],
                        &mut self.offsets[f],
                        &mut self.arcs[a..a + (e.1 - e.0) as usize],
                    );
                    (*radius, *inradius) = (bounds.radius, bounds.inradius);
                    (bounds.lo, bounds.hi)
                }
                (_, Placed::Sphere { centre, radius }) => {
                    let r = Vec3::repeat(*radius);
                    (*centre - r, *centre + r)
                }
                _ => continue,
            };
            if let Some(b) = boxes.next() {
                *b = Aabb3 {
                    min: [lo.x - half, lo.y - half, lo.z - half],
                    max: [hi.x + half, hi.y + half, hi.z + half],
                };
            }
        }
    }
}
