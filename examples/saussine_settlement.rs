//! A short settlement study on the Saussine et al. (2006) sample (§4.2 in
//! miniature): deposit a sample, load it for a few cycles on the reference
//! sublayer and on one 1000 × stiffer, and write the outputs people look at.
//!
//! `cargo run --release --example saussine_settlement -- [OUT] [CYCLES] [GRAINS] [SEED]`
//! (defaults: `out/saussine_settlement`, 10 cycles, 242 grains — a third of the
//! paper's sample, the width, sleeper and load scaled alike —, seed 1).
//!
//! Writes in OUT: `sample.toml` (the deposit), `cycles_k{F}.csv` and
//! `overlap_k{F}.csv` for each stiffness factor F, figures `settlement.{png,svg}`
//! (settlement vs cycles, Figs. 6/11), `interpenetration.{png,svg}` (mean and max
//! vs time, Figs. 3–4), `force_chains.{png,svg}` (Figs. 8–10) and
//! `displacements.{png,svg}` (grain displacements from the end of the first cycle
//! to the end of the last, Figs. 8–9), and VTK snapshots `vtk/*.vtp` of the
//! loaded sample at the start and at the end.

use ballast::io::cycles::CycleRecorder;
use ballast::io::figures::{self, Axes, Series};
use ballast::io::vtk;
use ballast::scenarios::saussine::{loaded_scene, measure_sample, sample_scene, LoadingSpec, SampleSpec, SLEEPER};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let out = PathBuf::from(args.get(1).map_or("out/saussine_settlement", |s| s.as_str()));
    let cycles: u64 = args.get(2).map_or(Ok(10), |s| s.parse())?;
    let grains: usize = args.get(3).map_or(Ok(242), |s| s.parse())?;
    let seed: u64 = args.get(4).map_or(Ok(1), |s| s.parse())?;
    std::fs::create_dir_all(out.join("vtk"))?;

    // 1. Deposit.
    let spec = SampleSpec::saussine(seed).scaled(grains);
    let scene = sample_scene(&spec)?;
    let eq = scene.simulation.equilibrium.expect("the sample scene stops at equilibrium");
    let mut sys = scene.build()?;
    let start = Instant::now();
    let mut calm = 0;
    for _ in 0..scene.steps() {
        let st = sys.step()?;
        calm = if st.kinetic_energy < eq.kinetic_energy { calm + 1 } else { 0 };
        if calm >= eq.steps() {
            break;
        }
    }
    let sample = scene.with_state(&sys);
    std::fs::write(out.join("sample.toml"), sample.to_toml_string()?)?;
    let r = measure_sample(&sample)?;
    println!(
        "deposit: {} grains at t = {:.3} s in {:.1} s; layer {:.1} mm, solid fraction {:.3}, coordination {:.2}, \
         sublayer {:.1} N for a weight of {:.1} N",
        r.grains,
        sys.time,
        start.elapsed().as_secs_f64(),
        1e3 * r.thickness_m,
        r.solid_fraction,
        r.coordination,
        r.sublayer_reaction_n,
        r.weight_n
    );

    // 2. Loading on two sublayers.
    let mut settlement = Vec::new();
    let mut overlap = Vec::new();
    for factor in [1.0, 1000.0] {
        let load = LoadingSpec { stiffness_factor: factor, ..LoadingSpec::saussine(cycles).scaled(spec.width) };
        let loaded = loaded_scene(&sample, &load)?;
        let mut sys = loaded.build()?;
        let body = loaded.bodies.iter().position(|b| b.name == SLEEPER).expect("the loaded scene has a sleeper");
        let mut rec = CycleRecorder::new(&sys, load.frequency, body);
        let (mut csv, mut ov) = (String::new(), String::new());
        writeln!(csv, "{}", ballast::io::cycles::CYCLES_HEADER)?;
        writeln!(ov, "time_s,mean_overlap_m,max_overlap_m,cumulated_overlap_m,iterations")?;
        let (mut points_mean, mut points_min, mut mean_ov, mut max_ov) = (vec![], vec![], vec![], vec![]);
        let mut after_first = None;
        let main = factor == 1.0;
        if main {
            vtk::write_bodies(&out.join("vtk/bodies_start.vtp"), &sys)?;
        }
        let start = Instant::now();
        for _ in 0..loaded.steps() {
            let st = sys.step()?;
            // Cumulated interpenetration (Fig. 2): the sum over the contacts.
            let (t, mean, max, sum) = (st.time, st.mean_overlap, st.max_overlap, st.total_overlap);
            writeln!(ov, "{t:e},{mean:e},{max:e},{sum:e},{}", st.iterations)?;
            mean_ov.push((st.time, st.mean_overlap));
            max_ov.push((st.time, st.max_overlap));
            if let Some(row) = rec.record(&sys, &st) {
                writeln!(csv, "{row}")?;
                let f: Vec<f64> = row.split(',').map(|x| x.parse().unwrap_or(f64::NAN)).collect();
                points_mean.push((f[0], 1e3 * f[2]));
                points_min.push((f[0], 1e3 * f[3]));
                if after_first.is_none() {
                    after_first = Some(sys.bodies.q.clone());
                }
                println!(
                    "k_N × {factor}: cycle {:.0}: settlement {:.3} mm (mean), {:.3} mm (load minimum), {:.0} sweeps/step",
                    f[0],
                    1e3 * f[2],
                    1e3 * f[3],
                    f[6]
                );
            }
        }
        println!(
            "k_N × {factor}: {cycles} cycles in {:.1} s ({:.2} s per cycle)",
            start.elapsed().as_secs_f64(),
            start.elapsed().as_secs_f64() / cycles as f64
        );
        std::fs::write(out.join(format!("cycles_k{factor}.csv")), csv)?;
        std::fs::write(out.join(format!("overlap_k{factor}.csv")), ov)?;
        settlement.push(Series {
            label: format!("k_N × {factor}, mean over the cycle"),
            points: points_mean,
            band: vec![],
        });
        settlement.push(Series {
            label: format!("k_N × {factor}, at the load minimum"),
            points: points_min,
            band: vec![],
        });
        if main {
            overlap.push(Series { label: "mean".into(), points: mean_ov, band: vec![] });
            overlap.push(Series { label: "max".into(), points: max_ov, band: vec![] });
            vtk::write_bodies(&out.join("vtk/bodies_end.vtp"), &sys)?;
            vtk::write_contacts(&out.join("vtk/contacts_end.vtp"), &sys)?;
            let (polys, fixed) = figures::polygons_of(&sys);
            let title = format!("Force chains after {cycles} cycles (line width ∝ normal force)");
            figures::force_chains(&out.join("force_chains"), &title, &polys, &fixed, &figures::force_lines_of(&sys))?;
            if let Some(q0) = after_first {
                let arrows = ballast::io::run_figures::displacement_arrows(&q0, &sys);
                let title = format!("Grain displacements from cycle 1 to cycle {cycles}");
                figures::displacement_field(&out.join("displacements"), &title, &polys, &fixed, &arrows, 20.0)?;
            }
        }
    }
    let axes = |title: &str, x: &str, y: &str, log_y| Axes {
        title: title.into(),
        x_label: x.into(),
        y_label: y.into(),
        log_x: false,
        log_y,
    };
    figures::line_chart(
        &out.join("settlement"),
        &axes("Sleeper settlement", "cycle", "settlement (mm)", false),
        &settlement,
    )?;
    figures::line_chart(
        &out.join("interpenetration"),
        &axes("Interpenetration, reference sublayer", "time (s)", "overlap (m)", true),
        &overlap,
    )?;
    println!("outputs in {}", out.display());
    Ok(())
}
