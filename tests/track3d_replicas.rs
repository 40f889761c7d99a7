//! Replicas of the 3D track section (`ballast::studies::replicas::perturb_scene3`,
//! `ballast::studies::track3d::{settle_replicas, convergence}`, `ballast track3d settle --replicas`,
//! `ballast track3d convergence`) on the 24-grain sample of `tests/track3d.rs`, loaded for one or two cycles of 50
//! steps: replica 0 is the sample bit for bit; replica r moves each mobile body by at most the distance and the
//! fixed ones not at all, the same (seed, r) giving the same scene; two replicas' runs differ; the ensemble of
//! three replicas equals the statistics computed here from their `cycles.csv`; the convergence study writes a row
//! per run with the difference from the reference setting, and a second invocation with `resume` runs nothing;
//! bad input is refused naming the field (library) or the flag (command line).

use crate::scratch;
use crate::track3d_common;

use ballast::nscd::d3::rows::{read_cycles, CycleRow3};
use ballast::scenarios::track3d::LoadingSpec;
use ballast::scene::{Scene3, SceneFile};
use ballast::studies::campaigns::StudyOptions;
use ballast::studies::replicas::{perturb_scene3, Perturbation, Replicas, SettlementEnsembleRow, REPLICA_FILE};
use ballast::studies::saussine::replica_dir;
use ballast::studies::track3d::{self as study, ConvergenceSpec, SettleOptions};
use ballast::studies::Quiet;
use std::path::Path;
use track3d_common::{ballast, refused, sample, LOAD_DT};

/// Student's t quantile t_{0.975, 2} (tables): the factor of the 95 % interval of the mean of three values.
const T_975_2: f64 = 4.302_652_729_911_275;

fn loading(cycles: u64) -> LoadingSpec {
    LoadingSpec { cycles, dt: LOAD_DT, ..LoadingSpec::default() }
}

fn no_snapshots() -> SettleOptions {
    SettleOptions { snapshot_every: 0, checkpoint_every_s: 300.0, resume: false }
}

fn replicas(count: u64, distance_m: f64, seating_cycles: u64) -> Replicas {
    Replicas { count, perturbation: Perturbation { distance_m, seed: 11 }, seating_cycles }
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-9), "{what}: {a} vs {b}");
}

/// An end of a 95 % interval of half width `half`: `statrs`'s t quantile is within 1e-9 of the tables.
fn close_end(a: f64, b: f64, half: f64, what: &str) {
    assert!((a - b).abs() <= 1e-9 * half + 1e-15, "{what}: {a} vs {b} (half width {half})");
}

/// Replica 0 is the sample bit for bit; replica r moves every mobile body by at most the distance (and does
/// move it), the fixed ones not at all, orientations and velocities untouched; the same (seed, r) gives the same
/// scene, another r or seed another.
#[test]
fn perturbed_starts_move_the_mobile_bodies_within_the_ball() {
    let (_, s) = sample();
    let scene = Scene3::load(&s.path).unwrap();
    let p = Perturbation { distance_m: 1e-4, seed: 7 };
    let mut zero = scene.clone();
    let record = perturb_scene3(&mut zero, &p, 0).unwrap();
    assert_eq!(zero, scene);
    assert_eq!((record.replica, record.bodies_moved, record.largest_displacement_m), (0, 0, 0.0));

    let mut three = scene.clone();
    let record = perturb_scene3(&mut three, &p, 3).unwrap();
    let mobile = scene.bodies.iter().filter(|b| !b.is_fixed()).count();
    assert!(mobile > 0 && mobile < scene.bodies.len(), "the sample has mobile and fixed bodies");
    assert_eq!(record.bodies_moved, mobile);
    let mut largest: f64 = 0.0;
    for (a, b) in scene.bodies.iter().zip(&three.bodies) {
        let d = ((b.position[0] - a.position[0]).powi(2)
            + (b.position[1] - a.position[1]).powi(2)
            + (b.position[2] - a.position[2]).powi(2))
        .sqrt();
        if a.is_fixed() {
            assert_eq!(a.position, b.position, "fixed body {} moved", a.name);
        } else {
            assert!(d > 0.0 && d <= p.distance_m * (1.0 + 1e-12), "body {} moved by {d} m", a.name);
        }
        largest = largest.max(d);
        assert_eq!((&a.orientation, a.velocity, a.spin), (&b.orientation, b.velocity, b.spin));
        assert_eq!((&a.name, &a.polyhedron, &a.cuboid), (&b.name, &b.polyhedron, &b.cuboid));
    }
    close(record.largest_displacement_m, largest, "largest displacement");

    let mut again = scene.clone();
    perturb_scene3(&mut again, &p, 3).unwrap();
    assert_eq!(again, three, "the same (seed, r) gives the same scene");
    let mut other = scene.clone();
    perturb_scene3(&mut other, &p, 2).unwrap();
    assert_ne!(other, three);
    let mut seed = scene.clone();
    perturb_scene3(&mut seed, &Perturbation { seed: 8, ..p }, 3).unwrap();
    assert_ne!(seed, three);
}

