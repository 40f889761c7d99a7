//! The 3D NSCD engine (`ballast::nscd::d3`) against closed forms and conservation laws: a tumbling free body
//! (angular momentum, its drift under the explicit gyroscopic term and the drift's order), a cube resting on a
//! floor (the floor carries its weight, the moments balance), a block on an incline (sticking below
//! `tan α = μ`, sliding above at `g (sin α − μ cos α)`), a column of cubes (each interface carries the weight
//! above it), a sphere on a polyhedral floor, and a cube dropped on a floor coming to rest without sinking. The
//! incline and the column also under the accelerated projected gradient (`solver = "apgd"`); the interior
//! point refused.

use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::method::{NlgsSettings, Policy, Solver};
use ballast::space::bodies::BodyInfo;
use ballast::space::detection::FaceGaps;
use nalgebra::UnitQuaternion;

const G: f64 = 9.81;
const RHO: f64 = 2700.0;

fn cuboid(half: [f64; 3]) -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid(half).expect("a valid box"))
}

/// A system with one material of friction `mu`, gravity `gravity`, a tight solve (`quad` 1e-8, so that the
/// balances below are judged against the mechanics and not the stopping rule).
fn system(dt: f64, gravity: Vec3, mu: f64) -> System3 {
    system_with(dt, gravity, mu, Solver::Nlgs)
}

/// [`system`] solved by `solver` (Gauss–Seidel, or the accelerated projected gradient: `solver = "apgd"`).
fn system_with(dt: f64, gravity: Vec3, mu: f64, solver: Solver) -> System3 {
    let nlgs = NlgsSettings {
        policy: Policy::Quad,
        tolerance: 1e-8,
        max_iterations: 20_000,
        solver,
        ..NlgsSettings::default()
    };
    let mut sys = System3::new(Params3 { dt, gravity, alert_distance: 1e-3, nlgs, ..Params3::default() }, 1);
    sys.set_law(0, 0, ContactLaw { friction: mu, ..ContactLaw::default() });
    sys
}

fn floor(sys: &mut System3) -> u32 {
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6])
}

/// A torque-free body spinning about its largest or smallest principal axis keeps its spin exactly (the
/// gyroscopic term vanishes); spun about a general axis, its world angular momentum `R I ω` is conserved by
/// the dynamics and drifts in the scheme by `O(h)` (the gyroscopic term is explicit, as in LMGC90): the drift
/// over one second halves when `h` halves.
#[test]
fn a_tumbling_free_body_keeps_its_angular_momentum_to_first_order() {
    let drift = |dt: f64| {
        let mut sys = system(dt, Vec3::zeros(), 0.0);
        let body = BodyInfo::mobile("brick", cuboid([0.1, 0.05, 0.025]), 0, RHO).unwrap();
        let i = sys.bodies.push(body, Pose::at(Vec3::zeros()), [0.0, 0.0, 0.0, 1.0, 10.0, 0.5]) as usize;
        let (l0, e0) = (sys.bodies.angular_momentum(i), sys.bodies.kinetic_energy());
        for _ in 0..(1.0 / dt).round() as usize {
            sys.step().unwrap();
        }
        ((sys.bodies.angular_momentum(i) - l0).norm() / l0.norm(), (sys.bodies.kinetic_energy() - e0).abs() / e0)
    };
    let (coarse, fine) = (drift(1e-3), drift(5e-4));
    // First order: the drift halves with h (2 ± 0.4 allows the second-order part at these steps).
    let ratio = coarse.0 / fine.0;
    assert!((1.6..2.4).contains(&ratio), "drift {coarse:?} at 1e-3 s, {fine:?} at 5e-4 s: ratio {ratio}");
    // And small: the spin about the intermediate axis (10 rad/s) is the unstable one, so this is the hard case.
    assert!(fine.0 < 2e-2, "relative drift of |L| in 1 s at h = 5e-4 s: {}", fine.0);

    // About a principal axis the spin is kept to round-off, and the frame turns by ω t exactly.
    let mut sys = system(1e-3, Vec3::zeros(), 0.0);
    let body = BodyInfo::mobile("brick", cuboid([0.1, 0.05, 0.025]), 0, RHO).unwrap();
    sys.bodies.push(body, Pose::at(Vec3::zeros()), [0.0, 0.0, 0.0, 0.0, 0.0, 2.0]);
    for _ in 0..1000 {
        sys.step().unwrap();
    }
    assert_eq!(sys.bodies.u[0][5], 2.0);
    let expected = UnitQuaternion::from_axis_angle(&Vec3::z_axis(), 2.0);
    assert!(sys.bodies.pose[0].rotation.angle_to(&expected) < 1e-12, "frame after 1 s at 2 rad/s");
}

