//! Replicas from perturbed starts (`ballast::studies::replicas`): the
//! perturbation of a scene, and `saussine settle | convergence --replicas` on
//! a 50-grain sample (flat sleeper, 2 cycles at dt = 1 ms), whose ensemble
//! tables must be the statistics of the replicas' own `cycles.csv`.

use crate::scratch;

use ballast::scene::SceneFile;
use ballast::scene::{MdScene, Scene};
use ballast::studies::replicas::{ball_point, perturb_md_scene, perturb_scene, t_quantile_975, Perturbation};
use std::collections::HashMap;
use std::path::Path;
use std::process::Command;

fn run(args: &[&str]) -> String {
    let r = Command::new(env!("CARGO_BIN_EXE_ballast")).args(args).arg("--quiet").output().unwrap();
    assert!(r.status.success(), "{args:?}\nstderr: {}", String::from_utf8_lossy(&r.stderr));
    String::from_utf8_lossy(&r.stdout).into_owned()
}

/// Rows of a CSV file as maps from column name to text.
fn csv(path: &Path) -> Vec<HashMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines();
    let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
    lines.map(|l| header.iter().cloned().zip(l.split(',').map(String::from)).collect()).collect()
}

fn num(row: &HashMap<String, String>, col: &str) -> f64 {
    row.get(col).unwrap_or_else(|| panic!("no column {col}")).parse().unwrap_or_else(|_| panic!("{col}: {row:?}"))
}

fn close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 1e-12 * b.abs().max(1e-6), "{what}: {a} vs {b}");
}

#[test]
fn perturbation_moves_mobile_bodies_within_the_disc() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(root.join("examples/pentagon_deposit.toml")).unwrap();
    let fixed = scene.bodies.iter().filter(|b| b.is_fixed()).count();
    assert!(fixed > 0 && fixed < scene.bodies.len());
    let p = Perturbation { distance_m: 1e-9, seed: 11 };
    let perturbed = |r: u64| {
        let mut s = scene.clone();
        let record = perturb_scene(&mut s, &p, r).unwrap();
        (s, record)
    };
    // Replica 0 is the start itself.
    let (zero, record) = perturbed(0);
    assert_eq!(zero, scene);
    assert_eq!((record.replica, record.bodies_moved, record.perturb_seed), (0, 0, 11));
    let (one, record) = perturbed(1);
    assert_eq!(record.bodies_moved, scene.bodies.len() - fixed);
    for (a, b) in scene.bodies.iter().zip(&one.bodies) {
        let d = (b.position[0] - a.position[0]).hypot(b.position[1] - a.position[1]);
        if a.is_fixed() {
            assert_eq!(a, b, "a fixed body does not move");
        } else {
            // ≤ the radius (plus the rounding of a coordinate near 0.5 m).
            assert!(d > 0.0 && d <= 1e-9 + 1e-15, "{}: moved {d:e}", a.name);
            assert_eq!((a.angle, a.velocity), (b.angle, b.velocity));
        }
    }
    assert!(record.largest_displacement_m <= 1e-9 && record.largest_displacement_m > 0.5e-9);
    // Same seed and replica: the same scene; another replica or seed: another.
    assert_eq!(perturbed(1).0, one);
    assert_ne!(perturbed(2).0, one);
    let mut other = scene.clone();
    perturb_scene(&mut other, &Perturbation { seed: 12, ..p }, 1).unwrap();
    assert_ne!(other, one);
    // Invalid distances are refused, naming the option.
    let e = perturb_scene(&mut scene.clone(), &Perturbation { distance_m: -1.0, seed: 0 }, 1).unwrap_err();
    assert!(e.to_string().contains("perturbation.distance_m"), "{e}");
}

