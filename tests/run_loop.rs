//! The library's run loop (`ballast::run::Runner`), the same tests on both
//! engines: a run stopped twice and resumed writes the same bytes as the
//! uninterrupted run; the equilibrium stop ends at the same step after a resume
//! inside its window; a diverging run stops with the step and body named and
//! leaves the last good state and its row; every CSV it writes reads back
//! through the library's row types.

use crate::fixtures;
use crate::scratch;

use ballast::engine::Engine;
use ballast::engine::FinalState;
use ballast::run::RunEnd;
use ballast::run::{RunOptions, RunPlan, Runner, Status};
use ballast::scene::common::{CyclesSpec, OutputSection};
use ballast::scene::SceneFile;
use ballast::scene::{MdScene, Scene};
use ballast::Error;
use std::path::{Path, PathBuf};

/// NSCD: the block of `examples/block_on_floor.toml` dropped 1 cm on its floor and a pentagon beside it, 5 cycles of 10 ms
/// followed on the block, with the positions of the mobile bodies per cycle.
fn nscd_scene() -> Scene {
    let mut scene = fixtures::block_and_pebble_scene();
    scene.bodies[1].position = [0.0, 0.06];
    let cycles = CyclesSpec { frequency: 100.0, body: Some("block".into()), positions: Some(true) };
    scene.output.get_or_insert_with(Default::default).cycles = Some(cycles);
    scene
}

/// [`nscd_scene`] as text.
fn nscd_text() -> String {
    nscd_scene().to_toml_string().unwrap()
}

/// MD: two Hertz spheres dropped on a base inside a cylinder (the example
/// scene, shortened), with `lid` a servo lid above them, cycles of 5 ms.
fn md_scene(duration: f64, with_lid: bool) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/md_two_spheres.toml");
    let lid = "[[wall]]\nname = \"lid\"\nmaterial = \"steel\"\n\
               disc = { point = [0.0, 0.0, 0.03], normal = [0.0, 0.0, -1.0], radius = 0.0075 }\n\
               servo = { mass = 0.01, viscosity = 1.0, force = 0.05 }\n\n[[body]]";
    let text = std::fs::read_to_string(path).unwrap();
    let out = text
        .replace("duration = 0.2\n", &format!("duration = {duration}\n"))
        .replace("every = 500\n", "every = 300\ncycles = { frequency = 200.0, positions = true }\n")
        .replacen("[[body]]", if with_lid { lid } else { "[[body]]" }, 1);
    assert!(out.contains("cycles = ") && out.contains("name = \"lid\"") == with_lid, "example scene changed");
    out
}

/// [`nscd_text`] and [`md_scene`] (lasting `md_duration` seconds, no lid) written as `dir/nscd.toml` and
/// `dir/md.toml`, for the tests that open scene files.
fn scene_files(dir: &Path, md_duration: f64) -> (PathBuf, PathBuf) {
    let (nscd, md) = (dir.join("nscd.toml"), dir.join("md.toml"));
    std::fs::write(&nscd, nscd_text()).unwrap();
    std::fs::write(&md, md_scene(md_duration, false)).unwrap();
    (nscd, md)
}

fn quiet() -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() }
}

/// The files two runs must share byte for byte.
fn outputs(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = ["series.csv", "cycles.csv", "final.json", "run.pvd"]
        .iter()
        .chain(&["cycle_bodies.csv", "cycle_displacements.npy"])
        .map(|f| dir.join(f))
        .collect();
    if let Ok(entries) = std::fs::read_dir(dir.join("vtk")) {
        let mut vtk: Vec<PathBuf> = entries.map(|e| e.unwrap().path()).collect();
        vtk.sort();
        files.extend(vtk);
    }
    files
}

fn summary_without_wall_time(dir: &Path) -> serde_json::Value {
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    for k in ["wall_time_s", "wall_time_per_step_s", "wall_time_per_cycle_s", "body_steps_per_s", "threads"] {
        v.as_object_mut().unwrap().remove(k);
    }
    v
}

