//! The convergence study of Karrech et al. (2007), Figs. 11–13, on a reduced
//! Saussine sample (NSCD pentagons): the error of the accelerated procedure
//! against the number of computed cycles per window `k` at a fixed jump `h`,
//! against `h` at a fixed `k`, and against the gained time, beside the noise
//! floor of full runs whose start differs by 1e-9 m.
//!
//! `cargo run --release --example settlement_convergence -- OUT [GRAINS] [CYCLES] [REPLICAS]`
//! (defaults 121 grains, 150 cycles, 4 full runs) deposits the sample of seed 1,
//! loads it (dt 1e-3 s, `quad_max` 1e-4, the Saussine load scaled to the sample's
//! width), runs `REPLICAS` full runs (replica 0 from the sample as it is, the
//! others from starts moved by at most 1e-9 m) and the accelerated runs from the
//! unperturbed start — `k_i` = 10, `k` ∈ {5, 10, 20, 40} at `h` = 20 and
//! `h` ∈ {5, 10, 40, 80} at `k` = 20 — two at a time, and writes:
//!
//! - `OUT/loaded.toml`, the scene every run starts from (with the seed);
//! - `OUT/runs/<name>/`, each run's folder (`settlement.csv`, `jumps.csv`,
//!   `summary.json`, the cycle positions);
//! - `OUT/convergence.csv`, one row per accelerated run: `k`, `h`, the cycles
//!   computed and reached, the gained cycles and wall time, the settlement
//!   accrued after the initial cycles against the full runs' mean, its error
//!   relative to that mean (Karrech's measure on what accrues, the issue's),
//!   the error against the unperturbed full run, and the configuration error
//!   `E_r` (eq. 22) at the last cycle against it;
//! - `OUT/noise_floor.csv`, the same measures for the perturbed full runs
//!   against the unperturbed one: what chaos alone gives;
//! - figures (PNG + SVG): `error_vs_k`, `error_vs_h` (Fig. 11), and
//!   `error_vs_gained_time` (Figs. 12–13), the noise floor drawn as a line.
//!
//! Errors are on the settlement accrued after the `k_i` initial cycles: the
//! first cycles seat the sleeper and dominate the total.

use ballast::io::figures::{line_chart, Axes, Series};
use ballast::run::positions::CyclePositions;
use ballast::run::{RunOptions, Runner, Status};
use ballast::scenarios::saussine::{loaded_scene, sample_scene, LoadingSpec, SampleSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::settlement::{configuration_error, Accelerated, Acceleration, AccelerationSummary, SettlementRow};
use ballast::studies::replicas::{perturb_scene, Estimate, Perturbation};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};

/// `k_i`, the initial cycles.
const INITIAL: u64 = 10;
/// `h` of the runs at varying `k`, and `k` of the runs at varying `h`.
const FIXED: u64 = 20;
/// The `k` and `h` studied.
const KS: [u64; 4] = [5, 10, 20, 40];
const HS: [u64; 4] = [5, 10, 40, 80];

/// One row of `convergence.csv` and `noise_floor.csv`.
#[derive(Debug, Clone, Serialize)]
struct Row {
    /// `"k"` (a run of the study at fixed h), `"h"` (at fixed k) or `"full"`.
    series: String,
    run: String,
    k: u64,
    h: u64,
    computed_cycles: u64,
    total_cycles: u64,
    gained_cycles: f64,
    wall_time_s: f64,
    /// The unperturbed full run's wall time over this run's.
    gained_time: f64,
    /// Settlement accrued after the initial cycles at the last cycle (m).
    accrued_m: f64,
    /// The full runs' mean of it and its 95 % interval (m).
    full_accrued_mean_m: f64,
    full_accrued_ci95_low_m: Option<f64>,
    full_accrued_ci95_high_m: Option<f64>,
    /// `|accrued − full mean| / full mean`.
    error_vs_mean: f64,
    /// `|accrued − accrued of the unperturbed full run| / the latter`.
    error_vs_start: f64,
    /// Eq. (22) at the last cycle against the unperturbed full run.
    configuration_error: f64,
}

/// A finished run: its settlement rows, summary and cycle positions.
struct Done {
    rows: Vec<SettlementRow>,
    summary: AccelerationSummary,
    positions: CyclePositions,
}

