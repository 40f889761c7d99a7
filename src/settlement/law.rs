//! Laws of the residual displacement of one coordinate against the cycle
//! number, fitted on the computed cycles and extrapolated (Karrech et al. 2007,
//! §3.1–3.2).
//!
//! A law is a trend `ũ(N)` with two coefficients `c`, fitted on the training data
//! `(N_p, u_p)`, `p = 0 … k` (the displacement of one coordinate of one body at
//! the end of the computed cycles `N_0 < N_1 < … < N_k`, counted from the start of
//! the loading; `p = 0` is the start of the window). The extrapolated value `h`
//! cycles after the last computed one is anchored at the last computed value:
//! `û(N_k + h) = u(N_k) + ũ(N_k + h) − ũ(N_k)`.
//!
//! - [`Linear`], eq. (16): `ũ(N) = u_0 + s (N − N_0)` with the mean increment per
//!   cycle `s = (u_k − u_0)/(N_k − N_0)`, so that `û(N_k + h) = u_k + h s`
//!   (`(h/k) Σ_p [u_p − u_{p−1}]` when the window has unit steps).
//! - [`Shenton`] (the driver's default): Shenton's law with a constant,
//!   `ũ(N) = c + a ln N + b N`, fitted by least squares on every computed point
//!   of the history, with one constant per window (module doc: why).
//! - [`ShentonDecelerating`]: the same over `a b ≥ 0` (module doc).
//! - [`ShentonOrigin`], eqs. (17)–(21) as printed: `ũ(N) = a ln N + b N`, fitted
//!   on `p = 1 … k` of the last window by the closed forms (20)–(21).
//!
//! `N` is the number of loading cycles since the load started (dimensionless,
//! `ln 1 = 0`). The paper writes the law in time `t_p = t + pT`: in time, `a ln t`
//! would add a constant `a ln T` that a law without intercept cannot absorb, so
//! the fit would depend on the unit of time.
//!
//! Why a constant: the law through the origin makes the first cycle's
//! settlement `ũ(1) = b`, the long-term rate. On a ballast sample the first
//! cycles seat the sleeper by far more than any later cycle (the reduced
//! Saussine sample: 10.6 mm in the first cycle, 0.1 µm per cycle after), so a
//! window late in the run holds nearly constant data, which `a ln N + b N`
//! can only follow with `a > 0`, `b < 0`: extrapolated, it falls (measured on
//! `examples/settlement_sleeper.toml`: the sleeper rose by 9 mm in 4
//! extrapolated cycles). The constant absorbs the seating; `a` and `b` keep the
//! paper's meaning, and data that follow `a ln N + b N` give `c = 0`, `a`, `b`.
//!
//! Why the history: Shenton's law is a law of the whole cyclic history. Fitted on
//! one short window far from `N = 1`, its columns `1, ln N, N` are nearly
//! dependent, a micrometre of scatter makes `a` and `b` large and of opposite
//! signs, and their curvature, extrapolated, sent the reference sample's
//! sleeper 0.3 m up in 69 cycles (measured; the run then diverged). A law whose
//! [`ResidualLaw::history`] is true is therefore fitted on every computed
//! cycle since the initial ones; the linear law keeps the paper's window.
//!
//! Why one constant per window: the offsets between two windows are what the
//! jump between them extrapolated and relaxed, not motion the sample made. With
//! one constant through the history (a first version), each over-extrapolation
//! became data for the next (measured: 14.9 mm accrued in 1000 cycles of the
//! reference sample where the full run accrues 3 mm). Each window (a
//! *segment* of the history) gets its own constant, so `a` and `b` are measured
//! on the motion within the windows only.
//!
//! [`ShentonDecelerating`] fits `a b ≥ 0`. Shenton's law describes a settlement
//! that decelerates, `a` and `b` of one sign. A window caught in an avalanche fits `a < 0 < b`, a motion
//! that accelerates, and extrapolated it turned the avalanche into a rate (the
//! reference sample's first window, cycles 10–30, has a 0.5 mm collapse in its
//! last two cycles: its unconstrained fit extrapolated 3.3 mm over the next 40
//! cycles, where the full run settled 1.1 mm); `b < 0 < a` turns the motion back
//! at `N = −a/b` (the sleeper rising). This law takes the least squares over
//! `a b ≥ 0`: when the free fit leaves that set, the better of the one-term laws
//! `c + a ln N` and `c + b N`.
//!
//! More laws are added by implementing [`ResidualLaw`].

use crate::error::Result;
use nalgebra::{DMatrix, DVector};

