//! Convergence policies of the NLGS iterations (Saussine et al. 2006, §2.7, §3.2).
//!
//! The norms are those of LMGC90's NLGS (the platform of the paper), so that
//! the paper's tolerances mean the same here. For every row α with a non-zero
//! impulse, after its update in a sweep: `ΔU_α = W_α ΔP_α` is the correction
//! of its local velocity (m/s), `P̄_α = ½ (P_old + P_new)` and the "Delassus
//! energy" `WPP_α = ½ (P_old·W P_old + P_new·W P_new)`, `|WP|²_α = ½ (|W P_old|² +
//! |W P_new|²)`. With means `⟨·⟩` over those `n` rows:
//! - `QuadDV = sqrt(⟨|ΔU|²⟩) / sqrt(⟨|WP|²⟩)`, `MaxmDV = max |ΔU| / sqrt(⟨|WP|²⟩)`;
//! - `QuadDVR = sqrt(⟨|ΔU|² |P̄|²⟩) / ⟨WPP⟩`, `MaxmDVR = max |ΔU| |P̄| / ⟨WPP⟩`;
//! - `MeanDVoR = Σ P̄·ΔU / Σ WPP`.
//!
//! Policies (LMGC90's names in brackets):
//! - `quad` (non-strict, "Quad "): `|MeanDVoR|`, `QuadDV`, `QuadDVR` < tol;
//! - `strict` ("Maxm "): `|MeanDVoR|`, `MaxmDV`, `MaxmDVR` < tol — every row;
//! - `quad_max` ("QM/16" for `max_factor` = 16.666): `quad` and `MaxmDV`, `MaxmDVR` <
//!   `max_factor` · tol. The default factor is 4: on a landing beside a heavily loaded
//!   bed it cuts the overlap 3× for 34 % more sweeps, where 16.666 changes little. A new contact weighs `1/n` in the quadratic means, so in a
//!   dense, heavily loaded packing `quad` alone stops before its reaction has
//!   built up (worst right after the sleeper unloads); the maxima catch it;
//! - `energy` (ours; the paper cites an energy criterion without defining it):
//!   relative change of `Σ P·WP` over a sweep;
//! - `velocity` (ours, issue 31): an estimate of the error left in the local
//!   velocities, which are unique in a hyperstatic packing where the impulses are
//!   not, and are what the settlement integrates. A sweep's largest velocity
//!   correction `δ = max |ΔU|` (`MaxmDV`'s numerator) is a step of a sequence that
//!   contracts by `q` per sweep, so the distance left to its limit is the geometric
//!   tail `δ q / (1 − q)`; `q` is measured over windows of
//!   [`VELOCITY_WINDOW`] sweeps (the ratio of their largest `δ`, to the power
//!   1/window, at most 0.9999) and the value is `δ q/(1 − q) / sqrt(⟨|WP|²⟩)`, the
//!   error relative to the velocity the impulses make. At NLGS's stall (q ≈ 0.999)
//!   the raw change per sweep underestimates the error a thousandfold, which is what
//!   the factor corrects. Measured during the sweeps, like `energy`.
//!
//! Where the norms are measured ([`Measure`]). LMGC90 measures them in a separate
//! *check* pass that solves every row from the current iterate and updates nothing
//! (Jean's violation): `P_old` is the stored impulse, `P_new` the local solution,
//! so the norms are the fixed-point residual of the iterate. The default here is
//! the same pass ([`Measure::Check`]), run only when it can succeed: the norms
//! accumulated during each updating sweep ([`Measure::Sweep`], each row's
//! correction when it is visited, free) times the ratio check/sweep last measured
//! in the step must meet the tolerance (and at the sweep cap). On a loaded
//! 536-pentagon pile the sweep's norm is 1.6× the check's at the same iterate
//! (ratio 0.60–0.66, stable over the sweeps of a step): stopping on it needed
//! 1.14–1.22× the sweeps of the check at the same tolerance, as many as the check
//! at 1.6× the tolerance (`examples/nlgs_measure.rs`, BENCHMARKS.md). That is why
//! our solver needed more sweeps than LMGC90 at the "same" tolerance.

