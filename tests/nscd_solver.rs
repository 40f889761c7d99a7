//! NLGS behaviour: convergence policies, warm start, reproducibility and the
//! handling of a blow-up.

use crate::common;
use ballast::nscd::{Policy, System};
use ballast::scene::SceneFile;
use ballast::Error;
use common::*;

/// The scene of the quadratic-mean weakness: a dense set of heavily loaded
/// contacts (600 blocks pressed on the floor by 500 N each, like grains under the
/// sleeper; converged and warm-started, they contribute almost nothing to the
/// corrections) and, beside them, a lightly loaded column that a block lands on
/// softly. The new contacts weigh 1/n in `quad` and their small impulses weigh
/// them down further, so `quad` stops before the landing has propagated down the
/// column and the blocks overlap; `quad_max` keeps iterating.
fn impact_scene(policy: Policy, drop: f64) -> System {
    let mut s = system(1e-3, 0.5, 0.0);
    s.params.nlgs.policy = policy;
    s.params.nlgs.tolerance = 1e-4;
    s.params.nlgs.min_iterations = 1;
    rect(&mut s, 10.0, 0.2, 0.0, -0.1, 0.0, true);
    let side = 0.01;
    for k in 0..600 {
        let i = rect(&mut s, side, side, -4.9 + 0.0125 * k as f64, side / 2.0, 0.0, false);
        s.bodies.info[i]
            .loads
            .push(ballast::nscd::Load { direction: [0.0, -1.0], force: ballast::nscd::Harmonic::constant(500.0) });
    }
    for k in 0..12 {
        rect(&mut s, side, side, 4.95, side * (k as f64 + 0.5), 0.0, false);
    }
    rect(&mut s, side, side, 4.95, side * 12.5 + drop, 0.0, false);
    s
}

#[test]
fn quad_max_policy_prevents_the_interpenetration_that_quad_allows() {
    let mut worst = Vec::new();
    for (policy, f) in [(Policy::Quad, 4.0), (Policy::QuadMax, 4.0), (Policy::QuadMax, 1.0)] {
        let mut s = impact_scene(policy, 2e-3);
        s.params.nlgs.max_factor = f;
        let mut max_overlap: f64 = 0.0;
        let mut iterations = 0;
        for _ in 0..100 {
            let st = s.step().unwrap();
            max_overlap = max_overlap.max(st.max_overlap);
            iterations += st.iterations;
        }
        eprintln!("{policy:?}: max overlap {max_overlap:.3e} m, {iterations} iterations");
        worst.push(max_overlap);
    }
    // With `quad` the column absorbs the landing with an overlap of 34 µm (a third of
    // a per cent of the 1 cm blocks). The maximum norms keep iterating until the new
    // contacts have built up their reactions: measured with the default max_factor 4,
    // 3.0× less overlap for 34 % more sweeps (asserted: 2×); with max_factor 1, 10×
    // (asserted: 5×). (LMGC90's QM/16, max_factor 16.666, gives only 1.1× here.)
    eprintln!("quad / quad_max: {:.1}, quad / quad_max(1): {:.1}", worst[0] / worst[1], worst[0] / worst[2]);
    assert!(worst[0] > 2e-5, "the scene no longer shows the weakness: {:.3e}", worst[0]);
    assert!(worst[1] * 2.0 < worst[0], "quad {:.3e} vs quad_max {:.3e}", worst[0], worst[1]);
    assert!(worst[2] * 5.0 < worst[0], "quad {:.3e} vs quad_max(1) {:.3e}", worst[0], worst[2]);
}

/// Warm start: a resting column converges in a few sweeps once its contact
/// impulses are carried over from the previous step, where a cold start needs
/// many to carry the weight down 10 blocks.
///
/// How few depends on where the norm is measured. With the norm of the sweeps
/// (1.6× the residual), every step stops at a residual well below the tolerance,
/// and the next, warm-started, meets it at once (≤ 2 sweeps). With LMGC90's check
/// (the default), a step stops as soon as the residual dips below the tolerance;
/// the next starts just above it, and the column's slowest mode (two contact
/// points per face, a hyperstatic stack) shaves the last per cent slowly: measured
/// 350 sweeps, where the cold start stops at the 5000-sweep cap. Asserted: under
/// half the cold start's.
#[test]
fn warm_start_makes_a_resting_column_converge_immediately() {
    for measure in [ballast::nscd::Measure::Sweep, ballast::nscd::Measure::Check] {
        let mut s = system(1e-3, 0.5, 0.0);
        s.params.nlgs.tolerance = 1e-6;
        s.params.nlgs.measure = measure;
        floor(&mut s);
        for k in 0..10 {
            rect(&mut s, 0.05, 0.05, 0.0, 0.05 * (k as f64 + 0.5), 0.0, false);
        }
        let first = s.step().unwrap();
        run(&mut s, 50);
        let later = s.step().unwrap();
        eprintln!("{measure:?}: cold {} sweeps, warm {}", first.iterations, later.iterations);
        assert!(first.iterations > 10, "cold start took {} sweeps", first.iterations);
        match measure {
            ballast::nscd::Measure::Sweep => assert!(later.iterations <= 2, "warm start took {}", later.iterations),
            ballast::nscd::Measure::Check => {
                assert!(later.converged && 2 * later.iterations < first.iterations, "{later:?} vs {first:?}")
            }
        }
        assert_eq!(later.contacts, 20, "two contact points per face");
    }
}

