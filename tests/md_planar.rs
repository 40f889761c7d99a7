//! The planar MD engine (soft contacts on 2D bodies) against closed forms:
//! impact time and restitution of the linear law, the static overlap of a face
//! resting on a floor (linear and Hertz-like), stick and slip on an incline at
//! `tan α = μ`, and a pad on a sublayer spring at the frequency it has under NSCD.

use crate::common;
use ballast::md::planar::{PlanarParams, PlanarSystem, SoftLaw, SoftModel};
use ballast::plane::{BodyInfo, Harmonic, Spring};
use std::f64::consts::{PI, TAU};

const RHO: f64 = 2700.0;

fn law(model: SoftModel, stiffness: f64, restitution: f64, friction: f64) -> SoftLaw {
    SoftLaw { model, normal_stiffness: stiffness, tangential_ratio: 0.5, restitution, friction }
}

fn system(dt: f64, gravity: [f64; 2], law: SoftLaw) -> PlanarSystem {
    let mut s = PlanarSystem::new(PlanarParams { dt, gravity, alert_distance: 0.0 }, 1);
    s.set_law(0, 0, law).unwrap();
    s
}

/// An axis-aligned `w × h` box, lower left corner at `(x, y)`.
fn boxed(s: &mut PlanarSystem, name: &str, x: f64, y: f64, w: f64, h: f64, fixed: bool) -> usize {
    let v = [[x, y], [x + w, y], [x + w, y + h], [x, y + h]];
    let (b, q) = BodyInfo::polygon(name, &v, 0, RHO, 1.0).unwrap();
    s.bodies.push(if fixed { b.into_fixed() } else { b }, q, [0.0; 3])
}

/// A disc launched at 1 m/s onto a fixed floor, no gravity, linear law with
/// restitution e: the contact lasts `t_c = π/ω_d`, `ω_d = ω0 √(1 − α²)`,
/// `α = −ln e/√(π² + ln² e)`, and the disc leaves at `e` m/s (David et al. §2).
#[test]
fn linear_impact_has_the_analytic_contact_time_and_restitution() {
    let (k, e, r) = (1e6, 0.5, 0.01);
    let l = law(SoftModel::Linear, k, e, 0.3);
    let (d, q) = BodyInfo::disc("disc", [0.0, r + 1e-4], r, 0, RHO, 1.0).unwrap();
    let m = d.mass;
    let alpha = -e.ln() / (PI * PI + e.ln().powi(2)).sqrt();
    let omega_d = (k / m).sqrt() * (1.0 - alpha * alpha).sqrt();
    let t_c = PI / omega_d;
    let dt = t_c / 1000.0;
    let mut s = system(dt, [0.0, 0.0], l);
    boxed(&mut s, "floor", -0.1, -0.05, 0.2, 0.05, true);
    let disc = s.bodies.push(d, q, [0.0, -1.0, 0.0]);
    let (mut first, mut last) = (None, None);
    for k in 1..=4000u64 {
        let stats = s.step().unwrap();
        if stats.contacts > 0 {
            first.get_or_insert(k);
            last = Some(k);
        }
    }
    let steps = (last.unwrap() - first.unwrap() + 1) as f64;
    let measured = steps * dt;
    let v = s.bodies.u[disc][1];
    eprintln!("contact {measured} s (analytic {t_c}), rebound {v} m/s (e = {e})");
    // The contact starts and ends between steps: the count is exact to one step
    // at each end, 2 steps of 1000.
    assert!((measured - t_c).abs() <= 2.0 * dt, "contact time {measured} vs {t_c}");
    // Velocity Verlet gives the dashpot the half-step velocity: a lag of h/2 on
    // a force ∝ α, relative error O(α ω h) ≈ 7e-4 on the rebound here; 2e-3 allows it.
    assert!((v - e).abs() < 2e-3 * e, "rebound {v} vs {e}");
    // The spin stays zero (a central impact).
    assert!(s.bodies.u[disc][2].abs() < 1e-9);
}