/// A cube resting on a floor: once at rest the floor's normal forces sum to `m g` and have no moment about the
/// centroid (their centre is below it); how the weight splits among the 4 points is hyperstatic and not judged.
#[test]
fn a_cube_resting_on_a_floor_is_carried_by_it() {
    let mut sys = system(1e-3, Vec3::new(0.0, 0.0, -G), 0.5);
    floor(&mut sys);
    let half = 0.05;
    let cube = BodyInfo::mobile("cube", cuboid([half; 3]), 0, RHO).unwrap();
    let weight = cube.mass * G;
    let pose = Pose { position: Vec3::new(0.0, 0.0, half), rotation: UnitQuaternion::from_euler_angles(0.0, 0.0, 0.3) };
    let i = sys.bodies.push(cube, pose, [0.0; 6]);
    for _ in 0..200 {
        sys.step().unwrap();
    }
    let centre = sys.bodies.pose[i as usize].position;
    let (mut total, mut moment, mut points) = (Vec3::zeros(), Vec3::zeros(), 0);
    for c in sys.contact_forces() {
        total += c.force;
        moment += (c.point - centre).cross(&c.force);
        points += 1;
    }
    assert_eq!(points, 4, "a face on the floor: 4 points");
    // At rest the step's impulses balance the weight over the step to the solver's tolerance (1e-8): 1e-6.
    assert!((total.z - weight).abs() < 1e-6 * weight, "{total:?} N for a weight of {weight} N");
    assert!(total.xy().norm() < 1e-6 * weight, "no friction needed at rest: {total:?}");
    assert!(moment.norm() < 1e-6 * weight * half, "moment about the centroid {moment:?}");
    assert!(sys.bodies.u[0].iter().all(|u| u.abs() < 1e-9), "at rest: {:?}", sys.bodies.u[0]);
}

/// A block on an incline (gravity tilted by α): it sticks while `tan α < μ` and slides when `tan α > μ` with
/// the acceleration `g (sin α − μ cos α)` along the slope, which the θ-method reproduces step by step (the
/// normal impulse per step is exactly `m g cos α h`, the friction impulse `μ` times it).
#[test]
fn a_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above_it() {
    block_on_an_incline(Solver::Nlgs);
}

/// The same under APGD (the 3D law's friction disc in its projection): the same closed forms.
#[test]
fn apgd_a_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above_it() {
    block_on_an_incline(Solver::Apgd);
}

