//! The relaxation of a 3D configuration (`ballast::space::relax`, the settlement driver's step after a jump):
//! the penalty's gradient against finite differences at a turned configuration (the rotation variables go
//! through SO(3)'s right Jacobian), the mass-metric projection of a single overlap against its closed form,
//! a sunk cube lifted straight up, held and imposed bodies left in place, and the engine's write-back.

use crate::scratch;
use ballast::engine::relax::Functional;
use ballast::engine::{Engine, RelaxSettings};
use ballast::geometry::{Polyhedron, Pose, Solid, Vec3};
use ballast::nscd::d3::system::{Params3, System3};
use ballast::nscd::Harmonic;
use ballast::space::bodies::{gen_dir, BodyInfo};
use ballast::space::loads::Imposed3;
use ballast::space::relax::{project, right_jacobian_transpose, Projection3};
use nalgebra::{Unit, UnitQuaternion};

const RHO: f64 = 2700.0;

fn cube(half: f64) -> Solid {
    Solid::Polyhedron(Polyhedron::cuboid([half; 3]).unwrap())
}

/// A floor and one cube of half size 5 cm standing on a corner (its diagonal vertical, then turned a little
/// about a tilted axis), the corner `depth` (m) below the floor.
fn corner_down(depth: f64) -> System3 {
    let mut sys = System3::new(Params3::default(), 1);
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    let diagonal = Vec3::new(-1.0, -1.0, -1.0).normalize();
    let r = UnitQuaternion::from_axis_angle(&Unit::new_normalize(Vec3::new(1.0, -2.0, 0.5)), 0.1)
        * UnitQuaternion::rotation_between(&diagonal, &-Vec3::z()).unwrap();
    let low = r * Vec3::new(-0.05, -0.05, -0.05);
    let body = BodyInfo::mobile("cube", cube(0.05), 0, RHO).unwrap();
    sys.bodies.push(body, Pose { position: Vec3::new(0.0, 0.0, -depth - low.z), rotation: r }, [0.0; 6]);
    sys
}

/// The right Jacobian's closed form against the derivative of `exp` by finite differences: `R(ψ + δ) ≈
/// R(ψ) exp(J_r(ψ) δ)`, so `(ψ + δ)` moves a body point `ρ` by `R (J_r δ) × ρ`; for every direction, the rate of
/// `n · R(ψ) ρ` is `(J_rᵀ (ρ × Rᵀ n)) · δ`. Central differences of step 1e-6: error ~1e-12.
#[test]
fn the_right_jacobian_is_the_derivative_of_the_exponential() {
    let (n, rho) = (Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::new(0.02, -0.04, 0.03));
    for psi in [Vec3::zeros(), Vec3::new(1e-6, -2e-6, 0.5e-6), Vec3::new(0.3, -0.2, 0.5), Vec3::new(1.5, 1.0, -2.0)] {
        let at = |p: Vec3| n.dot(&(UnitQuaternion::from_scaled_axis(p) * rho));
        let r = UnitQuaternion::from_scaled_axis(psi);
        let grad = right_jacobian_transpose(&psi, &rho.cross(&r.inverse_transform_vector(&n)));
        for k in 0..3 {
            let e = Vec3::from_fn(|i, _| if i == k { 1e-6 } else { 0.0 });
            let fd = (at(psi + e) - at(psi - e)) / 2e-6;
            assert!((fd - grad[k]).abs() < 1e-9, "ψ = {psi:?}, component {k}: {fd} vs {}", grad[k]);
        }
    }
}

