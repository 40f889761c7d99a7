//! The replicas of a Saussine settlement run (§4, `saussine settle --replicas`) as independent tasks, for
//! executors the library does not own (a Python `concurrent.futures` executor, a Dask cluster, MPI ranks, a
//! scheduler's job array): [`write_starts`] writes every replica's start into its folder, [`run_replica`] runs
//! one replica from its folder alone, [`finish`] reads the folders into the ensemble's table and figure.
//! [`super::saussine::settle_replicas`] is the three on a local thread pool.
//!
//! A replica's start depends on its index alone (stream `r` of the perturbation's seed,
//! [`super::replicas::Perturbation::rng`]) and its numbers do not depend on the threads of its steps, so the
//! ensemble is the same, byte for byte, whichever executor ran the tasks and in whatever order.

use super::replicas::{Replicas, Start};
use super::saussine::SettleReplicas;
use super::saussine::{finish_replicas, replica_dir, run_settle, steps_per_cycle, write_start, SettleOptions};
use super::tasks::Tasks;
use super::{output_error, RunDisplay};
use crate::error::{Error, Result};
use crate::io::{self, layout};
use crate::run::Prior;
use crate::scene::{Scene, SceneFile};
use std::path::Path;

/// What [`write_starts`] set up: the replicas to run and the seating cycle of their ensemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ReplicaTasks {
    /// Replicas, `0..count`.
    pub count: u64,
    /// The seating cycle of the ensemble (`replicas.seating_cycles`, at most the cycles run).
    pub seating: u64,
}

/// Writes the start of every replica of the loaded `scene` (a cyclic NSCD scene: the sleeper on a sample,
/// [`crate::scenarios::saussine::loaded_scene`]; `source` is named in the scenes' notes) into
/// `OUT/runs/replica-<r>/loaded.toml`, replica `r` perturbed as [`Start`] `r` says, with its
/// [`super::replicas::REPLICA_FILE`]: of the replicas `tasks` runs (every one, one alone, none). With
/// `resume`, the folders that hold a run already keep their start.
///
/// # Errors
/// [`Error::Scene`] naming the key for invalid replicas or a scene without loading cycles; an output that
/// cannot be written.
pub fn write_starts(
    scene: &Scene,
    source: &Path,
    out: &Path,
    replicas: &Replicas,
    resume: bool,
    tasks: Tasks,
) -> Result<ReplicaTasks> {
    replicas.check()?;
    tasks.check(replicas.count)?;
    let cycles = scene.plan()?.cycles.ok_or_else(|| {
        Error::Scene("output.cycles: the replicas' scene has no loading cycles (give [output] cycles)".into())
    })?;
    let total = (scene.simulation.duration * cycles.frequency).round() as u64;
    io::create_output_dir(&out.join("runs"))?;
    for r in (0..replicas.count).filter(|&r| tasks.runs(r)) {
        let dir = replica_dir(out, r);
        let prior = Prior::of(&dir, layout::SUMMARY, resume);
        let start = Start { replica: r, perturbation: replicas.perturbation };
        write_start(source, scene.clone(), &start, &dir, prior != Prior::Nothing, true, "")?;
    }
    Ok(ReplicaTasks { count: replicas.count, seating: replicas.seating_cycles.min(total) })
}

/// Runs replica `r` of the study in `out` from its folder (its `loaded.toml`, written by [`write_starts`]) as
/// `ballast saussine settle --replicas` runs it, on `threads` threads: `opts.resume` skips a finished replica
/// and resumes a checkpointed one. The run is labelled `replica-<r>`; a run that fails leaves its error in the
/// folder ([`super::tasks::record`]) for the summary.
///
/// # Errors
/// [`Error::Scene`] if the start is missing or invalid; else as [`crate::run::Runner::run`].
pub fn run_replica(out: &Path, r: u64, opts: &SettleOptions, threads: usize, display: &dyn RunDisplay) -> Result<()> {
    let dir = replica_dir(out, r);
    let prior = Prior::of(&dir, layout::SUMMARY, opts.resume);
    if prior == Prior::Finished {
        return Ok(());
    }
    let path = dir.join("loaded.toml");
    let scene = Scene::load(&path)?;
    let frequency = scene.plan()?.cycles.map_or(1.0 / scene.simulation.dt, |c| c.frequency);
    let per_cycle = steps_per_cycle(frequency, scene.simulation.dt);
    let resume = prior == Prior::Checkpointed;
    let result = run_settle(&path, &dir, per_cycle, opts, threads, resume, display, &format!("replica-{r}")).map(drop);
    super::tasks::record(&dir, &result)?;
    result
}

/// The ensemble of the replicas in `out` (`failures[r]`: the one-line error of replica `r`, `None` if it ran;
/// `seating`: [`ReplicaTasks::seating`]): `OUT/settlement_ensemble.csv` over the replicas' `cycles.csv` (the
/// ensemble stops at the last cycle every replica reached) and the figure `settlement_ensemble`.
///
/// # Errors
/// A table that cannot be read or written.
pub fn finish(out: &Path, failures: &[Option<String>], seating: u64) -> Result<SettleReplicas> {
    let read = |path: &Path| crate::plane::rows::read_cycles(path).map_err(output_error);
    finish_replicas(out, failures, layout::CYCLES, read, seating, "Settlement of the sleeper")
}
