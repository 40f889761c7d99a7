//! `ballast compare`: NSCD versus soft-contact MD on the same loaded 2D sample
//! ([`ballast::studies::compare`]), the MD runs at each overlap ratio, each
//! setting with replicas from perturbed starts, side by side.

use super::saussine::{LoadingArgs, ReplicaArgs, StudyArgs};
use super::{Bars, Failure};
use ballast::studies::compare::{self, CompareSpec, DEFAULT_OVERLAPS};
use std::path::PathBuf;

/// The arguments of `ballast compare`.
#[derive(Debug, clap::Args)]
pub struct CompareArgs {
    /// A deposited sample (`saussine sample`'s sample.toml, loaded with the loading options) or a
    /// loaded 2D scene with a followed body ([output.cycles] body; only --cycles applies to it).
    #[arg(long, value_name = "FILE")]
    sample: PathBuf,
    /// MD settings: the overlap of a base contact under the peak load over the smallest
    /// inradius ([soft] max_overlap_ratio), comma separated.
    #[arg(long, value_delimiter = ',', default_values_t = DEFAULT_OVERLAPS)]
    overlaps: Vec<f64>,
    /// MD contact law: linear or hertz.
    #[arg(long, default_value = "linear")]
    model: String,
    /// MD time step as a fraction of the contact time ([soft] dt_fraction; default: the engine's).
    #[arg(long)]
    dt_fraction: Option<f64>,
    #[command(flatten)]
    replicas: ReplicaArgs,
    #[command(flatten)]
    loading: LoadingArgs,
    #[command(flatten)]
    study: StudyArgs,
}

/// Runs `ballast compare`.
pub fn main(args: CompareArgs) -> Result<(), Failure> {
    let spec = CompareSpec {
        sample: args.sample,
        overlaps: args.overlaps,
        model: args.model,
        dt_fraction: args.dt_fraction,
        replicas: args.replicas.replicas(),
        loading: args.loading.loading()?,
    };
    let bars = Bars::group(args.study.quiet);
    args.study.run((spec.task_count(), 0), |o| compare::compare(&spec, o, &bars), |r| &r.study.failed, print)
}

/// The failed runs, `compare.md` and where the outputs are.
fn print(report: &compare::CompareReport) {
    let Some(table) = &report.study.table else {
        return super::print_study(&report.study);
    };
    for (label, e) in &report.study.failed {
        eprintln!("run {label} failed: {e}");
    }
    let md = table.path.with_file_name("compare.md");
    match std::fs::read_to_string(&md) {
        Ok(text) => println!("{text}"),
        Err(e) => eprintln!("{}: {e}", md.display()),
    }
    println!("per cycle: {}; runs in {}", table.path.display(), report.study.runs.display());
}
