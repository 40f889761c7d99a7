//! A run resumed with other solver settings (`RunOptions::change_solver`, `ballast run --resume
//! --change-solver`): it is the run that switched its settings at the checkpoint's step, bit for bit; the change
//! is recorded; any other change of the scene, an engine without solver settings and the option without a resume
//! are refused with one line.

use crate::scratch;
use ballast::engine::{Engine, FinalState};
use ballast::open::run_file;
use ballast::run::{RunEnd, RunOptions, SolverChange, Status};
use ballast::scene::{d3::Scene3, SceneFile};
use ballast::Error;
use std::path::{Path, PathBuf};

fn quiet() -> RunOptions {
    RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() }
}

/// `text` with `from` replaced by `to` (which must be there), written as `dir/name`.
fn variant(dir: &Path, name: &str, text: &str, from: &str, to: &str) -> PathBuf {
    assert!(text.contains(from), "{from}");
    let path = dir.join(name);
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&path, text.replacen(from, to, 1)).unwrap();
    path
}

/// The text of `examples/cubes3d.toml` lasting `duration` seconds, and its copy `dir/a.toml`.
fn cubes(dir: &Path, duration: &str) -> (String, PathBuf) {
    let text = std::fs::read_to_string("examples/cubes3d.toml").unwrap();
    let text = text.replacen("duration = 0.5", &format!("duration = {duration}"), 1);
    let a = variant(dir, "a.toml", &text, "duration", "duration");
    (text, a)
}

fn read_final(dir: &Path) -> FinalState {
    serde_json::from_str(&std::fs::read_to_string(dir.join("final.json")).unwrap()).unwrap()
}

/// The three cubes and the rock of `examples/cubes3d.toml`, 60 steps at `quad` 1e-6, stopped after 30 and
/// resumed at `quad` 1e-4 with Anderson mixing: the final state is that of the system stepped 30 steps with the
/// first settings and 30 with the second (the same bits), `solver_changes.csv` has the two rows, a plain resume
/// with the new scene goes on from the checkpoint written at the change, and the old scene no longer resumes.
#[test]
fn a_resumed_run_takes_the_new_solver_settings_at_its_step() {
    let dir = scratch::path("cubes");
    let (text, a) = cubes(&dir, "0.06");
    let b = variant(&dir, "b.toml", &text, "tolerance = 1.0e-6", "tolerance = 1.0e-4\nanderson = 3");
    let out = dir.join("run");
    let first = run_file(&a, &out, &RunOptions { stop_after: Some(30), ..quiet() }, &mut |_| {}).unwrap();
    assert_eq!((first.status, first.step), (Status::Stopped, 30));

    // Without the option the changed scene is another scene.
    let err = run_file(&b, &out, &RunOptions { resume: true, ..quiet() }, &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Checkpoint(_)) && err.to_string().contains("another scene"), "{err}");

    let opts = RunOptions { resume: true, change_solver: true, stop_after: Some(15), ..quiet() };
    let second = run_file(&b, &out, &opts, &mut |_| {}).unwrap();
    assert_eq!((second.status, second.step), (Status::Stopped, 45));
    let change = |key: &str, before: &str, after: &str| SolverChange {
        step: 30,
        time_s: first.time,
        key: key.into(),
        before: before.into(),
        after: after.into(),
    };
    let expected = vec![change("nscd.tolerance", "0.000001", "0.0001"), change("nscd.anderson", "0", "3")];
    assert_eq!(second.solver_changes, expected);
    let csv = std::fs::read_to_string(out.join("solver_changes.csv")).unwrap();
    assert_eq!(csv.lines().count(), 3, "{csv}");
    assert!(csv.starts_with("step,time_s,key,before,after\n30,"), "{csv}");

    // The checkpoint now belongs to the new scene: the old one is refused, a plain resume goes on.
    let err = run_file(&a, &out, &RunOptions { resume: true, ..quiet() }, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("another scene"), "{err}");
    let end = run_file(&b, &out, &RunOptions { resume: true, ..quiet() }, &mut |_| {}).unwrap();
    assert_eq!((end.status, end.step), (Status::Ended(RunEnd::Finished), 60));
    assert!(end.solver_changes.is_empty());
    assert_eq!(std::fs::read_to_string(out.join("solver_changes.csv")).unwrap(), csv, "recorded once");

    // The reference: the same system stepped by hand, its settings switched after step 30.
    let mut sys = Scene3::load(&a).unwrap().build().unwrap();
    for _ in 0..30 {
        sys.step().unwrap();
    }
    let new = Scene3::load(&b).unwrap().build().unwrap();
    assert_ne!(sys.params.nlgs, new.params.nlgs);
    sys.params.nlgs = new.params.nlgs;
    for _ in 0..30 {
        sys.step().unwrap();
    }
    assert_eq!(read_final(&out), Engine::final_state(&sys));
    // And the switch did change the run: the same 60 steps at the first settings end elsewhere.
    let straight = dir.join("straight");
    run_file(&a, &straight, &quiet(), &mut |_| {}).unwrap();
    assert_ne!(read_final(&straight), read_final(&out));
}

