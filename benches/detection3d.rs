//! 3D contact detection per step (`space::detection::Detector::run`: world placement, grid broad phase,
//! common-plane narrow phase) on two piles of 2028 cuboid grains (13 × 13 × 12 lattice, unit spacing) in a
//! box of five half-space walls, alert distance 1e-2:
//! - `jammed`: grains turned by up to 0.02 rad, each sized to reach 0.5–0.502 from its site in all six
//!   lattice directions, so that every grain presses on its six neighbours (nearly face to face, tilted
//!   faces, small overlaps): about six contacts of up to four points per grain;
//! - `random`: grains of random proportions and orientations reaching 0.5–0.502 in their largest lattice
//!   direction (vertex and edge contacts, many pairs of boxes apart).
//!
//! Each pile is detected on one thread and on two ([`Detector::set_threads`]); before timing, a counting
//! allocator checks that a call after two warm-up calls allocates nothing, and the two detectors' contacts
//! are compared bit for bit. Then the two are timed side by side: rounds of a few calls of one, then of the
//! other, alternating, so that both see the same machine (idle, or a busy process on the other core: run
//! `while :; do :; done &` beside it), and the medians and their ratio are printed; criterion then times each
//! on its own. Throughput is reported per grain.

use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::space::detection::Detector;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nalgebra::{Matrix3, Unit, UnitQuaternion};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

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

/// Bits of every contact, to compare two detectors.
fn bits(det: &Detector) -> Vec<[u64; 16]> {
    det.found
        .iter()
        .map(|f| {
            let mut b = [0u64; 16];
            (b[0], b[1], b[2]) = (f.key.0.into(), f.key.1.into(), f.key.2.into());
            for (k, v) in [f.position, f.normal, f.t1, f.t2].iter().enumerate() {
                for d in 0..3 {
                    b[3 + 3 * k + d] = v[d].to_bits();
                }
            }
            b[15] = f.gap.to_bits();
            b
        })
        .collect()
}

fn median(x: &mut [f64]) -> f64 {
    x.sort_by(f64::total_cmp);
    x[x.len() / 2]
}

/// With `DETECTION3D_PROFILE=jammed` (or `random`): only calls on one detector, for a profiler (`perf stat`,
/// `perf record`) or a comparison between builds, then exit: `DETECTION3D_CALLS=n` calls (default 200), or
/// calls for `DETECTION3D_SECONDS=s` if given, on `DETECTION3D_THREADS` threads (default 1), after three
/// warm-up calls. Prints the median, mean and fastest call, the mean of each phase, the team's joins and a
/// hash of the last call's contacts.
fn profile() -> bool {
    let Some(which) = std::env::var_os("DETECTION3D_PROFILE") else { return false };
    let var = |key: &str| std::env::var(key).ok();
    let calls: usize = var("DETECTION3D_CALLS").and_then(|v| v.parse().ok()).unwrap_or(200);
    let seconds: Option<f64> = var("DETECTION3D_SECONDS").and_then(|v| v.parse().ok());
    let threads: usize = var("DETECTION3D_THREADS").and_then(|v| v.parse().ok()).unwrap_or(1);
    let (solids, poses, mobile) = pile(which != "random");
    let mut det = Detector::with_threads(threads);
    for _ in 0..3 {
        det.run(&solids, &poses, &mobile, ALERT);
    }
    let stats0 = det.team_stats();
    let (start, mut times, mut phases) = (Instant::now(), Vec::new(), [0.0; 3]);
    while seconds.map_or(times.len() < calls, |s| start.elapsed().as_secs_f64() < s) {
        let t = Instant::now();
        det.run(&solids, &poses, &mobile, ALERT);
        times.push(1e3 * t.elapsed().as_secs_f64());
        let d = det.times();
        for (p, d) in phases.iter_mut().zip([d.placement, d.pairs, d.narrow]) {
            *p += d.as_secs_f64() * 1e3;
        }
    }
    let n = times.len() as f64;
    let mean = times.iter().sum::<f64>() / n;
    let fastest = times.iter().copied().fold(f64::INFINITY, f64::min);
    let stats = det.team_stats();
    let digest =
        bits(&det).iter().flatten().fold(0xcbf2_9ce4_8422_2325u64, |h, &x| (h ^ x).wrapping_mul(0x0100_0000_01b3));
    eprintln!(
        "{which:?} on {threads} thread(s), {} calls: median {:.3} ms, mean {mean:.3}, fastest {fastest:.3}; \
         placement {:.3} + pairs {:.3} + narrow {:.3} ms; joins: {} on the helper, {} taken back, {} in turn \
         ({} trials, {} switches); contacts {} hash {digest:016x}",
        times.len(),
        median(&mut times),
        phases[0] / n,
        phases[1] / n,
        phases[2] / n,
        stats.on_helper - stats0.on_helper,
        stats.taken_back - stats0.taken_back,
        stats.in_turn - stats0.in_turn,
        stats.trials - stats0.trials,
        stats.switches - stats0.switches,
        det.found.len(),
    );
    true
}

