//! 2D scenes on the planar MD engine (`engine = "md2d"`, formerly `engine = "md"` with `dimension = 2`, or
//! `ballast run --engine md2d`, formerly `--engine md`): the stiffness derived from `[soft]
//! max_overlap_ratio` gives the overlap it promises under the scene's load,
//! both engines write the same files from one scene, a stopped run resumes to
//! the same bytes, the settlement driver runs on it, and bad `[soft]` tables or
//! time steps are one-line errors naming the key and the numbers.

use crate::scratch;

use ballast::open::run_file;
use ballast::run::RunOptions;
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::path::{Path, PathBuf};

const BLOCK: &str = "examples/block_on_floor.toml";

fn opts(engine: Option<&str>) -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, threads: 1, engine: engine.map(String::from), ..RunOptions::default() }
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn scene_file(dir: &Path, text: &str) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("scene.in.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// The block of `examples/block_on_floor.toml` (0.1 m square, 27 kg) run with
/// `--engine md` and the default `[soft]`: one column of grains, so the
/// reference load is its weight and the stiffness is set for an overlap of
/// 1e-3 × its inradius (50 µm): at rest the face sits exactly that deep. Asked for two threads, the summary
/// records the one the planar step runs on.
#[test]
fn a_block_run_with_engine_md_rests_at_the_overlap_its_stiffness_was_derived_for() {
    let out = scratch::path("block");
    // Two threads asked: the planar step is not split, and the summary says it ran on one.
    let two = RunOptions { threads: 2, ..opts(Some("md")) };
    let outcome = run_file(BLOCK.as_ref(), &out, &two, &mut |_| {}).unwrap();
    assert_eq!(json(&out.join("summary.json"))["threads"], 1);
    let run = json(&out.join("run.json"));
    assert_eq!(run["engine"], "md2d");
    let model = &run["model"];
    assert_eq!(model["derived"], true);
    assert_eq!(model["columns"], 1);
    let weight = 2700.0 * 0.01 * 9.81;
    assert!((model["reference_load_n"].as_f64().unwrap() - weight).abs() < 1e-9 * weight);
    let dt = model["dt_s"].as_f64().unwrap();
    let t_c = model["contact_time_s"].as_f64().unwrap();
    assert!((dt - 0.02 * t_c).abs() < 1e-15, "dt = t_c / 50");
    assert!(dt < model["stability_limit_s"].as_f64().unwrap());
    assert_eq!(outcome.step, (0.5 / dt).round() as u64, "the scene's duration at the planar step");
    // The recorded scene says which engine ran.
    let recorded = Scene::load(out.join("scene.toml")).unwrap();
    assert!(recorded.is_planar_md());
    let fin = json(&out.join("final.json"));
    let y = fin["bodies"][1]["position"][1].as_f64().unwrap();
    let sunk = 0.05 - y;
    let expected = 1e-3 * 0.05;
    eprintln!("sunk {sunk:e} m, expected {expected:e} m, dt {dt:e} s");
    // Critically damped (no [[contact]] restitution: e = 0) and 200 contact times
    // later at rest: the face's two points carry the weight at k_n / 2 each.
    assert!((sunk - expected).abs() < 1e-6 * expected, "sunk {sunk} m against {expected} m");
}

/// One vocabulary: the planar engine is `md2d` in scenes, in `--engine` and in the outputs; its former
/// spellings (`engine = "md"` with `dimension = 2`, `--engine md` on a 2D scene) are still read, and a scene
/// rewritten for it (`--engine`) names it `md2d`.
#[test]
fn the_planar_engine_is_md2d_in_scenes_engine_and_outputs() {
    let text = std::fs::read_to_string(BLOCK).unwrap();
    let dir = scratch::path("vocabulary");
    let new = scene_file(&dir.join("new"), &text.replace("engine = \"nscd\"", "engine = \"md2d\""));
    let old = scene_file(&dir.join("old"), &text.replace("engine = \"nscd\"", "engine = \"md\"\ndimension = 2"));
    for path in [&new, &old] {
        let scene_text = std::fs::read_to_string(path).unwrap();
        assert_eq!(ballast::scene::engine_of(&scene_text).unwrap(), "md2d");
        assert!(Scene::from_toml_str(&scene_text).unwrap().is_planar_md());
    }
    let short = |o: RunOptions| RunOptions { length: Some(ballast::run::RunLength::Steps(20)), ..o };
    for (k, (path, engine)) in [(&new, None), (&old, None), (&PathBuf::from(BLOCK), Some("md2d"))].iter().enumerate() {
        let out = dir.join(format!("out{k}"));
        run_file(path, &out, &short(opts(*engine)), &mut |_| {}).unwrap();
        assert_eq!(json(&out.join("run.json"))["engine"], "md2d", "run {k}");
        assert_eq!(json(&out.join("summary.json"))["engine"], "md2d", "run {k}");
    }
    // The rewritten scene (the engine changed by --engine, and the length by `length`) names md2d alone.
    let recorded = std::fs::read_to_string(dir.join("out2/scene.toml")).unwrap();
    assert!(recorded.contains("engine = \"md2d\"") && !recorded.contains("dimension"), "{recorded}");
    // A 3D scene runs on md only.
    let e = run_file("examples/md_two_spheres.toml".as_ref(), &dir.join("out3"), &opts(Some("md2d")), &mut |_| {});
    let e = e.unwrap_err().one_line();
    assert!(e.contains("engine: md2d runs 2D scenes") && e.contains("use md"), "{e}");
}

/// One scene, both engines: the same files with the same columns.
#[test]
fn both_engines_write_the_same_files_from_one_scene() {
    let (nscd, md) = (scratch::path("both-nscd"), scratch::path("both-md"));
    run_file(BLOCK.as_ref(), &nscd, &opts(None), &mut |_| {}).unwrap();
    run_file(BLOCK.as_ref(), &md, &opts(Some("md")), &mut |_| {}).unwrap();
    for f in ["series.csv", "contacts.csv"] {
        let header = |d: &Path| std::fs::read_to_string(d.join(f)).unwrap().lines().next().unwrap().to_string();
        assert_eq!(header(&nscd), header(&md), "{f}");
    }
    for f in ["final.json", "summary.json", "final_scene.toml"] {
        assert!(nscd.join(f).is_file() && md.join(f).is_file(), "{f}");
    }
    // The final scene of the MD run restarts on MD.
    assert!(Scene::load(md.join("final_scene.toml")).unwrap().is_planar_md());
    assert!(!Scene::load(nscd.join("final_scene.toml")).unwrap().is_planar_md());
}

/// A planar run stopped and resumed writes the bytes of the uninterrupted run.
#[test]
fn a_planar_run_stopped_and_resumed_writes_the_same_bytes() {
    let (whole, cut) = (scratch::path("whole"), scratch::path("cut"));
    run_file(BLOCK.as_ref(), &whole, &opts(Some("md")), &mut |_| {}).unwrap();
    let stop = RunOptions { stop_after: Some(3001), ..opts(Some("md")) };
    run_file(BLOCK.as_ref(), &cut, &stop, &mut |_| {}).unwrap();
    assert!(cut.join("checkpoint.json").is_file());
    let resume = RunOptions { resume: true, ..opts(Some("md")) };
    run_file(BLOCK.as_ref(), &cut, &resume, &mut |_| {}).unwrap();
    for f in ["series.csv", "final.json", "contacts.csv"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(cut.join(f)).unwrap(), "{f}");
    }
}

