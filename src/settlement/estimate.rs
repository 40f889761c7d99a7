//! Time averaging of the computed cycles (Karrech et al. 2007, §3): each mobile
//! body's residual displacement, coordinate by coordinate, fitted with a
//! [`ResidualLaw`] on the configurations at the ends of the computed cycles and
//! extrapolated by `h` cycles; the accuracy measures `g_u(k)` (eq. 13) and
//! `f_ξ(k)` (eq. 14), the Chernoff bound (eq. 15) that gives the number of
//! computed cycles for an error `ε` and a probability `p`, and the relative
//! configuration error `E_r` (eq. 22).
//!
//! The displacement of a coordinate is measured from the configuration at the
//! start of the loading (cycle 0), so that a law without intercept (Shenton's)
//! sees the displacement since the load began. The measures of the paper are
//! over the degrees of translation (m); the rotation of a polygon (NSCD's `θ`) is
//! extrapolated with the same law but enters none of the measures.

use super::law::{Coefficients, ResidualLaw};
use super::smooth::Smoothing;
use crate::engine::Configuration;
use crate::error::{Error, Result};

/// The training data of one window: the configurations at the ends of the
/// computed cycles `N_0 < N_1 < … < N_k` (`N_0` the start of the window), and the
/// configuration at the start of the loading they are measured from.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Training {
    /// The configuration at cycle 0 (the start of the loading).
    pub origin: Configuration,
    /// Cycle numbers `N_p` since the start of the loading, computed or
    /// extrapolated (dimensionless, increasing).
    pub cycles: Vec<f64>,
    /// The configuration at the end of each cycle `N_p`, same bodies as `origin`.
    pub configurations: Vec<Configuration>,
    /// The run of computed cycles each point belongs to (non-decreasing, from
    /// 0; the first computed cycle after a jump starts a new one:
    /// [`Training::push_segment`]).
    #[serde(default)]
    pub segments: Vec<u32>,
}

impl Training {
    /// An empty window measured from `origin`.
    pub fn new(origin: Configuration) -> Self {
        Self { origin, cycles: Vec::new(), configurations: Vec::new(), segments: Vec::new() }
    }

    /// Adds the configuration at the end of cycle `n`, in the last point's segment.
    pub fn push(&mut self, n: f64, c: Configuration) {
        let segment = self.segments.last().copied().unwrap_or(0);
        self.cycles.push(n);
        self.configurations.push(c);
        self.segments.push(segment);
    }

    /// Adds the configuration at the end of cycle `n` as the first point of a new
    /// segment (the first computed cycle after a jump).
    pub fn push_segment(&mut self, n: f64, c: Configuration) {
        let segment = self.segments.last().map_or(0, |s| s + 1);
        self.cycles.push(n);
        self.configurations.push(c);
        self.segments.push(segment);
    }

    /// Computed cycles of the window, `k` (points minus the start).
    pub fn k(&self) -> usize {
        self.cycles.len().saturating_sub(1)
    }

    /// The index of the first point of the last segment (the last window's start).
    pub fn window_start(&self) -> usize {
        self.segments.iter().position(|&s| Some(&s) == self.segments.last()).unwrap_or(0)
    }

    /// The points of the last segment (the last window), as a training set of its own.
    pub fn last_segment(&self) -> Training {
        let first = self.window_start();
        Training {
            origin: self.origin.clone(),
            cycles: self.cycles[first..].to_vec(),
            configurations: self.configurations[first..].to_vec(),
            segments: self.segments[first..].to_vec(),
        }
    }

    fn check(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(format!("settlement fit: {msg}")));
        if self.cycles.len() < 2 {
            return bad(format!(
                "{} configurations; a window needs its start and at least one cycle",
                self.cycles.len()
            ));
        }
        let increasing = self.cycles.windows(2).all(|w| w[1] > w[0]) && self.cycles[0] >= 0.0;
        if !increasing {
            return bad(format!("cycle numbers not increasing from 0 or more: {:?}", self.cycles));
        }
        if self.segments.len() != self.cycles.len() || self.segments.windows(2).any(|w| w[1] < w[0]) {
            return bad("one non-decreasing segment number per point is needed".into());
        }
        for c in &self.configurations {
            if c.bodies != self.origin.bodies || c.dof != self.origin.dof || c.q.len() != self.origin.q.len() {
                return bad("the configurations do not hold the same bodies".into());
            }
        }
        Ok(())
    }
}

