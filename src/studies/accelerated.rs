//! Replicas of an accelerated settlement run (`saussine settle --accelerate …
//! --replicas R`): the settlement-acceleration procedure of Karrech et al.
//! (2007, Fig. 10) from R starts, replica 0 the sample as it is and replica
//! `r ≥ 1` moved by [`super::replicas::perturb_scene`], side by side, and the
//! ensemble of their settlements per cycle. One accelerated run is one draw of a
//! chaotic process (a start moved by 1e-9 m changes its error by tens of per
//! cent: BENCHMARKS.md, "Settlement acceleration"), so its error is an ensemble's.

use super::replicas::{Replicas, Start};
use super::saussine::{end_replicas, finish_replicas, replica_dir, replica_jobs, settle_accelerated};
use super::saussine::{Accelerate, SettleOptions, SettleReplicas};
use crate::error::Result;
use crate::io;
use crate::io::layout;
use crate::run::Prior;
use crate::scenarios::saussine::LoadingSpec;
use crate::settlement::SettlementRow;
use std::path::Path;

/// [`super::saussine::settle_accelerated`] from `replicas.count` starts (replica
/// `r` from [`Start`] `r`, the start [`super::saussine::settle_replicas`] gives
/// it), `jobs` at a time (`None`: one per core), each in `OUT/runs/replica-<r>/`
/// with the outputs of an accelerated run (`settlement.csv`, `jumps.csv`,
/// `summary.json`, figures), its `loaded.toml` and, for `r ≥ 1`,
/// [`super::replicas::REPLICA_FILE`]; `opts.resume` skips the finished replicas
/// and resumes the checkpointed ones. Then `OUT/settlement_ensemble.csv` over
/// the replicas' `settlement.csv` (the settlement at each cycle's end: measured
/// on computed cycles, the fitted law's on extrapolated ones) with the seating
/// cycle `replicas.seating_cycles`, and its figure. The runs report no progress. `opts.tasks` runs one
/// replica alone (no summary) or none (the summary from the replicas' folders).
///
/// # Errors
/// As [`super::saussine::settle_replicas`]; a replica that fails is reported in
/// [`SettleReplicas::failed`].
pub fn settle_accelerated_replicas(
    sample: &Path,
    loading: &LoadingSpec,
    accelerate: &Accelerate,
    out: &Path,
    opts: &SettleOptions,
    replicas: &Replicas,
    jobs: Option<usize>,
) -> Result<SettleReplicas> {
    crate::io::figures::require()?; // the runs end with their figures
    replicas.check()?;
    opts.tasks.check(replicas.count)?;
    let threads = replica_jobs(jobs, replicas.count)?;
    io::create_output_dir(&out.join("runs"))?;
    let priors: Vec<Prior> = (0..replicas.count)
        .map(|r| match opts.tasks.runs(r) {
            true => Prior::of(&replica_dir(out, r), layout::SUMMARY, opts.resume),
            // Not this invocation's: as if finished.
            false => Prior::Finished,
        })
        .collect();
    let pool = super::campaigns::pool(threads)?;
    let results: Vec<Result<()>> = pool.install(|| {
        use rayon::prelude::*;
        (0..replicas.count)
            .into_par_iter()
            .map(|r| match priors[r as usize] {
                Prior::Finished => Ok(()),
                prior => {
                    let start = Start { replica: r, perturbation: replicas.perturbation };
                    let opts = SettleOptions { resume: prior == Prior::Checkpointed, ..opts.clone() };
                    let dir = replica_dir(out, r);
                    let threads = super::campaigns::run_threads(if opts.tasks.side_by_side() { threads } else { 1 });
                    let result =
                        settle_accelerated(sample, loading, &start, accelerate, &dir, &opts, threads, &mut |_| {})
                            .map(|_| ());
                    super::tasks::record(&dir, &result)?;
                    result
                }
            })
            .collect()
    });
    let seating = replicas.seating_cycles.min(loading.cycles);
    let read = |path: &Path| io::read_csv::<SettlementRow>(path);
    end_replicas(out, replicas.count, opts.tasks, results, |failures| {
        finish_replicas(out, failures, "settlement.csv", read, seating, "Settlement of the sleeper, accelerated")
    })
}
