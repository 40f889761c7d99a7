//! The experiments of `ballast::studies` called as library functions (no
//! binary), at small sizes: what each writes, what it returns, what its
//! [`RunDisplay`] is told, and which errors are input errors.

use crate::scratch;

use ballast::io::table::write_all;
use ballast::run::{Progress, RunOptions, RunOutcome};
use ballast::scenarios::karrech::Loading as Plate;
use ballast::scenarios::saussine::LoadingSpec;
use ballast::scenarios::saussine::{SampleSpec, SLEEPER};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::studies::campaigns::{self, ConvergenceSpec, EnsembleRow, EnsembleSpec, StudyOptions};
use ballast::studies::karrech_replicas::{load_replicas, KarrechReplicas};
use ballast::studies::luding::{self, CompareRow, Compression, LoopRow, StrainRow};
use ballast::studies::md_stage::{Stage, TestSpec};
use ballast::studies::replicas::Replicas;
use ballast::studies::saussine::{self, Sample};
use ballast::studies::tasks::Tasks;
use ballast::studies::{karrech, Quiet, RunDisplay};
use ballast::Error;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

fn figures_exist(dir: &Path, stems: &[impl AsRef<str>]) {
    for stem in stems {
        for ext in ["png", "svg"] {
            let f = dir.join(format!("{}.{ext}", stem.as_ref()));
            assert!(f.is_file() && std::fs::metadata(&f).unwrap().len() > 1000, "{} missing", f.display());
        }
    }
}

/// The message of an input error (panics on any other result).
fn input_error<T: std::fmt::Debug>(r: ballast::Result<T>) -> String {
    match r {
        Err(Error::Scene(m)) => m,
        other => panic!("expected an input error, got {other:?}"),
    }
}

/// A display that records the runs it is told of.
#[derive(Default)]
struct Record {
    started: Mutex<Vec<String>>,
    ended: Mutex<Vec<(String, u64)>>,
    calls: Mutex<u64>,
    samples: Mutex<Vec<u64>>,
}

impl RunDisplay for Record {
    fn run(&self, label: &str) -> Box<dyn FnMut(&Progress) + '_> {
        self.started.lock().unwrap().push(label.to_string());
        Box::new(move |_| *self.calls.lock().unwrap() += 1)
    }
    fn ended(&self, label: &str, outcome: &RunOutcome) {
        self.ended.lock().unwrap().push((label.to_string(), outcome.step));
    }
    fn sample(&self, sample: &Sample) {
        self.samples.lock().unwrap().push(sample.report.seed);
    }
}

