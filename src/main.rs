//! The `ballast` command line.
//!
//! `ballast run SCENE.toml --out DIR [--quiet] [--checkpoint-every S] [--resume]
//! [--stop-after N]` loads and validates the scene, builds the system, makes
//! `round(duration / dt)` steps and writes `series.csv`, `final.json`,
//! `summary.json`, `scene.toml`, `final_scene.toml` and `run.json` in `DIR` (see
//! [`ballast::io`]); `--figures` draws the run's figures at the end (NSCD). The
//! scene's `[simulation] engine` picks the engine: `nscd` here, `md` in
//! `cli/md_run.rs`.
//! Every `S` seconds of wall time (default 300) it writes `checkpoint.json`;
//! `--resume` continues from it with the same numbers as an uninterrupted run;
//! `--stop-after N` stops after N steps with a checkpoint; `--vtk-every N` writes
//! ParaView snapshots every N steps (`DIR/vtk/*.vtp`, `DIR/run.pvd`).
//!
//! Exit codes: 0 on success; 2 for an invalid scene or command line (one line
//! `error: …` on stderr); 1 if the run diverges (`series.csv` and `final.json`
//! then hold the last good state) or an output file cannot be written.

use ballast::io::vtk::PvdCollection;
use ballast::io::{self, Checkpoint, FinalState, RunReport, RunSummary, SeriesWriter, CHECKPOINT_FILE};
use ballast::nscd::StepStats;
use ballast::scene::Scene;
use ballast::Error;
use clap::{Parser, Subcommand};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

#[path = "cli/md_run.rs"]
mod md_run;
#[path = "cli/md_tests.rs"]
mod md_tests;
#[path = "cli/saussine.rs"]
mod saussine;
#[path = "cli/studies.rs"]
mod studies;

#[derive(Debug, Parser)]
#[command(name = "ballast", version, about = "Granular mechanics under cyclic loading (railway ballast settlement)")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Runs a scene and writes its outputs to a directory.
    Run {
        /// The scene file (TOML, see docs/scene-format.md).
        scene: PathBuf,
        /// Output directory (created if needed; existing output files are overwritten).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
        /// Wall-clock seconds between checkpoints (`DIR/checkpoint.json`); 0 disables them.
        #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
        checkpoint_every: f64,
        /// Continue a killed or stopped run from `DIR/checkpoint.json` (same scene file).
        #[arg(long)]
        resume: bool,
        /// Stop after this many steps in this invocation, with a checkpoint to resume from.
        #[arg(long, value_name = "STEPS")]
        stop_after: Option<u64>,
        /// Write VTK snapshots (`DIR/vtk/*.vtp`, listed in `DIR/run.pvd`) every N steps; 0: none.
        #[arg(long, value_name = "N", default_value_t = 0)]
        vtk_every: u64,
        /// Threads of the NLGS sweeps (NSCD: large problems are swept as two halves
        /// side by side) or of the force evaluation (MD: two chunks side by side; the
        /// scene's `md.threads` wins). The numbers do not depend on it. Default: 2 if
        /// the machine has 2 cores.
        #[arg(long)]
        threads: Option<usize>,
        /// At the end, draw the run's figures (PNG + SVG): settlement and interpenetration
        /// curves, force chains, displacement field.
        #[arg(long)]
        figures: bool,
    },
    /// Writes the scene of a loose pentagon deposit with the Saussine et al. (2006)
    /// grading (circumradii 5, 7.5, 10 mm in the numbers 361 : 242 : 121), ready for `run`.
    Deposit {
        /// Number of grains.
        #[arg(long, default_value_t = 724)]
        grains: usize,
        /// Inner width of the box (m).
        #[arg(long, default_value_t = 0.5)]
        width: f64,
        /// Seed of the random positions, orientations and velocities.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Time step (s).
        #[arg(long, default_value_t = 2e-4)]
        dt: f64,
        /// Simulated time of the deposit (s).
        #[arg(long, default_value_t = 2.0)]
        duration: f64,
        /// Output scene file.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
    },
    /// The numerical experiments of Saussine et al. (2006): sample, loaded scenes, studies.
    #[command(subcommand)]
    Saussine(saussine::SaussineCommand),
    /// The MD sample of Karrech et al. (2007), Table 1: deposit, cyclic plate load.
    #[command(subcommand)]
    Karrech(md_tests::KarrechCommand),
    /// The cyclic triaxial box of David, García-Rojo, Herrmann & Luding: compression, cycles.
    #[command(subcommand)]
    Luding(md_tests::LudingCommand),
}

