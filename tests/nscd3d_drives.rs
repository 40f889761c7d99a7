//! What drives a 3D NSCD body besides gravity and contacts — harmonic forces and moments, imposed velocities, the
//! sublayer springs of law (17) — against closed forms: a free body under `A + B cos(2π f t − φ)` (the velocity
//! and position integrals, second order in `h`), a constant moment about a principal axis (the spin and the turn,
//! exact), imposed translation and spin (the motion exactly as imposed; a block dragged on a floor meets the
//! Coulomb force `μ m g`), a mass on a spring (the θ = 1/2 scheme is the trapezoidal rule: the discrete
//! oscillation is a rotation by `2 atan(Ω h / 2)` per step, exactly, and the energy is conserved), and a slab
//! guided along z on four compression-only springs (the static compression `m g L0 / (4 k_N)`).

use crate::scratch;
use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::method::{NlgsSettings, Policy};
use ballast::nscd::Harmonic;
use ballast::space::bodies::BodyInfo;
use ballast::space::loads::{Imposed3, Load3};
use ballast::space::springs::Spring3;
use nalgebra::{Unit, UnitQuaternion};
use std::f64::consts::{PI, TAU};

const RHO: f64 = 2700.0;

fn cuboid(half: [f64; 3]) -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid(half).expect("a valid box"))
}

fn system(dt: f64, gravity: Vec3, mu: f64) -> System3 {
    let nlgs =
        NlgsSettings { policy: Policy::Quad, tolerance: 1e-10, max_iterations: 20_000, ..NlgsSettings::default() };
    let mut sys = System3::new(Params3 { dt, gravity, alert_distance: 1e-3, nlgs, ..Params3::default() }, 1);
    sys.set_law(0, 0, ContactLaw { friction: mu, ..ContactLaw::default() });
    sys
}

/// A free body (no gravity) under the force `F(t) = A + B cos(ω t − φ)` along `d`: `m v(t) = A t + (B/ω)(sin(ω t −
/// φ) + sin φ)` and `m x(t) = A t²/2 + (B/ω²)(cos φ − cos(ω t − φ)) + (B/ω) t sin φ`. The scheme takes the force at
/// `t_m` (the midpoint rule for θ = 1/2) and moves by the trapezoid of the velocities: both second order, so the
/// error at 0.09 s falls by 4 when h halves.
#[test]
fn a_harmonic_force_moves_a_free_body_as_its_integral() {
    let (a, b, f, phi) = (-1000.0, -500.0, 20.0, -PI);
    let d = Vec3::new(1.0, -2.0, 2.0) / 3.0;
    let run = |dt: f64| {
        let mut sys = system(dt, Vec3::zeros(), 0.0);
        let value = Harmonic { mean: a, amplitude: b, frequency: f, phase: phi };
        let body = BodyInfo::mobile("sleeper", cuboid([0.1, 0.05, 0.03]), 0, RHO)
            .unwrap()
            .with_load(Load3::force(d * 7.0, value));
        let m = body.mass;
        sys.bodies.push(body, Pose::at(Vec3::zeros()), [0.0; 6]);
        // 1.8 periods: over whole periods the midpoint rule integrates the cosine exactly.
        let steps = (0.09 / dt).round() as usize;
        for _ in 0..steps {
            sys.step().unwrap();
        }
        let (t, w) = (sys.time, TAU * f);
        let v = (a * t + b / w * ((w * t - phi).sin() + phi.sin())) / m;
        let x = (a * t * t / 2.0 + b / (w * w) * (phi.cos() - (w * t - phi).cos()) + b / w * t * phi.sin()) / m;
        let u = sys.bodies.u[0];
        let (ve, xe) = (Vec3::new(u[0], u[1], u[2]), sys.bodies.pose[0].position);
        // Along d only, and no spin.
        assert!(ve.cross(&d).norm() < 1e-12 * ve.norm() && u[3..].iter().all(|&w| w == 0.0));
        ((ve.dot(&d) - v).abs() / v.abs(), (xe.dot(&d) - x).abs() / x.abs())
    };
    let (coarse, fine) = (run(1e-3), run(5e-4));
    for (k, what) in [(0, "velocity"), (1, "position")] {
        let (c, e) = if k == 0 { (coarse.0, fine.0) } else { (coarse.1, fine.1) };
        // Second order (4 ± 0.6: the next term of the error at these steps), and small in absolute terms.
        assert!((3.4..4.6).contains(&(c / e)), "{what}: relative errors {c:e} at 1e-3 s, {e:e} at 5e-4 s");
        assert!(e < 1e-3, "{what}: relative error {e:e} at 5e-4 s");
    }
}

