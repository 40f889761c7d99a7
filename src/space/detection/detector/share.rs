//! The narrow phase over the sorted pairs, shared by the caller and the team's helper: the pairs not yet
//! taken are one range, the caller takes blocks from its front and the helper from its back until they
//! meet ([`Claims`]); each thread writes its contacts and per-pair memory to its own buffers (the helper's
//! in a [`Part`], block by block), and the caller appends the helper's blocks after its own, in order, so
//! the result is the one-thread result whoever ran which pair.

use super::super::narrow::{
    polyhedron_half_space, polyhedron_polyhedron_into, polyhedron_sphere, sphere_half_space, sphere_polyhedron,
    sphere_sphere, Scratch,
};
use super::super::placed::{Edge3, PolyhedronView};
use super::super::{FaceGaps, Manifold};
use super::{Found, Memory, Placed};
use crate::geometry::{Solid, Vec3};
use std::borrow::Borrow;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

/// What the helper thread's share of the narrow phase writes: its contacts and memory, block after block
/// (blocks taken from the end of the pairs, so in decreasing order), and where each block's start.
#[derive(Debug, Clone, Default)]
#[repr(align(128))]
pub(super) struct Part {
    pub(super) found: Vec<Found>,
    pub(super) memory: Memory,
    pub(super) blocks: Vec<(usize, usize)>,
    pub(super) scratch: Scratch,
}

/// Pairs of the narrow phase per join of the team (about 0.5 ms of work in a jammed pile): a long phase is
/// cut in many joins, so that the team's timing of its two modes (which takes 16 joins at least) covers a
/// fraction of a call.
pub(super) const JOIN_PAIRS: usize = 768;
/// Pairs handed out at a time within a join: a sixteenth of those left, within these bounds.
pub(super) const MIN_BLOCK: u32 = 8;
const MAX_BLOCK: u32 = 256;

/// The pairs not yet taken, `front..back`, packed in one word: the caller takes blocks from the front, the
/// helper from the back, until they meet.
#[repr(align(128))]
pub(super) struct Claims(AtomicU64);

impl Claims {
    pub(super) fn new(front: usize, back: usize) -> Self {
        Claims(AtomicU64::new(((back as u64) << 32) | front as u64))
    }

    /// One entry from the front (`front`) or from the back, or none left.
    pub(super) fn take_one(&self, front: bool) -> Option<usize> {
        let mut cur = self.0.load(Ordering::Relaxed);
        loop {
            let (f, b) = (cur as u32, (cur >> 32) as u32);
            if f >= b {
                return None;
            }
            let (k, word) = if front { (f, cur + 1) } else { (b - 1, cur - (1 << 32)) };
            match self.0.compare_exchange_weak(cur, word, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => return Some(k as usize),
                Err(c) => cur = c,
            }
        }
    }

    /// A block from the front (`front`) or from the back, or none left.
    pub(super) fn take(&self, front: bool) -> Option<Range<usize>> {
        let mut cur = self.0.load(Ordering::Relaxed);
        loop {
            let (f, b) = (cur as u32, (cur >> 32) as u32);
            if f >= b {
                return None;
            }
            let size = ((b - f) / 16).clamp(MIN_BLOCK, MAX_BLOCK).min(b - f);
            let (r, next) = if front { (f..f + size, f + size) } else { (b - size..b, b - size) };
            let word =
                if front { (u64::from(b) << 32) | u64::from(next) } else { (u64::from(next) << 32) | u64::from(f) };
            match self.0.compare_exchange_weak(cur, word, Ordering::Relaxed, Ordering::Relaxed) {
                Ok(_) => return Some(r.start as usize..r.end as usize),
                Err(c) => cur = c,
            }
        }
    }
}

/// What the narrow phase reads.
///
/// Aligned to its own cache lines, as are [`Claims`] and [`Part`]: the two threads write nothing near what
/// the other reads (a shared line would be passed back and forth at every write).
#[repr(align(128))]
pub(super) struct Ctx<'a, S> {
    pub(super) placed: &'a [Placed],
    pub(super) vertices: &'a [Vec3],
    pub(super) normals: &'a [Vec3],
    pub(super) offsets: &'a [f64],
    pub(super) arcs: &'a [Vec3],
    pub(super) edges: &'a [Edge3],
    pub(super) solids: &'a [S],
    pub(super) pairs: &'a [(u32, u32)],
    pub(super) memory: &'a [((u32, u32), Vec3)],
    pub(super) alert: f64,
    pub(super) face_gaps: FaceGaps,
}

