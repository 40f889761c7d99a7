//! Two threads are never much slower than one, even beside a busy thread, and
//! give the same numbers (issue 31).
//!
//! The two-thread team (`ballast::team`) used to make the caller wait for its
//! helper however long the helper was off its core: beside one busy thread on
//! this 2-core machine, two threads took 1.7× the one-thread time (the loaded
//! 536 pile, 7.5 s against 12.5 s). Now the caller takes back a half the helper
//! has not started, and the team times both modes and runs in turn when two
//! threads lose (`src/team/choice.rs`); `examples/threads.rs` measured 1.00–1.02×
//! beside a busy process (BENCHMARKS.md, "Two threads never cost more than one").
//!
//! The test runs the loaded pile (split NLGS sweeps) and a 2000-sphere MD bed
//! (the force loop) on one thread and on two, alternately, twice each, with a
//! thread of this process spinning the whole time, and checks the best
//! two-thread time against the best one-thread time with a margin of 1.5: the
//! defect gave 1.7, a correct team 1.0–1.1, and the margin leaves room for a
//! shared CI machine without letting a team that waits for a descheduled helper
//! through (the team before this fix failed it at 1.74 on the loaded pile).
//! (The idle speed-up is a measurement, not a test: BENCHMARKS.md.)
//! One test function, so that nothing else of this binary runs meanwhile.

use ballast::md::MdSystem;
use ballast::nscd::System;
use ballast::scenarios::md_bed::{bed_system, BedSpec};
use ballast::scenarios::saussine::{loaded_scene, LoadingSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// Wall time of `steps` steps from `start` on `threads` threads, and the final
/// state's bits.
fn run<S: Clone>(
    start: &S,
    threads: usize,
    steps: usize,
    set: impl Fn(&mut S, usize),
    step: impl Fn(&mut S),
    bits: impl Fn(&S) -> Vec<u64>,
) -> (f64, Vec<u64>) {
    let mut s = start.clone();
    set(&mut s, threads);
    let t = Instant::now();
    for _ in 0..steps {
        step(&mut s);
    }
    (t.elapsed().as_secs_f64(), bits(&s))
}

fn nscd_bits(s: &System) -> Vec<u64> {
    s.bodies.q.iter().chain(&s.bodies.u).flatten().map(|x| x.to_bits()).collect()
}

fn md_bits(s: &MdSystem) -> Vec<u64> {
    s.particles.x.iter().chain(&s.particles.v).flat_map(|v| [v.x, v.y, v.z]).map(f64::to_bits).collect()
}

/// One then two threads, twice, beside `busy`: the best of each.
fn compare<S: Clone>(
    name: &str,
    start: &S,
    steps: usize,
    set: impl Fn(&mut S, usize) + Copy,
    step: impl Fn(&mut S) + Copy,
    bits: impl Fn(&S) -> Vec<u64> + Copy,
) {
    let (mut one, mut two) = (f64::INFINITY, f64::INFINITY);
    for _ in 0..2 {
        let (t1, b1) = run(start, 1, steps, set, step, bits);
        let (t2, b2) = run(start, 2, steps, set, step, bits);
        assert!(b1 == b2, "{name}: two threads changed the numbers");
        one = one.min(t1);
        two = two.min(t2);
    }
    eprintln!("{name}: beside a busy thread, 1 thread {one:.3} s, 2 threads {two:.3} s ({:.2})", two / one);
    assert!(two <= 1.5 * one, "{name}: two threads took {two:.3} s beside a busy thread, one {one:.3} s");
}

#[test]
fn two_threads_beside_a_busy_thread_cost_at_most_one_and_a_half() {
    // The loading takes the grains of the material named `ballast`.
    let pile = include_str!("../data/pentagon_pile_536.toml").replace("\"grain\"", "\"ballast\"");
    let pile = Scene::from_toml_str(&pile).unwrap();
    let loaded = loaded_scene(&pile, &LoadingSpec::saussine(2)).unwrap().build().unwrap();
    let bed = bed_system(&BedSpec::peers(2000, 12345)).unwrap();
    let stop = AtomicBool::new(false);
    /// Stops the busy thread when dropped, also when an assertion fails (else
    /// the scope would wait for it forever).
    struct Stop<'a>(&'a AtomicBool);
    impl Drop for Stop<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Relaxed);
        }
    }
    std::thread::scope(|s| {
        s.spawn(|| {
            while !stop.load(Ordering::Relaxed) {
                std::hint::spin_loop();
            }
        });
        let _stop = Stop(&stop);
        // About 0.7 and 0.3 s per run on one thread (the test profile is optimised).
        compare(
            "loaded 536 pile, 100 steps",
            &loaded,
            100,
            System::set_threads,
            |s| {
                s.step().unwrap();
            },
            nscd_bits,
        );
        compare(
            "2000-sphere bed, 5000 steps",
            &bed,
            5000,
            MdSystem::set_threads,
            |s| {
                s.step().unwrap();
            },
            md_bits,
        );
    });
}