/// A constant moment `M` about a world axis along a principal axis of a body at rest: no gyroscopic term (the
/// spin stays along the axis), `ω(t) = M t / I` and the body turns by `M t² / (2 I)` about the axis — a quadratic
/// the trapezoid integrates exactly, so both hold to round-off.
#[test]
fn a_constant_moment_spins_a_body_up_about_its_axis() {
    let dt = 1e-3;
    let mut sys = system(dt, Vec3::zeros(), 0.0);
    let axis = Unit::new_normalize(Vec3::new(0.0, 1.0, 1.0));
    // The brick's longest principal axis (its least moment) along `axis`.
    let rotation = UnitQuaternion::rotation_between(&Vec3::x(), &axis).unwrap();
    let body = BodyInfo::mobile("brick", cuboid([0.1, 0.05, 0.025]), 0, RHO).unwrap();
    let k = (0..3).min_by(|&i, &j| body.inertia[i].total_cmp(&body.inertia[j])).unwrap();
    assert_eq!(k, 0, "the brick's principal frame is its box frame");
    let (moment, inertia) = (0.3, body.inertia.x);
    let body = body.with_load(Load3::moment(axis.into_inner(), Harmonic::constant(moment)));
    sys.bodies.push(body, Pose { position: Vec3::zeros(), rotation }, [0.0; 6]);
    for _ in 0..400 {
        sys.step().unwrap();
    }
    let t = sys.time;
    let (v, w) = sys.bodies.world_velocity(0);
    assert_eq!(v, Vec3::zeros());
    assert!((w - axis.into_inner() * moment * t / inertia).norm() < 1e-12 * moment * t / inertia, "{w:?}");
    let turned = sys.bodies.pose[0].rotation * rotation.inverse();
    let expected = UnitQuaternion::from_axis_angle(&axis, moment * t * t / (2.0 * inertia));
    assert!(turned.angle_to(&expected) < 1e-12, "off by {:e} rad", turned.angle_to(&expected));
}

