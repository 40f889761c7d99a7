//! Where Gauss–Seidel stalls on one frozen 3D NSCD step, and three cheap ways around the stall measured there (the
//! diagnosis behind docs/track3d.md, "The plateau of the sweeps, and the section seating under `quad` 3e-5").
//!
//! `cargo run --release --example nscd3d_plateau -- SCENE.toml RUN_DIR SWEEPS EVERY [MODE] [TOP]`
//! - the state is that of `RUN_DIR/checkpoint.json` (a run of `SCENE.toml`) with the scene's `[nscd]` settings,
//!   as `ballast run --resume --change-solver` takes them; one step is made with them on one thread (give the
//!   scene a small `max_iterations` to start from an early iterate), and its problem is frozen
//!   ([`ballast::nscd::d3::system::System3::nlgs_problem`]) with the step's last impulses;
//! - then `SWEEPS` more serial forward sweeps on that problem; every `EVERY` sweeps the check pass of the iterate
//!   (LMGC90's, as the stopping rule measures it) prints `QuadDV` and `QuadDVR`, the share of `QuadDVR`² held by
//!   the `TOP` (default 100) leading points, how many of them led at the last check and at the first, and how many
//!   bodies they touch; beside it the same check of the iterate averaged over the `EVERY` sweeps (impulses
//!   averaged, velocities `u_free + M⁻¹ H P̄`), which is within the cones (they are convex);
//! - `MODE` (default `plain`): `local=L` adds, after each check, `L` sweeps over the `TOP` leading points alone;
//!   `ring=L` the same over every point that shares a body with them; `extrapolate` moves the impulses along
//!   their drift since the last check, `P + β (P − P_last)` projected on each point's cone for `β` in 1, 3, 10,
//!   30 and 100, and keeps the best by the check if it beats the iterate's. The column `work` counts row visits
//!   in sweeps of the whole problem: a check costs one, a trial two; the averaged iterate's check is a diagnosis
//!   and is not counted.

use ballast::nscd::d3::cone::project_cone;
use ballast::nscd::d3::contact::ContactRow3;
use ballast::nscd::d3::spring::SpringRow3;
use ballast::nscd::method::{apply_impulses, check, check_by_row, sweep, SweepNorms};
use std::collections::HashSet;

#[path = "common/resumed.rs"]
mod resumed;

/// What is done between two checks besides the sweeps.
#[derive(Clone, Copy, PartialEq)]
enum Mode {
    Plain,
    /// Sweeps over the leading points (with their bodies' other points when the flag is set).
    Local(usize, bool),
    Extrapolate,
}

fn mode(s: &str) -> Option<Mode> {
    let sweeps = |v: &str| v.parse().ok();
    match s.split_once('=') {
        None if s == "plain" => Some(Mode::Plain),
        None if s == "extrapolate" => Some(Mode::Extrapolate),
        Some(("local", v)) => sweeps(v).map(|l| Mode::Local(l, false)),
        Some(("ring", v)) => sweeps(v).map(|l| Mode::Local(l, true)),
        _ => None,
    }
}

