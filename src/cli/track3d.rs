//! `ballast track3d …`: the 3D track section (issue "3D NSCD"), Saussine et al. (2006) §3–4 with polyhedral
//! grains on the 3D NSCD engine, which [`ballast::studies::track3d`] carries out from scene files written into
//! the output folder and run with the same loop as `ballast run` (progress, checkpoints, `--resume`):
//!
//! - `sample`: generate the grains, deposit them on the sublayer to equilibrium, save `sample.toml`, measure
//!   the layer (`sample.json`);
//! - `load`: write the loaded scene (the sleeper on the layer under `F = A + B cos(2π f t − φ)`);
//! - `settle`: load a sample and run N cycles (`cycles.csv`), or with `--accelerate` through the settlement
//!   driver, or with `--replicas R` from R perturbed starts side by side (`settlement_ensemble.csv`);
//! - `convergence`: one loaded run per convergence policy × tolerance × replica (`convergence.csv`).
//!
//! The library's messages name its spec fields; [`as_flag`] turns those of this command into its flags.

use super::saussine::{policies, policy, print_replicas, AccelerateArgs, ReplicaArgs, StudyArgs};
use super::{input, print_study, Bars, Failure};
use ballast::scenarios::track3d::{LoadingSpec, SampleSpec};
use ballast::studies::track3d::{self, ConvergenceSpec, Sample, SettleOptions};
use ballast::Error;
use clap::Subcommand;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub enum Track3dCommand {
    /// Generates the ballast grains (hulls of 12–30 points, 25–50 mm), deposits them under gravity on the
    /// sublayer of sprung pads in a 0.6 × 0.4 m box until equilibrium, saves DIR/sample.toml and measures it
    /// (DIR/sample.json: grains, layer height, solid fraction, coordination, weight on the sublayer).
    Sample {
        /// Seed of the grains and their orientations.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Number of grains; the box's area is scaled with it (the layer keeps its thickness).
        #[arg(long, default_value_t = ballast::scenarios::track3d::TRACK_GRAINS)]
        grains: usize,
        /// Time step of the deposit (s).
        #[arg(long, default_value_t = SampleSpec::default().dt)]
        dt: f64,
        /// Longest deposit (s); it ends earlier at equilibrium.
        #[arg(long, default_value_t = SampleSpec::default().max_duration)]
        max_duration: f64,
        /// θ of the deposit's time scheme, in [0.5, 1]: 1 is dissipative and reached rest on every seed tried,
        /// with smaller overlaps (docs/track3d.md, "The deposit's θ"); the loaded runs keep θ = 1/2.
        #[arg(long, default_value_t = SampleSpec::default().theta)]
        theta: f64,
        /// Tolerance of the deposit's solver (`quad` policy).
        #[arg(long, default_value_t = SampleSpec::default().tolerance)]
        tolerance: f64,
        /// Most solver sweeps per step of the deposit.
        #[arg(long, default_value_t = SampleSpec::default().max_iterations)]
        max_iterations: usize,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: PathBuf,
        /// Continue an interrupted deposit.
        #[arg(long)]
        resume: bool,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Writes the loaded scene: the sample with the sleeper on top under F = A + B cos(2π f t − φ), ready for
    /// `ballast run`.
    Load {
        /// A deposited sample (`sample.toml` of `ballast track3d sample`).
        #[arg(long, value_name = "FILE")]
        sample: PathBuf,
        /// Output scene file.
        #[arg(long, value_name = "FILE")]
        out: PathBuf,
        #[command(flatten)]
        loading: LoadingArgs,
    },
    /// Loads a deposited sample and runs the cycles: the sleeper's settlement per cycle (cycles.csv),
    /// series.csv, summary.json, VTK snapshots, figures; with --accelerate, through the settlement driver.
    /// With --replicas R > 1: R runs from perturbed starts side by side in DIR/runs/replica-<r>/ (their
    /// starts in DIR/scenes/), and DIR/settlement_ensemble.csv (mean, sd, 95 % CI per cycle).
    Settle(Box<SettleArgs>),
    /// The cycles of a sample (or of a loaded scene, from its seated state) with each convergence policy and
    /// tolerance, from R starts each: convergence.csv
    /// (sweeps per step, steps at the cap, wall time per cycle, overlaps, settlement; the ensemble of each
    /// setting and its difference from the reference's with Welch's 95 % interval) and figures.
    /// (--criterion and --tolerance are replaced by those of each run.)
    Convergence(Box<ConvergenceArgs>),
}

/// The arguments of `track3d convergence`.
#[derive(Debug, clap::Args)]
pub struct ConvergenceArgs {
    /// A deposited sample (`sample.toml` of `ballast track3d sample`), or a loaded scene to run on from its
    /// state (a run's `final_scene.toml`, one with the sleeper): its loading and solver kept, --cycles of its
    /// cycles under each policy; the other loading flags are then refused unless at their defaults (the scene's
    /// own values apply).
    #[arg(long, value_name = "FILE")]
    sample: PathBuf,
    /// Runs as POLICY:TOLERANCE, comma separated.
    #[arg(long, value_delimiter = ',', default_value = "quad:1e-3,energy:1.66e-5,quad:1e-4")]
    policies: Vec<String>,
    /// The setting the others' mean settlements are compared with, POLICY:TOLERANCE (run after them when it is
    /// not one of them).
    #[arg(long, value_name = "POLICY:TOL", default_value = "quad:1e-5")]
    reference: String,
    #[command(flatten)]
    replicas: ReplicaArgs,
    #[command(flatten)]
    loading: LoadingArgs,
    #[command(flatten)]
    study: StudyArgs,
}

/// The arguments of `track3d settle`.
#[derive(Debug, clap::Args)]
pub struct SettleArgs {
    /// A deposited sample (`sample.toml` of `ballast track3d sample`).
    #[arg(long, value_name = "FILE")]
    sample: PathBuf,
    /// Output directory (the loaded scene is written there as `loaded.toml`).
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    loading: LoadingArgs,
    /// VTK snapshot (bodies and contacts) every this many cycles; 0: none.
    #[arg(long, value_name = "CYCLES", default_value_t = 10)]
    snapshot_every: u64,
    /// Wall-clock seconds between checkpoints.
    #[arg(long, value_name = "SECONDS", default_value_t = 300.0)]
    checkpoint_every: f64,
    /// Continue a killed run from its checkpoint (with --replicas: skip the finished replicas, resume the
    /// checkpointed ones).
    #[arg(long)]
    resume: bool,
    #[command(flatten)]
    replicas: ReplicaArgs,
    /// Replicas run at once (default: the number of cores; one alone runs on every core).
    #[arg(long)]
    jobs: Option<usize>,
    #[command(flatten)]
    accelerate: AccelerateArgs,
    /// No progress bar.
    #[arg(long)]
    quiet: bool,
}

/// Settings of the loaded stage.
#[derive(Debug, Clone, clap::Args)]
pub struct LoadingArgs {
    /// Number of loading cycles.
    #[arg(long, default_value_t = LoadingSpec::default().cycles)]
    pub cycles: u64,
    /// Time step (s).
    #[arg(long, default_value_t = LoadingSpec::default().dt)]
    pub dt: f64,
    /// θ of the time scheme, in [0.5, 1] (the paper's 0.5, whatever the sample was deposited with).
    #[arg(long, default_value_t = LoadingSpec::default().theta)]
    pub theta: f64,
    /// Convergence policy: strict, quad, quad_max, energy, velocity.
    #[arg(long, default_value_t = LoadingSpec::default().criterion)]
    pub criterion: String,
    /// Tolerance of the policy.
    #[arg(long, default_value_t = LoadingSpec::default().tolerance)]
    pub tolerance: f64,
    #[arg(long, default_value_t = LoadingSpec::default().min_iterations)]
    pub min_iterations: usize,
    #[arg(long, default_value_t = LoadingSpec::default().max_iterations)]
    pub max_iterations: usize,
    /// Gaps of the grains' face–face contacts: exact (each point its own) or common_plane (LMGC90's: the
    /// smallest, the faces counted flush).
    #[arg(long, default_value_t = LoadingSpec::default().face_gaps)]
    pub face_gaps: String,
    /// What a closed contact does with an overlap: kept (Moreau–Jean's velocity-level law) or held (an
    /// overlap may not grow past the shallowest the point has had).
    #[arg(long, default_value_t = LoadingSpec::default().overlaps)]
    pub overlaps: String,
    /// Depth of the Anderson mixing of the sweeps, 0 to 8 (0: plain Gauss–Seidel sweeps).
    #[arg(long, default_value_t = LoadingSpec::default().anderson)]
    pub anderson: usize,
    /// Width of the sleeper along the track (m); default: half the box's length (0.3 m on the full section).
    #[arg(long)]
    pub sleeper_width: Option<f64>,
    /// Length of the sleeper across the track (m); default: the box's width less 5 mm at each end.
    #[arg(long)]
    pub sleeper_length: Option<f64>,
    /// Mean A of the load as a pressure on the sleeper (Pa; negative pushes down).
    #[arg(long, allow_negative_numbers = true, default_value_t = LoadingSpec::default().mean_pressure)]
    pub mean_pressure: f64,
    /// Amplitude B of the load's cosine as a pressure (Pa).
    #[arg(long, allow_negative_numbers = true, default_value_t = LoadingSpec::default().amplitude_pressure)]
    pub amplitude_pressure: f64,
    /// Loading frequency f (Hz).
    #[arg(long, default_value_t = LoadingSpec::default().frequency)]
    pub frequency: f64,
    /// Factor on the sublayer stiffness (each spring keeps its static force).
    #[arg(long, default_value_t = LoadingSpec::default().stiffness_factor)]
    pub stiffness_factor: f64,
}

impl LoadingArgs {
    /// The library's loading (checked by it when a scene is made from it).
    pub fn loading(&self) -> LoadingSpec {
        LoadingSpec {
            cycles: self.cycles,
            dt: self.dt,
            theta: self.theta,
            criterion: self.criterion.clone(),
            tolerance: self.tolerance,
            min_iterations: self.min_iterations,
            max_iterations: self.max_iterations,
            face_gaps: self.face_gaps.clone(),
            overlaps: self.overlaps.clone(),
            anderson: self.anderson,
            sleeper_width: self.sleeper_width,
            sleeper_length: self.sleeper_length,
            mean_pressure: self.mean_pressure,
            amplitude_pressure: self.amplitude_pressure,
            frequency: self.frequency,
            stiffness_factor: self.stiffness_factor,
            ..LoadingSpec::default()
        }
    }
}

/// The spec fields of this command's library calls and their flags (the shared ones, `dt`, `cycles`, …, are
/// mapped by `flags.rs` too).
const FLAGS: [(&str, &str); 25] = [
    ("grains", "--grains"),
    ("dt", "--dt"),
    ("max_duration", "--max-duration"),
    ("theta", "--theta"),
    ("cycles", "--cycles"),
    ("criterion", "--criterion"),
    ("tolerance", "--tolerance"),
    ("min_iterations", "--min-iterations"),
    ("max_iterations", "--max-iterations"),
    ("face_gaps", "--face-gaps"),
    ("overlaps", "--overlaps"),
    ("anderson", "--anderson"),
    ("sleeper_width", "--sleeper-width"),
    ("sleeper_length", "--sleeper-length"),
    ("mean_pressure", "--mean-pressure"),
    ("amplitude_pressure", "--amplitude-pressure"),
    ("frequency", "--frequency"),
    ("stiffness_factor", "--stiffness-factor"),
    ("sample", "--sample"),
    ("replicas", "--replicas"),
    ("perturbation.distance_m", "--perturb"),
    ("jobs", "--jobs"),
    ("policies", "--policies"),
    ("reference", "--reference"),
    ("checkpoint_every_s", "--checkpoint-every"),
];

/// An input error of the library with its leading spec field replaced by this command's flag; other errors as
/// they are.
fn as_flag(e: Error) -> Failure {
    let Error::Scene(msg) = &e else { return Failure::from(e) };
    for (field, flag) in FLAGS {
        if let Some(rest) = msg.strip_prefix(field).filter(|r| r.starts_with(':')) {
            return input(format!("{flag}{rest}"));
        }
    }
    Failure::from(e)
}

/// The line of a deposited section.
fn print_sample(s: &Sample) {
    let r = &s.report;
    println!(
        "sample {}: {} grains on {} pads in a {:.3} × {:.3} m box, layer {:.1} mm high; weight {:.2} N, sublayer \
         {:.2} N, walls {:.2e} N (balance error {:.2e}); kinetic energy {:.2e} J; max overlap {:.2e} m; solid \
         fraction {:.3}, coordination {:.2} ({:.0} % rattlers)",
        s.path.display(),
        r.grains,
        r.pads,
        r.box_m[0],
        r.box_m[1],
        1e3 * r.layer_height_m,
        r.weight_n,
        r.sublayer_reaction_n,
        r.wall_reaction_n,
        r.balance_error,
        r.kinetic_energy_j,
        r.max_overlap_m,
        r.solid_fraction,
        r.coordination,
        100.0 * r.rattler_fraction
    );
}

pub fn main(cmd: Track3dCommand) -> Result<(), Failure> {
    match cmd {
        Track3dCommand::Sample {
            seed,
            grains,
            dt,
            max_duration,
            theta,
            tolerance,
            max_iterations,
            out,
            resume,
            quiet,
        } => {
            if grains == 0 {
                return Err(input("--grains: must be at least 1, got 0".into()));
            }
            let spec = SampleSpec {
                dt,
                max_duration,
                theta,
                tolerance,
                max_iterations,
                ..SampleSpec::track(seed).scaled(grains)
            };
            let sample = track3d::sample(&spec, &out, resume, &Bars::single(quiet)).map_err(as_flag)?;
            print_sample(&sample);
        }
        Track3dCommand::Load { sample, out, loading } => {
            track3d::load(&sample, &loading.loading(), &out).map_err(as_flag)?;
            println!("wrote {}", out.display());
        }
        Track3dCommand::Settle(args) => {
            let SettleArgs {
                sample,
                out,
                loading,
                snapshot_every,
                checkpoint_every,
                resume,
                replicas,
                jobs,
                accelerate,
                quiet,
            } = *args;
            let opts = SettleOptions { snapshot_every, checkpoint_every_s: checkpoint_every, resume };
            let loading = loading.loading();
            let replicas = replicas.replicas();
            replicas.check().map_err(as_flag)?;
            if replicas.count > 1 {
                if accelerate.accelerate()?.is_some() {
                    return Err(input("--replicas: not with --accelerate on the 3D section".into()));
                }
                let r = track3d::settle_replicas(&sample, &loading, &out, &opts, &replicas, jobs, &Bars::group(quiet))
                    .map_err(as_flag)?;
                print_replicas(&r);
            } else if let Some(acc) = accelerate.accelerate()? {
                let bar = super::cycle_bar(quiet);
                let mut show = |p: &ballast::settlement::AccelerationProgress| super::show_cycles(&bar, p);
                let s = track3d::settle_accelerated(&sample, &loading, &acc, &out, &opts, &mut show).map_err(as_flag);
                bar.finish_and_clear();
                super::print_acceleration(&s?, &out);
            } else {
                track3d::settle(&sample, &loading, &out, &opts, &Bars::single(quiet)).map_err(as_flag)?;
            }
        }
        Track3dCommand::Convergence(args) => {
            let ConvergenceArgs { sample, policies: given, reference, replicas, loading, study } = *args;
            study.options().check().map_err(as_flag)?;
            let spec = ConvergenceSpec {
                sample,
                policies: policies(&given)?,
                reference: Some(policy("--reference", &reference)?),
                replicas: replicas.replicas(),
                loading: loading.loading(),
            };
            spec.check().map_err(as_flag)?;
            let bars = Bars::group(study.quiet);
            study.run((spec.task_count(), 0), |o| track3d::convergence(&spec, o, &bars), |r| &r.failed, print_study)?;
        }
    }
    Ok(())
}
