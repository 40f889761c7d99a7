//! Generates a loose pentagon deposit with the Saussine grading, deposits it
//! under gravity and saves the settled pile as a scene.
//!
//! `cargo run --release --example make_pile -- [N] [WIDTH] [SEED] [OUT]`
//! (defaults: 536 grains, 0.4 m, seed 1, `data/pentagon_pile_536.toml`).

use ballast::scenarios::{pentagon_deposit, DepositSpec};
use ballast::scene::SceneFile;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).map_or(Ok(536), |s| s.parse())?;
    let width: f64 = args.get(2).map_or(Ok(0.4), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(1), |s| s.parse())?;
    let out = args.get(4).cloned().unwrap_or_else(|| format!("data/pentagon_pile_{n}.toml"));
    let spec = DepositSpec { duration: 2.5, ..DepositSpec::saussine(n, width, seed) };
    let scene = pentagon_deposit(&spec)?;
    let mut sys = scene.build()?;
    let start = Instant::now();
    let (mut iters, mut steps) = (0usize, 0usize);
    for k in 0..scene.steps() {
        let st = sys.step()?;
        iters += st.iterations;
        steps += 1;
        if k % 1000 == 0 {
            eprintln!(
                "t = {:.3} s  KE = {:.3e} J  contacts {}  iterations {}  max overlap {:.2e} m",
                st.time, st.kinetic_energy, st.contacts, st.iterations, st.max_overlap
            );
        }
    }
    eprintln!(
        "{steps} steps in {:.1} s, mean {:.1} iterations/step",
        start.elapsed().as_secs_f64(),
        iters as f64 / steps as f64
    );
    let mut settled = scene.with_state(&sys);
    settled.simulation.duration = 0.1;
    std::fs::write(&out, settled.to_toml_string()?)?;
    eprintln!("wrote {out}");
    Ok(())
}
