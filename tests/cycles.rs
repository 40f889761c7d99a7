//! Per-cycle settlement statistics (`cycles.csv`) against a quasi-static spring.

use crate::common;
use crate::scratch;
use ballast::nscd::{Harmonic, Load, Spring};
use ballast::run::{CyclePlan, RunOptions, RunPlan, Runner};
use common::*;

/// A pad on a stiff sublayer spring (k = k_N/L0 = 2.05e8 N/m, natural frequency
/// 2.5 kHz) under F = A + B cos(2π f t − φ), A = −100 N, B = −50 N, f = 20 Hz,
/// φ = −π, no gravity. Far below resonance the pad follows y = F/k, so the mean
/// settlement over a cycle is −A/k (the 500 samples of the cosine sum to zero) and
/// the settlement at the load minimum (|F| = 50 N at the start of each cycle) is
/// 50/k.
#[test]
fn cycle_settlement_of_a_sprung_pad_is_the_quasi_static_deflection() {
    let h = 1e-4;
    let mut s = system(h, 0.0, 0.0);
    s.params.gravity = [0.0, 0.0];
    let p = rect(&mut s, 0.02, 0.02, 0.0, 0.0, 0.0, false);
    for d in [0, 2] {
        s.bodies.info[p].imposed.dof[d] = Some(Harmonic::constant(0.0));
        s.bodies.inv_m[p][d] = 0.0;
    }
    let (a, b, f) = (-100.0, -50.0, 20.0);
    s.bodies.info[p].loads.push(Load {
        direction: [0.0, 1.0],
        force: Harmonic { mean: a, amplitude: b, frequency: f, phase: -std::f64::consts::PI },
    });
    let (k_n, l0) = (4.1e6, 0.02);
    s.springs.push(Spring {
        a: p,
        point_a: [0.0, 0.0],
        b: None,
        point_b: [0.0, -l0],
        k_n,
        nu: 80.0,
        rest_length: l0,
        prestrain: 0.0,
        compression_only: false,
        impulse: 0.0,
    });
    let k = k_n / l0;
    // The library's run loop writes cycles.csv (with the positions of the pad).
    let dir = scratch::path("cycles");
    let plan = RunPlan {
        cycles: Some(CyclePlan { frequency: f, body: Some(p), positions: true }),
        ..RunPlan::new(1500, 1500)
    };
    let opts = RunOptions { checkpoint_every_s: 0.0, ..RunOptions::default() };
    Runner::from_system(s, plan).unwrap().run(&dir, &opts, &mut |_| {}).unwrap();
    let rows: Vec<Vec<f64>> = ballast::plane::rows::read_cycles(&dir.join("cycles.csv"))
        .unwrap()
        .iter()
        .map(|r| {
            vec![r.cycle as f64, r.time_s, r.settlement_mean_m, r.settlement_at_min_load_m, r.mean_grain_speed_m_s]
        })
        .collect();
    // The positions at the cycle ends: the pad's height is y0 minus the settlement
    // at the cycle's last step, to the float32 resolution of the stored displacement.
    let positions = ballast::run::positions::read(&dir).unwrap();
    assert_eq!((positions.reference.bodies.clone(), positions.cycles.len()), (vec![p], 3));
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(rows.len(), 3, "one row per 20 Hz cycle over 0.15 s");
    for r in &rows[1..] {
        // Dynamic correction (f/f0)² = 6e-5; the θ-weighted spring tracks the load to
        // O((2π f h)²) = 1.6e-5. The first cycle carries the start-up transient.
        let (mean, at_min) = (r[2], r[3]);
        assert!((mean - (-a / k)).abs() < 1e-3 * (-a / k), "mean settlement {mean} vs {}", -a / k);
        let expected = (a.abs() - b.abs()) / k;
        assert!((at_min - expected).abs() < 1e-3 * expected, "settlement at min load {at_min} vs {expected}");
        assert_eq!(r[4], 0.0, "no other body moves");
    }
    assert!((rows[2][1] - 0.15).abs() < 1e-12, "third cycle ends at t = 0.15 s");
}
