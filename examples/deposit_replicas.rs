//! The noise floor of a deposit: the same NSCD scene run to its end (or its
//! equilibrium) from starts perturbed by `PERTURBATION` (each mobile body moved
//! by a random vector of that length, seeded), in the split NLGS order and in
//! the plain one (`split_min_rows = 0`), so that a change of one number of a
//! single run (steps to equilibrium, final overlap) can be told from chaos.
//!
//! `cargo run --release --example deposit_replicas -- SCENE OUT REPLICAS [serial|split] [FIRST]`
//! writes `OUT/<order>-<i>/` for each replica and prints one CSV line per run
//! (replica 0 is the unperturbed start).

use ballast::run::{Engine, RunOptions, Runner};
use ballast::scene::Scene;
use rand::{RngExt, SeedableRng};
use std::path::PathBuf;

/// Length of each body's start displacement, m (the guide's replica size).
const PERTURBATION: f64 = 1e-9;

fn main() -> Result<(), ballast::Error> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: deposit_replicas SCENE OUT REPLICAS [serial|split] [FIRST]");
        std::process::exit(2);
    }
    let scene = Scene::load(&args[1])?;
    let out = PathBuf::from(&args[2]);
    let replicas: usize = args[3].parse().expect("REPLICAS: a count");
    let order = args.get(4).map(String::as_str).unwrap_or("split");
    let first: usize = args.get(5).map(|s| s.parse().expect("FIRST: an index")).unwrap_or(0);
    println!(
        "order,replica,end,steps,time_s,final_max_overlap_m,run_max_overlap_m,unconverged_steps,mean_iterations,wall_s"
    );
    for i in first..first + replicas {
        let mut sys = scene.build()?;
        if order == "serial" {
            sys.params.nlgs.split_min_rows = 0;
        }
        sys.set_threads(1);
        if i > 0 {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(i as u64);
            let mut c = sys.configuration();
            for b in 0..c.bodies.len() {
                let a: f64 = rng.random_range(0.0..std::f64::consts::TAU);
                c.q[3 * b] += PERTURBATION * a.cos();
                c.q[3 * b + 1] += PERTURBATION * a.sin();
            }
            sys.set_configuration(&c)?;
        }
        let dir = out.join(format!("{order}-{i}"));
        let run = Runner::from_system(sys, scene.plan()?)?.run(&dir, &RunOptions::default(), &mut |_| {})?;
        let series = ballast::io::series::read_nscd(&dir.join("series.csv"))?;
        let last = series.last().expect("a run writes at least one row");
        let r = &run.report;
        println!(
            "{order},{i},{:?},{},{},{},{},{},{},{}",
            r.end,
            run.step,
            run.time,
            last.max_overlap_m,
            r.max_overlap_m,
            r.unconverged_steps.unwrap_or(0),
            r.mean_iterations.unwrap_or(f64::NAN),
            r.wall_time_s
        );
    }
    Ok(())
}
