//! Rigid-body mechanics of the NSCD engine against closed-form answers:
//! free fall, friction on an incline and on a floor, impacts, a resting column.

use crate::common;
use common::*;

/// θ = 1/2 integrates a constant acceleration exactly:
/// `q_f = q_i + h u_i + θ h (u_f − u_i)` with `u_f − u_i = −g h` gives `−g h²/2`.
#[test]
fn free_fall_is_the_exact_parabola() {
    let mut s = system(1e-3, 0.5, 0.0);
    let b = regular(&mut s, 5, 0.01, 0.0, 1.0, 0.3);
    s.bodies.u[b] = [0.7, 2.0, 3.0];
    run(&mut s, 1000);
    let t = s.time;
    let q = s.bodies.q[b];
    // Round-off of 1000 additions: 1e-12 relative is far below any scheme error (h² g = 1e-5).
    assert!((q[0] - 0.7 * t).abs() < 1e-12);
    assert!((q[1] - (1.0 + 2.0 * t - 0.5 * G * t * t)).abs() < 1e-12, "y = {}", q[1]);
    assert!((q[2] - (0.3 + 3.0 * t)).abs() < 1e-12);
}

/// A block on a fixed incline of angle α with μ = 0.5 stays put when tan α < μ and
/// slides with `a = g (sin α − μ cos α)` when tan α > μ.
#[test]
fn block_on_incline_sticks_or_slides_with_coulomb_acceleration() {
    for (alpha_deg, slides) in [(20.0_f64, false), (35.0, true)] {
        let alpha = alpha_deg.to_radians();
        let mut s = system(1e-3, 0.5, 0.0);
        let (c, sn) = (alpha.cos(), alpha.sin());
        // Incline: 4 m × 0.2 m slab whose top face passes through the origin.
        rect(&mut s, 4.0, 0.2, 0.1 * sn, -0.1 * c, alpha, true);
        // 0.1 m block resting on it (its centre 0.05 m above the face along the normal).
        let b = rect(&mut s, 0.1, 0.1, -0.05 * sn, 0.05 * c, alpha, false);
        let q0 = s.bodies.q[b];
        run(&mut s, 500);
        let t = s.time;
        let d = ((s.bodies.q[b][0] - q0[0]).powi(2) + (s.bodies.q[b][1] - q0[1]).powi(2)).sqrt();
        if slides {
            let a = G * (alpha.sin() - 0.5 * alpha.cos());
            // Constant acceleration is integrated exactly (see free fall); the solver
            // tolerance 1e-10 bounds the force error: 1e-6 relative is ample.
            assert!((d - 0.5 * a * t * t).abs() < 1e-6 * d, "slid {d}, expected {}", 0.5 * a * t * t);
            // Downhill, i.e. towards −x.
            assert!(s.bodies.q[b][0] < q0[0]);
        } else {
            // Sticking: no drift beyond round-off of the solver tolerance.
            assert!(d < 1e-9, "drifted {d} m");
        }
        assert!(s.bodies.q[b][2] - alpha < 1e-9, "block tipped");
    }
}

/// A block launched at v0 on a floor with μ = 0.5 decelerates at μ g and stops
/// after `v0² / (2 μ g)`.
#[test]
fn block_launched_on_floor_stops_after_coulomb_distance() {
    let h = 1e-4;
    let mut s = system(h, 0.5, 0.0);
    floor(&mut s);
    let b = rect(&mut s, 0.1, 0.1, 0.0, 0.05, 0.0, false);
    let v0 = 1.0;
    s.bodies.u[b] = [v0, 0.0, 0.0];
    run(&mut s, 4000); // 0.4 s, the block stops at v0/(μg) = 0.204 s
    let expected = v0 * v0 / (2.0 * 0.5 * G);
    let d = s.bodies.q[b][0];
    // The stop falls inside one step: the distance is exact up to v·h = 1e-4 m
    // travelled in the last step, i.e. 1e-3 of the distance.
    assert!((d - expected).abs() < 1e-3 * expected, "stopped after {d} m, expected {expected}");
    assert!(s.bodies.u[b][0].abs() < 1e-9, "still moving");
}

