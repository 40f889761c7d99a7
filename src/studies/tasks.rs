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

/// How the run in the folder `dir` ended, for a summary: `Some(Some(error))` for one that failed (its
/// [`layout::FAILED`], whatever else the folder holds: a run that diverged after a checkpoint keeps it),
/// `None` if it holds no finished run (no `summary.json`, or a checkpoint still to resume), `Some(None)` for a
/// run that ended, and `Some(Some(…))` too for a folder without a record whose `summary.json` says the run
/// diverged or stalled (a folder of an earlier version).
///
/// # Errors
/// A `summary.json` or record that cannot be read.
pub fn folder_end(dir: &Path) -> Result<Option<Option<String>>> {
    let failed = dir.join(layout::FAILED);
    if failed.is_file() {
        let text = std::fs::read_to_string(&failed).map_err(|e| crate::io::io_error(&failed, "read", e))?;
        return Ok(Some(Some(text.trim_end().to_string())));
    }
    let summary = dir.join(layout::SUMMARY);
    if !summary.is_file() || dir.join(layout::CHECKPOINT).exists() {
        return Ok(None);
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A run's end recorded in its folder and read back: a failure wins over a stale checkpoint (a run that
    /// diverged after checkpointing keeps it), a rerun that ends removes it, an input error is not a run's
    /// end, and a folder of an earlier version tells a divergence by its summary.
    #[test]
    fn a_runs_end_is_recorded_in_its_folder_and_read_back() {
        let dir = std::env::temp_dir().join(format!("ballast-tasks-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        assert_eq!(folder_end(&dir).unwrap(), None, "nothing run");
        let diverged = Error::Diverged { step: 7, body: 3, name: "g2".into(), what: "runaway overlap".into() };
        record(&dir, &Err(diverged)).unwrap();
        std::fs::write(dir.join(layout::CHECKPOINT), "{}").unwrap();
        let message = "step 7: body 3 ('g2'): runaway overlap".to_string();
        assert_eq!(folder_end(&dir).unwrap(), Some(Some(message.clone())));
        // An input error leaves the record as it was.
        record(&dir, &Err(Error::Scene("dt: must be positive".into()))).unwrap();
        assert_eq!(folder_end(&dir).unwrap(), Some(Some(message)));
        // Rerun and ended: no record; the checkpoint says the run is not finished, then its summary that it is.
        record(&dir, &Ok(())).unwrap();
        assert!(!dir.join(layout::FAILED).exists());
        assert_eq!(folder_end(&dir).unwrap(), None);
        std::fs::remove_file(dir.join(layout::CHECKPOINT)).unwrap();
        std::fs::write(dir.join(layout::SUMMARY), r#"{"end": "finished"}"#).unwrap();
        assert_eq!(folder_end(&dir).unwrap(), Some(None));
        std::fs::write(dir.join(layout::SUMMARY), r#"{"end": "diverged"}"#).unwrap();
        assert_eq!(folder_end(&dir).unwrap(), Some(Some("the run diverged (its summary.json)".into())));
        let folders = [("a".to_string(), dir.clone()), ("b".to_string(), dir.join("missing"))];
        let e = failures_from_folders(&folders).unwrap_err().to_string();
        assert!(e.contains("1 of 2 tasks have no finished run: b"), "{e}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
