//! MPI ranks for the studies' tasks (feature `mpi`): under `mpirun -np N ballast …` every rank runs its share
//! of the study's tasks (task `k` on rank `k mod N`, `ballast::studies::tasks::Tasks::Share`), waits for the
//! others, and rank 0 writes the summary from the tasks' folders. Without the feature, or on one rank, a study
//! runs as it always does.

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

/// Waits for every rank (nothing on one).
pub(crate) fn barrier() {
    #[cfg(feature = "mpi")]
    if ranks().1 > 1 {
        use mpi::traits::CommunicatorCollectives;
        mpi::topology::SimpleCommunicator::world().barrier();
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

/// `selection` on this rank: the whole study (`Tasks::All`) becomes this rank's share when MPI runs several
/// ranks; a task or a summary asked for stays as it is.
pub(crate) fn share(selection: Tasks) -> Tasks {
    match (selection, ranks()) {
        (Tasks::All, (rank, size)) if size > 1 => Tasks::Share { rank, size },
        (s, _) => s,
    }
}

/// Runs a study whose tasks are `tasks` (`study` with a selection of them); on a rank's share, waits for every
/// rank, and rank 0 writes the summary from the folders: what to print (`None` on the other ranks, which
/// print their own failures, `failed` of the report).
///
/// # Errors
/// The study's.
pub(crate) fn shared<R>(
    tasks: Tasks,
    study: impl Fn(Tasks) -> ballast::Result<R>,
    failed: impl Fn(&R) -> &[(String, String)],
) -> ballast::Result<Option<R>> {
    let r = study(tasks)?;
    let Tasks::Share { rank, .. } = tasks else { return Ok(Some(r)) };
    barrier();
    if rank > 0 {
        for (label, e) in failed(&r) {
            eprintln!("run {label} failed: {e}");
        }
        return Ok(None);
    }
    study(Tasks::Summarize).map(Some)
}
