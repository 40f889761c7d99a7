//! Tests of the accelerated solver against NLGS and closed forms.

use super::*;
use crate::geometry::{ConvexPolygon, Shape, Vec2};
use crate::nscd::contact::ContactLaw;
use crate::nscd::nlgs::{apply_impulses, solve_nlgs, NlgsProblem};
use crate::nscd::nlgs::{NlgsReport, NlgsSettings};
use crate::nscd::{BodyInfo, Measure, NscdParams, Policy, Spring, System};

fn settings(tolerance: f64) -> NlgsSettings {
    NlgsSettings {
        policy: Policy::Quad,
        tolerance,
        max_iterations: 200_000,
        split_min_rows: 0,
        measure: Measure::Check,
        ..NlgsSettings::default()
    }
}

/// Fifteen pentagons settled in a box for 0.3 s (friction 0.5), one of them
/// hung from a world anchor by a damped spring: the problem of the last step.
fn small_pile() -> NlgsProblem {
    let mut nlgs = settings(1e-8);
    nlgs.max_iterations = 20_000;
    let mut sys = System::new(NscdParams { dt: 1e-3, alert_distance: 5e-4, nlgs, ..NscdParams::default() }, 1);
    sys.set_law(0, 0, ContactLaw { friction: 0.5, ..ContactLaw::default() });
    let rect = |x0: f64, y0: f64, x1: f64, y1: f64| [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
    for (name, v) in [
        ("floor", rect(-0.3, -0.1, 0.3, 0.0)),
        ("left", rect(-0.4, 0.0, -0.3, 1.0)),
        ("right", rect(0.3, 0.0, 0.4, 1.0)),
    ] {
        let (b, q) = BodyInfo::polygon(name, &v, 0, 2700.0, 1.0).unwrap();
        sys.bodies.push(b.into_fixed(), q, [0.0; 3]);
    }
    for k in 0..15 {
        let (i, j) = (k % 5, k / 5);
        let shape = Shape::Polygon(ConvexPolygon::regular(5, 0.045).unwrap());
        let b = BodyInfo::new("p", shape, 0, 2400.0, 1.0).unwrap();
        let x = -0.24 + 0.12 * i as f64 + 0.01 * j as f64;
        sys.bodies.push(b, [x, 0.05 + 0.1 * j as f64, 0.37 * k as f64], [0.0; 3]);
    }
    sys.springs.push(Spring {
        a: 3,
        point_a: [0.0, 0.0],
        b: None,
        point_b: [-0.24, 0.9],
        k_n: 200.0,
        nu: 5.0,
        rest_length: 0.8,
        prestrain: 0.0,
        compression_only: false,
        impulse: 0.0,
    });
    for _ in 0..300 {
        sys.step().unwrap();
    }
    sys.nlgs_problem()
}

fn solve(p: &NlgsProblem, s: &NlgsSettings, apgd: Option<ApgdOptions>) -> (NlgsProblem, NlgsReport) {
    let mut q = p.clone();
    let r = match apgd {
        Some(o) => {
            solve_apgd_with(s, &o, &mut ApgdWorkspace::default(), &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs)
        }
        None => solve_nlgs(s, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs),
    };
    (q, r)
}

/// On a small pile APGD (every variant) reaches NLGS's solution. The
/// reference is NLGS to `quad` 1e-12. A solve to tolerance τ is within about
/// κ τ |W P| of the solution, κ the conditioning: measured on this pile, NLGS
/// to τ = 1e-9 is 6.8e-9 m/s from the reference (velocities), so every
/// variant, solved to 1e-9, must be within 2e-8 m/s (3× NLGS's own distance),
/// and the spring's impulse (a function of its velocity) within the
/// corresponding `hβ · 2e-8` plus round-off. Individual contact impulses are
/// not compared: the packing is hyperstatic (pentagons touching edge to edge
/// or wedged between walls), so they are not unique — NLGS to 1e-9 and APGD
/// to 1e-9 differ by 2.4e-5 N·s on some normal impulse while both satisfy
/// the law to the tolerance, and APGD stays at that distance when both are
/// tightened. The per-body resultants `H P` are unique: their difference is
/// the velocities' times the masses, tested through the velocities.
#[test]
fn reaches_the_nlgs_solution_on_a_small_pile() {
    let p = small_pile();
    assert!(p.rows.len() > 20 && p.springs.len() == 1, "{} rows", p.rows.len());
    let (reference, r0) = solve(&p, &settings(1e-12), None);
    assert!(r0.converged, "{r0:?}");
    let s = settings(1e-9);
    let (nlgs, r1) = solve(&p, &s, None);
    let distance = |x: &NlgsProblem| {
        x.u.iter().zip(&reference.u).flat_map(|(a, b)| (0..3).map(move |d| (a[d] - b[d]).abs())).fold(0.0, f64::max)
    };
    let d_nlgs = distance(&nlgs);
    assert!(r1.converged && d_nlgs < 1e-8, "{r1:?}: {d_nlgs:e}");
    for (friction, precondition, nlgs_first) in [
        (FrictionBound::Iterate, true, 0),
        (FrictionBound::Iterate, false, 0),
        (FrictionBound::Outer, true, 0),
        (FrictionBound::Iterate, true, 5),
        (FrictionBound::Iterate, true, 50),
    ] {
        let o = ApgdOptions { friction, precondition, nlgs_first, ..ApgdOptions::default() };
        let (x, r) = solve(&p, &s, Some(o));
        assert!(r.converged, "{o:?}: {r:?}");
        let du = distance(&x);
        assert!(du < 2e-8, "{o:?}: velocities {du:e} m/s from the reference (NLGS: {d_nlgs:e})");
        let ds = (x.springs[0].p - reference.springs[0].p).abs();
        assert!(ds < p.springs[0].h_beta * 2e-8 + 1e-12, "{o:?}: spring impulses differ by {ds:e} N·s");
        // The velocities are those of the impulses.
        let mut u = p.u.clone();
        apply_impulses(&mut u, &p.inv_m, &x.rows, &x.springs);
        let drift = u.iter().zip(&x.u).flat_map(|(a, b)| (0..3).map(move |d| (a[d] - b[d]).abs())).fold(0.0, f64::max);
        assert!(drift < 1e-12, "{drift:e}");
    }
}

/// A 2 kg block (inertia 0.01 kg·m²) on a fixed floor, one contact at `point`,
/// coming down at 1 m/s and sliding at `vx`.
fn block(point: [f64; 2], vx: f64, friction: f64) -> NlgsProblem {
    let inv_m = vec![[0.5, 0.5, 100.0], [0.0; 3]];
    let u = vec![[vx, -1.0, 0.0], [0.0; 3]];
    let row = ContactRow::new(
        (0, 1),
        Vec2::new(point[0], point[1]),
        Vec2::new(0.0, 1.0),
        (Vec2::new(0.0, 0.05), Vec2::new(0.0, -0.05)),
        (&inv_m[0], &inv_m[1]),
        (&u[0], &u[1]),
        0.0,
        1e-3,
        &ContactLaw { friction, ..ContactLaw::default() },
    );
    NlgsProblem { u, inv_m, rows: vec![row], springs: Vec::new() }
}

/// Frictionless contact off the centre: `P_N = (c − U_free,N) / W_NN`, exactly.
#[test]
fn single_frictionless_contact_matches_the_closed_form() {
    let p = block([0.03, 0.0], 0.4, 0.0);
    let w_nn = 0.5 + 100.0 * 0.03 * 0.03; // 1/m + (r × n)² / I
    let exact = 1.0 / w_nn;
    assert!((p.rows[0].w.nn - w_nn).abs() < 1e-12);
    let apgd = ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() };
    for o in [apgd, ApgdOptions { precondition: false, ..apgd }] {
        let (x, r) = solve(&p, &settings(1e-10), Some(o));
        assert!(r.converged, "{r:?}");
        assert!((x.rows[0].p[0] - exact).abs() < 1e-10 * exact, "{} vs {exact}", x.rows[0].p[0]);
        assert_eq!(x.rows[0].p[1], 0.0);
        let un = x.u[0][1] + 0.03 * x.u[0][2]; // h_n · u = v_y + (r × n) ω
        assert!(un.abs() < 1e-10, "{un}");
    }
}