/// The functional's gradient against central differences at a configuration away from the start (every
/// variable moved, the rotations by about 0.01 rad), where the one vertex–face overlap is smooth.
#[test]
fn the_penalty_gradient_matches_finite_differences() {
    let sys = corner_down(2e-3);
    let mut p = Projection3::new(&sys.bodies, &[], 1e5);
    let x0: Vec<f64> =
        p.start().iter().enumerate().map(|(k, v)| v + [1e-4, -2e-4, 1e-4, 0.01, -0.008, 0.012][k]).collect();
    let mut grad = vec![0.0; x0.len()];
    let phi = p.evaluate(&x0, &mut grad).unwrap();
    assert!(p.max_overlap(&x0).unwrap() > 1e-3, "the corner still overlaps");
    for k in 0..x0.len() {
        let h = if k < 3 { 1e-7 } else { 1e-6 };
        let mut at = |s: f64| {
            let mut x = x0.clone();
            x[k] += s;
            p.evaluate(&x, &mut vec![0.0; x0.len()]).unwrap()
        };
        let fd = (at(h) - at(-h)) / (2.0 * h);
        // Central differences: O(h²) of a smooth function plus round-off phi·1e-16/h.
        assert!(
            (fd - grad[k]).abs() < 1e-6 * grad[k].abs().max(1.0) + 1e-9 * phi / h,
            "variable {k}: {fd} vs {}",
            grad[k]
        );
    }
}

/// One vertex–face overlap `δ` resolved in the mass metric: to first order the projection moves the
/// configuration by `δ M⁻¹ h / (h M⁻¹ h)` (`h` the contact's generalised normal), the shortest move in the metric
/// `|Δ|²_M = Σ m_d Δ_d²` that closes the overlap. The relaxation stops at the first point without overlap its
/// minimiser reaches, not at the penalty's minimum: its move is along the projection's direction (cosine in the
/// metric above 0.999) and at most 5 % longer (measured: 4 % in rotation, its second quasi-Newton step
/// overshooting to a gap of 0).
#[test]
fn a_single_overlap_is_projected_in_the_mass_metric() {
    let depth = 1e-3;
    let sys = corner_down(depth);
    let (report, poses) = project(&sys.bodies, &RelaxSettings::new(1e-7)).unwrap();
    assert!(report.converged && report.max_overlap_after <= 1e-7, "{report:?}");
    assert!((report.max_overlap_before - depth).abs() < 1e-12);
    let start = &sys.bodies.pose[1];
    let corner = start.position + start.rotation * Vec3::new(-0.05, -0.05, -0.05);
    let contact = Vec3::new(corner.x, corner.y, -depth / 2.0);
    let rho = start.rotation.inverse_transform_vector(&(contact - start.position));
    let h = gen_dir(start, &rho, &Vec3::z());
    let im = sys.bodies.inv_m[1];
    let w: f64 = (0..6).map(|d| h[d] * im[d] * h[d]).sum();
    let expected: Vec<f64> = (0..6).map(|d| depth * im[d] * h[d] / w).collect();
    let moved = poses[1].position - start.position;
    let turned = (start.rotation.inverse() * poses[1].rotation).scaled_axis();
    let got = [moved.x, moved.y, moved.z, turned.x, turned.y, turned.z];
    let m: Vec<f64> = im.iter().map(|x| 1.0 / x).collect();
    let dot = |a: &[f64], b: &[f64]| (0..6).map(|d| m[d] * a[d] * b[d]).sum::<f64>();
    let (lg, le) = (dot(&got, &got).sqrt(), dot(&expected, &expected).sqrt());
    let cosine = dot(&got, &expected) / (lg * le);
    assert!(cosine > 0.999, "direction: cosine {cosine}, {got:?} vs {expected:?}");
    assert!((0.999..1.05).contains(&(lg / le)), "length {lg} vs the projection's {le}");
}

