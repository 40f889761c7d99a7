//! Replicas of the Karrech et al. (2007) loading (§4; `karrech load --replicas R`, plain or accelerated as in
//! Fig. 10): the deposit loaded from `R` starts, replica 0 the deposit as it is and replica `r ≥ 1` every
//! sphere moved by at most the perturbation ([`super::replicas::perturb_md_scene`], stream `r` of its seed),
//! each run in `OUT/runs/replica-<r>/` with the outputs of [`super::karrech::load`] (or
//! [`super::karrech::load_accelerated`]); then the ensemble of the plate's settlement per cycle,
//! `OUT/settlement_ensemble.csv` (mean, sd and 95 % interval, settlement accrued after the seating cycle) and
//! its figure. The replicas are the study's tasks ([`Tasks`]): one alone (a job array's element), an MPI rank's
//! share, or none (the summary from the folders).
//!
//! The settlement of a plain run at a cycle is the plate's displacement along its normal (down) since the
//! start of the loading, at the cycle's end (`plate_position_m` of `cycles.csv`): what the settlement driver
//! follows in an accelerated run (its `settlement.csv`).

use super::karrech::{load, load_accelerated, Start};
use super::md_stage::Stage;
use super::replicas::{CycleSettlement, Replicas};
use super::saussine::{end_replicas, finish_replicas, replica_dir, replica_jobs};
use super::saussine::{Accelerate, SettleReplicas};
use super::tasks::{record, Tasks};
use super::RunDisplay;
use crate::error::Result;
use crate::io::{self, layout};
use crate::run::Prior;
use crate::scenarios::karrech::Loading;
use crate::settlement::SettlementRow;
use std::path::Path;

/// The plate's settlement at the end of a cycle of a plain loading run (a row of its `cycles.csv`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlateCycle {
    /// Column `cycle`: the cycle ended (1 for the first).
    pub cycle: u64,
    /// Column `plate_position_m`: the plate's displacement along its normal, downwards, since the start of the
    /// loading (m).
    pub settlement_m: f64,
}

impl CycleSettlement for PlateCycle {
    fn cycle(&self) -> u64 {
        self.cycle
    }
    fn settlement_at_min_load(&self) -> f64 {
        self.settlement_m
    }
}

/// The plate's settlement per cycle of the plain loading run whose `cycles.csv` is `path`.
///
/// # Errors
/// A table that cannot be read or has no `cycle` or `plate_position_m` column.
pub fn read_plate_cycles(path: &Path) -> Result<Vec<PlateCycle>> {
    let c = io::table::read_columns(path, &["cycle", "plate_position_m"])?;
    Ok(c[0].iter().zip(&c[1]).map(|(&cycle, &s)| PlateCycle { cycle: cycle as u64, settlement_m: s }).collect())
}

/// The loading of a Karrech replica study.
#[derive(Debug, Clone)]
pub struct KarrechReplicas {
    /// The plate ([`Loading::FULL`] or [`Loading::PARTIAL`]).
    pub loading: Loading,
    /// Loading cycles of every replica.
    pub cycles: u32,
    /// The replicas, their perturbation and the seating cycle.
    pub replicas: Replicas,
    /// Accelerated runs (Karrech et al. 2007, Fig. 10) with these settings, or plain ones.
    pub accelerate: Option<Accelerate>,
}

/// The replicas of the loading of the deposit in `from` (module doc), in `stage.out`: each replica a stage of
/// `stage`'s settings in its folder, `jobs` at a time (`None`: one per core), on the threads a run has when
/// several go side by side; `stage.run.resume` skips the finished replicas and resumes the checkpointed ones;
/// `tasks` selects the replicas this invocation runs and whether it writes the summary.
///
/// # Errors
/// [`crate::Error::Scene`] for invalid replicas, task or `jobs`, before any run; as [`load`] for a replica's
/// input; a replica that fails is reported in [`SettleReplicas::failed`] and recorded in its folder; with the
/// summary, a replica without a finished run (named).
pub fn load_replicas(
    from: &Path,
    study: &KarrechReplicas,
    stage: &Stage,
    jobs: Option<usize>,
    tasks: Tasks,
    display: &dyn RunDisplay,
) -> Result<SettleReplicas> {
    crate::io::figures::require()?; // the runs end with their figures
    let replicas = &study.replicas;
    replicas.check()?;
    tasks.check(replicas.count)?;
    let threads = replica_jobs(jobs, replicas.count)?;
    let out = &stage.out;
    io::create_output_dir(&out.join("runs"))?;
    let pool = super::campaigns::pool(threads)?;
    let side_by_side = if tasks.side_by_side() { threads } else { 1 };
    let results: Vec<Result<()>> = pool.install(|| {
        use rayon::prelude::*;
        (0..replicas.count)
            .into_par_iter()
            .map(|r| {
                let dir = replica_dir(out, r);
                let prior = Prior::of(&dir, layout::SUMMARY, stage.run.resume);
                if !tasks.runs(r) || prior == Prior::Finished {
                    return Ok(());
                }
                let run = crate::run::RunOptions {
                    resume: prior == Prior::Checkpointed,
                    threads: super::campaigns::run_threads(side_by_side),
                    ..stage.run.clone()
                };
                let stage = Stage { out: dir.clone(), every: stage.every, run };
                let start = Start { replica: r, perturbation: replicas.perturbation };
                let result = match &study.accelerate {
                    Some(acc) => {
                        load_accelerated(from, study.loading, study.cycles, acc, &start, &stage, &mut |_| {}).map(drop)
                    }
                    None => load(from, study.loading, study.cycles, &start, &stage, display).map(drop),
                };
                record(&dir, &result)?;
                result
            })
            .collect()
    });
    let seating = replicas.seating_cycles.min(u64::from(study.cycles));
    let title = "Settlement of the plate (Karrech et al. 2007)";
    end_replicas(out, replicas.count, tasks, results, |failures| match study.accelerate {
        Some(_) => {
            let read = |path: &Path| io::read_csv::<SettlementRow>(path);
            finish_replicas(out, failures, layout::SETTLEMENT, read, seating, &format!("{title}, accelerated"))
        }
        None => finish_replicas(out, failures, layout::CYCLES, read_plate_cycles, seating, title),
    })
}
