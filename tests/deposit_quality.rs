//! The quality of a pentagon deposit, pinned at a size CI can afford: the
//! bundled 724-grain deposit (`examples/pentagon_deposit.toml`) scaled to 100
//! grains in a 0.1 m box, same grading, solver (`quad_max` 1e-4, ≤ 2000 sweeps),
//! time step and equilibrium rule (1e-11 J per grain for 500 steps), with
//! every NLGS problem split in two halves as the 724-grain deposit's are.
//!
//! A deposit is chaotic: the step at which it comes to rest moves by a factor
//! two when the start moves by 1e-9 m, so no single number of it can be pinned.
//! The bounds below are set from replicas of this very deposit (the
//! unperturbed start and starts perturbed by 1e-9 m, `examples/deposit_replicas.rs`,
//! BENCHMARKS.md "Deposits"): over 4 replicas, equilibrium at 2434–5519 steps,
//! final max overlap 1.0–16 µm, largest overlap of the run 37–91 µm, 33–182
//! steps at the iteration cap (1–4 %). Each bound has a margin of at least two
//! over the worst replica, and each is what a user needs of a deposit: it comes
//! to rest within its duration, it leaves overlaps below 1 % of the smallest
//! grain (Saussine et al. 2006, §3.3's accuracy measure), and the solver meets
//! its tolerance at nearly every step. The change that made the bundled deposit
//! take 7907 steps instead of 4693 (the split sweep order, a reordering of
//! Gauss–Seidel) stays within these bounds; a solver that converged worse
//! would not.

use crate::scratch;
use ballast::run::RunEnd;
use ballast::run::{RunOptions, Runner};
use ballast::scenarios::{pentagon_deposit, DepositSpec};
use ballast::scene::SceneFile;

#[test]
fn a_scaled_deposit_comes_to_rest_with_small_overlaps() {
    let spec = DepositSpec { duration: 2.0, ..DepositSpec::saussine(100, 0.1, 1) };
    let scene = pentagon_deposit(&spec).unwrap();
    let mut sys = scene.build().unwrap();
    sys.params.nlgs.split_min_rows = 1; // the 724-grain deposit's problems are all split
    let mut plan = scene.plan().unwrap();
    plan.output_every = 1000;
    let dir = scratch::path("deposit-quality");
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let run = Runner::from_system(sys, plan).unwrap().run(&dir, &opts, &mut |_| {}).unwrap();
    let r = &run.report;
    eprintln!(
        "{} steps, end {:?}, final max overlap {:.3e} m, run max {:.3e} m, {} unconverged, {:.1} sweeps/step",
        run.step,
        r.end,
        r.final_max_overlap_m,
        r.max_overlap_m,
        r.unconverged_steps.unwrap(),
        r.mean_iterations.unwrap()
    );
    // Replicas: 2434–5519 steps; the scene allows 10 000.
    assert_eq!(r.end, RunEnd::Equilibrium, "no equilibrium within {} steps", run.step);
    // 1 % of the smallest circumradius (5 mm); replicas ≤ 16 µm.
    assert!(r.final_max_overlap_m < 50e-6, "final max overlap {} m", r.final_max_overlap_m);
    // Impacts of the falling grains: replicas ≤ 91 µm.
    assert!(r.max_overlap_m < 200e-6, "largest overlap of the run {} m", r.max_overlap_m);
    // Replicas: ≤ 4 % of the steps at the iteration cap.
    let unconverged = r.unconverged_steps.unwrap() as f64 / run.step as f64;
    assert!(unconverged < 0.1, "{:.1} % of the steps at the iteration cap", 100.0 * unconverged);
    let _ = std::fs::remove_dir_all(&dir);
}
