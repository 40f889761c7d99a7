//! Replicas of the 3D track section's settlement run (`ballast track3d settle --replicas R`): the 2D
//! [`crate::studies::saussine::settle_replicas`] on the 3D scenes, through the studies' shared runner
//! ([`crate::studies::campaigns`]) and ensemble ([`crate::studies::replicas`]).

use super::{loaded, write_scene, SettleOptions};
use crate::error::Result;
use crate::io::layout;
use crate::nscd::d3::rows::{read_cycles, CycleRow3};
use crate::scenarios::track3d::LoadingSpec;
use crate::scene::Scene3;
use crate::studies::campaigns::{run_dir, run_written, scene_path, StudyOptions};
use crate::studies::replicas::{perturb_scene3, Replicas, Start, REPLICA_FILE};
use crate::studies::saussine::{finish_replicas, steps_per_cycle, SettleReplicas};
use crate::studies::{output_error, RunDisplay};
use std::path::Path;

/// The label of replica `r`: its run is `OUT/runs/replica-<r>/` ([`crate::studies::saussine::replica_dir`]).
fn label(r: u64) -> String {
    format!("replica-{r}")
}

/// Writes the start of the study's run `label` in `out`: `scene` (a loaded 3D scene, `source` named in its note)
/// perturbed as `start` says ([`perturb_scene3`]) as `OUT/scenes/<label>.toml`, and its [`REPLICA_FILE`] in
/// `OUT/runs/<label>/`.
///
/// # Errors
/// An invalid perturbation (named); an output that cannot be written.
pub(super) fn write_start(out: &Path, label: &str, scene: &Scene3, source: &Path, start: &Start) -> Result<()> {
    let mut scene = scene.clone();
    let record = perturb_scene3(&mut scene, &start.perturbation, start.replica)?;
    let path = scene_path(out, label);
    if let Some(parent) = path.parent() {
        crate::io::create_output_dir(parent)?;
    }
    let what = format!(
        "{label}, loaded from {}, replica {} (start perturbed by at most {} m, seed {})",
        source.display(),
        start.replica,
        if start.replica == 0 { 0.0 } else { start.perturbation.distance_m },
        start.perturbation.seed
    );
    write_scene(&path, &scene, &what)?;
    let dir = run_dir(out, label);
    crate::io::create_output_dir(&dir)?;
    crate::io::write_json(&dir.join(REPLICA_FILE), &record).map(drop)
}

/// §4 in 3D with replicas: [`super::settle`]'s loaded scene from `replicas.count` starts, replica 0 the sample
/// as it is and replica `r ≥ 1` with every mobile body moved by at most `replicas.perturbation.distance_m`
/// ([`perturb_scene3`]); the starts written as `OUT/scenes/replica-<r>.toml`, the runs side by side, `jobs` at a
/// time (`None`: one per core; one alone runs on [`crate::run::default_threads`] threads), each in
/// `OUT/runs/replica-<r>/` with `cycles.csv`, `series.csv`, `summary.json`, figures, VTK snapshots every
/// `opts.snapshot_every` cycles and [`REPLICA_FILE`]. `opts.resume` skips the finished replicas and
/// resumes the checkpointed ones. Then `OUT/settlement_ensemble.csv` (per cycle: mean, standard deviation and
/// 95 % interval of the settlement at the load minimum, [`crate::studies::replicas::CycleSettlement`] for
/// [`CycleRow3`], and of the settlement accrued since cycle `replicas.seating_cycles`) and the figure
/// `settlement_ensemble`, as `ballast saussine settle --replicas` writes them. The runs are labelled
/// `replica-<r>`.
///
/// # Errors
/// [`crate::Error::Scene`] naming the field for an unreadable sample, an invalid loading, `replicas`,
/// `perturbation.distance_m`, `jobs` or `checkpoint_every_s` (before any run), or an invalid checkpoint; a
/// replica that fails is reported in [`SettleReplicas::failed`]; an output that cannot be written is an
/// [`crate::Error::Io`].
pub fn settle_replicas(
    sample: &Path,
    loading: &LoadingSpec,
    out: &Path,
    opts: &SettleOptions,
    replicas: &Replicas,
    jobs: Option<usize>,
    display: &dyn RunDisplay,
) -> Result<SettleReplicas> {
    crate::io::figures::require()?; // the runs end with their figures
    replicas.check()?;
    let study = StudyOptions {
        jobs: Some(crate::studies::saussine::replica_jobs(jobs, replicas.count)?),
        resume: opts.resume,
        checkpoint_every_s: opts.checkpoint_every_s,
        ..StudyOptions::new(out)
    };
    study.threads()?;
    let scene = loaded(sample, loading)?;
    // Every start first, so that an invalid one stops before any run.
    let labels: Vec<String> = (0..replicas.count).map(label).collect();
    for (r, label) in (0..replicas.count).zip(&labels) {
        write_start(out, label, &scene, sample, &Start { replica: r, perturbation: replicas.perturbation })?;
    }
    let mut failed = Vec::new();
    let vtk_every = opts.snapshot_every.saturating_mul(steps_per_cycle(loading.frequency, loading.dt));
    run_written(&labels, 0, &study, vtk_every, display, &mut failed, read_cycles)?;
    let failures: Vec<Option<String>> =
        labels.iter().map(|l| failed.iter().find(|(f, _)| f == l).map(|(_, e)| e.clone())).collect();
    let read = |path: &Path| read_cycles(path).map_err(output_error);
    let seating = replicas.seating_cycles.min(loading.cycles);
    finish_replicas::<CycleRow3>(
        out,
        &failures,
        layout::CYCLES,
        read,
        seating,
        "Settlement of the sleeper, 3D track section",
    )
}
