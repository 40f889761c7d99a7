//! NLGS throughput on the settled 536-pentagon pile of `data/`: contact updates
//! per second (one update = one row's local solve and velocity scatter). The
//! problem is the pile's first step restarted cold (`P = 0`, `u = u_free`), so
//! every sweep does real corrections. `sweeps_*`: the plain sweep, one thread;
//! `split_*`: the domain-split solve (`nscd::split`, halves side by side) on one
//! and two threads, 20 sweeps each, its per-step set-up included.

use ballast::nscd::nlgs::{solve_nlgs_split, sweep, NlgsSettings};
use ballast::nscd::split::SplitWorkspace;
use ballast::nscd::Policy;
use ballast::scene::Scene;
use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use std::hint::black_box;

const SWEEPS: usize = 20;

fn bench(c: &mut Criterion) {
    let scene = Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/data/pentagon_pile_536.toml")).unwrap();
    let mut sys = scene.build().unwrap();
    sys.step().unwrap();
    let problem = sys.nlgs_problem();
    let rows = problem.rows.len() + problem.springs.len();
    eprintln!("{} bodies, {} contact rows", sys.bodies.len(), rows);
    let mut g = c.benchmark_group("nlgs");
    g.throughput(Throughput::Elements((rows * SWEEPS) as u64));
    g.bench_function("sweeps_pentagon_pile_536", |b| {
        b.iter_batched_ref(
            || problem.clone(),
            |p| {
                for _ in 0..SWEEPS {
                    black_box(sweep(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs, false));
                }
            },
            BatchSize::LargeInput,
        )
    });
    // Fixed work: 20 sweeps, whatever the norms say.
    let settings = NlgsSettings {
        policy: Policy::Quad,
        tolerance: 0.0,
        min_iterations: SWEEPS,
        max_iterations: SWEEPS,
        ..NlgsSettings::default()
    };
    let q = sys.bodies.q.clone();
    for threads in [1, 2] {
        let mut ws = SplitWorkspace::default();
        g.bench_function(format!("split_{threads}_threads_pentagon_pile_536"), |b| {
            b.iter_batched_ref(
                || problem.clone(),
                |p| {
                    let (u, m, r, s) = (&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
                    black_box(solve_nlgs_split(&settings, &mut ws, threads, &q, u, m, r, s))
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