/// With restitution 0 a pentagon dropped flat does not bounce: after the impact its
/// centre never rises above its resting height.
#[test]
fn pentagon_dropped_with_zero_restitution_does_not_bounce() {
    let mut s = system(1e-4, 0.5, 0.0);
    floor(&mut s);
    let r = 0.01;
    // Rotating by 18° puts the edge between vertices 3 and 4 horizontal, at the bottom.
    let angle = 18f64.to_radians();
    let rest = r * (36f64.to_radians()).cos(); // apothem
    let b = regular(&mut s, 5, r, 0.0, rest + 0.05, angle);
    let mut impacted = false;
    let mut highest_after = f64::NEG_INFINITY;
    for _ in 0..3000 {
        s.step().unwrap();
        let y = s.bodies.q[b][1];
        if !impacted && s.bodies.u[b][1] > -1e-6 && y < rest + 1e-3 {
            impacted = true;
        }
        if impacted {
            highest_after = highest_after.max(y);
        }
    }
    assert!(impacted);
    // No bounce: the centre stays at the resting height, to the contact tolerance
    // (the impact is resolved with the gap predicted to close within the step).
    assert!(highest_after - rest < 1e-6, "rose {} m above rest", highest_after - rest);
    assert!(
        (s.bodies.q[b][1] - rest).abs() < 1e-6,
        "final y {} rest {rest} q {:?} u {:?}",
        s.bodies.q[b][1],
        s.bodies.q[b],
        s.bodies.u[b]
    );
}

/// A square dropped flat from h0 with e = 0.5 rebounds to e² h0.
#[test]
fn square_dropped_with_restitution_rebounds_to_e2_h0() {
    let h = 1e-5;
    let mut s = system(h, 0.0, 0.5);
    floor(&mut s);
    let h0 = 0.1;
    let b = rect(&mut s, 0.05, 0.05, 0.0, 0.025 + h0, 0.0, false);
    let mut bounced = false;
    let mut apex: f64 = 0.0;
    for _ in 0..300_000 {
        s.step().unwrap();
        let v = s.bodies.u[b][1];
        if v > 0.0 {
            bounced = true;
        }
        if bounced {
            apex = apex.max(s.bodies.q[b][1] - 0.025);
            if v < 0.0 {
                break;
            }
        }
    }
    let expected = 0.25 * h0;
    // The impact is detected up to θ h v = 7e-6 m before contact and the apex is found
    // to within one step: 1 % of the 25 mm rebound covers both.
    assert!((apex - expected).abs() < 0.01 * expected, "apex {apex}, expected {expected}");
    assert!(s.bodies.q[b][2].abs() < 1e-9, "square rotated");
}

/// A column of blocks rests without drift and the floor carries its weight.
#[test]
fn resting_column_does_not_drift_and_floor_carries_its_weight() {
    let mut s = system(1e-3, 0.5, 0.0);
    let f = floor(&mut s);
    let n = 6;
    let side = 0.05;
    let ids: Vec<usize> = (0..n).map(|k| rect(&mut s, side, side, 0.0, side * (k as f64 + 0.5), 0.0, false)).collect();
    let q0: Vec<_> = ids.iter().map(|&i| s.bodies.q[i]).collect();
    run(&mut s, 1000);
    let weight: f64 = ids.iter().map(|&i| s.bodies.info[i].mass * G).sum();
    for (k, &i) in ids.iter().enumerate() {
        let d = (0..3).map(|c| (s.bodies.q[i][c] - q0[k][c]).abs()).fold(0.0, f64::max);
        // Stacked exactly: only round-off may move the blocks.
        assert!(d < 1e-9, "block {k} drifted {d}");
    }
    let r = s.contact_resultant(f);
    // The floor pushes the column up with its weight; solver tolerance 1e-10.
    assert!((-r[1] - weight).abs() < 1e-6 * weight, "floor reaction {} vs weight {weight}", -r[1]);
    assert!(r[0].abs() < 1e-6 * weight);
}

