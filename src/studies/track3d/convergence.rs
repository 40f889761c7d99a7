//! The 3D track section's convergence study (`ballast track3d convergence`): the 2D §3.2 study
//! ([`crate::studies::campaigns::convergence`]) on the 3D scenes, one loaded run of a sample per policy ×
//! tolerance × replica, through the studies' shared runner and summary (`convergence.csv` with the 2D
//! columns, the figures).

use super::replicas::write_start;
use crate::error::{Error, Result};
use crate::nscd::d3::rows::read_cycles;
use crate::scenarios::track3d::{is_loaded, loaded_scene, reloaded_scene, LoadingSpec};
use crate::scene::{Scene3, SceneFile};
use crate::studies::campaigns::{
    convergence_summary, label_number, not_summarized, reference_of, replica_labels, run_written, StudyOptions,
    StudyReport,
};
use crate::studies::replicas::Start;
use crate::studies::RunDisplay;

/// The settings of the 3D convergence study by default (`POLICY:TOLERANCE`): the track section's loaded runs
/// use `quad` 1e-4 ([`LoadingSpec::track`]), the 2D engine's default stopping rule is `energy` 1.66e-5, and
/// `quad` 1e-3 is the deposit's.
pub const DEFAULT_POLICIES: [(&str, f64); 3] = [("quad", 1e-3), ("energy", 1.66e-5), ("quad", 1e-4)];

/// The reference setting by default: `quad` 1e-5, a decade tighter than the loaded runs' tolerance.
pub const DEFAULT_REFERENCE: (&str, f64) = ("quad", 1e-5);

/// The 3D convergence study: the loaded sample under each convergence policy and tolerance, from
/// [`crate::studies::replicas::Replicas::count`] starts each (the 2D study's spec with the 3D loading; at least one policy, the reference
/// run after them when it is not one of them).
pub type ConvergenceSpec = crate::studies::campaigns::ConvergenceSpec<LoadingSpec>;

impl ConvergenceSpec {
    /// The study's settings: [`Self::policies`], then the reference if it is not among them.
    pub fn settings(&self) -> Vec<(String, f64)> {
        let mut runs = self.policies.clone();
        if let Some(r) = &self.reference {
            if !runs.contains(r) {
                runs.push(r.clone());
            }
        }
        runs
    }

    /// The study's tasks (`--tasks`): the settings × the replicas.
    pub fn task_count(&self) -> u64 {
        self.settings().len() as u64 * self.replicas.count
    }

    /// Checks the spec without running anything: the replicas, the policies, and the loaded scene of each
    /// setting from the sample.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `replicas`, `perturbation.distance_m`, `policies` (none, or one whose policy or
    /// tolerance is invalid), `reference` (likewise), `sample` (unreadable; a loaded scene without `[output]
    /// cycles`), or the loading's field (`cycles`, `dt`, …; for a loaded scene, any field but `cycles` given).
    pub fn check(&self) -> Result<()> {
        self.scenes().map(drop)
    }

    /// The sample and the loaded scene of each setting, checked.
    fn scenes(&self) -> Result<Vec<Scene3>> {
        self.replicas.check()?;
        if self.policies.is_empty() {
            return Err(Error::Scene("policies: give at least one POLICY:TOLERANCE".into()));
        }
        let sample = Scene3::load(&self.sample)?;
        let seated = is_loaded(&sample);
        self.settings()
            .iter()
            .map(|(policy, tol)| {
                let loading = LoadingSpec { criterion: policy.clone(), tolerance: *tol, ..self.loading.clone() };
                let scene = if seated { reloaded_scene(&sample, &loading) } else { loaded_scene(&sample, &loading) };
                scene.map_err(|e| match e {
                    // The setting's own fields: named as the policy or reference they came from.
                    Error::Scene(m) if m.starts_with("criterion:") || m.starts_with("tolerance:") => {
                        let from =
                            if self.policies.contains(&(policy.clone(), *tol)) { "policies" } else { "reference" };
                        Error::Scene(format!("{from}: {policy}:{tol:e}: {m}"))
                    }
                    e => e,
                })
            })
            .collect()
    }
}

/// The 3D convergence study (`ballast track3d convergence`): for each setting `(policy, tolerance)` (the
/// policies, then the reference when it is not among them) and each replica `r`, the sample loaded with that
/// criterion and tolerance ([`loaded_scene`]) — or, when `spec.sample` is a loaded scene already (it has the
/// sleeper: a run's `final_scene.toml`, a seated state), that scene for `spec.loading.cycles` cycles of its own
/// loading with that criterion and tolerance, all its other settings kept ([`reloaded_scene`]; the other fields
/// of `spec.loading` must then be the defaults) —
/// (replica `r ≥ 1` perturbed, [`crate::studies::replicas::perturb_scene3`], as `ballast run --replica r`
/// perturbs a scene), written as
/// `DIR/scenes/<run>.toml` and run in `DIR/runs/<run>/` (`<run>` is `<policy>_<tolerance>/replica-<r>`, or
/// `<policy>_<tolerance>` with one replica), `study.jobs` at a time; then, as the 2D study,
/// `convergence.csv` (one row per run: the setting, `replica`, mean sweeps per step, steps at the sweep cap,
/// wall time per cycle, largest and mean overlap, settlement at the last cycle, …, followed by the ensemble
/// columns of its setting and the difference of its setting's means from the reference's with Welch's 95 %
/// interval), `cumulated_interpenetration`, `iterations_vs_tolerance` and `settlement_ensemble`.
/// `study.resume` skips the finished runs and resumes the checkpointed ones; `study.tasks` runs a share of the
/// runs, or writes the summary alone.
///
/// # Errors
/// As [`ConvergenceSpec::check`], and `jobs`, `checkpoint_every_s` or `task` (before any run); an invalid
/// checkpoint; a run that fails is reported in the table instead; an output that cannot be written is an
/// [`Error::Io`].
pub fn convergence(spec: &ConvergenceSpec, study: &StudyOptions, display: &dyn RunDisplay) -> Result<StudyReport> {
    crate::io::figures::require()?; // the study ends with its figures
    let scenes = spec.scenes()?;
    // Every setting's scene has the same caps (the settings differ in criterion and tolerance only): a reloaded
    // scene keeps its own, `loaded_scene` writes the loading's.
    let nlgs = scenes[0].nlgs_settings()?;
    let runs = spec.settings();
    let reference = reference_of(&runs, spec.reference.as_ref())?;
    study.threads()?;
    study.tasks.check(spec.task_count())?;
    let mut labels = Vec::new();
    for ((policy, tol), scene) in runs.iter().zip(&scenes) {
        let setting = replica_labels(&format!("{policy}_{}", label_number(*tol)), &spec.replicas);
        for (r, label) in setting.into_iter().enumerate() {
            if study.tasks.runs(labels.len() as u64) {
                let start = Start { replica: r as u64, perturbation: spec.replicas.perturbation };
                write_start(&study.out, &label, scene, &spec.sample, &start)?;
            }
            labels.push(label);
        }
    }
    let mut failed = Vec::new();
    let Some(outcomes) = run_written(&labels, 0, study, 0, display, &mut failed, read_cycles)? else {
        return Ok(not_summarized(&study.out, failed));
    };
    let iterations = (nlgs.min_iterations, nlgs.max_iterations);
    let seating = spec.replicas.seating_cycles.min(spec.loading.cycles);
    convergence_summary(&study.out, &runs, reference, &outcomes, &spec.replicas, seating, iterations, failed)
}
