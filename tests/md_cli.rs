//! `ballast run` on MD scenes: the outputs of `examples/md_two_spheres.toml`,
//! stop and resume with the same bytes, the equilibrium stop, VTK snapshots,
//! servo-wall columns, and exit code 2 with one line on an invalid scene.

use crate::scratch;

use ballast::scene::SceneFile;
use std::path::Path;
use std::process::{Command, Output};

/// The example scene's text.
fn example() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/md_two_spheres.toml");
    std::fs::read_to_string(path).unwrap()
}

/// `ballast run SCENE --out OUT --quiet EXTRA…`.
fn run(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_ballast"))
        .arg("run")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .arg("--quiet")
        .args(extra)
        .output()
        .unwrap()
}

/// As [`run`], which must succeed; returns its stdout.
fn run_ok(scene: &Path, out: &Path, extra: &[&str]) -> String {
    let r = run(scene, out, extra);
    assert!(r.status.success(), "stderr: {}", String::from_utf8_lossy(&r.stderr));
    String::from_utf8_lossy(&r.stdout).to_string()
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn vector(v: &serde_json::Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()).collect()
}

const HEADER: &str =
    "time_s,kinetic_energy_J,elastic_energy_J,potential_energy_J,contacts,wall_contacts,max_overlap_m,\
mean_overlap_m,coordination,packing_fraction";