/// Tangential restitution (§2.8): with friction large enough to stay in the cone,
/// the weighted-mean law reverses the slip of the contact point, `U_T⁺ = −e_t U_T⁻`,
/// and the normal velocity becomes `−e_n U_N⁻`.
#[test]
fn rough_disc_impact_reverses_slip_by_tangential_restitution() {
    let h = 1e-6;
    let mut s = system(h, 10.0, 0.5);
    s.set_law(0, 0, ballast::nscd::ContactLaw { friction: 10.0, restitution_n: 0.5, restitution_t: 0.3 });
    floor(&mut s);
    let r = 0.01;
    let d = disc(&mut s, r, 0.0, r, false);
    s.params.gravity = [0.0, 0.0];
    s.bodies.u[d] = [1.0, -2.0, 0.0];
    // Contact point velocity relative to the floor: v + ω × (0, −r) = (vx + ω r, vy).
    let slip = |u: [f64; 3]| u[0] + u[2] * r;
    let before = (slip(s.bodies.u[d]), s.bodies.u[d][1]);
    while s.bodies.u[d][1] < 0.0 {
        s.step().unwrap();
    }
    let after = (slip(s.bodies.u[d]), s.bodies.u[d][1]);
    // The local law is solved exactly (the friction needed, |ΔP_T|/ΔP_N ≈ 0.25, is far
    // inside the cone μ = 10), so the normal velocity is exact to round-off. The
    // contact point is taken at q_m, where the disc overlaps the floor by up to
    // h |v_N|: its lever arm differs from r by 2e-4 r, hence 1e-3 on the slip.
    assert!((after.1 + 0.5 * before.1).abs() < 1e-9, "normal {after:?} vs {before:?}");
    assert!((after.0 + 0.3 * before.0).abs() < 1e-3 * before.0.abs(), "slip {after:?} vs {before:?}");
}

/// θ outside [0.5, 1] is refused by the library too, not only by scene files.
#[test]
fn theta_out_of_range_is_an_error() {
    let mut s = system(1e-3, 0.5, 0.0);
    s.params.theta = 0.3;
    let e = s.step().unwrap_err().to_string();
    assert!(e.contains("theta"), "{e}");
}

/// A plank whose bottom edge is tilted by 1° slides (frictionless, pressed by a
/// load, spin locked) over the top of a fixed block: an edge-to-edge contact whose
/// segment ends are the block's corners facing the tilted edge. Each end keeps the
/// normal of its own corner–edge pair, so the gap evolves at exactly `U_N` and the
/// plank rides over without sinking. (A common bisector normal, off by 0.5°, let
/// it sink by slip × tan 0.5° ≈ 4e-6 m per step here.)
#[test]
fn tilted_edge_sliding_over_a_corner_does_not_sink() {
    use ballast::nscd::{Harmonic, Load};
    let mut s = system(1e-3, 0.0, 0.0);
    s.params.gravity = [0.0, 0.0];
    rect(&mut s, 0.02, 0.02, 0.0, -0.01, 0.0, true);
    let tilt = 1f64.to_radians();
    // Plank 0.2 m × 0.01 m whose bottom edge passes 10 µm above the block's higher
    // top corner (the left one, x = −0.01, for a positive tilt). The gap exceeds the
    // 4.4 µm the edge drops over the corner in the explicit first half-step.
    let gap0 = 1e-5;
    let y = 0.005 / tilt.cos() + 0.01 * tilt.tan() + gap0;
    let p = rect(&mut s, 0.2, 0.01, 0.0, y, tilt, false);
    s.bodies.info[p].imposed.dof[0] = Some(Harmonic::constant(0.5));
    s.bodies.info[p].imposed.dof[2] = Some(Harmonic::constant(0.0));
    s.bodies.inv_m[p][0] = 0.0;
    s.bodies.inv_m[p][2] = 0.0;
    s.bodies.u[p][0] = 0.5;
    s.bodies.info[p].loads.push(Load { direction: [0.0, -1.0], force: Harmonic::constant(10.0) });
    let mut worst: f64 = 0.0;
    for _ in 0..100 {
        worst = worst.max(s.step().unwrap().max_overlap);
    }
    // 5 cm of slip over the corner: the plank closes the initial gap, then rises by
    // slip × tan 1° (to the solver tolerance).
    let rise = s.bodies.q[p][1] - y;
    let expected = 0.05 * tilt.tan() - gap0;
    assert!((rise - expected).abs() < 1e-9, "rose {rise}, expected {expected}");
    // Round-off and the solver tolerance only (the old bisector normal gave ~4e-4 m).
    assert!(worst < 1e-8, "overlap {worst:.3e} m");
}
