//! The estimators of the settlement driver against closed forms (Karrech et al.
//! 2007, §3): Shenton's least squares (eqs. 20–21) recovers `a` and `b` from
//! `a ln N + b N` data, the linear estimation (eq. 16) extrapolates a line, the
//! accuracy measures (eqs. 13–14) and the configuration error (eq. 22) match
//! their hand-computed values, and the Chernoff bound (eq. 15) its closed form.

use ballast::engine::Configuration;
use ballast::settlement::{
    chernoff_cycles, chernoff_probability, configuration_error, extrapolate, extrapolate_within, fit, law_named,
    trend_moves, Linear, ResidualLaw, Shenton, ShentonDecelerating, ShentonOrigin, Training,
};

/// A configuration of `bodies` bodies with 3 coordinates (x, y, θ) from `f(body, coordinate)`.
fn config(bodies: usize, f: impl Fn(usize, usize) -> f64) -> Configuration {
    let q = (0..bodies).flat_map(|b| (0..3).map(move |d| (b, d))).map(|(b, d)| f(b, d)).collect();
    Configuration { dof: 3, bodies: (0..bodies).collect(), q }
}

/// Body `b`'s coordinate `d` follows `a ln N + b N` with its own coefficients,
/// of one sign (a settlement that decelerates: the default law's set).
fn shenton_coefficients(b: usize, d: usize) -> (f64, f64) {
    let sign = if (b + d).is_multiple_of(2) { -1.0 } else { 1.0 };
    (sign * (1e-4 * (1.0 + b as f64) - 2e-5 * d as f64), sign * (3e-7 * (d as f64 + 1.0) + 1e-8 * b as f64))
}

/// A window of cycles `n0 ..= n0 + k` on top of an origin, each coordinate
/// following `law(b, d, N)` (m or rad) from the origin.
fn window(bodies: usize, n0: u64, k: u64, law: impl Fn(usize, usize, f64) -> f64) -> Training {
    let origin = config(bodies, |b, d| 0.1 * b as f64 + 0.01 * d as f64);
    let mut t = Training::new(origin.clone());
    for n in n0..=n0 + k {
        let nf = n as f64;
        t.push(nf, config(bodies, |b, d| origin.q[3 * b + d] + law(b, d, nf)));
    }
    t
}

#[test]
fn shenton_least_squares_recovers_a_and_b_and_extrapolates_the_law() {
    // k_i = 10 initial cycles, then a window of k = 20.
    let t = window(4, 10, 20, |b, d, n| {
        let (a, bb) = shenton_coefficients(b, d);
        a * n.ln() + bb * n
    });
    // Eqs. (20)-(21) as printed, and the law with a constant (which must find 0).
    // Exact data: rounding only. The closed forms are exact to 1e-9 relative (the
    // normal equations' condition number is ~1e4 here); the singular-value
    // solution of the 3-column design carries the design's condition number
    // (~1e5 for N in 10..30) times the data's rounding (~1e-16 of 0.3 m
    // coordinates, ~1e-17 m): ~1e-12 m of `c`, ~1e-9 relative of `a`, `b`.
    for (law, tol) in [(&ShentonOrigin as &dyn ResidualLaw, 1e-9), (&Shenton, 1e-7)] {
        let f = fit(law, &t, 3, 2).unwrap();
        for b in 0..4 {
            for d in 0..3 {
                let (a, bb) = shenton_coefficients(b, d);
                let c = f.coefficients[b * 3 + d];
                assert!(c[0].abs() < 1e-10, "{}: constant {}", law.name(), c[0]);
                assert!((c[1] - a).abs() <= tol * a.abs().max(1e-12), "{}: a: {} vs {a}", law.name(), c[1]);
                assert!((c[2] - bb).abs() <= tol * bb.abs().max(1e-10), "{}: b: {} vs {bb}", law.name(), c[2]);
            }
        }
        // Exact data: the error terms are rounding.
        assert!(f.f_xi < 1e-12, "{}: f_xi = {}", law.name(), f.f_xi);
        // The extrapolation 20 cycles on is the law's value at N = 50 (eq. 17).
        let e = extrapolate(law, &t, &f, 20.0);
        for b in 0..4 {
            for d in 0..3 {
                let (a, bb) = shenton_coefficients(b, d);
                let want = t.origin.q[3 * b + d] + a * 50f64.ln() + bb * 50.0;
                assert!((e.q[3 * b + d] - want).abs() < 1e-11, "{}: body {b} coordinate {d}", law.name());
            }
        }
    }
}