/// Same system, same numbers: bitwise.
#[test]
fn runs_are_bitwise_reproducible() {
    let build = || {
        let mut s = system(1e-3, 0.5, 0.0);
        floor(&mut s);
        for k in 0..40 {
            let x = -0.1 + 0.021 * (k % 10) as f64;
            let y = 0.01 + 0.021 * (k / 10) as f64;
            regular(&mut s, 5, 0.01, x + 0.002 * (k % 3) as f64, y, 0.37 * k as f64);
        }
        s
    };
    let (mut a, mut b) = (build(), build());
    run(&mut a, 300);
    run(&mut b, 300);
    assert_eq!(a.bodies.q, b.bodies.q);
    assert_eq!(a.bodies.u, b.bodies.u);
}

/// A blow-up stops with an error naming the step and the body, and the system
/// keeps the last good state.
#[test]
fn runaway_overlap_stops_with_the_step_and_body() {
    let mut s = system(1e-3, 0.5, 0.0);
    floor(&mut s);
    let b = rect(&mut s, 0.01, 0.01, 0.0, 0.5, 0.0, false);
    s.bodies.info[b].name = "bullet".into();
    run(&mut s, 2);
    // Teleport deep into the floor: the next step finds an overlap deeper than
    // half the block.
    s.bodies.q[b][1] = 0.0;
    let before = s.bodies.q.clone();
    match s.step() {
        Err(Error::Diverged { step, body, name, what }) => {
            assert_eq!((step, body, name.as_str()), (3, b, "bullet"));
            assert!(what.contains("overlap"), "{what}");
        }
        other => panic!("expected a divergence error, got {other:?} q {:?}", s.bodies.q),
    }
    assert_eq!(s.bodies.q, before, "state restored to the start of the failed step");
    assert_eq!(s.step, 2);
    // A NaN injected in a velocity is caught too.
    s.bodies.q[b][1] = 0.5;
    s.bodies.u[b][0] = f64::NAN;
    let e = s.step().unwrap_err().to_string();
    assert!(e.contains("step 3") && e.contains("bullet") && e.contains("non-finite"), "{e}");
}

/// A body flung to an absurd position stops the run with an error (no panic or
/// hang in the tile grid), and a fixed body ignores an imposed velocity.
#[test]
fn runaway_position_is_an_error_and_fixed_bodies_never_move() {
    let mut s = system(1e-3, 0.5, 0.0);
    floor(&mut s);
    let b = rect(&mut s, 0.01, 0.01, 0.0, 0.5, 0.0, false);
    s.bodies.q[b][0] = 1e300;
    let e = s.step().unwrap_err().to_string();
    assert!(e.contains("step 1") && e.contains("runaway position"), "{e}");

    let mut s = system(1e-3, 0.5, 0.0);
    let f = floor(&mut s);
    let mut info = s.bodies.info[f].clone();
    info.imposed.dof[0] = Some(ballast::nscd::Harmonic::constant(1.0));
    let g = s.bodies.push(info, [0.0, -0.5, 0.0], [0.0; 3]);
    run(&mut s, 10);
    assert_eq!(s.bodies.q[g], [0.0, -0.5, 0.0]);
}

/// The whole state is plain serde data: a run saved to JSON mid-way and resumed
/// gives bitwise the numbers of the uninterrupted run (warm-start impulses included).
#[test]
fn checkpoint_and_resume_reproduce_the_uninterrupted_run() {
    let build = || {
        let mut s = system(1e-3, 0.5, 0.0);
        floor(&mut s);
        for k in 0..30 {
            regular(&mut s, 5, 0.01, -0.1 + 0.021 * (k % 10) as f64, 0.012 + 0.021 * (k / 10) as f64, 0.5 * k as f64);
        }
        s
    };
    let mut straight = build();
    run(&mut straight, 400);
    let mut first = build();
    run(&mut first, 200);
    let json = serde_json::to_string(&first).unwrap();
    drop(first);
    let mut resumed: System = serde_json::from_str(&json).unwrap();
    run(&mut resumed, 200);
    assert_eq!(resumed.bodies.q, straight.bodies.q);
    assert_eq!(resumed.bodies.u, straight.bodies.u);
    assert_eq!((resumed.time, resumed.step), (straight.time, straight.step));
}

