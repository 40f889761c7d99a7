//! The Saussine et al. (2006) sample (§3–4) on a reduced scale: 1/6 of the
//! grains (121: 60 + 40 + 20 in the paper's proportions), the box width, sleeper
//! width and load scaled by the same factor so that the layer is as thick and the
//! pressure under the sleeper the same as in the full sample. The full sample is
//! measured by `ballast saussine sample` (data/saussine2006/README.md); the
//! reduced one keeps the tests within seconds.

use crate::scratch;

use ballast::run::{RunOptions, Runner, Status};
use ballast::scenarios::saussine::{loaded_scene, measure_sample, sample_scene, LoadingSpec, SampleSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::sync::OnceLock;

const GRAINS: usize = 121;

/// Deposits the reduced sample of `seed` with the library's run loop, which stops
/// once the kinetic energy has stayed below the scene's equilibrium threshold for
/// the scene's window of steps.
fn deposit(seed: u64) -> (Scene, f64) {
    let spec = SampleSpec::saussine(seed).scaled(GRAINS);
    let scene = sample_scene(&spec).unwrap();
    let sys = scene.build().unwrap();
    let dir = scratch::path(&format!("deposit{seed}"));
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let run = Runner::from_system(sys.clone(), scene.plan().unwrap()).unwrap().run(&dir, &opts, &mut |_| {}).unwrap();
    assert_eq!(
        run.status,
        Status::Ended(ballast::run::RunEnd::Equilibrium),
        "the deposit did not reach equilibrium within {} s",
        scene.simulation.duration
    );
    let fin = ballast::engine::FinalState::read(&dir.join("final.json")).unwrap();
    let mut sys = sys;
    for (i, b) in fin.bodies.iter().enumerate() {
        sys.bodies.q[i] = [b.position[0], b.position[1], b.angle.unwrap()];
        let spin = match b.spin {
            ballast::engine::Spin::Planar(w) => w,
            ballast::engine::Spin::Spatial(_) => unreachable!(),
        };
        sys.bodies.u[i] = [b.velocity[0], b.velocity[1], spin];
    }
    let _ = std::fs::remove_dir_all(&dir);
    (scene.with_state(&sys), spec.width)
}

/// The deposited reduced sample of seed 1 (made once for all the tests).
fn sample() -> &'static (Scene, f64) {
    static SAMPLE: OnceLock<(Scene, f64)> = OnceLock::new();
    SAMPLE.get_or_init(|| deposit(1))
}

/// Runs `cycles` loading cycles; returns the rows of `cycles.csv` as
/// (mean settlement, settlement at the load minimum) (m).
fn settle(scene: &Scene, cycles: u64, stiffness_factor: f64) -> Vec<(f64, f64)> {
    // dt = 1e-3 s (50 steps per 20 Hz cycle), the long end of the paper's §3.3 range, for speed.
    // The solver these tests were measured with (quad_max 1e-4, factor 4).
    let spec = LoadingSpec {
        dt: 1e-3,
        stiffness_factor,
        criterion: "quad_max".into(),
        tolerance: 1e-4,
        ..LoadingSpec::saussine(cycles).scaled(sample().1)
    };
    let loaded = loaded_scene(scene, &spec).unwrap();
    let dir = scratch::path(&format!("settle{cycles}_{stiffness_factor}"));
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let runner = Runner::from_system(loaded.build().unwrap(), loaded.plan().unwrap()).unwrap();
    runner.run(&dir, &opts, &mut |_| {}).unwrap();
    let rows = ballast::plane::rows::read_cycles(&dir.join("cycles.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(rows.len() as u64, cycles);
    rows.iter().map(|r| (r.settlement_mean_m, r.settlement_at_min_load_m)).collect()
}

#[test]
fn deposited_sample_is_in_equilibrium_with_a_pentagon_packing_structure() {
    let (scene, _) = sample();
    let r = measure_sample(scene).unwrap();
    println!("{r:#?}");
    // Static equilibrium: the supports (sublayer springs; smooth side walls carry
    // nothing vertically) balance the weight. The NLGS tolerance (quad_max 1e-4)
    // leaves force residuals far below 1 %; the issue asks for 1 %.
    let supports = r.sublayer_reaction_n + r.floor_reaction_n;
    assert!((supports - r.weight_n).abs() < 0.01 * r.weight_n, "supports {supports} N vs weight {} N", r.weight_n);
    // Mean interpenetration below 1e-3 of the smallest grain (1 cm diameter).
    assert!(r.mean_overlap_m < 1e-3 * 0.01, "mean overlap {} m", r.mean_overlap_m);
    // Literature ranges (data/saussine2006/README.md): solid fraction between a loose
    // pentagon deposit (0.70) and the random close packing of pentagons (0.838);
    // coordination between the frictional (3) and frictionless (4) isostatic values.
    // Measured on the full 724-grain sample: 0.772 and 3.12.
    assert!((0.70..=0.84).contains(&r.solid_fraction), "solid fraction {}", r.solid_fraction);
    assert!((3.0..=4.0).contains(&r.coordination), "coordination {}", r.coordination);
    // The layer is "about 10 cm thick".
    assert!((0.08..=0.13).contains(&r.thickness_m), "thickness {} m", r.thickness_m);
}

#[test]
fn sleeper_settles_monotonically_on_average_over_50_cycles() {
    let rows = settle(&sample().0, 50, 1.0);
    // Mean settlement over blocks of 10 cycles: each block lower than the one before
    // (monotonic on average; single cycles may rise a little as the layer "breathes",
    // §4.2). The first block is below the sample's initial level (positive settlement).
    let blocks: Vec<f64> = rows.chunks(10).map(|c| c.iter().map(|r| r.0).sum::<f64>() / c.len() as f64).collect();
    println!("settlement per block of 10 cycles (m): {blocks:?}");
    assert!(blocks[0] > 0.0);
    for w in blocks.windows(2) {
        assert!(w[1] > w[0], "settlement went back up between blocks: {blocks:?}");
    }
}

#[test]
fn stiffer_sublayer_settles_less() {
    // §4.2, Fig. 11: "the more the underlayer is flexible the larger is the settlement",
    // from 3000-cycle runs where the steady rate dominates. The first cycles seat the
    // sleeper's bars, a sample-dependent step (measured: 2.06 mm on the stiff sublayer,
    // 1.77 mm on the soft one after 2 cycles), so the comparison is on the settlement
    // accumulated from cycle 20 to cycle 40, at the load minimum (measured: 21 µm on
    // the reference sublayer, 12 µm with 1000 × k_N).
    let soft = settle(&sample().0, 40, 1.0);
    let stiff = settle(&sample().0, 40, 1000.0);
    let (s, k) = (soft[39].1 - soft[19].1, stiff[39].1 - stiff[19].1);
    println!("settlement from cycle 20 to 40 at the load minimum: soft {s:.3e} m, stiff {k:.3e} m");
    assert!(s > 0.0 && k > 0.0, "the sleeper went up: soft {s} m, stiff {k} m");
    assert!(k < s, "stiff sublayer settled {k} m, soft {s} m");
}