/// Least squares of `u` on `[ln N, N]` with one constant per segment of
/// points (`segments[p]`, non-decreasing), and with `decelerating` over
/// `a b ≥ 0`: the constants are eliminated by removing each segment's mean from
/// the columns and the data, then the two slopes are found by singular values
/// with the columns scaled to unit size (over a short window far from `N = 1`
/// they are nearly dependent; the minimum-norm solution for a design of lower
/// rank); with `decelerating`, slopes of opposite signs give way to the better
/// one-term law (module doc). `[c, a, b]` with `c` the constant of the last
/// segment.
fn least_squares(n: &[f64], u: &[f64], segments: &[u32], decelerating: bool) -> Coefficients {
    let len = n.len();
    // Each segment's means of ln N, N and u.
    let mut means = vec![[0.0f64; 3]; len];
    let mut start = 0;
    while start < len {
        let end = (start..len).find(|&p| segments[p] != segments[start]).unwrap_or(len);
        let m = (end - start) as f64;
        let mut mean = [0.0; 3];
        for p in start..end {
            mean[0] += n[p].ln() / m;
            mean[1] += n[p] / m;
            mean[2] += u[p] / m;
        }
        means[start..end].fill(mean);
        start = end;
    }
    let col = |p: usize, j: usize| if j == 0 { n[p].ln() - means[p][0] } else { n[p] - means[p][1] };
    let scale = |j: usize| (0..len).map(|p| col(p, j).abs()).fold(f64::MIN_POSITIVE, f64::max);
    let (sl, sn) = (scale(0), scale(1));
    let a = DMatrix::from_fn(len, 2, |p, j| col(p, j) / if j == 0 { sl } else { sn });
    let b = DVector::from_fn(len, |p, _| u[p] - means[p][2]);
    let x = a.svd(true, true).solve(&b, 1e-12).unwrap_or_else(|_| DVector::zeros(2));
    let (mut slope_ln, mut slope_n) = (x[0] / sl, x[1] / sn);
    if decelerating && slope_ln * slope_n < 0.0 {
        // A law that accelerates (a < 0 < b) or turns back (b < 0 < a): the
        // least squares over `a b ≥ 0` lie on a face, `a = 0` or `b = 0`; the
        // one-term fit with the smaller residual.
        let one = |j: usize| {
            let (sxx, sxy) = (0..len).fold((0.0, 0.0), |(xx, xy), p| {
                let x = col(p, j);
                (xx + x * x, xy + x * (u[p] - means[p][2]))
            });
            if sxx > 0.0 {
                (sxy / sxx, sxy * sxy / sxx)
            } else {
                (0.0, 0.0)
            }
        };
        // The residual is Σy² minus the explained sum `sxy²/sxx`: the larger that, the better.
        let ((a_only, explained_a), (b_only, explained_b)) = (one(0), one(1));
        (slope_ln, slope_n) = if explained_a >= explained_b { (a_only, 0.0) } else { (0.0, b_only) };
    }
    let last = means[len - 1];
    [last[2] - slope_ln * last[0] - slope_n * last[1], slope_ln, slope_n]
}

/// Coefficients of a fitted trend (their meaning is the law's).
pub type Coefficients = [f64; 3];

/// A law of residual displacement against the cycle number.
pub trait ResidualLaw: Send + Sync + std::fmt::Debug {
    /// The law's name in scenes and outputs.
    fn name(&self) -> &'static str;

    /// Fits the law to the displacements `u` (m or rad) at the cycle numbers `n`
    /// (`n[0]` the start of the window, strictly increasing, all ≥ 1 for a
    /// logarithmic law); `segments[p]` numbers the run of computed cycles point
    /// `p` belongs to (non-decreasing: the history is cut by each jump). `n`, `u`
    /// and `segments` have the same length, at least 2; a law fitted on the last
    /// window only sees one segment.
    fn fit(&self, n: &[f64], u: &[f64], segments: &[u32]) -> Coefficients;

    /// The trend's value at cycle number `n` (m or rad).
    fn trend(&self, c: &Coefficients, n: f64) -> f64;

    /// The first training point the fit uses (the residuals ξ_p are measured from it on).
    fn first_fitted(&self) -> usize;

    /// Whether the law is fitted on the whole computed history since the initial
    /// cycles (true) or on the last window of `k` computed cycles (false).
    fn history(&self) -> bool {
        false
    }

    /// The extrapolation `h` cycles after the last point: `u_k + ũ(N_k + h) − ũ(N_k)`.
    fn extrapolate(&self, c: &Coefficients, n_last: f64, u_last: f64, h: f64) -> f64 {
        u_last + self.trend(c, n_last + h) - self.trend(c, n_last)
    }
}