fn block_on_an_incline(solver: Solver) {
    let mu = 0.5;
    let run = |alpha: f64| {
        let gravity = G * Vec3::new(alpha.sin(), 0.0, -alpha.cos());
        let mut sys = system_with(1e-3, gravity, mu, solver);
        floor(&mut sys);
        let half = [0.1, 0.05, 0.02];
        let block = BodyInfo::mobile("block", cuboid(half), 0, RHO).unwrap();
        sys.bodies.push(block, Pose::at(Vec3::new(0.0, 0.0, half[2])), [0.0; 6]);
        let steps = 500;
        for _ in 0..steps {
            assert!(sys.step().unwrap().nlgs.converged, "every step meets the tolerance");
        }
        (sys.bodies.u[1][0], steps as f64 * 1e-3)
    };
    // Sticking at tan α = 0.4 < 0.5: the velocity stays at round-off.
    let (v, _) = run(0.4f64.atan());
    assert!(v.abs() < 1e-9, "sticking block moves at {v} m/s");
    // Sliding at tan α = 0.7: v = g (sin α − μ cos α) t, to the solver's tolerance (quad 1e-8 on the impulses;
    // measured 2e-14 relative: every point slides, so the law is linear in the step's impulses).
    let alpha = 0.7f64.atan();
    let (v, t) = run(alpha);
    let expected = G * (alpha.sin() - mu * alpha.cos()) * t;
    assert!((v - expected).abs() < 1e-8 * expected, "sliding block at {v} m/s, expected {expected} m/s");
}

/// A column of `N` cubes on a floor: at rest the interface under cube `k` (counted from the floor, 0-based)
/// carries the weight of the cubes from `k` up, `(N − k) m g`; Gauss–Seidel reaches it by iterating.
#[test]
fn a_column_of_cubes_carries_the_weight_above_each_interface() {
    column_of_cubes(Solver::Nlgs);
}

/// The same under APGD; the stack needs more than the 50 Gauss–Seidel sweeps APGD starts with (measured 431
/// sweep-equivalents in the worst step), so the accelerated iterations are what is judged.
#[test]
fn apgd_a_column_of_cubes_carries_the_weight_above_each_interface() {
    let most = column_of_cubes(Solver::Apgd);
    assert!(most > 50, "at most {most} sweep-equivalents: APGD never ran past its first Gauss–Seidel sweeps");
}

/// The interior point is a 2D solver (a polyhedral cone's LCP): a 3D system built by hand refuses it before the
/// first step, naming the key, and keeps its state.
#[test]
fn the_interior_point_is_refused_in_3d() {
    let mut sys = system_with(1e-3, Vec3::new(0.0, 0.0, -G), 0.3, Solver::InteriorPoint);
    let err = sys.step().unwrap_err().to_string();
    assert!(err.contains("nscd.solver") && err.contains("interior_point"), "{err}");
    assert_eq!(sys.steps, 0);
}

/// The same with the sweeps mixed by Anderson acceleration (`nscd.anderson = 5`): the mixing moves the path, not
/// the fixed point, and the worst step needs fewer sweeps than plain Gauss–Seidel's (measured 107 mixed against
/// 3 723 plain).
#[test]
fn anderson_a_column_of_cubes_carries_the_weight_above_each_interface() {
    let plain = column_of_cubes(Solver::Nlgs);
    let mixed = column_of_cubes_with(Solver::Nlgs, 5);
    eprintln!("worst step: {mixed} sweeps mixed, {plain} plain");
    assert!(mixed < plain, "worst step: {mixed} sweeps mixed, {plain} plain");
}

/// The column's check; returns the most sweeps (or sweep-equivalents) a step took.
fn column_of_cubes(solver: Solver) -> usize {
    column_of_cubes_with(solver, 0)
}

