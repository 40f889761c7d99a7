//! One thread against two, on an idle machine and beside a busy process: the
//! timed release example of issue 31 ("two threads never cost more than one").
//!
//! ```sh
//! cargo run --release --example threads -- [ROUNDS] [DEPOSIT_STEPS] [PILE_STEPS] [LOADED_STEPS] [MD_STEPS]
//! ```
//!
//! Four workloads, each run from the same start on one thread and on two:
//! - `deposit536`: the 536-pentagon deposit that `examples/make_pile.rs`
//!   settles into `data/pentagon_pile_536.toml` (Saussine grading, 0.4 m box,
//!   seed 1; `quad_max` 1e-4, split NLGS sweeps), from its step 2500 (0.5 s,
//!   the grains landing; reached once on two threads before the timings);
//! - `pile536`: that settled pile as it is (`ballast run
//!   data/pentagon_pile_536.toml`: at rest under gravity, few sweeps per step);
//! - `loaded536`: the settled pile under the Saussine sleeper load
//!   (`ballast saussine load` defaults: 2 bars, dt 2e-4 s, `energy` 1.66e-5);
//! - `md_bed`: the peers' 2000-sphere Hertz–Mindlin bed of
//!   `../shared/peers/md-bed`, settled once (cached in
//!   `target/md_bed_2000_settled.json`, as `cargo bench --bench md_bed` does).
//!
//! Each is timed `ROUNDS` times (default 2) as 1 thread, 2 threads, alternating,
//! first with the machine as it is, then beside a busy process (`sh -c 'while :;
//! do :; done'`, one core's worth of work, started here and killed at the end).
//! The table gives the median wall times and the ratio two / one; the numbers
//! of both runs are compared bit for bit, and the two-thread team's counts
//! (joins side by side, taken back, in turn, switches) are printed.

use ballast::md::MdSystem;
use ballast::nscd::System;
use ballast::scenarios::md_bed::{bed_system, BedSpec};
use ballast::scenarios::saussine::LoadingSpec;
use ballast::scenarios::{pentagon_deposit, DepositSpec};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use ballast::studies::saussine::load;
use ballast::team::TeamStats;
use std::process::{Child, Command};
use std::time::Instant;

type Error = Box<dyn std::error::Error>;

/// A system of either engine, stepped and compared the same way.
#[derive(Clone)]
enum Work {
    Nscd(Box<System>),
    Md(Box<MdSystem>),
}

impl Work {
    fn set_threads(&mut self, t: usize) {
        match self {
            Work::Nscd(s) => s.set_threads(t),
            Work::Md(s) => s.set_threads(t),
        }
    }

    fn step(&mut self) -> Result<(), Error> {
        match self {
            Work::Nscd(s) => s.step().map(drop).map_err(Into::into),
            Work::Md(s) => s.step().map(drop).map_err(Into::into),
        }
    }

    /// Every coordinate, as bits.
    fn state(&self) -> Vec<u64> {
        match self {
            Work::Nscd(s) => s.bodies.q.iter().chain(&s.bodies.u).flatten().map(|x| x.to_bits()).collect(),
            Work::Md(s) => {
                let p = &s.particles;
                p.x.iter().chain(&p.v).flat_map(|v| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>()).collect()
            }
        }
    }

    fn team(&self) -> TeamStats {
        match self {
            Work::Nscd(s) => s.team_stats(),
            Work::Md(s) => s.team_stats(),
        }
    }
}

/// The busy process beside the runs; killed when dropped.
struct Busy(Child);

impl Busy {
    fn start() -> Result<Self, Error> {
        Ok(Busy(Command::new("sh").args(["-c", "while :; do :; done"]).spawn()?))
    }
}