#[test]
fn shenton_over_the_history_ignores_the_offsets_the_jumps_left() {
    // Three runs of computed cycles (11..=30, 51..=70, 91..=110) of `a ln N + b N`,
    // each shifted by what the jump before it got wrong (0, +3 mm, −2 mm): the
    // per-segment constants absorb the shifts, the slopes are the law's.
    let shift = |n: f64| {
        if n > 90.0 {
            -2e-3
        } else if n > 50.0 {
            3e-3
        } else {
            0.0
        }
    };
    let law = |b: usize, d: usize, n: f64| {
        let (a, bb) = shenton_coefficients(b, d);
        a * n.ln() + bb * n + shift(n)
    };
    let full = window(3, 10, 100, law);
    let mut t = Training::new(full.origin.clone());
    for (n, c) in full.cycles.iter().zip(&full.configurations) {
        match *n as u64 {
            51 | 91 => t.push_segment(*n, c.clone()),
            10..=30 | 52..=70 | 92..=110 => t.push(*n, c.clone()),
            _ => {}
        }
    }
    assert_eq!(t.segments.iter().filter(|&&s| s == 2).count(), 20);
    let f = fit(&Shenton, &t, 3, 2).unwrap();
    // Exact data: rounding, amplified by the design's condition number (as above).
    for b in 0..3 {
        for d in 0..3 {
            let (a, bb) = shenton_coefficients(b, d);
            let c = f.coefficients[b * 3 + d];
            assert!((c[1] - a).abs() <= 1e-7 * a.abs(), "a: {} vs {a}", c[1]);
            assert!((c[2] - bb).abs() <= 1e-7 * bb.abs().max(1e-10), "b: {} vs {bb}", c[2]);
            // The constant is the last segment's shift.
            assert!((c[0] + 2e-3).abs() < 1e-10, "constant {}", c[0]);
        }
    }
    // The measures are over the last window (20 points: 19 increments), where the law fits exactly.
    assert_eq!(f.k, 19);
    assert!(f.f_xi < 1e-12, "f_xi {}", f.f_xi);
    // The extrapolation 40 cycles on moves each coordinate by the law's increment.
    let e = extrapolate(&Shenton, &t, &f, 40.0);
    let last = t.configurations.last().unwrap();
    for b in 0..3 {
        for d in 0..3 {
            let (a, bb) = shenton_coefficients(b, d);
            let want = last.q[3 * b + d] + a * (150f64 / 110.0).ln() + bb * 40.0;
            assert!((e.q[3 * b + d] - want).abs() < 1e-11, "body {b} coordinate {d}");
        }
    }
    // The same points as one run (the shifts taken for motion) give another law.
    let mut one = t.clone();
    one.segments.iter_mut().for_each(|s| *s = 0);
    let wrong = fit(&Shenton, &one, 3, 2).unwrap();
    let (a, _) = shenton_coefficients(0, 1);
    assert!((wrong.coefficients[1][1] - a).abs() > 1e-2 * a.abs());
}

