//! `ballast run` for MD scenes (`[simulation] engine = "md"`): the same loop,
//! options and outputs as an NSCD run (`run` in `main.rs`), for an
//! [`MdSystem`].
//!
//! `MdScene` → `build` → `MdSystem` → `step()` × `round(duration / dt)`; every
//! `output.every` steps and at the last step a row of `series.csv`
//! (`io::md_series`); `--vtk-every N` sphere snapshots; the equilibrium stop;
//! `checkpoint.json` (the serde form of the `MdSystem`) every
//! `--checkpoint-every` seconds and at `--stop-after`, from which `--resume`
//! continues with the same numbers; at the end `final.json`, `summary.json`
//! (particle-steps per second) and `final_scene.toml`.
//!
//! Energies and overlaps are measured on every step (`MdSystem::measure_every`
//! = 1), so that the largest overlap of `summary.json` is that of the whole run
//! and the equilibrium condition sees the elastic energy of every step; on a
//! 2000-sphere bed this costs a few per cent of the step (within the noise of the
//! measurement).

use crate::{
    check_checkpoint_every, print_stopped, progress_bar, write_final_scene, write_run_info, Failure, RunOptions,
};
use ballast::io::vtk::PvdCollection;
use ballast::io::{
    self, md_series_header, md_series_row, Checkpoint, MdFinalState, MdRunReport, MdRunSummary, SeriesWriter,
    CHECKPOINT_FILE,
};
use ballast::md::{MdStepStats, MdSystem};
use ballast::scene::MdScene;
use ballast::Error;
use std::path::Path;
use std::time::Instant;

/// Force-evaluation threads of an MD run: the scene's `md.threads`, else those
/// of the options (`--threads`, whose default is 2 on a machine with 2 cores: the
/// engine cuts the work into 2 chunks).
fn threads(scene: &MdScene, opts: &RunOptions) -> usize {
    scene.threads().unwrap_or(opts.threads)
}