/// Imposed components move as imposed, whatever acts on the body: a block dragged along x at 0.1 m/s on a floor
/// with μ = 0.4 keeps that velocity, slides without turning, and the floor pushes back with `m g` up and the
/// Coulomb force `μ m g` against the drag; a harmonic imposed `v_z` on a free body moves it by the trapezoid of
/// the imposed values; an imposed world spin about a tilted axis turns a body by `ω t` about it exactly.
#[test]
fn imposed_velocities_hold_and_the_floor_resists_with_coulomb() {
    let (dt, mu, g) = (1e-3, 0.4, 9.81);
    let mut sys = system(dt, Vec3::new(0.0, 0.0, -g), mu);
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    let half = [0.05, 0.04, 0.03];
    let drag = Imposed3 { velocity: [Some(Harmonic::constant(0.1)), None, None], spin: None };
    let block = BodyInfo::mobile("block", cuboid(half), 0, RHO).unwrap().with_imposed(drag);
    let m = block.mass;
    sys.bodies.push(block, Pose::at(Vec3::new(0.0, 0.0, half[2])), [0.0; 6]);
    for _ in 0..300 {
        sys.step().unwrap();
    }
    let u = sys.bodies.u[1];
    assert_eq!(u[0], 0.1, "the imposed component");
    // The rest of the motion comes from the contacts: the solve's tolerance (1e-10) bounds it.
    assert!(u[1..].iter().all(|x| x.abs() < 1e-8), "{u:?}");
    let x = sys.bodies.pose[1].position.x;
    assert!((x - 0.1 * sys.time).abs() < 1e-12, "x = {x}, t = {}", sys.time);
    let total = sys.contact_forces().fold(Vec3::zeros(), |s, c| s + if c.candidate == 1 { c.force } else { -c.force });
    // Σ f_n = m g and the friction μ m g against +x, to the solve's tolerance (relative 1e-6 is far above it).
    assert!((total.z - m * g).abs() < 1e-6 * m * g, "normal {total:?} vs {}", m * g);
    assert!((total.x + mu * m * g).abs() < 1e-6 * m * g, "friction {total:?} vs {}", -mu * m * g);

    // A harmonic imposed v_z, v(t) = 0.2 cos(2π 5 t): z moves by the trapezoid of the imposed values.
    let mut sys = system(dt, Vec3::new(0.0, 0.0, -g), 0.0);
    let value = Harmonic { mean: 0.0, amplitude: 0.2, frequency: 5.0, phase: 0.0 };
    let shaken = Imposed3 { velocity: [None, None, Some(value)], spin: None };
    let body = BodyInfo::mobile("shaken", Solid::Sphere { radius: 0.02 }, 0, RHO).unwrap().with_imposed(shaken);
    sys.bodies.push(body, Pose::at(Vec3::zeros()), [0.0; 6]);
    let mut z = 0.0;
    for k in 0..100 {
        sys.step().unwrap();
        z += 0.5 * dt * (value.at(k as f64 * dt) + value.at((k + 1) as f64 * dt));
    }
    assert!((sys.bodies.pose[0].position.z - z).abs() < 1e-15, "{} vs {z}", sys.bodies.pose[0].position.z);
    // Gravity acts on the free components: x and y stay 0 (gravity is along z, which is imposed).
    assert_eq!(sys.bodies.u[0][..2], [0.0, 0.0]);

    // An imposed spin about a tilted world axis on a brick at a general orientation.
    let mut sys = system(dt, Vec3::zeros(), 0.0);
    let axis = Unit::new_normalize(Vec3::new(1.0, 1.0, 0.5));
    let rate = 3.0;
    let spin = axis.into_inner() * rate;
    let imposed = Imposed3 { velocity: [None; 3], spin: Some([spin.x, spin.y, spin.z].map(Harmonic::constant)) };
    let body = BodyInfo::mobile("brick", cuboid([0.1, 0.05, 0.025]), 0, RHO).unwrap().with_imposed(imposed);
    let start = UnitQuaternion::from_euler_angles(0.3, -0.7, 1.2);
    sys.bodies.push(body, Pose { position: Vec3::zeros(), rotation: start }, [0.0; 6]);
    for _ in 0..250 {
        sys.step().unwrap();
    }
    let expected = UnitQuaternion::from_axis_angle(&axis, rate * sys.time) * start;
    assert!(sys.bodies.pose[0].rotation.angle_to(&expected) < 1e-12);
    assert!((sys.bodies.world_velocity(0).1 - spin).norm() < 1e-12);
}

/// A sphere on a spring to a world anchor, no gravity, released stretched by `x0` along z: the θ = 1/2 step is
/// the trapezoidal rule on `m ẍ = −k x` (`k = k_N / L0`), whose discrete solution is `x_n = x0 cos(n Ω_h h)` with
/// `tan(Ω_h h / 2) = Ω h / 2`: exact to round-off, and the energy `½ m v² + ½ k_N L0 ε²` is conserved.
#[test]
fn a_mass_on_a_spring_oscillates_as_the_trapezoidal_rule_says() {
    let (dt, k_n, rest, x0) = (1e-3, 500.0, 0.2, 0.01);
    let mut sys = system(dt, Vec3::zeros(), 0.0);
    let body = BodyInfo::mobile("bob", Solid::Sphere { radius: 0.03 }, 0, RHO).unwrap();
    let m = body.mass;
    sys.bodies.push(body, Pose::at(Vec3::new(0.0, 0.0, rest + x0)), [0.0; 6]);
    sys.springs.push(Spring3 {
        a: 0,
        point_a: Vec3::zeros(),
        b: None,
        point_b: Vec3::zeros(),
        k_n,
        nu: 0.0,
        rest_length: rest,
        prestrain: 0.0,
        compression_only: false,
        impulse: 0.0,
    });
    let omega = (k_n / rest / m).sqrt();
    let omega_h = 2.0 / dt * (omega * dt / 2.0).atan();
    let energy = |sys: &System3| sys.bodies.kinetic_energy() + sys.spring_energy();
    let e0 = energy(&sys);
    for n in 1..=2000 {
        sys.step().unwrap();
        let x = sys.bodies.pose[0].position.z - rest;
        // Round-off of 2000 steps of an affine map: 1e-12 of the amplitude is ample and far below the O(h²)
        // phase error of the true solution (Ω_h − Ω ≈ Ω³ h² / 12 ≈ 2e-3 rad/s here).
        assert!((x - x0 * (omega_h * n as f64 * dt).cos()).abs() < 1e-12 * x0 * n as f64, "step {n}: {x}");
        assert!((energy(&sys) - e0).abs() < 1e-10 * e0, "step {n}: energy {} vs {e0}", energy(&sys));
    }
    // The phase error against the true frequency exists and is the predicted one (a check that cannot pass by
    // accident: the scheme is not the exact solution).
    assert!(((omega_h - omega) / (omega.powi(3) * dt * dt / 12.0) + 1.0).abs() < 0.01);
}

