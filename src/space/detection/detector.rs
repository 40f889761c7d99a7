//! The per-step contact detection of the 3D engine, as LMGC90 runs its 3D modules each step (predetection
//! of the pairs in boxes, then the fine detection of each; mod_PRPRx keeps each pair's last separating
//! normal for its next shadow overlap): every shape placed in the world once, the pairs found by the grid
//! ([`super::broad`]) and every half-space tested against each finite body's box, then the narrow phase
//! ([`super::narrow`]) on each pair with at least one mobile body. Contacts come out sorted by key
//! (candidate, antagonist, point index), so the solver's order — and every result — is reproducible.
//!
//! The candidate is the lower body index, unless the other body is a half-space: a half-space is always the
//! antagonist. Two half-spaces never meet. Within a pair the points are in the order of the features that
//! make them (see [`super::polygon::Label`]: the candidate's vertices by index, then the antagonist's, then
//! edge crossings), which does not depend on the world frame and changes only when the contact's topology
//! does; the point index of the key is the rank in that order.
//!
//! The detector remembers, per polyhedron pair, the last normal (or the axis that separated the pair) in a
//! vector sorted by pair, walked alongside the sorted pairs; it is only a cheap first test (see [`super::axis`]), so the result of
//! a call does not depend on the previous calls. Once the buffers have grown, a call allocates nothing.

use super::broad::{Aabb3, Grid3};
use super::narrow::{
    polyhedron_half_space, polyhedron_polyhedron_into, polyhedron_sphere, sphere_half_space, sphere_polyhedron,
    sphere_sphere,
};
use super::placed::{place_into, Edge3, Plane, PolyhedronView, Topologies};
use super::polygon::Scratch;
use super::Manifold;
use crate::geometry::{Pose, Solid, Vec3};
use crate::team::{Team, TeamStats};
use std::borrow::Borrow;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

/// A contact point found by [`Detector::run`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Found {
    /// Candidate body, antagonist body, index of the point in the pair's manifold (0..4).
    pub key: (u32, u32, u32),
    /// Position (world, m), half-way between the two surfaces.
    pub position: Vec3,
    /// Unit normal from the antagonist towards the candidate.
    pub normal: Vec3,
    /// First tangent ([`super::tangent_frame`]).
    pub t1: Vec3,
    /// Second tangent, `normal × t1`.
    pub t2: Vec3,
    /// Signed gap (m), negative when overlapping.
    pub gap: f64,
}

/// A body placed in the world: for a polyhedron, ranges in the detector's buffers (its edges in the
/// topology cache's).
#[derive(Debug, Clone, Copy)]
enum Placed {
    Polyhedron {
        vertices: (u32, u32),
        faces: (u32, u32),
        edges: (u32, u32),
        /// First of its arcs (one per edge).
        arcs: u32,
        centre: Vec3,
        radius: f64,
        inradius: f64,
    },
    Sphere {
        centre: Vec3,
        radius: f64,
    },
    Wall(Plane),
}

/// The shapes placed in the world, which the narrow phase reads.
#[derive(Debug, Clone, Default)]
struct World {
    placed: Vec<Placed>,
    vertices: Vec<Vec3>,
    normals: Vec<Vec3>,
    offsets: Vec<f64>,
    arcs: Vec<Vec3>,
}

/// The per-pair memory: (candidate, antagonist) and the axis, sorted by pair.
type Memory = Vec<((u32, u32), Vec3)>;

/// What the helper thread's share of the narrow phase writes: its contacts and memory, block after block
/// (blocks taken from the end of the pairs, so in decreasing order), and where each block's start.
#[derive(Debug, Clone, Default)]
struct Part {
    found: Vec<Found>,
    memory: Memory,
    blocks: Vec<(usize, usize)>,
    scratch: Scratch,
}

/// Reused detection buffers, the per-pair memory of the normal and the threads.
#[derive(Debug, Clone, Default)]
pub struct Detector {
    world: World,
    shapes: Topologies,
    /// For each body, its entry in `shapes` at the last call (`u32::MAX`: none).
    shape_of: Vec<u32>,
    /// Boxes of the finite bodies (enlarged by half the alert distance each), and their body indices.
    boxes: Vec<Aabb3>,
    finite: Vec<u32>,
    walls: Vec<u32>,
    grid: Grid3,
    /// (candidate, antagonist) pairs to test, sorted.
    pairs: Vec<(u32, u32)>,
    /// The higher neighbours of one body.
    around: Vec<u32>,
    memory: Memory,
    next_memory: Memory,
    /// The caller's polygon buffers.
    scratch: Scratch,
    /// The helper's share.
    back: Part,
    team: Team,
    /// Contacts found by the last call, sorted by key.
    pub found: Vec<Found>,
}

/// Pairs of the narrow phase handed out at a time: a sixteenth of those left, within these bounds.
const MIN_BLOCK: u32 = 16;
const MAX_BLOCK: u32 = 1024;

/// The pairs not yet taken, `front..back`, packed in one word: the caller takes blocks from the front, the
/// helper from the back, until they meet.
struct Claims(AtomicU64);

