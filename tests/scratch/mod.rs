//! Scratch folders of the integration tests: one per test file, process and tag, under the system's
//! temporary folder, emptied first when an earlier run left one behind. The one temp-dir helper of `tests/`.

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
    let dir = std::env::temp_dir().join(format!("ballast-{file}-{}-{tag}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The scratch folder `tag` of the calling test file, created empty.
#[track_caller]
pub fn dir(tag: &str) -> PathBuf {
    let dir = path(tag);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
