//! `ballast figures DIR`: the figures of a finished run folder of either engine,
//! drawn from its files alone ([`ballast::report::draw_run_figures`]);
//! with `--reference FULL`, an accelerated run's errors against a full run
//! ([`ballast::report::settlement::draw`]), measured after the run, e.g. when
//! the full run finished later.

use super::{input, Failure};
use ballast::io::layout::{self, SETTLEMENT};
use std::path::PathBuf;

/// The arguments of `ballast figures`.
#[derive(Debug, clap::Args)]
pub struct FiguresArgs {
    /// The output folder of a finished run (`ballast run --out DIR`).
    dir: PathBuf,
    /// For an accelerated run (a folder with settlement.csv): the folder of a full
    /// run of the same scene; writes errors.csv (settlement, error on what accrued
    /// after the initial cycles, coordination, E_r of eq. 22) and draws both curves.
    #[arg(long, value_name = "FULL")]
    reference: Option<PathBuf>,
}

/// `ballast figures`: draws, then prints each figure written and each skipped.
pub fn main(a: FiguresArgs) -> Result<(), Failure> {
    let figures = match &a.reference {
        None => ballast::report::draw_run_figures(&a.dir)?,
        Some(reference) => {
            if !a.dir.join(layout::SETTLEMENT).is_file() {
                return Err(input(format!(
                    "--reference: '{}' has no {SETTLEMENT} (the errors are those of an accelerated run)",
                    a.dir.display()
                )));
            }
            ballast::report::settlement::draw(&a.dir, Some(reference))?
        }
    };
    for stem in &figures.written {
        println!("wrote {}.png, .svg", stem.display());
    }
    for (stem, why) in &figures.skipped {
        println!("skipped {stem}: {why}");
    }
    if a.reference.is_some() {
        let summary: ballast::settlement::AccelerationSummary = ballast::io::read_json(&a.dir.join(layout::SUMMARY))?;
        super::saussine::print_errors(&a.dir, &summary)?;
    }
    Ok(())
}