use serde::{Deserialize, Serialize};

/// Which convergence policy ends the iterations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Policy {
    /// LMGC90's "Maxm ": `|MeanDVoR|`, `MaxmDV` and `MaxmDVR` below the tolerance
    /// (every row must have converged).
    Strict,
    /// LMGC90's "Quad " (the default): `|MeanDVoR|`, `QuadDV` and `QuadDVR` below the
    /// tolerance (quadratic means over the rows).
    #[default]
    Quad,
    /// LMGC90's "QM/16" family: [`Policy::Quad`], and `MaxmDV`, `MaxmDVR` below
    /// `max_factor` × tolerance.
    QuadMax,
    /// Relative change of `Σ P·WP` over a sweep below the tolerance (ours; the
    /// paper cites an energy criterion without defining it).
    Energy,
    /// The estimated error left in the local velocities, relative to the velocity
    /// the impulses make, below the tolerance (ours; module text).
    Velocity,
}

impl Policy {
    /// Every policy, in the order scenes list them.
    pub const ALL: [Policy; 5] = [Policy::Strict, Policy::Quad, Policy::QuadMax, Policy::Energy, Policy::Velocity];

    /// The policy named `name` (as [`Policy::name`] writes it).
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }

    /// The policy's name in scenes and reports (`strict`, `quad`, `quad_max`, `energy`,
    /// `velocity`), as serde writes it.
    pub fn name(self) -> &'static str {
        match self {
            Policy::Strict => "strict",
            Policy::Quad => "quad",
            Policy::QuadMax => "quad_max",
            Policy::Energy => "energy",
            Policy::Velocity => "velocity",
        }
    }

    /// Whether the policy measures a change from sweep to sweep (`energy`,
    /// `velocity`) rather than a residual of the iterate: it is measured during the
    /// sweeps, never by the check pass.
    pub fn over_sweeps(self) -> bool {
        matches!(self, Policy::Energy | Policy::Velocity)
    }
}

/// Where the norms of a sweep are measured.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Measure {
    /// During the updating sweep, each row's correction when it is visited (no extra
    /// pass). Measured 1.6× LMGC90's value at the same iterate on a loaded pile: a
    /// tolerance means 1.6× less here.
    Sweep,
    /// In a separate pass after the sweep that solves every row from the current
    /// iterate and updates nothing (LMGC90's check; the default). The pass runs only
    /// when the sweep's norm, times the last measured ratio of the two, meets the
    /// tolerance, and at the sweep cap: 1–3 passes per step.
    #[default]
    Check,
}

impl Measure {
    /// The name in scenes (`sweep`, `check`).
    pub fn name(self) -> &'static str {
        match self {
            Measure::Sweep => "sweep",
            Measure::Check => "check",
        }
    }

    /// The measure named `name` (as [`Measure::name`] writes it).
    pub fn from_name(name: &str) -> Option<Self> {
        [Measure::Sweep, Measure::Check].into_iter().find(|m| m.name() == name)
    }
}

/// Running sums over one sweep.
#[derive(Debug, Clone, Copy, Default)]
pub struct SweepNorms {
    /// Rows with a non-zero (mean) impulse.
    pub active: usize,
    /// `Σ |ΔU|²` over the active rows, `ΔU = W ΔP` the row's local velocity correction ((m/s)²).
    pub sum_dvdv: f64,
    /// `max |ΔU|²` over the active rows ((m/s)²).
    pub max_dvdv: f64,
    /// `Σ |ΔU|² |P̄|²` over the active rows, `P̄` the midpoint impulse (J²).
    pub sum_dvdvrr: f64,
    /// `max |ΔU|² |P̄|²` over the active rows (J²).
    pub max_dvdvrr: f64,
    /// `Σ P̄·ΔU` over the active rows (J).
    pub sum_dvor: f64,
    /// `Σ WPP` over the active rows, `WPP = ½ (P_old·W P_old + P_new·W P_new)` (J).
    pub sum_wrr: f64,
    /// `Σ |WP|²` over the active rows, `|WP|² = ½ (|W P_old|² + |W P_new|²)` ((m/s)²).
    pub sum_wrwr: f64,
    /// Σ P_new·W P_new over all rows (energy criterion).
    pub sum_wpp: f64,
    /// Whether any impulse changed.
    pub changed: bool,
}