/// [`column_of_cubes`] with the sweeps' Anderson depth `anderson` (0: plain).
fn column_of_cubes_with(solver: Solver, anderson: usize) -> usize {
    let mut sys = system_with(1e-3, Vec3::new(0.0, 0.0, -G), 0.3, solver);
    sys.params.nlgs.anderson = anderson;
    floor(&mut sys);
    let (half, n) = (0.05, 5);
    let mut weight = 0.0;
    for k in 0..n {
        let cube = BodyInfo::mobile(&format!("cube{k}"), cuboid([half; 3]), 0, RHO).unwrap();
        weight = cube.mass * G;
        sys.bodies.push(cube, Pose::at(Vec3::new(0.0, 0.0, half * (2 * k + 1) as f64)), [0.0; 6]);
    }
    let mut most = 0;
    for _ in 0..300 {
        let stats = sys.step().unwrap();
        assert!(stats.nlgs.converged, "{stats:?}");
        most = most.max(stats.nlgs.iterations);
    }
    // The tolerance: quad 1e-8 on the impulses leaves at most ~1e-8 relative per interface once summed over
    // the four points (measured 1e-9); 1e-6 stays far above it and far below one cube's weight.
    for k in 0..n {
        // Body k + 1 is cube k; the interface under it is with the floor (0) or the cube below (body k).
        let carried: f64 = sys
            .contact_forces()
            .filter(|c| c.candidate as usize == k + 1 || c.antagonist as usize == k + 1)
            .filter(|c| c.point.z < sys.bodies.pose[k + 1].position.z)
            .map(|c| c.r_n)
            .sum();
        let expected = (n - k) as f64 * weight;
        assert!((carried - expected).abs() < 1e-6 * expected, "under cube {k}: {carried} N, expected {expected} N");
    }
    most
}

/// A sphere resting on a fixed polyhedral floor (a box) is carried by one point straight under its centre.
#[test]
fn a_sphere_on_a_polyhedral_floor_is_carried_by_one_point() {
    let mut sys = system(1e-3, Vec3::new(0.0, 0.0, -G), 0.5);
    sys.bodies.push(BodyInfo::fixed("slab", cuboid([1.0, 1.0, 0.1]), 0), Pose::at(Vec3::new(0.0, 0.0, -0.1)), [0.0; 6]);
    let r = 0.05;
    let ball = BodyInfo::mobile("ball", Solid::Sphere { radius: r }, 0, RHO).unwrap();
    let weight = ball.mass * G;
    sys.bodies.push(ball, Pose::at(Vec3::new(0.2, -0.3, r)), [0.0; 6]);
    for _ in 0..100 {
        sys.step().unwrap();
    }
    let contacts: Vec<_> = sys.contact_forces().collect();
    assert_eq!(contacts.len(), 1, "{contacts:?}");
    let c = contacts[0];
    assert!((c.r_n - weight).abs() < 1e-6 * weight, "{} N for a weight of {weight} N", c.r_n);
    assert!((c.point.xy() - nalgebra::Vector2::new(0.2, -0.3)).norm() < 1e-9, "point {:?}", c.point);
}

/// A cube dropped from 2 cm lands and comes to rest: the plastic impact (e_n = 0) stops it, and the overlap
/// never exceeds the gap prediction's bound (a contact closes at the next intermediate configuration: at most
/// the velocity error of one step, here < 1 µm).
#[test]
fn a_dropped_cube_lands_and_rests_without_sinking() {
    let mut sys = system(1e-3, Vec3::new(0.0, 0.0, -G), 0.5);
    floor(&mut sys);
    let half = 0.05;
    let cube = BodyInfo::mobile("cube", cuboid([half; 3]), 0, RHO).unwrap();
    sys.bodies.push(cube, Pose::at(Vec3::new(0.0, 0.0, half + 0.02)), [0.0; 6]);
    let mut lowest = f64::INFINITY;
    for _ in 0..400 {
        sys.step().unwrap();
        lowest = lowest.min(sys.bodies.pose[1].position.z - half);
    }
    assert!(lowest > -1e-6, "the cube sank {lowest} m into the floor");
    assert!(sys.bodies.kinetic_energy() < 1e-12, "still moving: {} J", sys.bodies.kinetic_energy());
}

