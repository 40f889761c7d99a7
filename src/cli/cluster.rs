//! MPI ranks for the studies' tasks (feature `mpi`): under `mpirun -np N ballast …` every rank runs its share
//! of the study's tasks (static: task `k` on rank `k mod N`, `ballast::studies::tasks::Tasks::Share`; dynamic:
//! the tasks rank 0 hands out one at a time, `--schedule dynamic`), waits for the others, and rank 0 writes
//! the summary from the tasks' folders. Without the feature, without a launcher, or on one rank, a study runs
//! as it always does.

use ballast::studies::tasks::Tasks;
use std::sync::OnceLock;

/// `(rank, size)` of this process, set by [`init`] when MPI runs more than one rank.
static RANKS: OnceLock<(u64, u64)> = OnceLock::new();

/// The MPI environment while the command runs (finalised when dropped, at the end of `main`).
pub(crate) struct Session {
    #[cfg(feature = "mpi")]
    _universe: Option<mpi::environment::Universe>,
}

/// Whether an MPI launcher started this process: the variables OpenMPI (`OMPI_COMM_WORLD_SIZE`), MPICH's
/// Hydra and Intel MPI (`PMI_RANK`, `PMI_SIZE`, `MPI_LOCALNRANKS`) or a PMIx launcher such as Slurm's `srun
/// --mpi=pmix` (`PMIX_RANK`) give every rank.
#[cfg(feature = "mpi")]
fn launched_by_mpi() -> bool {
    ["OMPI_COMM_WORLD_SIZE", "PMI_RANK", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"]
        .iter()
        .any(|v| std::env::var_os(v).is_some())
}

/// Initialises MPI (feature `mpi`; nothing without it) for the command's life, when an MPI launcher started
/// the process: a process started alone (a job array's task, a plain command) is one rank without MPI's
/// start-up (a singleton start of OpenMPI costs 0.3 s per process here).
pub(crate) fn init() -> Session {
    #[cfg(feature = "mpi")]
    {
        if !launched_by_mpi() {
            return Session { _universe: None };
        }
        use mpi::traits::Communicator;
        let universe = mpi::initialize();
        if let Some(u) = &universe {
            let world = u.world();
            let _ = RANKS.set((world.rank() as u64, world.size() as u64));
        }
        Session { _universe: universe }
    }
    #[cfg(not(feature = "mpi"))]
    Session {}
}

/// This process's rank and the number of ranks, `(rank, size)`: `(0, 1)` without MPI.
pub(crate) fn ranks() -> (u64, u64) {
    RANKS.get().copied().unwrap_or((0, 1))
}

/// Waits for every rank (nothing on one), asleep: MPI's own blocking calls spin, and a rank done early would
/// take a core from the ranks still working when there are more ranks than cores.
pub(crate) fn barrier() {
    #[cfg(feature = "mpi")]
    if ranks().1 > 1 {
        use mpi::traits::CommunicatorCollectives;
        let mut request = Some(mpi::topology::SimpleCommunicator::world().immediate_barrier());
        poll(|| match request.take()?.test() {
            Ok(_) => Some(()),
            Err(pending) => {
                request = Some(pending);
                None
            }
        });
    }
}

/// Calls `f` until it gives a value, sleeping 2 ms between calls.
#[cfg(feature = "mpi")]
fn poll<T>(mut f: impl FnMut() -> Option<T>) -> T {
    loop {
        if let Some(t) = f() {
            return t;
        }
        std::thread::sleep(std::time::Duration::from_millis(2));
    }
}

/// Ends every rank with `code` when one of several fails (the others would wait for it at the barrier);
/// returns on one rank.
pub(crate) fn abort_others(code: u8) {
    #[cfg(feature = "mpi")]
    if ranks().1 > 1 {
        use mpi::traits::Communicator;
        mpi::topology::SimpleCommunicator::world().abort(i32::from(code));
    }
    let _ = code;
}

/// How MPI ranks share a study's tasks (`--schedule`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum Schedule {
    /// Task `k` on rank `k mod N`, each rank its share side by side on its cores.
    #[default]
    Static,
    /// Rank 0 hands out the task indices in order, one at a time, to the ranks that ask (it runs none
    /// itself): for tasks of unequal cost on many ranks.
    Dynamic,
}

