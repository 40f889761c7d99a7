//! The noise floor of a deposit: the same NSCD scene run to its end (or its
//! equilibrium) from starts perturbed by at most `PERTURBATION` (each mobile
//! body moved uniformly in the disc of that radius,
//! `ballast::studies::replicas::perturb_scene`, seed `PERTURB_SEED`, replica i
//! on stream i; before the library had it, each body moved by exactly that
//! length, seeded by i, so older replicas are other draws), in the split NLGS order
//! (`split`: every problem split), the plain one (`serial`: none) or the
//! default (`default`: problems of 512 rows or more), so that a change of one
//! number of a single run (steps to equilibrium, final overlap) can be told
//! from chaos.
//!
//! `cargo run --release --example deposit_replicas -- SCENE OUT REPLICAS [serial|split|default] [FIRST]`
//! writes `OUT/<order>-<i>/` for each replica and prints one CSV line per run
//! (replica 0 is the unperturbed start).

use ballast::run::{RunOptions, Runner};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::studies::replicas::{perturb_scene, Perturbation, DEFAULT_PERTURB_SEED};
use std::path::PathBuf;

/// Largest start displacement of each body, m (the guide's replica size).
const PERTURBATION: f64 = 1e-9;

fn main() -> Result<(), ballast::Error> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 4 {
        eprintln!("usage: deposit_replicas SCENE OUT REPLICAS [serial|split|default] [FIRST]");
        std::process::exit(2);
    }
    let scene = Scene::load(&args[1])?;
    let out = PathBuf::from(&args[2]);
    let replicas: usize = args[3].parse().expect("REPLICAS: a count");
    let order = args.get(4).map(String::as_str).unwrap_or("default");
    let first: usize = args.get(5).map(|s| s.parse().expect("FIRST: an index")).unwrap_or(0);
    println!(
        "order,replica,end,steps,time_s,final_max_overlap_m,run_max_overlap_m,unconverged_steps,mean_iterations,wall_s"
    );
    let perturbation = Perturbation { distance_m: PERTURBATION, seed: DEFAULT_PERTURB_SEED };
    for i in first..first + replicas {
        let mut start = scene.clone();
        perturb_scene(&mut start, &perturbation, i as u64)?; // replica 0: unchanged
        let mut sys = start.build()?;
        match order {
            "serial" => sys.params.nlgs.split_min_rows = 0,
            "split" => sys.params.nlgs.split_min_rows = 1,
            _ => {}
        }
        sys.set_threads(1);
        let dir = out.join(format!("{order}-{i}"));
        let run = Runner::from_system(sys, start.plan()?)?.run(&dir, &RunOptions::default(), &mut |_| {})?;
        let series = ballast::plane::rows::read_series(&dir.join("series.csv"))?;
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