fn main() -> Result<(), ballast::Error> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 2 {
        eprintln!("usage: settlement_convergence OUT [GRAINS] [CYCLES] [REPLICAS]");
        std::process::exit(2);
    }
    let out = PathBuf::from(&args[1]);
    let arg = |i: usize, default: u64, what: &str| -> u64 {
        args.get(i).map_or(default, |s| s.parse().unwrap_or_else(|_| panic!("{what}: a whole number, got '{s}'")))
    };
    let grains = arg(2, 121, "GRAINS") as usize;
    let cycles = arg(3, 150, "CYCLES");
    let replicas = arg(4, 4, "REPLICAS").max(2);
    assert!(cycles > INITIAL + 2 * FIXED, "CYCLES: more than {} are needed", INITIAL + 2 * FIXED);
    std::fs::create_dir_all(&out)?;
    let loaded = loaded_sample(grains, cycles, &out)?;
    ballast::io::write_text(&out, "loaded.toml", &loaded.to_toml_string()?)?;

    // Every run: the full ones first (the reference), then the study.
    let mut jobs: Vec<(String, String, u64, u64, Scene)> = Vec::new();
    for r in 0..replicas {
        let mut scene = loaded.clone();
        perturb_scene(&mut scene, &Perturbation::default(), r)?; // replica 0 unchanged
        jobs.push(("full".into(), format!("full-{r}"), cycles + 1, 1, scene));
    }
    for k in KS {
        jobs.push(("k".into(), format!("k{k}-h{FIXED}"), k, FIXED, loaded.clone()));
    }
    for h in HS {
        jobs.push(("h".into(), format!("k{FIXED}-h{h}"), FIXED, h, loaded.clone()));
    }
    let done: Vec<Done> = jobs
        .par_iter()
        .map(|(_, name, k, h, scene)| run(scene, *k, *h, cycles, &out.join("runs").join(name)))
        .collect::<Result<_, _>>()?;

    let last = cycles as usize - 1;
    let accrued = |d: &Done| d.rows[last].settlement_m - d.rows[INITIAL as usize - 1].settlement_m;
    let full: Vec<f64> = done[..replicas as usize].iter().map(accrued).collect();
    let estimate = Estimate::of(&full).expect("two full runs or more");
    let start = &done[0];
    let row = |(series, name, k, h, _): &(String, String, u64, u64, Scene), d: &Done| {
        let a = accrued(d);
        Row {
            series: series.clone(),
            run: name.clone(),
            k: *k,
            h: *h,
            computed_cycles: d.summary.computed_cycles,
            total_cycles: d.summary.total_cycles,
            gained_cycles: d.summary.gained,
            wall_time_s: d.summary.wall_time_s,
            gained_time: start.summary.wall_time_s / d.summary.wall_time_s,
            accrued_m: a,
            full_accrued_mean_m: estimate.mean,
            full_accrued_ci95_low_m: estimate.low(),
            full_accrued_ci95_high_m: estimate.high(),
            error_vs_mean: (a - estimate.mean).abs() / estimate.mean.abs(),
            error_vs_start: (a - full[0]).abs() / full[0].abs(),
            configuration_error: configuration_error(
                &start.positions.reference,
                &start.positions.cycles[last],
                &d.positions.cycles[last],
                2,
            ),
        }
    };
    let rows: Vec<Row> = jobs.iter().zip(&done).map(|(j, d)| row(j, d)).collect();
    let (floor, study) = rows.split_at(replicas as usize);
    ballast::io::table::write_all(&out.join("noise_floor.csv"), &floor[1..])?;
    ballast::io::table::write_all(&out.join("convergence.csv"), study)?;

    // The noise floor: the perturbed full runs' mean distances from the unperturbed one.
    let mean = |f: fn(&Row) -> f64| floor[1..].iter().map(f).sum::<f64>() / (floor.len() - 1) as f64;
    let floor_settlement = mean(|r| r.error_vs_start);
    let floor_configuration = mean(|r| r.configuration_error);
    // The interval of the full runs' mean, relative to it: an error inside is chaos.
    let ci_half = estimate.ci95.map_or(0.0, |(lo, hi)| 0.5 * (hi - lo) / estimate.mean.abs());
    for r in study {
        println!(
            "{:>8}: computed {:>4} of {} ({:.2}x cycles, {:.2}x time); accrued {:.3e} m vs full mean {:.3e} m \
             (95 % CI ±{:.1} %): error {:.1} %, vs the same start {:.1} % (floor {:.1} %); E_r {:.3} (floor {:.3})",
            r.run,
            r.computed_cycles,
            r.total_cycles,
            r.gained_cycles,
            r.gained_time,
            r.accrued_m,
            r.full_accrued_mean_m,
            100.0 * ci_half,
            100.0 * r.error_vs_mean,
            100.0 * r.error_vs_start,
            100.0 * floor_settlement,
            r.configuration_error,
            floor_configuration,
        );
    }
    figures(&out, study, floor_settlement, floor_configuration, ci_half)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The sample of seed 1 reduced to `grains` pentagons, deposited and loaded for
