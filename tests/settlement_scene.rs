//! `[settlement]` in a scene: `ballast run` (the library's `settlement::run_file`)
//! runs the procedure; a stopped run resumes to the same numbers; bad tables are
//! one-line errors naming the key.

use crate::scratch;

use ballast::open::settle_file;
use ballast::run::RunOptions;
use ballast::scene::SceneFile;
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

/// Runs the scene `text` (a single-threaded run, no checkpoints) in a fresh
/// folder named after `name`: its summary and tables, the folder removed.
fn run_text(name: &str, text: &str) -> (AccelerationSummary, (Vec<SettlementRow>, Vec<JumpRow>)) {
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let dir = scratch::path(name);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let s = settle_file(&scene, &dir.join("out"), &opts, &mut |_| {}).unwrap().unwrap();
    let t = tables(&dir.join("out"));
    let _ = std::fs::remove_dir_all(dir);
    (s, t)
}

#[test]
fn the_example_runs_through_the_procedure_and_resumes_to_the_same_numbers() {
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let whole = scratch::path("whole");
    let s = settle_file(SCENE.as_ref(), &whole, &opts, &mut |_| {}).unwrap().expect("the example has [settlement]");
    // 30 cycles: 2 initial, then 4 computed + 4 extrapolated, three times, and 4 computed.
    assert_eq!((s.total_cycles, s.computed_cycles, s.jumps), (30, 18, 3));
    assert!((s.gained - 30.0 / 18.0).abs() < 1e-12);
    let (rows, jumps) = tables(&whole);
    assert_eq!(rows.len(), 30);
    assert_eq!(rows.iter().filter(|r| r.computed == 1).count(), 18);
    assert_eq!(jumps.len(), 3);
    for f in ["summary.json", "final.json", "scene.toml", "run.json"] {
        assert!(whole.join(f).is_file(), "{f}");
    }
    assert!(!whole.join("checkpoint.json").exists());
    // Stopped after 1000 steps (cycle 14, inside the second window), resumed.
    let cut = scratch::path("cut");
    let stop = RunOptions { stop_after: Some(1000), ..opts.clone() };
    let s1 = settle_file(SCENE.as_ref(), &cut, &stop, &mut |_| {}).unwrap().unwrap();
    assert_eq!(s1.end, "stopped");
    assert!(cut.join("checkpoint.json").is_file());
    let resume = RunOptions { resume: true, ..opts.clone() };
    let s2 = settle_file(SCENE.as_ref(), &cut, &resume, &mut |_| {}).unwrap().unwrap();
    assert_eq!(s2.end, "finished");
    assert_eq!(tables(&cut), (rows, jumps), "the resumed run's tables are the uninterrupted run's");
    assert_eq!(s2.settlement_m.to_bits(), s.settlement_m.to_bits());
    // Figures, and the errors against a reference: the uninterrupted run is the
    // resumed run's reference, so every accrued error is exactly 0.
    let figs = ballast::report::settlement::draw(&cut, Some(&whole)).unwrap();
    assert_eq!(figs.written.len(), 2);
    for stem in &figs.written {
        assert!(stem.with_extension("png").is_file() && stem.with_extension("svg").is_file());
    }
    let errors: Vec<ballast::report::settlement::ErrorRow> = ballast::io::read_csv(&cut.join("errors.csv")).unwrap();
    assert_eq!(errors.len(), 30);
    assert!(errors[..2].iter().all(|e| e.accrued_error.is_none()), "no accrual before k_i");
    assert!(errors[2..].iter().all(|e| e.accrued_error == Some(0.0)));
    // An accelerated run of the same scene as the reference: errors after k_i only.
    let rows: Vec<SettlementRow> = ballast::io::read_csv(&whole.join("settlement.csv")).unwrap();
    let full: Vec<(f64, Option<f64>)> = rows.iter().map(|r| (r.settlement_m + 1e-6, r.coordination)).collect();
    let e = ballast::report::settlement::errors(&rows, &full, 2);
    // s_full − s_full(2) is s − s(2): the error is 1e-6 m over what accrued.
    let accrued = rows[29].settlement_m - rows[1].settlement_m;
    assert!((e[29].accrued_error.unwrap() - 1e-6 / accrued.abs()).abs() < 1e-9 / accrued.abs());
    // The same errors afterwards from the command line: `ballast figures ACC --reference FULL`.
    std::fs::remove_file(cut.join("errors.csv")).unwrap();
    let figures = |dir: &Path| {
        std::process::Command::new(env!("CARGO_BIN_EXE_ballast"))
            .arg("figures")
            .arg(dir)
            .arg("--reference")
            .arg(&whole)
            .output()
            .unwrap()
    };
    let out = figures(&cut);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("error on what accrued after the 2 initial cycles: 0.00 %"), "{stdout}");
    assert_eq!(
        ballast::io::read_csv::<ballast::report::settlement::ErrorRow>(&cut.join("errors.csv")).unwrap().len(),
        30
    );
    // A scene without [settlement] is not run by it, and its folder has no
    // accelerated run to measure: one line naming the file, exit code 2.
    let none = scratch::path("none");
    assert!(settle_file("examples/sleeper_load.toml".as_ref(), &none, &opts, &mut |_| {}).unwrap().is_none());
    std::fs::create_dir_all(&none).unwrap();
    let out = figures(&none);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("has no settlement.csv") && stderr.lines().count() == 1, "{stderr}");
    for d in [whole, cut, none] {
        let _ = std::fs::remove_dir_all(d);
    }
}