#[test]
fn shenton_decelerating_does_not_extrapolate_an_acceleration_or_a_return() {
    // A window that ends in an avalanche fits a < 0 < b (an accelerating motion);
    // one that levels off and dips fits b < 0 < a (a return). The law takes
    // the better one-term law instead: here the data are exactly `c + a ln N`
    // or `c + b N` plus a small term of the other sign, so the one-term law
    // fitted is that term's, and the extrapolation keeps its direction.
    let accelerating = window(1, 10, 20, |_, d, n| if d == 1 { -2e-4 * n.ln() + 2e-5 * n } else { 0.0 });
    let f = fit(&ShentonDecelerating, &accelerating, 3, 2).unwrap();
    let [_, a, b] = f.coefficients[1];
    assert!(a * b >= 0.0, "a = {a}, b = {b}");
    let returning = window(1, 10, 20, |_, d, n| if d == 1 { 1e-3 * n.ln() - 1e-6 * n } else { 0.0 });
    let f = fit(&ShentonDecelerating, &returning, 3, 2).unwrap();
    let [_, a, b] = f.coefficients[1];
    assert!(a * b >= 0.0 && a > 0.0, "a = {a}, b = {b}");
    // The free laws, with a constant or through the origin (the paper's), find
    // the data's law.
    for law in [&Shenton as &dyn ResidualLaw, &ShentonOrigin] {
        let [_, a, b] = fit(law, &returning, 3, 2).unwrap().coefficients[1];
        assert!((a - 1e-3).abs() < 1e-9 && (b + 1e-6).abs() < 1e-12, "{}: a = {a}, b = {b}", law.name());
    }
    // Far past the turning point N = a/b = 1000 (u(10 030) < u(30)), the free law goes back down;
    // the constrained one keeps rising.
    let last = returning.configurations.last().unwrap().q[1];
    let at = |law: &dyn ResidualLaw| extrapolate(law, &returning, &fit(law, &returning, 3, 2).unwrap(), 10000.0).q[1];
    assert!(at(&ShentonDecelerating) > last && at(&Shenton) < last);
}

#[test]
fn shenton_with_a_constant_follows_a_seated_sample_where_the_law_through_the_origin_cannot() {
    // A seating of 10 mm, then 0.1 µm per cycle: a window from cycle 10 to 30.
    let t = window(1, 10, 20, |_, d, n| if d == 1 { -(1e-2 + 1e-7 * n) } else { 0.0 });
    let last = t.configurations.last().unwrap().q[1];
    let with = extrapolate(&Shenton, &t, &fit(&Shenton, &t, 3, 2).unwrap(), 20.0).q[1];
    let origin = extrapolate(&ShentonOrigin, &t, &fit(&ShentonOrigin, &t, 3, 2).unwrap(), 20.0).q[1];
    // The data are a line: the law with a constant continues it (to the rounding
    // of a 1e-2 m offset through a design of condition ~1e5: 1e-12 m).
    assert!((with - (last - 20.0 * 1e-7)).abs() < 1e-11, "with a constant: {:e}", with - last);
    // Through the origin, the fit bends: it predicts the sleeper rising.
    assert!(origin - last > 1e-5, "through the origin: {:e}", origin - last);
}