/// A cube thrown at the floor at 20 m/s covers 20 mm per 1 ms step, twenty times the alert distance (1 mm).
/// Its intermediate configurations are 90, 70, … 10 mm above the floor, then 10 mm into it: detected within the
/// alert distance alone, the floor would first be seen 10 mm deep. The alert distance is raised to twice the
/// step's travel (`2 h v_max`, as in 2D), so the contact is found while still open and closes at
/// `U_N = −g_m / h`: the cube stops on the floor without entering it, and rests there.
#[test]
fn a_cube_thrown_fast_at_the_floor_stops_on_it() {
    let mut sys = system(1e-3, Vec3::new(0.0, 0.0, -G), 0.5);
    floor(&mut sys);
    let half = 0.02;
    let cube = BodyInfo::mobile("cube", cuboid([half; 3]), 0, RHO).unwrap();
    sys.bodies.push(cube, Pose::at(Vec3::new(0.0, 0.0, half + 0.1)), [0.0, 0.0, -20.0, 0.0, 0.0, 0.0]);
    let mut lowest = f64::INFINITY;
    for _ in 0..300 {
        sys.step().unwrap();
        lowest = lowest.min(sys.bodies.pose[1].position.z - half);
    }
    assert!(lowest > -1e-6, "the cube went {lowest} m into the floor");
    assert!((sys.bodies.pose[1].position.z - half).abs() < 1e-6, "at rest on the floor");
    assert!(sys.bodies.kinetic_energy() < 1e-12, "still moving: {} J", sys.bodies.kinetic_energy());
}

/// The face–face gap rule in the mechanics. A 0.1 m cube rests on one edge on a fixed polyhedral slab, its
/// bottom face tilted by 1 mrad, so that the far edge is 0.1 mm up. Under the exact gaps (the default) the far
/// points are open, and gravity rocks the cube about the low edge until it lies flat: in about 5 ms, since its
/// angular acceleration about the edge is 3 g / (4 a) ≈ 74 rad/s² (side a = 0.1 m, moment of inertia about the
/// edge 2 m a² / 3), and it lands plastically. Under
/// LMGC90's common-plane rule the four corners share the low edge's gap (0), so the faces count as flush and
/// the cube stays at its tilt: it cannot turn about the edge without closing the far points' gap.
#[test]
fn a_tilted_cube_rocks_flat_under_exact_gaps_and_stays_tilted_under_the_common_plane() {
    let tilt = 1e-3;
    let half = 0.05;
    for face_gaps in [FaceGaps::Exact, FaceGaps::CommonPlane] {
        let mut sys = system(1e-3, Vec3::new(0.0, 0.0, -G), 0.5);
        sys.params.face_gaps = face_gaps;
        // The slab's top face at z = 0.
        sys.bodies.push(
            BodyInfo::fixed("slab", cuboid([0.2, 0.2, 0.05]), 0),
            Pose::at(Vec3::new(0.0, 0.0, -0.05)),
            [0.0; 6],
        );
        let cube = BodyInfo::mobile("cube", cuboid([half; 3]), 0, RHO).unwrap();
        let rotation = UnitQuaternion::from_euler_angles(tilt, 0.0, 0.0);
        // The low edge (y = −half in the cube's frame) on the slab.
        let low = rotation * Vec3::new(0.0, -half, -half);
        let i = sys.bodies.push(cube, Pose { position: Vec3::new(0.0, 0.0, -low.z), rotation }, [0.0; 6]);
        for _ in 0..200 {
            sys.step().unwrap();
        }
        let left = sys.bodies.pose[i as usize].rotation.angle();
        match face_gaps {
            // Flat to 1e-6 rad (0.1 µm over the face); the exact landing leaves nothing measurable.
            FaceGaps::Exact => assert!(left < 1e-6, "exact gaps: the cube is still tilted by {left} rad"),
            // The tilt kept to 1e-3 of itself: the solve's tolerance (quad 1e-8) allows no turn.
            FaceGaps::CommonPlane => {
                assert!((left - tilt).abs() < 1e-3 * tilt, "common plane: the tilt went from {tilt} to {left} rad")
            }
        }
        assert!(sys.bodies.kinetic_energy() < 1e-12, "{face_gaps:?}: still moving, {} J", sys.bodies.kinetic_energy());
    }
}