#[test]
fn bad_settlement_tables_name_the_key() {
    let text = std::fs::read_to_string(SCENE).unwrap();
    let cases: &[(&str, &str, &str)] = &[
        ("law = \"shenton\"", "law = \"power\"", "settlement.law: unknown law 'power'"),
        ("computed_cycles = 4", "computed_cycles = 1", "settlement.computed_cycles: a fit needs at least 2 cycles"),
        ("extrapolated_cycles = 4", "extrapolated_cycles = 0", "settlement.extrapolated_cycles: must be at least 1"),
        ("relax_tolerance = 1.0e-5", "relax_tolerance = -1.0", "settlement.relax_tolerance: must be a positive length"),
        (
            "relax_tolerance = 1.0e-5",
            "relax_tolerance = \"loose\"",
            "settlement.relax_tolerance: expected a length (m) or \"computed\", got 'loose'",
        ),
        (
            "settlement_body = \"sleeper\"",
            "settlement_body = \"floor\"",
            "settlement.settlement_body: body 'floor' is fixed",
        ),
        (
            "settlement_body = \"sleeper\"",
            "settlement_body = \"nobody\"",
            "settlement.settlement_body: unknown body 'nobody'",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nerror = 1e-6",
            "settlement.probability: needed with settlement.error",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\ngrowth = 0.5",
            "settlement.growth: must be a finite factor of at least 1",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nrelax_method = \"newton\"",
            "settlement.relax_method: unknown method 'newton'",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nrelax_stage = 0.0",
            "settlement.relax_stage: must be a positive fraction of the smallest body's size",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nrelax_stage = nan",
            "settlement.relax_stage: must be a positive fraction of the smallest body's size",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nextrapolation_limit = 0.0",
            "settlement.extrapolation_limit: must be a positive fraction",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nextrapolation_limit = nan",
            "settlement.extrapolation_limit: must be a positive fraction",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nsmoothing_length = -1e-3",
            "settlement.smoothing_length: must be a positive length (m), got -0.001",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nsmoothing_length = inf",
            "settlement.smoothing_length: must be a positive length (m), got inf",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nsettle_cycles = 4",
            "settlement.settle_cycles: must be at least 1 and less than computed_cycles (4), got 4",
        ),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nsettle_rate = 0.0",
            "settlement.settle_rate: must be a positive factor on the predicted rate, got 0",
        ),
        ("law = \"shenton\"", "law = \"shenton\"\nspeed = 2", "unknown field `speed`"),
        (
            "law = \"shenton\"",
            "law = \"shenton\"\nhold_anchored = \"pads\"",
            "expected a boolean (at `hold_anchored = \"pads\"`)",
        ),
        ("initial_cycles = 2", "initial_cycles = 0", "settlement.initial_cycles: Shenton's law needs at least 1"),
        (
            "cycles = { frequency = 20.0, body = \"sleeper\" }",
            "",
            "settlement: needs the loading frequency of [output] cycles",
        ),
    ];
    for (from, to, want) in cases {
        assert!(text.contains(from), "{from}");
        let bad = text.replacen(from, to, 1);
        let e = ballast::scene::Scene::from_toml_str(&bad).unwrap_err().to_string();
        assert!(e.contains(want), "{to}: {e}");
        assert!(!e.contains('\n'), "one line: {e}");
    }
}

