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
//! vector sorted by pair, walked alongside the sorted pairs; it is only a cheap first test (see
//! [`super::axis`]), so the result of a call does not depend on the previous calls. Once the buffers have
//! grown, a call allocates nothing.
//!
//! With two threads ([`Detector::set_threads`]) the placement and the narrow phase are shared with the
//! helper of a [`Team`] (`share`: blocks of pairs taken from both ends; `place`: blocks of bodies); the
//! contacts are the same, bit for bit, on one thread or two.

mod place;
mod share;

use super::broad::{Aabb3, Broad3};
use super::narrow::Scratch;
use super::placed::{Plane, Topologies};
use super::FaceGaps;
use crate::geometry::{Pose, Solid, Vec3};
use crate::team::{Team, TeamStats};
use place::{PlaceBlock, PLACE_BLOCKS, PLACE_MIN};
use share::{Claims, Ctx, Part, JOIN_PAIRS, MIN_BLOCK};
use std::borrow::Borrow;
use std::sync::Mutex;
use std::time::{Duration, Instant};

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

/// How long the phases of a [`Detector::run`] took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Times {
    /// Placement of the shapes in the world and their boxes.
    pub placement: Duration,
    /// The pairs: the broad phase and the half-spaces.
    pub pairs: Duration,
    /// The narrow phase on every pair.
    pub narrow: Duration,
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
    /// The walls' planes and mobility, for the pairs.
    walls_here: Vec<(u32, Plane, bool)>,
    broad: Broad3,
    /// (candidate, antagonist) pairs to test, sorted.
    pairs: Vec<(u32, u32)>,
    /// The higher neighbours of one body.
    around: Vec<u32>,
    memory: Memory,
    next_memory: Memory,
    /// The face–face gap rule of polyhedron pairs.
    face_gaps: FaceGaps,
    /// The caller's polygon buffers.
    scratch: Scratch,
    /// The helper's share (in its own allocation, see [`Ctx`]).
    back: Box<Part>,
    team: Team,
    times: Times,
    /// Contacts found by the last call, sorted by key.
    pub found: Vec<Found>,
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

    /// Sets the face–face gap rule of polyhedron pairs ([`FaceGaps::Exact`] by default).
    pub fn set_face_gaps(&mut self, face_gaps: FaceGaps) {
        self.face_gaps = face_gaps;
    }

    /// Threads of the narrow phase (1 or 2).
    pub fn threads(&self) -> usize {
        self.team.threads()
    }

    /// What the team's joins did so far (all zero on one thread).
    pub fn team_stats(&self) -> TeamStats {
        self.team.stats()
    }

    /// How long the phases of the last call took.
    pub fn times(&self) -> Times {
        self.times
    }

    /// Number of pairs the last call passed to the narrow phase.
    pub fn pairs_tested(&self) -> usize {
        self.pairs.len()
    }

    /// Detects every contact with a gap at most `alert` (m) between the bodies of shapes `solids` at `poses`,
    /// skipping pairs of fixed bodies (`mobile[i]` false); the result is in [`Self::found`].
    pub fn run<S: Borrow<Solid> + Sync>(&mut self, solids: &[S], poses: &[Pose], mobile: &[bool], alert: f64) {
        assert!(solids.len() == poses.len() && solids.len() == mobile.len(), "one pose and one flag per body");
        let start = Instant::now();
        self.place(solids, poses, alert);
        let placed = Instant::now();
        self.find_pairs(mobile, alert);
        let paired = Instant::now();
        self.narrow_all(solids, alert);
        self.times = Times { placement: placed - start, pairs: paired - placed, narrow: paired.elapsed() };
        std::mem::swap(&mut self.memory, &mut self.next_memory);
        debug_assert!(self.found.windows(2).all(|w| w[0].key < w[1].key));
    }

    /// World placement of every body and the boxes of the finite ones: the ranges first (and each
    /// polyhedron's topology from the cache), then the buffers filled.
    fn place<S: Borrow<Solid> + Sync>(&mut self, solids: &[S], poses: &[Pose], alert: f64) {
        if self.shapes.len() > MAX_SHAPES {
            self.shapes = Topologies::default();
        }
        self.shape_of.resize(solids.len(), u32::MAX);
        let w = &mut self.world;
        w.placed.clear();
        self.finite.clear();
        self.walls.clear();
        // Bodies per block of the placement (at most PLACE_BLOCKS blocks), and where each block starts in
        // the buffers: vertices, faces, arcs, finite bodies.
        let n = solids.len();
        let per = n.div_ceil(PLACE_BLOCKS).max(PLACE_MIN);
        let mut starts = [(0u32, 0u32, 0u32, 0u32); PLACE_BLOCKS + 1];
        let (mut nv, mut nf, mut na) = (0u32, 0u32, 0u32);
        for (i, (solid, pose)) in solids.iter().zip(poses).enumerate() {
            if i % per == 0 {
                starts[i / per] = (nv, nf, na, self.finite.len() as u32);
            }
            let placed = match solid.borrow() {
                Solid::Polyhedron(p) => {
                    let k = self.shapes.entry(p, self.shape_of[i]);
                    self.shape_of[i] = k;
                    let edges = self.shapes.edges_of(k);
                    let (v, f, a) = (nv, nf, na);
                    nv += p.vertices.len() as u32;
                    nf += p.faces.len() as u32;
                    na += edges.1 - edges.0;
                    self.finite.push(i as u32);
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
                Solid::Sphere { radius } => {
                    self.finite.push(i as u32);
                    Placed::Sphere { centre: pose.position, radius: *radius }
                }
                Solid::HalfSpace => {
                    self.walls.push(i as u32);
                    Placed::Wall(Plane::from_pose(pose))
                }
            };
            w.placed.push(placed);
        }
        let blocks = n.div_ceil(per);
        starts[blocks] = (nv, nf, na, self.finite.len() as u32);
        w.vertices.resize(nv as usize, Vec3::zeros());
        w.normals.resize(nf as usize, Vec3::zeros());
        w.offsets.resize(nf as usize, 0.0);
        w.arcs.resize(na as usize, Vec3::zeros());
        self.boxes.resize(self.finite.len(), Aabb3::default());
        // The buffers cut in blocks, each handed whole to one thread.
        let cells: [Mutex<Option<PlaceBlock>>; PLACE_BLOCKS] = std::array::from_fn(|_| Mutex::new(None));
        let (mut placed, mut vertices, mut normals) = (&mut w.placed[..], &mut w.vertices[..], &mut w.normals[..]);
        let (mut offsets, mut arcs, mut boxes) = (&mut w.offsets[..], &mut w.arcs[..], &mut self.boxes[..]);
        for (k, cell) in cells.iter().enumerate().take(blocks) {
            let (s, e) = (starts[k], starts[k + 1]);
            let body = k * per;
            macro_rules! cut {
                ($buf:ident, $len:expr) => {{
                    let (here, rest) = std::mem::take(&mut $buf).split_at_mut($len as usize);
                    $buf = rest;
                    here
                }};
            }
            let block = PlaceBlock {
                first: body,
                base: s,
                placed: cut!(placed, (n - body).min(per)),
                vertices: cut!(vertices, e.0 - s.0),
                normals: cut!(normals, e.1 - s.1),
                offsets: cut!(offsets, e.1 - s.1),
                arcs: cut!(arcs, e.2 - s.2),
                boxes: cut!(boxes, e.3 - s.3),
            };
            *cell.lock().unwrap_or_else(std::sync::PoisonError::into_inner) = Some(block);
        }
        let claims = Claims::new(0, blocks);
        let (edges, half) = (&self.shapes.edges[..], 0.5 * alert.max(0.0));
        let work = |front: bool| {
            while let Some(r) = claims.take_one(front) {
                let block = cells[r].lock().unwrap_or_else(std::sync::PoisonError::into_inner).take();
                if let Some(block) = block {
                    block.fill(solids, poses, edges, half);
                }
            }
        };
        self.team.join(|| work(true), || work(false));
    }

    /// The (candidate, antagonist) pairs whose enlarged boxes meet, at least one body mobile, sorted: each
    /// finite body's higher neighbours from the grid, merged with the half-spaces its box reaches.
    fn find_pairs(&mut self, mobile: &[bool], alert: f64) {
        let Detector { world, boxes, finite, walls, walls_here, broad, pairs, around, .. } = self;
        let (finite, boxes) = (&finite[..], &boxes[..]);
        walls_here.clear();
        walls_here.extend(walls.iter().map(|&w| {
            let Placed::Wall(plane) = world.placed[w as usize] else { unreachable!("walls are half-spaces") };
            (w, plane, mobile[w as usize])
        }));
        let fixed = |i: usize, j: usize| !mobile[finite[i] as usize] && !mobile[finite[j] as usize];
        let half = 0.5 * alert.max(0.0);
        pairs.clear();
        // The Verlet list's margin: a twentieth of the mean box (grains moving less than that from one grid
        // run to the next use the list).
        let margin = 0.05 * boxes.iter().map(|b| (0..3).map(|d| b.max[d] - b.min[d]).fold(0.0, f64::max)).sum::<f64>()
            / boxes.len().max(1) as f64;
        broad.pairs_with(boxes, margin, fixed, |k, higher| {
            let (b, i) = (&boxes[k as usize], finite[k as usize]);
            // `finite` is increasing, so the lower grid index is the lower body index: the candidate.
            around.clear();
            around.extend(higher.iter().map(|&j| finite[j as usize]));
            let mut next = 0;
            // The box's centre and half extents, for every wall.
            let c: [f64; 3] = std::array::from_fn(|d| 0.5 * (b.min[d] + b.max[d]));
            let e: [f64; 3] = std::array::from_fn(|d| 0.5 * (b.max[d] - b.min[d]));
            for &(w, ref plane, wall_mobile) in walls_here.iter() {
                if !mobile[i as usize] && !wall_mobile {
                    continue;
                }
                // Lowest point of the box along the wall's normal.
                let low: f64 =
                    (0..3).map(|d| plane.normal[d] * (c[d] - plane.point[d]) - plane.normal[d].abs() * e[d]).sum();
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

    /// The narrow phase on every pair, in joins of the team of about [`JOIN_PAIRS`] pairs each: in a join the
    /// caller takes blocks of pairs from the front and the helper (with two threads) from the back, and the
    /// helper's blocks are then appended in order.
    fn narrow_all<S: Borrow<Solid> + Sync>(&mut self, solids: &[S], alert: f64) {
        let Detector { world, shapes, pairs, memory, next_memory, face_gaps, scratch, back, team, found, .. } = self;
        let ctx = Ctx {
            placed: &world.placed,
            vertices: &world.vertices,
            normals: &world.normals,
            offsets: &world.offsets,
            arcs: &world.arcs,
            edges: &shapes.edges,
            solids,
            pairs,
            memory,
            alert,
            face_gaps: *face_gaps,
        };
        // The caller's outputs on its own stack while the helper runs (see `Ctx`).
        let (mut found_here, mut memory_here) = (std::mem::take(found), std::mem::take(next_memory));
        let (found, next_memory) = (&mut found_here, &mut memory_here);
        found.clear();
        next_memory.clear();
        let n = pairs.len();
        let joins = n.div_ceil(JOIN_PAIRS).max(1);
        // The helper may take any share of the pairs: its buffers hold them all, so that a warm call does
        // not allocate whatever the share.
        back.found.clear();
        back.found.reserve(found.capacity());
        back.memory.clear();
        back.memory.reserve(n);
        back.blocks.clear();
        back.blocks.reserve(JOIN_PAIRS / MIN_BLOCK as usize + 1);
        // The caller's blocks follow each other from join to join: the memory is walked once alongside.
        let mut cursor = 0;
        for k in 0..joins {
            let claims = Claims::new(k * n / joins, (k + 1) * n / joins);
            back.found.clear();
            back.memory.clear();
            back.blocks.clear();
            team.join(|| ctx.front(&claims, &mut cursor, found, next_memory, scratch), || ctx.back(&claims, back));
            let ends = (back.found.len(), back.memory.len());
            for (k, &(f0, m0)) in back.blocks.iter().enumerate().rev() {
                let (f1, m1) = back.blocks.get(k + 1).copied().unwrap_or(ends);
                found.extend_from_slice(&back.found[f0..f1]);
                next_memory.extend_from_slice(&back.memory[m0..m1]);
            }
        }
        (self.found, self.next_memory) = (found_here, memory_here);
    }
}
