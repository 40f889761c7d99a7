//! `ballast karrech …` and `ballast luding …`: the arguments of the ready-made
//! MD tests, which [`ballast::studies::karrech`] and [`ballast::studies::luding`]
//! carry out.
//!
//! - `karrech deposit --out DIR`: the Table 1 sample of Karrech et al. (2007)
//!   deposited under gravity until `E_c/E_p ≤ 10⁻⁶` (scene `DIR/deposit.toml`,
//!   run in `DIR`), then the Fig. 3 figures from `series.csv`: apparent weight,
//!   coordination number, packing fraction, kinetic and potential energy.
//! - `karrech load --from DEPOSIT --out DIR --mode full|partial --cycles K`: the
//!   deposited sample under the cyclic plate (§4), then `cycles.csv` (residual
//!   displacement per cycle) and its figures; with `--replicas R`, R runs from
//!   perturbed starts and the ensemble of the plate's settlement
//!   ([`ballast::studies::karrech_replicas`]; `--task K`, `--summarize-only`, MPI ranks).
//! - `luding compress --out DIR --spheres N --friction μ`: isotropic compression of
//!   the triaxial box of David et al.; `luding cycle --from COMPRESSED --out DIR
//!   --cycles K`: the cyclic σ_xx, then `loops.csv` (σ_D, ε_D), `strain.csv`
//!   (ε_N per cycle) and the figures of the paper's Figs. 2–5 for that run;
//!   `luding compare --runs DIR… --out DIR`: several cycled runs (sizes N or
//!   frictions μ) on common axes, as the paper's Figs. 3–5.
//!
//! Every run is an ordinary `ballast run` of a written scene: progress bar,
//! checkpoints, `--resume`, `--vtk-every` and the outputs of `ballast run`.

use super::{Bars, Failure};
use ballast::run::{default_threads, RunOptions};
use ballast::scenarios::karrech::Loading;
use ballast::studies::karrech::{self as karrech_test, Deposit, Start};
use ballast::studies::karrech_replicas::{load_replicas, KarrechReplicas};
use ballast::studies::luding::{self, Compression};
use ballast::studies::md_stage::{Stage, StageOutcome};
use ballast::studies::replicas::{Perturbation, Replicas, DEFAULT_PERTURBATION_M, DEFAULT_PERTURB_SEED};
use clap::{Args, Subcommand, ValueEnum};
use std::path::PathBuf;

/// Options shared by every MD test run.
#[derive(Debug, Args, Clone)]
pub struct RunArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    /// Steps between rows of `series.csv`.
    #[arg(long, default_value_t = 1000)]
    every: u64,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
    /// Continue a run from its checkpoint.
    #[arg(long)]
    resume: bool,
    /// Wall-clock seconds between checkpoints.
    #[arg(long, default_value_t = 300.0)]
    checkpoint_every: f64,
    /// VTK snapshots every N steps (0: none).
    #[arg(long, default_value_t = 0)]
    vtk_every: u64,
    /// Force-evaluation threads (default: the cores, at most 2).
    #[arg(long)]
    threads: Option<usize>,
}

impl RunArgs {
    fn stage(&self) -> Stage {
        let run = RunOptions {
            checkpoint_every_s: self.checkpoint_every,
            resume: self.resume,
            vtk_every: self.vtk_every,
            threads: self.threads.unwrap_or_else(default_threads),
            ..RunOptions::default()
        };
        Stage { out: self.out.clone(), every: self.every, run }
    }

    fn display(&self) -> Bars {
        Bars::single(self.quiet)
    }

