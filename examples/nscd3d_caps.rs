//! How far a 3D NSCD step's Gauss–Seidel iterate is from where it goes: one step solved from the same state with
//! growing sweep caps, each iterate compared with the last one (the diagnosis behind docs/track3d.md, "What holds
//! the seated 2 000-grain section at `quad` 3e-5").
//!
//! `cargo run --release --example nscd3d_caps -- SCENE.toml RUN_DIR STEPS CAPS TOLERANCE [THREADS]`
//! - the state is that of `RUN_DIR/checkpoint.json` (a run of `SCENE.toml`, its warm start included) with the
//!   scene's `[nscd]` settings, as `ballast run --resume --change-solver` takes them; `STEPS` steps are made
//!   first with those settings;
//! - then the next step is solved once per cap of `CAPS` (comma separated, growing), each from that same state,
//!   with the scene's settings but `max_iterations` = the cap and `tolerance` = `TOLERANCE` (e.g. 1e-12 to make
//!   every solve run to its cap);
//! - printed per cap: sweeps, converged, wall time; the contact points' states (open: `P_N` = 0; sliding:
//!   `|P_T| ≥ (1 − 1e-6) μ P_N`; sticking otherwise) against the last cap's, as a 3 × 3 table (rows: this cap,
//!   columns: the last; open, sticking, sliding); the mass-weighted relative difference of the translational
//!   velocities of the mobile bodies but the sleeper (the grains and the sublayer's pads) from the last cap's,
//!   `sqrt(Σ m |Δv|² / Σ m |v|²)`; the vertical velocity of the
//!   body named `sleeper` (m/s; the `z` component), which the settlement integrates.

use ballast::nscd::d3::system::System3;
use std::collections::HashMap;
use std::time::Instant;

#[path = "common/resumed.rs"]
mod resumed;

/// A point's state: 0 open, 1 sticking, 2 sliding.
fn states(sys: &System3) -> HashMap<(u32, u32, u32), usize> {
    let state = |p: [f64; 3], mu: f64| {
        if p[0] <= 0.0 {
            0
        } else if p[1].hypot(p[2]) >= (1.0 - 1e-6) * mu * p[0] {
            2
        } else {
            1
        }
    };
    let mu = |a: u32, b: u32| sys.law(a as usize, b as usize).friction;
    sys.contacts().iter().map(|c| (c.key, state(c.p, mu(c.key.0, c.key.1)))).collect()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: nscd3d_caps SCENE.toml RUN_DIR STEPS CAPS TOLERANCE [THREADS]";
    if args.len() < 5 {
        return Err(usage.into());
    }
    let steps: u64 = args[2].parse()?;
    let caps: Vec<usize> = args[3].split(',').map(str::parse).collect::<Result<_, _>>()?;
    let tolerance: f64 = args[4].parse()?;
    let threads: usize = args.get(5).map_or(Ok(2), |s| s.parse())?;
    let mut sys = resumed::system(&args[0], Some(&args[1]))?;
    sys.set_threads(threads);
    for _ in 0..steps {
        sys.step()?;
    }
    let sleeper = sys.bodies.info.iter().position(|b| b.name == "sleeper").ok_or("no body named sleeper")?;
    let mut solved = Vec::new();
    for &cap in &caps {
        let mut s = sys.clone();
        (s.params.nlgs.max_iterations, s.params.nlgs.tolerance) = (cap, tolerance);
        let t = Instant::now();
        let stats = s.step()?;
        let wall = t.elapsed().as_secs_f64();
        println!("cap {cap}: {} sweeps, converged {}, {wall:.1} s", stats.nlgs.iterations, stats.nlgs.converged);
        solved.push((cap, states(&s), s.bodies.u.clone()));
    }
    let (_, last, u_last) = solved.last().ok_or("CAPS is empty")?;
    let count = |k: usize| last.values().filter(|&&s| s == k).count();
    println!("last cap: {} points open, {} sticking, {} sliding", count(0), count(1), count(2));
    for (cap, st, u) in &solved {
        let mut table = [[0usize; 3]; 3];
        for (key, &s) in st {
            if let Some(&t) = last.get(key) {
                table[s][t] += 1;
            }
        }
        let (mut d2, mut v2) = (0.0, 0.0);
        for (i, (ui, li)) in u.iter().zip(u_last).enumerate() {
            let im = sys.bodies.inv_m[i][0];
            if im > 0.0 && i != sleeper {
                d2 += (0..3).map(|k| (ui[k] - li[k]).powi(2)).sum::<f64>() / im;
                v2 += (0..3).map(|k| li[k].powi(2)).sum::<f64>() / im;
            }
        }
        println!(
            "cap {cap}: states (rows this cap, columns the last; open, sticking, sliding) {table:?}; grains' \
             velocities {:.3e} from the last; sleeper w {:.6e} m/s (last {:.6e})",
            if v2 > 0.0 { (d2 / v2).sqrt() } else { 0.0 },
            u[sleeper][2],
            u_last[sleeper][2]
        );
    }
    Ok(())
}
