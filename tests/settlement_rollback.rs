//! A landing that fails is rolled back, not fatal (issue 32,
//! `src/settlement/driver/rollback.rs`), on the example sleeper scene: jumps
//! whose relaxation cannot converge are rolled back until their cycles are
//! computed, and the run then has the numbers of a run that never jumps, bit
//! for bit; a landing rolled back after its window (`rollback_rate`) from a
//! checkpoint taken on probation resumes to the uninterrupted run's numbers.

use crate::scratch;

use ballast::open::settle_file;
use ballast::run::RunOptions;
use ballast::settlement::{AccelerationSummary, JumpRow, SettlementRow};
use std::path::Path;

const SCENE: &str = "examples/settlement_sleeper.toml";

fn tables(dir: &Path) -> (Vec<SettlementRow>, Vec<JumpRow>) {
    let mut rows: Vec<SettlementRow> = ballast::io::read_csv(&dir.join("settlement.csv")).unwrap();
    let mut jumps: Vec<JumpRow> = ballast::io::read_csv(&dir.join("jumps.csv")).unwrap();
    // Wall times differ from run to run.
    rows.iter_mut().for_each(|r| r.wall_time_s = 0.0);
    jumps.iter_mut().for_each(|j| j.relax_wall_time_s = 0.0);
    (rows, jumps)
}

/// The example scene with `[settlement]` keys replaced or added.
fn scene_with(keys: &[(&str, &str)]) -> String {
    let text = std::fs::read_to_string(SCENE).unwrap();
    let mut out = String::new();
    let mut in_settlement = false;
    for line in text.lines() {
        if line.starts_with('[') {
            if in_settlement {
                keys.iter().for_each(|(k, v)| out.push_str(&format!("{k} = {v}\n")));
            }
            in_settlement = line.trim() == "[settlement]";
        } else if in_settlement && keys.iter().any(|(k, _)| line.split('=').next().is_some_and(|l| l.trim() == *k)) {
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

/// Runs the scene `text` in `dir` (one thread, no periodic checkpoints).
fn run(dir: &Path, text: &str, opts: &RunOptions) -> AccelerationSummary {
    std::fs::create_dir_all(dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    settle_file(&scene, &dir.join("out"), opts, &mut |_| {}).unwrap().unwrap()
}

fn opts() -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() }
}

#[test]
fn jumps_whose_relaxation_fails_are_rolled_back_to_computed_cycles() {
    // A window longer than the run: never a jump, every cycle computed.
    let full_dir = scratch::path("full");
    let full = run(&full_dir, &scene_with(&[("computed_cycles", "31")]), &opts());
    assert_eq!((full.computed_cycles, full.jumps, full.rollbacks), (30, 0, 0));
    // A relaxation that cannot reach 1e-14 m in one iteration: every landing fails.
    let failing_dir = scratch::path("failing");
    let text = scene_with(&[("relax_tolerance", "1e-14"), ("relax_max_iterations", "1")]);
    let s = run(&failing_dir, &text, &opts());
    assert_eq!(s.end, "finished");
    assert_eq!((s.total_cycles, s.computed_cycles, s.jumps), (30, 30, 0));
    let (rows, jumps) = tables(&failing_dir.join("out"));
    let (full_rows, _) = tables(&full_dir.join("out"));
    // Each failed jump is a row, marked, with its reason; h = 4 fails, its half
    // (2) is shorter than a window (4), so its 4 cycles are computed, and so on.
    assert_eq!(jumps.len() as u64, s.rollbacks);
    assert!(s.rollbacks >= 3, "{} rollbacks", s.rollbacks);
    assert!(jumps.iter().all(|j| j.rolled_back && j.rollback_reason.contains("relaxation did not reach")));
    assert_eq!((jumps[0].from_cycle, jumps[0].extrapolated_cycles), (6, 4));
    assert_eq!((jumps[1].from_cycle, jumps[1].extrapolated_cycles), (10, 2));
    // Every cycle is computed from the state the failed jump started from, as
    // the run that never jumps computes it: the same numbers, bit for bit.
    assert_eq!(rows.len(), 30);
    for (a, b) in rows.iter().zip(&full_rows) {
        assert_eq!((a.cycle, a.computed), (b.cycle, 1));
        assert_eq!(a.settlement_m.to_bits(), b.settlement_m.to_bits(), "cycle {}", a.cycle);
    }
    assert_eq!(s.settlement_m.to_bits(), full.settlement_m.to_bits());
    let _ = std::fs::remove_dir_all(full_dir);
    let _ = std::fs::remove_dir_all(failing_dir);
}

#[test]
fn a_landing_rolled_back_after_its_window_resumes_to_the_same_numbers() {
    // Every window after a landing that moves at all is "off" its predicted rate.
    let text = scene_with(&[("rollback_rate", "1e-9")]);
    let whole_dir = scratch::path("whole");
    let s = run(&whole_dir, &text, &opts());
    assert_eq!(s.end, "finished");
    let (rows, jumps) = tables(&whole_dir.join("out"));
    assert_eq!(rows.len(), 30);
    assert_eq!(jumps.len() as u64, s.jumps + s.rollbacks);
    assert!(s.rollbacks >= 1);
    let first = jumps.iter().find(|j| j.rolled_back).unwrap();
    assert!(first.rollback_reason.contains("rollback_rate"), "{}", first.rollback_reason);
    // The first jump (cycle 6 → 10) landed and relaxed; its window (cycles
    // 11–14) then rolled it back, and its 4 cycles were computed.
    assert_eq!((first.from_cycle, first.to_cycle), (6, 10));
    assert!(first.relax_converged);
    assert!(rows[6..10].iter().all(|r| r.computed == 1));
    // Stopped on probation (1800 steps: cycle 12, two cycles after the first
    // landing), the checkpoint holds the state before the jump; resumed, the run
    // rolls the landing back as the uninterrupted one did.
    let cut_dir = scratch::path("cut");
    let stop = RunOptions { stop_after: Some(1800), ..opts() };
    let s1 = run(&cut_dir, &text, &stop);
    assert_eq!(s1.end, "stopped");
    let checkpoint = std::fs::read_to_string(cut_dir.join("out/checkpoint.json")).unwrap();
    assert!(checkpoint.contains("\"before_jump\":{"), "the checkpoint keeps the state before the jump on probation");
    let resume = RunOptions { resume: true, ..opts() };
    let s2 = settle_file(&cut_dir.join("scene.toml"), &cut_dir.join("out"), &resume, &mut |_| {}).unwrap().unwrap();
    assert_eq!(s2.end, "finished");
    assert_eq!((s2.rollbacks, s2.jumps, s2.computed_cycles), (s.rollbacks, s.jumps, s.computed_cycles));
    assert_eq!(tables(&cut_dir.join("out")), (rows, jumps), "the resumed run's tables are the uninterrupted run's");
    assert_eq!(s2.settlement_m.to_bits(), s.settlement_m.to_bits());
    let _ = std::fs::remove_dir_all(whole_dir);
    let _ = std::fs::remove_dir_all(cut_dir);
}