/// Why a command failed, and its exit code.
pub(crate) enum Failure {
    /// Invalid input: exit code 2.
    Input(Error),
    /// The run or its outputs failed: exit code 1.
    Run(Error),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run { scene, out, quiet, checkpoint_every, resume, stop_after, vtk_every, threads, figures } => {
            let threads = threads.unwrap_or_else(default_threads);
            let opts =
                RunOptions { quiet, checkpoint_every, resume, stop_after, vtk_every, figures, threads, progress: None };
            run(&scene, &out, &opts)
        }
        Command::Deposit { grains, width, seed, dt, duration, out } => deposit(grains, width, seed, dt, duration, &out),
        Command::Saussine(cmd) => saussine::main(cmd),
        Command::Karrech(cmd) => md_tests::karrech_main(cmd),
        Command::Luding(cmd) => md_tests::luding_main(cmd),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure::Input(e)) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(2)
        }
        Err(Failure::Run(e)) => {
            eprintln!("error: {}", one_line(&e));
            ExitCode::from(1)
        }
    }
}

/// Cores of the machine (1 if unknown).
pub(crate) fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// Threads of a single run: 2 when the machine has 2 cores (the split NLGS solver
/// and the MD force evaluation use at most 2).
pub(crate) fn default_threads() -> usize {
    cores().min(2)
}

/// What an output folder holds for `--resume`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Prior {
    /// A finished run: `marker` is there and no checkpoint.
    Finished,
    /// A run to continue from its checkpoint.
    Checkpointed,
    /// Nothing to continue: start afresh.
    Nothing,
}

impl Prior {
    /// The state of `dir` as `--resume` (`resume`) sees it; without `--resume`, always `Nothing`.
    pub(crate) fn of(dir: &Path, marker: &str, resume: bool) -> Self {
        let checkpoint = dir.join(CHECKPOINT_FILE).exists();
        match (resume, checkpoint) {
            (false, _) => Prior::Nothing,
            (true, true) => Prior::Checkpointed,
            (true, false) if dir.join(marker).exists() => Prior::Finished,
            (true, false) => Prior::Nothing,
        }
    }
}

/// `ballast deposit`: generates, validates and writes a loose deposit scene.
fn deposit(grains: usize, width: f64, seed: u64, dt: f64, duration: f64, out: &Path) -> Result<(), Failure> {
    use ballast::scenarios::{pentagon_deposit, DepositSpec};
    if grains == 0 || !(width.is_finite() && width > 0.0) {
        return Err(Failure::Input(Error::Scene(format!(
            "deposit: need at least one grain and a positive width, got {grains} grains and {width} m"
        ))));
    }
    // The generated scene goes through the same validation as any scene file.
    let scene = pentagon_deposit(&DepositSpec { dt, duration, ..DepositSpec::saussine(grains, width, seed) })
        .map_err(Failure::Input)?;
    let text = format!(
        "# Loose pentagon deposit: {grains} grains, seed {seed}.\n{}",
        scene.to_toml_string().map_err(Failure::Run)?
    );
    std::fs::write(out, text).map_err(|e| Failure::Run(Error::Io(e)))?;
    println!("wrote {} ({grains} grains, seed {seed})", out.display());
    Ok(())
}

/// The error's message on a single line.
pub(crate) fn one_line(e: &Error) -> String {
    e.to_string().split_whitespace().collect::<Vec<_>>().join(" ")
}

fn progress_bar(steps: u64, quiet: bool) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let pb = ProgressBar::with_draw_target(Some(steps), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{prefix} {bar:40} {pos}/{len} steps, {msg} [{elapsed_precise} < {eta}]")
    {
        pb.set_style(style);
    }
    pb
}

/// `--checkpoint-every` must be a number of seconds ≥ 0.
pub(crate) fn check_checkpoint_every(opts: &RunOptions) -> Result<(), Failure> {
    if opts.checkpoint_every.is_finite() && opts.checkpoint_every >= 0.0 {
        Ok(())
    } else {
        Err(Failure::Input(Error::Scene(format!(
            "--checkpoint-every: must be a non-negative number of seconds, got {}",
            opts.checkpoint_every
        ))))
    }
}

/// Options of `ballast run` besides the scene and the output directory.
#[derive(Default)]
pub(crate) struct RunOptions {
    pub quiet: bool,
    pub checkpoint_every: f64,
    pub resume: bool,
    pub stop_after: Option<u64>,
    pub vtk_every: u64,
    /// Draw the run's figures at the end (`io::run_figures`).
    pub figures: bool,
    /// Threads of the NLGS sweeps (NSCD) or of the force evaluation (MD, unless
    /// the scene gives `md.threads`); the numbers do not depend on it.
    pub threads: usize,
    /// Show the progress bar in this group (runs of a study side by side), with a label.
    pub progress: Option<(indicatif::MultiProgress, String)>,
}