/// What the ranks need to share a study's tasks: the selection asked for, the schedule, the number of tasks
/// and the first task of a second stage that needs every task before it finished (0: one stage).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Plan {
    pub(crate) selection: Tasks,
    pub(crate) schedule: Schedule,
    pub(crate) count: u64,
    pub(crate) second_stage: u64,
}

/// `selection` on this rank: the whole study (`Tasks::All`) becomes this rank's share when MPI runs several
/// ranks; a task or a summary asked for stays as it is.
fn share(selection: Tasks) -> Tasks {
    match (selection, ranks()) {
        (Tasks::All, (rank, size)) if size > 1 => Tasks::Share { rank, size },
        (s, _) => s,
    }
}

/// Runs a study (`study` with a selection of its tasks) as `plan` says: alone, the selection; on several MPI
/// ranks, the whole study shared (static: each rank its share; dynamic: the tasks rank 0 hands out, one at a
/// time), then, once every rank is done, rank 0 writes the summary from the folders. What to print: `None` on
/// the other ranks, which print their own failures (`failed` of the report).
///
/// # Errors
/// The study's.
pub(crate) fn shared<R>(
    plan: Plan,
    study: impl Fn(Tasks) -> ballast::Result<R>,
    failed: impl Fn(&R) -> &[(String, String)],
) -> ballast::Result<Option<R>> {
    let tasks = share(plan.selection);
    let Tasks::Share { rank, .. } = tasks else {
        // A task or a summary asked for under mpirun: rank 0's alone (two ranks would write the same folder).
        return if ranks().0 == 0 { study(tasks).map(Some) } else { Ok(None) };
    };
    let mut failures = Vec::new();
    match plan.schedule {
        Schedule::Static => failures.extend(failed(&study(tasks)?).iter().cloned()),
        Schedule::Dynamic if rank == 0 => hand_out(plan.count, plan.second_stage),
        Schedule::Dynamic => {
            while let Some(k) = next_task() {
                failures.extend(failed(&study(Tasks::One(k))?).iter().cloned());
            }
        }
    }
    barrier();
    if rank > 0 {
        for (label, e) in &failures {
            eprintln!("run {label} failed: {e}");
        }
        return Ok(None);
    }
    study(Tasks::Summarize).map(Some)
}

/// The message of "no task": no task done yet (to rank 0), no task left (from it).
#[cfg(feature = "mpi")]
const NONE: u64 = u64::MAX;

/// Rank 0 of a dynamic schedule (asleep between requests, [`poll`]): answers each rank's request (which
/// carries the task it finished) with the next task in order, or [`NONE`] when none is left; a task of the
/// second stage waits until every task before `second_stage` has finished.
fn hand_out(count: u64, second_stage: u64) {
    #[cfg(feature = "mpi")]
    {
        use mpi::traits::{Communicator, Destination, Source};
        let world = mpi::topology::SimpleCommunicator::world();
        let (mut next, mut first_done, mut workers) = (0u64, 0u64, world.size() - 1);
        let mut waiting = std::collections::VecDeque::new();
        while workers > 0 {
            let (message, status) = poll(|| world.any_process().immediate_matched_probe());
            let (done, _) = message.matched_receive::<u64>();
            if done != NONE && done < second_stage {
                first_done += 1;
            }
            waiting.push_back(status.source_rank());
            while let Some(&r) = waiting.front() {
                if next >= second_stage.min(count) && next < count && first_done < second_stage {
                    break; // the second stage needs the first finished
                }
                let task = if next < count { next } else { NONE };
                world.process_at_rank(r).send(&task);
                if task == NONE {
                    workers -= 1;
                } else {
                    next += 1;
                }
                waiting.pop_front();
            }
        }
    }
    let _ = (count, second_stage);
}

/// A rank of a dynamic schedule: tells rank 0 the task it finished (none at first) and receives the next one.
fn next_task() -> Option<u64> {
    #[cfg(feature = "mpi")]
    {
        use mpi::traits::{Communicator, Destination, Source};
        thread_local!(static DONE: std::cell::Cell<u64> = const { std::cell::Cell::new(NONE) });
        let world = mpi::topology::SimpleCommunicator::world();
        world.process_at_rank(0).send(&DONE.get());
        let (message, _) = poll(|| world.process_at_rank(0).immediate_matched_probe());
        let (task, _) = message.matched_receive::<u64>();
        DONE.set(task);
        (task != NONE).then_some(task)
    }
    #[cfg(not(feature = "mpi"))]
    None
}