/// Three replicas of two cycles: `settlement_ensemble.csv` (and the rows returned) are the mean, sample standard
/// deviation and Student 95 % interval of the three `cycles.csv`, total and accrued since cycle 1; each replica's
/// start, record and snapshots are in its folder, and replicas 0 and 1 settle differently.
#[test]
fn the_ensemble_of_three_replicas_is_their_statistics() {
    let (dir, s) = sample();
    let out = dir.join("replicas");
    let reps = replicas(3, 1e-6, 1);
    let opts = SettleOptions { snapshot_every: 1, ..no_snapshots() };
    let r = study::settle_replicas(&s.path, &loading(2), &out, &opts, &reps, Some(2), &Quiet).unwrap();
    assert!(r.failed.is_empty() && r.summarized, "{:?}", r.failed);
    let runs: Vec<Vec<CycleRow3>> =
        (0..3).map(|k| read_cycles(&replica_dir(&out, k).join("cycles.csv")).unwrap()).collect();
    assert!(runs.iter().all(|c| c.len() == 2));
    assert_ne!(runs[0], runs[1], "two replicas' runs differ");
    for k in 0..3 {
        let record: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(replica_dir(&out, k).join(REPLICA_FILE)).unwrap()).unwrap();
        assert_eq!(record["replica"], k);
        assert!(out.join(format!("scenes/replica-{k}.toml")).is_file());
        let vtk = std::fs::read_dir(replica_dir(&out, k).join("vtk")).unwrap().count();
        assert!(vtk >= 2, "replica {k}: {vtk} VTK files for a snapshot every cycle of two");
    }
    let table: Vec<SettlementEnsembleRow> = ballast::io::read_csv(&out.join("settlement_ensemble.csv")).unwrap();
    assert_eq!(table, r.rows);
    assert_eq!(table.len(), 2);
    let stats = |x: [f64; 3]| {
        let mean = (x[0] + x[1] + x[2]) / 3.0;
        let sd = (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        let half = T_975_2 * sd / 3f64.sqrt();
        (mean, sd, half)
    };
    for (c, row) in table.iter().enumerate() {
        assert_eq!((row.cycle, row.replicas, row.seating_cycle), (c as u64 + 1, 3, 1));
        let (mean, sd, half) = stats([0, 1, 2].map(|k| runs[k][c].settlement_m));
        close(row.settlement_mean_m, mean, "mean");
        close(row.settlement_sd_m.unwrap(), sd, "sd");
        close_end(row.settlement_ci95_low_m.unwrap(), mean - half, half, "low");
        close_end(row.settlement_ci95_high_m.unwrap(), mean + half, half, "high");
        let (mean, sd, half) = stats([0, 1, 2].map(|k| runs[k][c].settlement_m - runs[k][0].settlement_m));
        close(row.accrued_mean_m.unwrap(), mean, "accrued mean");
        if c == 0 {
            assert_eq!(row.accrued_sd_m, Some(0.0));
        } else {
            close(row.accrued_sd_m.unwrap(), sd, "accrued sd");
            close_end(row.accrued_ci95_low_m.unwrap(), mean - half, half, "accrued low");
            close_end(row.accrued_ci95_high_m.unwrap(), mean + half, half, "accrued high");
        }
    }
}