/// Five bricks stacked on a wide foundation shaken along y (LMGC90's `Colonne_PR`: its bricks, density, time step,
/// norm and tolerance; one friction for all): the bricks ride on it, so each step's problem is the last one moved
/// by `O(h)`, and its warm start (the last step's impulses, at the same points) leaves little to iterate. The
/// bricks' faces are flush, so the corners of each contact polygon come from either brick as the bricks shift by
/// round-off, and a point's rank in its pair changes from step to step: a warm start by rank put the impulses on
/// the wrong corners. Measured over steps 2–40 (the first, cold step 1 088 sweeps): 12.2 sweeps per step with the
/// warm start at the points' places, 274 with it by rank. The bound, a tenth of the cold step, lies between them
/// with a factor of 8.9 below it and 2.5 above. (From step ~42 all twenty points carry load and every step needs
/// ~200 sweeps however it starts: Gauss–Seidel down a five-brick stack.)
#[test]
fn a_shaken_column_of_flush_bricks_is_warm_started_at_its_points() {
    use ballast::nscd::Harmonic;
    use ballast::space::loads::Imposed3;
    let nlgs =
        NlgsSettings { policy: Policy::Strict, tolerance: 1e-4, max_iterations: 5_000, ..NlgsSettings::default() };
    let params =
        Params3 { dt: 1e-3, gravity: Vec3::new(0.0, 0.0, -G), alert_distance: 1e-2, nlgs, ..Params3::default() };
    let mut sys = System3::new(params, 1);
    sys.set_law(0, 0, ContactLaw { friction: 0.3, ..ContactLaw::default() });
    // v_y = 0.16 sin(4π t), the other dofs held.
    let shake = Harmonic { mean: 0.0, amplitude: 0.16, frequency: 2.0, phase: std::f64::consts::FRAC_PI_2 };
    let still = Some(Harmonic::constant(0.0));
    let imposed = Imposed3 { velocity: [still, Some(shake), still], spin: Some([Harmonic::constant(0.0); 3]) };
    let base = BodyInfo::mobile("foundation", cuboid([0.5, 0.5, 0.05]), 0, 100.0).unwrap().with_imposed(imposed);
    sys.bodies.push(base, Pose::at(Vec3::new(0.0, 0.0, -0.05)), [0.0; 6]);
    let half = [0.11, 0.055, 0.055];
    for k in 1..=5 {
        let brick = BodyInfo::mobile(&format!("brick{k}"), cuboid(half), 0, 100.0).unwrap();
        sys.bodies.push(brick, Pose::at(Vec3::new(0.0, 0.0, half[2] * (2 * k - 1) as f64)), [0.0; 6]);
    }
    let cold = sys.step().unwrap().nlgs.iterations;
    let steps = 39;
    let mut warm = 0;
    for _ in 0..steps {
        let stats = sys.step().unwrap();
        assert!(stats.nlgs.converged && stats.contacts == 20, "{stats:?}");
        warm += stats.nlgs.iterations;
    }
    let mean = warm as f64 / steps as f64;
    assert!(mean < 0.1 * cold as f64, "{mean} sweeps per warm step against {cold} for the cold one");
    // The bricks ride with the foundation (friction holds them: the peak acceleration, 2.0 m/s², is below μ g):
    // after 40 ms none is 0.1 mm off it along y (measured 2 µm: the stack rocks on its points), where bricks it
    // did not carry would be left 1.6 mm behind (the foundation's travel, 0.16/(4π) (1 − cos(4π · 0.04)) m).
    for k in 1..=5 {
        let dy = sys.bodies.pose[k].position.y - sys.bodies.pose[0].position.y;
        assert!(dy.abs() < 1e-4, "brick {k} moved {dy} m along y relative to the foundation");
    }
}