impl<S: Borrow<Solid>> Ctx<'_, S> {
    /// The caller's share: blocks from the front, in order, into `found` and `memory`.
    pub(super) fn front(
        &self,
        claims: &Claims,
        cursor: &mut usize,
        found: &mut Vec<Found>,
        memory: &mut Memory,
        scratch: &mut Scratch,
    ) {
        while let Some(r) = claims.take(true) {
            self.block(r, cursor, found, memory, scratch);
        }
    }

    /// The helper's share: blocks from the back.
    pub(super) fn back(&self, claims: &Claims, part: &mut Part) {
        while let Some(r) = claims.take(false) {
            part.blocks.push((part.found.len(), part.memory.len()));
            let first = self.pairs[r.start];
            let mut cursor = self.memory.partition_point(|m| m.0 < first);
            self.block(r, &mut cursor, &mut part.found, &mut part.memory, &mut part.scratch);
        }
    }

    /// The narrow phase on pairs `r`, the memory walked from `cursor`.
    fn block(
        &self,
        r: Range<usize>,
        cursor: &mut usize,
        found: &mut Vec<Found>,
        memory: &mut Memory,
        scratch: &mut Scratch,
    ) {
        let mem = self.memory;
        let mut m = Manifold::new(Vec3::z());
        for &(i, j) in &self.pairs[r] {
            while *cursor < mem.len() && mem[*cursor].0 < (i, j) {
                *cursor += 1;
            }
            let hint = mem.get(*cursor).filter(|m| m.0 == (i, j)).map(|m| &m.1);
            if self.narrow(i, j, hint, memory, scratch, &mut m) {
                for (p, q) in m.points().iter().enumerate() {
                    found.push(Found {
                        key: (i, j, p as u32),
                        position: q.position,
                        normal: m.normal,
                        t1: m.t1,
                        t2: m.t2,
                        gap: q.gap,
                    });
                }
            }
        }
    }

    fn view(&self, k: u32) -> Option<PolyhedronView<'_>> {
        match (self.placed[k as usize], self.solids[k as usize].borrow()) {
            (
                Placed::Polyhedron { vertices: v, faces: f, edges: e, arcs, centre, radius, inradius },
                Solid::Polyhedron(p),
            ) => {
                let r = |r: (u32, u32)| r.0 as usize..r.1 as usize;
                let w = self;
                Some(PolyhedronView {
                    vertices: &w.vertices[r(v)],
                    normals: &w.normals[r(f)],
                    offsets: &w.offsets[r(f)],
                    faces: &p.faces,
                    edges: &self.edges[r(e)],
                    arcs: &w.arcs[arcs as usize..(arcs + e.1 - e.0) as usize],
                    centre,
                    radius,
                    inradius,
                })
            }
            _ => None,
        }
    }

    /// The narrow phase on candidate `i` and antagonist `j`, `hint` the pair's last normal, into `out`: whether
    /// they are in contact. A polyhedron pair's axis is pushed on `memory`.
    fn narrow(
        &self,
        i: u32,
        j: u32,
        hint: Option<&Vec3>,
        memory: &mut Memory,
        scratch: &mut Scratch,
        out: &mut Manifold,
    ) -> bool {
        let alert = self.alert;
        let m = match (self.placed[i as usize], self.placed[j as usize]) {
            (Placed::Polyhedron { .. }, Placed::Polyhedron { .. }) => {
                let (Some(a), Some(b)) = (self.view(i), self.view(j)) else { return false };
                let (met, axis) = polyhedron_polyhedron_into(&a, &b, alert, hint, self.face_gaps, scratch, out);
                memory.push(((i, j), axis));
                return met;
            }
            (Placed::Polyhedron { .. }, Placed::Sphere { centre, radius }) => {
                self.view(i).and_then(|a| polyhedron_sphere(&a, &centre, radius, alert))
            }
            (Placed::Sphere { centre, radius }, Placed::Polyhedron { .. }) => {
                self.view(j).and_then(|b| sphere_polyhedron(&centre, radius, &b, alert))
            }
            (Placed::Sphere { centre: ca, radius: ra }, Placed::Sphere { centre: cb, radius: rb }) => {
                sphere_sphere(&ca, ra, &cb, rb, alert)
            }
            (Placed::Polyhedron { .. }, Placed::Wall(w)) => {
                self.view(i).and_then(|a| polyhedron_half_space(&a, &w, alert))
            }
            (Placed::Sphere { centre, radius }, Placed::Wall(w)) => sphere_half_space(&centre, radius, &w, alert),
            (Placed::Wall(_), _) => unreachable!("a half-space is never the candidate"),
        };
        m.map(|m| *out = m).is_some()
    }
}