    fn quiet(&self) -> bool {
        self.quiet
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// The whole top under the plate, Δσ = 14.15 kPa, 50 Hz.
    Full,
    /// 80 % of the top's area, Δσ = 5.87 kPa, 10 Hz.
    Partial,
}

#[derive(Debug, Subcommand)]
pub enum KarrechCommand {
    /// Deposits the Table 1 sample in a quarter cylinder under gravity.
    Deposit {
        /// Number of spheres (850: the paper's 13.6 N sample, a quarter of it).
        #[arg(long, default_value_t = Deposit::default().spheres)]
        spheres: usize,
        #[arg(long, default_value_t = Deposit::default().seed)]
        seed: u64,
        /// Time step (s).
        #[arg(long, default_value_t = Deposit::default().dt)]
        dt: f64,
        /// Longest deposit (s); at Table 1's stiffness the full sample reaches
        /// E_c/E_p = 1.9e-6 at 1 s, hence 2 s.
        #[arg(long, default_value_t = Deposit::default().duration)]
        duration: f64,
        /// Young's modulus of the spheres (Pa); lower it only for quick looks.
        #[arg(long, default_value_t = Deposit::default().young)]
        young: f64,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Loads a deposited sample cyclically by a plate.
    Load {
        /// The deposit's output directory (its `final_scene.toml`).
        #[arg(long, value_name = "DIR")]
        from: PathBuf,
        #[arg(long, value_enum, default_value_t = Mode::Full)]
        mode: Mode,
        #[arg(long, default_value_t = 10)]
        cycles: u32,
        /// Start from replica R of the deposit: 0 as deposited, R ≥ 1 with every sphere
        /// moved by at most --perturb (the noise floor of a comparison; `replica.json`).
        #[arg(long, value_name = "R", default_value_t = 0, conflicts_with = "replicas")]
        replica: u64,
        /// Load R replicas (0 … R−1, each as --replica gives it) side by side in DIR/runs/replica-<r>/,
        /// then DIR/settlement_ensemble.csv: the plate's settlement per cycle, mean, sd, 95 % CI.
        #[arg(long, value_name = "R", default_value_t = 1)]
        replicas: u64,
        /// Seating cycles S of the ensemble: accrued settlement = settlement − settlement after S cycles.
        #[arg(long, value_name = "S", default_value_t = ballast::studies::replicas::DEFAULT_SEATING_CYCLES)]
        seating_cycles: u64,
        /// Replicas run at once, each on one core (default: the number of cores).
        #[arg(long)]
        jobs: Option<usize>,
        #[command(flatten)]
        tasks: super::saussine::TaskArgs,
        /// Largest displacement of a sphere at a replica's start (m), uniform in the ball.
        #[arg(long, value_name = "DIST", default_value_t = DEFAULT_PERTURBATION_M)]
        perturb: f64,
        /// Seed of the perturbations (replica R draws from stream R of it).
        #[arg(long, value_name = "SEED", default_value_t = DEFAULT_PERTURB_SEED)]
        perturb_seed: u64,
        #[command(flatten)]
        run: RunArgs,
        #[command(flatten)]
        accelerate: Box<super::saussine::AccelerateArgs>,
    },
}

#[derive(Debug, Subcommand)]
pub enum LudingCommand {
    /// Isotropic compression of the triaxial box at p₀ from all sides.
    Compress {
        /// Number of spheres (343, 1000, 1728, 3375 in the paper).
        #[arg(long, default_value_t = Compression::default().spheres)]
        spheres: usize,
        /// Friction coefficient μ (0.1, 0.15, 0.2, 0.25, 0.5 in the paper).
        #[arg(long, default_value_t = Compression::default().friction)]
        friction: f64,
        #[arg(long, default_value_t = Compression::default().seed)]
        seed: u64,
        /// Longest compression (s).
        #[arg(long, default_value_t = Compression::default().duration)]
        duration: f64,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Cyclic σ_xx on a compressed box.
    Cycle {
        /// The compression's output directory (its `final_scene.toml` and `spec.json`).
        #[arg(long, value_name = "DIR")]
        from: PathBuf,
        #[arg(long, default_value_t = 10)]
        cycles: u32,
        #[command(flatten)]
        run: RunArgs,
    },
    /// Several cycled runs on common axes (the paper's Figs. 3–5): ε_N per cycle
    /// and the first cycle's σ_D–ε_D loop of each, labelled by N and μ.
    Compare {
        /// Output directories of `luding cycle` runs.
        #[arg(long, value_name = "DIR", num_args = 1.., required = true)]
        runs: Vec<PathBuf>,
        /// Where the figures and `compare.csv` go.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
    },
}

/// The line after a stage's run: what it wrote.
fn print_written(o: &StageOutcome, what: &str) {
    println!("{what} written in {}", o.run.out.display());
}

pub(crate) fn karrech_main(cmd: KarrechCommand) -> Result<(), Failure> {
    match cmd {
        KarrechCommand::Deposit { spheres, seed, dt, duration, young, run: args } => {
            let spec = Deposit { spheres, seed, dt, duration, young };
            let o = karrech_test::deposit(&spec, &args.stage(), &args.display())?;
            print_written(&o, "figures fig3a–d");
        }
        KarrechCommand::Load {
            from,
            mode,
            cycles,
            replica,
            replicas,
            seating_cycles,
            jobs,
            tasks,
            perturb,
            perturb_seed,
            run: args,
            accelerate,
        } => {
            let loading = if mode == Mode::Full { Loading::FULL } else { Loading::PARTIAL };
            let perturbation = Perturbation { distance_m: perturb, seed: perturb_seed };
            if tasks.tasks {
                println!("{replicas}"); // one task per replica (a single run is one task)
                return Ok(());
            }
            if replicas != 1 {
                // A replica study (R = 0 refused by it, naming --replicas).
                let study = KarrechReplicas {
                    loading,
                    cycles,
                    replicas: Replicas { count: replicas, perturbation, seating_cycles },
                    accelerate: accelerate.accelerate()?,
                };
                let (stage, bars) = (args.stage(), Bars::group(args.quiet()));
                let run = |t| load_replicas(&from, &study, &stage, jobs, t, &bars);
                let shared = super::cluster::shared(tasks.plan(replicas, 0), run, |r| &r.failed)?;
                if let Some(r) = shared {
                    super::saussine::print_replicas(&r);
                }
                return Ok(());
            }
            if !tasks.single_run()? {
                return Ok(());
            }
            let start = Start { replica, perturbation };
            if let Some(acc) = accelerate.accelerate()? {
                let bar = super::cycle_bar(args.quiet());
                let mut show = |p: &ballast::settlement::AccelerationProgress| super::show_cycles(&bar, p);
                let stage = args.stage();
                let s = karrech_test::load_accelerated(&from, loading, cycles, &acc, &start, &stage, &mut show)?;
                bar.finish_and_clear();
                super::print_acceleration(&s, &stage.out);
                if acc.reference.is_some() {
                    super::saussine::print_errors(&stage.out, &s)?;
                }
            } else {
                let o = karrech_test::load(&from, loading, cycles, &start, &args.stage(), &args.display())?;
                print_written(&o, "figures residual_displacement, plate");
            }
        }
    }
    Ok(())
}

pub(crate) fn luding_main(cmd: LudingCommand) -> Result<(), Failure> {
    match cmd {
        LudingCommand::Compress { spheres, friction, seed, duration, run: args } => {
            let spec = Compression { spheres, friction, seed, duration };
            luding::compress(&spec, &args.stage(), &args.display())?;
        }
        LudingCommand::Cycle { from, cycles, run: args } => {
            let o = luding::cycle(&from, cycles, &args.stage(), &args.display())?;
            print_written(&o, "loops.csv, strain.csv and figures");
        }
        LudingCommand::Compare { runs, out } => {
            luding::compare(&runs, &out)?;
            println!("compare.csv, strain_accumulation and first_cycle_loops written in {}", out.display());
        }
    }
    Ok(())
}
