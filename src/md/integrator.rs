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
//!
//! Stability ([`Integrator::amplification`], [`Integrator::stability_limit`]):
//! each integrator is linear on the test equation `ẍ = −ω² x − c ẋ` (a contact
//! spring `ω² = k/m` with its dashpot and background damping `c = γ/m`), one step
//! being a matrix on the integrator's state; the step is stable when that
//! matrix's spectral radius is at most 1 (+ [`STABILITY_TOLERANCE`]). Velocity
//! Verlet undamped: `ω Δt < 2`; with `c` alone: `c Δt < 2`.

use serde::{Deserialize, Serialize};

/// A Gear coefficient set.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GearSet {
    /// Karrech et al. 2007 eqs. 2–4 as printed (`q = 3`, scaled coefficients `(0, 2, 1)`).
    Karrech,
    /// Allen & Tildesley's third-order set `(0, 1, 1)`.
    Gear3,
    /// Allen & Tildesley's fourth-order set `(1/6, 5/6, 1, 1/3)`.
    Gear4,
    /// Allen & Tildesley's fifth-order set `(19/120, 3/4, 1, 1/2, 1/12)`.
    Gear5,
    /// Allen & Tildesley's sixth-order set `(3/20, 251/360, 1, 11/18, 1/6, 1/60)`.
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

    /// The name of the set in scenes.
    pub fn name(self) -> &'static str {
        match self {
            GearSet::Karrech => "karrech",
            GearSet::Gear3 => "gear3",
            GearSet::Gear4 => "gear4",
            GearSet::Gear5 => "gear5",
            GearSet::Gear6 => "gear6",
        }
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
    /// Velocity Verlet (kick–drift–kick), forces evaluated with the half-step velocities.
    Verlet,
    /// Gear predictor–corrector with the given coefficient set.
    Gear(GearSet),
}

/// Growth of the spectral radius above 1 per step still taken as stable. Gear 5
/// and 6 amplify an undamped oscillation weakly at any step (the spectral radius
/// is 1 + 2e-6 at `ω Δt = 0.2`, 1 + 4e-4 at 0.5 for Gear 5: 0.2 % over the
/// ~6 steps of a contact); the instability that matters grows by a factor per
/// step, far above this.
pub const STABILITY_TOLERANCE: f64 = 1e-3;

impl Integrator {
    /// `velocity Verlet` or `Gear 'karrech'`, for messages.
    pub fn describe(self) -> String {
        match self {
            Integrator::Verlet => "velocity Verlet".into(),
            Integrator::Gear(set) => format!("Gear '{}'", set.name()),
        }
    }

    /// Spectral radius of one step of the integrator on `ẍ = −ω² x − c ẋ`, with
    /// `p = (ω Δt)²` and `q = c Δt`: the factor by which an oscillation (or a
    /// decay) grows per step in the long run. Velocity Verlet on `(x_n, Δt v_{n−½})`
    /// (the forces see the half-kicked velocity) is `[[1 − p, 1 − q], [−p, 1 − q]]`;
    /// a Gear set on its scaled derivatives is `(I + c eᵀ) P`, with `P` the Pascal
    /// predictor, `c` the corrector coefficients and `e = (−p/2, −q/2, −1, 0, …)`
    /// (`Δ = Δt²/2 a(x_p, v_p) − r₂`). Computed as `‖M^{2³⁰}‖^{2⁻³⁰}` by repeated squaring.
    pub fn amplification(self, p: f64, q: f64) -> f64 {
        let mut m = [[0.0f64; 6]; 6];
        let n = match self {
            Integrator::Verlet => {
                m[0] = [1.0 - p, 1.0 - q, 0.0, 0.0, 0.0, 0.0];
                m[1] = [-p, 1.0 - q, 0.0, 0.0, 0.0, 0.0];
                2
            }
            Integrator::Gear(set) => {
                let c = set.coefficients();
                let n = c.len();
                let e = [-0.5 * p, -0.5 * q, -1.0, 0.0, 0.0, 0.0];
                for (i, row) in m.iter_mut().enumerate().take(n) {
                    for (j, mij) in row.iter_mut().enumerate().take(n) {
                        // Row i of (I + c eᵀ) times column j of P (P[k][j] = C(j, k)).
                        let a = |k: usize| (if i == k { 1.0 } else { 0.0 }) + c[i] * e[k];
                        *mij = (0..=j).map(|k| a(k) * BINOMIAL[j][k]).sum();
                    }
                }
                n
            }
        };
        spectral_radius(m, n)
    }

    /// Largest time step (s) for which the integrator is stable on
    /// `ẍ = −ω² x − c ẋ`, given `omega2 = ω²` (1/s²) and `c` (1/s): the
    /// [`amplification`](Integrator::amplification) stays within
    /// 1 + [`STABILITY_TOLERANCE`] (scanned in steps of 0.05 of `(ω + c) Δt`, then
    /// bisected). Infinite if `ω = c = 0`.
    pub fn stability_limit(self, omega2: f64, c: f64) -> f64 {
        let scale = omega2.sqrt() + c;
        if !(scale > 0.0 && scale.is_finite()) {
            return if scale == 0.0 { f64::INFINITY } else { 0.0 };
        }
        // u = (ω + c) Δt: stable below about 2 for every integrator and damping.
        let stable = |u: f64| {
            let dt = u / scale;
            self.amplification(omega2 * dt * dt, c * dt) <= 1.0 + STABILITY_TOLERANCE
        };
        let step = 0.05;
        let mut lo = 0.0;
        while lo < 8.0 && stable(lo + step) {
            lo += step;
        }
        let mut hi = lo + step;
        for _ in 0..40 {
            let mid = 0.5 * (lo + hi);
            if stable(mid) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        lo / scale
    }
}

/// Spectral radius of the top-left `n × n` block of `m`, from the norm of its
/// 2³⁰-th power (repeated squaring, rescaled at each squaring).
fn spectral_radius(mut m: [[f64; 6]; 6], n: usize) -> f64 {
    const SQUARINGS: i32 = 30;
    let mut log = 0.0;
    for _ in 0..SQUARINGS {
        let mut sq = [[0.0f64; 6]; 6];
        for (row, out) in m.iter().zip(sq.iter_mut()).take(n) {
            for (&a, mk) in row.iter().zip(&m).take(n) {
                for (o, &b) in out.iter_mut().zip(mk).take(n) {
                    *o += a * b;
                }
            }
        }
        let norm = sq.iter().flatten().fold(0.0f64, |a, &b| a.max(b.abs()));
        if !(norm > 0.0 && norm.is_finite()) {
            return if norm == 0.0 { 0.0 } else { f64::INFINITY };
        }
        for v in sq.iter_mut().flatten() {
            *v /= norm;
        }
        m = sq;
        log = 2.0 * log + norm.ln();
    }
    (log / 2f64.powi(SQUARINGS)).exp()
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