/// A 0.1 m square at rest on a fixed floor: its face has two contact points,
/// each carries half the weight, and the face sits at the static overlap of the
/// pair's stiffness under the whole weight: `m g / k_n` (linear) and
/// `(m g / K)^{2/3}` (Hertz-like), whichever way the load is split.
#[test]
fn a_face_at_rest_sits_at_the_static_overlap_of_its_weight() {
    for (model, k) in [(SoftModel::Linear, 1e8), (SoftModel::Hertz, 1e11)] {
        let l = law(model, k, 0.2, 0.5);
        let mut s = system(2e-5, [0.0, -common::G], l);
        boxed(&mut s, "floor", -0.5, -0.1, 1.0, 0.1, true);
        let b = boxed(&mut s, "block", 0.0, 0.0, 0.1, 0.1, false);
        let weight = s.bodies.info[b].mass * common::G;
        for _ in 0..20_000 {
            s.step().unwrap();
        }
        let expected = l.static_overlap(weight, 1.0);
        let points: Vec<_> = s.contact_forces().collect();
        assert_eq!(points.len(), 2, "{model:?}: two points on a flat face");
        let carried: f64 = points.iter().map(|c| c.r_n).sum();
        eprintln!(
            "{model:?}: overlaps {:e} {:e} m (expected {expected:e}), carried {carried} N of {weight} N",
            -points[0].gap, -points[1].gap
        );
        // After 0.4 s (about 60 periods of the contact, restitution 0.2) the
        // residual motion is below 1e-6 of the weight's overlap.
        for c in &points {
            assert!((-c.gap - expected).abs() < 1e-4 * expected, "{model:?}: overlap {} vs {expected}", -c.gap);
            assert!(
                (c.r_n - 0.5 * weight).abs() < 1e-4 * weight,
                "{model:?}: point load {} vs {}",
                c.r_n,
                0.5 * weight
            );
        }
        assert!((carried - weight).abs() < 1e-6 * weight);
        let sunk = 0.05 - s.bodies.q[b][1];
        assert!((sunk - expected).abs() < 1e-4 * expected);
    }
}

/// A 0.2 × 0.1 m block on a floor, gravity tilted by α (the floor is the incline),
/// μ = 0.5: at tan α = 0.4 it sticks (it moves only by the tangential springs'
/// elastic shear, `m g sin α / k_t`), at tan α = 0.6 it slides with
/// `a = g (sin α − μ cos α)`.
#[test]
fn a_block_on_an_incline_sticks_below_tan_alpha_mu_and_slides_above() {
    let (k, mu) = (1e8, 0.5);
    for tan in [0.4, 0.6] {
        let alpha = f64::atan(tan);
        let g = [common::G * alpha.sin(), -common::G * alpha.cos()];
        let l = law(SoftModel::Linear, k, 0.2, mu);
        let mut s = system(2e-5, g, l);
        boxed(&mut s, "incline", -2.0, -0.1, 4.0, 0.1, true);
        // Placed at its static overlap so that it starts nearly at rest.
        let b = boxed(&mut s, "block", 0.0, -1e-6, 0.2, 0.1, false);
        let m = s.bodies.info[b].mass;
        let x0 = s.bodies.q[b][0];
        let (mut t1, mut v1) = (0.0, 0.0);
        for step in 1..=20_000 {
            s.step().unwrap();
            if step == 10_000 {
                (t1, v1) = (s.time(), s.bodies.u[b][0]);
            }
        }
        let (t2, v2) = (s.time(), s.bodies.u[b][0]);
        let moved = s.bodies.q[b][0] - x0;
        if tan < mu {
            let shear = m * common::G * alpha.sin() / (0.5 * k);
            eprintln!("tan α = {tan}: moved {moved:e} m, elastic shear {shear:e} m");
            // Sticking: the block moves by the shear of its springs (plus the
            // settling of the normal overlap along the slope); 3× the shear bounds it,
            // and a slide at even 1 % of g sin α for 0.4 s would move it 3 mm.
            assert!(moved.abs() < 3.0 * shear, "sticking block moved {moved} m");
            assert!(v2.abs() < 1e-4, "sticking block at {v2} m/s");
        } else {
            let a = (v2 - v1) / (t2 - t1);
            let expected = common::G * (alpha.sin() - mu * alpha.cos());
            eprintln!("tan α = {tan}: acceleration {a} m/s² (expected {expected})");
            // Sliding at μ F_n on both points with F_n = m g cos α once the
            // landing transient has died (0.2 s, restitution 0.2): 1e-3 relative.
            assert!((a - expected).abs() < 1e-3 * expected, "sliding at {a} vs {expected}");
        }
    }
}