/// `cycles` cycles (as `tests/settlement_driver.rs`).
fn loaded_sample(grains: usize, cycles: u64, out: &Path) -> Result<Scene, ballast::Error> {
    let spec = SampleSpec::saussine(1).scaled(grains);
    let scene = sample_scene(&spec)?;
    let dir = out.join("deposit");
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    let deposit = Runner::from_system(scene.build()?, scene.plan()?)?.run(&dir, &opts, &mut |_| {})?;
    if deposit.status != Status::Ended(ballast::run::RunEnd::Equilibrium) {
        eprintln!("warning: the deposit ended without reaching equilibrium ({:?})", deposit.status);
    }
    let fin = ballast::engine::FinalState::read(&dir.join("final.json"))?;
    let mut sys = scene.build()?;
    for (i, b) in fin.bodies.iter().enumerate() {
        sys.bodies.q[i] = [b.position[0], b.position[1], b.angle.unwrap_or(0.0)];
    }
    let load = LoadingSpec {
        dt: 1e-3,
        criterion: "quad_max".into(),
        tolerance: 1e-4,
        ..LoadingSpec::saussine(cycles).scaled(spec.width)
    };
    loaded_scene(&scene.with_state(&sys), &load)
}

/// The procedure with `k` computed and `h` extrapolated cycles (a window longer
/// than the run: the full run) on `scene`, into `dir`.
fn run(scene: &Scene, k: u64, h: u64, cycles: u64, dir: &Path) -> Result<Done, ballast::Error> {
    let plan = scene.plan()?;
    let c = plan.cycles.expect("the loaded scene has cycles");
    let spec = Acceleration { settlement_body: c.body, positions: true, ..Acceleration::new(INITIAL, k, h, 1e-5) };
    let run = Accelerated::from_scene(scene.build()?, spec, c.frequency, cycles, 1, scene.to_toml_string()?);
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let outcome = run.run(dir, &opts, &mut |_| {})?;
    Ok(Done {
        rows: ballast::io::read_csv(&dir.join("settlement.csv"))?,
        summary: outcome.summary,
        positions: ballast::run::positions::read(dir)?,
    })
}

/// Figs. 11–13: the two errors against `k`, `h` and the gained time.
fn figures(out: &Path, study: &[Row], floor: f64, floor_e_r: f64, ci_half: f64) -> Result<(), ballast::Error> {
    let pct = |v: f64| 100.0 * v;
    let floor_line = |xs: &[f64], y: f64, label: &str| Series {
        label: label.into(),
        points: xs.iter().map(|&x| (x, y)).collect(),
        ..Series::default()
    };
    for (series, x_of, x_label, stem, title) in [
        ("k", (|r: &Row| r.k as f64) as fn(&Row) -> f64, "computed cycles per window k", "error_vs_k", "h = 20"),
        ("h", |r: &Row| r.h as f64, "extrapolated cycles per jump h", "error_vs_h", "k = 20"),
        ("", |r: &Row| r.gained_time, "gained time (full run's wall time / this run's)", "error_vs_gained_time", ""),
    ] {
        let mut pick: Vec<&Row> = study.iter().filter(|r| series.is_empty() || r.series == series).collect();
        pick.sort_by(|a, b| x_of(a).total_cmp(&x_of(b)));
        if series == "k" || series == "h" {
            // The run at k = h = 20 belongs to both series.
            let shared = study.iter().find(|r| r.k == FIXED && r.h == FIXED);
            if let Some(s) = shared.filter(|s| !pick.iter().any(|p| std::ptr::eq(*p, *s))) {
                pick.push(s);
                pick.sort_by(|a, b| x_of(a).total_cmp(&x_of(b)));
            }
        }
        let xs: Vec<f64> = pick.iter().map(|r| x_of(r)).collect();
        let pts = |f: fn(&Row) -> f64| pick.iter().map(|r| (x_of(r), pct(f(r)))).collect();
        let series = [
            Series {
                label: "accrued settlement vs full runs' mean".into(),
                points: pts(|r| r.error_vs_mean),
                points_only: stem.ends_with("time"),
                ..Series::default()
            },
            Series {
                label: "accrued settlement vs the same start".into(),
                points: pts(|r| r.error_vs_start),
                points_only: stem.ends_with("time"),
                ..Series::default()
            },
            Series {
                label: "configuration, E_r (eq. 22)".into(),
                points: pts(|r| r.configuration_error),
                points_only: stem.ends_with("time"),
                ..Series::default()
            },
            floor_line(&xs, pct(floor), "noise floor: settlement"),
            floor_line(&xs, pct(floor_e_r), "noise floor: E_r"),
            floor_line(&xs, pct(ci_half), "95 % CI of the full runs' mean"),
        ];
        let axes = Axes {
            title: if title.is_empty() {
                "Error against gained time".into()
            } else {
                format!("Error of the accelerated run, {title}")
            },
            x_label: x_label.into(),
            y_label: "error (%)".into(),
            log_x: !stem.ends_with("time"),
            ..Axes::default()
        };
        line_chart(&out.join(stem), &axes, &series)?;
    }
    Ok(())
}