/// Every convergence policy reaches the static equilibrium of a column: the floor
/// carries the weight to within the policy's tolerance.
/// Four blocks stacked on a floor, 200 steps at tolerance 1e-8 with `policy` and
/// over-relaxation `omega`: the system, the floor and the blocks.
fn settled_column(policy: Policy, omega: f64) -> (System, usize, Vec<usize>) {
    let mut s = system(1e-3, 0.5, 0.0);
    s.params.nlgs.policy = policy;
    s.params.nlgs.tolerance = 1e-8;
    s.params.nlgs.relaxation = omega;
    let f = floor(&mut s);
    let ids: Vec<usize> = (0..4).map(|k| rect(&mut s, 0.05, 0.05, 0.0, 0.05 * (k as f64 + 0.5), 0.0, false)).collect();
    run(&mut s, 200);
    (s, f, ids)
}

#[test]
fn every_policy_reaches_the_equilibrium_of_a_column() {
    for policy in Policy::ALL {
        let (s, f, ids) = settled_column(policy, 1.0);
        let weight: f64 = ids.iter().map(|&i| s.bodies.info[i].mass * G).sum();
        let r = s.contact_resultant(f);
        // A relative tolerance 1e-8 on contact impulses bounds the reaction error
        // far below 1e-5 of the weight.
        assert!((-r[1] - weight).abs() < 1e-5 * weight, "{policy:?}: {} vs {weight}", -r[1]);
    }
}

/// Over-relaxed sweeps (`relaxation`) keep the law's fixed point: a column of
/// blocks on the floor (hyperstatic: two corner contacts per interface) reaches
/// the reaction = weight equilibrium and rest at every ω tried, and the same
/// column with ω = 1 matches it. An ω outside (0, 2) is refused naming the key.
#[test]
fn over_relaxed_sweeps_reach_the_same_equilibrium() {
    for omega in [1.0, 1.3, 1.8] {
        let (s, f, ids) = settled_column(Policy::Quad, omega);
        let weight: f64 = ids.iter().map(|&i| s.bodies.info[i].mass * G).sum();
        let r = s.contact_resultant(f);
        // As in `every_policy_reaches_the_equilibrium_of_a_column`: 1e-8 on the
        // impulses bounds the reaction error far below 1e-5 of the weight.
        assert!((-r[1] - weight).abs() < 1e-5 * weight, "omega {omega}: {} vs {weight}", -r[1]);
        let v = ids.iter().map(|&i| s.bodies.u[i][1].abs()).fold(0.0, f64::max);
        // At rest: the last step's velocity error is the tolerance's, ≪ g h = 1e-2 m/s.
        assert!(v < 1e-6, "omega {omega}: |vy| {v}");
    }
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/examples/block_on_floor.toml")).unwrap();
    let bad = text.replace("[output]", "[nscd]\nrelaxation = 2.0\n\n[output]");
    assert!(bad.contains("relaxation"), "the example has an [output] table");
    let err = ballast::scene::Scene::from_toml_str(&bad).and_then(|s| s.build().map(|_| ())).unwrap_err();
    assert!(err.to_string().contains("nscd.relaxation"), "{err}");
}

/// The domain-split NLGS (`nscd::split`) on the settled 536-pentagon pile (≈ 900
/// rows, above the split threshold): two threads give bit for bit the numbers of
/// one; the split order differs from the unsplit one (so the split really ran)
/// but both converge to the same static state, to within the solver tolerance.
#[test]
fn split_sweeps_same_numbers_on_one_or_two_threads() {
    let scene =
        ballast::scene::Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/data/pentagon_pile_536.toml")).unwrap();
    let base = scene.build().unwrap();
    let run = |threads: usize, split_min_rows: usize| {
        let mut s = base.clone();
        s.params.nlgs.split_min_rows = split_min_rows;
        s.set_threads(threads);
        let mut rows = 0;
        for _ in 0..20 {
            rows = s.step().unwrap().contacts;
        }
        (s, rows)
    };
    let (one, rows) = run(1, 512);
    assert!(rows + base.springs.len() >= 512, "the pile must be large enough to split ({rows} rows)");
    let (two, _) = run(2, 512);
    assert_eq!(one.bodies.q, two.bodies.q);
    assert_eq!(one.bodies.u, two.bodies.u);
    let (unsplit, _) = run(1, 0);
    assert_ne!(one.bodies.q, unsplit.bodies.q, "another sweep order gives other round-off");
    // A settled pile stays put under both orders: 20 steps of 0.2 ms move no grain
    // by more than 1 µm from the other order's position (the grains are 1–2 cm;
    // the NLGS stops at a relative tolerance of 1e-4; measured 5e-8 m; a lost row
    // would let grains fall ½ g t² ≈ 80 µm).
    let worst =
        one.bodies.q.iter().zip(&unsplit.bodies.q).map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1])).fold(0.0, f64::max);
    assert!(worst < 1e-6, "largest difference {worst:e} m");
}
