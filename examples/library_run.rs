//! Running simulations from a program that links the crate: a scene file of
//! either engine, and a system built in code, both through the library's run
//! loop (`ballast::run`), which writes the same output folder as `ballast run`
//! (series, final state, summary, checkpoints, per-cycle positions).
//!
//! `cargo run --release --example library_run -- [OUT]` (default `out/library_run`).

use ballast::geometry::{ConvexPolygon, Shape};
use ballast::nscd::{BodyInfo, NscdParams, System};
use ballast::run::{run_file, Engine, RunOptions, RunPlan, Runner};
use std::path::PathBuf;

fn main() -> Result<(), ballast::Error> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/library_run".into()));

    // 1. A scene file (the engine comes from its `[simulation] engine`).
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/md_two_spheres.toml");
    let run = run_file(&scene, &out.join("md"), &RunOptions::default(), &mut |_| {})?;
    println!("md: {} steps to t = {} s, max overlap {:.3e} m", run.step, run.time, run.report.max_overlap_m);

    // 2. A system built in code: a square block dropped on a fixed floor.
    let mut sys = System::new(NscdParams { dt: 1e-3, ..NscdParams::default() }, 1);
    let square = |w: f64| Shape::Polygon(ConvexPolygon::new(&[[-w, -w], [w, -w], [w, w], [-w, w]]).unwrap().0);
    let body = |name: &str, shape: Shape, fixed: bool| {
        let (area, polar) = shape.area_and_polar_moment(); // mass = ρ A × 1 m of thickness
        let (mass, inertia) = (2700.0 * area, 2700.0 * polar);
        BodyInfo {
            name: name.into(),
            shape,
            material: 0,
            mass,
            inertia,
            fixed,
            imposed: Default::default(),
            loads: vec![],
        }
    };
    sys.bodies.push(body("floor", square(0.5), true), [0.0, -0.5, 0.0], [0.0; 3]);
    sys.bodies.push(body("block", square(0.05), false), [0.0, 0.1, 0.0], [0.0; 3]);
    let run =
        Runner::from_system(sys, RunPlan::new(500, 10))?.run(&out.join("nscd"), &RunOptions::default(), &mut |_| {})?;
    println!(
        "nscd: {} steps to t = {} s, {} bodies; outputs in {}",
        run.step,
        run.time,
        run.report.bodies,
        out.display()
    );

    // The positions a cyclic driver reads and writes back (x, y, θ of each mobile body).
    let scene =
        ballast::scene::Scene::load(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/block_on_floor.toml"))?;
    let mut sys = scene.build()?;
    let mut c = sys.configuration();
    c.q[1] += 0.01; // lift the first mobile body by 1 cm
    sys.set_configuration(&c)?;
    println!("written back: body {} at y = {} m, at rest", c.bodies[0], sys.bodies.q[c.bodies[0]][1]);
    Ok(())
}