/// The linear estimation of eq. (16): the mean increment per cycle over the window.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Linear;

impl ResidualLaw for Linear {
    fn name(&self) -> &'static str {
        "linear"
    }

    /// `c = [u_0 − s N_0, s, 0]`, `s = (u_k − u_0)/(N_k − N_0)`.
    fn fit(&self, n: &[f64], u: &[f64], _segments: &[u32]) -> Coefficients {
        let (n0, nk) = (n[0], n[n.len() - 1]);
        let (u0, uk) = (u[0], u[u.len() - 1]);
        let s = (uk - u0) / (nk - n0);
        [u0 - s * n0, s, 0.0]
    }

    fn trend(&self, c: &Coefficients, n: f64) -> f64 {
        c[0] + c[1] * n
    }

    fn first_fitted(&self) -> usize {
        0
    }
}

/// Shenton's logarithmic law with a constant, `c + a ln N + b N`, fitted by
/// least squares on the whole computed history, one constant per run of
/// computed cycles between two jumps (module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Shenton;

impl ResidualLaw for Shenton {
    fn name(&self) -> &'static str {
        "shenton"
    }

    /// `c = [c, a, b]`: the least-squares `a`, `b` by singular values of the
    /// design `[ln N_p, N_p]` with one constant per segment, and the last
    /// segment's constant `c`.
    fn fit(&self, n: &[f64], u: &[f64], segments: &[u32]) -> Coefficients {
        least_squares(n, u, segments, false)
    }

    fn history(&self) -> bool {
        true
    }

    fn trend(&self, c: &Coefficients, n: f64) -> f64 {
        c[0] + c[1] * n.ln() + c[2] * n
    }

    fn first_fitted(&self) -> usize {
        0
    }
}

/// [`Shenton`] restricted to laws that do not accelerate or turn back,
/// `a b ≥ 0` (module doc).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShentonDecelerating;

impl ResidualLaw for ShentonDecelerating {
    fn name(&self) -> &'static str {
        "shenton_decelerating"
    }

    /// As [`Shenton`], the least squares over `a b ≥ 0`.
    fn fit(&self, n: &[f64], u: &[f64], segments: &[u32]) -> Coefficients {
        least_squares(n, u, segments, true)
    }

    fn history(&self) -> bool {
        true
    }

    fn trend(&self, c: &Coefficients, n: f64) -> f64 {
        Shenton.trend(c, n)
    }

    fn first_fitted(&self) -> usize {
        0
    }
}

/// Shenton's logarithmic law through the origin, `a ln N + b N`, fitted by the
/// closed forms of eqs. (18)–(21).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ShentonOrigin;

impl ResidualLaw for ShentonOrigin {
    fn name(&self) -> &'static str {
        "shenton_origin"
    }

    /// `c = [0, a, b]` of eqs. (20)–(21) on the points `p = 1 … k` (the start of the
    /// window, `p = 0`, is not a training datum of the paper's sums). With a
    /// single fitted point or a singular system (all `N` equal), the law
    /// degenerates to the line through the origin `b N` (`a = 0`).
    fn fit(&self, n: &[f64], u: &[f64], _segments: &[u32]) -> Coefficients {
        let (mut sll, mut stt, mut stl, mut sul, mut sut) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (&t, &v) in n.iter().zip(u).skip(1) {
            let l = t.ln();
            sll += l * l;
            stt += t * t;
            stl += t * l;
            sul += v * l;
            sut += v * t;
        }
        let det = sll * stt - stl * stl;
        // Relative to its terms, a determinant this small is a cancellation.
        if det.abs() <= 1e-12 * sll * stt || stt == 0.0 {
            return [0.0, 0.0, if stt > 0.0 { sut / stt } else { 0.0 }];
        }
        let a = (stt * sul - stl * sut) / det;
        let b = (sll * sut - stl * sul) / det;
        [0.0, a, b]
    }

    fn trend(&self, c: &Coefficients, n: f64) -> f64 {
        c[1] * n.ln() + c[2] * n
    }

    fn first_fitted(&self) -> usize {
        1
    }
}

/// The law named `name` in a scene or on the command line: `"linear"`,
/// `"shenton"` or `"shenton_origin"` ([`super::Law::from_name`]).
///
/// # Errors
/// [`crate::Error::Scene`] naming `settlement.law` and the accepted values.
pub fn law_named(name: &str) -> Result<&'static dyn ResidualLaw> {
    super::Law::from_name(name, "settlement.law").map(super::Law::estimator)
}