/// The settlement driver on the planar MD engine: the example sleeper scene
/// with `--engine md` runs 30 cycles with 18 computed, every landing relaxed
/// below the scene's tolerance, and resumes to the same numbers.
#[test]
fn the_settlement_driver_runs_on_the_planar_md_engine() {
    let scene = "examples/settlement_sleeper.toml";
    let out = scratch::path("driver");
    let s = ballast::open::settle_file(scene.as_ref(), &out, &opts(Some("md")), &mut |_| {}).unwrap().unwrap();
    assert_eq!((s.total_cycles, s.computed_cycles, s.jumps), (30, 18, 3));
    assert_eq!(json(&out.join("run.json"))["engine"], "md2d");
    let jumps: Vec<ballast::settlement::JumpRow> = ballast::io::read_csv(&out.join("jumps.csv")).unwrap();
    assert_eq!(jumps.len(), 3);
    for j in &jumps {
        assert!(j.relax_converged && j.max_overlap_after_relax_m <= j.relax_tolerance_m, "{j:?}");
    }
    let cut = scratch::path("driver-cut");
    let stop = RunOptions { stop_after: Some(20_000), ..opts(Some("md")) };
    let s1 = ballast::open::settle_file(scene.as_ref(), &cut, &stop, &mut |_| {}).unwrap().unwrap();
    assert_eq!(s1.end, "stopped");
    let resume = RunOptions { resume: true, ..opts(Some("md")) };
    let s2 = ballast::open::settle_file(scene.as_ref(), &cut, &resume, &mut |_| {}).unwrap().unwrap();
    assert_eq!(s2.settlement_m.to_bits(), s.settlement_m.to_bits());
}

/// Bad `[soft]` tables and engines: one line naming the key and the numbers.
#[test]
fn bad_soft_tables_name_the_key() {
    let base = std::fs::read_to_string(BLOCK).unwrap();
    let dir = scratch::path("errors");
    let cases: [(&str, &str); 6] = [
        ("[soft]\ndt = 1.0e-2\n", "stability limit"),
        ("[soft]\nmodel = \"soft\"\n", "soft.model: unknown model 'soft'"),
        ("[soft]\nnormal_stiffness = 1e6\nmax_overlap_ratio = 1e-3\n", "not both"),
        ("[soft]\nmax_overlap_ratio = 0.5\n", "soft.max_overlap_ratio: must be in (0, 0.1]"),
        ("[soft]\ndt = \"fast\"\n", "soft.dt: must be a time step (s) or \"auto\", got 'fast'"),
        ("[soft]\nstiffness = 1e6\n", "unknown field `stiffness`"),
    ];
    for (k, (table, want)) in cases.iter().enumerate() {
        let path = scene_file(&dir.join(k.to_string()), &format!("{base}\n{table}"));
        let e = run_file(&path, &dir.join(format!("out{k}")), &opts(Some("md")), &mut |_| {}).unwrap_err().one_line();
        assert!(e.contains(want), "{table}: {e}");
        assert!(!e.contains('\n'));
    }
    // The dt error names both numbers.
    let path = scene_file(&dir.join("dt"), &format!("{base}\n[soft]\ndt = 1.0e-2\n"));
    let e = run_file(&path, &dir.join("out-dt"), &opts(Some("md")), &mut |_| {}).unwrap_err().to_string();
    assert!(e.starts_with("soft.dt: 0.01 s is above the stability limit"), "{e}");
    // A 3D MD scene has no NSCD form.
    let e = run_file("examples/md_two_spheres.toml".as_ref(), &dir.join("out-3d"), &opts(Some("nscd")), &mut |_| {})
        .unwrap_err()
        .to_string();
    assert!(e.contains("engine: nscd runs 2D scenes, and this is a 3D MD scene"), "{e}");
}
