//! Contact detection per step on the settled 536-pentagon pile of `data/`:
//! world placement, tile-grid predetection and shadow-overlap narrow phase.
//! Throughput is reported per body. Single thread.

use ballast::nscd::detection::Detector;
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn bench(c: &mut Criterion) {
    let scene = Scene::load(concat!(env!("CARGO_MANIFEST_DIR"), "/data/pentagon_pile_536.toml")).unwrap();
    let sys = scene.build().unwrap();
    let mut det = Detector::default();
    let alert = sys.params.alert_distance;
    det.run(&sys.bodies, &sys.bodies.q, alert);
    eprintln!("{} bodies, {} contacts, alert {alert:e} m", sys.bodies.len(), det.found.len());
    let mut g = c.benchmark_group("detection");
    g.throughput(Throughput::Elements(sys.bodies.len() as u64));
    g.bench_function("step_pentagon_pile_536", |b| b.iter(|| det.run(&sys.bodies, &sys.bodies.q, alert)));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