#[test]
fn the_relaxation_tolerance_is_a_length_or_the_computed_overlap() {
    // A length is the tolerance; "computed", or no key, asks each jump to relax
    // down to the largest overlap of the configuration it starts from.
    let text = std::fs::read_to_string(SCENE).unwrap();
    let plan = |t: &str| ballast::scene::Scene::from_toml_str(t).unwrap().acceleration().unwrap().unwrap().spec;
    let given = plan(&text);
    assert!(!given.relax_to_computed && given.relax.tolerance == 1.0e-5);
    for t in [
        text.replace("relax_tolerance = 1.0e-5", "relax_tolerance = \"computed\""),
        text.replace("relax_tolerance = 1.0e-5\n", ""),
    ] {
        assert!(t != text);
        assert!(plan(&t).relax_to_computed);
    }
}

#[test]
fn the_smoothing_length_is_off_unless_given() {
    let text = std::fs::read_to_string(SCENE).unwrap();
    let plan = |t: &str| ballast::scene::Scene::from_toml_str(t).unwrap().acceleration().unwrap().unwrap().spec;
    assert_eq!(plan(&text).smoothing_length, None);
    let t = text.replace("law = \"shenton\"", "law = \"shenton\"\nsmoothing_length = 0.02");
    assert_eq!(plan(&t).smoothing_length, Some(0.02));
}

#[test]
fn settle_cycles_leave_the_first_cycles_after_a_landing_out_of_the_window() {
    // The linear law (eq. 16) on the last window is the line through its first
    // and last points, so the settlement over the second jump's extrapolated
    // cycles continues the slope from the window's first point: with
    // `settle_cycles = 3` (k = 4) the cycles 11 and 12 after the landing at
    // cycle 10 are not data, the window is 13–14 and the slope s(14) − s(13);
    // by default it is 11–14, slope (s(14) − s(11))/3. Exact to rounding.
    let text = std::fs::read_to_string(SCENE).unwrap().replace("duration = 1.5 ", "duration = 0.9 ");
    for (settle, first) in [(None, 11usize), (Some(3), 13)] {
        let mut t = text.replace("law = \"shenton\"", "law = \"linear\"");
        if let Some(n) = settle {
            t = t.replace("law = \"linear\"", &format!("law = \"linear\"\nsettle_cycles = {n}"));
        }
        let (s, (rows, _)) = run_text(&format!("settle{first}"), &t);
        // 18 cycles: 2 initial, 4 computed, 4 extrapolated, 4 computed, 4 extrapolated.
        assert_eq!((s.total_cycles, s.computed_cycles, s.jumps), (18, 10, 2));
        let at = |cycle: usize| rows[cycle - 1].settlement_m;
        assert!(rows[10..14].iter().all(|r| r.computed == 1), "cycles 11-14 computed");
        let slope = (at(14) - at(first)) / (14 - first) as f64;
        for j in 1..4 {
            let want = at(14) + j as f64 * slope;
            assert!(
                (at(14 + j) - want).abs() <= 1e-12 * want.abs(),
                "settle {settle:?}, cycle {}: {} vs {want}",
                14 + j,
                at(14 + j)
            );
        }
    }
}

