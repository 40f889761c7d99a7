//! Running simulations from a program that links the crate: a scene file of
//! either engine, and a system of each engine built in code with the
//! constructors (`nscd::BodyInfo::polygon`, `md::Particles::add_sphere`: masses
//! and inertias computed, NSCD bodies placed by their centroids), all through the
//! library's run loop (`ballast::run`), which writes the same output folder as
//! `ballast run` (series, final state, summary, checkpoints, per-cycle positions).
//!
//! `cargo run --release --example library_run -- [OUT]` (default `out/library_run`).

use ballast::engine::Engine;
use ballast::md::{Ghosts, LawTable, Material, MdSettings, MdSystem, Motion, PairLaw, Particles, Wall, V3};
use ballast::nscd::{BodyInfo, ContactLaw, NscdParams, System};
use ballast::open::run_file;
use ballast::run::{RunOptions, RunPlan, Runner};
use ballast::scene::SceneFile;
use std::path::PathBuf;

fn main() -> Result<(), ballast::Error> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "out/library_run".into()));

    // 1. A scene file (the engine comes from its `[simulation] engine`).
    let scene = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/md_two_spheres.toml");
    let run = run_file(&scene, &out.join("md"), &RunOptions::default(), &mut |_| {})?;
    println!("md: {} steps to t = {} s, max overlap {:.3e} m", run.step, run.time, run.report.max_overlap_m);

    // 2. An NSCD system built in code: a 0.1 m square block dropped from 5 cm on a
    //    fixed floor, both of granite (2700 kg/m³) and 1 m thick. Vertices are
    //    where the bodies are in the world (counter-clockwise); the constructor
    //    computes mass ρ·A·t and inertia ρ·J·t and returns the centroid to push at.
    let mut sys = System::new(NscdParams { dt: 1e-3, ..NscdParams::default() }, 1);
    sys.set_law(0, 0, ContactLaw { friction: 0.5, ..ContactLaw::default() }); // else frictionless
    let square = |x: f64, y: f64, a: f64| [[x, y], [x + a, y], [x + a, y + a], [x, y + a]];
    let (floor, q) = BodyInfo::polygon("floor", &square(-0.5, -1.0, 1.0), 0, 2700.0, 1.0)?;
    sys.bodies.push(floor.into_fixed(), q, [0.0; 3]);
    let (block, q) = BodyInfo::polygon("block", &square(-0.05, 0.05, 0.1), 0, 2700.0, 1.0)?;
    println!("nscd: block of {} kg, centroid at ({}, {}) m", block.mass, q[0], q[1]);
    sys.bodies.push(block, q, [0.0; 3]);
    sys.params.alert_distance = sys.bodies.default_alert_distance(); // a scene's default
    let run =
        Runner::from_system(sys, RunPlan::new(500, 10))?.run(&out.join("nscd"), &RunOptions::default(), &mut |_| {})?;
    println!(
        "nscd: {} steps to t = {} s, {} bodies; outputs in {}",
        run.step,
        run.time,
        run.report.bodies,
        out.display()
    );

    // 3. An MD system built in code: a 1 cm rock sphere dropped from 1 cm on a
    //    plane. Every pair of materials that can touch needs a law (here rock on
    //    rock, the plane being of rock too); MdSystem::new refuses a missing one.
    let rock = Material { density: 2000.0, young: 1e7, poisson: 0.25 };
    let mut spheres = Particles::default();
    spheres.add_sphere(0, rock.density, 0.01, V3::new(0.0, 0.0, 0.02), V3::zeros())?; // mass ρ 4/3 π r³
    let plane = ballast::md::Shape::Plane { point: V3::zeros(), normal: V3::z() };
    let walls = vec![Wall::new("floor", 0, plane, Motion::Fixed)];
    let mut laws = LawTable::named(&["rock"]);
    laws.set(0, 0, PairLaw::hertz(&rock, &rock, 0.3, 0.3, 0.5));
    let settings = MdSettings { dt: 1e-5, skin: 1e-3, ..MdSettings::default() };
    let sys = MdSystem::new(settings, spheres, walls, laws, Ghosts::new(Vec::new()))?;
    let run = Runner::from_system(sys, RunPlan::new(10_000, 100))?.run(
        &out.join("md_code"),
        &RunOptions::default(),
        &mut |_| {},
    )?;
    println!("md (in code): {} steps to t = {} s, max overlap {:.3e} m", run.step, run.time, run.report.max_overlap_m);

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
