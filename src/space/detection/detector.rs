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
    polyhedron_half_space, polyhedron_polyhedron_axis, polyhedron_sphere, sphere_half_space, sphere_polyhedron,
    sphere_sphere,
};
use super::placed::{place, Edge3, Plane, PolyhedronView};
use super::Manifold;
use crate::geometry::{Pose, Solid, Vec3};
use std::borrow::Borrow;

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

/// A body placed in the world: ranges in the detector's buffers for a polyhedron.
#[derive(Debug, Clone, Copy)]
enum Placed {
    Polyhedron { vertices: (u32, u32), faces: (u32, u32), edges: (u32, u32), centre: Vec3, radius: f64, inradius: f64 },
    Sphere { centre: Vec3, radius: f64 },
    Wall(Plane),
}

/// Reused detection buffers and the per-pair memory of the normal.
#[derive(Debug, Clone, Default)]
pub struct Detector {
    placed: Vec<Placed>,
    vertices: Vec<Vec3>,
    normals: Vec<Vec3>,
    offsets: Vec<f64>,
    edges: Vec<Edge3>,
    arcs: Vec<Vec3>,
    scratch: Vec<(u32, u32, u32)>,
    /// Boxes of the finite bodies (enlarged by half the alert distance each), and their body indices.
    boxes: Vec<Aabb3>,
    finite: Vec<u32>,
    walls: Vec<u32>,
    grid: Grid3,
    grid_pairs: Vec<(u32, u32)>,
    /// (candidate, antagonist) pairs to test, sorted.
    pairs: Vec<(u32, u32)>,
    memory: Vec<((u32, u32), Vec3)>,
    next_memory: Vec<((u32, u32), Vec3)>,
    /// Contacts found by the last call, sorted by key.
    pub found: Vec<Found>,
}

impl Detector {
    /// Number of pairs the last call passed to the narrow phase.
    pub fn pairs_tested(&self) -> usize {
        self.pairs.len()
    }

