//! The 3D track section (issue "3D NSCD", item "A 3D track section"): Saussine et al. (2006) §3–4 in 3D on
//! the scenes of [`crate::scenarios::track3d`], each written into the output folder and run with the same loop as
//! `ballast run` (progress, checkpoints, `--resume`), as the 2D [`super::saussine`] does:
//!
//! - [`sample`]: generate and deposit the section to equilibrium (`deposit.toml` run in `OUT/deposit/`), save it
//!   as `sample.toml`, measure its grains, layer height, solid fraction, coordination and weight balance
//!   (`sample.json`);
//! - [`load`]: write the loaded scene (the sleeper on the layer under `F = A + B cos(2π f t − φ)`, cycles
//!   followed on it) from a deposited sample;
//! - [`settle`] (§4): load a sample and run its cycles: `cycles.csv` (settlement per cycle), `series.csv`,
//!   `summary.json`, VTK snapshots every few cycles;
//! - [`settle_accelerated`]: the same loaded scene through the settlement driver (Karrech et al. 2007, Fig. 10),
//!   as the 2D [`super::saussine::settle_accelerated`]; its jumps land through the 3D engine's relaxation
//!   (`crate::space::relax`);
//! - [`settle_replicas`] (`replicas.rs`): [`settle`] from several starts, replica 0 the sample as it is and the
//!   others with every mobile body moved by at most a small distance ([`crate::studies::replicas::perturb_scene3`]),
//!   side by side, and the ensemble's settlement per cycle with its 95 % interval (`settlement_ensemble.csv`), as
//!   the 2D [`super::saussine::settle_replicas`];
//! - [`convergence`] (`convergence.rs`): one loaded run per convergence policy × tolerance × replica and
//!   `convergence.csv` (sweeps, steps at the cap, wall time, overlaps, settlement; the ensemble of each setting and
//!   its difference from a reference setting with Welch's 95 % interval), as the 2D
//!   [`super::campaigns::convergence`].
//!
//! The runs go on [`crate::run::default_threads`] threads (the 3D contact solve splits in two halves on two; the
//! numbers do not depend on it) and end with the 3D figures (`crate::report`: energies, overlaps, settlement per
//! cycle, a vertical cut with the force chains).

mod convergence;
mod replicas;

pub use convergence::{convergence, ConvergenceSpec, DEFAULT_POLICIES, DEFAULT_REFERENCE};
pub use replicas::settle_replicas;

use super::{output_error, run_scene, write_scene_file, Accelerate, RunDisplay};
use crate::error::Result;
use crate::io;
use crate::io::layout;
use crate::run::{default_threads, Prior, RunOptions, RunOutcome};
use crate::scenarios::track3d::{loaded_scene, measure_sample, sample_scene, LoadingSpec, SampleReport, SampleSpec};
use crate::scene::{Scene3, SceneFile};
use std::path::{Path, PathBuf};

/// Writes `scene` to `path` with a header line saying `what` it is.
///
/// # Errors
/// [`crate::Error::Io`] naming the file.
pub fn write_scene(path: &Path, scene: &Scene3, what: &str) -> Result<()> {
    write_scene_file(path, scene, "3D track section, Saussine et al. 2006 in 3D", what)
}

/// A deposited section: its scene and what `sample.json` records.
#[derive(Debug, Clone)]
pub struct Sample {
    /// `sample.toml`, the deposited section as a scene.
    pub path: PathBuf,
    /// Its grains, layer, solid fraction, coordination and balance (`sample.json`).
    pub report: SampleReport,
}

/// Deposits the section of `spec` into `out`: `deposit.toml` run in `out/deposit/` until equilibrium, then
/// `sample.toml` (the deposit's end state) and `sample.json`. With `resume`, a finished deposit is not run again
/// and a checkpointed one is resumed. The run is labelled `sample <seed>`.
///
/// # Errors
/// [`crate::Error::Scene`] naming the field of an invalid spec (or an invalid checkpoint); a deposit that fails
/// (divergence) or an output that cannot be written or read back is another error.
pub fn sample(spec: &SampleSpec, out: &Path, resume: bool, display: &dyn RunDisplay) -> Result<Sample> {
    let scene = sample_scene(spec)?;
    io::create_output_dir(out)?;
    let deposit = out.join("deposit.toml");
    write_scene(&deposit, &scene, &format!("the loose section to deposit, seed {}", spec.seed))?;
    let dir = out.join("deposit");
    let prior = Prior::of(&dir, layout::FINAL_SCENE, resume);
    if prior != Prior::Finished {
        let opts = RunOptions {
            checkpoint_every_s: 300.0,
            resume: prior == Prior::Checkpointed,
            threads: default_threads(),
            ..RunOptions::default()
        };
        run_scene(&deposit, &dir, &opts, display, &format!("sample {}", spec.seed))?;
    }
    let settled = Scene3::load(dir.join(layout::FINAL_SCENE)).map_err(output_error)?;
    let path = out.join("sample.toml");
    write_scene(&path, &settled, &format!("deposited section, seed {}", spec.seed))?;
    let report = measure_sample(&settled).map_err(output_error)?;
    io::write_json(&out.join("sample.json"), &report)?;
    Ok(Sample { path, report })
}

