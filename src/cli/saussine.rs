//! `ballast saussine …`: the arguments of the numerical experiments of Saussine
//! et al. (2006), which [`ballast::studies::saussine`] and
//! [`ballast::studies::campaigns`] carry out: each from scene files that are
//! written into the output folder and run with the same loop as `ballast run`
//! (progress, checkpoints, `--resume`).
//!
//! - `sample`: generate and deposit the sample (stage 1, and 1b for a free bank),
//!   save it as `sample.toml`, measure its balance, solid fraction and
//!   coordination number (`sample.json`);
//! - `load`: write the loaded scene (sleeper with bars, load, sublayer stiffness,
//!   solver, time step, number of cycles) from a deposited sample;
//! - `settle`: load a sample and run N cycles (§4): `cycles.csv`, `summary.json`,
//!   VTK snapshots every few cycles, figures; with `--replicas R`, R runs from
//!   perturbed starts and their ensemble (`settlement_ensemble.csv`);
//! - `convergence`, `steps`, `ensemble`: the studies of §3.2, §3.3 and §4.2
//!   ([`ballast::studies::campaigns`]).
//!
//! A sample scaled to fewer grains (`--grains`) is loaded with the sleeper's width
//! and the load scaled alike (same pressure), unless `--sleeper-width` is given.

