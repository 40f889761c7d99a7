//! Time integrators: velocity Verlet and Gear predictor–correctors.
//!
//! Gear (Karrech et al. 2007 eqs. 2–4; Allen & Tildesley 1987 §3.2): each sphere
//! carries its position and scaled time derivatives `r_k = Δt^k/k! d^k x/dt^k`,
//! `k < q`. The predictor is the Taylor (Pascal-triangle) step; forces are
//! evaluated at the predicted state; with `Δ = Δt²/2 (a_c − a_p)` the corrector
//! sets `r_k ← r_k + c_k Δ`. Coefficient sets:
//! - [`GearSet::Karrech`]: eqs. 2–4 as printed (`q = 3`, `r ← r_p + c₀ Δt²/2 Δa`,
//!   `v ← v_p + c₁ Δt Δa`, `a ← a_p + c₂ Δa` with `c = (0, 1, 1)`), i.e. the
//!   scaled set `(0, 2, 1)`: the velocity is corrected with the full new
//!   acceleration;
//! - [`GearSet::Gear3`] … [`GearSet::Gear6`]: Allen & Tildesley's sets for
//!   second-order equations, `(0, 1, 1)`, `(1/6, 5/6, 1, 1/3)`,
//!   `(19/120, 3/4, 1, 1/2, 1/12)`, `(3/20, 251/360, 1, 11/18, 1/6, 1/60)`.
//!
//! Spins are integrated the same way as velocities (as derivatives of a virtual
//! rotation vector, rows `k ≥ 1`); orientations by exact rotation with the
//! corrected spin ([`super::particles::rotate`]).
//!
//! Velocity Verlet (kick–drift–kick) evaluates the forces with the half-step
//! velocities, as LAMMPS and LIGGGHTS do.

use serde::{Deserialize, Serialize};

/// A Gear coefficient set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GearSet {
    Karrech,
    Gear3,
    Gear4,
    Gear5,
    Gear6,
}

impl GearSet {
    /// Corrector coefficients `c_k` of the scaled derivatives.
    pub fn coefficients(self) -> &'static [f64] {
        match self {
            GearSet::Karrech => &[0.0, 2.0, 1.0],
            GearSet::Gear3 => &[0.0, 1.0, 1.0],
            GearSet::Gear4 => &[1.0 / 6.0, 5.0 / 6.0, 1.0, 1.0 / 3.0],
            GearSet::Gear5 => &[19.0 / 120.0, 3.0 / 4.0, 1.0, 1.0 / 2.0, 1.0 / 12.0],
            GearSet::Gear6 => &[3.0 / 20.0, 251.0 / 360.0, 1.0, 11.0 / 18.0, 1.0 / 6.0, 1.0 / 60.0],
        }
    }

    /// Number of stored derivatives `q` (position included).
    pub fn order(self) -> usize {
        self.coefficients().len()
    }

    /// The set named `name` in scenes: `karrech`, `gear3` … `gear6`.
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "karrech" => GearSet::Karrech,
            "gear3" => GearSet::Gear3,
            "gear4" => GearSet::Gear4,
            "gear5" => GearSet::Gear5,
            "gear6" => GearSet::Gear6,
            _ => return None,
        })
    }
}

/// The integrator of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Integrator {
    Verlet,
    Gear(GearSet),
}

/// Binomial coefficients for the Pascal predictor, `C(j, k)`.
pub(crate) const BINOMIAL: [[f64; 6]; 6] = [
    [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
    [1.0, 2.0, 1.0, 0.0, 0.0, 0.0],
    [1.0, 3.0, 3.0, 1.0, 0.0, 0.0],
    [1.0, 4.0, 6.0, 4.0, 1.0, 0.0],
    [1.0, 5.0, 10.0, 10.0, 5.0, 1.0],
];

/// The Taylor predictor on scaled derivatives `d[from..q]` (in place).
#[inline(always)]
pub(crate) fn predict<T>(d: &mut [T; 6], from: usize, q: usize)
where
    T: Copy + std::ops::AddAssign + std::ops::Mul<f64, Output = T>,
{
    for k in from..q {
        let mut acc = d[k];
        for j in k + 1..q {
            acc += d[j] * BINOMIAL[j][k];
        }
        d[k] = acc;
    }
}