/// Runs `runner` whole, then stopped at `stop` and at `2 stop` and resumed, with
/// a snapshot every `vtk` steps: the same bytes; a checkpoint left after the
/// first stop is refused by a runner of another scene.
fn resume_is_bit_identical<E: Engine>(runner: &Runner<E>, other: &Runner<E>, stop: u64, vtk: u64, test: &str) {
    let dir = scratch::dir(test);
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    let opts = RunOptions { vtk_every: vtk, ..quiet() };
    // Nothing to resume yet: an input error, nothing written.
    let err = runner.run(&parts, &RunOptions { resume: true, ..opts.clone() }, &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Checkpoint(_)) && err.to_string().contains("resume: no checkpoint.json"), "{err}");
    assert!(!parts.join("series.csv").exists());
    let done = runner.run(&whole, &opts, &mut |_| {}).unwrap();
    assert_eq!(done.status, Status::Ended(RunEnd::Finished));
    let first = runner.run(&parts, &RunOptions { stop_after: Some(stop), ..opts.clone() }, &mut |_| {}).unwrap();
    assert_eq!((first.status, first.step), (Status::Stopped, stop));
    assert!(parts.join("checkpoint.json").is_file() && !parts.join("final.json").exists());
    let err = other.run(&parts, &RunOptions { resume: true, ..opts.clone() }, &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Checkpoint(_)) && err.to_string().contains("another scene"), "{err}");
    let resume = RunOptions { resume: true, ..opts.clone() };
    let second = runner.run(&parts, &RunOptions { stop_after: Some(stop), ..resume.clone() }, &mut |_| {}).unwrap();
    assert_eq!((second.status, second.step), (Status::Stopped, 2 * stop));
    // A kill after the checkpoint leaves rows it does not know: they go.
    let mut f = std::fs::OpenOptions::new().append(true).open(parts.join("series.csv")).unwrap();
    std::io::Write::write_all(&mut f, b"9e9,9e9,9,9,9,9e9,1,9e9,9e9,9e9\n").unwrap();
    drop(f);
    let mut f = std::fs::OpenOptions::new().append(true).open(parts.join("cycle_times.csv")).unwrap();
    std::io::Write::write_all(&mut f, b"999,1.0,1\n").unwrap();
    drop(f);
    let end = runner.run(&parts, &resume, &mut |_| {}).unwrap();
    assert_eq!(end.status, Status::Ended(RunEnd::Finished));
    assert!(!parts.join("checkpoint.json").exists());
    for f in outputs(&whole) {
        let name = f.file_name().unwrap();
        let g = parts.join(f.strip_prefix(&whole).unwrap());
        assert_eq!(std::fs::read(&f).unwrap(), std::fs::read(&g).unwrap(), "{name:?} differs");
    }
    assert_eq!(summary_without_wall_time(&whole), summary_without_wall_time(&parts));
    // The wall time of each cycle, in both folders: one row per row of cycles.csv (the rows written after the
    // last checkpoint dropped, the cycles split by a stop timed across it), together no more than the run's.
    for d in [&whole, &parts] {
        let rows = ballast::run::cycle_times::read(d).unwrap();
        let cycles = std::fs::read_to_string(d.join("cycles.csv")).unwrap().lines().count() as u64 - 1;
        assert!(cycles >= 3, "{test}: {cycles} cycles");
        assert_eq!(rows.iter().map(|r| r.cycle).collect::<Vec<_>>(), (1..=cycles).collect::<Vec<_>>(), "{d:?}");
        let walls: Vec<f64> = rows.iter().map(|r| r.wall_s.expect("every cycle timed")).collect();
        let summary: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(d.join("summary.json")).unwrap()).unwrap();
        let run = summary["wall_time_s"].as_f64().unwrap();
        let sum: f64 = walls.iter().sum();
        assert!(walls.iter().all(|&w| w >= 0.0) && sum > 0.0 && sum <= run, "{d:?}: {walls:?} against {run} s");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nscd_resume_is_bit_identical() {
    let scene = nscd_scene();
    let runner = Runner::from_system(scene.build().unwrap(), scene.plan().unwrap()).unwrap();
    let other_scene =
        Scene { output: Some(OutputSection { every: Some(8), ..scene.output.clone().unwrap() }), ..scene.clone() };
    let other = Runner::from_system(other_scene.build().unwrap(), other_scene.plan().unwrap()).unwrap();
    // Stops at 17 and 34: between rows and inside cycles.
    resume_is_bit_identical(&runner, &other, 17, 10, "nscd_resume");
}