use super::cluster::Schedule;
use super::{input, print_sample, print_study, Bars, Failure};
use ballast::io::layout;
use ballast::run::default_threads;
use ballast::scenarios::saussine::LoadingSpec;
use ballast::scenarios::saussine::{Guide, SampleSpec};
use ballast::studies::campaigns::{self, ConvergenceSpec, EnsembleSpec, StepsSpec, StudyOptions};
use ballast::studies::replicas::{
    Perturbation, Replicas, Start, DEFAULT_PERTURBATION_M, DEFAULT_PERTURB_SEED, DEFAULT_SEATING_CYCLES,
};
use ballast::studies::saussine::{self, SettleOptions, SettleReplicas};
use ballast::studies::tasks::Tasks;
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub enum SaussineCommand {
    /// Generates the sample (361 + 242 + 121 pentagons on the viscoelastic sublayer),
    /// deposits it under gravity until equilibrium and saves it as DIR/sample.toml.
    Sample {
        /// Seed of the grains' order, positions, orientations and velocities.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Free bank: deposit in a mould, remove it and let the layer settle again.
        #[arg(long)]
        bank: bool,
        /// Scale the grading to about this many grains (and the width with it).
        #[arg(long)]
        grains: Option<usize>,
        /// Time step of the deposit (s).
        #[arg(long, default_value_t = 2e-4)]
        dt: f64,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Continue an interrupted deposit.
        #[arg(long)]
        resume: bool,
        #[arg(long)]
        quiet: bool,
    },
    /// Writes the loaded scene: the sample with the sleeper (and its bars) on top under
    /// F = A + B cos(2π f t − φ), ready for `ballast run`.
    Load {
        /// A deposited sample (`sample.toml` of `ballast saussine sample`).
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Output scene file.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        #[command(flatten)]
        loading: LoadingArgs,
    },
    /// Loads a deposited sample and runs the cycles (§4): per-cycle settlement, mean
    /// grain speed, contacts and iterations (`cycles.csv`), VTK snapshots, figures.
    /// With --replicas R > 1: R runs (accelerated ones with --accelerate) from perturbed
    /// starts side by side in DIR/runs/replica-<r>/, and DIR/settlement_ensemble.csv
    /// (mean, sd, 95 % CI per cycle); --replica R runs one of them alone.
    Settle {
        /// A deposited sample (`sample.toml` of `ballast saussine sample`).
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Output directory (the loaded scene is written there as `loaded.toml`).
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        #[command(flatten)]
        loading: LoadingArgs,
        /// VTK snapshot (bodies and contact forces) every this many cycles; 0: none.
        #[arg(long, value_name = "CYCLES", default_value_t = 10)]
        snapshot_every: u64,
        /// Wall-clock seconds between checkpoints.
        #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
        checkpoint_every: f64,
        /// Continue a killed run from its checkpoint (with --replicas: skip the finished
        /// replicas, resume the checkpointed ones).
        #[arg(long)]
        resume: bool,
        #[command(flatten)]
        replicas: ReplicaArgs,
        /// Run replica R alone (one run, or one accelerated run): 0 from the sample as
        /// it is, R ≥ 1 from the start replica R of --replicas has (every mobile body
        /// moved by at most --perturb, stream R of --perturb-seed; `replica.json`).
        #[arg(long, value_name = "R", default_value_t = 0, conflicts_with = "replicas")]
        replica: u64,
        /// Replicas run at once, each on one core (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
        #[command(flatten)]
        accelerate: AccelerateArgs,
        #[command(flatten)]
        tasks: TaskArgs,
        #[arg(long)]
        quiet: bool,
    },
    /// §3.2: the same cycles with each convergence policy and tolerance of the paper's
    /// table; mean NLGS iterations, wall time and interpenetration per run.
    /// (--criterion and --tolerance are replaced by those of each run.)
    Convergence {
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Runs as POLICY:TOLERANCE, comma separated (default: the paper's table).
        #[arg(long, value_delimiter = ',')]
        policies: Vec<String>,
        /// The setting the others' mean settlements are compared with, POLICY:TOLERANCE
        /// (default: the tightest strict tolerance among the runs, else the tightest of any policy).
        #[arg(long, value_name = "POLICY:TOL")]
        reference: Option<String>,
        #[command(flatten)]
        replicas: ReplicaArgs,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// §3.3: the same cycles with each time step, at each inclination; mean and max
    /// interpenetration over time. (--dt and --inclination are replaced by those of each run.)
    Steps {
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Time steps (s), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "1e-4,2e-4,3e-4,4e-4,5e-4,6e-4,7e-4,8e-4,9e-4,1e-3")]
        dts: Vec<f64>,
        /// Inclinations of the load (degrees), comma separated.
        #[arg(long, value_delimiter = ',', default_value = "0,5")]
        inclinations: Vec<f64>,
        #[command(flatten)]
        replicas: ReplicaArgs,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
    /// §4.2: samples that differ only by their seed, each on sublayers of several
    /// stiffnesses, run in parallel; mean and spread of the settlement per stiffness.
    /// (--stiffness-factor is replaced by those of each run.)
    Ensemble {
        /// Number of samples (seeds first-seed, first-seed + 1, …).
        #[arg(long, default_value_t = 8)]
        samples: u64,
        #[arg(long, default_value_t = 1)]
        first_seed: u64,
        /// Factors on the sublayer stiffness k_N, comma separated.
        #[arg(long, value_delimiter = ',', default_value = "1,100,1000")]
        factors: Vec<f64>,
        /// Scale the grading to about this many grains (and the width with it).
        #[arg(long)]
        grains: Option<usize>,
        /// Time step of the deposits (s).
        #[arg(long, default_value_t = 2e-4)]
        sample_dt: f64,
        #[command(flatten)]
        loading: LoadingArgs,
        #[command(flatten)]
        study: StudyArgs,
    },
}

/// Settings of the loaded stage shared by the subcommands.
#[derive(Debug, Clone, clap::Args)]
pub struct LoadingArgs {
    /// Number of loading cycles.
    #[arg(long, default_value_t = LoadingSpec::default().cycles)]
    pub cycles: u64,
    /// Angle of the load from the vertical (degrees).
    #[arg(long, default_value_t = LoadingSpec::default().inclination_deg)]
    pub inclination: f64,
    /// Sleeper guide: vertical (vx, spin imposed), level (spin imposed) or free;
    /// default: vertical for a vertical load, level otherwise.
    #[arg(long)]
    pub guide: Option<String>,
    /// Factor on the sublayer stiffness k_N (§4.2: 1, 100, 1000).
    #[arg(long, default_value_t = LoadingSpec::default().stiffness_factor)]
    pub stiffness_factor: f64,
    /// Time step (s).
    #[arg(long, default_value_t = LoadingSpec::default().dt)]
    pub dt: f64,
    /// Convergence policy: strict, quad, quad_max, energy, velocity (default: the cheapest measured to
    /// keep the max overlap below 1 % of the smallest grain over 1000 cycles; it under-predicts the
    /// settlement accrued after the seating by about half on a small sample: for accrual rates use
    /// quad 1e-6, where the settlement of a small sample stops changing, BENCHMARKS.md).
    #[arg(long, default_value_t = LoadingSpec::default().criterion)]
    pub criterion: String,
    /// Tolerance of the policy.
    #[arg(long, default_value_t = LoadingSpec::default().tolerance)]
    pub tolerance: f64,
    #[arg(long, default_value_t = LoadingSpec::default().min_iterations)]
    pub min_iterations: usize,
    #[arg(long, default_value_t = LoadingSpec::default().max_iterations)]
    pub max_iterations: usize,
    /// Square bars under the sleeper (0: a flat sleeper).
    #[arg(long, default_value_t = LoadingSpec::default().bars)]
    pub bars: usize,
    /// Width of the sleeper (m).
    #[arg(long)]
    pub sleeper_width: Option<f64>,
}

impl LoadingArgs {
    /// The library's loading (checked by it when a scene is made from it).
    pub fn loading(&self) -> Result<LoadingSpec, Failure> {
        let guide = self.guide.as_deref().map(Guide::from_name).transpose()?;
        Ok(LoadingSpec {
            cycles: self.cycles,
            inclination_deg: self.inclination,
            guide,
            stiffness_factor: self.stiffness_factor,
            dt: self.dt,
            criterion: self.criterion.clone(),
            tolerance: self.tolerance,
            min_iterations: self.min_iterations,
            max_iterations: self.max_iterations,
            bars: self.bars,
            sleeper_width: self.sleeper_width,
            ..LoadingSpec::default()
        })
    }
}

/// Replicas of each setting from perturbed starts (`ballast::studies::replicas`).
#[derive(Debug, Clone, clap::Args)]
pub struct ReplicaArgs {
    /// Runs of each setting: replica 0 from the sample as it is, replicas 1 … R−1 from
    /// starts with every mobile body moved by at most --perturb; 1: the single run.
    #[arg(long, value_name = "R", default_value_t = Replicas::default().count)]
    pub replicas: u64,
    /// Largest displacement of a body at a replica's start (m), uniform in the disc (2D) or the ball (3D).
    #[arg(long, value_name = "DIST", default_value_t = DEFAULT_PERTURBATION_M)]
    pub perturb: f64,
    /// Seed of the perturbations (replica r draws from stream r of it).
    #[arg(long, value_name = "SEED", default_value_t = DEFAULT_PERTURB_SEED)]
    pub perturb_seed: u64,
    /// Seating cycles S: seating = settlement after S cycles, accrued = settlement − seating
    /// (clipped to --cycles).
    #[arg(long, value_name = "S", default_value_t = DEFAULT_SEATING_CYCLES)]
    pub seating_cycles: u64,
}

impl ReplicaArgs {
    /// The library's replicas (checked by it).
    pub fn replicas(&self) -> Replicas {
        Replicas {
            count: self.replicas,
            perturbation: Perturbation { distance_m: self.perturb, seed: self.perturb_seed },
            seating_cycles: self.seating_cycles,
        }
    }
}

/// Which of a study's tasks an invocation runs (`ballast::studies::tasks`): a scheduler's job array runs one
/// task per element, then `--summarize-only` writes the summary.
#[derive(Debug, Clone, clap::Args)]
pub struct TaskArgs {
    /// Run task K of the study alone (numbered 0 … N−1, --tasks), in the folder the whole study gives it,
    /// without the summary: a job array's element (`--task $SLURM_ARRAY_TASK_ID`).
    #[arg(long, value_name = "K", conflicts_with = "summarize_only")]
    pub task: Option<u64>,
    /// Print the number of tasks of the study and exit.
    #[arg(long)]
    pub tasks: bool,
    /// Run nothing: write the summary from the tasks' folders (every task must have finished; the
    /// others are named).
    #[arg(long)]
    pub summarize_only: bool,
    /// Under mpirun: static (task k on rank k mod N) or dynamic (rank 0 hands out the tasks in order
    /// and runs none: for tasks of unequal cost on many ranks).
    #[arg(long, value_enum, default_value_t = Schedule::Static)]
    pub schedule: Schedule,
}

impl TaskArgs {
    /// How to share a study of `count` tasks whose tasks from `second_stage` on need the ones before (0: one
    /// stage).
    pub(crate) fn plan(&self, count: u64, second_stage: u64) -> super::cluster::Plan {
        super::cluster::Plan { selection: self.selection(), schedule: self.schedule, count, second_stage }
    }

    /// For a single run (no replica study): refuses `--task` and `--summarize-only`, and says whether this
    /// process runs it (under mpirun, rank 0 alone).
    pub(crate) fn single_run(&self) -> Result<bool, Failure> {
        if self.selection() != Tasks::All {
            let flag = if self.summarize_only { "--summarize-only" } else { "--task" };
            return Err(input(format!("{flag}: for a study of --replicas R > 1 (a single run is its one task)")));
        }
        Ok(super::cluster::ranks().0 == 0)
    }

    /// The library's selection.
    pub fn selection(&self) -> Tasks {
        match (self.task, self.summarize_only) {
            (Some(k), _) => Tasks::One(k),
            (None, true) => Tasks::Summarize,
            (None, false) => Tasks::All,
        }
    }
}

/// Settings shared by the studies.
#[derive(Debug, Clone, clap::Args)]
pub struct StudyArgs {
    /// Output directory of the study.
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Runs at once, each on one core (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Skip the finished runs and resume the checkpointed ones of an interrupted study.
    #[arg(long)]
    pub resume: bool,
    /// Wall-clock seconds between checkpoints of each run.
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
    pub checkpoint_every: f64,
    /// No progress bars.
    #[arg(long)]
    pub quiet: bool,
    #[command(flatten)]
    pub tasks: TaskArgs,
}

impl StudyArgs {
    /// The library's options (every task; [`Self::run`] selects them).
    pub(crate) fn options(&self) -> StudyOptions {
        StudyOptions {
            out: self.out.clone(),
            jobs: self.jobs,
            resume: self.resume,
            checkpoint_every_s: self.checkpoint_every,
            tasks: Tasks::All,
            stage_done: super::cluster::barrier,
        }
    }

    /// Runs `study` with these options on the tasks asked for (on MPI ranks, shared as `--schedule` says, then
    /// rank 0 the summary) and prints its report; with `--tasks`, prints the study's `count` tasks instead.
    /// Tasks from `second_stage` on need every task before finished (0: one stage).
    pub(crate) fn run<R>(
        &self,
        (count, second_stage): (u64, u64),
        study: impl Fn(&StudyOptions) -> ballast::Result<R>,
        failed: impl Fn(&R) -> &[(String, String)],
        print: impl FnOnce(&R),
    ) -> Result<(), Failure> {
        if self.tasks.tasks {
            println!("{count}");
            return Ok(());
        }
        let opts = self.options();
        let run = |tasks| study(&StudyOptions { tasks, ..opts.clone() });
        if let Some(r) = super::cluster::shared(self.tasks.plan(count, second_stage), run, failed)? {
            print(&r);
        }
        Ok(())
    }
}

/// `--policies`: POLICY:TOLERANCE pairs.
pub(crate) fn policies(given: &[String]) -> Result<Vec<(String, f64)>, Failure> {
    given.iter().map(|p| policy("--policies", p)).collect()
}

/// One POLICY:TOLERANCE pair of `option`.
pub(crate) fn policy(option: &str, p: &str) -> Result<(String, f64), Failure> {
    let (name, tol) = p
        .split_once(':')
        .ok_or_else(|| input(format!("{option}: expected POLICY:TOLERANCE (e.g. quad:1e-6), got '{p}'")))?;
    let tol: f64 = tol.parse().map_err(|_| input(format!("{option}: '{tol}' in '{p}' is not a number")))?;
    Ok((name.to_string(), tol))
}

/// The settlement-acceleration procedure on a settlement run.
#[derive(Debug, clap::Args)]
pub(crate) struct AccelerateArgs {
    /// Accelerate the run (Karrech et al. 2007, Fig. 10): K_I initial cycles, then
    /// windows of K computed cycles each followed by H extrapolated ones;
    /// settlement.csv (one row per cycle, computed or not), jumps.csv, summary.json.
    #[arg(long, value_name = "K_I,K,H")]
    accelerate: Option<String>,
    /// Law of the residual displacement: shenton (c + a ln N + b N on the whole
    /// history, one c per window), shenton_decelerating (the same with a b ≥ 0),
    /// linear (eq. 16), shenton_origin (a ln N + b N, eqs. 20-21).
    #[arg(long, default_value = "shenton", requires = "accelerate")]
    law: String,
    /// Factor on H after each jump.
    #[arg(long, default_value_t = 1.0, requires = "accelerate")]
    growth: f64,
    /// Largest overlap left by the relaxation after a jump (m); default: 1 % of
    /// the smallest grain's inradius (saussine), the largest overlap of the
    /// computed configuration the jump starts from (karrech).
    #[arg(long, value_name = "M", requires = "accelerate")]
    relax_tolerance: Option<f64>,
    /// The largest move a jump may give a body, as a fraction of its size (NSCD
    /// equal-area radius, MD radius), never less than 3 times the median trend
    /// move; default 0.25; inf: no bound.
    #[arg(long, value_name = "FRACTION", requires = "accelerate")]
    extrapolation_limit: Option<f64>,
    /// Smooth each jump's moves: every body moved by the local linear fit of its
    /// neighbours' fitted moves, Gaussian weights of this length (m; cut at 3
    /// times it); default: every body on its own fit (the paper).
    #[arg(long, value_name = "M", requires = "accelerate")]
    smoothing_length: Option<f64>,
    /// Computed cycles after each jump through which the landing re-seats: the
    /// window's data start at the end of the last of them (default 1).
    #[arg(long, value_name = "N", requires = "accelerate")]
    settle_cycles: Option<u64>,
    /// Keep re-seating past --settle-cycles while the settlement's increment
    /// (mean of the last two computed cycles) exceeds this factor times the
    /// per-cycle rate the jump's fit predicted at the landing; those cycles are
    /// computed in addition to the window's, at most K of them (default: none).
    #[arg(long, value_name = "FACTOR", requires = "accelerate")]
    settle_rate: Option<f64>,
    /// Roll a landing back (and retry the jump at half its length, or compute
    /// its cycles) when the window after it settles at more than this factor
    /// times the per-cycle rate the jump's fit predicted (default: none; a landing
    /// is always rolled back when its relaxation fails or a cycle after it fails).
    #[arg(long, value_name = "FACTOR", requires = "accelerate")]
    rollback_rate: Option<f64>,
    /// Land each jump in stages, each moving a point of a body by at most this
    /// fraction of the smallest grain's size and relaxed before the next (a
    /// relaxation from deep overlaps can push a grain through a sublayer pad);
    /// default 0.25; inf: one relaxation of the extrapolated configuration (the paper's).
    #[arg(long, value_name = "FRACTION", requires = "accelerate")]
    relax_stage: Option<f64>,
    /// Hold the sublayer pads (the bodies tied to an anchor by a spring) at their
    /// computed positions through each landing: neither extrapolated nor moved by
    /// the relaxation (default: every body on its own fit, the paper's).
    #[arg(long, requires = "accelerate")]
    hold_anchored: bool,
    /// A full run of the same sample and loading (its output folder, e.g. from
    /// `--accelerate K_I,N+1,1`, which never jumps, or a plain settle): errors.csv
    /// (settlement, accrued error after K_I, coordination) and its curve on the figure.
    #[arg(long, value_name = "DIR", requires = "accelerate")]
    reference: Option<PathBuf>,
}

impl AccelerateArgs {
    pub(crate) fn accelerate(&self) -> Result<Option<saussine::Accelerate>, Failure> {
        let Some(text) = &self.accelerate else { return Ok(None) };
        let parts: Vec<Option<u64>> = text.split(',').map(|p| p.trim().parse().ok()).collect();
        let cycles = match parts.as_slice() {
            [Some(a), Some(b), Some(c)] => [*a, *b, *c],
            _ => return Err(input(format!("--accelerate: expected K_I,K,H (three whole numbers), got '{text}'"))),
        };
        Ok(Some(saussine::Accelerate {
            cycles,
            law: self.law.clone(),
            growth: self.growth,
            relax_tolerance: self.relax_tolerance,
            extrapolation_limit: self.extrapolation_limit,
            smoothing_length: self.smoothing_length,
            settle_cycles: self.settle_cycles,
            settle_rate: self.settle_rate,
            rollback_rate: self.rollback_rate,
            relax_stage: self.relax_stage,
            hold_anchored: self.hold_anchored,
            reference: self.reference.clone(),
        }))
    }
}

/// The accrued-settlement error at the last cycle of an accelerated run compared with its reference.
pub(crate) fn print_errors(out: &std::path::Path, s: &ballast::settlement::AccelerationSummary) -> Result<(), Failure> {
    let rows: Vec<ballast::report::settlement::ErrorRow> = ballast::io::read_csv(&out.join(layout::ERRORS))?;
    if let Some(last) = rows.last() {
        println!(
            "against the reference at cycle {}: settlement {:.4e} m vs {:.4e} m; error on what accrued after the {} \
             initial cycles: {}; configuration error E_r (eq. 22): {}",
            last.cycle,
            last.settlement_m,
            last.reference_settlement_m,
            s.initial_cycles,
            last.accrued_error.map_or("-".to_string(), |e| format!("{:.2} %", 100.0 * e)),
            last.configuration_error.map_or("- (needs both runs' cycle positions)".to_string(), |e| format!("{e:.4}")),
        );
    }
    Ok(())
}

/// The line of an ensemble of settlement runs.
pub(crate) fn print_replicas(r: &SettleReplicas) {
    for (label, e) in &r.failed {
        eprintln!("run {label} failed: {e}");
    }
    if !r.summarized {
        println!(
            "task done (runs in {}); --summarize-only writes the summary once every task has run",
            r.runs.display()
        );
        return;
    }
    let mm = |x: Option<f64>| x.map_or("-".to_string(), |x| format!("{:.3}", 1e3 * x));
    if let Some(last) = r.rows.last() {
        let s = r.rows.iter().find(|row| row.cycle == last.seating_cycle);
        println!(
            "{} replicas, cycle {}: settlement {} mm (95 % CI {} … {}); seating after {} cycles {} mm (CI {} … {}); \
             accrued since {} mm (CI {} … {})",
            last.replicas,
            last.cycle,
            mm(Some(last.settlement_mean_m)),
            mm(last.settlement_ci95_low_m),
            mm(last.settlement_ci95_high_m),
            last.seating_cycle,
            mm(s.map(|s| s.settlement_mean_m)),
            mm(s.and_then(|s| s.settlement_ci95_low_m)),
            mm(s.and_then(|s| s.settlement_ci95_high_m)),
            mm(last.accrued_mean_m),
            mm(last.accrued_ci95_low_m),
            mm(last.accrued_ci95_high_m),
        );
    }
    println!("ensemble: {}; runs in {}", r.table.display(), r.runs.display());
}

pub fn main(cmd: SaussineCommand) -> Result<(), Failure> {
    match cmd {
        SaussineCommand::Sample { seed, bank, grains, dt, out, resume, quiet } => {
            let mut spec = SampleSpec { bank, dt, ..SampleSpec::saussine(seed) };
            if let Some(n) = grains {
                if n == 0 {
                    return Err(input("--grains: must be at least 1".into()));
                }
                spec = spec.scaled(n);
            }
            let sample = saussine::sample(&spec, &out, resume, default_threads(), &Bars::single(quiet))?;
            print_sample(&sample);
        }
        SaussineCommand::Load { sample, out, loading } => {
            saussine::load(&sample, &loading.loading()?, &out)?;
            println!("wrote {}", out.display());
        }
        SaussineCommand::Settle {
            sample,
            out,
            loading,
            snapshot_every,
            checkpoint_every,
            resume,
            replicas,
            replica,
            jobs,
            accelerate,
            tasks,
            quiet,
        } => {
            let replicas = replicas.replicas();
            if tasks.tasks {
                // One task per replica (a single run is one task).
                println!("{}", replicas.count);
                return Ok(());
            }
            if replicas.count == 1 && !tasks.single_run()? {
                return Ok(());
            }
            let plan = tasks.plan(replicas.count, 0);
            let opts =
                SettleOptions { snapshot_every, checkpoint_every_s: checkpoint_every, resume, tasks: plan.selection };
            let start = Start { replica, perturbation: replicas.perturbation };
            if let Some(acc) = accelerate.accelerate()? {
                if replicas.count > 1 {
                    let loading = loading.loading()?;
                    let study = |opts: &SettleOptions| {
                        ballast::studies::accelerated::settle_accelerated_replicas(
                            &sample, &loading, &acc, &out, opts, &replicas, jobs,
                        )
                    };
                    if let Some(r) = super::cluster::shared(
                        plan,
                        |tasks| study(&SettleOptions { tasks, ..opts.clone() }),
                        |r| &r.failed,
                    )? {
                        print_replicas(&r);
                    }
                    return Ok(());
                }
                let bar = super::cycle_bar(quiet);
                let mut show = |p: &ballast::settlement::AccelerationProgress| super::show_cycles(&bar, p);
                let s = saussine::settle_accelerated(
                    &sample,
                    &loading.loading()?,
                    &start,
                    &acc,
                    &out,
                    &opts,
                    default_threads(),
                    &mut show,
                )?;
                bar.finish_and_clear();
                super::print_acceleration(&s, &out);
                if accelerate.reference.is_some() {
                    print_errors(&out, &s)?;
                }
            } else if replicas.count == 1 {
                replicas.check()?;
                saussine::settle(&sample, &loading.loading()?, &start, &out, &opts, &Bars::single(quiet))?;
            } else {
                let (bars, loading) = (Bars::group(quiet), loading.loading()?);
                let study = |opts: &SettleOptions| {
                    saussine::settle_replicas(&sample, &loading, &out, opts, &replicas, jobs, &bars)
                };
                if let Some(r) = super::cluster::shared(
                    plan,
                    |tasks| study(&SettleOptions { tasks, ..opts.clone() }),
                    |r| &r.failed,
                )? {
                    print_replicas(&r);
                }
            }
        }
        SaussineCommand::Convergence { sample, policies: given, reference, replicas, loading, study } => {
            let reference = reference.map(|r| policy("--reference", &r)).transpose()?;
            let spec = ConvergenceSpec {
                sample,
                policies: policies(&given)?,
                reference,
                replicas: replicas.replicas(),
                loading: loading.loading()?,
            };
            let bars = Bars::group(study.quiet);
            study.run(
                (spec.task_count(), 0),
                |o| campaigns::convergence(&spec, o, &bars),
                |r| &r.failed,
                print_study,
            )?;
        }
        SaussineCommand::Steps { sample, dts, inclinations, replicas, loading, study } => {
            let spec =
                StepsSpec { sample, dts, inclinations, replicas: replicas.replicas(), loading: loading.loading()? };
            let bars = Bars::group(study.quiet);
            study.run((spec.task_count(), 0), |o| campaigns::steps(&spec, o, &bars), |r| &r.failed, print_study)?;
        }
        SaussineCommand::Ensemble { samples, first_seed, factors, grains, sample_dt, loading, study } => {
            let spec = EnsembleSpec { samples, first_seed, factors, grains, sample_dt, loading: loading.loading()? };
            let bars = Bars::group(study.quiet);
            study.run(
                (spec.task_count(), spec.samples),
                |o| campaigns::ensemble(&spec, o, &bars),
                |r| &r.failed,
                print_study,
            )?;
        }
    }
    Ok(())
}
