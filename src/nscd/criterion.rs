//! Convergence policies of the NLGS iterations (Saussine et al. 2006, §2.7, §3.2).
//!
//! After a sweep every row α (contact or spring) has changed its impulse by
//! `ΔP_α`, i.e. corrected its own local velocity by `ΔU_α = W_α ΔP_α`. The norms
//! are dimensionless, relative to the mean "Delassus energy" `⟨P·W P⟩` of the
//! rows, as in LMGC90's NLGS:
//! - `quad` (non-strict): `sqrt(⟨|ΔU|² |P|²⟩) / ⟨P·WP⟩` — a quadratic mean;
//! - `strict`: `sqrt(max |ΔU|² |P|²) / ⟨P·WP⟩` — every row below the tolerance;
//! - `quad_max`: `quad ≤ tol` **and** `strict ≤ max_factor · tol`. A new contact weighs
//!   `1/n` in the quadratic mean, so in a dense packing `quad` alone stops before its
//!   reaction has built up; the maximum catches it;
//! - `energy`: relative change of `Σ P·WP` over the sweep — an energy (work of the
//!   contact impulses in the local Delassus metric) that stops changing at convergence.

use serde::{Deserialize, Serialize};

/// Which convergence policy ends the iterations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Policy {
    Strict,
    #[default]
    Quad,
    QuadMax,
    Energy,
}

impl Policy {
    pub fn name(self) -> &'static str {
        match self {
            Policy::Strict => "strict",
            Policy::Quad => "quad",
            Policy::QuadMax => "quad_max",
            Policy::Energy => "energy",
        }
    }
}

/// Running sums over one sweep.
#[derive(Debug, Clone, Copy, Default)]
pub struct SweepNorms {
    pub rows: usize,
    /// Σ |ΔU|² |P|²
    pub sum_dudu_pp: f64,
    /// max |ΔU|² |P|²
    pub max_dudu_pp: f64,
    /// Σ P·WP
    pub sum_wpp: f64,
    /// Whether any impulse changed.
    pub changed: bool,
}

impl SweepNorms {
    /// Adds one row's correction `du = W ΔP`, new impulse `p` and `wp = W p`.
    #[inline(always)]
    pub fn add(&mut self, du2: f64, p2: f64, pwp: f64, changed: bool) {
        let x = du2 * p2;
        self.rows += 1;
        self.sum_dudu_pp += x;
        if x > self.max_dudu_pp {
            self.max_dudu_pp = x;
        }
        self.sum_wpp += pwp;
        self.changed |= changed;
    }

    fn relative(&self, x: f64) -> f64 {
        if self.rows == 0 || !self.changed {
            return 0.0;
        }
        let mean_wpp = self.sum_wpp / self.rows as f64;
        if mean_wpp > 0.0 {
            x / mean_wpp
        } else {
            f64::INFINITY
        }
    }

    pub fn quad(&self) -> f64 {
        self.relative((self.sum_dudu_pp / self.rows.max(1) as f64).sqrt())
    }

    pub fn max(&self) -> f64 {
        self.relative(self.max_dudu_pp.sqrt())
    }
}

/// Evaluates the policy: returns `(value, converged)`. `previous_wpp` is `Σ P·WP`
/// after the previous sweep (for the energy criterion).
pub fn evaluate(policy: Policy, tol: f64, max_factor: f64, s: &SweepNorms, previous_wpp: f64) -> (f64, bool) {
    match policy {
        Policy::Quad => {
            let q = s.quad();
            (q, q <= tol)
        }
        Policy::Strict => {
            let m = s.max();
            (m, m <= tol)
        }
        Policy::QuadMax => {
            let (q, m) = (s.quad(), s.max());
            (q.max(m / max_factor), q <= tol && m <= max_factor * tol)
        }
        Policy::Energy => {
            let e = if !s.changed {
                0.0
            } else if s.sum_wpp > 0.0 {
                (s.sum_wpp - previous_wpp).abs() / s.sum_wpp
            } else {
                f64::INFINITY
            };
            (e, e <= tol)
        }
    }
}
