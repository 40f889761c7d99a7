//! `ballast figures DIR`: the figures of a finished run folder of either engine,
//! drawn from its files alone ([`ballast::io::run_figures::draw_run_figures`]).

use super::Failure;
use std::path::PathBuf;

/// The arguments of `ballast figures`.
#[derive(Debug, clap::Args)]
pub struct FiguresArgs {
    /// The output folder of a finished run (`ballast run --out DIR`).
    dir: PathBuf,
}

/// `ballast figures`: draws, then prints each figure written and each skipped.
pub fn main(a: FiguresArgs) -> Result<(), Failure> {
    let figures = ballast::io::run_figures::draw_run_figures(&a.dir)?;
    for stem in &figures.written {
        println!("wrote {}.png, .svg", stem.display());
    }
    for (stem, why) in &figures.skipped {
        println!("skipped {stem}: {why}");
    }
    Ok(())
}
