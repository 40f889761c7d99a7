//! A short settlement study on the Saussine et al. (2006) sample (§4.2 in
//! miniature): deposit a sample, load it for a few cycles on the reference
//! sublayer and on one 1000 × stiffer, each through the library's run loop, and
//! draw the settlement of both on one figure.
//!
//! `cargo run --release --example saussine_settlement -- [OUT] [CYCLES] [GRAINS] [SEED]`
//! (defaults: `out/saussine_settlement`, 10 cycles, 242 grains — a third of the
//! paper's sample, the width, sleeper and load scaled alike —, seed 1).
//!
//! Writes in OUT: `deposit.toml` and its run in `deposit/` (its `final_scene.toml`
//! is the sample), `loaded_k{F}.toml` and its run in `k{F}/` for each stiffness
//! factor F (`series.csv`, `cycles.csv`, the positions of every grain at each
//! cycle end, `summary.json`, the run's figures: settlement, interpenetration,
//! force chains, displacements, and VTK snapshots at the start and end), and
//! `settlement.{png,svg}` with the settlement of both runs (Figs. 6/11).

use ballast::io::figures::{self, Axes};
use ballast::open::run_file;
use ballast::report::plane::settlement_series;
use ballast::run::{RunOptions, Status};
use ballast::scenarios::saussine::{loaded_scene, measure_sample, sample_scene, LoadingSpec, SampleSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = PathBuf::from(args.get(1).map_or("out/saussine_settlement", |s| s.as_str()));
    let cycles: u64 = args.get(2).map_or(Ok(10), |s| s.parse())?;
    let grains: usize = args.get(3).map_or(Ok(242), |s| s.parse())?;
    let seed: u64 = args.get(4).map_or(Ok(1), |s| s.parse())?;
    std::fs::create_dir_all(&out)?;

    // 1. Deposit, until equilibrium.
    let spec = SampleSpec::saussine(seed).scaled(grains);
    let deposit = out.join("deposit.toml");
    std::fs::write(&deposit, sample_scene(&spec)?.to_toml_string()?)?;
    let done = run_file(&deposit, &out.join("deposit"), &RunOptions::default(), &mut |_| {})?;
    let sample = Scene::load(out.join("deposit").join("final_scene.toml"))?;
    let r = measure_sample(&sample)?;
    println!(
        "deposit: {} grains at t = {:.3} s in {:.1} s; layer {:.1} mm, solid fraction {:.3}, coordination {:.2}, \
         sublayer {:.1} N for a weight of {:.1} N",
        r.grains,
        done.time,
        done.elapsed_s,
        1e3 * r.thickness_m,
        r.solid_fraction,
        r.coordination,
        r.sublayer_reaction_n,
        r.weight_n
    );

    // 2. Loading on two sublayers, with the positions of every grain at each cycle end.
    let mut settlement = Vec::new();
    for factor in [1.0, 1000.0] {
        let load = LoadingSpec { stiffness_factor: factor, ..LoadingSpec::saussine(cycles).scaled(spec.width) };
        let mut loaded = loaded_scene(&sample, &load)?;
        if let Some(c) = loaded.output.as_mut().and_then(|o| o.cycles.as_mut()) {
            c.positions = Some(true);
        }
        let path = out.join(format!("loaded_k{factor}.toml"));
        std::fs::write(&path, loaded.to_toml_string()?)?;
        let dir = out.join(format!("k{factor}"));
        let steps = loaded.steps();
        let opts = RunOptions { figures: true, vtk_every: steps, ..RunOptions::default() };
        let run = run_file(&path, &dir, &opts, &mut |_| {})?;
        assert_eq!(run.status, Status::Ended(ballast::run::RunEnd::Finished));
        let rows = ballast::plane::rows::read_cycles(&dir.join("cycles.csv"))?;
        for row in &rows {
            println!(
                "k_N × {factor}: cycle {}: settlement {:.3} mm (mean), {:.3} mm (load minimum), {:.0} sweeps/step",
                row.cycle,
                1e3 * row.settlement_mean_m,
                1e3 * row.settlement_at_min_load_m,
                row.iterations
            );
        }
        println!(
            "k_N × {factor}: {cycles} cycles in {:.1} s ({:.2} s per cycle)",
            run.elapsed_s,
            run.elapsed_s / cycles as f64
        );
        settlement.extend(settlement_series(&rows, &format!("k_N × {factor}"), 1e3));
    }
    let axes = Axes {
        title: "Sleeper settlement".into(),
        x_label: "cycle".into(),
        y_label: "settlement (mm)".into(),
        ..Axes::default()
    };
    figures::line_chart(&out.join("settlement"), &axes, &settlement)?;
    println!("outputs in {}", out.display());
    Ok(())
}
