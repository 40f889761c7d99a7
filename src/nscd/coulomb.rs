//! Exact solution of the single-contact 2D Signorini–Coulomb problem
//! (Saussine et al. 2006, law (11)) with its 2×2 local Delassus block.
//!
//! Unknowns are the impulses `P = (P_N, P_T) = h (R_N, R_T)` (N·s). The local
//! velocity is affine in `P`: `U = U_free + W P` with `W = H* M⁻¹ H` symmetric
//! positive (semi-)definite. The law is, with a normal threshold `c`:
//! `U_N ≥ c, P_N ≥ 0, (U_N − c) P_N = 0; |P_T| ≤ μ P_N; U_T ≠ 0 ⇒ P_T = −μ P_N sign(U_T)`.
//! `c` carries the gap prediction and the restitution (see [`super::contact`]).
//! The 2D law is piecewise linear, so the exact solution is one of four
//! candidates tried in order: separation, sticking, sliding in either direction.

/// Local Delassus block `[[W_NN, W_NT], [W_NT, W_TT]]` (m/s per N·s).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Delassus {
    /// `W_NN`: normal velocity per unit normal impulse (1/kg); > 0 unless both bodies are immobile along `n`.
    pub nn: f64,
    /// `W_NT`: normal velocity per unit tangential impulse, equal to the tangential velocity
    /// per unit normal impulse (1/kg); nonzero through the lever arms.
    pub nt: f64,
    /// `W_TT`: tangential velocity per unit tangential impulse (1/kg).
    pub tt: f64,
}

/// Solves the local problem.
///
/// - `u_free`: `(U_N, U_T)` without this contact's impulse (m/s);
/// - `s_open`: the contact stays open (P = 0) when `U_free_N ≥ s_open`;
/// - `c_closed`: the normal velocity enforced once closed (`≥ s_open`);
/// - `mu`: friction coefficient.
///
/// Returns `(P_N, P_T)`.
#[inline]
pub fn solve(w: Delassus, u_free: [f64; 2], s_open: f64, c_closed: f64, mu: f64) -> [f64; 2] {
    let [un, ut] = u_free;
    if un >= s_open {
        return [0.0, 0.0];
    }
    let rn = c_closed - un; // > 0
    let det = w.nn * w.tt - w.nt * w.nt;
    if det > 1e-12 * w.nn * w.tt {
        // Sticking: U_N = c, U_T = 0.
        let pn = (w.tt * rn + w.nt * ut) / det;
        let pt = (-w.nt * rn - w.nn * ut) / det;
        if pn >= 0.0 && pt.abs() <= mu * pn {
            return [pn, pt];
        }
    }
    // Sliding with U_T of sign σ: P_T = −σ μ P_N. The sticking solution tells
    // which side the friction saturates on; try that side first.
    let first = if ut + w.nt * rn / w.nn.max(f64::MIN_POSITIVE) >= 0.0 { 1.0 } else { -1.0 };
    for sigma in [first, -first] {
        let denom = w.nn - sigma * mu * w.nt;
        if denom <= 0.0 {
            continue;
        }
        let pn = rn / denom;
        let pt = -sigma * mu * pn;
        let u_t = ut + w.nt * pn + w.tt * pt;
        if sigma * u_t >= -1e-12 * (ut.abs() + w.tt * pt.abs()) {
            return [pn, pt];
        }
    }
    // Degenerate block (a body that can only move along one axis): frictionless normal.
    if w.nn > 0.0 {
        [rn / w.nn, 0.0]
    } else {
        [0.0, 0.0]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks that `p` satisfies the law for the given data, to round-off.
    fn check(w: Delassus, uf: [f64; 2], c: f64, mu: f64, p: [f64; 2]) {
        let un = uf[0] + w.nn * p[0] + w.nt * p[1];
        let ut = uf[1] + w.nt * p[0] + w.tt * p[1];
        let tol = 1e-9;
        assert!(p[0] >= 0.0);
        assert!(p[1].abs() <= mu * p[0] + tol);
        if p[0] > 0.0 {
            assert!((un - c).abs() < tol, "un {un} c {c}");
        } else {
            assert!(un >= c - tol);
        }
        if ut.abs() > tol {
            assert!((p[1] + mu * p[0] * ut.signum()).abs() < tol);
        }
    }

    #[test]
    fn exact_law_on_random_problems() {
        let mut seed = 7u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        for _ in 0..10_000 {
            // W = J Jᵀ with a random 2×2 J is symmetric positive definite.
            let j = [rnd(), rnd(), rnd(), rnd()];
            let w = Delassus {
                nn: j[0] * j[0] + j[1] * j[1] + 0.1,
                nt: j[0] * j[2] + j[1] * j[3],
                tt: j[2] * j[2] + j[3] * j[3] + 0.1,
            };
            let uf = [rnd(), rnd()];
            let mu = 0.5 * (rnd() + 1.0);
            let p = solve(w, uf, 0.0, 0.0, mu);
            check(w, uf, 0.0, mu, p);
        }
    }
}