/// Writes `run.json` (seed, engine, crate version, steps, time step) in `out`.
pub(crate) fn write_run_info(out: &Path, seed: u64, engine: &str, steps: u64, dt: f64) -> Result<(), Failure> {
    let info =
        io::RunInfo { seed, engine: engine.to_string(), version: env!("CARGO_PKG_VERSION").to_string(), steps, dt };
    info.write(out).map(|_| ()).map_err(Failure::Run)
}

/// Writes `final_scene.toml`: `state` (the scene holding the final state, as TOML)
/// under a header naming the crate version, the input scene, the time and the step.
pub(crate) fn write_final_scene(
    out: &Path,
    scene_path: &Path,
    time: f64,
    step: u64,
    state: &str,
) -> Result<(), Failure> {
    let text = format!(
        "# Written by ballast {}: the state of {} at t = {time} s (step {step}).\n\
         # Rerun it with `ballast run`; time restarts at 0.\n\n{state}",
        env!("CARGO_PKG_VERSION"),
        scene_path.display().to_string().replace(char::is_control, "?"),
    );
    io::write_text(out, "final_scene.toml", &text).map(|_| ()).map_err(Failure::Run)
}

/// The line printed when a run stops on request (`--stop-after`), leaving a checkpoint.
pub(crate) fn print_stopped(step: u64, steps: u64, time: f64, elapsed_s: f64) {
    println!("stopped at step {step} of {steps} (t = {time:.6} s) after {elapsed_s:.2} s; continue with --resume");
}