/// The loaded scene of the sample at `sample` under `loading`.
///
/// # Errors
/// [`crate::Error::Scene`] for an unreadable sample (named `sample: …` when it is not one of this generator) or
/// an invalid loading (the field named).
pub fn loaded(sample: &Path, loading: &LoadingSpec) -> Result<Scene3> {
    loaded_scene(&Scene3::load(sample)?, loading)
}

/// Writes the loaded scene of the sample at `sample` (a `sample.toml` of [`sample`]) to `out`, ready for
/// `ballast run`.
///
/// # Errors
/// As [`loaded`]; [`crate::Error::Io`] if `out` cannot be written.
pub fn load(sample: &Path, loading: &LoadingSpec, out: &Path) -> Result<()> {
    let scene = loaded(sample, loading)?;
    write_scene(out, &scene, &format!("loaded from {}", sample.display()))
}

/// How [`settle`] and [`settle_accelerated`] run.
#[derive(Debug, Clone, PartialEq)]
pub struct SettleOptions {
    /// A VTK snapshot (bodies and contacts) every this many cycles; 0: none.
    pub snapshot_every: u64,
    /// Wall-clock seconds between checkpoints.
    pub checkpoint_every_s: f64,
    /// Continue a killed run from its checkpoint (the `loaded.toml` there is kept).
    pub resume: bool,
}

impl Default for SettleOptions {
    /// A snapshot every 10 cycles, a checkpoint every 5 minutes, a fresh run.
    fn default() -> Self {
        Self { snapshot_every: 10, checkpoint_every_s: 300.0, resume: false }
    }
}

/// Writes the loaded scene as `out/loaded.toml`, unless `resume` keeps the one there; its path.
fn write_loaded(sample: &Path, scene: &Scene3, out: &Path, resume: bool, what: &str) -> Result<PathBuf> {
    io::create_output_dir(out)?;
    let path = out.join("loaded.toml");
    if !(resume && path.exists()) {
        write_scene(&path, scene, &format!("loaded from {}{what}", sample.display()))?;
    }
    Ok(path)
}

/// §4 in 3D: loads the sample at `sample` and runs its cycles in `out` (the loaded scene written there as
/// `loaded.toml`): `cycles.csv` (the sleeper's settlement per cycle), `series.csv`, `summary.json`,
/// `final.json`, VTK snapshots every `opts.snapshot_every` cycles, checkpoints, figures. The run is labelled `settle`.
///
/// # Errors
/// [`crate::Error::Scene`] for an unreadable sample, an invalid loading or checkpoint; else as
/// [`crate::run::Runner::run`].
pub fn settle(
    sample: &Path,
    loading: &LoadingSpec,
    out: &Path,
    opts: &SettleOptions,
    display: &dyn RunDisplay,
) -> Result<RunOutcome> {
    let scene = loaded(sample, loading)?;
    let path = write_loaded(sample, &scene, out, opts.resume, "")?;
    let per_cycle = super::saussine::steps_per_cycle(loading.frequency, loading.dt);
    let run = RunOptions {
        checkpoint_every_s: opts.checkpoint_every_s,
        resume: opts.resume,
        vtk_every: opts.snapshot_every.saturating_mul(per_cycle),
        figures: true,
        threads: default_threads(),
        ..RunOptions::default()
    };
    run_scene(&path, out, &run, display, "settle")
}

/// §4 accelerated: [`settle`]'s loaded scene with the `[settlement]` table of `accelerate` (the sleeper as the
/// settlement body; the relaxation's tolerance by default 1 % of the smallest grain's inradius, as in 2D)
/// written as `OUT/loaded.toml` and run through [`crate::open::settle_file`]: `settlement.csv`, `jumps.csv`,
/// `summary.json`, the settlement figures.
///
/// # Errors
/// [`crate::Error::Scene`] for an unreadable sample, an invalid loading or settings; else as
/// [`crate::settlement::Accelerated::run`].
pub fn settle_accelerated(
    sample: &Path,
    loading: &LoadingSpec,
    accelerate: &Accelerate,
    out: &Path,
    opts: &SettleOptions,
    progress: &mut dyn FnMut(&crate::settlement::AccelerationProgress),
) -> Result<crate::settlement::AccelerationSummary> {
    let mut scene = loaded(sample, loading)?;
    let sys = scene.build()?;
    let smallest = (0..sys.bodies.len())
        .filter(|&i| !sys.bodies.info[i].fixed)
        .map(|i| crate::nscd::d3::system::inradius(&sys.bodies.info[i].solid))
        .fold(f64::INFINITY, f64::min);
    let sleeper = Some(crate::scenarios::track3d::SLEEPER.to_string());
    scene.settlement = Some(accelerate.section(sleeper, Some(0.01 * smallest)));
    scene.validate()?;
    let path = write_loaded(sample, &scene, out, opts.resume, ", accelerated")?;
    let run = RunOptions {
        checkpoint_every_s: opts.checkpoint_every_s,
        resume: opts.resume,
        figures: true,
        threads: default_threads(),
        ..RunOptions::default()
    };
    accelerate.run_scene(&path, out, &run, progress)
}