/// A square pad moving only vertically on one sublayer spring (law 17) to a
/// fixed anchor: it oscillates at `ω_d = ω0 √(1 − ζ²)`, `ω0 = √(k_N/(L0 m))`,
/// under the planar MD engine as under NSCD (the same spring code).
#[test]
fn a_pad_on_a_sublayer_spring_has_the_frequency_it_has_under_nscd() {
    let (l0, k_n, nu) = (0.02, 4100.0, 0.5);
    let spring = |a| Spring {
        a,
        point_a: [0.0, 0.0],
        b: None,
        point_b: [0.0, -l0],
        k_n,
        nu,
        rest_length: l0,
        prestrain: 0.0,
        compression_only: false,
        impulse: 0.0,
    };
    let slide = |info: BodyInfo| {
        info.with_imposed(ballast::plane::Imposed::new(
            Some(Harmonic::constant(0.0)),
            None,
            Some(Harmonic::constant(0.0)),
        ))
    };
    let pad = || {
        BodyInfo::polygon("pad", &[[-0.01, -0.01], [0.01, -0.01], [0.01, 0.01], [-0.01, 0.01]], 0, RHO, 1.0).unwrap()
    };
    let (info, q) = pad();
    let m = info.mass;
    let (k, c) = (k_n / l0, nu / l0);
    let omega0 = (k / m).sqrt();
    let zeta = c / (2.0 * m * omega0);
    let omega_d = omega0 * (1.0 - zeta * zeta).sqrt();
    let y_eq = -m * common::G / k;
    let h = 1e-5;
    let n = ((20.0 * TAU / omega_d) / h) as usize;
    // Frequency from the upward crossings of the equilibrium, interpolated.
    let frequency = |y: &[f64]| {
        let ups: Vec<f64> = (1..y.len())
            .filter(|&k| y[k - 1] < y_eq && y[k] >= y_eq)
            .map(|k| (k - 1) as f64 + (y_eq - y[k - 1]) / (y[k] - y[k - 1]))
            .collect();
        TAU * (ups.len() - 1) as f64 / ((ups[ups.len() - 1] - ups[0]) * h)
    };
    let mut md = system(h, [0.0, -common::G], law(SoftModel::Linear, 1e8, 0.5, 0.5));
    let p = md.bodies.push(slide(info), q, [0.0; 3]);
    md.springs.push(spring(p));
    let mut y = vec![md.bodies.q[p][1]];
    for _ in 0..n {
        md.step().unwrap();
        y.push(md.bodies.q[p][1]);
    }
    let w_md = frequency(&y);
    let mut ns = common::system(h, 0.0, 0.0);
    let (info, q) = pad();
    let p = ns.bodies.push(slide(info), q, [0.0; 3]);
    ns.springs.push(spring(p));
    let mut y = vec![ns.bodies.q[p][1]];
    for _ in 0..n {
        ns.step().unwrap();
        y.push(ns.bodies.q[p][1]);
    }
    let w_nscd = frequency(&y);
    eprintln!("ω_d: planar MD {w_md}, NSCD {w_nscd}, analytic {omega_d} rad/s");
    // Both integrators are second order for the spring ((ω h)² ≈ 2e-5 relative
    // here); the dashpot's half-step lag under Verlet shifts ω_d by O(ζ ω h) ≈ 1e-5.
    // 1e-4 of ω_d allows both and would catch a wrong stiffness, mass or lever arm.
    assert!((w_md - omega_d).abs() < 1e-4 * omega_d, "planar MD {w_md} vs {omega_d}");
    assert!((w_nscd - omega_d).abs() < 1e-4 * omega_d, "NSCD {w_nscd} vs {omega_d}");
    assert!((w_md - w_nscd).abs() < 1e-4 * omega_d);
}