#[test]
fn md_resume_is_bit_identical() {
    let text = md_scene(0.02, true);
    let scene = MdScene::from_toml_str(&text).unwrap();
    let runner = Runner::from_system(scene.build().unwrap(), scene.plan().unwrap()).unwrap();
    let other_scene = MdScene::from_toml_str(&text.replace("every = 300", "every = 301")).unwrap();
    let other = Runner::from_system(other_scene.build().unwrap(), other_scene.plan().unwrap()).unwrap();
    // 10 000 steps of 2 µs; stops at 3 333 and 6 666: off the row and cycle grids.
    resume_is_bit_identical(&runner, &other, 3333, 2500, "md_resume");
}

/// Runs to equilibrium; the last row is the stop step; stopped 10 steps before
/// the stop and resumed, the same stop and bytes.
fn equilibrium_stop_survives_a_resume<E: Engine>(runner: &Runner<E>, test: &str) -> u64 {
    let dir = scratch::dir(test);
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    let done = runner.run(&whole, &quiet(), &mut |_| {}).unwrap();
    assert_eq!(done.status, Status::Ended(RunEnd::Equilibrium));
    assert!(done.step < done.end_step, "stopped early: {} of {}", done.step, done.end_step);
    let fin = FinalState::read(&whole.join("final.json")).unwrap();
    assert_eq!(fin.step, done.step);
    let series = std::fs::read_to_string(whole.join("series.csv")).unwrap();
    let last_time: f64 = series.lines().last().unwrap().split(',').next().unwrap().parse().unwrap();
    assert_eq!(last_time, fin.time, "the stop step is the last row");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(whole.join("summary.json")).unwrap()).unwrap();
    assert_eq!((report["end"].as_str(), report["equilibrium"].as_bool()), (Some("equilibrium"), Some(true)));
    runner.run(&parts, &RunOptions { stop_after: Some(done.step - 10), ..quiet() }, &mut |_| {}).unwrap();
    runner.run(&parts, &RunOptions { resume: true, ..quiet() }, &mut |_| {}).unwrap();
    for f in ["series.csv", "final.json"] {
        assert_eq!(std::fs::read(whole.join(f)).unwrap(), std::fs::read(parts.join(f)).unwrap(), "{f} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
    done.step
}

#[test]
fn nscd_equilibrium_stop() {
    // The block (1 mm up) and the pebble (8 cm up) land within 0.13 s; the
    // 50-step window follows: far before the 2 s asked for.
    let text = nscd_text();
    assert!(text.contains("duration = 0.05") && text.contains("seed = 42"), "{text}");
    let text = text
        .replace("duration = 0.05", "duration = 2.0")
        .replace("seed = 42", "seed = 42\nequilibrium = { kinetic_energy = 1e-12, steps = 50 }");
    let scene = Scene::from_toml_str(&text).unwrap();
    let runner = Runner::from_system(scene.build().unwrap(), scene.plan().unwrap()).unwrap();
    let stop = equilibrium_stop_survives_a_resume(&runner, "nscd_equilibrium");
    assert!((130..1000).contains(&stop), "stopped at step {stop}");
}

#[test]
fn md_equilibrium_stop() {
    // E_k below 1e-8 J for 2000 steps (4 ms, longer than the top of a bounce)
    // once the spheres have landed (the lower one falls 0.8 mm: 12.8 ms).
    let text =
        md_scene(0.4, false).replace("seed = 1\n", "seed = 1\nequilibrium = { kinetic_energy = 1e-8, steps = 2000 }\n");
    let scene = MdScene::from_toml_str(&text).unwrap();
    let runner = Runner::from_system(scene.build().unwrap(), scene.plan().unwrap()).unwrap();
    let stop = equilibrium_stop_survives_a_resume(&runner, "md_equilibrium");
    assert!(stop > 6400, "stopped at step {stop}, before the lower sphere landed");
}

/// A run whose step `k + 1` diverges: the error names that step and a body; the
/// run folder holds the state of step `k` (`final.json`), whose row ends
/// `series.csv`, and `summary.json` says it diverged.
fn divergence_keeps_the_last_good_state<E: Engine>(runner: &Runner<E>, body: &str, test: &str) {
    let dir = scratch::dir(test);
    let err = runner.run(&dir, &quiet(), &mut |_| {}).unwrap_err();
    let Error::Diverged { step, name, .. } = &err else { panic!("{err}") };
    assert_eq!(name, body, "{err}");
    assert_eq!(err.to_string().lines().count(), 1);
    let fin = FinalState::read(&dir.join("final.json")).unwrap();
    assert_eq!(fin.step + 1, *step, "final.json holds the step before the failure: {err}");
    assert!(fin.bodies.iter().all(|b| b.position.iter().chain(&b.velocity).all(|x| x.is_finite())));
    let series = std::fs::read_to_string(dir.join("series.csv")).unwrap();
    let last_time: f64 = series.lines().last().unwrap().split(',').next().unwrap().parse().unwrap();
    assert_eq!(last_time, fin.time, "the last good step is the last row");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!((report["end"].as_str(), report["steps"].as_u64()), (Some("diverged"), Some(fin.step)));
    assert!(!dir.join("final_scene.toml").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn nscd_divergence_keeps_the_last_good_state() {
    // A block squeezed between the floor and a press whose velocity is imposed:
    // nothing stops the press, the overlap runs away.
    let press = "[[body]]\nname = \"press\"\nmaterial = \"grain\"\n\
                 polygon = [[-0.1, 0.0], [0.1, 0.0], [0.1, 0.05], [-0.1, 0.05]]\nposition = [0.0, 0.12]\n\
                 imposed = { vx = 0.0, vy = -1.0, spin = 0.0 }\n";
    let mut scene = fixtures::with_bodies(Scene { output: None, ..nscd_scene() }, press);
    scene.bodies[1].position = [0.0, 0.05];
    let runner = Runner::from_system(scene.build().unwrap(), RunPlan::new(100, 10)).unwrap();
    divergence_keeps_the_last_good_state(&runner, "block", "nscd_diverge");
}

#[test]
fn md_divergence_keeps_the_last_good_state() {
    // Two soft spheres (E = 1 MPa) thrown at each other at 20 m/s each: the Hertz
    // contact cannot stop them before the overlap passes half a radius (contact
    // near step 150 of 10 µs, a replay from the backup at step 100).
    let text = "[simulation]\nengine = \"md\"\ndt = 1e-5\nduration = 0.01\ngravity = [0.0, 0.0, 0.0]\n\n\
         [[material]]\nname = \"soft\"\ndensity = 2000.0\nyoung = 1e6\npoisson = 0.25\n\n\
         [[contact]]\nbetween = [\"soft\", \"soft\"]\nmodel = \"hertz\"\nfriction = 0.5\nnormal_damping_ratio = 0.3\n\n\
         [[body]]\nname = \"left\"\nmaterial = \"soft\"\nsphere = 0.005\nposition = [-0.035, 0.0, 0.1]\nvelocity = [20.0, 0.0, 0.0]\n\n\
         [[body]]\nname = \"right\"\nmaterial = \"soft\"\nsphere = 0.005\nposition = [0.035, 0.0, 0.1]\nvelocity = [-20.0, 0.0, 0.0]\n";
    let scene = MdScene::from_toml_str(text).unwrap();
    let runner = Runner::from_system(scene.build().unwrap(), RunPlan::new(1000, 7)).unwrap();
    let dir = scratch::dir("md_diverge_probe");
    let err = runner.run(&dir, &quiet(), &mut |_| {}).unwrap_err();
    let _ = std::fs::remove_dir_all(&dir);
    let Error::Diverged { name, .. } = &err else { panic!("{err}") };
    divergence_keeps_the_last_good_state(&runner, name, "md_diverge");
}

/// Every CSV of a run of each engine reads back through the library's row types.
#[test]
fn outputs_read_back_through_the_row_types() {
    use ballast::run::positions;
    let dir = scratch::dir("read_back");
    let scene = nscd_scene();
    let nscd = dir.join("nscd");
    Runner::from_system(scene.build().unwrap(), scene.plan().unwrap())
        .unwrap()
        .run(&nscd, &quiet(), &mut |_| {})
        .unwrap();
    let rows = ballast::plane::rows::read_series(&nscd.join("series.csv")).unwrap();
    assert_eq!(rows.len(), 8, "steps 7, 14, …, 49 and 50");
    assert_eq!(rows.last().unwrap().time_s, 0.05);
    let c = ballast::plane::rows::read_cycles(&nscd.join("cycles.csv")).unwrap();
    assert_eq!(c.iter().map(|r| r.cycle).collect::<Vec<_>>(), [1, 2, 3, 4, 5]);
    let p = positions::read(&nscd).unwrap();
    assert_eq!((p.reference.bodies.clone(), p.cycles.len()), (vec![1, 2], 5));
    assert_eq!(p.names, ["block", "pebble"]);
    // The last cycle ends with the run: its positions are the final state's, to
    // the float32 resolution of the stored displacement (7 digits of it).
    let fin = FinalState::read(&nscd.join("final.json")).unwrap();
    for (k, &i) in p.reference.bodies.iter().enumerate() {
        let (q, q0) = (p.cycles[4].body(k), p.reference.body(k));
        let want = [fin.bodies[i].position[0], fin.bodies[i].position[1], fin.bodies[i].angle.unwrap()];
        for d in 0..3 {
            assert!((q[d] - want[d]).abs() <= 1e-7 * (want[d] - q0[d]).abs() + 1e-300, "body {i} coordinate {d}");
        }
    }

    let md = dir.join("md");
    let text = md_scene(0.01, true);
    let scene = MdScene::from_toml_str(&text).unwrap();
    Runner::from_system(scene.build().unwrap(), scene.plan().unwrap())
        .unwrap()
        .run(&md, &quiet(), &mut |_| {})
        .unwrap();
    let (header, rows) = ballast::md::rows::read_series(&md.join("series.csv")).unwrap();
    assert_eq!(&header[header.len() - 4..], ["base_force_N", "mould_force_N", "lid_force_N", "lid_position_m"]);
    assert!(rows.iter().all(|r| r.walls.len() == 4), "three wall forces and one servo position per row");
    assert!(rows.last().unwrap().walls[3] > 0.0, "the lid moved down along its normal");
    let c = ballast::md::rows::read_cycles(&md.join("cycles.csv")).unwrap();
    assert_eq!(c.len(), 2, "two 5 ms cycles in 10 ms");
    assert_eq!(c[1].walls, [rows.last().unwrap().walls[3]], "the lid at the end of the run");
    let p = positions::read(&md).unwrap();
    assert_eq!((p.reference.dof, p.reference.bodies.clone(), p.cycles.len()), (6, vec![0, 1], 2));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `RunOptions::length` (`ballast run --steps | --duration`) replaces the scene's
/// duration for one run, on both engines: the run makes exactly that many steps
/// (the clock is exact, so the last time is steps · dt), the scene copy records
/// the new duration and plans the same steps when read back; a length the scene
/// cannot take is an error naming the option. The summary's final overlap is
/// that of the last row of `series.csv`.
#[test]
fn a_run_length_replaces_the_scene_duration() {
    use ballast::open::run_file;
    use ballast::run::RunLength;
    let dir = scratch::dir("length");
    let (nscd, md) = scene_files(&dir, 0.01);
    for (scene, dt) in [(&nscd, 1e-3), (&md, 2e-6)] {
        let out = dir.join(format!("out-{}", scene.file_stem().unwrap().to_string_lossy()));
        for (length, steps) in [(RunLength::Steps(7), 7), (RunLength::Duration(11.0 * dt), 11)] {
            let opts = RunOptions { length: Some(length), ..quiet() };
            let run = ballast::open::run_file(scene, &out, &opts, &mut |_| {}).unwrap();
            assert_eq!(run.step, steps, "{}", scene.display());
            // The final overlap reported is the last row's; the run's largest bounds it.
            let last = if scene == &md {
                ballast::md::rows::read_series(&out.join("series.csv")).unwrap().1.last().unwrap().max_overlap_m
            } else {
                ballast::plane::rows::read_series(&out.join("series.csv")).unwrap().last().unwrap().max_overlap_m
            };
            assert_eq!(run.report.final_max_overlap_m, last);
            assert!(run.report.max_overlap_m >= last);
            let copy = std::fs::read_to_string(out.join("scene.toml")).unwrap();
            let planned = if scene == &md {
                MdScene::from_toml_str(&copy).unwrap().steps()
            } else {
                Scene::from_toml_str(&copy).unwrap().steps()
            };
            assert_eq!(planned, steps);
        }
        for (length, option) in [(RunLength::Steps(0), "length.steps"), (RunLength::Duration(-1.0), "length.duration")]
        {
            let opts = RunOptions { length: Some(length), ..quiet() };
            let e = run_file(scene, &out, &opts, &mut |_| {}).unwrap_err().to_string();
            assert!(e.starts_with(option) && !e.contains('\n'), "{e}");
        }
    }
}

/// `Loaded::run_on`, the run of an opened scene that the Python binding drives, on both engines: a stop asked
/// by the control callback at step `k` leaves a checkpoint and the system at step `k`; the same scene opened
/// afresh and resumed ends with the bytes of an uninterrupted run; a run from a state the scene does not build
/// (stepped on after the stop) records that state (`initial_state.json`) instead of `scene.toml`, and starts
/// its steps there.
#[test]
fn an_opened_scene_runs_stops_and_resumes() {
    use ballast::open::{open, Loaded};
    use std::ops::ControlFlow;
    let dir = scratch::dir("run_on");
    let (nscd, md) = scene_files(&dir, 0.004);
    let steps_done = |l: &Loaded| match l {
        Loaded::Nscd(o) => o.system.steps_done(),
        Loaded::PlanarMd(o, _) => o.system.steps_done(),
        Loaded::Md(o) => o.system.steps_done(),
        Loaded::Nscd3(o) => o.system.steps_done(),
    };
    for (scene, stop) in [(&nscd, 23), (&md, 777)] {
        let out = |name: &str| dir.join(format!("{}-{name}", scene.file_stem().unwrap().to_string_lossy()));
        let whole = open(scene, &quiet()).unwrap().run(&out("whole"), &quiet(), &mut |_| {}).unwrap();
        assert_eq!(whole.status, Status::Ended(RunEnd::Finished));
        let mut sim = open(scene, &quiet()).unwrap();
        let mut stop_at = |p: &ballast::run::Progress| {
            if p.step == stop {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        };
        let first = sim.run_on(&out("parts"), &quiet(), &mut stop_at).unwrap();
        assert_eq!((first.status, first.step, steps_done(&sim)), (Status::Stopped, stop, stop));
        assert!(out("parts").join("checkpoint.json").is_file() && !out("parts").join("final.json").exists());
        let resume = RunOptions { resume: true, ..quiet() };
        // The state held (step `stop`) is not the run's start: the resume starts from the scene's.
        let end = sim.run_on(&out("parts"), &resume, &mut |_| ControlFlow::Continue(())).unwrap();
        assert_eq!((end.status, end.step), (Status::Ended(RunEnd::Finished), whole.step));
        let files: Vec<PathBuf> = outputs(&out("whole")).into_iter().filter(|f| f.exists()).collect();
        assert!(files.len() >= 4, "{files:?}");
        for f in files {
            let g = out("parts").join(f.strip_prefix(out("whole")).unwrap());
            assert_eq!(std::fs::read(&f).unwrap(), std::fs::read(&g).unwrap(), "{f:?} differs");
        }
        assert_eq!(steps_done(&sim), whole.step);
        // Stepped on: 5 more steps from the state held, recorded as that state.
        let more = RunOptions { length: Some(ballast::run::RunLength::Steps(5)), ..quiet() };
        let on = sim.run_on(&out("on"), &more, &mut |_| ControlFlow::Continue(())).unwrap();
        assert_eq!((on.step, steps_done(&sim)), (whole.step + 5, whole.step + 5));
        assert!(out("on").join("initial_state.json").is_file() && !out("on").join("scene.toml").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `extend` and `keep_checkpoint`, on both engines: a run of `n` steps (inside a loading cycle) that keeps its
/// checkpoint, resumed with `extend` to `2n + 1` steps, writes the bytes of a run asked for `2n + 1` steps from
/// the start (`n` is off the output grid, so the kept checkpoint must come before the last row); a finished
/// run without a kept checkpoint, a plain resume with another length, an extension that ends before the step
/// reached and a scene changed in more than its duration are refused, naming the option or key.
#[test]
fn a_kept_checkpoint_extends_a_finished_run_with_the_numbers_of_a_longer_run() {
    use ballast::open::run_file;
    use ballast::run::RunLength;
    let dir = scratch::dir("extend");
    let (nscd, md) = scene_files(&dir, 0.004);
    for (scene, n) in [(&nscd, 23), (&md, 2601)] {
        let out = |name: &str| dir.join(format!("{}-{name}", scene.file_stem().unwrap().to_string_lossy()));
        let steps = |k| RunOptions { length: Some(RunLength::Steps(k)), ..quiet() };
        let whole = run_file(scene, &out("whole"), &steps(2 * n + 1), &mut |_| {}).unwrap();
        assert_eq!((whole.status, whole.step), (Status::Ended(RunEnd::Finished), 2 * n + 1));
        // Finished without a kept checkpoint: nothing to extend.
        run_file(scene, &out("plain"), &steps(n), &mut |_| {}).unwrap();
        let extend = |k| RunOptions { resume: true, extend: true, ..steps(k) };
        let e = run_file(scene, &out("plain"), &extend(2 * n + 1), &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("resume: no checkpoint.json"), "{e}");
        // Kept: a finished run with its checkpoint.
        let first = run_file(scene, &out("parts"), &RunOptions { keep_checkpoint: true, ..steps(n) }, &mut |_| {});
        assert_eq!(first.unwrap().status, Status::Ended(RunEnd::Finished));
        assert!(out("parts").join("checkpoint.json").is_file() && out("parts").join("final.json").is_file());
        // Another length without `extend` is another scene; with it, not shorter than the steps made.
        let resume = RunOptions { resume: true, ..steps(2 * n + 1) };
        let e = run_file(scene, &out("parts"), &resume, &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("another scene") && e.contains("only in simulation.duration: resume with extend"), "{e}");
        let e = run_file(scene, &out("parts"), &extend(n - 1), &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("extend: simulation.duration ends the run at step") && !e.contains('\n'), "{e}");
        // A scene changed in more than its duration.
        let other = dir.join("other.toml");
        let text = std::fs::read_to_string(scene).unwrap();
        let changed = text.replacen("seed = ", "seed = 1", 1);
        assert_ne!(changed, text, "the scenes have a seed");
        std::fs::write(&other, changed).unwrap();
        let e = run_file(&other, &out("parts"), &extend(2 * n + 1), &mut |_| {}).unwrap_err().to_string();
        assert!(e.contains("differs from the run's") && e.contains("simulation.duration"), "{e}");
        assert!(out("parts").join("final.json").is_file(), "a refused extension leaves the folder as it was");
        let end = run_file(scene, &out("parts"), &extend(2 * n + 1), &mut |_| {}).unwrap();
        assert_eq!((end.status, end.step), (Status::Ended(RunEnd::Finished), 2 * n + 1));
        assert!(!out("parts").join("checkpoint.json").exists());
        let files: Vec<PathBuf> = outputs(&out("whole")).into_iter().filter(|f| f.exists()).collect();
        assert!(files.len() >= 4, "{files:?}");
        for f in files.iter().chain(&[out("whole").join("contacts.csv"), out("whole").join("scene.toml")]) {
            let g = out("parts").join(f.strip_prefix(out("whole")).unwrap());
            assert_eq!(std::fs::read(f).unwrap(), std::fs::read(&g).unwrap(), "{f:?} differs");
        }
        assert_eq!(summary_without_wall_time(&out("whole")), summary_without_wall_time(&out("parts")));
        let cycles = ballast::run::cycle_times::read(&out("parts")).unwrap();
        let rows = std::fs::read_to_string(out("parts").join("cycles.csv")).unwrap().lines().count() as u64 - 1;
        assert_eq!(cycles.iter().map(|r| r.cycle).collect::<Vec<_>>(), (1..=rows).collect::<Vec<_>>());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
