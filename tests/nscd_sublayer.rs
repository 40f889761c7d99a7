//! Viscoelastic sublayer springs (law 17) against the damped linear oscillator.

use crate::common;
use ballast::nscd::{Harmonic, Spring, System};
use common::*;

/// A `side`-square pad moving only vertically (vx and spin imposed to 0).
fn pad(s: &mut System, side: f64, y: f64) -> usize {
    let i = rect(s, side, side, 0.0, y, 0.0, false);
    s.bodies.info[i].imposed.dof[0] = Some(Harmonic::constant(0.0));
    s.bodies.info[i].imposed.dof[2] = Some(Harmonic::constant(0.0));
    s.bodies.inv_m[i][0] = 0.0;
    s.bodies.inv_m[i][2] = 0.0;
    i
}

fn spring_to_ground(a: usize, anchor_y: f64, k_n: f64, nu: f64, l0: f64) -> Spring {
    Spring {
        a,
        point_a: [0.0, 0.0],
        b: None,
        point_b: [0.0, anchor_y],
        k_n,
        nu,
        rest_length: l0,
        prestrain: 0.0,
        compression_only: false,
        impulse: 0.0,
    }
}

/// Times of the upward zero crossings of `x`, linearly interpolated.
fn upward_crossings(t: &[f64], x: &[f64]) -> Vec<f64> {
    (1..x.len())
        .filter(|&k| x[k - 1] < 0.0 && x[k] >= 0.0)
        .map(|k| t[k - 1] + (t[k] - t[k - 1]) * (-x[k - 1]) / (x[k] - x[k - 1]))
        .collect()
}

/// A pad of mass m on one spring: `m ẍ + (ν/L0) ẋ + (k_N/L0) x = 0` about the
/// equilibrium `x_eq = −m g L0 / k_N`. Its damped frequency is
/// `ω_d = ω0 √(1 − ζ²)`, `ω0 = √(k_N/(L0 m))`, `ζ = ν / (2 L0 m ω0)`.
#[test]
fn pad_on_spring_oscillates_at_analytic_frequency_and_damping() {
    let h = 1e-5;
    let mut s = system(h, 0.0, 0.0);
    let (l0, k_n, nu) = (0.02, 4100.0, 0.5);
    let p = pad(&mut s, 0.02, 0.0);
    s.springs.push(spring_to_ground(p, -l0, k_n, nu, l0));
    let m = s.bodies.info[p].mass;
    let (k, c) = (k_n / l0, nu / l0);
    let omega0 = (k / m).sqrt();
    let zeta = c / (2.0 * m * omega0);
    let omega_d = omega0 * (1.0 - zeta * zeta).sqrt();
    let y_eq = -m * G / k;
    // Start from rest at the unstretched length: amplitude m g / k.
    let (mut t, mut x) = (vec![0.0], vec![-y_eq]);
    for _ in 0..((20.0 * std::f64::consts::TAU / omega_d) / h) as usize {
        s.step().unwrap();
        t.push(s.time);
        x.push(s.bodies.q[p][1] - y_eq);
    }
    let ups = upward_crossings(&t, &x);
    let periods = (ups.len() - 1) as f64;
    let measured = std::f64::consts::TAU * periods / (ups[ups.len() - 1] - ups[0]);
    // θ = 1/2 is the trapezoidal rule for the spring: its frequency error is
    // (ω h)²/12 ≈ 2e-6 here; interpolated crossings are exact to O(h²) too.
    assert!((measured - omega_d).abs() < 1e-4 * omega_d, "ω_d {measured} vs {omega_d}");
    // Damping ratio from the decay of the peaks over all periods (log decrement).
    let peak = |a: f64, b: f64| {
        t.iter().zip(&x).filter(|(ti, _)| **ti >= a && **ti < b).map(|(_, xi)| *xi).fold(f64::MIN, f64::max)
    };
    let first = peak(ups[0], ups[1]);
    let last = peak(ups[ups.len() - 2], ups[ups.len() - 1]);
    let delta = (first / last).ln() / (periods - 1.0);
    let zeta_measured = delta / (4.0 * std::f64::consts::PI * std::f64::consts::PI + delta * delta).sqrt();
    eprintln!("ω_d {measured} (analytic {omega_d}), ζ {zeta_measured} (analytic {zeta}), {periods} periods");
    // Peaks are sampled every h: amplitude error (ω h)²/8 ≈ 3e-6, negligible against
    // the 1 % tolerance on a ratio taken from amplitudes decaying by e^{-2πζ·18}.
    assert!((zeta_measured - zeta).abs() < 0.01 * zeta, "ζ {zeta_measured} vs {zeta}");
}

/// Sublayer stiffness up to 1000 × 4100 at dt = 2e-4 s (ω h ≈ 3) stays stable:
/// the implicit treatment never amplifies the motion.
#[test]
fn stiff_spring_is_stable_at_large_step() {
    for factor in [1.0, 100.0, 1000.0] {
        let h = 2e-4;
        let mut s = system(h, 0.5, 0.0);
        let (l0, k_n, nu) = (0.02, 4100.0 * factor, 80.0);
        let p = pad(&mut s, 0.02, 0.0);
        s.springs.push(spring_to_ground(p, -l0, k_n, nu, l0));
        let amp0 = s.bodies.info[p].mass * G * l0 / k_n;
        let mut max_dev: f64 = 0.0;
        for _ in 0..5000 {
            s.step().unwrap();
            let y_eq = -amp0;
            max_dev = max_dev.max((s.bodies.q[p][1] - y_eq).abs());
        }
        // Released from the unstretched length the deviation can never exceed amp0
        // (the energy only decreases); round-off allowance 1e-9 relative.
        assert!(max_dev <= amp0 * (1.0 + 1e-9), "factor {factor}: deviation {max_dev} > {amp0}");
        assert!((s.bodies.q[p][1] + amp0).abs() < 1e-3 * amp0, "factor {factor}: not at rest");
    }
}

/// A block resting on a sprung pad: the spring carries pad + block weight, so the
/// static compression is `(m_pad + m_block) g L0 / k_N`.
#[test]
fn block_on_sprung_pad_compresses_it_by_the_total_weight() {
    let mut s = system(2e-4, 0.5, 0.0);
    let (l0, k_n, nu) = (0.02, 4100.0 * 100.0, 80.0);
    let p = pad(&mut s, 0.02, 0.0);
    let b = rect(&mut s, 0.02, 0.02, 0.0, 0.02, 0.0, false);
    s.springs.push(spring_to_ground(p, -l0, k_n, nu, l0));
    run(&mut s, 10_000);
    let w = (s.bodies.info[p].mass + s.bodies.info[b].mass) * G;
    let force: f64 = s.spring_forces().sum();
    // Static equilibrium after 2 s (ζ ≈ 0.9 here): the spring force equals the weight
    // to the solver tolerance.
    assert!((force - w).abs() < 1e-6 * w, "spring force {force} vs weight {w}");
    let compression = -s.bodies.q[p][1];
    assert!((compression - w * l0 / k_n).abs() < 1e-6 * compression);
}