/// The field of a CSV row by its column name.
fn field<'a>(header: &[String], row: &'a [String], name: &str) -> &'a str {
    &row[header.iter().position(|h| h == name).unwrap_or_else(|| panic!("no column {name}"))]
}

/// The convergence study: one setting and a reference not among the policies (run after it), two replicas each:
/// four rows with the run columns, the ensemble of its setting and the difference of the mean settlements from
/// the reference's, here computed again from the runs' `cycles.csv`; a second invocation with `resume` runs
/// nothing and writes the same table.
#[test]
fn the_convergence_study_writes_a_row_per_run_with_the_reference_difference() {
    let (dir, s) = sample();
    let out = dir.join("convergence");
    let spec = ConvergenceSpec {
        sample: s.path.clone(),
        policies: vec![("quad".into(), 1e-2)],
        reference: Some(("quad".into(), 1e-3)),
        replicas: replicas(2, 1e-6, 0),
        loading: loading(1),
    };
    let study_opts = StudyOptions { jobs: Some(2), ..StudyOptions::new(&out) };
    let report = study::convergence(&spec, &study_opts, &Quiet).unwrap();
    assert!(report.failed.is_empty(), "{:?}", report.failed);
    let table = report.table.unwrap();
    let (h, rows) = (&table.header, &table.rows);
    assert_eq!(rows.len(), 4);
    for name in [
        "mean_iterations",
        "unconverged_steps",
        "wall_time_per_cycle_s",
        "max_overlap_m",
        "mean_overlap_m",
        "settlement_at_min_load_m",
        "settlement_ens_mean_m",
        "accrued_ci95_high_m",
        "settlement_diff_ci95_low_m",
    ] {
        assert!(h.iter().any(|c| c == name), "no column {name}");
    }
    let last = |label: &str| {
        let c = read_cycles(&out.join("runs").join(label).join("cycles.csv")).unwrap();
        c.last().unwrap().settlement_m
    };
    let setting = [last("quad_1e-2/replica-0"), last("quad_1e-2/replica-1")];
    let reference = [last("quad_1e-3/replica-0"), last("quad_1e-3/replica-1")];
    let diff = (setting[0] + setting[1]) / 2.0 - (reference[0] + reference[1]) / 2.0;
    for (i, row) in rows.iter().enumerate() {
        let (policy, replica) = (field(h, row, "tolerance"), field(h, row, "replica"));
        assert_eq!((field(h, row, "policy"), replica), ("quad", ["0", "1"][i % 2]));
        assert_eq!(policy.parse::<f64>().unwrap(), [1e-2, 1e-3][i / 2]);
        assert_eq!((field(h, row, "status"), field(h, row, "reference")), ("ok", "quad:1e-3"));
        let own = [setting, reference][i / 2][i % 2];
        close(field(h, row, "settlement_at_min_load_m").parse().unwrap(), own, "settlement of the run");
        let d: f64 = field(h, row, "settlement_diff_m").parse().unwrap();
        close(d, [diff, 0.0][i / 2], "difference from the reference");
        let (lo, hi): (f64, f64) = (
            field(h, row, "settlement_diff_ci95_low_m").parse().unwrap(),
            field(h, row, "settlement_diff_ci95_high_m").parse().unwrap(),
        );
        assert!(lo <= d && d <= hi, "{lo} {d} {hi}");
        assert!(field(h, row, "mean_iterations").parse::<f64>().unwrap() >= 1.0);
    }
    let stamp = |p: &Path| std::fs::metadata(p.join("summary.json")).unwrap().modified().unwrap();
    let before = stamp(&out.join("runs/quad_1e-3/replica-1"));
    let again = study::convergence(&spec, &StudyOptions { resume: true, ..study_opts }, &Quiet).unwrap();
    assert_eq!(stamp(&out.join("runs/quad_1e-3/replica-1")), before, "a finished run is not run again");
    assert_eq!(again.table.unwrap().rows, table.rows);
}

