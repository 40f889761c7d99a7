//! The accelerated projected gradient (`solver = "apgd"`, `ballast::nscd::method::apgd`) on the 3D NSCD engine,
//! judged as the Gauss–Seidel solve is (`tests/nscd3d.rs`) against closed forms: a block on an incline sticks
//! below `tan α = μ` and slides above it at `g (sin α − μ cos α)` (the disc of the 3D law in the projection),
//! and a column of cubes carries the weight above each interface (a hyperstatic stack of 4-point faces).

use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::contact::ContactLaw;
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::method::{NlgsSettings, Policy, Solver};
use ballast::space::bodies::BodyInfo;

const G: f64 = 9.81;
const RHO: f64 = 2700.0;

fn cuboid(half: [f64; 3]) -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid(half).expect("a valid box"))
}

/// A system solved by APGD to `quad` 1e-8 (the balances below judge the mechanics, not the stopping rule).
fn system(gravity: Vec3, mu: f64) -> System3 {
    let nlgs = NlgsSettings {
        policy: Policy::Quad,
        tolerance: 1e-8,
        max_iterations: 20_000,
        solver: Solver::Apgd,
        ..NlgsSettings::default()
    };
    let mut sys = System3::new(Params3 { dt: 1e-3, gravity, alert_distance: 1e-3, nlgs, ..Params3::default() }, 1);
    sys.set_law(0, 0, ContactLaw { friction: mu, ..ContactLaw::default() });
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    sys
}

#[test]
fn apgd_a_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above_it() {
    let mu = 0.5;
    let run = |alpha: f64| {
        let mut sys = system(G * Vec3::new(alpha.sin(), 0.0, -alpha.cos()), mu);
        let half = [0.1, 0.05, 0.02];
        sys.bodies.push(
            BodyInfo::mobile("block", cuboid(half), 0, RHO).unwrap(),
            Pose::at(Vec3::new(0.0, 0.0, half[2])),
            [0.0; 6],
        );
        let mut converged = 0;
        for _ in 0..500 {
            converged += usize::from(sys.step().unwrap().nlgs.converged);
        }
        assert_eq!(converged, 500, "every step meets the tolerance");
        sys.bodies.u[1][0]
    };
    // Sticking (tan α = 0.4): the solve's tolerance leaves round-off.
    let v = run(0.4f64.atan());
    assert!(v.abs() < 1e-9, "sticking block moves at {v} m/s");
    // Sliding (tan α = 0.7): v = g (sin α − μ cos α) t to the tolerance, as with Gauss–Seidel.
    let alpha = 0.7f64.atan();
    let v = run(alpha);
    let expected = G * (alpha.sin() - mu * alpha.cos()) * 0.5;
    assert!((v - expected).abs() < 1e-7 * expected, "sliding block at {v} m/s, expected {expected} m/s");
}

#[test]
fn apgd_a_column_of_cubes_carries_the_weight_above_each_interface() {
    let mut sys = system(Vec3::new(0.0, 0.0, -G), 0.3);
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
    // The stack needs more than the 50 Gauss–Seidel sweeps APGD starts with (measured 431 sweep-equivalents in
    // the worst step): the accelerated iterations ran.
    assert!(most > 50, "at most {most} sweep-equivalents: APGD never ran past its first Gauss–Seidel sweeps");
    for k in 0..n {
        let carried: f64 = sys
            .contact_forces()
            .filter(|c| c.candidate as usize == k + 1 || c.antagonist as usize == k + 1)
            .filter(|c| c.point.z < sys.bodies.pose[k + 1].position.z)
            .map(|c| c.r_n)
            .sum();
        let expected = (n - k) as f64 * weight;
        assert!((carried - expected).abs() < 1e-6 * expected, "under cube {k}: {carried} N, expected {expected} N");
    }
}

/// The interior point is a 2D solver (a polyhedral cone's LCP): a 3D system built by hand refuses it before the
/// first step, naming the key, and keeps its state.
#[test]
fn the_interior_point_is_refused_in_3d() {
    let mut sys = system(Vec3::new(0.0, 0.0, -G), 0.3);
    sys.params.nlgs.solver = Solver::InteriorPoint;
    let err = sys.step().unwrap_err().to_string();
    assert!(err.contains("nscd.solver") && err.contains("interior_point"), "{err}");
    assert_eq!(sys.steps, 0);
}
