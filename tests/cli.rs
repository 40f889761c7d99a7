//! The `ballast run` command: output files on a valid scene, exit code 2 and a
//! one-line error on an invalid one.

use crate::fixtures;
use crate::scratch;

use std::process::Command;

/// The block on the floor of `examples/block_on_floor.toml` with a pebble beside it, 50 steps, a row every 7.
fn scene_text() -> String {
    fixtures::block_and_pebble()
}

fn ballast() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ballast"))
}

#[test]
fn run_writes_the_outputs() {
    let dir = scratch::dir("valid");
    let scene = dir.join("in.toml");
    let text = scene_text();
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let result = ballast().arg("run").arg(&scene).arg("--out").arg(&out).arg("--quiet").output().unwrap();
    assert!(result.status.success(), "stderr: {}", String::from_utf8_lossy(&result.stderr));

    for name in ["series.csv", "final.json", "scene.toml", "run.json", "final_scene.toml"] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    // scene.toml is a byte copy.
    assert_eq!(std::fs::read(out.join("scene.toml")).unwrap(), text.as_bytes());

    // series.csv: required columns, one row every 7 steps and the last (50 steps: 7, 14, …, 49, 50).
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let mut lines = series.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    for col in [
        "time_s",
        "kinetic_energy_J",
        "contacts",
        "iterations",
        "criterion",
        "mean_overlap_m",
        "max_overlap_m",
        "total_overlap_m",
    ] {
        assert!(header.contains(&col), "column {col} missing from {header:?}");
    }
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse::<f64>().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 8);
    let t = header.iter().position(|&c| c == "time_s").unwrap();
    assert!((rows[0][t] - 0.007).abs() < 1e-12);
    assert!((rows[7][t] - 0.05).abs() < 1e-12);
    for r in &rows {
        assert_eq!(r.len(), header.len());
    }

    // final.json: bodies in scene order.
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("final.json")).unwrap()).unwrap();
    assert_eq!(json["step"], 50);
    assert!((json["time"].as_f64().unwrap() - 0.05).abs() < 1e-12);
    let names: Vec<&str> = json["bodies"].as_array().unwrap().iter().map(|b| b["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["floor", "block", "pebble"]);
    let block = &json["bodies"][1];
    // The block rests on the floor: its centre stays 5 cm above it.
    assert!((block["position"][1].as_f64().unwrap() - 0.05).abs() < 1e-4);
    assert!(block["velocity"][0].is_number() && block["spin"].is_number() && block["angle"].is_number());

    // run.json
    let run: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("run.json")).unwrap()).unwrap();
    assert_eq!(run["seed"], 42);
    assert_eq!(run["engine"], "nscd");
    assert_eq!(run["steps"], 50);
    assert_eq!(run["dt"], 1.0e-3);
    assert_eq!(run["version"], env!("CARGO_PKG_VERSION"));

    // final_scene.toml is a valid scene with the final state; it runs again.
    let restarted = ballast()
        .arg("run")
        .arg(out.join("final_scene.toml"))
        .arg("--out")
        .arg(dir.join("out2"))
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(restarted.status.success(), "stderr: {}", String::from_utf8_lossy(&restarted.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}

fn assert_scene_error(args: &[&str], scene: Option<&str>, test: &str, expected: &str) {
    let dir = scratch::dir(test);
    let path = dir.join("bad.toml");
    if let Some(text) = scene {
        std::fs::write(&path, text).unwrap();
    }
    let result = ballast().arg("run").arg(&path).arg("--out").arg(dir.join("out")).args(args).output().unwrap();
    assert_eq!(result.status.code(), Some(2));
    let stderr = String::from_utf8(result.stderr).unwrap();
    assert!(stderr.starts_with("error: "), "stderr: {stderr:?}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "stderr: {stderr:?}");
    assert!(stderr.contains(expected), "stderr: {stderr:?}");
    assert!(!dir.join("out").join("series.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_scene_exits_with_code_2() {
    let bad = scene_text().replace("friction = 0.5", "friction = -0.5");
    assert_scene_error(&["--quiet"], Some(&bad), "bad", "contact[0].friction");
    let unknown = scene_text().replace("seed = 42", "seed = 42\nsteps = 3");
    assert_scene_error(&[], Some(&unknown), "unknown", "bad.toml line 7: unknown field `steps`");
    let polygon = scene_text().replace("[0.05, -0.05], [0.05, 0.05]", "[0.05, 0.05], [0.05, -0.05]");
    assert_scene_error(&["--quiet"], Some(&polygon), "polygon", "body[1] 'block': polygon");
}

#[test]
fn missing_scene_file_exits_with_code_2() {
    assert_scene_error(&["--quiet"], None, "missing", "cannot read scene file");
}

/// A block squeezed between a fixed floor and a press whose velocity is imposed:
/// nothing can stop the press, so the overlap runs away.
const SQUEEZE: &str = r#"
[simulation]
engine = "nscd"
dt = 1.0e-3
duration = 0.1

[output]
every = 10

[[material]]
name = "grain"
density = 2700.0

[[body]]
name = "floor"
material = "grain"
polygon = [[-0.5, -0.1], [0.5, -0.1], [0.5, 0.0], [-0.5, 0.0]]
position = [0.0, 0.0]
fixed = true

[[body]]
name = "block"
material = "grain"
polygon = [[-0.05, -0.05], [0.05, -0.05], [0.05, 0.05], [-0.05, 0.05]]
position = [0.0, 0.05]

[[body]]
name = "press"
material = "grain"
polygon = [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.05], [-0.1, 0.05]]
position = [0.0, 0.11]
imposed = { vx = 0.0, vy = -1.0, spin = 0.0 }
"#;

#[test]
fn diverging_run_exits_with_code_1_and_keeps_the_last_good_state() {
    let dir = scratch::dir("diverge");
    let path = dir.join("in.toml");
    std::fs::write(&path, SQUEEZE).unwrap();
    let out = dir.join("out");
    let result = ballast().arg("run").arg(&path).arg("--out").arg(&out).arg("--quiet").output().unwrap();
    let stderr = String::from_utf8(result.stderr).unwrap();
    assert_eq!(result.status.code(), Some(1), "stderr: {stderr:?}");
    assert!(stderr.starts_with("error: step "), "stderr: {stderr:?}");
    assert!(stderr.contains("'block'"), "stderr: {stderr:?}");
    assert_eq!(stderr.trim_end().lines().count(), 1);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("final.json")).unwrap()).unwrap();
    let step = json["step"].as_u64().unwrap();
    assert!(step > 0 && step < 100, "step {step}");
    assert!(json["bodies"][1]["position"][1].as_f64().unwrap().is_finite());
    // The last row of the series is the last good step, even off the output grid.
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let last: f64 = series.lines().last().unwrap().split(',').next().unwrap().parse().unwrap();
    assert_eq!(last, json["time"].as_f64().unwrap());
    assert!(!out.join("final_scene.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--change-solver` resumes a run with another tolerance, says so and records it; it needs `--resume`.
#[test]
fn a_run_resumes_with_another_tolerance() {
    let dir = scratch::dir("change-solver");
    let (a, b) = (dir.join("a.toml"), dir.join("b.toml"));
    let text = scene_text();
    std::fs::write(&a, &text).unwrap();
    std::fs::write(&b, text.replacen("[output]", "[nscd]\ntolerance = 3e-6\n\n[output]", 1)).unwrap();
    let out = dir.join("out");
    let run = |scene: &std::path::Path, extra: &[&str]| {
        ballast().arg("run").arg(scene).arg("--out").arg(&out).arg("--quiet").args(extra).output().unwrap()
    };
    assert!(run(&a, &["--stop-after", "20"]).status.success());
    let refused = run(&b, &["--change-solver"]);
    assert!(!refused.status.success());
    assert!(String::from_utf8_lossy(&refused.stderr).contains("--resume"));
    let r = run(&b, &["--resume", "--change-solver"]);
    assert!(r.status.success(), "stderr: {}", String::from_utf8_lossy(&r.stderr));
    let stdout = String::from_utf8_lossy(&r.stdout);
    assert!(stdout.contains("resumed at step 20") && stdout.contains("nscd.tolerance = 0.000003"), "{stdout}");
    assert!(out.join("solver_changes.csv").is_file() && out.join("final.json").is_file());
}

/// A run stopped twice and resumed from its checkpoints writes, byte for byte,
/// the series and final state of the uninterrupted run; a checkpoint is refused
/// for another scene.
#[test]
fn stopped_and_resumed_run_matches_the_uninterrupted_run() {
    let dir = scratch::dir("resume");
    let scene = dir.join("in.toml");
    // With per-cycle statistics (5 cycles of 10 ms over the 50 steps).
    let text = scene_text().replace("every = 7", "every = 7\ncycles = { frequency = 100.0, body = \"block\" }");
    assert!(text.contains("cycles = "), "scene template changed");
    std::fs::write(&scene, &text).unwrap();
    let run = |out: &std::path::Path, extra: &[&str]| {
        let r = ballast().arg("run").arg(&scene).arg("--out").arg(out).arg("--quiet").args(extra).output().unwrap();
        assert!(r.status.success(), "stderr: {}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).to_string()
    };
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    run(&whole, &["--vtk-every", "10"]);
    // Stop at step 17 (between two series rows), again 20 steps later, then finish.
    assert!(run(&parts, &["--stop-after", "17", "--vtk-every", "10"]).contains("stopped at step 17"));
    assert!(parts.join("checkpoint.json").is_file() && !parts.join("final.json").exists());
    assert!(run(&parts, &["--resume", "--stop-after", "20", "--vtk-every", "10"]).contains("stopped at step 37"));
    // A kill after the checkpoint leaves rows the checkpoint does not know: they go.
    let mut f = std::fs::OpenOptions::new().append(true).open(parts.join("series.csv")).unwrap();
    std::io::Write::write_all(&mut f, b"9e9,9e9,9,9,9,9e9,1,9e9,9e9,9e9\n").unwrap();
    drop(f);
    run(&parts, &["--resume", "--vtk-every", "10"]);
    // Snapshots at steps 0, 10, …, 50 and their ParaView collection are identical too.
    let mut files = ["series.csv", "final.json", "run.pvd", "cycles.csv"].map(String::from).to_vec();
    assert_eq!(std::fs::read_to_string(whole.join("cycles.csv")).unwrap().lines().count(), 6, "header + 5 cycles");
    for step in (0..=50).step_by(10) {
        files.push(format!("vtk/bodies_{step:09}.vtp"));
        files.push(format!("vtk/contacts_{step:09}.vtp"));
    }
    for f in &files {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(parts.join(f)).unwrap(), "{f} differs");
    }
    assert!(!parts.join("checkpoint.json").exists(), "a finished run leaves no checkpoint");
    // summary.json: the same sums over the 50 steps; only the wall time may differ.
    let summary = |dir: &std::path::Path| {
        let mut v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
        for k in ["wall_time_s", "wall_time_per_step_s", "wall_time_per_cycle_s", "body_steps_per_s"] {
            assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
            v.as_object_mut().unwrap().remove(k);
        }
        v
    };
    let s = summary(&whole);
    assert_eq!(s, summary(&parts));
    assert_eq!((s["steps"].as_u64(), s["cycles"].as_u64()), (Some(50), Some(5)));
    // Its mean sweeps per step are those of the per-cycle means (5 cycles of 10 steps).
    let cycles = std::fs::read_to_string(whole.join("cycles.csv")).unwrap();
    let col = cycles.lines().next().unwrap().split(',').position(|c| c == "iterations").unwrap();
    let per_cycle: Vec<f64> = cycles.lines().skip(1).map(|l| l.split(',').nth(col).unwrap().parse().unwrap()).collect();
    let mean = per_cycle.iter().sum::<f64>() / per_cycle.len() as f64;
    assert!((s["mean_iterations"].as_f64().unwrap() - mean).abs() < 1e-12 * mean);
    // Checkpoints written by the clock (here after every step) change no number.
    let clocked = dir.join("clocked");
    run(&clocked, &["--checkpoint-every", "1e-9"]);
    for f in ["series.csv", "final.json"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(clocked.join(f)).unwrap(), "{f} differs");
    }

    // A checkpoint of another scene is refused with a one-line input error.
    run(&parts, &["--stop-after", "5"]);
    std::fs::write(&scene, text.replace("every = 7", "every = 8")).unwrap();
    let r = ballast().arg("run").arg(&scene).arg("--out").arg(&parts).arg("--resume").output().unwrap();
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.starts_with("error:") && err.contains("another scene") && err.trim().lines().count() == 1, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A deposit with `simulation.equilibrium` ends once the kinetic energy has stayed
/// below the threshold for the window, with the usual final outputs; a run stopped
/// inside that window and resumed ends at the same step with the same numbers.
#[test]
fn run_stops_at_equilibrium_and_resumes_into_the_same_stop() {
    let dir = scratch::dir("equilibrium");
    let scene = dir.join("in.toml");
    // 2 s of simulated time; the block and pebble settle within a fraction of it.
    let text = scene_text()
        .replace("duration = 0.05", "duration = 2.0")
        .replace("[output]", "equilibrium = { kinetic_energy = 1e-12, steps = 50 }\n\n[output]");
    assert!(text.contains("equilibrium = "), "scene template changed");
    std::fs::write(&scene, &text).unwrap();
    let run = |out: &std::path::Path, extra: &[&str]| {
        let r = ballast().arg("run").arg(&scene).arg("--out").arg(out).arg("--quiet").args(extra).output().unwrap();
        assert!(r.status.success(), "stderr: {}", String::from_utf8_lossy(&r.stderr));
        String::from_utf8_lossy(&r.stdout).to_string()
    };
    let whole = dir.join("whole");
    assert!(run(&whole, &[]).contains("(equilibrium reached)"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("final.json")).unwrap()).unwrap();
    let stop = json["step"].as_u64().unwrap();
    // The pebble drops 10 cm (0.14 s), the 50-step window follows: far before 2000 steps.
    assert!((60..1000).contains(&stop), "stopped at step {stop}");
    assert!(whole.join("final_scene.toml").is_file() && !whole.join("checkpoint.json").exists());
    let series = std::fs::read_to_string(whole.join("series.csv")).unwrap();
    let last_time: f64 = series.lines().last().unwrap().split(',').next().unwrap().parse().unwrap();
    assert!((last_time - json["time"].as_f64().unwrap()).abs() < 1e-12, "the stop step is the last row");

    let parts = dir.join("parts");
    run(&parts, &["--stop-after", &(stop - 10).to_string()]);
    run(&parts, &["--resume"]);
    for f in ["series.csv", "final.json"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(parts.join(f)).unwrap(), "{f} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
