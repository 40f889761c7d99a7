//! NLGS throughput on the settled 536-pentagon pile of `data/`: contact updates
//! per second (one update = one row's local solve and velocity scatter). The
//! problem is the pile's first step restarted cold (`P = 0`, `u = u_free`), so
//! every sweep does real corrections. `sweeps_*`: the plain sweep, one thread;
//! `split_*`: the domain-split solve (`nscd::split`, halves side by side) on one
//! and two threads, 20 sweeps each, its per-step set-up included.
//!
//! `converged_*` (issue 31): one problem of the same pile under the Saussine sleeper
//! load (`saussine load --cycles 2`, step 100 of the default run, restarted cold)
//! solved to `quad` 1e-6 by NLGS and by the interior point of `nscd::interior` alone,
//! and by NLGS to the default `energy` 1.66e-5 (the time a converged solve is to match).

use ballast::nscd::interior::{solve_interior, InteriorOptions, InteriorWorkspace};
use ballast::nscd::nlgs::{solve_nlgs, solve_nlgs_split, sweep, NlgsSettings, SplitWorkspace};
use ballast::nscd::{Measure, Policy};
use ballast::scenarios::saussine::{loaded_scene, LoadingSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
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
                    black_box(solve_nlgs_split(&settings, &mut ws, threads, |i| q[i][0], u, m, r, s))
                },
                BatchSize::LargeInput,
            )
        });
    }
    g.finish();
    converged(c);
}

fn converged(c: &mut Criterion) {
    // `loaded_scene` takes the grains of the material named `ballast`.
    let pile = include_str!("../data/pentagon_pile_536.toml").replace("\"grain\"", "\"ballast\"");
    let pile = Scene::from_toml_str(&pile).unwrap();
    let mut sys = loaded_scene(&pile, &LoadingSpec::saussine(2)).unwrap().build().unwrap();
    sys.set_threads(1);
    for _ in 0..100 {
        sys.step().unwrap();
    }
    let problem = sys.nlgs_problem();
    let base = NlgsSettings { measure: Measure::Check, split_min_rows: 0, min_iterations: 1, ..sys.params.nlgs };
    let tight = NlgsSettings { policy: Policy::Quad, tolerance: 1e-6, max_iterations: 20_000, ..base };
    let default = NlgsSettings { policy: Policy::Energy, tolerance: 1.66e-5, max_iterations: 2000, ..base };
    let alone = InteriorOptions { nlgs_first: 0, max_iterations: 100, nlgs_after: false };
    {
        // What each solve reaches on this problem (printed once).
        let mut p = problem.clone();
        let d = solve_nlgs(&default, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        let mut p = problem.clone();
        let t = solve_nlgs(&tight, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        let mut p = problem.clone();
        let ws = &mut InteriorWorkspace::default();
        let i = solve_interior(&tight, &alone, ws, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        eprintln!("{} rows; energy 1.66e-5: {d:?}; quad 1e-6: {t:?}; interior point: {i:?}", problem.rows.len());
    }
    let mut g = c.benchmark_group("converged");
    g.sample_size(10);
    for (name, s) in [("nlgs_energy_1.66e-5", default), ("nlgs_quad_1e-6", tight)] {
        g.bench_function(format!("{name}_loaded_pile_536"), |b| {
            b.iter_batched_ref(
                || problem.clone(),
                |p| black_box(solve_nlgs(&s, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs)),
                BatchSize::LargeInput,
            )
        });
    }
    let mut ws = InteriorWorkspace::default();
    g.bench_function("interior_point_quad_1e-6_loaded_pile_536", |b| {
        b.iter_batched_ref(
            || problem.clone(),
            |p| black_box(solve_interior(&tight, &alone, &mut ws, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs)),
            BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
