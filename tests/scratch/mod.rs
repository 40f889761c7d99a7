//! Scratch folders of the integration tests: one per test file and tag, in a folder of the process under the
//! system's temporary folder (`ballast-tests-<pid>/<file>-<tag>`), emptied first when an earlier run left one
//! behind. The one temp-dir helper of `tests/`. A run's folders stay for inspection after it ends; the first
//! scratch folder of the next run removes the folders of test processes that are no longer running (on Linux,
//! where `/proc` says which are), so at most the last run's outputs stay behind.

// Each test file uses one or both of these.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// The path of the scratch folder `tag` of the calling test file, removed if it exists (and not created: for
/// outputs that a run or a command creates itself). The files share one test binary (`tests/main.rs`), so the
/// folder is named by the caller's file: two files may use the same tag at once.
#[track_caller]
pub fn path(tag: &str) -> PathBuf {
    let caller = Path::new(std::panic::Location::caller().file());
    // `tests/x.rs` is `x`; a helper `tests/x/mod.rs` is `x` too.
    let file = match caller.file_stem().and_then(|s| s.to_str()) {
        Some("mod") => caller.parent().and_then(|p| p.file_name()),
        _ => caller.file_stem(),
    };
    let file = file.map_or("tests".into(), |f| f.to_string_lossy());
    static SWEPT: std::sync::Once = std::sync::Once::new();
    SWEPT.call_once(remove_finished_runs);
    let dir = std::env::temp_dir().join(format!("ballast-tests-{}", std::process::id())).join(format!("{file}-{tag}"));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// Removes the scratch folders of test processes that have ended (Linux: no `/proc/<pid>`); elsewhere nothing.
fn remove_finished_runs() {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(std::env::temp_dir()) else { return };
    for entry in entries.flatten() {
        let name = entry.file_name();
        let pid = name.to_str().and_then(|n| n.strip_prefix("ballast-tests-")).and_then(|p| p.parse::<u32>().ok());
        if let Some(pid) = pid {
            if pid != std::process::id() && !Path::new(&format!("/proc/{pid}")).exists() {
                let _ = std::fs::remove_dir_all(entry.path());
            }
        }
    }
}

/// The scratch folder `tag` of the calling test file, created empty.
#[track_caller]
pub fn dir(tag: &str) -> PathBuf {
    let dir = path(tag);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