    /// Detects every contact with a gap at most `alert` (m) between the bodies of shapes `solids` at `poses`,
    /// skipping pairs of fixed bodies (`mobile[i]` false); the result is in [`Self::found`].
    pub fn run<S: Borrow<Solid>>(&mut self, solids: &[S], poses: &[Pose], mobile: &[bool], alert: f64) {
        assert!(solids.len() == poses.len() && solids.len() == mobile.len(), "one pose and one flag per body");
        self.place(solids, poses, alert);
        self.find_pairs(mobile, alert);
        self.found.clear();
        self.next_memory.clear();
        // Both the pairs and the memory are sorted: the memory is walked once alongside.
        let mut cursor = 0;
        for k in 0..self.pairs.len() {
            let (i, j) = self.pairs[k];
            while cursor < self.memory.len() && self.memory[cursor].0 < (i, j) {
                cursor += 1;
            }
            let hint = (cursor < self.memory.len() && self.memory[cursor].0 == (i, j)).then_some(cursor);
            let m = self.narrow(solids, i, j, alert, hint);
            if let Some(m) = m {
                for (p, q) in m.points().iter().enumerate() {
                    self.found.push(Found {
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
        std::mem::swap(&mut self.memory, &mut self.next_memory);
        debug_assert!(self.found.windows(2).all(|w| w[0].key < w[1].key));
    }

    /// World placement of every body and the boxes of the finite ones.
    fn place<S: Borrow<Solid>>(&mut self, solids: &[S], poses: &[Pose], alert: f64) {
        self.placed.clear();
        self.vertices.clear();
        self.normals.clear();
        self.offsets.clear();
        self.edges.clear();
        self.arcs.clear();
        self.boxes.clear();
        self.finite.clear();
        self.walls.clear();
        let half = 0.5 * alert.max(0.0);
        for (i, (solid, pose)) in solids.iter().zip(poses).enumerate() {
            let (placed, bounds) = match solid.borrow() {
                Solid::Polyhedron(p) => {
                    let (v0, f0, e0) = (self.vertices.len() as u32, self.normals.len() as u32, self.edges.len() as u32);
                    let bounds = place(
                        p,
                        pose,
                        &mut self.scratch,
                        &mut self.vertices,
                        &mut self.normals,
                        &mut self.offsets,
                        &mut self.edges,
                        &mut self.arcs,
                    );
                    let (v1, f1, e1) = (self.vertices.len() as u32, self.normals.len() as u32, self.edges.len() as u32);
                    let placed = Placed::Polyhedron {
                        vertices: (v0, v1),
                        faces: (f0, f1),
                        edges: (e0, e1),
                        centre: pose.position,
                        radius: bounds.radius,
                        inradius: bounds.inradius,
                    };
                    (placed, Some((bounds.lo, bounds.hi)))
                }
                Solid::Sphere { radius } => {
                    let r = Vec3::repeat(*radius);
                    (
                        Placed::Sphere { centre: pose.position, radius: *radius },
                        Some((pose.position - r, pose.position + r)),
                    )
                }
                Solid::HalfSpace => (Placed::Wall(Plane::from_pose(pose)), None),
            };
            self.placed.push(placed);
            match bounds {
                Some((lo, hi)) => {
                    self.finite.push(i as u32);
                    self.boxes.push(Aabb3 {
                        min: [lo.x - half, lo.y - half, lo.z - half],
                        max: [hi.x + half, hi.y + half, hi.z + half],
                    });
                }
                None => self.walls.push(i as u32),
            }
        }
    }

    /// The (candidate, antagonist) pairs whose enlarged boxes meet, at least one body mobile, sorted.
    fn find_pairs(&mut self, mobile: &[bool], alert: f64) {
        let finite = &self.finite;
        let fixed = |i: usize, j: usize| !mobile[finite[i] as usize] && !mobile[finite[j] as usize];
        self.grid.pairs(&self.boxes, fixed, &mut self.grid_pairs);
        self.pairs.clear();
        // `finite` is increasing, so the lower grid index is the lower body index: the candidate.
        self.pairs.extend(self.grid_pairs.iter().map(|&(i, j)| (finite[i as usize], finite[j as usize])));
        let half = 0.5 * alert.max(0.0);
        for &w in &self.walls {
            let Placed::Wall(plane) = self.placed[w as usize] else { unreachable!("walls are half-spaces") };
            for (b, &i) in self.boxes.iter().zip(&self.finite) {
                if !mobile[i as usize] && !mobile[w as usize] {
                    continue;
                }
                // Lowest point of the box along the wall's normal.
                let low: f64 = (0..3)
                    .map(|d| {
                        let (c, e) = (0.5 * (b.min[d] + b.max[d]), 0.5 * (b.max[d] - b.min[d]));
                        plane.normal[d] * (c - plane.point[d]) - plane.normal[d].abs() * e
                    })
                    .sum();
                if low <= half {
                    self.pairs.push((i, w));
                }
            }
        }
        self.pairs.sort_unstable();
    }

    fn view<'s, S: Borrow<Solid>>(&'s self, solids: &'s [S], k: u32) -> Option<PolyhedronView<'s>> {
        match (self.placed[k as usize], solids[k as usize].borrow()) {
            (
                Placed::Polyhedron { vertices: v, faces: f, edges: e, centre, radius, inradius },
                Solid::Polyhedron(p),
            ) => {
                let r = |r: (u32, u32)| r.0 as usize..r.1 as usize;
                Some(PolyhedronView {
                    vertices: &self.vertices[r(v)],
                    normals: &self.normals[r(f)],
                    offsets: &self.offsets[r(f)],
                    faces: &p.faces,
                    edges: &self.edges[r(e)],
                    arcs: &self.arcs[r(e)],
                    centre,
                    radius,
                    inradius,
                })
            }
            _ => None,
        }
    }

    /// The narrow phase on candidate `i` and antagonist `j`; `memory` is where the pair's last normal is.
    fn narrow<S: Borrow<Solid>>(
        &mut self,
        solids: &[S],
        i: u32,
        j: u32,
        alert: f64,
        memory: Option<usize>,
    ) -> Option<Manifold> {
        match (self.placed[i as usize], self.placed[j as usize]) {
            (Placed::Polyhedron { .. }, Placed::Polyhedron { .. }) => {
                let (a, b) = (self.view(solids, i)?, self.view(solids, j)?);
                let hint = memory.map(|k| &self.memory[k].1);
                let (m, axis) = polyhedron_polyhedron_axis(&a, &b, alert, hint);
                self.next_memory.push(((i, j), axis));
                m
            }
            (Placed::Polyhedron { .. }, Placed::Sphere { centre, radius }) => {
                polyhedron_sphere(&self.view(solids, i)?, &centre, radius, alert)
            }
            (Placed::Sphere { centre, radius }, Placed::Polyhedron { .. }) => {
                sphere_polyhedron(&centre, radius, &self.view(solids, j)?, alert)
            }
            (Placed::Sphere { centre: ca, radius: ra }, Placed::Sphere { centre: cb, radius: rb }) => {
                sphere_sphere(&ca, ra, &cb, rb, alert)
            }
            (Placed::Polyhedron { .. }, Placed::Wall(w)) => polyhedron_half_space(&self.view(solids, i)?, &w, alert),
            (Placed::Sphere { centre, radius }, Placed::Wall(w)) => sphere_half_space(&centre, radius, &w, alert),
            (Placed::Wall(_), _) => unreachable!("a half-space is never the candidate"),
        }
    }
}
