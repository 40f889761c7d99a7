//! Relaxation of an extrapolated configuration (Karrech et al. 2007, §4), on
//! both engines: the MD functional (29) has the engine's forces as its
//! gradient; the paper's nine-particle cell (Fig. 8 style) and a deliberately
//! overlapped NSCD pile are brought from their initial overlap below the
//! tolerance with the functional decreasing at every iteration, in fewer
//! iterations than the paper's gradient method, and the relaxed state then
//! steps at rest.

use crate::md_common;

use ballast::engine::Engine;
use ballast::engine::{Functional, Method, RelaxReport, RelaxSettings};
use ballast::md::relax::Potential;
use ballast::md::{Ghosts, Integrator, LawTable, Material, MdSystem, PairLaw, Particles, SymmetryPlane, V3};
use ballast::scene::SceneFile;
use md_common::{plane, settings};

/// Karrech et al. Table 1: diorite.
fn diorite() -> Material {
    Material { density: 2710.0, young: 46.9e9, poisson: 0.25 }
}

fn steel() -> Material {
    Material { density: 7800.0, young: 210e9, poisson: 0.3 }
}

fn hertz_laws() -> LawTable {
    let mut t = LawTable::new(2);
    t.set(0, 0, PairLaw::hertz(&diorite(), &diorite(), 0.44, 0.44, 0.5));
    t.set(0, 1, PairLaw::hertz(&diorite(), &steel(), 0.44, 0.44, 0.5));
    t
}

const R: f64 = 3.2e-3;

/// The functional decreases at every iteration (the line search enforces the
/// strong Wolfe conditions): rounding aside, a later value is never above an
/// earlier one. 1e-12 relative covers the rounding of a sum of ~10³ terms.
fn assert_monotone(r: &RelaxReport) {
    for w in r.functional.windows(2) {
        assert!(w[1] <= w[0] + 1e-12 * w[0].abs().max(1e-30), "the functional rose: {} -> {}", w[0], w[1]);
    }
}

/// Nine spheres of Table 1 on a steel floor, in a 3 × 3 layer 1.7 r apart inside
/// four steel walls that leave 5.4 r for three diameters: every neighbour pair
/// overlaps by about 0.3 r (0.96 mm), as an extrapolation overshooting by far
/// would leave them. Without a way out in the plane, the relaxation must lift some.
fn nine_particle_cell() -> MdSystem {
    let mut p = Particles::default();
    let s = 1.7 * R;
    for i in 0..3 {
        for j in 0..3 {
            // Off the lattice by up to 2 % of r, as no extrapolated state is symmetric.
            let k = (3 * i + j) as f64;
            let jitter = |a: f64| 0.02 * R * ((k * a).sin());
            let x =
                V3::new((i as f64 - 1.0) * s + jitter(1.3), (j as f64 - 1.0) * s + jitter(2.1), R + jitter(0.7).abs());
            p.add_sphere(0, diorite().density, R, x, V3::zeros()).unwrap();
        }
    }
    let half = s + R;
    let walls = vec![
        plane("floor", 1, V3::zeros(), V3::z()),
        plane("x-", 1, V3::new(-half, 0.0, 0.0), V3::x()),
        plane("x+", 1, V3::new(half, 0.0, 0.0), -V3::x()),
        plane("y-", 1, V3::new(0.0, -half, 0.0), V3::y()),
        plane("y+", 1, V3::new(0.0, half, 0.0), -V3::y()),
    ];
    let set = settings(1e-7, V3::new(0.0, 0.0, -9.81), Integrator::Verlet, 0.2 * R);
    MdSystem::new(set, p, walls, hertz_laws(), Ghosts::new(Vec::new())).unwrap()
}

#[test]
fn md_functional_gradient_is_minus_the_engine_forces() {
    // Overlapping spheres near a symmetry plane (their images count half), a
    // floor and each other: the gradient against central differences of the value.
    let mut p = Particles::default();
    let xs = [V3::new(0.9 * R, 0.0, 0.95 * R), V3::new(2.6 * R, 0.3 * R, 0.97 * R), V3::new(1.7 * R, 1.5 * R, 1.6 * R)];
    for x in xs {
        p.add_sphere(0, diorite().density, R, x, V3::zeros()).unwrap();
    }
    let walls = vec![plane("floor", 1, V3::zeros(), V3::z())];
    let ghosts = Ghosts::new(vec![SymmetryPlane { point: V3::zeros(), normal: V3::x() }]);
    let set = settings(1e-7, V3::new(0.0, 0.0, -9.81), Integrator::Verlet, 0.2 * R);
    let mut sys = MdSystem::new(set, p, walls, hertz_laws(), ghosts).unwrap();
    let mut f = Potential::new(&mut sys, &[]);
    let x = f.start();
    let mut g = vec![0.0; x.len()];
    f.evaluate(&x, &mut g).unwrap();
    let h = 1e-9;
    let mut scratch = vec![0.0; x.len()];
    for k in 0..x.len() {
        let (mut a, mut b) = (x.clone(), x.clone());
        a[k] += h;
        b[k] -= h;
        let fd = (f.evaluate(&a, &mut scratch).unwrap() - f.evaluate(&b, &mut scratch).unwrap()) / (2.0 * h);
        // Central differences err by h²/6 F''' ~ 1e-18 × F'/δ² with overlaps δ ≳ 1e-4 m:
        // 1e-10 relative; the rounding of values ~1e-3 J over 2h = 2e-9 m gives
        // ~1e-10 N absolute. The forces here are ~10² N.
        assert!((fd - g[k]).abs() <= 1e-6 * g[k].abs() + 1e-6, "variable {k}: gradient {} vs differences {fd}", g[k]);
    }
}