#[test]
fn the_example_writes_every_output() {
    let dir = scratch::dir("example");
    let scene = dir.join("in.toml");
    let text = example();
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    let stdout = run_ok(&scene, &out, &[]);
    assert!(stdout.contains("100000 steps") && stdout.contains("body-steps/s"), "{stdout}");
    for name in ["series.csv", "final.json", "summary.json", "run.json", "scene.toml", "final_scene.toml"] {
        assert!(out.join(name).is_file(), "{name} missing");
    }
    assert!(!out.join("checkpoint.json").exists() && !out.join("vtk").exists());
    assert_eq!(std::fs::read_to_string(out.join("scene.toml")).unwrap(), text, "a byte copy");

    // series.csv: the exact header, one row every 500 steps of 100 000.
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let mut lines = series.lines();
    assert_eq!(lines.next().unwrap(), format!("{HEADER},base_force_N,mould_force_N"));
    let rows: Vec<Vec<f64>> = lines.map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    assert_eq!(rows.len(), 200);
    assert!(rows.iter().all(|r| r.len() == 12));
    assert!((rows[0][0] - 1e-3).abs() < 1e-12 && (rows[199][0] - 0.2).abs() < 1e-12);
    // At the end the spheres have landed and roll: the base carries the lower one
    // and at most the upper one too, within 1 %; the energy went down.
    let weight = 4.0 / 3.0 * std::f64::consts::PI * 0.0032f64.powi(3) * 2710.0 * 9.81;
    let (first, last) = (&rows[0], &rows[199]);
    assert!(last[10] > 0.99 * weight && last[10] < 2.01 * weight, "base force {} vs weight {weight}", last[10]);
    assert!(last[1] + last[3] < first[1] + first[3], "energy {last:?} vs {first:?}");
    assert!(last[2] > 0.0 && last[5] >= 1.0, "{last:?}");
    assert_eq!(last[11], 0.0, "a cylinder has no single normal force");

    // final.json: 3-component vectors, bodies and walls in scene order.
    let fin = json(&out.join("final.json"));
    assert_eq!(
        (fin["step"].as_u64(), fin["time"].as_f64().map(|t| (t - 0.2).abs() < 1e-12)),
        (Some(100000), Some(true))
    );
    let names: Vec<&str> = fin["bodies"].as_array().unwrap().iter().map(|b| b["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["lower", "upper"]);
    for b in fin["bodies"].as_array().unwrap() {
        for key in ["position", "velocity", "spin"] {
            assert_eq!(vector(&b[key]).len(), 3, "{key}");
        }
        assert_eq!(b["radius"].as_f64(), Some(0.0032));
        // Above the base, inside the cylinder.
        let x = vector(&b["position"]);
        assert!(x[2] > 0.0031 && x[0].hypot(x[1]) < 0.0075 - 0.0031, "{x:?}");
    }
    let walls: Vec<&str> = fin["walls"].as_array().unwrap().iter().map(|w| w["name"].as_str().unwrap()).collect();
    assert_eq!(walls, ["base", "mould"]);
    assert_eq!(vector(&fin["walls"][0]["force"]).len(), 3);
    assert_eq!(fin["walls"][0]["displacement"].as_f64(), Some(0.0));
    assert!((vector(&fin["walls"][0]["force"])[2] + last[10]).abs() < 1e-12, "force on the base is −its load");

    let info = json(&out.join("run.json"));
    assert_eq!(
        (info["engine"].as_str(), info["seed"].as_u64(), info["steps"].as_u64()),
        (Some("md"), Some(1), Some(100000))
    );
    assert_eq!(info["dt"].as_f64(), Some(2e-6));
    let summary = json(&out.join("summary.json"));
    assert_eq!((summary["steps"].as_u64(), summary["bodies"].as_u64()), (Some(100000), Some(2)));
    assert!(summary["body_steps_per_s"].as_f64().unwrap() > 0.0);
    assert!(summary["max_overlap_m"].as_f64().unwrap() > 0.0 && summary["mean_contacts"].as_f64().unwrap() > 0.0);
    assert_eq!(summary["equilibrium"], false);

    // final_scene.toml is an MD scene with the final state; it runs again.
    let restart = std::fs::read_to_string(out.join("final_scene.toml")).unwrap();
    let again = ballast::scene::MdScene::from_toml_str(&restart).unwrap();
    assert_eq!(again.bodies[1].position, <[f64; 3]>::try_from(vector(&fin["bodies"][1]["position"])).unwrap());
    let short = restart.replace("duration = 0.2\n", "duration = 0.001\n");
    assert_ne!(short, restart);
    let restart_path = dir.join("restart.toml");
    std::fs::write(&restart_path, short).unwrap();
    run_ok(&restart_path, &dir.join("out2"), &[]);
    // The same numbers on one thread.
    let one = dir.join("one");
    run_ok(&scene, &one, &["--threads", "1"]);
    assert_eq!(std::fs::read(one.join("series.csv")).unwrap(), series.as_bytes());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn stopped_and_resumed_run_matches_the_uninterrupted_run() {
    let dir = scratch::dir("resume");
    let scene = dir.join("in.toml");
    std::fs::write(&scene, example()).unwrap();
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    run_ok(&scene, &whole, &["--vtk-every", "10000"]);
    // Stop off the output grid, again 20 000 steps later, then finish.
    assert!(
        run_ok(&scene, &parts, &["--stop-after", "12345", "--vtk-every", "10000"]).contains("stopped at step 12345")
    );
    assert!(parts.join("checkpoint.json").is_file() && !parts.join("final.json").exists());
    let resumed = run_ok(&scene, &parts, &["--resume", "--stop-after", "20000", "--vtk-every", "10000"]);
    assert!(resumed.contains("stopped at step 32345"), "{resumed}");
    // A kill after the checkpoint leaves rows the checkpoint does not know: they go.
    let mut f = std::fs::OpenOptions::new().append(true).open(parts.join("series.csv")).unwrap();
    std::io::Write::write_all(&mut f, b"9e9,9e9,9e9,9e9,9,9,9e9,9e9,9e9,9e9,9e9\n").unwrap();
    drop(f);
    run_ok(&scene, &parts, &["--resume", "--vtk-every", "10000"]);
    assert!(!parts.join("checkpoint.json").exists(), "a finished run leaves no checkpoint");
    let mut files = ["series.csv", "final.json", "final_scene.toml", "run.pvd"].map(String::from).to_vec();
    files.extend((0..=100000).step_by(10000).map(|k| format!("vtk/spheres_{k:09}.vtp")));
    for f in &files {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(parts.join(f)).unwrap(), "{f} differs");
    }
    // summary.json: the same sums; only the wall time and the speed may differ.
    let summary = |d: &Path| {
        let mut v = json(&d.join("summary.json"));
        for k in ["wall_time_s", "wall_time_per_step_s", "body_steps_per_s"] {
            assert!(v[k].as_f64().unwrap() > 0.0, "{k}");
            v.as_object_mut().unwrap().remove(k);
        }
        v
    };
    assert_eq!(summary(&whole), summary(&parts));
    // Checkpoints written by the clock (after every step) change no number: the
    // first 1000 steps give the first two rows.
    let clocked = dir.join("clocked");
    run_ok(&scene, &clocked, &["--checkpoint-every", "1e-9", "--stop-after", "1000"]);
    let head: Vec<String> =
        std::fs::read_to_string(whole.join("series.csv")).unwrap().lines().take(3).map(|l| format!("{l}\n")).collect();
    assert_eq!(std::fs::read_to_string(clocked.join("series.csv")).unwrap(), head.concat());
    // A checkpoint of another scene is refused.
    std::fs::write(&scene, example().replace("every = 500", "every = 400")).unwrap();
    let r = run(&scene, &clocked, &["--resume"]);
    assert_eq!(r.status.code(), Some(2));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(err.starts_with("error:") && err.contains("another scene") && err.trim().lines().count() == 1, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn vtk_snapshots_are_sphere_points_listed_in_the_pvd() {
    let dir = scratch::dir("vtk");
    let scene = dir.join("in.toml");
    std::fs::write(&scene, example().replace("duration = 0.2\n", "duration = 0.01\n")).unwrap();
    let out = dir.join("out");
    run_ok(&scene, &out, &["--vtk-every", "1000"]);
    let pvd = std::fs::read_to_string(out.join("run.pvd")).unwrap();
    let files: Vec<&str> = pvd.split("file=\"").skip(1).map(|s| &s[..s.find('"').unwrap()]).collect();
    let expected: Vec<String> = (0..=5000).step_by(1000).map(|k| format!("vtk/spheres_{k:09}.vtp")).collect();
    assert_eq!(files, expected);
    assert_eq!(pvd.matches("part=\"0\" name=\"spheres\"").count(), 6);
    for f in &files {
        let vtp = std::fs::read_to_string(out.join(f)).unwrap();
        assert!(vtp.contains("<VTKFile type=\"PolyData\""), "{f}");
        assert!(vtp.contains("NumberOfPoints=\"2\" NumberOfVerts=\"2\""), "{f}");
        assert!(vtp.contains("<PointData Scalars=\"radius\" Vectors=\"velocity\">"), "{f}");
        for array in ["radius", "velocity", "spin", "id", "material"] {
            assert!(vtp.contains(&format!("Name=\"{array}\"")), "{array} missing from {f}");
        }
        assert!(vtp.contains("\n3.2e-3\n3.2e-3\n"), "radii");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The legacy form of a spheres snapshot holds the same arrays as point data.
#[test]
fn legacy_spheres_snapshot() {
    let dir = scratch::dir("legacy");
    let sys = ballast::scene::MdScene::from_toml_str(&example()).unwrap().build().unwrap();
    let path = dir.join("spheres.vtk");
    ballast::md::vtk::write_spheres(&path, &sys).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("# vtk DataFile Version 3.0\nballast MD spheres, step 0"), "{text}");
    for line in [
        "DATASET POLYDATA\nPOINTS 2 double\n0e0 0e0 4e-3\n2e-3 1e-3 1.2e-2\n",
        "VERTICES 2 4\n1 0\n1 1\n",
        "POINT_DATA 2\nSCALARS radius double 1\nLOOKUP_TABLE default\n3.2e-3\n3.2e-3\n",
        "SCALARS id int 1\nLOOKUP_TABLE default\n0\n1\n",
        "VECTORS velocity double\n",
        "FIELD FieldData 1\nspin 3 2 double\n",
    ] {
        assert!(text.contains(line), "{line:?} missing from {text}");
    }
    assert!(!text.contains("CELL_DATA"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn run_stops_at_equilibrium() {
    let dir = scratch::dir("equilibrium");
    let scene = dir.join("in.toml");
    // At most 0.4 s; the spheres have landed and roll slowly after about 0.2 s (a
    // window of 2000 steps, 4 ms, is longer than the top of a bounce).
    let text = example()
        .replace("duration = 0.2\n", "duration = 0.4\n")
        .replace("seed = 1\n", "seed = 1\nequilibrium = { kinetic_energy = 1e-8, steps = 2000 }\n");
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    assert!(run_ok(&scene, &out, &[]).contains("(equilibrium reached)"));
    let fin = json(&out.join("final.json"));
    let stop = fin["step"].as_u64().unwrap();
    assert!((2000..200000).contains(&stop), "stopped at step {stop}");
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let last: Vec<f64> = series.lines().last().unwrap().split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(last[0], fin["time"].as_f64().unwrap(), "the stop step is the last row");
    assert!(last[1] < 1e-8 && last[2] > 0.0, "measured at the stop: {last:?}");
    assert_eq!(json(&out.join("summary.json"))["equilibrium"], true);
    // Stopped inside the window and resumed: the same stop, the same bytes.
    let parts = dir.join("parts");
    run_ok(&scene, &parts, &["--stop-after", &(stop - 100).to_string()]);
    run_ok(&scene, &parts, &["--resume"]);
    for f in ["series.csv", "final.json"] {
        assert_eq!(std::fs::read(out.join(f)).unwrap(), std::fs::read(parts.join(f)).unwrap(), "{f} differs");
    }
    // With E_k / E_p as well (both must hold): a later stop, or the same.
    let ratio = text.replace("kinetic_energy = 1e-8,", "kinetic_energy = 1e-8, energy_ratio = 1e-5,");
    std::fs::write(&scene, ratio).unwrap();
    let both = dir.join("both");
    run_ok(&scene, &both, &[]);
    assert!(json(&both.join("final.json"))["step"].as_u64().unwrap() >= stop);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Spheres released from rest meet `E_k < r E_p` at once (E_k = 0): the
/// equilibrium window must not start before the condition has failed once. The
/// lower sphere's bottom is 0.8 mm above the base: it lands after
/// √(2 · 0.8 mm / g) = 12.8 ms = 6386 steps of 2 µs; with `energy_ratio = 1e-2`
/// and a 100-step window, a run that counted from the start stopped at step 100.
#[test]
fn equilibrium_is_not_declared_before_the_sample_has_moved() {
    let dir = scratch::dir("equilibrium_rest");
    let scene = dir.join("in.toml");
    let text = example()
        .replace("seed = 1\n", "seed = 1\nequilibrium = { energy_ratio = 1e-2, steps = 100 }\n")
        .replace("every = 500", "every = 1");
    std::fs::write(&scene, &text).unwrap();
    let out = dir.join("out");
    run_ok(&scene, &out, &[]);
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    let rows: Vec<Vec<f64>> =
        series.lines().skip(1).map(|l| l.split(',').map(|x| x.parse().unwrap()).collect()).collect();
    // The condition held over the first 100 steps (columns: time, E_k, E_el, E_p).
    assert!(rows[..100].iter().all(|r| r[1] < 1e-2 * r[3]), "the test needs a calm start");
    let stop = json(&out.join("final.json"))["step"].as_u64().unwrap();
    assert!(stop > 6386, "stopped at step {stop}, before the lower sphere landed");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn servo_walls_get_a_position_column() {
    let dir = scratch::dir("servo");
    let scene = dir.join("in.toml");
    let lid = "[[wall]]\nname = \"lid\"\nmaterial = \"steel\"\n\
               disc = { point = [0.0, 0.0, 0.02], normal = [0.0, 0.0, -1.0], radius = 0.0075 }\n\
               servo = { mass = 0.01, viscosity = 1.0, force = 0.05 }\n\n[[body]]";
    let text = example().replace("duration = 0.2\n", "duration = 0.004\n").replacen("[[body]]", lid, 1);
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    run_ok(&scene, &out, &[]);
    let series = std::fs::read_to_string(out.join("series.csv")).unwrap();
    assert_eq!(
        series.lines().next().unwrap(),
        format!("{HEADER},base_force_N,mould_force_N,lid_force_N,lid_position_m")
    );
    // The lid is pushed down by 0.05 N against its viscosity: it moves down.
    let s: f64 = series.lines().last().unwrap().split(',').next_back().unwrap().parse().unwrap();
    assert!(s > 0.0, "displacement along its normal (−z): {s}");
    let fin = json(&out.join("final.json"));
    assert_eq!(fin["walls"][2]["displacement"].as_f64(), Some(s));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A servo lid of 10 g pushed by 10 MN crushes the upper sphere within a few
/// steps (a scene validation cannot foresee: the load is a force, not a speed):
/// the run diverges (exit code 1, one line naming the step and the sphere); the
/// outputs hold the last good state, the step before. (Spheres started one inside
/// the other are refused at load: tests/md_safety.rs.)
#[test]
fn diverging_run_exits_with_code_1() {
    let dir = scratch::dir("diverge");
    let scene = dir.join("in.toml");
    let lid = "[[wall]]\nname = \"lid\"\nmaterial = \"steel\"\n\
               disc = { point = [0.0, 0.0, 0.016], normal = [0.0, 0.0, -1.0], radius = 0.0075 }\n\
               servo = { mass = 0.01, viscosity = 0.0, force = 1e7 }\n\n[[body]]";
    std::fs::write(&scene, example().replacen("[[body]]", lid, 1)).unwrap();
    let out = dir.join("out");
    let r = run(&scene, &out, &[]);
    let stderr = String::from_utf8(r.stderr).unwrap();
    assert_eq!(r.status.code(), Some(1), "stderr: {stderr:?}");
    assert!(stderr.starts_with("error: step ") && stderr.contains("runaway"), "{stderr:?}");
    assert_eq!(stderr.trim_end().lines().count(), 1);
    // The step named is the one being made; the outputs hold the one before.
    let step: u64 = stderr["error: step ".len()..].split(':').next().unwrap().parse().unwrap();
    assert!((1..10).contains(&step), "crushed within a few steps: {stderr}");
    let fin = json(&out.join("final.json"));
    assert_eq!(fin["step"].as_u64(), Some(step - 1));
    assert!(vector(&fin["bodies"][1]["position"]).iter().all(|x| x.is_finite()));
    assert!(out.join("summary.json").is_file() && !out.join("final_scene.toml").exists());
    // The contact list of the last good step.
    let contacts = ballast::engine::contacts::read(&out.join("contacts.csv")).unwrap();
    assert!(contacts.iter().all(|c| c.f_n.is_finite() && c.gap_m < 0.0), "{contacts:?}");
    // The header, and the row of the last good step if one was made.
    let rows = std::fs::read_to_string(out.join("series.csv")).unwrap().lines().count();
    assert_eq!(rows, 1 + usize::from(step > 1));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs an invalid scene: exit code 2, one line `error: …` containing `expected`, no outputs.
fn assert_refused(text: &str, extra: &[&str], test: &str, expected: &str) {
    let dir = scratch::dir(test);
    let path = dir.join("bad.toml");
    std::fs::write(&path, text).unwrap();
    let r = run(&path, &dir.join("out"), extra);
    assert_eq!(r.status.code(), Some(2));
    let stderr = String::from_utf8(r.stderr).unwrap();
    assert!(stderr.starts_with("error: "), "stderr: {stderr:?}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "stderr: {stderr:?}");
    assert!(stderr.contains(expected), "stderr: {stderr:?}");
    assert!(!dir.join("out").join("series.csv").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn invalid_scenes_exit_with_code_2_and_one_line() {
    let text = example();
    assert_refused(
        &text.replace("sphere = 0.0032\nposition = [0.0, 0.0, 0.004]", "sphere = -0.001\nposition = [0.0, 0.0, 0.004]"),
        &[],
        "radius",
        "body[0] 'lower': sphere: must be positive and finite, got -0.001",
    );
    assert_refused(
        &text.replace("poisson = 0.25", "poisson = 0.25\nhardness = 1.0"),
        &[],
        "unknown",
        "bad.toml line 28: unknown field `hardness`",
    );
    assert_refused(
        &text.replace("engine = \"md\"", "engine = \"dem\""),
        &[],
        "engine",
        "unknown engine 'dem', expected 'nscd', 'md2d' or 'md'",
    );
    assert_refused(
        &text.replace("between = [\"diorite\", \"steel\"]", "between = [\"steel\", \"steel\"]"),
        &[],
        "law",
        "contact: no [[contact]] between materials 'diorite' and 'steel'",
    );
    assert_refused(&text, &["--checkpoint-every", "nan"], "checkpoint", "--checkpoint-every");
}
