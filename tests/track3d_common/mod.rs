//! The 24-grain sample of the 3D track section's tests (`tests/track3d.rs`, `tests/track3d_replicas.rs`),
//! deposited once per test process (the two files share `tests/main.rs`'s binary) into its scratch folder,
//! helpers on its scenes, and the command line.

// Each test file uses some of these.
#![allow(dead_code)]

use crate::scratch;
use ballast::scenarios::track3d::SampleSpec;
use ballast::scene::Scene3;
use ballast::studies::track3d::{self as study, Sample};
use ballast::studies::Quiet;
use std::path::PathBuf;
use std::sync::OnceLock;

/// Grains of the sample.
pub const GRAINS: usize = 24;
/// The loaded runs' step (s): 50 steps per cycle, for a test of seconds.
pub const LOAD_DT: f64 = 1e-3;

/// The sample: 24 grains (seed 3) in a 0.12 × 0.1 m box on 4 × 3 pads of 25 mm (the full section's rules on a
/// box two grains deep), deposited once into a scratch folder; for a test of seconds, dt = 5e-4 s, `quad` 1e-3
/// and a 100-step rest window (the defaults: 2e-4 s, 1e-3, 500 steps).
pub fn sample() -> &'static (PathBuf, Sample) {
    static SAMPLE: OnceLock<(PathBuf, Sample)> = OnceLock::new();
    SAMPLE.get_or_init(|| {
        let dir = scratch::path("sample");
        let spec = SampleSpec {
            length: 0.12,
            width: 0.1,
            pad_size: 0.025,
            dt: 5e-4,
            tolerance: 1e-3,
            max_iterations: 1000,
            rest_steps: 100,
            ..SampleSpec::track(3).scaled(GRAINS)
        };
        let s = study::sample(&spec, &dir, false, &Quiet).expect("the deposit runs to equilibrium");
        (dir, s)
    })
}

/// The bodies of `scene` named `prefix` + digits.
pub fn named(scene: &Scene3, prefix: &str) -> Vec<usize> {
    let is = |n: &str| n.strip_prefix(prefix).is_some_and(|r| !r.is_empty() && r.chars().all(|c| c.is_ascii_digit()));
    scene.bodies.iter().enumerate().filter(|(_, b)| is(&b.name)).map(|(i, _)| i).collect()
}

/// Runs the `ballast` binary with `args`: its exit code and standard error.
pub fn ballast(args: &[&str]) -> (i32, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_ballast")).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Asserts that the command line refuses `args` on one line led by `error: <flag>`, exit code 2.
pub fn refused(args: &[&str], flag: &str) {
    let (code, err) = ballast(args);
    assert_eq!(code, 2, "{args:?}: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{args:?}: {err}");
    assert!(err.starts_with(&format!("error: {flag}")), "{args:?}: {err}");
}
