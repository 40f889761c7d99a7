//! The experiments of the papers as library functions: each writes its scenes
//! into an output folder, runs them through the run loop ([`crate::run`]) like
//! `ballast run` (outputs, checkpoints, `--resume`), then reads the runs'
//! outputs back into its own tables and figures. The `ballast` subcommands
//! `saussine …`, `karrech …` and `luding …` are these functions behind
//! command-line arguments.
//!
//! - [`saussine`]: the Saussine et al. (2006) sample deposited in stages
//!   ([`saussine::sample`]), loaded ([`saussine::load`]) and settled over cycles
//!   (§4, [`saussine::settle`]); [`accelerated`]: replicas of its accelerated run;
//! - [`campaigns`]: the studies of Saussine et al. (2006) §3.2 (convergence
//!   policies), §3.3 (time steps) and §4.2 (ensembles of samples), many runs side
//!   by side on a thread pool;
//! - [`karrech`]: the Karrech et al. (2007) deposit and cyclic plate load, with
//!   the figures of its Fig. 3 and the residual displacement per cycle;
//! - [`luding`]: the cyclic triaxial box of David, García-Rojo, Herrmann &
//!   Luding: isotropic compression, cycles (`loops.csv`, `strain.csv`), and the
//!   comparison of several cycled runs (`compare.csv`);
//! - [`md_stage`]: what the two-stage MD tests share (`spec.json`, where and how
//!   a stage runs);
//! - [`replicas`]: replicas of a run from perturbed starts, and the statistics of
//!   their ensemble (mean, standard deviation, 95 % confidence intervals of the
//!   mean and of a difference of means; seating and accrued settlement), which
//!   `saussine settle`, `convergence` and `steps` report with `--replicas`.
//!
//! Progress goes through a [`RunDisplay`]: one callback per run, and a word
//! when each run ends ([`Quiet`] shows nothing). Invalid inputs are
//! [`Error::Scene`] with a one-line message naming the spec's field (`cycles`,
//! `jobs`, `perturbation.distance_m`, …; the command line maps them to its
//! flags); a failed run or an unwritable output is another error.
//!
//! A 60-grain sample, deposited quietly:
//! ```no_run
//! use ballast::scenarios::saussine::SampleSpec;
//! use ballast::studies::{saussine, Quiet};
//! let spec = SampleSpec::saussine(1).scaled(60);
//! let sample = saussine::sample(&spec, "out/sample".as_ref(), false, 1, &Quiet)?;
//! println!("{}: solid fraction {:.3}", sample.path.display(), sample.report.solid_fraction);
//! # Ok::<(), ballast::Error>(())
//! ```

pub mod accelerated;
pub mod campaigns;
pub mod compare;
mod display;
pub mod karrech;
pub mod karrech_replicas;
pub mod luding;
pub mod md_stage;
pub mod replica_tasks;
pub mod replicas;
pub mod saussine;
pub mod tasks;
pub mod track3d;

pub use display::{run_loaded, run_scene, Quiet, RunDisplay};

use crate::error::{Error, Result};
use crate::io::figures::Axes;
use std::path::{Path, PathBuf};

/// A summary table a study wrote, read back as text (as the CSV has it).
#[derive(Debug, Clone, PartialEq)]
pub struct SummaryTable {
    /// The CSV file.
    pub path: PathBuf,
    /// Its column names.
    pub header: Vec<String>,
    /// Its rows, each field as written.
    pub rows: Vec<Vec<String>>,
}

impl SummaryTable {
    /// Reads the CSV file at `path` (rows that cannot be read are left out).
    ///
    /// # Errors
    /// [`Error::Io`] if the file or its header cannot be read.
    pub fn read(path: &Path) -> Result<Self> {
        let io = |e: csv::Error| Error::Io(std::io::Error::other(e));
        let mut reader = csv::Reader::from_path(path).map_err(io)?;
        let header = reader.headers().map_err(io)?.iter().map(String::from).collect();
        let rows = reader.records().flatten().map(|r| r.iter().map(String::from).collect()).collect();
        Ok(Self { path: path.to_path_buf(), header, rows })
    }
}

/// An error on a file the study wrote itself, or on a run's outputs: a failure
/// of the study, not of its input ([`Error::Scene`] becomes [`Error::Io`] with
/// the same message; the others are kept).
pub(crate) fn output_error(e: Error) -> Error {
    match e {
        Error::Scene(msg) => Error::Io(std::io::Error::other(msg)),
        e => e,
    }
}

/// Writes `text` to `path`; the error names the file.
pub(crate) fn write_file(path: &Path, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| crate::io::io_error(path, "write", e))
}

/// Writes `scene` to `path` as TOML under a header line naming the build, the `study` that wrote it and `what`
/// it is (control characters of `what` shown as `?`); the error names the file.
pub(crate) fn write_scene_file(
    path: &Path,
    scene: &impl crate::scene::SceneFile,
    study: &str,
    what: &str,
) -> Result<()> {
    let text = format!(
        "# Written by ballast {} ({study}): {}.\n\n{}",
        env!("CARGO_PKG_VERSION"),
        what.replace(char::is_control, "?"),
        scene.to_toml_string()?
    );
    write_file(path, &text)
}