/// A window fitted coordinate by coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Coordinates fitted per body (the first `fitted` of each body's `dof`).
    pub fitted: usize,
    /// Degrees of translation per body (2 or 3), the coordinates of the measures.
    pub dim: usize,
    /// Coefficients of coordinate `d` of the `b`-th body at `b * fitted + d`.
    pub coefficients: Vec<Coefficients>,
    /// Eq. (13): `(1/k) (Σ_{β,p,d} [ũ(N_p) − ũ(N_{p−1})]²)^½` (m), the trend's
    /// increments over the window.
    pub g_u: f64,
    /// Eq. (14): `(1/k) (Σ_{β,p,d} ξ_p²)^½` (m), `ξ_p = u_p − ũ(N_p)` the error
    /// term of each fitted point.
    pub f_xi: f64,
    /// The widest range `b − a` of one coordinate's error terms `ξ_p` over the
    /// window (m): the bound of eq. (15).
    pub xi_range: f64,
    /// Points of the window (its last segment) minus its start, `k`.
    pub k: usize,
}

/// Fits `law` to every body's first `fitted` coordinates over the window; the
/// measures are over the first `dim` (the translations).
///
/// # Errors
/// [`Error::Scene`] if the window has fewer than two points, its cycle numbers do
/// not increase, its configurations differ in bodies, or `dim > fitted > dof`.
pub fn fit(law: &dyn ResidualLaw, training: &Training, fitted: usize, dim: usize) -> Result<Fit> {
    training.check()?;
    let dof = training.origin.dof;
    if dim > fitted || fitted > dof {
        return Err(Error::Scene(format!(
            "settlement fit: {dim} translations, {fitted} fitted of {dof} coordinates per body"
        )));
    }
    let n = &training.cycles;
    let segments = &training.segments;
    // The measures are over the last segment, the window.
    let w0 = training.window_start();
    let k = n.len() - 1 - w0;
    if k == 0 {
        return Err(Error::Scene("settlement fit: the last window has a single point".into()));
    }
    let bodies = training.origin.len();
    let mut u = vec![0.0; n.len()];
    let mut coefficients = Vec::with_capacity(bodies * fitted);
    let (mut sum_g, mut sum_xi, mut xi_range) = (0.0, 0.0, 0.0f64);
    for b in 0..bodies {
        for d in 0..fitted {
            let at = b * dof + d;
            for (up, c) in u.iter_mut().zip(&training.configurations) {
                *up = c.q[at] - training.origin.q[at];
            }
            let c = law.fit(n, &u, segments);
            if d < dim {
                let mut prev = law.trend(&c, n[w0]);
                let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
                for (p, (&np, &up)) in n.iter().zip(&u).enumerate().skip(w0).map(|(p, x)| (p - w0, x)) {
                    let t = law.trend(&c, np);
                    if p >= 1 {
                        sum_g += (t - prev) * (t - prev);
                    }
                    prev = t;
                    if p >= law.first_fitted() {
                        let xi = up - t;
                        sum_xi += xi * xi;
                        lo = lo.min(xi);
                        hi = hi.max(xi);
                    }
                }
                xi_range = xi_range.max(hi - lo);
            }
            coefficients.push(c);
        }
    }
    let kf = k as f64;
    Ok(Fit { fitted, dim, coefficients, g_u: sum_g.sqrt() / kf, f_xi: sum_xi.sqrt() / kf, xi_range, k })
}

/// The configuration `h` cycles after the last of the window (eq. 16 or 17):
/// each fitted coordinate moved by its trend's increment from `N_k` to `N_k + h`,
/// the others (an MD sphere's orientation) kept at their last computed value.
pub fn extrapolate(law: &dyn ResidualLaw, training: &Training, fit: &Fit, h: f64) -> Configuration {
    extrapolate_within(law, training, fit, h, &[], None).0
}

/// The length of each body's trend move over `h` cycles after the last of the
/// window (m): the norm of the increments [`extrapolate`] gives its first
/// `fit.dim` coordinates (its translation), `‖ũ(N_k + h) − ũ(N_k)‖`.
pub fn trend_moves(law: &dyn ResidualLaw, training: &Training, fit: &Fit, h: f64) -> Vec<f64> {
    let last = training.configurations.last().expect("a fitted window has points");
    let n_last = *training.cycles.last().expect("a fitted window has points");
    (0..last.len())
        .map(|b| {
            (0..fit.dim)
                .map(|d| {
                    let m = law.extrapolate(&fit.coefficients[b * fit.fitted + d], n_last, 0.0, h);
                    m * m
                })
                .sum::<f64>()
                .sqrt()
        })
        .collect()
}

