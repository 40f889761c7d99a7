//! Which of a study's tasks an invocation runs: all of them side by side on the local pool (the default), one
//! alone (an element of a scheduler's job array: `--task K`, `SLURM_ARRAY_TASK_ID`), a share of them (one MPI
//! rank's: task `k` on rank `k mod N`), or none, the summary then written from the tasks' folders
//! (`--summarize-only`, or rank 0 once every rank is done). A task's start depends on its index alone and
//! its numbers not on the threads of its steps, so the summary of tasks run one by one in separate
//! processes, in any order, is the summary of the local run, byte for byte.

use crate::error::{Error, Result};
use crate::io::layout;
use std::path::{Path, PathBuf};

/// Which of a study's tasks (`0..count`, in the study's fixed order) this invocation runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Tasks {
    /// Every task, side by side on the local pool, then the summary.
    #[default]
    All,
    /// Task `k` alone, without the summary.
    One(u64),
    /// The tasks `k` with `k mod size == rank`, side by side on the local pool, without the summary (one of
    /// `size` processes, e.g. MPI ranks, each with its own `rank` in `0..size`).
    Share {
        /// This process's index, in `0..size`.
        rank: u64,
        /// The processes sharing the tasks, ≥ 1.
        size: u64,
    },
    /// No task: the summary from the tasks' folders, every one of which must hold a finished run.
    Summarize,
}

impl Tasks {
    /// Checks the selection against the study's `count` tasks.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `task` for a task that the study does not have.
    pub fn check(&self, count: u64) -> Result<()> {
        match *self {
            Tasks::One(k) if k >= count => Err(Error::Scene(format!(
                "task: the study has {count} tasks, 0 to {}; got {k}",
                count.saturating_sub(1)
            ))),
            Tasks::Share { rank, size } if rank >= size => {
                Err(Error::Scene(format!("task: rank {rank} of {size} processes (ranks are 0 to size − 1)")))
            }
            _ => Ok(()),
        }
    }

    /// Whether this invocation runs task `k`.
    pub fn runs(&self, k: u64) -> bool {
        match *self {
            Tasks::All => true,
            Tasks::One(j) => j == k,
            Tasks::Share { rank, size } => k % size == rank,
            Tasks::Summarize => false,
        }
    }

    /// Whether this invocation writes the study's summary.
    pub fn summarizes(&self) -> bool {
        matches!(self, Tasks::All | Tasks::Summarize)
    }

    /// Whether the tasks it runs go side by side on the local pool (all, or a share), rather than one alone.
    pub fn side_by_side(&self) -> bool {
        matches!(self, Tasks::All | Tasks::Share { .. })
    }
}

/// Records in the folder `dir` of a task how its run ended (`result`), so that a summary written later, by
/// another process, reports it: [`layout::FAILED`] with the one-line error of a run that failed, none for a
/// run that ended. An input error ([`Error::is_input`]: an invalid scene or checkpoint, which stops the
/// study) is not a run's end and is not recorded.
///
/// # Errors
/// The record that cannot be written or removed.
pub fn record(dir: &Path, result: &Result<()>) -> Result<()> {
    let path = dir.join(layout::FAILED);
    match result {
        Ok(()) if path.exists() => std::fs::remove_file(&path).map_err(|e| crate::io::io_error(&path, "remove", e)),
        Err(e) if !e.is_input() => {
            std::fs::write(&path, format!("{}\n", e.one_line())).map_err(|e| crate::io::io_error(&path, "write", e))
        }
        _ => Ok(()),
    }
}

/// How the run in the folder `dir` ended, for a summary: `None` if it holds no finished run (no
/// `summary.json`, or a checkpoint still to resume), `Some(None)` for a run that ended, `Some(Some(error))` for
/// one that failed: its [`layout::FAILED`], else, for a folder without one whose `summary.json` says the run
/// diverged or stalled, that.
///
/// # Errors
/// A `summary.json` or record that cannot be read.
pub fn folder_end(dir: &Path) -> Result<Option<Option<String>>> {
    let summary = dir.join(layout::SUMMARY);
    if !summary.is_file() || dir.join(layout::CHECKPOINT).exists() {
        return Ok(None);
    }
    let failed = dir.join(layout::FAILED);
    if failed.is_file() {
        let text = std::fs::read_to_string(&failed).map_err(|e| crate::io::io_error(&failed, "read", e))?;
        return Ok(Some(Some(text.trim_end().to_string())));
    }
    let text = std::fs::read_to_string(&summary).map_err(|e| crate::io::io_error(&summary, "read", e))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Error::Scene(format!("{}: not a run's summary: {e}", summary.display())))?;
    let end = value.get("end").and_then(|e| e.as_str()).unwrap_or("");
    Ok(Some(matches!(end, "diverged" | "stalled").then(|| format!("the run {end} (its summary.json)"))))
}

/// The failures of the tasks in `folders` (`(label, folder)`, in task order), read from the folders
/// ([`folder_end`]) for a summary: `None` for a run that ended, `Some` with the error of one that failed.
///
/// # Errors
/// [`Error::Scene`] naming the tasks whose folder holds no finished run, or a folder that cannot be read.
pub fn failures_from_folders(folders: &[(String, PathBuf)]) -> Result<Vec<Option<String>>> {
    let mut missing = Vec::new();
    let mut failures = Vec::with_capacity(folders.len());
    for (label, dir) in folders {
        match folder_end(dir)? {
            Some(end) => failures.push(end),
            None => {
                missing.push(label.as_str());
                failures.push(None);
            }
        }
    }
    if !missing.is_empty() {
        return Err(Error::Scene(format!(
            "summarize: {} of {} tasks have no finished run: {} (run each alone, or resume the study)",
            missing.len(),
            folders.len(),
            missing.join(", ")
        )));
    }
    Ok(failures)
}
