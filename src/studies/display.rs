//! How the runs of a study show their progress: the study asks a
//! [`RunDisplay`] for one progress callback per run (runs may go side by side
//! on a pool, hence `Sync`), and tells it when a run has ended. [`Quiet`] shows
//! nothing; the `ballast` binary draws progress bars (one per run, grouped when
//! runs go side by side) and prints each run's last line.

use super::saussine::Sample;
use crate::error::Result;
use crate::open::Loaded;
use crate::run::{Progress, RunOptions, RunOutcome};
use std::path::Path;

/// What a study shows while it goes. Every method may be called from several
/// threads at once (one per run side by side).
pub trait RunDisplay: Sync {
    /// The progress callback of the run labelled `label` (e.g. `quad_1e-5`,
    /// `sample 3`), called after every step of that run. It is dropped when the
    /// run returns, before [`RunDisplay::ended`].
    fn run(&self, label: &str) -> Box<dyn FnMut(&Progress) + '_>;

    /// The run labelled `label` has ended, or stopped with a checkpoint (not
    /// called for a run that failed: its error is returned or reported).
    fn ended(&self, label: &str, outcome: &RunOutcome) {
        let _ = (label, outcome);
    }

    /// A Saussine sample has been deposited within a study (the samples of
    /// [`super::campaigns::ensemble`]), once its `sample.json` is written.
    fn sample(&self, sample: &Sample) {
        let _ = sample;
    }
}

/// Shows nothing.
#[derive(Debug, Clone, Copy, Default)]
pub struct Quiet;

impl RunDisplay for Quiet {
    fn run(&self, _label: &str) -> Box<dyn FnMut(&Progress) + '_> {
        Box::new(|_| {})
    }
}

/// Runs the scene file `scene` into `out` ([`crate::open::run_file`]) with the progress
/// callback of `display` for `label`, then tells `display` that it has ended.
///
/// # Errors
/// As [`crate::open::run_file`].
pub fn run_scene(
    scene: &Path,
    out: &Path,
    opts: &RunOptions,
    display: &dyn RunDisplay,
    label: &str,
) -> Result<RunOutcome> {
    run_loaded(crate::open::open(scene, opts)?, out, opts, display, label)
}

/// Runs a scene already opened ([`crate::open::open`] with the same `opts`) into `out` as [`run_scene`] does.
///
/// # Errors
/// As [`Loaded::run`].
pub fn run_loaded(
    loaded: Loaded,
    out: &Path,
    opts: &RunOptions,
    display: &dyn RunDisplay,
    label: &str,
) -> Result<RunOutcome> {
    let result = {
        let mut progress = display.run(label);
        loaded.run(out, opts, &mut *progress)
    };
    let outcome = result?;
    display.ended(label, &outcome);
    Ok(outcome)
}