/// A block sliding at 2 m/s, contact under its centre (`W_NT = 0`), μ = 0.3:
/// friction saturated, `P_N = m`, `P_T = μ m` against the motion, and the block
/// leaves at `2 − μ` m/s, spun by the friction's moment.
#[test]
fn sliding_block_saturates_friction() {
    let p = block([0.0, 0.0], 2.0, 0.3);
    assert_eq!(p.rows[0].w.nt, 0.0);
    for friction in [FrictionBound::Iterate, FrictionBound::Outer] {
        let o = ApgdOptions { friction, nlgs_first: 0, ..ApgdOptions::default() };
        let (x, r) = solve(&p, &settings(1e-10), Some(o));
        assert!(r.converged, "{o:?}: {r:?}");
        let [pn, pt] = x.rows[0].p;
        assert!((pn - 2.0).abs() < 1e-9, "{pn}");
        // t = (−1, 0): the block's U_T = −2 < 0, so P_T = +μ P_N pushes along t, against the motion.
        assert!((pt - 0.6).abs() < 1e-9, "{pt}");
        assert!((x.u[0][0] - 1.7).abs() < 1e-9 && x.u[0][1].abs() < 1e-9, "{:?}", x.u[0]);
        // r × t = (0, −0.05) × (−1, 0) = −0.05: ω = 100 × (−0.05) × 0.6.
        assert!((x.u[0][2] + 3.0).abs() < 1e-8, "{:?}", x.u[0]);
    }
}

/// A reused workspace gives the same numbers as a fresh one.
#[test]
fn workspace_reuse_is_transparent() {
    let p = small_pile();
    let s = settings(1e-6);
    let o = ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() };
    let mut ws = ApgdWorkspace::default();
    let mut runs = Vec::new();
    for _ in 0..2 {
        let mut q = p.clone();
        let r = solve_apgd_with(&s, &o, &mut ws, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs);
        runs.push((r, q.u, q.rows.iter().map(|r| r.p).collect::<Vec<_>>()));
    }
    assert_eq!(runs[0].0, runs[1].0);
    assert_eq!(runs[0].1, runs[1].1);
    assert_eq!(runs[0].2, runs[1].2);
}
