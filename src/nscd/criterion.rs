//! Convergence policies of the NLGS iterations (Saussine et al. 2006, §2.7, §3.2).
//!
//! After a sweep every row α (contact or spring) has changed its impulse by
//! `ΔP_α`, i.e. corrected its own local velocity by `ΔU_α = W_α ΔP_α` (m/s). The
//! norms are dimensionless:
//! - `quad` (non-strict, as LMGC90's NLGS): `sqrt(⟨|ΔU|² |P|²⟩) / ⟨P·WP⟩`, a
//!   quadratic mean weighted by the impulses;
//! - `strict`: `max_α |ΔU_α| / ⟨|W P|⟩`, the worst velocity correction of any row
//!   relative to the mean velocity scale of the contact impulses: every row below
//!   the tolerance. A velocity error `δU` over the step is an overlap `h δU`, so
//!   this is the norm that bounds interpenetration;
//! - `quad_max`: `quad ≤ tol` **and** `strict ≤ max_factor · tol`. A new contact
//!   weighs `1/n` in the quadratic mean, and its small impulse weighs it down
//!   further, so in a dense, heavily loaded packing `quad` alone stops before its
//!   reaction has built up (worst right after the sleeper unloads, when new
//!   contacts form under small forces); the maximum catches it;
//! - `energy`: relative change of `Σ P·WP` over the sweep — the work of the contact
//!   impulses in the local Delassus metric, which stops changing at convergence.

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
    /// max |ΔU| (m/s)
    pub max_du: f64,
    /// Σ |W P| (m/s)
    pub sum_wp: f64,
    /// Σ P·WP
    pub sum_wpp: f64,
    /// Whether any impulse changed.
    pub changed: bool,
}

impl SweepNorms {
    /// Adds one row: `du2 = |W ΔP|²`, `p2 = |P|²`, `wp2 = |W P|²`, `pwp = P·WP`.
    #[inline(always)]
    pub fn add(&mut self, du2: f64, p2: f64, wp2: f64, pwp: f64, changed: bool) {
        self.rows += 1;
        self.sum_dudu_pp += du2 * p2;
        let du = du2.sqrt();
        if du > self.max_du {
            self.max_du = du;
        }
        self.sum_wp += wp2.sqrt();
        self.sum_wpp += pwp;
        self.changed |= changed;
    }

    /// `x / scale`, 0 when nothing changed, ∞ when the scale vanishes but something changed.
    fn relative(&self, x: f64, scale: f64) -> f64 {
        if self.rows == 0 || !self.changed {
            0.0
        } else if scale > 0.0 {
            x / scale
        } else {
            f64::INFINITY
        }
    }

    pub fn quad(&self) -> f64 {
        let n = self.rows.max(1) as f64;
        self.relative((self.sum_dudu_pp / n).sqrt(), self.sum_wpp / n)
    }

    pub fn max(&self) -> f64 {
        self.relative(self.max_du, self.sum_wp / self.rows.max(1) as f64)
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