/// Changes beyond the solver keys, the option without a resume, and an engine without solver settings.
#[test]
fn what_the_change_of_solver_refuses() {
    let dir = scratch::path("refused");
    let (text, a) = cubes(&dir, "0.02");
    let out = dir.join("run");
    run_file(&a, &out, &RunOptions { stop_after: Some(10), ..quiet() }, &mut |_| {}).unwrap();
    let opts = RunOptions { resume: true, change_solver: true, ..quiet() };
    for (from, to) in [("gravity = [0.0, 0.0, -9.81]", "gravity = [0.0, 0.0, -9.80]"), ("dt = 1.0e-3", "dt = 0.5e-3")] {
        let b = variant(&dir, "b.toml", &text, from, to);
        let err = run_file(&b, &out, &opts, &mut |_| {}).unwrap_err();
        let msg = err.to_string();
        assert!(matches!(err, Error::Checkpoint(_)) && msg.contains("change_solver: the scene differs"), "{msg}");
        assert!(msg.contains("tolerance") && msg.contains("anderson") && !msg.contains('\n'), "{msg}");
    }
    let err = run_file(&a, &dir.join("fresh"), &RunOptions { change_solver: true, ..quiet() }, &mut |_| {});
    assert!(err.unwrap_err().to_string().starts_with("change_solver: "));

    // The MD engine has no solver settings: the option is refused even with its own scene.
    let md = dir.join("md");
    let spheres = Path::new("examples/md_two_spheres.toml");
    run_file(spheres, &md, &RunOptions { stop_after: Some(5), ..quiet() }, &mut |_| {}).unwrap();
    let err = run_file(spheres, &md, &opts, &mut |_| {}).unwrap_err();
    assert!(err.to_string().contains("no solver settings"), "{err}");
}

/// The 2D engine takes the change too: the block of `examples/block_on_floor.toml` (no `[nscd]` table) resumed
/// with one that only sets the tolerance.
#[test]
fn a_2d_run_takes_a_new_tolerance() {
    let dir = scratch::path("block");
    let text = std::fs::read_to_string("examples/block_on_floor.toml").unwrap().replacen(
        "duration = 0.5",
        "duration = 0.04",
        1,
    );
    let a = variant(&dir, "a.toml", &text, "[output]", "[output]");
    let b = variant(&dir, "b.toml", &text, "[output]", "[nscd]\ntolerance = 1e-6\n\n[output]");
    let out = dir.join("run");
    run_file(&a, &out, &RunOptions { stop_after: Some(20), ..quiet() }, &mut |_| {}).unwrap();
    let opts = RunOptions { resume: true, change_solver: true, ..quiet() };
    let end = run_file(&b, &out, &opts, &mut |_| {}).unwrap();
    assert_eq!(end.step, 40);
    let keys: Vec<_> = end.solver_changes.iter().map(|c| (c.step, c.key.as_str(), c.after.as_str())).collect();
    assert_eq!(keys, [(20, "nscd.tolerance", "0.000001")]);
    // A fresh run in the folder leaves no record of the earlier run's change.
    assert!(out.join("solver_changes.csv").is_file());
    run_file(&b, &out, &quiet(), &mut |_| {}).unwrap();
    assert!(!out.join("solver_changes.csv").exists());
}

/// `extend` with `change_solver` on the 3D engine: the cubes of [`cubes`] run 30 steps at `quad` 1e-6 and keep
/// their checkpoint, then go on to 60 steps at `quad` 1e-4 with Anderson mixing; the files of the 60-step run
/// stopped at 30 and resumed with the new settings, bit for bit. Without `change_solver` the new settings are
/// refused as more than the duration.
#[test]
fn a_finished_run_is_extended_with_other_solver_settings() {
    let dir = scratch::path("cubes-extend");
    let (text, a60) = cubes(&dir, "0.06");
    let a30 = variant(&dir, "a30.toml", &text, "duration = 0.06", "duration = 0.03");
    let b60 = variant(&dir, "b60.toml", &text, "tolerance = 1.0e-6", "tolerance = 1.0e-4\nanderson = 3");
    let (reference, extended) = (dir.join("reference"), dir.join("extended"));
    let first = run_file(&a60, &reference, &RunOptions { stop_after: Some(30), ..quiet() }, &mut |_| {}).unwrap();
    assert_eq!(first.status, Status::Stopped);
    let change = RunOptions { resume: true, change_solver: true, ..quiet() };
    run_file(&b60, &reference, &change, &mut |_| {}).unwrap();
    let done = run_file(&a30, &extended, &RunOptions { keep_checkpoint: true, ..quiet() }, &mut |_| {}).unwrap();
    assert_eq!((done.status, done.step), (Status::Ended(RunEnd::Finished), 30));
    let plain = RunOptions { extend: true, change_solver: false, ..change.clone() };
    let err = run_file(&b60, &extended, &plain, &mut |_| {}).unwrap_err().to_string();
    assert!(err.contains("in more than simulation.duration;"), "{err}");
    let end = run_file(&b60, &extended, &RunOptions { extend: true, ..change }, &mut |_| {}).unwrap();
    assert_eq!((end.status, end.step, end.solver_changes.len()), (Status::Ended(RunEnd::Finished), 60, 2));
    for f in ["series.csv", "final.json", "contacts.csv", "solver_changes.csv"] {
        let (r, e) = (std::fs::read(reference.join(f)).unwrap(), std::fs::read(extended.join(f)).unwrap());
        assert!(r == e, "{f} differs");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