#[test]
fn linear_estimation_is_the_mean_increment_of_eq_16() {
    // A line: exact; the trend's increments give g_u = (1/k)(k Σ_{b,d} s²)^½.
    let slope = |b: usize, d: usize| 1e-6 * (b as f64 + 1.0) * (1.0 - d as f64);
    let t = window(3, 10, 20, |b, d, n| slope(b, d) * n);
    let f = fit(&Linear, &t, 3, 2).unwrap();
    let e = extrapolate(&Linear, &t, &f, 15.0);
    let last = t.configurations.last().unwrap();
    for b in 0..3 {
        for d in 0..3 {
            let want = last.q[3 * b + d] + 15.0 * slope(b, d);
            assert!((e.q[3 * b + d] - want).abs() < 1e-15);
        }
    }
    let sum_s2: f64 = (0..3).flat_map(|b| (0..2).map(move |d| slope(b, d).powi(2))).sum();
    let g_u = (20.0 * sum_s2).sqrt() / 20.0;
    assert!((f.g_u - g_u).abs() < 1e-12 * g_u, "g_u {} vs {g_u}", f.g_u);
    // Rounding only: coordinates of 0.1-0.3 m carry ~3e-17 m of it per point.
    assert!(f.f_xi < 1e-15, "f_xi = {}", f.f_xi);

    // Scattered data: eq. (16) uses the end points only, u_k + (h/k) Σ [u_p − u_{p−1}].
    let noise = |n: f64| 1e-6 * (1.7 * n).sin();
    let t = window(1, 0, 10, |_, d, n| if d == 1 { -2e-6 * n + noise(n) } else { 0.0 });
    let f = fit(&Linear, &t, 3, 2).unwrap();
    let u: Vec<f64> = t.configurations.iter().map(|c| c.q[1] - t.origin.q[1]).collect();
    let increments: f64 = u.windows(2).map(|w| w[1] - w[0]).sum();
    let want = u[10] + 7.0 / 10.0 * increments;
    let e = extrapolate(&Linear, &t, &f, 7.0);
    assert!((e.q[1] - t.origin.q[1] - want).abs() < 1e-16);
    // f_ξ of eq. (14) by hand: the error terms about the chord through the ends.
    let xi2: f64 = (0..=10).map(|p| (u[p] - (u[0] + (u[10] - u[0]) * p as f64 / 10.0)).powi(2)).sum();
    assert!((f.f_xi - xi2.sqrt() / 10.0).abs() < 1e-16);
}

#[test]
fn rotations_are_extrapolated_but_not_measured() {
    // Only θ moves: the measures (translations) see nothing.
    let t = window(2, 5, 10, |_, d, n| if d == 2 { 1e-3 * n } else { 0.0 });
    let f = fit(&Linear, &t, 3, 2).unwrap();
    assert_eq!(f.g_u, 0.0);
    let e = extrapolate(&Linear, &t, &f, 10.0);
    assert!((e.q[2] - t.configurations.last().unwrap().q[2] - 1e-2).abs() < 1e-15);
    // Fitting only the translations keeps θ at its last value (an MD sphere's orientation).
    let f = fit(&Linear, &t, 2, 2).unwrap();
    let e = extrapolate(&Linear, &t, &f, 10.0);
    assert_eq!(e.q[2], t.configurations.last().unwrap().q[2]);
}

#[test]
fn bounded_moves_keep_the_direction_and_hold_a_body_at_bound_zero() {
    // Linear drifts in (x, y) and θ: body 0 moves 15 × |(3, -4)| µm = 75 µm,
    // inside its 1 mm bound; body 1 moves 15 × 5 mm = 75 mm, past its 1 mm
    // bound; body 2 is held (bound 0).
    let rate = |b: usize, d: usize| [3e-6, -4e-6, 1e-3][d] * if b == 1 { 1e3 } else { 1.0 };
    let t = window(3, 10, 20, |b, d, n| rate(b, d) * n);
    let f = fit(&Linear, &t, 3, 2).unwrap();
    let free = extrapolate(&Linear, &t, &f, 15.0);
    let (e, limited) = extrapolate_within(&Linear, &t, &f, 15.0, &[1e-3, 1e-3, 0.0], None);
    let last = t.configurations.last().unwrap();
    assert_eq!(limited, 2, "body 1 (past its bound) and body 2 (held, with a trend)");
    // Body 0: the law's move, bit for bit (scale 1).
    assert_eq!(&e.q[0..3], &free.q[0..3]);
    // Body 1: |move| = the bound, along the trend (−0.6, 0.8 of it in x, y
    // within rounding of 0.3 m coordinates, ~1e-16 m), θ scaled by the same
    // factor 1 mm / 75 mm (θ ~30 rad carries ~4e-15 rad of rounding).
    let (dx, dy) = (e.q[3] - last.q[3], e.q[4] - last.q[4]);
    assert!((dx.hypot(dy) - 1e-3).abs() < 1e-15, "move {}", dx.hypot(dy));
    assert!((dx - 0.6e-3).abs() < 1e-15 && (dy + 0.8e-3).abs() < 1e-15, "direction ({dx}, {dy})");
    let dtheta = e.q[5] - last.q[5];
    assert!((dtheta - 15.0 / 75.0).abs() < 1e-12, "θ moved {dtheta}");
    // Body 2: where it was.
    assert_eq!(&e.q[6..9], &last.q[6..9]);
    // The trend moves the driver takes the median of: 15 × 5 µm, 15 × 5 mm (body 2
    // has body 0's trend).
    let moves = trend_moves(&Linear, &t, &f, 15.0);
    for (m, want) in moves.iter().zip([75e-6, 75e-3, 75e-6]) {
        assert!((m - want).abs() < 1e-12 * want.max(1e-3), "{m} vs {want}");
    }
    // Unbounded (an empty slice, or infinite bounds): the law's configuration.
    assert_eq!(extrapolate_within(&Linear, &t, &f, 15.0, &[], None), (free.clone(), 0));
    assert_eq!(extrapolate_within(&Linear, &t, &f, 15.0, &[f64::INFINITY; 3], None), (free, 0));
}