/// The library names the argument or field of a bad value, before any run.
#[test]
fn bad_replica_arguments_name_their_field() {
    let (dir, s) = sample();
    let out = dir.join("bad");
    let scene = Scene3::load(&s.path).unwrap();
    let starts = |e: ballast::Error, field: &str| {
        let e = e.to_string();
        assert!(e.starts_with(&format!("{field}:")) && !e.contains('\n'), "{e}");
    };
    let mut moved = scene.clone();
    starts(
        perturb_scene3(&mut moved, &Perturbation { distance_m: f64::NAN, seed: 1 }, 1).unwrap_err(),
        "perturbation.distance_m",
    );
    assert_eq!(moved, scene);
    let settle = |reps: Replicas, jobs: Option<usize>, opts: SettleOptions| {
        study::settle_replicas(&s.path, &loading(1), &out, &opts, &reps, jobs, &Quiet).unwrap_err()
    };
    starts(settle(replicas(0, 1e-9, 1), None, no_snapshots()), "replicas");
    starts(settle(replicas(2, -1.0, 1), None, no_snapshots()), "perturbation.distance_m");
    starts(settle(replicas(2, 1e-9, 1), Some(0), no_snapshots()), "jobs");
    starts(
        settle(replicas(2, 1e-9, 1), None, SettleOptions { checkpoint_every_s: f64::NAN, ..no_snapshots() }),
        "checkpoint_every_s",
    );
    let spec = ConvergenceSpec {
        sample: s.path.clone(),
        policies: vec![("quad".into(), 1e-3)],
        reference: Some(("quad".into(), 1e-4)),
        replicas: replicas(2, 1e-9, 1),
        loading: loading(1),
    };
    let conv = |spec: ConvergenceSpec, jobs: Option<usize>| {
        study::convergence(&spec, &StudyOptions { jobs, ..StudyOptions::new(&out) }, &Quiet).unwrap_err()
    };
    starts(conv(ConvergenceSpec { policies: vec![], ..spec.clone() }, None), "policies");
    starts(conv(ConvergenceSpec { policies: vec![("fast".into(), 1e-3)], ..spec.clone() }, None), "policies");
    starts(conv(ConvergenceSpec { reference: Some(("quad".into(), 2.0)), ..spec.clone() }, None), "reference");
    starts(conv(ConvergenceSpec { replicas: replicas(0, 1e-9, 1), ..spec.clone() }, None), "replicas");
    starts(conv(ConvergenceSpec { loading: loading(0), ..spec.clone() }, None), "cycles");
    starts(conv(spec, Some(0)), "jobs");
    assert!(!out.join("runs").exists(), "nothing ran");
}

