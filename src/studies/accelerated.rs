//! Replicas of an accelerated settlement run (`saussine settle --accelerate …
//! --replicas R`): the settlement-acceleration procedure of Karrech et al.
//! (2007, Fig. 10) from R starts, replica 0 the sample as it is and replica
//! `r ≥ 1` moved by [`super::replicas::perturb_scene`], side by side, and the
//! ensemble of their settlements per cycle. One accelerated run is one draw of a
//! chaotic process (a start moved by 1e-9 m changes its error by tens of per
//! cent: BENCHMARKS.md, "Settlement acceleration"), so its error is an ensemble's.

use super::replicas::{settlement_ensemble, Replicas, Start};
use super::saussine::SettleReplicas;
use super::saussine::{ensemble_figure, replica_dir, settle_accelerated_on, Accelerate, Loading, SettleOptions};
use crate::error::{Error, Result};
use crate::io;
use crate::run::{files, Prior};
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
/// cycle `replicas.seating_cycles`, and its figure. The runs report no progress.
///
/// # Errors
/// As [`super::saussine::settle_replicas`]; a replica that fails is reported in
/// [`SettleReplicas::failed`].
pub fn settle_accelerated_replicas(
    sample: &Path,
    loading: &Loading,
    accelerate: &Accelerate,
    out: &Path,
    opts: &SettleOptions,
    replicas: &Replicas,
    jobs: Option<usize>,
) -> Result<SettleReplicas> {
    crate::io::figures::require()?; // the runs end with their figures
    replicas.check()?;
    let threads = match jobs.unwrap_or_else(crate::run::cores) {
        0 => return Err(Error::Scene("--jobs: must be at least 1".into())),
        n => n.min(replicas.count as usize),
    };
    io::create_output_dir(&out.join("runs"))?;
    let priors: Vec<Prior> =
        (0..replicas.count).map(|r| Prior::of(&replica_dir(out, r), files::SUMMARY, opts.resume)).collect();
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
                    let threads = super::campaigns::run_threads(threads);
                    settle_accelerated_on(sample, loading, &start, accelerate, &dir, &opts, threads, &mut |_| {})
                        .map(|_| ())
                }
            })
            .collect()
    });
    let mut failed = Vec::new();
    let mut tables = Vec::new();
    for (r, result) in results.into_iter().enumerate() {
        match result {
            Ok(()) => {}
            Err(e @ Error::Scene(_)) => return Err(e),
            Err(e) => failed.push((format!("replica-{r}"), e.one_line())),
        }
        let path = replica_dir(out, r as u64).join("settlement.csv");
        tables.push(if path.exists() { io::read_csv::<SettlementRow>(&path)? } else { vec![] });
    }
    let runs: Vec<&[SettlementRow]> = tables.iter().map(Vec::as_slice).collect();
    let rows = settlement_ensemble(&runs, replicas.seating_cycles.min(loading.cycles));
    let table = out.join("settlement_ensemble.csv");
    io::table::write_all(&table, &rows)?;
    ensemble_figure(&out.join("settlement_ensemble"), "Settlement of the sleeper, accelerated", &runs, &rows)?;
    Ok(SettleReplicas { runs: out.join("runs"), table, rows, failed })
}