impl Claims {
    fn new(n: usize) -> Self {
        Claims(AtomicU64::new((n as u64) << 32))
    }

    /// A block from the front (`front`) or from the back, or none left.
    fn take(&self, front: bool) -> Option<Range<usize>> {
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
struct Ctx<'a, S> {
    world: &'a World,
    edges: &'a [Edge3],
    solids: &'a [S],
    pairs: &'a [(u32, u32)],
    memory: &'a [((u32, u32), Vec3)],
    alert: f64,
}

impl<S: Borrow<Solid>> Ctx<'_, S> {
    /// The caller's share: blocks from the front, in order, into `found` and `memory`.
    fn front(&self, claims: &Claims, found: &mut Vec<Found>, memory: &mut Memory, scratch: &mut Scratch) {
        // The front blocks follow each other: the memory is walked once alongside.
        let mut cursor = 0;
        while let Some(r) = claims.take(true) {
            self.block(r, &mut cursor, found, memory, scratch);
        }
    }

    /// The helper's share: blocks from the back.
    fn back(&self, claims: &Claims, part: &mut Part) {
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
        match (self.world.placed[k as usize], self.solids[k as usize].borrow()) {
            (
                Placed::Polyhedron { vertices: v, faces: f, edges: e, arcs, centre, radius, inradius },
                Solid::Polyhedron(p),
            ) => {
                let r = |r: (u32, u32)| r.0 as usize..r.1 as usize;
                let w = self.world;
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
        let m = match (self.world.placed[i as usize], self.world.placed[j as usize]) {
            (Placed::Polyhedron { .. }, Placed::Polyhedron { .. }) => {
                let (Some(a), Some(b)) = (self.view(i), self.view(j)) else { return false };
                let (met, axis) = polyhedron_polyhedron_into(&a, &b, alert, hint, scratch, out);
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

/// The topology cache is started again beyond this many entries (shapes that keep changing).
const MAX_SHAPES: usize = 1 << 16;

impl Detector {
    /// A detector running its narrow phase on `threads` threads (see [`Self::set_threads`]).
    pub fn with_threads(threads: usize) -> Self {
        let mut d = Self::default();
        d.set_threads(threads);
        d
    }

    /// Runs the narrow phase on `threads` threads: 1 (the default) or 2 (the caller and a helper thread of
    /// a [`Team`]; more are taken as 2). The contacts are the same, bit for bit, on one thread or two.
    pub fn set_threads(&mut self, threads: usize) {
        if (threads >= 2) != (self.team.threads() >= 2) {
            self.team = Team::new(threads.min(2));
        }
    }

    /// Threads of the narrow phase (1 or 2).
    pub fn threads(&self) -> usize {
        self.team.threads()
    }

    /// What the team's joins did so far (all zero on one thread).
    pub fn team_stats(&self) -> TeamStats {
        self.team.stats()
    }

    /// Number of pairs the last call passed to the narrow phase.
    pub fn pairs_tested(&self) -> usize {
        self.pairs.len()
    }

    /// Detects every contact with a gap at most `alert` (m) between the bodies of shapes `solids` at `poses`,
    /// skipping pairs of fixed bodies (`mobile[i]` false); the result is in [`Self::found`].
    pub fn run<S: Borrow<Solid> + Sync>(&mut self, solids: &[S], poses: &[Pose], mobile: &[bool], alert: f64) {
        assert!(solids.len() == poses.len() && solids.len() == mobile.len(), "one pose and one flag per body");
        let t0 = std::time::Instant::now();
        self.place(solids, poses, alert);
        let t1 = std::time::Instant::now();
        self.find_pairs(mobile, alert);
        let t2 = std::time::Instant::now();
        self.narrow_all(solids, alert);
        let t3 = std::time::Instant::now();
        static SHOW: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        if *SHOW.get_or_init(|| std::env::var_os("DET_TIMES").is_some()) {
            eprintln!("TIMES {} place {:?} pairs {:?} narrow {:?} back {}", self.team.threads(), t1 - t0, t2 - t1, t3 - t2, self.back.blocks.len());
        }
        std::mem::swap(&mut self.memory, &mut self.next_memory);
        debug_assert!(self.found.windows(2).all(|w| w[0].key < w[1].key));
    }

    /// World placement of every body and the boxes of the finite ones: the ranges first (and each
    /// polyhedron's topology from the cache), then the buffers filled.
    fn place<S: Borrow<Solid>>(&mut self, solids: &[S], poses: &[Pose], alert: f64) {
        if self.shapes.len() > MAX_SHAPES {
            self.shapes = Topologies::default();
        }
        self.shape_of.resize(solids.len(), u32::MAX);
        let w = &mut self.world;
        w.placed.clear();
        self.boxes.clear();
        self.finite.clear();
        self.walls.clear();
        let (mut nv, mut nf, mut na) = (0u32, 0u32, 0u32);
        for (i, (solid, pose)) in solids.iter().zip(poses).enumerate() {
            let placed = match solid.borrow() {
                Solid::Polyhedron(p) => {
                    let k = self.shapes.entry(p, self.shape_of[i]);
                    self.shape_of[i] = k;
                    let edges = self.shapes.edges_of(k);
                    let (v, f, a) = (nv, nf, na);
                    nv += p.vertices.len() as u32;
                    nf += p.faces.len() as u32;
                    na += edges.1 - edges.0;
                    let centre = pose.position;
                    Placed::Polyhedron {
                        vertices: (v, nv),
                        faces: (f, nf),
                        edges,
                        arcs: a,
                        centre,
                        radius: 0.0,
                        inradius: 0.0,
                    }
                }
                Solid::Sphere { radius } => Placed::Sphere { centre: pose.position, radius: *radius },
                Solid::HalfSpace => {
                    self.walls.push(i as u32);
                    Placed::Wall(Plane::from_pose(pose))
                }
            };
            w.placed.push(placed);
        }
        w.vertices.resize(nv as usize, Vec3::zeros());
        w.normals.resize(nf as usize, Vec3::zeros());
        w.offsets.resize(nf as usize, 0.0);
        w.arcs.resize(na as usize, Vec3::zeros());
        let half = 0.5 * alert.max(0.0);
        let edges = &self.shapes.edges;
        for (i, ((solid, pose), placed)) in solids.iter().zip(poses).zip(&mut w.placed).enumerate() {
            let (lo, hi) = match (solid.borrow(), placed) {
                (
                    Solid::Polyhedron(p),
                    Placed::Polyhedron { vertices: v, faces: f, edges: e, arcs, radius, inradius, .. },
                ) => {
                    let r = |r: (u32, u32)| r.0 as usize..r.1 as usize;
                    let bounds = place_into(
                        p,
                        pose,
                        &edges[r(*e)],
                        &mut w.vertices[r(*v)],
                        &mut w.normals[r(*f)],
                        &mut w.offsets[r(*f)],
                        &mut w.arcs[*arcs as usize..(*arcs + e.1 - e.0) as usize],
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
            self.finite.push(i as u32);
            self.boxes.push(Aabb3 {
                min: [lo.x - half, lo.y - half, lo.z - half],
                max: [hi.x + half, hi.y + half, hi.z + half],
            });
        }
    }

    /// The (candidate, antagonist) pairs whose enlarged boxes meet, at least one body mobile, sorted: each
    /// finite body's higher neighbours from the grid, merged with the half-spaces its box reaches.
    fn find_pairs(&mut self, mobile: &[bool], alert: f64) {
        let Detector { world, boxes, finite, walls, grid, pairs, around, .. } = self;
        let (finite, walls, boxes) = (&finite[..], &walls[..], &boxes[..]);
        let fixed = |i: usize, j: usize| !mobile[finite[i] as usize] && !mobile[finite[j] as usize];
        let half = 0.5 * alert.max(0.0);
        pairs.clear();
        grid.pairs_with(boxes, fixed, |k, higher| {
            let (b, i) = (&boxes[k as usize], finite[k as usize]);
            // `finite` is increasing, so the lower grid index is the lower body index: the candidate.
            around.clear();
            around.extend(higher.iter().map(|&j| finite[j as usize]));
            let mut next = 0;
            for &w in walls {
                if !mobile[i as usize] && !mobile[w as usize] {
                    continue;
                }
                let Placed::Wall(plane) = world.placed[w as usize] else { unreachable!("walls are half-spaces") };
                // Lowest point of the box along the wall's normal.
                let low: f64 = (0..3)
                    .map(|d| {
                        let (c, e) = (0.5 * (b.min[d] + b.max[d]), 0.5 * (b.max[d] - b.min[d]));
                        plane.normal[d] * (c - plane.point[d]) - plane.normal[d].abs() * e
                    })
                    .sum();
                if low <= half {
                    // Both lists are increasing: the grid's neighbours below this wall first.
                    while next < around.len() && around[next] < w {
                        pairs.push((i, around[next]));
                        next += 1;
                    }
                    pairs.push((i, w));
                }
            }
            pairs.extend(around[next..].iter().map(|&j| (i, j)));
        });
        debug_assert!(pairs.windows(2).all(|w| w[0] < w[1]));
    }

    /// The narrow phase on every pair, the caller taking blocks of pairs from the front and the helper (with
    /// two threads) from the back; the helper's blocks are then appended in order.
    fn narrow_all<S: Borrow<Solid> + Sync>(&mut self, solids: &[S], alert: f64) {
        let Detector { world, shapes, pairs, memory, next_memory, scratch, back, team, found, .. } = self;
        found.clear();
        next_memory.clear();
        back.found.clear();
        back.memory.clear();
        back.blocks.clear();
        let ctx = Ctx { world, edges: &shapes.edges, solids, pairs, memory, alert };
        let claims = Claims::new(pairs.len());
        team.join(|| ctx.front(&claims, found, next_memory, scratch), || ctx.back(&claims, back));
        let ends = (back.found.len(), back.memory.len());
        for (k, &(f0, m0)) in back.blocks.iter().enumerate().rev() {
            let (f1, m1) = back.blocks.get(k + 1).copied().unwrap_or(ends);
            found.extend_from_slice(&back.found[f0..f1]);
            next_memory.extend_from_slice(&back.memory[m0..m1]);
        }
    }
}