/// The command line refuses bad replica flags on one line naming the flag, exit code 2, before any run.
#[test]
fn bad_replica_flags_are_named_on_one_line() {
    let (_, s) = sample();
    let dir = scratch::dir("cli");
    let sample = s.path.to_str().unwrap();
    let out = dir.join("out");
    let out = out.to_str().unwrap();
    let settle = ["track3d", "settle", "--sample", sample, "--out", out, "--quiet"];
    let conv = ["track3d", "convergence", "--sample", sample, "--out", out, "--quiet"];
    let cases: [(&[&str], &[&str], &str); 12] = [
        (&settle, &["--replicas", "0"], "--replicas:"),
        (&settle, &["--replicas", "2", "--perturb=-1"], "--perturb:"),
        (&settle, &["--replicas", "2", "--perturb", "nan"], "--perturb:"),
        (&settle, &["--replicas", "2", "--jobs", "0"], "--jobs:"),
        (&conv, &["--replicas", "0"], "--replicas:"),
        (&conv, &["--jobs", "0"], "--jobs:"),
        (&conv, &["--checkpoint-every", "nan"], "--checkpoint-every:"),
        (&settle, &["--replicas", "2", "--checkpoint-every=-1"], "--checkpoint-every:"),
        (&conv, &["--policies", "quad"], "--policies:"),
        (&conv, &["--policies", "fast:1e-3"], "--policies:"),
        (&conv, &["--reference", "quad:x"], "--reference:"),
        (&conv, &["--reference", "quad:2"], "--reference:"),
    ];
    for (command, flags, flag) in cases {
        let args: Vec<&str> = command.iter().chain(flags).copied().collect();
        refused(&args, flag);
    }
    assert!(!dir.join("out/runs").exists(), "nothing ran");
}

/// `track3d settle --replicas 2` and `track3d convergence` run from the command line: the ensemble's table, and a
/// `convergence.csv` row per run.
#[test]
fn the_commands_run_replicas_and_the_convergence_study() {
    let (_, s) = sample();
    let dir = scratch::dir("cli-runs");
    let sample = s.path.to_str().unwrap();
    let (settle, conv) = (dir.join("settle"), dir.join("conv"));
    let fast = ["--cycles", "1", "--dt", "1e-3", "--replicas", "2", "--seating-cycles", "0", "--jobs", "2", "--quiet"];
    let args = ["track3d", "settle", "--sample", sample, "--out", settle.to_str().unwrap()];
    let (code, err) = ballast(&[&args[..], &fast].concat());
    assert_eq!(code, 0, "{err}");
    let rows: Vec<SettlementEnsembleRow> = ballast::io::read_csv(&settle.join("settlement_ensemble.csv")).unwrap();
    assert_eq!((rows.len(), rows[0].replicas), (1, 2));
    let args = ["track3d", "convergence", "--sample", sample, "--out", conv.to_str().unwrap()];
    let policies = ["--policies", "quad:1e-2", "--reference", "quad:1e-3"];
    let (code, err) = ballast(&[&args[..], &policies, &fast].concat());
    assert_eq!(code, 0, "{err}");
    let table = ballast::studies::SummaryTable::read(&conv.join("convergence.csv")).unwrap();
    assert_eq!(table.rows.len(), 4);
    assert!(table.rows.iter().all(|r| field(&table.header, r, "settlement_diff_m").parse::<f64>().is_ok()));
}

