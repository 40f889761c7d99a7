//! MD step on the settled bed of `../shared/peers/md-bed` (N = 2000 Hertz–Mindlin
//! spheres with tangential history, velocity Verlet, Δt = 5 µs, skin 1 mm), the
//! problem LAMMPS `gran/hertz/history` and LIGGGHTS are timed on
//! (`benches/peers/run_peers.sh`). Throughput is reported in particle-steps: one
//! element = one sphere advanced by one step. The bed is settled once (120 000
//! steps, as the peers: 100 000 + 20 000) and cached in
//! `target/md_bed_<N>_settled.json`; `MD_BED_N=8000` benches the larger bed.

use ballast::md::MdSystem;
use ballast::scenarios::md_bed::{bed_system, top_centre, BedSpec};
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn settled(n: usize) -> MdSystem {
    let path = format!("{}/target/md_bed_{n}_settled.json", env!("CARGO_MANIFEST_DIR"));
    if let Some(sys) = std::fs::read_to_string(&path).ok().and_then(|t| serde_json::from_str(&t).ok()) {
        return sys;
    }
    let mut sys = bed_system(&BedSpec::peers(n, 12345)).expect("the peers' bed");
    sys.set_threads(2);
    for _ in 0..120_000 {
        sys.step().expect("settling the bed");
    }
    eprintln!("settled: top centre {:.4} m, kinetic energy {:.3e} J", top_centre(&sys), sys.last.kinetic_energy);
    let _ = std::fs::write(&path, serde_json::to_string(&sys).expect("serialise"));
    sys
}

fn bench(c: &mut Criterion) {
    let n: usize = std::env::var("MD_BED_N").ok().and_then(|s| s.parse().ok()).unwrap_or(2000);
    let base = settled(n);
    let steps = 100;
    let mut g = c.benchmark_group("md_bed");
    g.throughput(Throughput::Elements((n * steps) as u64));
    g.sample_size(20);
    for threads in [1, 2] {
        let mut sys = base.clone();
        sys.set_threads(threads);
        sys.measure_every = 1000;
        g.bench_function(format!("{n}_spheres_100_steps_{threads}_threads"), |b| {
            b.iter(|| {
                for _ in 0..steps {
                    sys.step().expect("dense bed");
                }
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