/// The check pass of an iterate (which writes nothing): per point, and the whole `(QuadDV, QuadDVR)`.
fn checked(
    u: &mut [[f64; 6]],
    inv_m: &[[f64; 6]],
    rows: &mut [ContactRow3],
    springs: &mut [SpringRow3],
) -> (Vec<SweepNorms>, [f64; 2]) {
    let (of_springs, per) = check_by_row(u, inv_m, rows, springs);
    let total = per.iter().chain(&of_springs).fold(SweepNorms::default(), |a, b| a.merged(*b)).norms();
    (per, [total[0], total[2]])
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: nscd3d_plateau SCENE.toml RUN_DIR SWEEPS EVERY [plain|local=L|ring=L|extrapolate] [TOP]";
    let [scene, run, sweeps, every] = [0, 1, 2, 3].map(|i| args.get(i).ok_or(usage));
    let (sweeps, every): (usize, usize) = (sweeps?.parse()?, every?.parse()?);
    let mode = mode(args.get(4).map_or("plain", String::as_str)).ok_or(usage)?;
    let top: usize = args.get(5).map_or(Ok(100), |s| s.parse())?;
    if every == 0 {
        return Err(usage.into());
    }
    let mut sys = resumed::system(scene?, Some(run?))?;
    sys.set_threads(1);
    let stats = sys.step()?;
    println!("step {}: {} sweeps, converged {}", sys.steps, stats.nlgs.iterations, stats.nlgs.converged);
    let problem = sys.nlgs_problem().ok_or("the step left no problem")?;
    let (u_free, inv_m, mut rows, mut springs) = (problem.u, problem.inv_m, problem.rows, problem.springs);
    let mut u = u_free.clone();
    apply_impulses(&mut u, &inv_m, &rows, &springs);
    let n = rows.len().max(1);
    let (mut work, mut done) = (0, 0);
    let (mut first, mut last) = (None::<HashSet<usize>>, HashSet::new());
    let mut before: Vec<[f64; 3]> = rows.iter().map(|r| r.p).collect();
    let mut sum_p = vec![[0.0; 3]; rows.len()];
    let mut sum_s = vec![0.0; springs.len()];
    while done < sweeps {
        sum_p.iter_mut().for_each(|s| *s = [0.0; 3]);
        sum_s.iter_mut().for_each(|s| *s = 0.0);
        for _ in 0..every {
            sweep(&mut u, &inv_m, &mut rows, &mut springs, false);
            work += n;
            for (s, r) in sum_p.iter_mut().zip(&rows) {
                (0..3).for_each(|k| s[k] += r.p[k]);
            }
            for (s, r) in sum_s.iter_mut().zip(&springs) {
                *s += r.p;
            }
        }
        done += every;
        let (per, norms) = checked(&mut u, &inv_m, &mut rows, &mut springs);
        work += n;
        let (mut ra, mut sa) = (rows.clone(), springs.clone());
        ra.iter_mut().zip(&sum_p).for_each(|(r, s)| r.p = s.map(|x| x / every as f64));
        sa.iter_mut().zip(&sum_s).for_each(|(r, s)| r.p = s / every as f64);
        let mut ua = u_free.clone();
        apply_impulses(&mut ua, &inv_m, &ra, &sa);
        let averaged = check(&mut ua, &inv_m, &mut ra, &mut sa).norms();
        let mut order: Vec<usize> = (0..rows.len()).collect();
        order.sort_by(|&i, &j| per[j].sum_dvdvrr.total_cmp(&per[i].sum_dvdvrr));
        let leading: HashSet<usize> = order.iter().take(top).copied().collect();
        let total: f64 = per.iter().map(|p| p.sum_dvdvrr).sum();
        let share = order.iter().take(top).map(|&i| per[i].sum_dvdvrr).sum::<f64>() / total.max(f64::MIN_POSITIVE);
        let bodies: HashSet<u32> = leading.iter().flat_map(|&i| [rows[i].a, rows[i].b]).collect();
        let first = first.get_or_insert_with(|| leading.clone());
        print!(
            "{done:6} work {:7} QuadDV {:.3e} QuadDVR {:.3e} top {share:.3} (led last {:3}, first {:3}, {:3} bodies) \
             averaged {:.3e} {:.3e}",
            work / n,
            norms[0],
            norms[1],
            leading.intersection(&last).count(),
            leading.intersection(first).count(),
            bodies.len(),
            averaged[0],
            averaged[2]
        );
        match mode {
            Mode::Plain => {}
            Mode::Local(local, ring) => {
                let mut pick: Vec<usize> = leading.iter().copied().collect();
                if ring {
                    pick = (0..rows.len())
                        .filter(|&i| bodies.contains(&rows[i].a) || bodies.contains(&rows[i].b))
                        .collect();
                }
                pick.sort_unstable();
                let mut sub: Vec<ContactRow3> = pick.iter().map(|&i| rows[i]).collect();
                for _ in 0..local {
                    sweep(&mut u, &inv_m, &mut sub, &mut [] as &mut [SpringRow3], false);
                    work += sub.len();
                }
                pick.iter().zip(&sub).for_each(|(&i, r)| rows[i] = *r);
                print!(" | {} points swept {local} times", pick.len());
            }
            Mode::Extrapolate => {
                let mut best = (norms[1], 0.0, None);
                for beta in [1.0, 3.0, 10.0, 30.0, 100.0] {
                    let mut trial = rows.clone();
                    for (r, b) in trial.iter_mut().zip(&before) {
                        r.p = project_cone([0, 1, 2].map(|k| r.p[k] + beta * (r.p[k] - b[k])), r.mu);
                    }
                    let mut ut = u_free.clone();
                    apply_impulses(&mut ut, &inv_m, &trial, &springs);
                    let value = check(&mut ut, &inv_m, &mut trial, &mut springs).norms()[2];
                    work += 2 * n;
                    print!(" | β {beta}: {value:.2e}");
                    if value < best.0 {
                        best = (value, beta, Some((trial, ut)));
                    }
                }
                print!(" -> β {}", best.1);
                if let (_, _, Some((trial, ut))) = best {
                    (rows, u) = (trial, ut);
                }
            }
        }
        println!();
        last = leading;
        before = rows.iter().map(|r| r.p).collect();
    }
    Ok(())
}