/// The axes of a line chart.
pub(crate) fn axes(title: &str, x: &str, y: &str, log_x: bool, log_y: bool) -> Axes {
    Axes { title: title.into(), x_label: x.into(), y_label: y.into(), log_x, log_y }
}

/// The settlement-acceleration procedure of `[settlement]` (Karrech et al.
/// 2007, Fig. 10) on a ready-made cyclic test (`saussine settle`, `karrech
/// load`): `k_i` cycles first, then windows of `k` computed and `h` extrapolated
/// cycles.
#[derive(Debug, Clone, PartialEq)]
pub struct Accelerate {
    /// `k_i`, `k`, `h`.
    pub cycles: [u64; 3],
    /// `"shenton"` (default), `"shenton_decelerating"`, `"linear"` or `"shenton_origin"`.
    pub law: String,
    /// Factor on `h` after each jump (≥ 1).
    pub growth: f64,
    /// Largest overlap left by the relaxation (m); `None`: the command's default
    /// (NSCD: 1 % of the smallest grain's inradius, the overlap the default NLGS
    /// setting keeps below; MD: the largest overlap of the computed
    /// configuration each jump starts from).
    pub relax_tolerance: Option<f64>,
    /// The largest move a jump may give a body, as a fraction of its size;
    /// `None`: [`crate::settlement::Acceleration::EXTRAPOLATION_LIMIT`].
    pub extrapolation_limit: Option<f64>,
    /// Smooth each jump's moves over the neighbours within a few of this
    /// length (m); `None`: every body on its own fit.
    pub smoothing_length: Option<f64>,
    /// Computed cycles after each jump before the window's data start; `None`: 1.
    pub settle_cycles: Option<u64>,
    /// Keep re-seating while the settlement runs ahead of this factor times the
    /// landing's predicted rate; `None`: a fixed count.
    pub settle_rate: Option<f64>,
    /// `rollback_rate` of the accelerated runs ([`crate::settlement::Acceleration::rollback_rate`]).
    pub rollback_rate: Option<f64>,
    /// `relax_stage` of the accelerated runs ([`crate::settlement::Acceleration::relax_stage`]);
    /// `None`: [`crate::settlement::sweep::RELAX_STAGE`].
    pub relax_stage: Option<f64>,
    /// `hold_anchored` of the accelerated runs ([`crate::settlement::Acceleration::hold_anchored`]).
    pub hold_anchored: bool,
    /// A full run of the same loaded sample (its folder) to measure the errors
    /// against: `errors.csv` and its curve on the settlement figure.
    pub reference: Option<PathBuf>,
}

impl Accelerate {
    /// The `[settlement]` table of these settings, the settlement measured on
    /// `body` (the sleeper, the plate), the relaxation tolerance defaulting to
    /// `default_tolerance` (m; `None`: `"computed"`).
    pub fn section(
        &self,
        body: Option<String>,
        default_tolerance: Option<f64>,
    ) -> crate::scene::common::SettlementSection {
        let [initial_cycles, computed_cycles, extrapolated_cycles] = self.cycles;
        crate::scene::common::SettlementSection {
            initial_cycles,
            computed_cycles,
            extrapolated_cycles,
            growth: Some(self.growth),
            law: Some(self.law.clone()),
            relax_tolerance: self
                .relax_tolerance
                .or(default_tolerance)
                .map(crate::scene::common::RelaxTolerance::Length),
            settlement_body: body,
            extrapolation_limit: self.extrapolation_limit,
            smoothing_length: self.smoothing_length,
            settle_cycles: self.settle_cycles,
            settle_rate: self.settle_rate,
            rollback_rate: self.rollback_rate,
            relax_stage: self.relax_stage,
            hold_anchored: self.hold_anchored.then_some(true),
            ..Default::default()
        }
    }

    /// Runs the scene at `path` (with its `[settlement]` table) into `out`
    /// through [`crate::open::settle_file`], the reference, if any, checked to
    /// have a settlement first and compared after
    /// ([`crate::report::settlement::draw`]: `errors.csv`).
    ///
    /// # Errors
    /// A reference without a settlement, before the run; a scene without
    /// `[settlement]`; else as [`crate::open::settle_file`] and the figures.
    pub fn run_scene(
        &self,
        path: &Path,
        out: &Path,
        opts: &crate::run::RunOptions,
        progress: &mut dyn FnMut(&crate::settlement::AccelerationProgress),
    ) -> crate::error::Result<crate::settlement::AccelerationSummary> {
        if let Some(r) = &self.reference {
            crate::report::settlement::reference_settlement(r)?;
        }
        let summary = crate::open::settle_file(path, out, opts, progress)?
            .ok_or_else(|| crate::error::Error::Scene(format!("{}: no [settlement] table", path.display())))?;
        if let Some(r) = &self.reference {
            crate::report::settlement::draw(out, Some(r))?;
        }
        Ok(summary)
    }
}