/// MD replicas: every sphere moves within the ball, walls stay; the ball's draws
/// have its moments.
#[test]
fn md_perturbation_moves_every_sphere_within_the_ball() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = MdScene::load(root.join("examples/md_two_spheres.toml")).unwrap();
    let p = Perturbation { distance_m: 1e-9, seed: 3 };
    let perturbed = |r: u64| {
        let mut s = scene.clone();
        let record = perturb_md_scene(&mut s, &p, r).unwrap();
        (s, record)
    };
    let (zero, record) = perturbed(0);
    assert_eq!((zero, record.bodies_moved), (scene.clone(), 0));
    let (one, record) = perturbed(1);
    assert_eq!(record.bodies_moved, scene.bodies.len());
    for (a, b) in scene.bodies.iter().zip(&one.bodies) {
        let d: f64 = a.position.iter().zip(b.position).map(|(a, b)| (b - a) * (b - a)).sum::<f64>().sqrt();
        assert!(d > 0.0 && d <= 1e-9 + 1e-15, "{}: moved {d:e}", a.name);
        assert_eq!((a.velocity, a.spin, a.sphere), (b.velocity, b.spin, b.sphere));
    }
    assert_eq!(one.walls, scene.walls);
    assert_eq!(perturbed(1).0, one);
    assert_ne!(perturbed(2).0, one);
    let e = perturb_md_scene(&mut scene.clone(), &Perturbation { distance_m: f64::NAN, seed: 0 }, 1).unwrap_err();
    assert!(e.to_string().contains("perturbation.distance_m"), "{e}");

    // Uniform in the ball of radius R: E|d| = 3R/4 (the density of |d| is 3r²/R³),
    // P(|d| < R/2) = 1/8, E d = 0. With n = 20 000 draws the standard errors are
    // √(3/80)/√n R = 1.4e-3 R, √(7/64)/√n = 2.3e-3 and √(1/5)/√n R = 3.2e-3 R per
    // coordinate: the bounds below are 5 standard errors.
    let mut rng = p.rng(9);
    let n = 20_000;
    let (mut mean_r, mut inner, mut mean) = (0.0, 0.0, [0.0; 3]);
    for _ in 0..n {
        let d = ball_point(&mut rng, 2.0);
        let r = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        assert!(r <= 2.0);
        mean_r += r / 2.0 / n as f64;
        inner += f64::from(u8::from(r < 1.0)) / n as f64;
        for k in 0..3 {
            mean[k] += d[k] / 2.0 / n as f64;
        }
    }
    assert!((mean_r - 0.75).abs() < 7e-3, "E|d|/R = {mean_r}");
    assert!((inner - 0.125).abs() < 1.2e-2, "P(|d| < R/2) = {inner}");
    assert!(mean.iter().all(|m| m.abs() < 1.6e-2), "E d / R = {mean:?}");
}