impl SweepNorms {
    /// Adds one row: `du2 = |ΔU|²`, `pm2 = |P̄|²`, `dvor = P̄·ΔU`, `wrr = WPP`,
    /// `wrwr = |WP|²` (midpoint averages), `wpp_new = P_new·W P_new`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub fn add(&mut self, du2: f64, pm2: f64, dvor: f64, wrr: f64, wrwr: f64, wpp_new: f64, changed: bool) {
        self.sum_wpp += wpp_new;
        self.changed |= changed;
        if pm2 == 0.0 {
            return;
        }
        self.active += 1;
        self.sum_dvdv += du2;
        self.max_dvdv = self.max_dvdv.max(du2);
        let x = du2 * pm2;
        self.sum_dvdvrr += x;
        self.max_dvdvrr = self.max_dvdvrr.max(x);
        self.sum_dvor += dvor;
        self.sum_wrr += wrr;
        self.sum_wrwr += wrwr;
    }

    /// The norms of two parts of a pass together: sums added, maxima taken (the split solve's halves, or the
    /// rows of [`super::check_by_row`]).
    pub fn merged(self, other: SweepNorms) -> SweepNorms {
        SweepNorms {
            active: self.active + other.active,
            sum_dvdv: self.sum_dvdv + other.sum_dvdv,
            max_dvdv: self.max_dvdv.max(other.max_dvdv),
            sum_dvdvrr: self.sum_dvdvrr + other.sum_dvdvrr,
            max_dvdvrr: self.max_dvdvrr.max(other.max_dvdvrr),
            sum_dvor: self.sum_dvor + other.sum_dvor,
            sum_wrr: self.sum_wrr + other.sum_wrr,
            sum_wrwr: self.sum_wrwr + other.sum_wrwr,
            sum_wpp: self.sum_wpp + other.sum_wpp,
            changed: self.changed || other.changed,
        }
    }

    /// `(QuadDV, MaxmDV, QuadDVR, MaxmDVR, MeanDVoR)`; all zero when no impulse changed
    /// or no row carries an impulse, infinite if the scales vanish while impulses change.
    pub fn norms(&self) -> [f64; 5] {
        if !self.changed || self.active == 0 {
            return [0.0; 5];
        }
        let n = self.active as f64;
        let (quad_wr, mean_wrr) = ((self.sum_wrwr / n).sqrt(), self.sum_wrr / n);
        if !(quad_wr > 0.0 && mean_wrr > 0.0) {
            return [f64::INFINITY; 5];
        }
        [
            (self.sum_dvdv / n).sqrt() / quad_wr,
            self.max_dvdv.sqrt() / quad_wr,
            (self.sum_dvdvrr / n).sqrt() / mean_wrr,
            self.max_dvdvrr.sqrt() / mean_wrr,
            self.sum_dvor / self.sum_wrr,
        ]
    }
}

/// Sweeps per window of the contraction estimate of [`Policy::Velocity`].
pub const VELOCITY_WINDOW: usize = 10;

/// The geometric-tail factor `q/(1 − q)` of [`Policy::Velocity`], from the largest
/// velocity correction of each window of [`VELOCITY_WINDOW`] sweeps.
#[derive(Debug, Clone, Copy)]
pub struct VelocityTail {
    sweeps: usize,
    window_max: f64,
    last_max: f64,
    factor: f64,
}

