//! The MD benchmark bed (`../shared/peers/md-bed`): settles N Hertz–Mindlin
//! spheres for 100 000 steps (+ 20 000, as the peers do), then times 3 × 10 000
//! steps on the settled bed with 1 and 2 threads and prints particle-steps per
//! second and the settled bed height (highest sphere centre).
//!
//! `cargo run --release --example md_bed -- [N] [settle_steps] [timed_steps]`

use ballast::md::MdSystem;
use ballast::scenarios::md_bed::{bed_system, top_centre, BedSpec};
use std::time::Instant;

fn main() {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse().expect("integer argument")).collect();
    let n = args.first().copied().unwrap_or(2000);
    let settle = args.get(1).copied().unwrap_or(120_000);
    let timed = args.get(2).copied().unwrap_or(10_000);
    // BED_CACHE=FILE: reuse a settled bed saved by an earlier run (JSON).
    let cache = std::env::var("BED_CACHE").ok();
    let cached: Option<MdSystem> =
        cache.as_ref().and_then(|f| std::fs::read_to_string(f).ok()).and_then(|t| serde_json::from_str(&t).ok());
    let settle = if cached.is_some() { 0 } else { settle };
    let mut sys = match cached.map_or_else(|| bed_system(&BedSpec::peers(n, 12345)), Ok) {
        Ok(sys) => sys,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    sys.set_threads(2);
    let t0 = Instant::now();
    for k in 0..settle {
        if let Err(e) = sys.step() {
            eprintln!("settling failed: {e}");
            std::process::exit(1);
        }
        if k % 20_000 == 0 {
            println!(
                "step {k}: Ek {:.3e} J, top centre {:.4} m, contacts {}",
                sys.last.kinetic_energy,
                top_centre(&sys),
                sys.last.contacts
            );
        }
    }
    let settle_s = t0.elapsed().as_secs_f64();
    println!(
        "settled {n} spheres in {settle} steps, {settle_s:.1} s ({:.2} M particle-steps/s on 2 threads); top centre {:.4} m; \
         Ek {:.3e} J; {} neighbour builds; {} listed pairs, {} contacts, {} wall contacts",
        n as f64 * settle as f64 / settle_s / 1e6,
        top_centre(&sys),
        sys.last.kinetic_energy,
        sys.neighbours.builds,
        sys.neighbours.pairs(),
        sys.last.contacts,
        sys.last.wall_contacts
    );
    if let (Some(f), 0) = (&cache, settle) {
        println!("loaded the settled bed from {f}");
    } else if let Some(f) = &cache {
        std::fs::write(f, serde_json::to_string(&sys).expect("serialise")).expect("write cache");
    }
    // BED_THREADS=1 or =2: time only that count (default both).
    let only: Option<usize> = std::env::var("BED_THREADS").ok().and_then(|t| t.parse().ok());
    for threads in [1, 2].into_iter().filter(|t| only.is_none_or(|o| o == *t)) {
        let mut run = sys.clone();
        run.set_threads(threads);
        // Energies and overlap statistics every 10 000 steps, as the peers' thermo output.
        run.measure_every = 10_000;
        for rep in 0..3 {
            let t = Instant::now();
            for _ in 0..timed {
                run.step().expect("dense run");
            }
            let s = t.elapsed().as_secs_f64();
            println!("threads {threads} run {rep}: {:.2} M particle-steps/s", n as f64 * timed as f64 / s / 1e6);
        }
    }
}