/// A cube sunk 2 mm flat into the floor comes straight up by 2 mm (four face points, symmetric: no turn, no
/// sideways move), to the tolerance; a held cube and one whose every component is imposed stay where they are.
#[test]
fn a_sunk_cube_comes_straight_up_and_held_bodies_stay() {
    let mut sys = System3::new(Params3::default(), 1);
    sys.bodies.push(BodyInfo::fixed("floor", Solid::HalfSpace, 0), Pose::at(Vec3::zeros()), [0.0; 6]);
    let sunk = |x: f64| Pose::at(Vec3::new(x, 0.0, 0.05 - 2e-3));
    sys.bodies.push(BodyInfo::mobile("free", cube(0.05), 0, RHO).unwrap(), sunk(0.0), [0.0; 6]);
    sys.bodies.push(BodyInfo::mobile("held", cube(0.05), 0, RHO).unwrap(), sunk(0.3), [0.0; 6]);
    let all = Imposed3 { velocity: [Some(Harmonic::constant(0.0)); 3], spin: Some([Harmonic::constant(0.0); 3]) };
    let guided = BodyInfo::mobile("guided", cube(0.05), 0, RHO).unwrap().with_imposed(all);
    sys.bodies.push(guided, sunk(0.6), [0.0; 6]);
    let settings = RelaxSettings { held: vec![2], ..RelaxSettings::new(1e-8) };
    let report = sys.relax(&settings).unwrap();
    assert!(report.converged, "{report:?}");
    let p = &sys.bodies.pose[1];
    assert!((p.position - Vec3::new(0.0, 0.0, 0.05)).norm() < 2e-8, "{:?}", p.position);
    assert!(p.rotation.angle() < 1e-9);
    assert_eq!(sys.bodies.pose[2], sunk(0.3));
    assert_eq!(sys.bodies.pose[3], sunk(0.6));
    assert!(sys.bodies.u.iter().all(|u| *u == [0.0; 6]));
    // A held body that does not exist is named.
    let e = sys.relax(&RelaxSettings { held: vec![9], ..RelaxSettings::new(1e-8) }).unwrap_err().to_string();
    assert!(e.contains("held body 9 does not exist"), "{e}");
}

/// The settlement driver on the 3D engine, unchanged: the sleeper example (`examples/sleeper3d.toml`) run for 10
/// cycles with a `[settlement]` section computes 2 cycles, fits 3, jumps 3, lands (relaxed) and computes on to the
/// end: one jump in `jumps.csv`, every cycle in `settlement.csv` (computed or extrapolated), a settlement that
/// grows.
#[test]
fn the_settlement_driver_runs_on_the_3d_engine() {
    use ballast::open::open;
    use ballast::run::RunOptions;
    let text = include_str!("../examples/sleeper3d.toml").replace("duration = 0.1 ", "duration = 0.5 ")
        + "\n[settlement]\ninitial_cycles = 2\ncomputed_cycles = 3\nextrapolated_cycles = 3\n";
    let dir = scratch::dir("accelerated");
    let path = dir.join("accelerated.toml");
    std::fs::write(&path, text).unwrap();
    let opts = RunOptions { checkpoint_every_s: 0.0, threads: 1, ..RunOptions::default() };
    let loaded = open(&path, &opts).unwrap();
    assert!(loaded.settles());
    loaded.settle(&dir.join("run"), &opts, &mut |_| {}).unwrap().expect("an accelerated run");
    let jumps = std::fs::read_to_string(dir.join("run/jumps.csv")).unwrap();
    assert_eq!(jumps.lines().count(), 2, "one jump:\n{jumps}");
    assert!(jumps.lines().nth(1).unwrap().starts_with("1,5,8,3,3,"), "{jumps}");
    let settlement = std::fs::read_to_string(dir.join("run/settlement.csv")).unwrap();
    let rows: Vec<Vec<String>> =
        settlement.lines().skip(1).map(|l| l.split(',').map(str::to_string).collect()).collect();
    assert_eq!(rows.len(), 10, "{settlement}");
    let header: Vec<&str> = settlement.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| h.starts_with("settlement")).unwrap();
    let s: Vec<f64> = rows.iter().map(|r| r[col].parse().unwrap()).collect();
    assert!(s[9] > s[0] && s[0] > 0.0, "{s:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