/// The convergence study from a loaded scene, a seated state (`ballast::scenarios::track3d::reloaded_scene`):
/// the `final_scene.toml` of a one-cycle run of the sample, run on for two more cycles under each setting. Each
/// run keeps the scene's own time step (not the loading's default) and is, cycle for cycle, what
/// `ballast run SCENE --replica r` gives on that scene with its tolerance and duration edited by hand; the
/// loading's other fields are refused by name, by the library and the command line, before any run.
#[test]
fn the_convergence_study_runs_on_from_a_loaded_scene() {
    let (dir, s) = sample();
    let dir = dir.join("reloaded");
    let first = dir.join("first");
    let loaded = dir.join("loaded.toml");
    let scene = ballast::scenarios::track3d::loaded_scene(&Scene3::load(&s.path).unwrap(), &loading(1)).unwrap();
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(&loaded, scene.to_toml_string().unwrap()).unwrap();
    let (code, err) = ballast(&["run", loaded.to_str().unwrap(), "--out", first.to_str().unwrap(), "--quiet"]);
    assert_eq!(code, 0, "{err}");
    let seated = first.join("final_scene.toml");
    let out = dir.join("study");
    // Only `cycles` is the study's: dt stays the scene's LOAD_DT although the loading says 2e-4 s.
    let spec = ConvergenceSpec {
        sample: seated.clone(),
        policies: vec![("quad".into(), 1e-2)],
        reference: Some(("quad".into(), 1e-3)),
        replicas: replicas(2, 1e-6, 0),
        loading: LoadingSpec { cycles: 2, ..LoadingSpec::default() },
    };
    let report = study::convergence(&spec, &StudyOptions { jobs: Some(2), ..StudyOptions::new(&out) }, &Quiet).unwrap();
    assert!(report.failed.is_empty(), "{:?}", report.failed);
    assert_eq!(report.table.unwrap().rows.len(), 4);
    // The same runs by hand: the seated scene with the tolerance and two cycles' duration written in.
    let mut by_hand = Scene3::load(&seated).unwrap();
    by_hand.simulation.duration = 100.0 * LOAD_DT;
    by_hand.nscd.as_mut().unwrap().tolerance = Some(1e-3);
    let by_hand_file = dir.join("by_hand.toml");
    std::fs::write(&by_hand_file, by_hand.to_toml_string().unwrap()).unwrap();
    for r in ["0", "1"] {
        let run = dir.join(format!("by_hand-{r}"));
        let args = ["run", by_hand_file.to_str().unwrap(), "--out", run.to_str().unwrap(), "--quiet"];
        let perturb = ["--replica", r, "--perturb", "1e-6", "--perturb-seed", "11"];
        let (code, err) = ballast(&[&args[..], &perturb].concat());
        assert_eq!(code, 0, "{err}");
        let cycles = |d: &Path| std::fs::read_to_string(d.join("cycles.csv")).unwrap();
        let studied = out.join("runs/quad_1e-3").join(format!("replica-{r}"));
        assert_eq!(cycles(&studied), cycles(&run), "replica {r}");
        let c = read_cycles(&studied.join("cycles.csv")).unwrap();
        assert_eq!(c.len(), 2, "two cycles of 50 steps of the scene's own dt");
    }
    let written = Scene3::load(out.join("scenes/quad_1e-2/replica-0.toml")).unwrap();
    assert_eq!((written.simulation.dt, written.nscd.as_ref().unwrap().tolerance), (LOAD_DT, Some(1e-2)));
    // A loading field other than cycles is the scene's own: refused by name, nothing run.
    let bad = dir.join("bad");
    let refuse = |loading: LoadingSpec, field: &str| {
        let spec = ConvergenceSpec { loading, ..spec.clone() };
        let e = study::convergence(&spec, &StudyOptions::new(&bad), &Quiet).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{field}:")) && !e.contains('\n'), "{e}");
    };
    refuse(LoadingSpec { cycles: 1, dt: LOAD_DT, ..LoadingSpec::default() }, "dt");
    refuse(LoadingSpec { cycles: 1, anderson: 0, ..LoadingSpec::default() }, "anderson");
    refuse(LoadingSpec { cycles: 0, ..LoadingSpec::default() }, "cycles");
    let mut no_cycles = Scene3::load(&seated).unwrap();
    no_cycles.output = None;
    let no_cycles_file = dir.join("no_cycles.toml");
    std::fs::write(&no_cycles_file, no_cycles.to_toml_string().unwrap()).unwrap();
    let spec_nc = ConvergenceSpec { sample: no_cycles_file, ..spec.clone() };
    let e = study::convergence(&spec_nc, &StudyOptions::new(&bad), &Quiet).unwrap_err().to_string();
    assert!(e.starts_with("sample:") && e.contains("[output] cycles"), "{e}");
    let args = ["track3d", "convergence", "--sample", seated.to_str().unwrap(), "--out", bad.to_str().unwrap()];
    refused(&[&args[..], &["--dt", "1e-3", "--quiet"]].concat(), "--dt:");
    refused(&[&args[..], &["--frequency", "10", "--quiet"]].concat(), "--frequency:");
    assert!(!bad.join("runs").exists(), "nothing ran");
}