/// `ballast run`: the engine of the scene (`[simulation] engine`) runs it.
pub(crate) fn run(scene_path: &Path, out: &Path, opts: &RunOptions) -> Result<(), Failure> {
    let scene_text = Scene::read_text(scene_path).map_err(Failure::Input)?;
    let name = scene_path.display().to_string();
    let engine = ballast::scene::engine_of_named(&scene_text, &name).map_err(Failure::Input)?;
    if engine == "md" {
        return md_run::run(scene_path, &scene_text, out, opts);
    }
    let scene = Scene::from_toml_str_named(&scene_text, &name).map_err(Failure::Input)?;
    let steps = scene.steps();
    let every = scene.output_every();
    check_checkpoint_every(opts)?;

    // A fresh run, or the continuation of a checkpointed one.
    let vtk_dir = out.join("vtk");
    let cycles_path = out.join("cycles.csv");
    let pvd_path = out.join("run.pvd");
    let (mut sys, mut series, mut summary, mut snapshots, mut cycles) = if opts.resume {
        let cp = Checkpoint::<ballast::nscd::System>::load(out, &scene_text).map_err(Failure::Input)?;
        let series =
            SeriesWriter::resume(&out.join("series.csv"), cp.series_bytes, cp.series_rows).map_err(Failure::Run)?;
        io::remove_stale(out, "final_scene.toml").map_err(Failure::Run)?;
        let cycles = cp.cycles;
        if let Some(c) = &cycles {
            io::cycles::truncate_rows(&cycles_path, c.cycle).map_err(Failure::Run)?;
        }
        (cp.system, series, cp.summary, cp.snapshots, cycles)
    } else {
        let sys = scene.build().map_err(Failure::Input)?;
        io::create_output_dir(out).map_err(Failure::Run)?;
        // Files left by an earlier run would pass for this run's.
        io::remove_stale(out, "final_scene.toml").map_err(Failure::Run)?;
        io::remove_stale(out, CHECKPOINT_FILE).map_err(Failure::Run)?;
        io::copy_scene(scene_path, out).map_err(Failure::Run)?;
        write_run_info(out, scene.seed(), &scene.simulation.engine, steps, scene.simulation.dt)?;
        let series = SeriesWriter::create(&out.join("series.csv")).map_err(Failure::Run)?;
        let mut snapshots = PvdCollection::new();
        if opts.vtk_every > 0 {
            // The initial state is the first snapshot.
            io::create_output_dir(&vtk_dir).map_err(Failure::Run)?;
            snapshots.write_snapshot(&vtk_dir, &sys).map_err(Failure::Run)?;
            snapshots.write(&pvd_path).map_err(Failure::Run)?;
        }
        io::remove_stale(out, "cycles.csv").map_err(Failure::Run)?;
        let cycles = scene.output_cycles().map(|(f, body)| io::cycles::CycleRecorder::new(&sys, f, body));
        (sys, series, RunSummary::default(), snapshots, cycles)
    };
    sys.set_threads(opts.threads);
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
    let mut last: Option<(StepStats, bool)> = None;
    let mut diverged = None;
    let equilibrium = scene.simulation.equilibrium;
    let mut at_equilibrium = false;
    let checkpoint = |sys: &ballast::nscd::System,
                      series: &mut SeriesWriter,
                      summary: RunSummary,
                      snapshots: &PvdCollection,
                      cycles: &Option<io::cycles::CycleRecorder>| {
        let series_bytes = series.sync()?;
        Checkpoint {
            version: env!("CARGO_PKG_VERSION").to_string(),
            scene: scene_text.clone(),
            series_bytes,
            series_rows: series.rows(),
            summary,
            system: sys.clone(),
            snapshots: snapshots.clone(),
            cycles: cycles.clone(),
        }
        .write(out)
    };
    for k in first..=last_step {
        match sys.step() {
            Ok(stats) => {
                summary.add(&stats);
                let calm = equilibrium.is_some_and(|e| stats.kinetic_energy < e.kinetic_energy);
                summary.calm_steps = if calm { summary.calm_steps + 1 } else { 0 };
                at_equilibrium = equilibrium.is_some_and(|e| summary.calm_steps >= e.steps());
                let written = k % every == 0 || k == steps || at_equilibrium;
                if let Some(row) = cycles.as_mut().and_then(|c| c.record(&sys, &stats)) {
                    io::cycles::append_row(&cycles_path, &row).map_err(Failure::Run)?;
                }
                if written {
                    series.write(&stats).map_err(Failure::Run)?;
                }
                last = Some((stats, written));
                if k % message_every == 0 {
                    let per_cycle = cycles.as_ref().map(|c| {
                        let y = sys.bodies.q[c.body][1];
                        let total = (steps as f64 * scene.simulation.dt * c.frequency).round();
                        format!(", cycle {} of {total}, settlement {:.3} mm", c.cycle, 1e3 * (c.y0 - y))
                    });
                    pb.set_message(format!(
                        "t = {:.4} s, Ek = {:.3e} J{}",
                        stats.time,
                        stats.kinetic_energy,
                        per_cycle.unwrap_or_default()
                    ));
                }
                pb.inc(1);
                if opts.vtk_every > 0 && k % opts.vtk_every == 0 {
                    io::create_output_dir(&vtk_dir).map_err(Failure::Run)?;
                    snapshots.write_snapshot(&vtk_dir, &sys).map_err(Failure::Run)?;
                    snapshots.write(&pvd_path).map_err(Failure::Run)?;
                }
                if opts.checkpoint_every > 0.0 && checkpointed.elapsed().as_secs_f64() >= opts.checkpoint_every {
                    summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
                    checkpoint(&sys, &mut series, summary, &snapshots, &cycles).map_err(Failure::Run)?;
                    checkpointed = Instant::now();
                }
            }
            Err(e) => {
                diverged = Some(e);
                break;
            }
        }
        if at_equilibrium {
            break;
        }
    }
    pb.finish_and_clear();
    summary.wall_time_s = wall0 + started.elapsed().as_secs_f64();
    if diverged.is_none() && sys.step < steps && !at_equilibrium {
        // Stopped on request: leave a checkpoint and nothing that looks final.
        checkpoint(&sys, &mut series, summary, &snapshots, &cycles).map_err(Failure::Run)?;
        series.finish().map_err(Failure::Run)?;
        print_stopped(sys.step, steps, sys.time, started.elapsed().as_secs_f64());
        return Ok(());
    }
    if let Some((stats, false)) = last {
        // The run stopped early: keep the last good step in the series.
        series.write(&stats).map_err(Failure::Run)?;
    }
    series.finish().map_err(Failure::Run)?;
    FinalState::of(&sys).write(&out.join("final.json")).map_err(Failure::Run)?;
    let report =
        RunReport::new(&summary, scene.simulation.dt, sys.time, cycles.as_ref().map(|c| c.cycle), at_equilibrium);
    io::write_json(&out.join("summary.json"), &report).map_err(Failure::Run)?;
    if opts.figures {
        let first = cycles.as_ref().and_then(|c| c.first_cycle_q.as_deref());
        io::run_figures::write_run_figures(out, &sys, first).map_err(Failure::Run)?;
    }
    if let Some(e) = diverged {
        return Err(Failure::Run(e));
    }
    io::remove_stale(out, CHECKPOINT_FILE).map_err(Failure::Run)?;
    let state = scene.with_state(&sys).to_toml_string().map_err(Failure::Run)?;
    write_final_scene(out, scene_path, sys.time, sys.step, &state)?;

    let energy = last.map_or(0.0, |(s, _)| s.kinetic_energy);
    println!(
        "{} steps to t = {:.6} s{} in {:.2} s: {} bodies, final kinetic energy {:.3e} J, max overlap {:.3e} m, {} \
         steps not converged; outputs in {}",
        sys.step,
        sys.time,
        if at_equilibrium { " (equilibrium reached)" } else { "" },
        started.elapsed().as_secs_f64(),
        sys.bodies.len(),
        energy,
        summary.max_overlap,
        summary.unconverged,
        out.display()
    );
    Ok(())
}