/// A 60-grain sample, then its loaded scene, then §3.2 with two policies for
/// one cycle on two runs side by side: the table's rows and the figures, the
/// runs the display was told of, and a resume that reruns nothing.
#[test]
fn saussine_sample_load_and_convergence_study() {
    let dir = scratch::dir("saussine");
    let spec = SampleSpec { dt: 5e-4, ..SampleSpec::saussine(1) }.scaled(60);
    let sample = saussine::sample(&spec, &dir.join("sample"), false, 1, &Quiet).unwrap();
    assert_eq!(sample.path, dir.join("sample/sample.toml"));
    assert_eq!(sample.report.grains, 60);
    assert!(dir.join("sample/sample.json").is_file() && dir.join("sample/deposit/final_scene.toml").is_file());

    // The loading is checked, naming the fields.
    for (bad, needle) in [
        (LoadingSpec { stiffness_factor: 0.0, ..LoadingSpec::default() }, "stiffness_factor:"),
        (LoadingSpec { inclination_deg: 90.0, ..LoadingSpec::default() }, "inclination_deg:"),
        (LoadingSpec { cycles: 0, ..LoadingSpec::default() }, "cycles:"),
    ] {
        assert!(input_error(saussine::load(&sample.path, &bad, &dir.join("bad.toml"))).contains(needle), "{needle}");
    }
    // The load of a 60-grain sample is scaled with it (same pressure).
    let loading = LoadingSpec { cycles: 1, dt: 1e-3, bars: 0, ..LoadingSpec::default() };
    let loaded = dir.join("loaded.toml");
    saussine::load(&sample.path, &loading, &loaded).unwrap();
    let scene = Scene::load(&loaded).unwrap();
    let sleeper = scene.bodies.iter().find(|b| b.name == SLEEPER).unwrap();
    assert_eq!(sleeper.load.unwrap().mean, -1000.0 * 60.0 / 724.0);

    let study = StudyOptions { jobs: Some(2), ..StudyOptions::new(dir.join("conv")) };
    let conv = ConvergenceSpec {
        sample: sample.path.clone(),
        policies: vec![("quad".into(), 1e-2), ("quad".into(), 1e-5)],
        reference: None,
        replicas: Replicas::default(),
        loading: loading.clone(),
    };
    let record = Record::default();
    let report = campaigns::convergence(&conv, &study, &record).unwrap();
    let table = report.table.as_ref().unwrap();
    assert_eq!(table.path, dir.join("conv/convergence.csv"));
    assert_eq!(report.runs, dir.join("conv/runs"));
    assert!(report.failed.is_empty(), "{:?}", report.failed);
    assert_eq!(&table.header[..4], ["policy", "tolerance", "min_iterations", "max_iterations"]);
    let col = |name: &str| table.header.iter().position(|h| h == name).unwrap();
    assert_eq!(table.rows.len(), 2);
    for (row, tol) in table.rows.iter().zip([1e-2, 1e-5]) {
        assert_eq!(row[col("policy")], "quad");
        assert_eq!(row[col("tolerance")].parse::<f64>().unwrap(), tol);
        assert_eq!((row[col("status")].as_str(), row[col("cycles")].as_str()), ("ok", "1"));
    }
    figures_exist(&dir.join("conv"), &["cumulated_interpenetration", "iterations_vs_tolerance"]);
    for label in ["quad_1e-2", "quad_1e-5"] {
        assert!(dir.join("conv/scenes").join(format!("{label}.toml")).is_file());
        assert!(dir.join("conv/runs").join(label).join("cycles.csv").is_file());
    }
    // One callback per run, called after every step; each run's end told with its steps.
    let mut started = record.started.lock().unwrap().clone();
    started.sort();
    assert_eq!(started, ["quad_1e-2", "quad_1e-5"]);
    let mut ended = record.ended.lock().unwrap().clone();
    ended.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(ended, [("quad_1e-2".to_string(), 50), ("quad_1e-5".to_string(), 50)]);
    assert_eq!(*record.calls.lock().unwrap(), 100);

    // Resumed, the finished study runs nothing and reports the same table.
    let again = Record::default();
    let resumed = campaigns::convergence(&conv, &StudyOptions { resume: true, ..study.clone() }, &again).unwrap();
    assert!(again.started.lock().unwrap().is_empty());
    assert_eq!(resumed.table, report.table);

    // Invalid study options are input errors, before any run.
    let bad = StudyOptions { jobs: Some(0), ..StudyOptions::new(dir.join("bad")) };
    assert!(input_error(campaigns::convergence(&conv, &bad, &Quiet)).contains("jobs:"));
    assert!(!dir.join("bad/runs").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// §4.2 on two 50-grain samples and one sublayer for one cycle: the samples
/// are told to the display as they are deposited, and the ensemble's row is the
/// mean of the two runs. A loading without cycles is refused before any deposit.
#[test]
fn saussine_ensemble_of_two_samples() {
    let dir = scratch::dir("ensemble");
    let loading = LoadingSpec { cycles: 1, dt: 1e-3, bars: 0, ..LoadingSpec::default() };
    let spec = EnsembleSpec {
        samples: 2,
        first_seed: 3,
        factors: vec![1.0],
        grains: Some(50),
        sample_dt: 5e-4,
        loading: loading.clone(),
    };
    let study = StudyOptions { jobs: Some(2), ..StudyOptions::new(dir.join("ens")) };
    let no_cycle = EnsembleSpec { loading: LoadingSpec { cycles: 0, ..loading }, ..spec.clone() };
    assert!(input_error(campaigns::ensemble(&no_cycle, &study, &Quiet)).contains("cycles:"));
    assert!(!dir.join("ens/samples").exists());

    let record = Record::default();
    let report = campaigns::ensemble(&spec, &study, &record).unwrap();
    let table = report.table.as_ref().unwrap();
    let mut seeds = record.samples.lock().unwrap().clone();
    seeds.sort();
    assert_eq!(seeds, [3, 4]);
    assert_eq!(table.path, dir.join("ens/runs.csv"));
    assert_eq!(&table.header[..2], ["seed", "stiffness_factor"]);
    assert_eq!(table.rows.len(), 2);
    let rows: Vec<EnsembleRow> = ballast::io::read_csv(&dir.join("ens/ensemble.csv")).unwrap();
    assert_eq!(rows.len(), 1);
    let settled: Vec<f64> = [3, 4]
        .iter()
        .map(|seed| {
            let c =
                ballast::plane::rows::read_cycles(&dir.join(format!("ens/runs/seed_{seed}_k_1e0/cycles.csv"))).unwrap();
            c[0].settlement_mean_m
        })
        .collect();
    assert_eq!((rows[0].samples, rows[0].cycle), (2, 1));
    assert!((rows[0].settlement_mean_m - 0.5 * (settled[0] + settled[1])).abs() <= 1e-12 * settled[0].abs().max(1e-9));
    figures_exist(&dir.join("ens"), &["settlement_ensemble"]);

    // The same study as tasks (2 deposits, then 2 loaded runs). A loaded run asked for before its sample is
    // deposited is refused, naming the deposit's task.
    let tasks = |t: Tasks| StudyOptions { tasks: t, jobs: Some(1), ..StudyOptions::new(dir.join("tasks")) };
    assert_eq!(spec.task_count(), 4);
    assert!(input_error(campaigns::ensemble(&spec, &tasks(Tasks::One(3)), &Quiet)).contains("seed_3 is not (task 0"));
    // Two processes sharing them (threads here; an MPI barrier there) meet between the deposits and the runs
    // that need them: each rank's loaded run is on the sample the other rank deposited.
    static BARRIER: std::sync::OnceLock<std::sync::Barrier> = std::sync::OnceLock::new();
    BARRIER.get_or_init(|| std::sync::Barrier::new(2));
    fn meet() {
        BARRIER.get().unwrap().wait();
    }
    std::thread::scope(|s| {
        let ranks: Vec<_> = (0..2)
            .map(|rank| {
                let o = StudyOptions { stage_done: meet, ..tasks(Tasks::Share { rank, size: 2 }) };
                let spec = &spec;
                s.spawn(move || campaigns::ensemble(spec, &o, &Quiet).unwrap())
            })
            .collect();
        for r in ranks {
            let r = r.join().unwrap();
            assert!(r.table.is_none() && r.failed.is_empty());
        }
    });
    assert!(!dir.join("tasks/ensemble.csv").exists());
    let summary = campaigns::ensemble(&spec, &tasks(Tasks::Summarize), &Quiet).unwrap();
    assert_eq!(summary.table.unwrap().rows.len(), 2);
    // The samples, hence the runs and the ensemble, are those of the whole study, byte for byte.
    let bytes = |d: &str, f: &str| std::fs::read(dir.join(d).join(f)).unwrap();
    assert_eq!(bytes("ens", "ensemble.csv"), bytes("tasks", "ensemble.csv"));
    for f in ["samples/seed_4/sample.toml", "runs/seed_3_k_1e0/cycles.csv", "runs/seed_4_k_1e0/series.csv"] {
        assert_eq!(bytes("ens", f), bytes("tasks", f), "{f}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A short Karrech deposit of 40 softened spheres, then one cycle of the plate:
/// the stages' scenes, `spec.json`, tables and figures.
#[test]
fn karrech_deposit_then_one_cycle() {
    let dir = scratch::dir("karrech");
    let stage = |name: &str| Stage {
        out: dir.join(name),
        every: 1000,
        run: RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() },
    };
    let spec = karrech::Deposit { spheres: 40, young: 1e7, dt: 2e-6, duration: 0.3, ..karrech::Deposit::default() };
    let bad = karrech::Deposit { spheres: 0, ..spec.clone() };
    assert!(input_error(karrech::deposit(&bad, &stage("bad"), &Quiet)).starts_with("karrech deposit: need spheres"));

    let deposit = karrech::deposit(&spec, &stage("deposit"), &Quiet).unwrap();
    assert_eq!(deposit.run.out, dir.join("deposit"));
    assert_eq!(
        deposit.written,
        ["fig3a_apparent_weight", "fig3b_coordination", "fig3c_packing_fraction", "fig3d_energies"]
    );
    figures_exist(&dir.join("deposit"), &deposit.written);
    let written = TestSpec::read(&dir.join("deposit")).unwrap();
    assert_eq!((written.spheres, written.dt, written.young), (40, Some(2e-6), Some(1e7)));

    // The load needs a finished deposit: an input error naming the option.
    assert!(input_error(karrech::load(&dir.join("bad"), Plate::FULL, 1, &Default::default(), &stage("x"), &Quiet))
        .contains("from:"));
    let load =
        karrech::load(&dir.join("deposit"), Plate::FULL, 1, &Default::default(), &stage("load"), &Quiet).unwrap();
    assert!(dir.join("load/load.toml").is_file());
    assert_eq!(load.written, ["residual_displacement", "plate"]);
    figures_exist(&dir.join("load"), &load.written);
    let cycles = ballast::io::table::read_columns(&dir.join("load/cycles.csv"), &["cycle"]).unwrap();
    assert_eq!(cycles[0], [1.0]);

    // Three replicas of two cycles: the ensemble is the mean of the plates' settlements (their cycles.csv), and
    // the same study run task by task, in another order, then summarized, writes it byte for byte.
    let study = KarrechReplicas {
        loading: Plate::FULL,
        cycles: 2,
        replicas: Replicas { count: 3, seating_cycles: 1, ..Replicas::default() },
        accelerate: None,
    };
    let from = dir.join("deposit");
    let whole = load_replicas(&from, &study, &stage("whole"), Some(2), Tasks::All, &Quiet).unwrap();
    assert!(whole.summarized && whole.failed.is_empty());
    let plates: Vec<Vec<f64>> = (0..3)
        .map(|r| {
            let path = dir.join(format!("whole/runs/replica-{r}/cycles.csv"));
            ballast::io::table::read_columns(&path, &["plate_position_m"]).unwrap().remove(0)
        })
        .collect();
    assert_eq!(whole.rows.len(), 2);
    for (c, row) in whole.rows.iter().enumerate() {
        let mean = plates.iter().map(|p| p[c]).sum::<f64>() / 3.0;
        assert!((row.settlement_mean_m - mean).abs() <= 1e-12 * mean.abs(), "cycle {}: {row:?}", c + 1);
        assert_eq!(row.replicas, 3);
    }
    // Replicas from perturbed starts differ (the perturbation reaches the settlement).
    assert_ne!(plates[1], plates[2]);
    for t in [Tasks::One(2), Tasks::One(0), Tasks::One(1), Tasks::Summarize] {
        let r = load_replicas(&from, &study, &stage("tasks"), Some(2), t, &Quiet).unwrap();
        assert_eq!(r.summarized, t == Tasks::Summarize);
    }
    let table = |d: &str| std::fs::read(dir.join(d).join("settlement_ensemble.csv")).unwrap();
    assert_eq!(table("whole"), table("tasks"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// A short Luding compression writes its scene and `spec.json`; the comparison
/// of two cycled runs (their outputs written here as a cycle leaves them)
/// tabulates ε_N per run and cycle, and refuses a folder that is not a cycled run.
#[test]
fn luding_compression_and_compare_of_two_runs() {
    let dir = scratch::dir("luding");
    let stage = Stage {
        every: 500,
        run: RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() },
        ..Stage::new(dir.join("compress"))
    };
    let bad = Compression { spheres: 0, ..Compression::default() };
    assert!(input_error(luding::compress(&bad, &stage, &Quiet)).starts_with("luding compress: need spheres"));
    let spec = Compression { spheres: 27, duration: 0.2, ..Compression::default() };
    let compressed = luding::compress(&spec, &stage, &Quiet).unwrap();
    assert!(compressed.written.is_empty() && dir.join("compress/compress.toml").is_file());
    let written = TestSpec::read(&dir.join("compress")).unwrap();
    assert_eq!((written.spheres, written.friction, written.period), (27, Some(0.1), None));

    // Two cycled runs of 2 cycles of 10 s (as `luding cycle` leaves them).
    let runs: Vec<PathBuf> = ["mu_0.1", "mu_0.5"].iter().map(|n| dir.join(n)).collect();
    for (k, (run, mu)) in runs.iter().zip([0.1, 0.5]).enumerate() {
        std::fs::create_dir_all(run).unwrap();
        let spec = TestSpec {
            spheres: 27,
            seed: 1,
            friction: Some(mu),
            period: Some(10.0),
            cycles: Some(2),
            dt: None,
            young: None,
        };
        ballast::io::write_json(&run.join("spec.json"), &spec).unwrap();
        let e = |c: f64| 1e-3 * c * (k + 1) as f64;
        let strain: Vec<StrainRow> =
            (1..=2).map(|c| StrainRow { cycle: c, time_s: 10.0 * c as f64, epsilon_n: e(c as f64) }).collect();
        write_all(&run.join("strain.csv"), &strain).unwrap();
        let loops: Vec<LoopRow> = (0..=8)
            .map(|i| {
                let t = 2.5 * i as f64;
                let s = 100.0 * (1.0 - (std::f64::consts::PI * t / 5.0).cos());
                LoopRow { time_s: t, sigma_xx_pa: 1e3 + s, sigma_yy_pa: 1e3, sigma_d_pa: s, epsilon_d: e(t / 10.0) }
            })
            .collect();
        write_all(&run.join("loops.csv"), &loops).unwrap();
    }
    let out = dir.join("compare");
    let written = luding::compare(&runs, &out).unwrap();
    assert_eq!(written, ["compare.csv", "strain_accumulation", "first_cycle_loops"]);
    figures_exist(&out, &written[1..]);
    let rows: Vec<CompareRow> = ballast::io::read_csv(&out.join("compare.csv")).unwrap();
    assert_eq!(rows.len(), 4, "{rows:?}");
    for (row, (run, mu, cycle)) in rows.iter().zip([(0, 0.1, 1), (0, 0.1, 2), (1, 0.5, 1), (1, 0.5, 2)]) {
        assert_eq!(row.run, runs[run].display().to_string());
        assert_eq!((row.spheres, row.friction, row.cycle), (27, mu, cycle));
        assert_eq!(row.epsilon_n, 1e-3 * cycle as f64 * (run + 1) as f64);
    }

    // The compression is not a cycled run; a folder without spec.json is not a
    // run at all (both input errors); a cycled run without its loops is a failure.
    assert!(input_error(luding::compare(&[dir.join("compress")], &out)).contains("not a `luding cycle` output"));
    assert!(input_error(luding::compare(&[dir.join("nowhere")], &out)).contains("spec.json"));
    std::fs::remove_file(runs[1].join("loops.csv")).unwrap();
    assert!(matches!(luding::compare(&runs, &out), Err(Error::Io(_))));
    let _ = std::fs::remove_dir_all(&dir);
}