#[test]
fn settle_rate_keeps_re_seating_cycles_out_of_the_window_until_the_rate_falls() {
    // The rule, recomputed from the tables: after a landing the window opens at
    // the first computed cycle (from the `settle_cycles`-th on) whose increment,
    // averaged with the previous one since the landing, is at most `settle_rate`
    // times |landing_rate_m| of the jump (or after `computed_cycles` extra
    // cycles). Those cycles are computed in addition to the k after the landing, which
    // the linear law (eq. 16) then fits from its first point: the slope over
    // the next extrapolated cycles is (s(last) − s(first)) / (last − first),
    // exact to rounding. A huge factor never re-seats past the fixed count (the
    // default run, bit for bit); a tiny one always re-seats k extra cycles.
    let text = std::fs::read_to_string(SCENE).unwrap().replace("law = \"shenton\"", "law = \"linear\"");
    let run = |name: &str, extra: &str| {
        run_text(name, &text.replace("law = \"linear\"", &format!("law = \"linear\"\n{extra}")))
    };
    let (base, base_tables) = run("rate-none", "");
    let (never, never_tables) = run("rate-huge", "settle_rate = 1e30");
    assert_eq!(never_tables, base_tables);
    assert_eq!(never.settlement_m.to_bits(), base.settlement_m.to_bits());
    let k = 4u64; // the example's computed_cycles
    let mut mid = false;
    for (name, extra, settle, factor) in [
        ("rate-tiny", "settle_rate = 1e-30", 1, 1e-30),
        ("rate-one", "settle_rate = 1.0", 1, 1.0),
        ("rate-two", "settle_cycles = 2\nsettle_rate = 2.0", 2, 2.0),
    ] {
        let (s, (rows, jumps)) = run(name, extra);
        assert!(jumps.len() >= 2, "{name}: {} jumps", jumps.len());
        let at = |cycle: u64| rows[cycle as usize - 1].settlement_m;
        for pair in jumps.windows(2) {
            let (landed, next) = (&pair[0], &pair[1]);
            // Recompute the re-seating of the cycles after `landed`.
            let mut n = 0;
            let mut previous: Option<f64> = None;
            let first = loop {
                n += 1;
                let cycle = landed.to_cycle + n;
                assert_eq!(rows[cycle as usize - 1].computed, 1, "{name}: cycle {cycle}");
                let inc = at(cycle) - at(cycle - 1);
                let mean = previous.map_or(inc, |p| 0.5 * (p + inc));
                previous = Some(inc);
                if n >= settle && (mean <= factor * landed.landing_rate_m.abs() || n - settle >= k) {
                    break cycle;
                }
            };
            // The rule ended the re-seating itself: past the fixed count, before the cap.
            mid |= next.settling_cycles >= settle && next.settling_cycles < settle - 1 + k;
            assert_eq!(next.settling_cycles, first - landed.to_cycle - 1, "{name}: jump {}", next.jump);
            assert_eq!(next.from_cycle, first + k - settle, "{name}: jump {}", next.jump);
            if name == "rate-tiny" {
                assert_eq!(next.settling_cycles, k, "{name}: every landing re-seats k cycles");
            }
            let last = next.from_cycle;
            let slope = (at(last) - at(first)) / (last - first) as f64;
            for j in 1..next.extrapolated_cycles.min(3) {
                let want = at(last) + j as f64 * slope;
                let got = at(last + j);
                assert!((got - want).abs() <= 1e-12 * want.abs(), "{name}, cycle {}: {got} vs {want}", last + j);
            }
        }
        assert!(s.computed_cycles > base.computed_cycles || name != "rate-tiny");
    }
    assert!(mid, "no landing's re-seating ended between the fixed count and the cap");
}

#[test]
fn a_body_that_leaves_the_domain_stops_the_run_naming_it() {
    // A pentagon thrown sideways at 30 m/s above the walls: 1.5 m in the first
    // cycle (0.05 s), far out of the domain (the start box of the mobile bodies,
    // 0.24 m × 0.48 m, widened by 0.24 m on each side).
    let text = std::fs::read_to_string(SCENE).unwrap().replace("duration = 1.5 ", "duration = 0.5 ")
        + "\n[[body]]\nname = \"stray\"\nmaterial = \"grain\"\nregular = { sides = 5, radius = 0.03 }\n\
           position = [0.0, 0.5]\nvelocity = [30.0, 0.0]\n";
    let dir = scratch::path("stray");
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("stray.toml");
    std::fs::write(&scene, text).unwrap();
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let e = settle_file(&scene, &dir.join("out"), &opts, &mut |_| {}).unwrap_err().to_string();
    assert!(e.contains("'stray'") && e.contains("computed cycle 1 carried it out of the domain"), "{e}");
    assert!(!e.contains('\n'), "one line: {e}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/summary.json")).unwrap()).unwrap();
    assert_eq!(summary["end"], "diverged");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn relax_stage_sets_the_stages_of_each_landing() {
    let text = std::fs::read_to_string(SCENE).unwrap();
    let with = |stage: &str| text.replace("law = \"shenton\"", &format!("law = \"shenton\"\nrelax_stage = {stage}"));
    let (_, (_, one)) = run_text("single", &with("inf"));
    // The example's landings move a grain by about 1e-10 m: one stage
    // at the default, several at a stage of 1e-9 of the smallest grain's size (0.02 nm).
    let (_, (_, default)) = run_text("default", &text);
    let (_, (_, fine)) = run_text("fine", &with("1e-9"));
    assert!(one.iter().chain(&default).all(|j| j.relax_stages == 1), "{one:?} {default:?}");
    assert_eq!(one, default);
    assert!(fine.iter().all(|j| j.relax_stages > 1 && j.relax_converged), "{fine:?}");
    for (f, o) in fine.iter().zip(&one) {
        // No stage starts deeper than the single relaxation's overlap (these
        // are below the tolerance, left as they are: the stages only add the
        // moves up in parts, and the runs part at round-off, 1e-15 m).
        assert!(f.max_overlap_before_relax_m <= o.max_overlap_before_relax_m + 1e-12, "{f:?} {o:?}");
    }
}

