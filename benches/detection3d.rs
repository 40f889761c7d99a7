//! 3D contact detection per step (`space::detection::Detector::run`: world placement, grid broad phase,
//! common-plane narrow phase) on two piles of 2028 cuboid grains (13 × 13 × 12 lattice, unit spacing) in a
//! box of five half-space walls, alert distance 1e-2:
//! - `jammed`: grains turned by up to 0.02 rad, each sized to reach 0.5–0.502 from its site in all six
//!   lattice directions, so that every grain presses on its six neighbours (nearly face to face, tilted
//!   faces, small overlaps): about six contacts of up to four points per grain;
//! - `random`: grains of random proportions and orientations reaching 0.5–0.502 in their largest lattice
//!   direction (vertex and edge contacts, many pairs of boxes apart).
//!
//! Throughput is reported per grain. Single thread. Before timing, a counting allocator checks that a call
//! after two warm-up calls allocates nothing.

use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::space::detection::Detector;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{Matrix3, Unit, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The system allocator, counting allocations.
struct Counting;

static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

const ALERT: f64 = 1e-2;
const N: [usize; 3] = [13, 13, 12];

fn turn(rng: &mut ChaCha8Rng, max: f64) -> UnitQuaternion<f64> {
    let axis = Vec3::from_fn(|_, _| rng.random_range(-1.0..1.0));
    UnitQuaternion::from_axis_angle(&Unit::new_normalize(axis), rng.random_range(-max..max))
}

/// The pile: grains on the lattice, then the floor and four side walls (fixed).
fn pile(jammed: bool) -> (Vec<Solid>, Vec<Pose>, Vec<bool>) {
    let mut rng = ChaCha8Rng::seed_from_u64(if jammed { 1 } else { 2 });
    let (mut solids, mut poses, mut mobile) = (Vec::new(), Vec::new(), Vec::new());
    for k in 0..N[2] {
        for j in 0..N[1] {
            for i in 0..N[0] {
                let reach = 0.5 + rng.random_range(0.0..2e-3);
                let (rotation, half) = if jammed {
                    // Half sizes h with |R| h = reach: the rotated box reaches `reach` along ±x, ±y, ±z.
                    let r = turn(&mut rng, 0.02);
                    let m: Matrix3<f64> = r.to_rotation_matrix().matrix().abs();
                    let h = m.try_inverse().unwrap() * Vec3::repeat(reach);
                    (r, [h.x, h.y, h.z])
                } else {
                    let r = turn(&mut rng, std::f64::consts::PI);
                    let h = Vec3::from_fn(|_, _| rng.random_range(0.25..0.5));
                    let m = r.to_rotation_matrix().matrix().abs();
                    let s = reach / (m * h).max();
                    (r, [h.x * s, h.y * s, h.z * s])
                };
                solids.push(Solid::Polyhedron(Polyhedron::cuboid(half).unwrap()));
                poses.push(Pose { position: Vec3::new(i as f64, j as f64, k as f64), rotation });
                mobile.push(true);
            }
        }
    }
    // Floor at z = -0.5 and side walls at the lattice's ends, normals inwards.
    let wall = |point: Vec3, normal: Vec3| Pose {
        position: point,
        rotation: UnitQuaternion::rotation_between(&Vec3::z(), &normal)
            .unwrap_or_else(|| UnitQuaternion::from_axis_angle(&Vec3::x_axis(), std::f64::consts::PI)),
    };
    let (x1, y1) = (N[0] as f64 - 0.5, N[1] as f64 - 0.5);
    for (p, n) in [
        (Vec3::new(0.0, 0.0, -0.5), Vec3::z()),
        (Vec3::new(-0.5, 0.0, 0.0), Vec3::x()),
        (Vec3::new(x1, 0.0, 0.0), -Vec3::x()),
        (Vec3::new(0.0, -0.5, 0.0), Vec3::y()),
        (Vec3::new(0.0, y1, 0.0), -Vec3::y()),
    ] {
        solids.push(Solid::HalfSpace);
        poses.push(wall(p, n));
        mobile.push(false);
    }
    (solids, poses, mobile)
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("detection3d");
    for (name, jammed) in [("jammed_2028", true), ("random_2028", false)] {
        let (solids, poses, mobile) = pile(jammed);
        let grains = mobile.iter().filter(|m| **m).count();
        let mut det = Detector::default();
        det.run(&solids, &poses, &mobile, ALERT);
        let mut pairs: Vec<_> = det.found.iter().map(|f| (f.key.0, f.key.1)).collect();
        pairs.dedup();
        let overlap = det.found.iter().filter(|f| f.gap < 0.0).count();
        // The per-pair memory is double-buffered: the second call warms the other buffer.
        det.run(&solids, &poses, &mobile, ALERT);
        let before = ALLOCATIONS.load(Ordering::Relaxed);
        det.run(&solids, &poses, &mobile, ALERT);
        let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
        assert_eq!(allocations, 0, "a warm call allocates nothing");
        eprintln!(
            "{name}: {grains} grains, {} pairs tested, {} contacts, {} points ({overlap} overlapping), alert {ALERT:e}",
            det.pairs_tested(),
            pairs.len(),
            det.found.len()
        );
        g.throughput(Throughput::Elements(grains as u64));
        g.bench_function(name, |b| b.iter(|| det.run(&solids, &poses, &mobile, ALERT)));
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