impl Drop for Busy {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

fn deposit() -> Result<Work, Error> {
    let spec = DepositSpec { duration: 2.5, ..DepositSpec::saussine(536, 0.4, 1) };
    let mut sys = pentagon_deposit(&spec)?.build()?;
    sys.set_threads(2);
    for _ in 0..2500 {
        sys.step()?;
    }
    Ok(Work::Nscd(Box::new(sys)))
}

fn pile() -> Result<Work, Error> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/data/pentagon_pile_536.toml");
    Ok(Work::Nscd(Box::new(Scene::load(path)?.build()?)))
}

fn loaded(dir: &std::path::Path) -> Result<Work, Error> {
    let pile = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/data/pentagon_pile_536.toml"))?;
    let sample = dir.join("pile536_ballast.toml");
    // `saussine load` takes the grains of the material named `ballast`.
    std::fs::write(&sample, pile.replace("\"grain\"", "\"ballast\""))?;
    let scene = dir.join("loaded536.toml");
    load(&sample, &LoadingSpec { cycles: 2, ..LoadingSpec::default() }, &scene)?;
    Ok(Work::Nscd(Box::new(Scene::load(&scene)?.build()?)))
}

fn md_bed() -> Result<Work, Error> {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/target/md_bed_2000_settled.json");
    if let Some(sys) = std::fs::read_to_string(path).ok().and_then(|t| serde_json::from_str::<MdSystem>(&t).ok()) {
        return Ok(Work::Md(Box::new(sys)));
    }
    eprintln!("settling the 2000-sphere bed (120 000 steps, once; cached in {path})");
    let mut sys = bed_system(&BedSpec::peers(2000, 12345))?;
    sys.set_threads(2);
    for _ in 0..120_000 {
        sys.step()?;
    }
    std::fs::write(path, serde_json::to_string(&sys)?)?;
    Ok(Work::Md(Box::new(sys)))
}

/// Wall time of `steps` steps from `start` on `threads` threads, the final
/// state and the team's counts.
fn time(start: &Work, threads: usize, steps: usize) -> Result<(f64, Vec<u64>, TeamStats), Error> {
    let mut w = start.clone();
    w.set_threads(threads);
    let t = Instant::now();
    for _ in 0..steps {
        w.step()?;
    }
    Ok((t.elapsed().as_secs_f64(), w.state(), w.team()))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn main() -> Result<(), Error> {
    let args: Vec<usize> = std::env::args().skip(1).map(|a| a.parse()).collect::<Result<_, _>>()?;
    let rounds = args.first().copied().unwrap_or(2).max(1);
    let default = [500, 1000, 200, 2000];
    let steps: Vec<usize> = (0..4).map(|k| args.get(k + 1).copied().unwrap_or(default[k])).collect();
    let dir = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/target/threads-example"));
    std::fs::create_dir_all(dir)?;
    let works = [("deposit536", deposit()?), ("pile536", pile()?), ("loaded536", loaded(dir)?), ("md_bed", md_bed()?)];
    println!("| workload | steps | machine | 1 thread (s) | 2 threads (s) | 2 / 1 | same bits | team (side by side / taken back / in turn / switches) |");
    println!("|---|---|---|---|---|---|---|---|");
    for busy in [false, true] {
        let _load = if busy { Some(Busy::start()?) } else { None };
        for ((name, work), &n) in works.iter().zip(&steps) {
            let (mut one, mut two) = (Vec::new(), Vec::new());
            let mut same = true;
            let mut team = TeamStats::default();
            for _ in 0..rounds {
                let (t1, s1, _) = time(work, 1, n)?;
                let (t2, s2, st) = time(work, 2, n)?;
                one.push(t1);
                two.push(t2);
                same &= s1 == s2;
                team = st;
            }
            let (m1, m2) = (median(one), median(two));
            println!(
                "| {name} | {n} | {} | {m1:.3} | {m2:.3} | {:.2} | {} | {} / {} / {} / {} |",
                if busy { "beside a busy process" } else { "as it is" },
                m2 / m1,
                if same { "yes" } else { "NO" },
                team.on_helper,
                team.taken_back,
                team.in_turn,
                team.switches
            );
        }
    }
    Ok(())
}
