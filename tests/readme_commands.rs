//! Every `ballast …` command of README.md's `sh` blocks runs, in the README's
//! order (later commands read what earlier ones wrote, as a reader typing them
//! would), from a folder holding the repository's `examples/`, at a size CI can
//! afford: each command gets the options of its subcommand in [`REDUCTIONS`]
//! (an option present is given the reduced value, an absent one is added). A
//! README command whose subcommand is not listed fails the test, so a new
//! command cannot be documented without being run here.
//!
//! The `cargo …` lines (install, test, bench, examples) are toolchain
//! commands: the examples and benches are built by `cargo clippy
//! --all-targets` in CI, the tests by this very run.

use crate::scratch;

use std::path::Path;
use std::process::Command;

/// Reduced options per subcommand: `(subcommand words, [(option, value)])`;
/// an empty value is a flag.
const REDUCTIONS: &[(&str, &[(&str, &str)])] = &[
    ("run", &[("--steps", "20"), ("--quiet", "")]),
    // 10 cycles: 2 initial, 4 computed, a jump of 4 (20 steps would hold no cycle).
    ("run examples/settlement_sleeper.toml", &[("--steps", "2500"), ("--quiet", "")]),
    ("figures", &[]),
    (
        "compare",
        &[
            ("--overlaps", "1e-1"),
            ("--cycles", "1"),
            ("--dt", "1e-3"),
            ("--bars", "0"),
            ("--replicas", "2"),
            ("--quiet", ""),
        ],
    ),
    ("deposit", &[("--grains", "16"), ("--width", "0.1")]),
    ("saussine sample", &[("--grains", "60"), ("--dt", "1e-4"), ("--quiet", "")]),
    ("saussine settle", &[("--cycles", "1"), ("--dt", "1e-3"), ("--bars", "0"), ("--quiet", "")]),
    (
        "saussine convergence",
        &[
            ("--policies", "quad:1e-2"),
            ("--cycles", "1"),
            ("--dt", "1e-3"),
            ("--bars", "0"),
            ("--quiet", ""),
            ("--replicas", "2"),
        ],
    ),
    (
        "saussine steps",
        &[("--dts", "1e-3"), ("--inclinations", "0"), ("--cycles", "1"), ("--bars", "0"), ("--quiet", "")],
    ),
    (
        "saussine ensemble",
        &[
            ("--samples", "1"),
            ("--factors", "1"),
            ("--grains", "50"),
            ("--sample-dt", "5e-4"),
            ("--cycles", "1"),
            ("--dt", "1e-3"),
            ("--quiet", ""),
        ],
    ),
    (
        "karrech deposit",
        &[
            ("--spheres", "40"),
            ("--young", "1e7"),
            ("--dt", "2e-6"),
            ("--duration", "0.6"),
            ("--every", "1000"),
            ("--quiet", ""),
        ],
    ),
    ("karrech load", &[("--cycles", "1"), ("--every", "500"), ("--quiet", "")]),
    ("luding compress", &[("--spheres", "27"), ("--duration", "3"), ("--every", "2000"), ("--quiet", "")]),
    ("luding cycle", &[("--cycles", "1"), ("--every", "1000"), ("--quiet", "")]),
    ("luding compare", &[]),
];

/// The `ballast` commands of the `sh` blocks of `text`, continuation lines
/// joined and comments removed, as argument lists (without `ballast`).
fn commands(text: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut in_sh = false;
    let mut pending = String::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_sh = line.trim() == "```sh";
            continue;
        }
        if !in_sh {
            continue;
        }
        let code = line.split(" #").next().unwrap_or("").trim_end();
        if code.trim_start().starts_with('#') {
            continue;
        }
        if let Some(head) = code.strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(code);
        let words: Vec<String> = pending.split_whitespace().map(String::from).collect();
        pending.clear();
        if words.first().map(String::as_str) == Some("ballast") {
            out.push(words[1..].to_vec());
        }
    }
    out
}

/// `args` with the reduced options of their subcommand.
fn reduced(args: &[String]) -> Vec<String> {
    let (_, options) = REDUCTIONS
        .iter()
        .filter(|(sub, _)| {
            let words: Vec<&str> = sub.split(' ').collect();
            args.len() >= words.len() && args.iter().zip(&words).all(|(a, w)| a == w)
        })
        .max_by_key(|(sub, _)| sub.len())
        .unwrap_or_else(|| panic!("README command `ballast {}` has no reduction in REDUCTIONS", args.join(" ")));
    let mut out = args.to_vec();
    for (option, value) in options.iter() {
        match out.iter().position(|a| a == option) {
            Some(i) if !value.is_empty() => out[i + 1] = value.to_string(),
            Some(_) => {}
            None => {
                out.push(option.to_string());
                if !value.is_empty() {
                    out.push(value.to_string());
                }
            }
        }
    }
    out
}

#[test]
fn every_readme_command_runs() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let readme = std::fs::read_to_string(root.join("README.md")).unwrap();
    let cmds = commands(&readme);
    // The README's main kinds of run must be among them (the parser found the blocks).
    for sub in ["run", "saussine sample", "karrech deposit", "luding compare", "figures"] {
        assert!(cmds.iter().any(|c| c.join(" ").starts_with(sub)), "no `ballast {sub}` found in README.md");
    }
    let dir = scratch::dir("readme");
    std::os::unix::fs::symlink(root.join("examples"), dir.join("examples")).unwrap();
    for args in &cmds {
        let args = reduced(args);
        let start = std::time::Instant::now();
        let r = Command::new(env!("CARGO_BIN_EXE_ballast")).args(&args).current_dir(&dir).output().unwrap();
        assert!(
            r.status.success(),
            "`ballast {}` failed:\n{}{}",
            args.join(" "),
            String::from_utf8_lossy(&r.stdout),
            String::from_utf8_lossy(&r.stderr)
        );
        eprintln!("ballast {}: {:.1} s", args.join(" "), start.elapsed().as_secs_f64());
    }
    let _ = std::fs::remove_dir_all(&dir);
}