/// [`extrapolate`] with a bound on each body's move: the fitted increments of
/// body `b` (smoothed over its neighbours first if `smoothing` is given:
/// [`Smoothing`]) are scaled down together (the move keeps its direction) so
/// that its translation from the last computed configuration is at most
/// `max_move[b]` (m); `0` holds the body where it is. An empty `max_move`
/// bounds nothing. Also returns how many bodies the bound moved less than
/// their trend (held bodies with a trend included).
///
/// # Panics
/// If `max_move` is neither empty nor one value per body, or `smoothing` was
/// built for other bodies.
pub fn extrapolate_within(
    law: &dyn ResidualLaw,
    training: &Training,
    fit: &Fit,
    h: f64,
    max_move: &[f64],
    smoothing: Option<&Smoothing>,
) -> (Configuration, usize) {
    let last = training.configurations.last().expect("a fitted window has points");
    let n_last = *training.cycles.last().expect("a fitted window has points");
    let dof = last.dof;
    assert!(max_move.is_empty() || max_move.len() == last.len(), "one bound per body");
    let mut moved = vec![0.0; last.len() * fit.fitted];
    for (b, m) in moved.chunks_mut(fit.fitted).enumerate() {
        for (d, md) in m.iter_mut().enumerate() {
            let at = b * dof + d;
            let u_last = last.q[at] - training.origin.q[at];
            *md = law.extrapolate(&fit.coefficients[b * fit.fitted + d], n_last, u_last, h) - u_last;
        }
    }
    if let Some(s) = smoothing {
        s.apply(&mut moved, fit.fitted, fit.dim);
    }
    let mut out = last.clone();
    let mut limited = 0;
    for (b, m) in moved.chunks(fit.fitted).enumerate() {
        let length = m[..fit.dim].iter().map(|m| m * m).sum::<f64>().sqrt();
        let scale = match max_move.get(b) {
            Some(&bound) if length > bound => {
                limited += 1;
                bound / length
            }
            _ => 1.0,
        };
        for (d, md) in m.iter().enumerate() {
            out.q[b * dof + d] += scale * md;
        }
    }
    (out, limited)
}

/// Eq. (15), the Chernoff bound: the probability that the mean of `k` independent
/// errors bounded in a range of width `range` (m) is `epsilon` (m) or more away
/// from its expectation is at most `2 exp(−2 k ε² / range²)` (capped at 1).
pub fn chernoff_probability(k: u64, epsilon: f64, range: f64) -> f64 {
    if range <= 0.0 {
        return 0.0;
    }
    (2.0 * (-2.0 * k as f64 * epsilon * epsilon / (range * range)).exp()).min(1.0)
}

/// The computed cycles eq. (15) asks for: the least `k ≥ 1` with
/// `k ≥ range² / (2 ε²) · ln(2/p)`, so that the probability of a mean error of
/// `epsilon` (m) or more is at most `probability`.
///
/// # Errors
/// [`Error::Scene`] if `epsilon` is not positive or `probability` not in (0, 1).
pub fn chernoff_cycles(epsilon: f64, probability: f64, range: f64) -> Result<u64> {
    if !(epsilon > 0.0 && epsilon.is_finite()) {
        return Err(Error::Scene(format!("settlement.error: must be a positive length (m), got {epsilon}")));
    }
    if !(probability > 0.0 && probability < 1.0) {
        return Err(Error::Scene(format!("settlement.probability: must be in (0, 1), got {probability}")));
    }
    let k = range * range / (2.0 * epsilon * epsilon) * (2.0 / probability).ln();
    Ok((k.ceil() as u64).max(1))
}

/// Eq. (22), the relative configuration error `‖u − û‖ / ‖u‖` over the first
/// `dim` coordinates (the translations) of every body: `u` the displacement from
/// `origin` of a computed configuration, `û` that of an estimated one (same
/// bodies). 0 if both are at the origin, infinite if only the estimate moved.
pub fn configuration_error(
    origin: &Configuration,
    computed: &Configuration,
    estimated: &Configuration,
    dim: usize,
) -> f64 {
    let dof = origin.dof;
    let (mut num, mut den) = (0.0, 0.0);
    for b in 0..origin.len() {
        for d in 0..dim.min(dof) {
            let at = b * dof + d;
            let u = computed.q[at] - origin.q[at];
            let e = estimated.q[at] - origin.q[at];
            num += (u - e) * (u - e);
            den += u * u;
        }
    }
    if num == 0.0 {
        0.0
    } else if den == 0.0 {
        f64::INFINITY
    } else {
        (num / den).sqrt()
    }
}