/// `ballast run --replica R --perturb D`: the run starts from the same scene the library's perturbation gives
/// (2D polygons, 3D spheres, 3D polyhedra), records it in `scene.toml` and `replica.json`; replica 0 is the
/// scene as it is; a bad distance is refused naming the flag.
#[test]
fn run_replica_starts_from_the_librarys_perturbed_scene() {
    use ballast::scene::Scene3;
    use ballast::studies::replicas::{perturb_scene3, ReplicaRecord, REPLICA_FILE};
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let dir = scratch::dir("run-replica");
    let p = Perturbation { distance_m: 1e-6, seed: 5 };
    let go = |scene: &str, r: u64, out: &str| {
        let (scene, out) = (root.join(scene), dir.join(out));
        let (r, d, s) = (r.to_string(), p.distance_m.to_string(), p.seed.to_string());
        let (scene_s, out_s) = (scene.to_str().unwrap(), out.to_str().unwrap());
        run(&["run", scene_s, "--out", out_s, "--steps", "2", "--replica", &r, "--perturb", &d, "--perturb-seed", &s]);
        let record: ReplicaRecord =
            serde_json::from_str(&std::fs::read_to_string(out.join(REPLICA_FILE)).unwrap()).unwrap();
        (out.join("scene.toml"), record)
    };
    // The recorded `scene.toml` has the run's length (`--steps`): the bodies are compared.
    let (file, record) = go("examples/pentagon_deposit.toml", 3, "2d");
    let mut want = Scene::load(root.join("examples/pentagon_deposit.toml")).unwrap();
    let want_record = perturb_scene(&mut want, &p, 3).unwrap();
    assert_eq!(record, want_record);
    assert_eq!(Scene::load(&file).unwrap().bodies, want.bodies);
    assert!(record.bodies_moved > 0 && record.largest_displacement_m <= 1e-6);

    let (file, record) = go("examples/md_two_spheres.toml", 2, "md");
    let mut want = MdScene::load(root.join("examples/md_two_spheres.toml")).unwrap();
    assert_eq!(record, perturb_md_scene(&mut want, &p, 2).unwrap());
    assert_eq!(MdScene::load(&file).unwrap().bodies, want.bodies);

    let (file, record) = go("examples/cubes3d.toml", 1, "3d");
    let mut want = Scene3::load(root.join("examples/cubes3d.toml")).unwrap();
    assert_eq!(record, perturb_scene3(&mut want, &p, 1).unwrap());
    assert_eq!(Scene3::load(&file).unwrap().bodies, want.bodies);

    // Replica 0: the scene as it is, nothing moved.
    let (file, record) = go("examples/cubes3d.toml", 0, "3d-0");
    assert_eq!((record.replica, record.bodies_moved, record.largest_displacement_m), (0, 0, 0.0));
    assert_eq!(Scene3::load(&file).unwrap().bodies, Scene3::load(root.join("examples/cubes3d.toml")).unwrap().bodies);

    let r = Command::new(env!("CARGO_BIN_EXE_ballast"))
        .args(["run", root.join("examples/cubes3d.toml").to_str().unwrap(), "--out"])
        .arg(dir.join("bad"))
        .args(["--replica", "1", "--perturb=-1e-9", "--quiet"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(!r.status.success() && err.contains("--perturb"), "{err}");
}

/// A 50-grain sample (as the ensemble study's test deposits it).
fn sample(dir: &Path) -> String {
    let out = dir.join("sample");
    run(&["saussine", "sample", "--grains", "50", "--dt", "5e-4", "--out", out.to_str().unwrap()]);
    out.join("sample.toml").to_str().unwrap().to_string()
}

const SHORT: [&str; 6] = ["--cycles", "2", "--dt", "1e-3", "--bars", "0"];

/// `saussine settle --replicas 3`: three runs side by side, each with its
/// perturbed scene and `replica.json`; `settlement_ensemble.csv` is the mean,
/// sd and Student-t interval of their own `cycles.csv`, seating and accrued
/// per replica; `--resume` reruns nothing. With `--perturb 0` the replicas are
/// the same run: identical settlements, sd exactly 0.
#[test]
fn settle_replicas_ensemble_is_that_of_the_replicas() {
    let dir = scratch::dir("settle");
    let sample = sample(&dir);
    let out = dir.join("settle");
    let out_s = out.to_str().unwrap();
    let args = [
        &["saussine", "settle", "--sample", &sample, "--out", out_s, "--replicas", "3", "--seating-cycles", "1"][..],
        &["--perturb-seed", "5", "--jobs", "2", "--snapshot-every", "0"],
        &SHORT,
    ]
    .concat();
    let stdout = run(&args);
    assert!(stdout.contains("3 replicas, cycle 2"), "{stdout}");
    let replica = |r: usize| out.join(format!("runs/replica-{r}"));
    let cycles: Vec<Vec<HashMap<String, String>>> = (0..3).map(|r| csv(&replica(r).join("cycles.csv"))).collect();
    for (r, c) in cycles.iter().enumerate() {
        assert_eq!(c.len(), 2, "replica {r}");
        let rec: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(replica(r).join("replica.json")).unwrap()).unwrap();
        assert_eq!((rec["replica"].as_u64(), rec["perturb_seed"].as_u64()), (Some(r as u64), Some(5)));
        assert_eq!(rec["perturb_m"].as_f64(), Some(1e-9));
        for f in ["loaded.toml", "summary.json", "settlement.png", "scene.toml"] {
            assert!(replica(r).join(f).is_file(), "replica {r}: {f}");
        }
    }
    // The scene each replica ran is its perturbed start.
    let loaded = |r: usize| Scene::load(replica(r).join("loaded.toml")).unwrap();
    let plain = dir.join("plain.toml");
    let r = Command::new(env!("CARGO_BIN_EXE_ballast"))
        .args(["saussine", "load", "--sample", &sample, "--out", plain.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(r.status.success());
    let plain = Scene::load(&plain).unwrap();
    let positions = |s: &Scene| s.bodies.iter().map(|b| b.position).collect::<Vec<_>>();
    assert_eq!(positions(&loaded(0)), positions(&plain), "replica 0 is the unperturbed start");
    assert_ne!(positions(&loaded(1)), positions(&plain));
    assert_ne!(positions(&loaded(1)), positions(&loaded(2)));

    let rows = csv(&out.join("settlement_ensemble.csv"));
    assert_eq!(rows.len(), 2);
    let t2 = t_quantile_975(2.0);
    assert!((t2 - 4.302_652_73).abs() < 1e-7);
    for (c, row) in rows.iter().enumerate() {
        assert_eq!((num(row, "cycle"), num(row, "replicas"), num(row, "seating_cycle")), ((c + 1) as f64, 3.0, 1.0));
        let s: Vec<f64> = cycles.iter().map(|r| num(&r[c], "settlement_at_min_load_m")).collect();
        let mean = s.iter().sum::<f64>() / 3.0;
        let sd = (s.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / 2.0).sqrt();
        close(num(row, "settlement_mean_m"), mean, "mean");
        close(num(row, "settlement_sd_m"), sd, "sd");
        close(num(row, "settlement_ci95_high_m"), mean + t2 * sd / 3f64.sqrt(), "ci high");
        close(num(row, "settlement_ci95_low_m"), mean - t2 * sd / 3f64.sqrt(), "ci low");
        // Accrued since cycle 1, per replica then averaged.
        let a: Vec<f64> = cycles
            .iter()
            .map(|r| num(&r[c], "settlement_at_min_load_m") - num(&r[0], "settlement_at_min_load_m"))
            .collect();
        close(num(row, "accrued_mean_m"), a.iter().sum::<f64>() / 3.0, "accrued");
    }
    // The sleeper goes down, and 1e-9 m at the start changes the settlement.
    assert!(num(&rows[1], "settlement_mean_m") > 0.0 && num(&rows[1], "settlement_sd_m") > 0.0, "{rows:?}");
    for stem in ["settlement_ensemble.png", "settlement_ensemble.svg"] {
        assert!(std::fs::metadata(out.join(stem)).unwrap().len() > 1000);
    }
    // One replica alone (`--replica R`, the same perturbation): the same start
    // and the same run as replica R of the ensemble, bit for bit; accelerated,
    // the same start.
    let alone = dir.join("alone");
    let alone_s = alone.to_str().unwrap();
    let one = [&["saussine", "settle", "--sample", &sample, "--out", alone_s, "--replica", "2"][..], &SHORT].concat();
    run(&[&one[..], &["--perturb-seed", "5", "--snapshot-every", "0"]].concat());
    assert_eq!(csv(&alone.join("cycles.csv")), cycles[2]);
    assert_eq!(positions(&Scene::load(alone.join("loaded.toml")).unwrap()), positions(&loaded(2)));
    assert!(alone.join("replica.json").is_file());
    // Accelerated (1 initial cycle, windows of 2 computed cycles and a jump of
    // 1, over 4 cycles): replica 1 alone, then the ensemble of two.
    let accelerated = ["--cycles", "4", "--dt", "1e-3", "--bars", "0", "--perturb-seed", "5", "--snapshot-every", "0"];
    let accelerated = [&accelerated[..], &["--accelerate", "1,2,1", "--seating-cycles", "1"]].concat();
    let fast = dir.join("alone-accelerated");
    let fast_s = fast.to_str().unwrap();
    run(&[&["saussine", "settle", "--sample", &sample, "--out", fast_s, "--replica", "1"][..], &accelerated].concat());
    assert_eq!(positions(&Scene::load(fast.join("loaded.toml")).unwrap()), positions(&loaded(1)));
    let ens = dir.join("accelerated-ensemble");
    let ens_s = ens.to_str().unwrap();
    let stdout =
        run(&[&["saussine", "settle", "--sample", &sample, "--out", ens_s, "--replicas", "2"][..], &accelerated]
            .concat());
    assert!(stdout.contains("2 replicas, cycle 4"), "{stdout}");
    // Wall times aside, replica 1 of the ensemble is the run of `--replica 1`.
    let table = |d: &Path| -> Vec<HashMap<String, String>> {
        let mut t = csv(&d.join("settlement.csv"));
        t.iter_mut().for_each(|r| drop(r.remove("wall_time_s")));
        t
    };
    let (r0, r1) = (table(&ens.join("runs/replica-0")), table(&ens.join("runs/replica-1")));
    assert_eq!(r1, table(&fast));
    assert_eq!(r1.len(), 4);
    assert!(r1.iter().any(|r| r["computed"] == "0"), "a jump: {r1:?}");
    // The ensemble is theirs: the mean of the two settlements, per cycle.
    let rows = csv(&ens.join("settlement_ensemble.csv"));
    assert_eq!(rows.len(), 4);
    for (c, row) in rows.iter().enumerate() {
        let mean = (num(&r0[c], "settlement_m") + num(&r1[c], "settlement_m")) / 2.0;
        close(num(row, "settlement_mean_m"), mean, "accelerated mean");
        assert_eq!(num(row, "replicas"), 2.0);
    }
    assert_ne!(r0, r1, "the perturbed start is another draw");
    let both =
        Command::new(env!("CARGO_BIN_EXE_ballast")).args([&one[..], &["--replicas", "3"]].concat()).output().unwrap();
    assert!(!both.status.success());
    let e = String::from_utf8_lossy(&both.stderr);
    assert!(e.contains("--replica") && e.contains("--replicas"), "{e}");

    // Resumed, the finished replicas are not rerun.
    let summary = replica(2).join("summary.json");
    let before = std::fs::read(&summary).unwrap();
    run(&[&args[..], &["--resume"]].concat());
    assert_eq!(std::fs::read(&summary).unwrap(), before);

    // Determinism: unperturbed replicas are the same run, bit for bit.
    let same = dir.join("same");
    let args = [
        &["saussine", "settle", "--sample", &sample, "--out", same.to_str().unwrap(), "--replicas", "2"][..],
        &["--perturb", "0", "--snapshot-every", "0"],
        &SHORT,
    ]
    .concat();
    run(&args);
    let (a, b) = (csv(&same.join("runs/replica-0/cycles.csv")), csv(&same.join("runs/replica-1/cycles.csv")));
    assert_eq!(a, b);
    let rows = csv(&same.join("settlement_ensemble.csv"));
    for row in &rows {
        assert_eq!(num(row, "settlement_sd_m"), 0.0, "{row:?}");
        // S = 10 clipped to the 2 cycles run: no accrued settlement before cycle 2.
        assert_eq!(num(row, "seating_cycle"), 2.0);
    }
    assert_eq!(rows[0]["accrued_mean_m"], "");
    assert_eq!((num(&rows[1], "accrued_mean_m"), num(&rows[1], "accrued_sd_m")), (0.0, 0.0));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `saussine convergence --replicas 2`: one row per run, the ensemble columns
/// of its setting, and the difference from the reference (by default the
/// tightest tolerance when no strict run is there) with Welch's interval.
#[test]
fn convergence_replicas_compare_with_the_reference() {
    let dir = scratch::dir("conv");
    let sample = sample(&dir);
    let out = dir.join("conv");
    let args = [
        &["saussine", "convergence", "--sample", &sample, "--out", out.to_str().unwrap()][..],
        &["--policies", "quad:1e-2,quad:1e-4", "--replicas", "2", "--seating-cycles", "1", "--jobs", "2"],
        &SHORT,
    ]
    .concat();
    run(&args);
    let rows = csv(&out.join("convergence.csv"));
    assert_eq!(rows.len(), 4);
    for (row, (label, replica)) in
        rows.iter().zip([("quad_1e-2", 0), ("quad_1e-2", 1), ("quad_1e-4", 0), ("quad_1e-4", 1)])
    {
        assert_eq!((row["replica"].as_str(), row["status"].as_str()), (replica.to_string().as_str(), "ok"));
        assert_eq!(row["reference"], "quad:1e-4");
        let c = csv(&out.join("runs").join(label).join(format!("replica-{replica}/cycles.csv")));
        close(num(row, "settlement_at_min_load_m"), num(&c[1], "settlement_at_min_load_m"), "run's settlement");
    }
    let setting =
        |k: usize| -> Vec<f64> { (0..2).map(|r| num(&rows[2 * k + r], "settlement_at_min_load_m")).collect() };
    let (loose, tight) = (setting(0), setting(1));
    let mean = |v: &[f64]| 0.5 * (v[0] + v[1]);
    close(num(&rows[0], "settlement_ens_mean_m"), mean(&loose), "ensemble mean");
    close(num(&rows[1], "settlement_ens_mean_m"), mean(&loose), "repeated on each run of the setting");
    close(num(&rows[0], "settlement_diff_m"), mean(&loose) - mean(&tight), "difference");
    // Welch with two values each: se² = (a₀ − a₁)²/4 + (b₀ − b₁)²/4.
    let se = (((loose[0] - loose[1]).powi(2) + (tight[0] - tight[1]).powi(2)) / 4.0).sqrt();
    let half = num(&rows[0], "settlement_diff_ci95_high_m") - num(&rows[0], "settlement_diff_m");
    assert!(half >= t_quantile_975(2.0) * se * (1.0 - 1e-9) && half <= t_quantile_975(1.0) * se * (1.0 + 1e-9));
    // The reference against itself: a zero difference, within its interval.
    assert_eq!(num(&rows[2], "settlement_diff_m"), 0.0);
    assert_eq!(rows[2]["settlement_same_as_reference"], "true");
    for stem in ["settlement_ensemble", "cumulated_interpenetration", "iterations_vs_tolerance"] {
        assert!(out.join(format!("{stem}.svg")).is_file(), "{stem}");
    }
    // A reference that is not among the runs is refused before any run.
    let r = Command::new(env!("CARGO_BIN_EXE_ballast"))
        .args(["saussine", "convergence", "--sample", &sample, "--policies", "quad:1e-2", "--reference", "strict:1e-4"])
        .args(["--out", dir.join("bad").to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(r.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&r.stderr).contains("--reference"));
    assert!(!dir.join("bad/runs").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The default solver setting of `ballast saussine` (`LoadingSpec::saussine`:
/// `energy` 1.66e-5, ≤ 2000 sweeps) against a tight reference (`strict` 1e-5,
/// ≤ 20 000 sweeps) on a small loaded sample (50 grains, the default load, bars
/// and time step, 6 cycles), 4 replicas each, within its stated error:
/// - the settlement (seating-dominated) is the reference's: the difference of the
///   ensemble means lies within Welch's 95 % interval (measured −0.03 % of 7.76 mm,
///   interval ±0.12 %);
/// - the settlement accrued after 2 seating cycles is *under-predicted*: 0.62 µm
///   against 1.31 µm, difference in [−1.15, −0.23] µm (release run, BENCHMARKS.md,
///   "Settlement against the stopping rule"). That is the default's stated error,
///   asserted as a ratio to the reference's accrual between 0.3 and 1.2; a default
///   that under- or over-predicts the accrual further fails here.
#[test]
fn the_default_setting_settles_like_the_reference_within_its_stated_error() {
    let dir = scratch::dir("default");
    let sample = sample(&dir);
    let out = dir.join("conv");
    let spec = ballast::scenarios::saussine::LoadingSpec::saussine(1);
    let default = format!("{}:{:e}", spec.criterion, spec.tolerance);
    let policies = format!("{default},strict:1e-5");
    let args = [
        &["saussine", "convergence", "--sample", &sample, "--out", out.to_str().unwrap()][..],
        &["--policies", &policies, "--reference", "strict:1e-5", "--max-iterations", "20000"],
        &["--replicas", "4", "--seating-cycles", "2", "--cycles", "6", "--jobs", "2"],
    ]
    .concat();
    run(&args);
    let rows = csv(&out.join("convergence.csv"));
    assert_eq!(rows.len(), 8);
    let (row, reference) = (&rows[0], &rows[4]);
    eprintln!(
        "default {default}: total diff {} [{}, {}] m, accrued {} against {} m, diff [{}, {}] m",
        row["settlement_diff_m"],
        row["settlement_diff_ci95_low_m"],
        row["settlement_diff_ci95_high_m"],
        row["accrued_mean_m"],
        reference["accrued_mean_m"],
        row["accrued_diff_ci95_low_m"],
        row["accrued_diff_ci95_high_m"]
    );
    assert_eq!(row["settlement_same_as_reference"], "true", "{row:?}");
    let accrued = num(reference, "accrued_mean_m");
    assert!(accrued > 0.0, "the reference accrues nothing after the seating: {reference:?}");
    let ratio = num(row, "accrued_mean_m") / accrued;
    assert!((0.3..=1.2).contains(&ratio), "accrued settlement {ratio:.2} × the reference's");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A job array: `saussine settle --replicas 4` as four `--task K` processes (in a scrambled order) and a
/// `--summarize-only`, the summary byte for byte that of the run of all four side by side; `--tasks` says 4;
/// a summary asked for before every task has run names the missing ones; a task that is not the study's is
/// refused naming `--task`. The same with `--accelerate`.
#[test]
fn replica_tasks_run_one_by_one_summarize_to_the_whole_studys_bytes() {
    let dir = scratch::dir("tasks");
    let sample = sample(&dir);
    for accelerated in [false, true] {
        let base = |out: &Path| {
            let mut a: Vec<String> = ["saussine", "settle", "--sample", &sample, "--replicas", "4"]
                .iter()
                .chain(&["--snapshot-every", "0", "--out", out.to_str().unwrap()])
                .chain(&SHORT)
                .map(|s| s.to_string())
                .collect();
            if accelerated {
                // 2 cycles: 1 initial, a window of 2 computed cycles would exceed them; k_i = 0 is refused for
                // Shenton's law: a linear law over 2 computed cycles, no jump (the tasks' machinery is tested).
                a.extend(["--accelerate", "0,2,1", "--law", "linear"].map(String::from));
            }
            a
        };
        let whole = dir.join(format!("whole-{accelerated}"));
        let args = base(&whole);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        run(&args);
        let parts = dir.join(format!("parts-{accelerated}"));
        let parts_args = base(&parts);
        let with = |extra: &[&'static str]| -> Vec<String> {
            parts_args.iter().cloned().chain(extra.iter().map(|s| s.to_string())).collect()
        };
        let run = |a: Vec<String>| run(&a.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(run(with(&["--tasks"])).trim(), "4");
        for k in ["2", "0", "3"] {
            let out = run(with(&["--task", k]));
            assert!(out.contains("--summarize-only"), "{out}");
        }
        let r = Command::new(env!("CARGO_BIN_EXE_ballast")).args(with(&["--summarize-only", "--quiet"])).output();
        let e = String::from_utf8_lossy(&r.unwrap().stderr).into_owned();
        assert!(e.contains("--summarize-only: 1 of 4 tasks have no finished run: replica-1"), "{e}");
        run(with(&["--task", "1"]));
        run(with(&["--summarize-only"]));
        let summary = |d: &Path| std::fs::read(d.join("settlement_ensemble.csv")).unwrap();
        assert_eq!(summary(&whole), summary(&parts), "accelerated: {accelerated}");
        let r = Command::new(env!("CARGO_BIN_EXE_ballast")).args(with(&["--task", "4", "--quiet"])).output();
        let e = String::from_utf8_lossy(&r.unwrap().stderr).into_owned();
        assert!(e.contains("--task: the study has 4 tasks, 0 to 3; got 4"), "{e}");
    }
    // A single run is its one task: --task and --summarize-only are refused for it, naming the flag.
    for flag in [&["--task", "0"][..], &["--summarize-only"]] {
        let args = [&["saussine", "settle", "--sample", &sample, "--out", "unused", "--quiet"][..], flag].concat();
        let r = Command::new(env!("CARGO_BIN_EXE_ballast")).args(&args).output().unwrap();
        let e = String::from_utf8_lossy(&r.stderr).into_owned();
        assert_eq!(r.status.code(), Some(2), "{e}");
        assert!(e.contains(&format!("{}: for a study of --replicas R > 1", flag[0])), "{e}");
    }
}

/// A study's summary table without the columns of wall-clock time (which differ between any two runs).
fn without_times(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().map(|l| l.split(',').map(String::from).collect::<Vec<_>>());
    let header = lines.next().unwrap();
    let keep: Vec<usize> = (0..header.len()).filter(|&i| !header[i].starts_with("wall_time")).collect();
    assert!(keep.len() < header.len(), "no wall time column in {}", path.display());
    std::iter::once(header).chain(lines).map(|row| keep.iter().map(|&i| row[i].clone()).collect()).collect()
}

/// `saussine steps` with a time step that diverges (3e-2 s: a runaway overlap at step 2) and one that does
/// not, two replicas each, run as four `--task` processes in a shuffled order and summarized: `steps.csv` is
/// the whole study's (but for its wall times), the failed runs' status naming their step and body in both
/// (recorded in their folders, `failed.txt`), and a summary asked for before every task ran names the
/// missing one.
#[test]
fn campaign_tasks_one_by_one_summarize_to_the_whole_studys_table_failures_included() {
    let dir = scratch::dir("campaign-tasks");
    let sample = sample(&dir);
    let base = |out: &Path| -> Vec<String> {
        [&["saussine", "steps", "--sample", &sample, "--out", out.to_str().unwrap()][..]]
            .concat()
            .iter()
            .chain(&["--dts", "1e-3,3e-2", "--inclinations", "0", "--replicas", "2", "--cycles", "1", "--bars", "0"])
            .map(|s| s.to_string())
            .collect()
    };
    let call = |args: Vec<String>| Command::new(env!("CARGO_BIN_EXE_ballast")).args(args).arg("--quiet").output();
    let whole = dir.join("whole");
    let r = call(base(&whole)).unwrap();
    let stderr = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(r.status.success() && stderr.contains("run incl_0e0_dt_3e-2/replica-1 failed: step "), "{stderr}");
    let parts = dir.join("parts");
    let with = |extra: &[&str]| -> Vec<String> {
        base(&parts).into_iter().chain(extra.iter().map(|s| s.to_string())).collect()
    };
    assert_eq!(run(&with(&["--tasks"]).iter().map(String::as_str).collect::<Vec<_>>()).trim(), "4");
    for k in ["3", "0", "2"] {
        let r = call(with(&["--task", k])).unwrap();
        assert!(r.status.success() && String::from_utf8_lossy(&r.stdout).contains("--summarize-only"));
    }
    let r = call(with(&["--summarize-only"])).unwrap();
    let e = String::from_utf8_lossy(&r.stderr).into_owned();
    assert!(!r.status.success() && e.contains("1 of 4 tasks have no finished run: incl_0e0_dt_1e-3/replica-1"), "{e}");
    assert!(call(with(&["--task", "1"])).unwrap().status.success());
    let r = call(with(&["--summarize-only"])).unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (a, b) = (without_times(&whole.join("steps.csv")), without_times(&parts.join("steps.csv")));
    assert_eq!(a, b);
    let status = a[0].iter().position(|h| h == "status").unwrap();
    let statuses: Vec<&str> = a[1..].iter().map(|row| row[status].as_str()).collect();
    assert_eq!(&statuses[..2], ["ok", "ok"]);
    for s in &statuses[2..] {
        assert!(s.starts_with("failed: step ") && s.contains("runaway overlap"), "{s}");
    }
    let recorded = std::fs::read_to_string(parts.join("runs/incl_0e0_dt_3e-2/replica-0/failed.txt")).unwrap();
    assert_eq!(format!("failed: {}", recorded.trim_end()), statuses[2]);
    // Every run's own outputs are the whole study's.
    for run in ["incl_0e0_dt_1e-3/replica-1", "incl_0e0_dt_3e-2/replica-0"] {
        let f = |d: &Path| std::fs::read(d.join("runs").join(run).join("series.csv")).unwrap();
        assert_eq!(f(&whole), f(&parts), "{run}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