#[test]
fn hold_anchored_keeps_the_sprung_bodies_where_the_computed_cycle_left_them() {
    // The example with two bottom grains on springs to anchors under the floor
    // (at rest length: no force at the start), every cycle's positions written.
    let text = std::fs::read_to_string(SCENE)
        .unwrap()
        .replace("body = \"sleeper\" }", "body = \"sleeper\", positions = true }")
        + "\n[[spring]]\nbody = \"grain1\"\nanchor = [-0.05906, 0.00477]\nk_n = 1000.0\nnu = 1.0\nrest_length = 0.02\n\
           \n[[spring]]\nbody = \"grain3\"\nanchor = [0.05906, 0.00477]\nk_n = 1000.0\nnu = 1.0\nrest_length = 0.02\n";
    let with = |hold: &str| text.replace("law = \"shenton\"", &format!("law = \"shenton\"\nhold_anchored = {hold}"));
    let positions = |name: &str, t: &str| {
        let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
        let dir = scratch::path(name);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("scene.toml"), t).unwrap();
        settle_file(&dir.join("scene.toml"), &dir.join("out"), &opts, &mut |_| {}).unwrap().unwrap();
        let p = ballast::run::positions::read(&dir.join("out")).unwrap();
        let jumps = tables(&dir.join("out")).1;
        let _ = std::fs::remove_dir_all(dir);
        (p, jumps)
    };
    // The sprung grains' coordinates at the end of cycle `c` (cycles[0] ends cycle 1).
    let sprung = |p: &ballast::run::positions::CyclePositions, c: u64| -> Vec<f64> {
        ["grain1", "grain3"]
            .iter()
            .flat_map(|n| {
                let k = p.names.iter().position(|m| m == n).unwrap();
                p.cycles[c as usize - 1].body(k).to_vec()
            })
            .collect()
    };
    let (held, held_jumps) = positions("hold-held", &with("true"));
    let (free, free_jumps) = positions("hold-free", &with("false"));
    assert_eq!((held_jumps.len(), free_jumps.len()), (3, 3));
    for j in &held_jumps {
        // Both counted as held, and landed exactly where the window ended.
        assert!(j.held_bodies >= 2, "{j:?}");
        assert_eq!(sprung(&held, j.to_cycle), sprung(&held, j.from_cycle), "jump {}", j.jump);
    }
    // Free, their fits move them (by about 1e-10 m in this example): the hold
    // is what keeps them.
    assert!(free_jumps.iter().any(|j| sprung(&free, j.to_cycle) != sprung(&free, j.from_cycle)));
    // `false` is the default.
    let (_, default_jumps) = positions("hold-default", &text);
    assert_eq!(default_jumps, free_jumps);
}