#[test]
fn nine_particle_cell_relaxes_below_the_tolerance_faster_than_gradient_descent() {
    let tol = 1e-6;
    let mut lbfgs = nine_particle_cell();
    let r = lbfgs.relax(&RelaxSettings::new(tol)).unwrap();
    assert!(r.max_overlap_before > 0.25 * R, "{r:?}");
    assert!(r.converged && r.max_overlap_after <= tol, "{r:?}");
    assert_monotone(&r);
    let mut gd = nine_particle_cell();
    let settings = RelaxSettings { method: Method::GradientDescent, ..RelaxSettings::new(tol) };
    let g = gd.relax(&settings).unwrap();
    assert_monotone(&g);
    eprintln!(
        "nine-particle cell: L-BFGS {} iterations ({} evaluations), gradient descent {} ({}; converged {})",
        r.iterations, r.evaluations, g.iterations, g.evaluations, g.converged
    );
    assert!(r.iterations < g.iterations, "L-BFGS {} vs gradient descent {}", r.iterations, g.iterations);

    // The relaxed cell is at rest: 2000 steps (0.2 ms) give it no more kinetic
    // energy than a millionth of what the overlapped cell stored.
    let stored = {
        let mut cell = nine_particle_cell();
        let mut f = Potential::new(&mut cell, &[]);
        let x = f.start();
        let mut g = vec![0.0; x.len()];
        f.evaluate(&x, &mut g).unwrap()
    };
    let mut ek: f64 = 0.0;
    for _ in 0..2000 {
        let s = lbfgs.step().unwrap();
        ek = ek.max(s.kinetic_energy);
    }
    assert!(ek < 1e-6 * stored, "kinetic energy {ek:e} J after relaxing, {stored:e} J stored before");
}

#[test]
fn a_deliberately_overlapped_nscd_pile_is_projected_below_the_tolerance() {
    let scene = ballast::scene::Scene::load("data/pentagon_pile_536.toml").unwrap();
    let settled = scene.build().unwrap();
    let c0 = settled.configuration();
    // Every grain pushed down by up to a fifth of its inradius (a fixed
    // pseudo-random sequence): overlaps of the order of 1 mm.
    let mut pushed = c0.clone();
    for (k, &i) in c0.bodies.iter().enumerate() {
        let r = settled.bodies.info[i].shape.inner_radius();
        let u = ((k as f64 * 0.618_033_988_75).fract() * 2.0 - 1.0).abs();
        pushed.body_mut(k)[1] -= 0.2 * r * u;
    }
    let mut sys = settled.clone();
    sys.set_configuration(&pushed).unwrap();
    let tol = 1e-5;
    let r = sys.clone().relax(&RelaxSettings::new(tol)).unwrap();
    let mut relaxed = sys.clone();
    let r2 = relaxed.relax(&RelaxSettings::new(tol)).unwrap();
    assert_eq!(r, r2, "same input, same numbers");
    assert!(r.max_overlap_before > 1e-4, "{r:?}");
    assert!(r.converged && r.max_overlap_after <= tol, "{r:?}");
    assert_monotone(&r);
    // Moving as little as possible: no grain moves further than the push it got
    // back (1/5 of the largest inradius), and the relaxed pile is at least as
    // close to the pushed one, in the metric of the masses, as the settled pile
    // it came from (which has overlaps of its own up to the tolerance's order).
    let c1 = relaxed.configuration();
    let dist = |a: &ballast::engine::Configuration| {
        let mut s = 0.0;
        for (k, &i) in a.bodies.iter().enumerate() {
            let info = &sys.bodies.info[i];
            let (p, q) = (a.body(k), pushed.body(k));
            s += info.mass * ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)) + info.inertia * (p[2] - q[2]).powi(2);
        }
        s.sqrt()
    };
    eprintln!(
        "overlapped pile: {:.3e} m -> {:.3e} m in {} iterations ({} evaluations), largest move {:.3e}; distance from the pushed pile: relaxed {:.4e}, settled {:.4e}",
        r.max_overlap_before, r.max_overlap_after, r.iterations, r.evaluations, r.largest_move, dist(&c1), dist(&c0)
    );
    assert!(dist(&c1) <= dist(&c0), "relaxed {} vs settled {}", dist(&c1), dist(&c0));
    let gd_settings =
        RelaxSettings { method: Method::GradientDescent, max_iterations: 2000, ..RelaxSettings::new(tol) };
    let gd = sys.clone().relax(&gd_settings).unwrap();
    eprintln!("gradient descent: {} iterations, converged {}", gd.iterations, gd.converged);
    assert!(r.iterations < gd.iterations);
    // The relaxed pile steps at rest: no overlap beyond the tolerance's order appears.
    for _ in 0..50 {
        let s = relaxed.step().unwrap();
        assert!(s.max_overlap < 5.0 * tol, "{:e}", s.max_overlap);
    }
}
