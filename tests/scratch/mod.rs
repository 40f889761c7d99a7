//! Scratch folders of the integration tests: one per test binary, process and tag, under the system's
//! temporary folder, emptied first when an earlier run left one behind. The one temp-dir helper of `tests/`.

// Each test binary uses one or both of these.
#![allow(dead_code)]

use std::path::PathBuf;

/// The path of the scratch folder `tag` of this test binary, removed if it exists (and not created: for
/// outputs that a run or a command creates itself).
pub fn path(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("ballast-{}-{}-{tag}", env!("CARGO_CRATE_NAME"), std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The scratch folder `tag` of this test binary, created empty.
pub fn dir(tag: &str) -> PathBuf {
    let dir = path(tag);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