/// Largest contraction per sweep the estimate admits (a factor of 9999).
const MAX_CONTRACTION: f64 = 0.9999;

impl Default for VelocityTail {
    /// No window yet: the largest factor.
    fn default() -> Self {
        Self { sweeps: 0, window_max: 0.0, last_max: f64::NAN, factor: MAX_CONTRACTION / (1.0 - MAX_CONTRACTION) }
    }
}

impl VelocityTail {
    /// Takes one sweep's `δ` (any positive multiple of it: only ratios matter) and
    /// returns `δ q/(1 − q)` with the contraction of the last complete windows.
    pub fn estimate(&mut self, delta: f64) -> f64 {
        self.window_max = self.window_max.max(delta);
        self.sweeps += 1;
        if self.sweeps.is_multiple_of(VELOCITY_WINDOW) {
            if self.last_max > 0.0 {
                let q = (self.window_max / self.last_max).powf(1.0 / VELOCITY_WINDOW as f64);
                let q = if q.is_finite() { q.min(MAX_CONTRACTION) } else { MAX_CONTRACTION };
                self.factor = q / (1.0 - q);
            }
            (self.last_max, self.window_max) = (self.window_max, 0.0);
        }
        delta * self.factor
    }
}

/// Evaluates the policy: returns `(value, converged)`, `value` being the largest of the
/// norms the policy tests, each divided by its bound (so convergence is `value < tol`).
/// `previous_wpp` is `Σ P·WP` after the previous sweep (energy criterion).
pub fn evaluate(policy: Policy, tol: f64, max_factor: f64, s: &SweepNorms, previous_wpp: f64) -> (f64, bool) {
    let [quad_dv, maxm_dv, quad_dvr, maxm_dvr, mean_dvor] = s.norms();
    let value = match policy {
        Policy::Quad => mean_dvor.abs().max(quad_dv).max(quad_dvr),
        Policy::Strict => mean_dvor.abs().max(maxm_dv).max(maxm_dvr),
        Policy::QuadMax => mean_dvor.abs().max(quad_dv).max(quad_dvr).max(maxm_dv.max(maxm_dvr) / max_factor),
        // The raw correction; `iterate` multiplies it by the tail factor.
        Policy::Velocity => maxm_dv,
        Policy::Energy => {
            if !s.changed {
                0.0
            } else if s.sum_wpp > 0.0 {
                (s.sum_wpp - previous_wpp).abs() / s.sum_wpp
            } else {
                f64::INFINITY
            }
        }
    };
    (value, value < tol)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On a geometric sequence of corrections `δ_k = δ_0 q^k` the estimate is the
    /// exact distance left to the limit, `δ_k q/(1 − q)`, once two windows are
    /// complete; before, it is the largest factor; a growing sequence keeps it there.
    #[test]
    fn velocity_tail_is_exact_on_a_geometric_sequence() {
        let q: f64 = 0.99;
        let mut tail = VelocityTail::default();
        for k in 0..5 * VELOCITY_WINDOW {
            let delta = 3.0 * q.powi(k as i32);
            let e = tail.estimate(delta);
            if k < 2 * VELOCITY_WINDOW - 1 {
                let largest = delta * MAX_CONTRACTION / (1.0 - MAX_CONTRACTION);
                assert!((e - largest).abs() < 1e-12 * largest, "sweep {k}: {e} vs {largest}");
            } else {
                let exact: f64 = (k + 1..100_000).map(|j| 3.0 * q.powi(j as i32)).sum();
                assert!((e - exact).abs() < 1e-9 * exact, "sweep {k}: {e} vs {exact}");
            }
        }
        let mut tail = VelocityTail::default();
        let last = (0..3 * VELOCITY_WINDOW).map(|k| tail.estimate(1.0 + k as f64)).last().unwrap();
        let largest = 30.0 * MAX_CONTRACTION / (1.0 - MAX_CONTRACTION);
        assert!((last - largest).abs() < 1e-12 * largest, "{last} vs {largest}");
    }
}