/// `Loaded::settle_on`, the accelerated run of an opened scene that the Python binding drives: the table and
/// the cycles of a request replace the scene's (the loaded sleeper without `[settlement]`, given the example's
/// table, runs as the example does); a stop asked by the control callback leaves a checkpoint and the system at
/// the cycle reached, and the scene opened afresh and resumed ends with the uninterrupted run's numbers; a
/// scene without a table and no request's is refused naming the key.
#[test]
fn an_opened_scene_settles_with_a_request_stops_and_resumes() {
    use ballast::engine::Engine;
    use ballast::open::{open, Loaded, SettleRequest};
    use ballast::scene::Scene;
    use std::ops::ControlFlow;
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let go = &mut |_: &ballast::settlement::AccelerationProgress| ControlFlow::Continue(());
    let steps = |l: &Loaded| match l {
        Loaded::Nscd(o) => o.system.steps_done(),
        _ => unreachable!("an NSCD scene"),
    };
    let cycles = Some(14);
    let own = SettleRequest { settlement: None, cycles };
    let whole = scratch::path("settle_on_whole");
    let mut sim = open(SCENE.as_ref(), &opts).unwrap();
    let s = sim.settle_on(&whole, &opts, &own, go).unwrap();
    // 2 initial + 4 computed, a jump of 4, 4 computed: 10 computed cycles of 250 steps.
    assert_eq!((s.total_cycles, s.computed_cycles, s.end.as_str()), (14, 10, "finished"));
    assert_eq!(steps(&sim), s.steps);
    let table = Scene::load(SCENE).unwrap().settlement;
    let given = SettleRequest { settlement: table, cycles };
    let plain = scratch::path("settle_on_given");
    let mut other = open("examples/sleeper_load.toml".as_ref(), &opts).unwrap();
    let t = other.settle_on(&plain, &opts, &given, go).unwrap();
    assert_eq!(tables(&whole), tables(&plain));
    assert_eq!((t.settlement_m, t.jumps), (s.settlement_m, s.jumps));
    // Stopped after cycle 11 (past the jump, inside the second window), resumed by a fresh opening.
    let cut = scratch::path("settle_on_cut");
    let mut sim = open(SCENE.as_ref(), &opts).unwrap();
    let mut stop = |p: &ballast::settlement::AccelerationProgress| {
        if p.cycle == 11 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    };
    let first = sim.settle_on(&cut, &opts, &own, &mut stop).unwrap();
    assert_eq!((first.end.as_str(), first.total_cycles), ("stopped", 11));
    assert_eq!(steps(&sim), first.steps, "the system holds the cycle reached");
    assert!(cut.join("checkpoint.json").is_file());
    let resume = RunOptions { resume: true, ..opts.clone() };
    let end = open(SCENE.as_ref(), &opts).unwrap().settle_on(&cut, &resume, &own, go).unwrap();
    assert_eq!((end.settlement_m, end.total_cycles), (s.settlement_m, 14));
    assert_eq!(tables(&whole), tables(&cut));
    let e = open("examples/sleeper_load.toml".as_ref(), &opts)
        .unwrap()
        .settle_on(&scratch::path("settle_on_none"), &opts, &SettleRequest::default(), go)
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("settlement: the scene has no [settlement] table"), "{e}");
    for dir in [whole, plain, cut] {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// The run-loop options that change a run's scene or keep its last checkpoint are refused by a `[settlement]`
/// run, before anything is written, with one line naming the option; `extend` without `resume` is refused as
/// any run refuses it.
#[test]
fn a_settlement_run_refuses_the_run_loops_scene_changes() {
    let dir = scratch::path("refusals");
    let base = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let cases = [
        (RunOptions { resume: true, change_solver: true, ..base.clone() }, "change_solver: "),
        (RunOptions { resume: true, extend: true, ..base.clone() }, "extend: "),
        (RunOptions { keep_checkpoint: true, ..base.clone() }, "keep_checkpoint: "),
    ];
    for (opts, key) in cases {
        let e = settle_file(SCENE.as_ref(), &dir, &opts, &mut |_| {}).unwrap_err().to_string();
        assert!(e.starts_with(key) && e.contains("[settlement]") && !e.contains('\n'), "{e}");
        assert!(!dir.exists(), "{key}: nothing written");
    }
    let opts = RunOptions { extend: true, ..base };
    let e = ballast::open::run_file("examples/block_on_floor.toml".as_ref(), &dir, &opts, &mut |_| {}).unwrap_err();
    assert!(e.to_string().starts_with("extend: continues a resumed run past its end"), "{e}");
}