/// A slab guided along z on four compression-only, damped springs under its corners: it settles at the
/// compression `δ` with `4 k_N δ / L0 = m g`, each spring carrying a quarter of the weight.
#[test]
fn a_slab_on_four_springs_settles_at_the_static_compression() {
    let (dt, g, k_n, nu, rest) = (1e-3, 9.81, 2.0e4, 200.0, 0.1);
    let mut sys = system(dt, Vec3::new(0.0, 0.0, -g), 0.0);
    let half = [0.2, 0.1, 0.02];
    // Guided as a sleeper is (free along z only): vertical springs under compression push a body that moves
    // sideways further aside (their lateral stiffness is −F/L, an inverted pendulum growing at √(g/L) ≈ 10 /s
    // here), which a free slab duly does after 2 s.
    let guide = Imposed3 {
        velocity: [Some(Harmonic::constant(0.0)), Some(Harmonic::constant(0.0)), None],
        spin: Some([Harmonic::constant(0.0); 3]),
    };
    let slab = BodyInfo::mobile("slab", cuboid(half), 0, RHO).unwrap().with_imposed(guide);
    let m = slab.mass;
    sys.bodies.push(slab, Pose::at(Vec3::new(0.0, 0.0, rest + half[2])), [0.0; 6]);
    for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
        let corner = Vec3::new(sx * half[0], sy * half[1], -half[2]);
        sys.springs.push(Spring3 {
            a: 0,
            point_a: corner,
            b: None,
            point_b: Vec3::new(corner.x, corner.y, 0.0),
            k_n,
            nu,
            rest_length: rest,
            prestrain: 0.0,
            compression_only: true,
            impulse: 0.0,
        });
    }
    for _ in 0..3000 {
        sys.step().unwrap();
    }
    let delta = m * g * rest / (4.0 * k_n);
    let z = sys.bodies.pose[0].position.z - half[2];
    // The damping (ζ ≈ 0.5) leaves e^{-15} of the start after 3 s: far below 1e-9 relative.
    assert!((rest - z - delta).abs() < 1e-9 * delta, "compression {} vs {delta}", rest - z);
    for f in sys.spring_forces() {
        assert!((f - m * g / 4.0).abs() < 1e-6 * m * g, "spring force {f} vs {}", m * g / 4.0);
    }
}

const SLEEPER: &str = include_str!("../examples/sleeper3d.toml");

