//! `ballast run SCENE --out DIR`: one scene file of either engine through the
//! library's run loop, or, if it has a `[settlement]` table, through the
//! settlement-acceleration procedure: opened once ([`ballast::open::open`]), then
//! [`ballast::open::Loaded::run`] or [`ballast::open::Loaded::settle`].

use super::{Bars, Failure};
use ballast::run::{default_threads, RunLength, RunOptions};
use ballast::settlement::AccelerationProgress;
use ballast::studies::replicas::{
    perturbed_text, Perturbation, Start, DEFAULT_PERTURBATION_M, DEFAULT_PERTURB_SEED, REPLICA_FILE,
};
use ballast::studies::run_loaded;
use std::path::PathBuf;

/// The arguments of `ballast run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
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
    /// With --resume: the scene may differ from the run's in its `[nscd]` solver keys (criterion, tolerance,
    /// sweep caps, anderson, solver, …), every other key the same; the run goes on from its checkpoint with the
    /// new settings and records them in `DIR/solver_changes.csv` (not for runs with `[settlement]`).
    #[arg(long, requires = "resume")]
    change_solver: bool,
    /// With --resume: the scene may differ from the run's in `[simulation] duration` (or --steps/--duration give
    /// the new length), every other key the same; the run goes on past its end with the numbers of a run that
    /// asked for the longer duration from the start. A finished run can be extended if it ran with
    /// --keep-checkpoint (not for runs with `[settlement]`).
    #[arg(long, requires = "resume")]
    extend: bool,
    /// At the end, keep a checkpoint of the last step (`DIR/checkpoint.json`) from which `--resume --extend`
    /// continues the run.
    #[arg(long)]
    keep_checkpoint: bool,
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
    /// At the end, draw the run's figures (PNG + SVG), as `ballast figures DIR`
    /// does: NSCD settlement and interpenetration curves, force chains,
    /// displacement field; MD energies, coordination, overlaps, wall forces, plate
    /// settlement, side view with contact forces.
    #[arg(long)]
    figures: bool,
    /// Simulated seconds to run instead of the scene's `[simulation] duration`
    /// (for a quick try; the scene copy in DIR records it).
    #[arg(long, value_name = "SECONDS", conflicts_with = "steps", allow_negative_numbers = true)]
    duration: Option<f64>,
    /// Time steps to run instead of the scene's `[simulation] duration`
    /// (duration = STEPS · dt; the scene copy in DIR records it).
    #[arg(long, value_name = "STEPS")]
    steps: Option<u64>,
    /// Run a 2D scene on this engine instead of its own: `nscd` (rigid contacts)
    /// or `md2d` (soft contacts, the scene's `[soft]` table: stiffness and time
    /// step; `md` on a 2D scene, its former spelling, is the same); the scene copy
    /// in DIR records it. A 3D MD scene runs on `md` only.
    #[arg(long, value_name = "ENGINE", value_parser = ["nscd", "md2d", "md"])]
    engine: Option<String>,
    /// Run replica R of the scene instead of the scene itself: R = 0 is the scene as it is, R ≥ 1 the scene
    /// with every mobile body moved by at most --perturb, drawn from stream R of --perturb-seed (the starts
    /// the studies' replicas have: `track3d settle --replicas`, `saussine convergence --replicas`). The scene
    /// copy in DIR records the moved start, `DIR/replica.json` what was done.
    #[arg(long, value_name = "R")]
    replica: Option<u64>,
    /// Largest displacement of a body at the replica's start (m), uniform in the disc (2D) or the ball (3D).
    #[arg(long, value_name = "DIST", requires = "replica", default_value_t = DEFAULT_PERTURBATION_M, allow_negative_numbers = true)]
    perturb: f64,
    /// Seed of the perturbation (replica R draws from stream R of it).
    #[arg(long, value_name = "SEED", requires = "replica", default_value_t = DEFAULT_PERTURB_SEED)]
    perturb_seed: u64,
}

/// `ballast run`.
pub fn main(a: RunArgs) -> Result<(), Failure> {
    let opts = RunOptions {
        checkpoint_every_s: a.checkpoint_every,
        resume: a.resume,
        change_solver: a.change_solver,
        extend: a.extend,
        keep_checkpoint: a.keep_checkpoint,
        stop_after: a.stop_after,
        vtk_every: a.vtk_every,
        threads: a.threads.unwrap_or_else(default_threads),
        figures: a.figures,
        length: match (a.duration, a.steps) {
            (Some(d), _) => Some(RunLength::Duration(d)),
            (None, Some(n)) => Some(RunLength::Steps(n)),
            (None, None) => None,
        },
        engine: a.engine,
    };
    // A scene with `[settlement]` runs the settlement-acceleration procedure.
    let bar = super::cycle_bar(a.quiet);
    let mut show = |p: &AccelerationProgress| super::show_cycles(&bar, p);
    let loaded = match a.replica {
        None => ballast::open::open(&a.scene, &opts)?,
        Some(replica) => {
            let start = Start { replica, perturbation: Perturbation { distance_m: a.perturb, seed: a.perturb_seed } };
            let text = ballast::scene::read_text(&a.scene)?;
            let name = a.scene.display().to_string();
            let (text, record) = perturbed_text(text, &name, opts.engine.as_deref(), &start)?;
            let loaded = ballast::open::open_text(text, &a.scene, &opts)?;
            ballast::io::create_output_dir(&a.out)?;
            ballast::io::write_json(&a.out.join(REPLICA_FILE), &record)?;
            loaded
        }
    };
    if loaded.settles() {
        let summary = loaded.settle(&a.out, &opts, &mut show)?;
        bar.finish_and_clear();
        if let Some(s) = summary {
            super::print_acceleration(&s, &a.out);
        }
        return Ok(());
    }
    bar.finish_and_clear();
    run_loaded(loaded, &a.out, &opts, &Bars::single(a.quiet), "run")?;
    Ok(())
}
