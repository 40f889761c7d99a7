//! A timed deposit of 3D ballast grains ([`ballast::scenarios::grains3d`]: hulls of 12–30 points on random
//! ellipsoids, 25–50 mm uniform by mass) under gravity in a box of four half-space walls on a half-space floor,
//! with the 3D NSCD engine ([`ballast::nscd::d3`]): where a step's time goes (detection, solve) and how the
//! solve converges, for the performance target of the 3D track section.
//!
//! `cargo run --release --example pile3d -- [GRAINS] [STEPS] [TOLERANCE] [THREADS]` (defaults 500, 400, 1e-4, 1:
//! `quad`
//! policy, θ = 1/2, dt 2e-4 s, μ 0.8 between grains and with the walls; the grains start on a lattice with a
//! random orientation each, 5 cm cells, and fall). Prints a line every 50 steps (time, contacts, sweeps,
//! steps at the cap, the ms per step of detection and solve) and the totals. With THREADS 2 the contact solve
//! (problems of at least 512 rows) sweeps its two halves side by side (the numbers are those of one thread); the
//! team's record is printed.

use ballast::geometry::{Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::method::{NlgsSettings, Policy};
use ballast::scenarios::grains3d::{grains, GrainSpec};
use ballast::space::bodies::BodyInfo;
use nalgebra::UnitQuaternion;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn main() -> ballast::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let count: usize = args.first().map_or(500, |a| a.parse().expect("GRAINS: a count"));
    let steps: usize = args.get(1).map_or(400, |a| a.parse().expect("STEPS: a count"));
    let tolerance: f64 = args.get(2).map_or(1e-4, |a| a.parse().expect("TOLERANCE: a number"));
    let threads: usize = args.get(3).map_or(1, |a| a.parse().expect("THREADS: a count"));
    let nlgs = NlgsSettings { policy: Policy::Quad, tolerance, max_iterations: 2000, ..NlgsSettings::default() };
    let params = Params3 { dt: 2e-4, alert_distance: 1e-3, nlgs, ..Params3::default() };
    let mut sys = System3::new(params, 1);
    sys.set_law(0, 0, ContactLaw { friction: 0.8, ..ContactLaw::default() });
    sys.set_threads(threads);

    let drawn = grains(&GrainSpec::default(), count)?;
    let cell = 2.0 * drawn.iter().map(|g| g.shape.radius).fold(0.0, f64::max) + 1e-3;
    let side = (count as f64 / 4.0).sqrt().ceil() as usize; // about four layers
    let width = side as f64 * cell;
    // Floor z ≤ 0, walls x = 0, x = width, y = 0, y = width (each the half-space z ≤ 0 of its own frame).
    let wall = |name: &str, position: Vec3, normal: Vec3| {
        let rotation = UnitQuaternion::rotation_between(&Vec3::z(), &normal).unwrap_or(UnitQuaternion::identity());
        (BodyInfo::fixed(name, Solid::HalfSpace, 0), Pose { position, rotation })
    };
    for (info, pose) in [
        wall("floor", Vec3::zeros(), Vec3::z()),
        wall("x0", Vec3::zeros(), Vec3::x()),
        wall("x1", Vec3::new(width, 0.0, 0.0), -Vec3::x()),
        wall("y0", Vec3::zeros(), Vec3::y()),
        wall("y1", Vec3::new(0.0, width, 0.0), -Vec3::y()),
    ] {
        sys.bodies.push(info, pose, [0.0; 6]);
    }
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for (k, g) in drawn.into_iter().enumerate() {
        let (i, j, l) = (k % side, (k / side) % side, k / (side * side));
        let centre = Vec3::new((i as f64 + 0.5) * cell, (j as f64 + 0.5) * cell, (l as f64 + 0.5) * cell);
        let axis = Vec3::new(rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5, rng.random::<f64>() - 0.5);
        let pose = Pose { position: centre, rotation: UnitQuaternion::from_scaled_axis(axis * 6.0) };
        let info = BodyInfo::mobile(&format!("g{k}"), Solid::Polyhedron(g.shape), 0, 2700.0)?;
        sys.bodies.push(info, pose, [0.0; 6]);
    }
    println!("{count} grains in a {width:.3} m square box, {steps} steps of {} s, quad {tolerance:e}", sys.params.dt);

    let (mut detect, mut solve, mut sweeps, mut capped, mut contacts) = (0.0, 0.0, 0usize, 0usize, 0usize);
    let start = std::time::Instant::now();
    for step in 1..=steps {
        let stats = sys.step()?;
        detect += stats.detect_seconds;
        solve += stats.solve_seconds;
        sweeps += stats.nlgs.iterations;
        capped += usize::from(!stats.nlgs.converged);
        contacts += stats.contacts;
        if step % 50 == 0 {
            println!(
                "step {step:5}  t {:.3} s  contacts {:6}  sweeps {:5}  capped so far {capped:4}  detect {:.2} ms  solve {:.2} ms  Ek {:.3e} J",
                sys.time,
                stats.contacts,
                stats.nlgs.iterations,
                1e3 * stats.detect_seconds,
                1e3 * stats.solve_seconds,
                sys.bodies.kinetic_energy()
            );
        }
    }
    let wall_s = start.elapsed().as_secs_f64();
    let n = steps as f64;
    println!(
        "total {wall_s:.2} s: {:.2} ms/step (detection {:.2}, solve {:.2}); {:.0} contacts, {:.0} sweeps per step; {capped} steps at the cap",
        1e3 * wall_s / n,
        1e3 * detect / n,
        1e3 * solve / n,
        contacts as f64 / n,
        sweeps as f64 / n
    );
    // The final state's fingerprint: equal on one thread and two.
    let fingerprint = sys.bodies.pose.iter().map(|p| p.position.x + p.position.y + p.position.z).sum::<f64>();
    println!("threads {threads}: team {:?}; sum of centroid coordinates {fingerprint:.17e}", sys.team_stats());
    Ok(())
}