/// The sleeper example (a guided sleeper under the harmonic load on nine cubes on a pad hung on four springs):
/// the vertical momentum of the whole system changes by exactly the impulses from outside it — the springs'
/// impulses, the load's `h F(t_m)` and the weight `h m g` of every body — step after step: the contacts are
/// internal (equal and opposite impulses, whatever the solve's convergence) and every body is free along z.
/// Round-off is the only error (1e-9 of the weight's impulse over the run is far above it).
#[test]
fn the_sleeper_example_balances_vertical_momentum() {
    use ballast::scene::{d3::Scene3, SceneFile};
    let scene = Scene3::from_toml_str(SLEEPER).unwrap();
    let mut sys = scene.build().unwrap();
    let (dt, g) = (sys.params.dt, -sys.params.gravity.z);
    let mobile: Vec<usize> = (0..sys.bodies.len()).filter(|&i| !sys.bodies.info[i].fixed).collect();
    let momentum = |sys: &System3| mobile.iter().map(|&i| sys.bodies.info[i].mass * sys.bodies.u[i][2]).sum::<f64>();
    let weight: f64 = mobile.iter().map(|&i| sys.bodies.info[i].mass * g).sum();
    let sleeper = sys.bodies.info.iter().position(|b| b.name == "sleeper").unwrap();
    let load = sys.bodies.info[sleeper].loads[0];
    let p0 = momentum(&sys);
    let mut outside = 0.0;
    for _ in 0..200 {
        let t_m = sys.time + (1.0 - sys.params.theta) * dt;
        sys.step().unwrap();
        outside += sys.springs.iter().map(|s| s.impulse).sum::<f64>() + dt * load.at(t_m).z - dt * weight;
    }
    let scale = weight * sys.time;
    assert!((momentum(&sys) - p0 - outside).abs() < 1e-9 * scale, "{} vs {outside}", momentum(&sys) - p0);
    // The springs carry the weight and the load: in compression, the pad pressed down.
    assert!(sys.springs.iter().all(|s| s.impulse > 0.0));
    let pad = sys.bodies.info.iter().position(|b| b.name == "pad").unwrap();
    assert!(sys.bodies.pose[pad].position.z < 0.12);
    assert_eq!(<System3 as ballast::engine::Engine>::anchored_bodies(&sys), vec![pad]);
}

/// The example run by the run loop straight, and stopped after 70 steps then resumed: the same bytes in every
/// file (the springs' impulses are part of the checkpoint), the cycle rows of the sleeper (two cycles), and the
/// run's figures drawn from its folder.
#[test]
fn the_sleeper_example_runs_stops_and_resumes_to_the_same_bytes() {
    use ballast::open::open;
    use ballast::run::RunOptions;
    let dir = scratch::dir("sleeper");
    let path = dir.join("sleeper3d.toml");
    std::fs::write(&path, SLEEPER).unwrap();
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let (whole, parts) = (dir.join("whole"), dir.join("parts"));
    open(&path, &opts).unwrap().run(&whole, &opts, &mut |_| {}).unwrap();
    open(&path, &opts).unwrap().run(&parts, &RunOptions { stop_after: Some(70), ..opts.clone() }, &mut |_| {}).unwrap();
    assert!(parts.join("checkpoint.json").is_file() && !parts.join("final.json").exists());
    open(&path, &opts).unwrap().run(&parts, &RunOptions { resume: true, ..opts.clone() }, &mut |_| {}).unwrap();
    let mut files = vec![];
    for entry in std::fs::read_dir(&whole).unwrap() {
        let p = entry.unwrap().path();
        // Wall times differ between any two runs.
        if p.is_file() && !["summary.json", "checkpoint.json", "cycle_times.csv"].iter().any(|n| p.ends_with(n)) {
            files.push(p);
        }
    }
    assert!(files.iter().any(|f| f.ends_with("cycles.csv")) && files.len() >= 5, "{files:?}");
    for f in &files {
        let other = parts.join(f.file_name().unwrap());
        assert_eq!(std::fs::read(f).unwrap(), std::fs::read(&other).unwrap(), "{f:?} differs");
    }
    let cycles = std::fs::read_to_string(whole.join("cycles.csv")).unwrap();
    assert_eq!(cycles.lines().count(), 3, "a header and two cycles:\n{cycles}");
    // The figures of a 3D run, from its folder alone.
    let drawn = ballast::report::draw_run_figures(&whole).unwrap();
    let stems: Vec<String> =
        drawn.written.iter().map(|p| p.file_name().unwrap().to_string_lossy().into_owned()).collect();
    assert_eq!(stems, ["energies", "overlaps", "settlement_cycles", "vertical_cut"], "{drawn:?}");
    for stem in &drawn.written {
        for ext in ["png", "svg"] {
            assert!(stem.with_extension(ext).metadata().unwrap().len() > 1000, "{stem:?}.{ext}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