fn bench(c: &mut Criterion) {
    if profile() {
        return;
    }
    let mut g = c.benchmark_group("detection3d");
    for (name, jammed) in [("jammed_2028", true), ("random_2028", false)] {
        let (solids, poses, mobile) = pile(jammed);
        let grains = mobile.iter().filter(|m| **m).count();
        let mut dets = [Detector::with_threads(1), Detector::with_threads(2)];
        for det in &mut dets {
            // The per-pair memory is double-buffered: the second call warms the other buffer. (Both
            // detectors warmed before either is counted: the counter sees every thread, and the helper
            // thread allocates as it starts.)
            det.run(&solids, &poses, &mobile, ALERT);
            det.run(&solids, &poses, &mobile, ALERT);
        }
        for det in &mut dets {
            let before = ALLOCATIONS.load(Ordering::Relaxed);
            det.run(&solids, &poses, &mobile, ALERT);
            let allocations = ALLOCATIONS.load(Ordering::Relaxed) - before;
            assert_eq!(allocations, 0, "a warm call allocates nothing ({} threads)", det.threads());
        }
        assert!(bits(&dets[0]) == bits(&dets[1]), "the same contacts on one thread and two");
        let det = &dets[0];
        let mut pairs: Vec<_> = det.found.iter().map(|f| (f.key.0, f.key.1)).collect();
        pairs.dedup();
        let overlap = det.found.iter().filter(|f| f.gap < 0.0).count();
        eprintln!(
            "{name}: {grains} grains, {} pairs tested, {} contacts, {} points ({overlap} overlapping), alert {ALERT:e}",
            det.pairs_tested(),
            pairs.len(),
            det.found.len()
        );
        // Side by side: rounds of a few calls (20 ms) of one detector then of the other, for 3 s first (the
        // two-thread team's trials of its two modes, frequent at first, are then 2.5 s apart), then 4 s timed.
        let once = {
            let t = Instant::now();
            dets[0].run(&solids, &poses, &mobile, ALERT);
            t.elapsed().as_secs_f64()
        };
        let calls = ((0.02 / once).ceil() as usize).max(1);
        let rounds = |seconds: f64| ((seconds / (2.0 * calls as f64 * once)) as usize).clamp(10, 2000);
        // Per detector: the time of each round's calls, and the phases' times summed over the calls.
        let round = |dets: &mut [Detector; 2], times: &mut [Vec<f64>; 2], phases: &mut [[f64; 3]; 2]| {
            for ((det, t), p) in dets.iter_mut().zip(times).zip(phases) {
                let start = Instant::now();
                for _ in 0..calls {
                    det.run(&solids, &poses, &mobile, ALERT);
                    let d = det.times();
                    for (p, d) in p.iter_mut().zip([d.placement, d.pairs, d.narrow]) {
                        *p += d.as_secs_f64();
                    }
                }
                t.push(start.elapsed().as_secs_f64() / calls as f64);
            }
        };
        let (mut times, mut phases) = ([Vec::new(), Vec::new()], [[0.0; 3]; 2]);
        for _ in 0..rounds(3.0) {
            round(&mut dets, &mut times, &mut phases);
        }
        let (stats0, rounds) = (dets[1].team_stats(), rounds(4.0));
        (times, phases) = ([Vec::new(), Vec::new()], [[0.0; 3]; 2]);
        for _ in 0..rounds {
            round(&mut dets, &mut times, &mut phases);
        }
        let stats = dets[1].team_stats();
        let mean = times.each_ref().map(|t| t.iter().sum::<f64>() / t.len() as f64);
        let [t1, t2] = times.map(|mut t| median(&mut t));
        let per_call = (rounds * calls) as f64 / 1e3;
        let phase = |p: &[f64; 3]| format!("{:.3} + {:.3} + {:.3}", p[0] / per_call, p[1] / per_call, p[2] / per_call);
        eprintln!(
            "{name}: side by side ({rounds} rounds of {calls} calls each), median (mean): 1 thread {:.3} ({:.3}) ms, \
             2 threads {:.3} ({:.3}) ms, ratio {:.2} ({:.2}); placement + pairs + narrow (ms, mean): {} and {}; \
             2 threads' joins: {} on the helper, {} taken back, {} in turn ({} trials, {} switches)",
            1e3 * t1,
            1e3 * mean[0],
            1e3 * t2,
            1e3 * mean[1],
            t2 / t1,
            mean[1] / mean[0],
            phase(&phases[0]),
            phase(&phases[1]),
            stats.on_helper - stats0.on_helper,
            stats.taken_back - stats0.taken_back,
            stats.in_turn - stats0.in_turn,
            stats.trials - stats0.trials,
            stats.switches - stats0.switches,
        );
        g.throughput(Throughput::Elements(grains as u64));
        for det in &mut dets {
            let id = format!("{name}/{}", det.threads());
            g.bench_function(id, |b| b.iter(|| det.run(&solids, &poses, &mobile, ALERT)));
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