/// `ballast run` of the MD scene `scene_text` read from `scene_path`.
pub(crate) fn run(scene_path: &Path, scene_text: &str, out: &Path, opts: &RunOptions) -> Result<(), Failure> {
    let scene = MdScene::from_toml_str_named(scene_text, &scene_path.display().to_string()).map_err(Failure::Input)?;
    let steps = scene.steps();
    let every = scene.output_every();
    check_checkpoint_every(opts)?;
    if opts.figures {
        return Err(Failure::Input(Error::Scene("--figures: not available for MD scenes (engine = \"md\")".into())));
    }

    // A fresh run, or the continuation of a checkpointed one.
    let vtk_dir = out.join("vtk");
    let pvd_path = out.join("run.pvd");
    let series_path = out.join("series.csv");
    let (mut sys, mut series, mut summary, mut snapshots) = if opts.resume {
        let cp = Checkpoint::<MdSystem, MdRunSummary>::load(out, scene_text).map_err(Failure::Input)?;
        let series = SeriesWriter::resume(&series_path, cp.series_bytes, cp.series_rows).map_err(Failure::Run)?;
        io::remove_stale(out, "final_scene.toml").map_err(Failure::Run)?;
        (cp.system, series, cp.summary, cp.snapshots)
    } else {
        let sys = scene.build().map_err(Failure::Input)?;
        io::create_output_dir(out).map_err(Failure::Run)?;
        // Files left by an earlier run would pass for this run's.
        for stale in ["final_scene.toml", CHECKPOINT_FILE, "cycles.csv"] {
            io::remove_stale(out, stale).map_err(Failure::Run)?;
        }
        io::copy_scene(scene_path, out).map_err(Failure::Run)?;
        write_run_info(out, scene.seed(), &scene.simulation.engine, steps, scene.simulation.dt)?;
        let series = SeriesWriter::with_header(&series_path, &md_series_header(&sys)).map_err(Failure::Run)?;
        let mut snapshots = PvdCollection::new();
        if opts.vtk_every > 0 {
            // The initial state is the first snapshot.
            io::create_output_dir(&vtk_dir).map_err(Failure::Run)?;
            snapshots.write_spheres_snapshot(&vtk_dir, &sys).map_err(Failure::Run)?;
            snapshots.write(&pvd_path).map_err(Failure::Run)?;
        }
        (sys, series, MdRunSummary::default(), snapshots)
    };
    let cycles_path = out.join("cycles.csv");
    let recorder = scene.output.as_ref().and_then(|o| o.cycles).map(|c| {
        let x0 = scene.bodies.iter().map(|b| ballast::md::V3::from(b.position)).collect();
        io::md_cycles::MdCycleRecorder::new(c.frequency, x0)
    });
    if let (true, Some(r)) = (opts.resume, &recorder) {
        io::cycles::truncate_rows(&cycles_path, r.cycles_at(sys.time)).map_err(Failure::Run)?;
    }
    let cycles_header = io::md_cycles::MdCycleRecorder::header(&sys);
    let threads = threads(&scene, opts);
    sys.set_threads(threads);
    sys.measure_every = 1;
    let first = sys.step + 1;
    let last_step = opts.stop_after.map_or(steps, |n| steps.min(sys.step.saturating_add(n)));

    let mut pb = progress_bar(steps, opts.quiet);
    if let (Some((group, label)), false) = (&opts.progress, opts.quiet) {
        pb = group.add(pb.with_prefix(label.clone()));
    }
    pb.set_position(sys.step);
    let wall0 = summary.wall_time_s;
    let message_every = (steps / 1000).max(1);
    let started = Instant::now();
    let mut checkpointed = Instant::now();
    let mut last: Option<MdStepStats> = None;
    let mut diverged = None;
    let equilibrium = scene.simulation.equilibrium;
    // E_p (a loop over the spheres) only when the condition uses it.
    let ratio = equilibrium.is_some_and(|e| e.energy_ratio.is_some());
    let mut at_equilibrium = false;
    let checkpoint = |sys: &MdSystem, series: &mut SeriesWriter, summary: MdRunSummary, snapshots: &PvdCollection| {
        let series_bytes = series.sync()?;
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene_text.to_string(),
            series_bytes,
            series_rows: series.rows(),
            summary,
            system: sys.clone(),
            snapshots: snapshots.clone(),
            cycles: None,
        }
        .write(out)
    };
    for k in first..=last_step {
        let t_before = sys.time;
        let stats = match sys.step() {
            Ok(stats) => stats,
            Err(e) => {
                diverged = Some(e);
                break;
            }
        };
        summary.add(&stats);
        if let Some(row) = recorder.as_ref().and_then(|r| r.record(&sys, t_before)) {
            io::cycles::append_with_header(&cycles_path, &cycles_header, &row).map_err(Failure::Run)?;
        }
        let calm = equilibrium.is_some_and(|e| {
            let ep = if ratio { sys.gravitational_energy() + stats.elastic_energy } else { 0.0 };
            // Moving servo walls are part of the motion that has to die out.
            e.holds(stats.kinetic_energy + sys.wall_kinetic_energy(), ep)
        });
        // Calm steps count only once the condition has failed at least once: a
        // deposit released from rest meets E_k < r E_p before anything has fallen.
        summary.moved |= equilibrium.is_some() && !calm;
        summary.calm_steps = if calm && summary.moved { summary.calm_steps + 1 } else { 0 };
        at_equilibrium = equilibrium.is_some_and(|e| summary.calm_steps >= e.steps());
        if k % every == 0 || k == steps || at_equilibrium {
            series.write_row(&md_series_row(&sys, &stats)).map_err(Failure::Run)?;
        }
        last = Some(stats);
        if k % message_every == 0 {
            pb.set_message(format!(
                "t = {:.4} s, Ek = {:.3e} J, {} contacts + {} on walls",
                stats.time, stats.kinetic_energy, stats.contacts, stats.wall_contacts
            ));
        }
        pb.inc(1);
        if opts.vtk_every > 0 && k % opts.vtk_every == 0 {
            io::create_output_dir(&vtk_dir).map_err(Failure::Run)?;
            snapshots.write_spheres_snapshot(&vtk_dir, &sys).map_err(Failure::Run)?;
            snapshots.write(&pvd_path).map_err(Failure::Run)?;
        }
        if opts.checkpoint_every > 0.0 && checkpointed.elapsed().as_secs_f64() >= opts.checkpoint_every {
            summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
            checkpoint(&sys, &mut series, summary, &snapshots).map_err(Failure::Run)?;
            checkpointed = Instant::now();
        }
        if at_equilibrium {
            break;
        }
    }
    pb.finish_and_clear();
    summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
    if diverged.is_none() && sys.step < steps && !at_equilibrium {
        // Stopped on request: leave a checkpoint and nothing that looks final.
        checkpoint(&sys, &mut series, summary, &snapshots).map_err(Failure::Run)?;
        series.finish().map_err(Failure::Run)?;
        print_stopped(sys.step, steps, sys.time, started.elapsed().as_secs_f64());
        return Ok(());
    }
    // After a divergence the engine holds its last saved good state (at most a
    // hundred steps back): final.json is that state; the series ends at its last
    // row before the divergence.
    series.finish().map_err(Failure::Run)?;
    MdFinalState::of(&sys).write(&out.join("final.json")).map_err(Failure::Run)?;
    let report =
        MdRunReport::new(&summary, sys.particles.len(), threads, scene.simulation.dt, sys.time, at_equilibrium);
    io::write_json(&out.join("summary.json"), &report).map_err(Failure::Run)?;
    if let Some(e) = diverged {
        return Err(Failure::Run(e));
    }
    io::remove_stale(out, CHECKPOINT_FILE).map_err(Failure::Run)?;
    let state = scene.with_state(&sys).to_toml_string().map_err(Failure::Run)?;
    write_final_scene(out, scene_path, sys.time, sys.step, &state)?;

    println!(
        "{} steps to t = {:.6} s{} in {:.2} s ({:.3e} particle-steps/s on {threads} threads): {} spheres, final \
         kinetic energy {:.3e} J, max overlap {:.3e} m; outputs in {}",
        sys.step,
        sys.time,
        if at_equilibrium { " (equilibrium reached)" } else { "" },
        started.elapsed().as_secs_f64(),
        report.particle_steps_per_s,
        sys.particles.len(),
        last.map_or(0.0, |s| s.kinetic_energy),
        summary.max_overlap,
        out.display()
    );
    Ok(())
}
