//! `ballast deposit`: writes the scene of a loose pentagon deposit.

use super::{input, Failure};
use ballast::scene::SceneFile;
use std::path::PathBuf;

/// The arguments of `ballast deposit`.
#[derive(Debug, clap::Args)]
pub struct DepositArgs {
    /// Number of grains.
    #[arg(long, default_value_t = 724)]
    grains: usize,
    /// Inner width of the box (m).
    #[arg(long, default_value_t = 0.5)]
    width: f64,
    /// Seed of the random positions, orientations and velocities.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Time step (s).
    #[arg(long, default_value_t = 2e-4)]
    dt: f64,
    /// Simulated time of the deposit (s).
    #[arg(long, default_value_t = 2.0)]
    duration: f64,
    /// Output scene file.
    #[arg(long, value_name = "FILE")]
    out: PathBuf,
}

/// `ballast deposit`: generates, validates and writes a loose deposit scene.
pub fn main(a: DepositArgs) -> Result<(), Failure> {
    use ballast::scenarios::{pentagon_deposit, DepositSpec};
    if a.grains == 0 || !(a.width.is_finite() && a.width > 0.0) {
        return Err(input(format!(
            "deposit: need at least one grain and a positive width, got {} grains and {} m",
            a.grains, a.width
        )));
    }
    let spec = DepositSpec { dt: a.dt, duration: a.duration, ..DepositSpec::saussine(a.grains, a.width, a.seed) };
    // The generated scene goes through the same validation as any scene file.
    let scene = pentagon_deposit(&spec).map_err(Failure::Input)?;
    let text = format!(
        "# Loose pentagon deposit: {} grains, seed {}.\n{}",
        a.grains,
        a.seed,
        scene.to_toml_string().map_err(Failure::Run)?
    );
    std::fs::write(&a.out, text).map_err(|e| Failure::Run(ballast::io::io_error(&a.out, "write", e)))?;
    println!("wrote {} ({} grains, seed {})", a.out.display(), a.grains, a.seed);
    Ok(())
}