#[test]
fn chernoff_bound_matches_its_closed_form() {
    // k ≥ (b − a)²/(2ε²) ln(2/p): range 20 µm, ε = 1 µm, p = 5 %:
    // 200 ln 40 = 737.78 → 738.
    let k = chernoff_cycles(1e-6, 0.05, 2e-5).unwrap();
    assert_eq!(k, 738);
    assert!(chernoff_probability(738, 1e-6, 2e-5) <= 0.05);
    assert!(chernoff_probability(737, 1e-6, 2e-5) > 0.05);
    // 2 exp(−2 k ε²/range²) at k = 1000: 2 e^{-5}; at k = 100 the bound exceeds 1 and says nothing.
    assert!((chernoff_probability(1000, 1e-6, 2e-5) - 2.0 * (-5.0f64).exp()).abs() < 1e-15);
    assert_eq!(chernoff_probability(100, 1e-6, 2e-5), 1.0);
    // Bad inputs are errors naming the field.
    assert!(chernoff_cycles(0.0, 0.05, 1.0).unwrap_err().to_string().contains("settlement.error"));
    assert!(chernoff_cycles(1e-6, 1.0, 1.0).unwrap_err().to_string().contains("settlement.probability"));
}

#[test]
fn configuration_error_of_eq_22() {
    let origin = config(2, |_, _| 0.0);
    let computed = config(2, |b, d| {
        if d == 0 {
            3.0 * (b as f64 + 1.0)
        } else if d == 1 {
            4.0
        } else {
            9.0
        }
    });
    let estimated = config(2, |b, d| {
        if d == 0 {
            3.0 * (b as f64 + 1.0)
        } else if d == 1 {
            4.0 + 1.0
        } else {
            0.0
        }
    });
    // u = [(3,4), (6,4)]: ‖u‖² = 9 + 16 + 36 + 16 = 77; u − û = [(0,−1),(0,−1)]: 2. θ not counted.
    let e = configuration_error(&origin, &computed, &estimated, 2);
    assert!((e - (2.0f64 / 77.0).sqrt()).abs() < 1e-15);
    assert_eq!(configuration_error(&origin, &computed, &computed, 2), 0.0);
}

#[test]
fn laws_are_named_and_bad_windows_refused() {
    assert_eq!(law_named("shenton").unwrap().name(), "shenton");
    assert_eq!(law_named("linear").unwrap().name(), "linear");
    assert_eq!(law_named("shenton_origin").unwrap().name(), "shenton_origin");
    assert_eq!(law_named("shenton_decelerating").unwrap().name(), "shenton_decelerating");
    let e = law_named("power").unwrap_err().to_string();
    assert!(e.contains("settlement.law") && e.contains("power"), "{e}");
    let mut t = window(1, 3, 1, |_, _, _| 0.0);
    t.cycles[1] = 3.0;
    assert!(fit(&Linear, &t, 3, 2).unwrap_err().to_string().contains("increasing"));
}
