//! Alart–Curnier's semismooth Newton for the single-contact 3D law, to measure the exact solver against
//! (LMGC90's non-diagonal local solver, `mu_NG_solver_` of `nlgs_3D`, is this Newton without a line search).
//!
//! Alart and Curnier (1991) write the law as the root of the augmented-Lagrangian function
//! `Φ_N = P_N − max(0, P_N − ρ_N (U_N − c))`,
//! `Φ_T = P_T − proj_{disc(μ P_N⁺)}(P_T − ρ_T U_T)`,
//! piecewise smooth in `P`; Newton's step uses its generalized Jacobian, and a backtracking line search on
//! `|Φ|²` (Armijo) globalizes it.

use super::Delassus3;

/// The convergence tolerance of [`solve_alart_curnier`]: `|Φ| ≤ AC_TOLERANCE · max(|P|, ρ_N |c − U_free_N|)`,
/// relative to the impulse's scale (`ρ_N |c − U_free_N|` is the frictionless normal impulse).
pub const AC_TOLERANCE: f64 = 1e-12;

/// The cap on Newton steps of [`solve_alart_curnier`].
pub const AC_MAX_ITERATIONS: usize = 50;

/// `Φ(P)` and a generalized Jacobian `∂Φ/∂P`.
#[allow(clippy::too_many_arguments)]
fn eval(
    m: &[[f64; 3]; 3],
    uf: [f64; 3],
    c: f64,
    mu: f64,
    (rn, rt): (f64, f64),
    p: [f64; 3],
) -> ([f64; 3], [[f64; 3]; 3]) {
    let u: [f64; 3] = std::array::from_fn(|i| uf[i] + m[i][0] * p[0] + m[i][1] * p[1] + m[i][2] * p[2]);
    let mut phi = [0.0; 3];
    let mut jac = [[0.0; 3]; 3];
    if p[0] - rn * (u[0] - c) > 0.0 {
        phi[0] = rn * (u[0] - c);
        jac[0] = m[0].map(|x| rn * x);
    } else {
        phi[0] = p[0];
        jac[0] = [1.0, 0.0, 0.0];
    }
    let y = [p[1] - rt * u[1], p[2] - rt * u[2]];
    let ny = (y[0] * y[0] + y[1] * y[1]).sqrt();
    let radius = mu * p[0].max(0.0);
    if ny <= radius {
        phi[1] = rt * u[1];
        phi[2] = rt * u[2];
        jac[1] = m[1].map(|x| rt * x);
        jac[2] = m[2].map(|x| rt * x);
    } else {
        let yh = [y[0] / ny, y[1] / ny];
        let k = radius / ny;
        let dr = if p[0] > 0.0 { mu } else { 0.0 };
        phi[1] = p[1] - radius * yh[0];
        phi[2] = p[2] - radius * yh[1];
        // dy/dP = [0 | I] − ρ_T W_T·, and d(R ŷ) = ŷ dR + (R/|y|) (I − ŷŷᵀ) dy.
        let dy: [[f64; 3]; 2] =
            std::array::from_fn(|i| std::array::from_fn(|j| f64::from(u8::from(j == i + 1)) - rt * m[i + 1][j]));
        for i in 0..2 {
            for j in 0..3 {
                let proj = (0..2).map(|l| (f64::from(u8::from(i == l)) - yh[i] * yh[l]) * dy[l][j]).sum::<f64>();
                let dphi = f64::from(u8::from(j == i + 1)) - yh[i] * if j == 0 { dr } else { 0.0 } - k * proj;
                jac[i + 1][j] = dphi;
            }
        }
    }
    (phi, jac)
}

/// `x` with `a x = b` by Gaussian elimination with partial pivoting; `None` if `a` is singular to round-off.
fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> Option<[f64; 3]> {
    let size = a.iter().flatten().fold(0.0f64, |s, x| s.max(x.abs()));
    for col in 0..3 {
        let piv = (col..3).max_by(|&i, &j| a[i][col].abs().total_cmp(&a[j][col].abs()))?;
        if a[piv][col].is_nan() || a[piv][col].abs() <= 1e-14 * size {
            return None;
        }
        a.swap(col, piv);
        b.swap(col, piv);
        let pivot_row = a[col];
        for row in col + 1..3 {
            let f = a[row][col] / pivot_row[col];
            for (x, y) in a[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * y;
            }
            b[row] -= f * b[col];
        }
    }
    let mut x = [0.0; 3];
    for row in (0..3).rev() {
        let s = (row + 1..3).map(|k| a[row][k] * x[k]).sum::<f64>();
        x[row] = (b[row] - s) / a[row][row];
    }
    Some(x)
}

fn norm2(v: [f64; 3]) -> f64 {
    v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
}

/// Alart–Curnier's semismooth Newton from `start` (same data as [`super::solve`]), with `ρ_N = 1/W_NN` and
/// `ρ_T = 2/(W_T1T1 + W_T2T2)` and an Armijo backtracking on `|Φ|²` (halving, down to 1/1024; the best trial is
/// taken if none passes); a step of a singular Jacobian is replaced by the projection step `ΔP = −Φ`.
///
/// Returns the impulse and the number of Newton steps; `AC_MAX_ITERATIONS + 1` ([`AC_MAX_ITERATIONS`]) when
/// `|Φ|` did not meet [`AC_TOLERANCE`] within the cap (the impulse is then the last iterate).
pub fn solve_alart_curnier(
    w: &Delassus3,
    u_free: [f64; 3],
    s_open: f64,
    c_closed: f64,
    mu: f64,
    start: [f64; 3],
) -> ([f64; 3], usize) {
    let m = &w.m;
    if u_free[0] >= s_open || !u_free.iter().chain(m.iter().flatten()).all(|x| x.is_finite()) {
        return ([0.0; 3], 0);
    }
    let mu = mu.max(0.0);
    let diag_max = m[0][0].max(m[1][1]).max(m[2][2]);
    let inv = |x: f64| {
        if x > 1e-300 * diag_max && x > 0.0 {
            1.0 / x
        } else if diag_max > 0.0 {
            1.0 / diag_max
        } else {
            1.0
        }
    };
    let rho = (inv(m[0][0]), inv(0.5 * (m[1][1] + m[2][2])));
    let p_scale = rho.0 * (c_closed - u_free[0]).abs();
    let mut p = if start.iter().all(|x| x.is_finite()) { start } else { [0.0; 3] };
    let (mut phi, mut jac) = eval(m, u_free, c_closed, mu, rho, p);
    for it in 0..=AC_MAX_ITERATIONS {
        let f = norm2(phi);
        let tol = AC_TOLERANCE * norm2(p).sqrt().max(p_scale);
        if f.sqrt() <= tol {
            return (p, it);
        }
        if it == AC_MAX_ITERATIONS {
            break;
        }
        let step = solve3(jac, phi.map(|x| -x)).unwrap_or(phi.map(|x| -x));
        let trial = |alpha: f64| {
            let q: [f64; 3] = std::array::from_fn(|i| p[i] + alpha * step[i]);
            let (phi_q, jac_q) = eval(m, u_free, c_closed, mu, rho, q);
            (norm2(phi_q), q, phi_q, jac_q)
        };
        let mut alpha = 1.0;
        let mut best = trial(alpha);
        while best.0 > (1.0 - 2e-4 * alpha) * f && alpha >= 1.0 / 1024.0 {
            alpha *= 0.5;
            let next = trial(alpha);
            if next.0 < best.0 {
                best = next;
            }
        }
        let (_, q, phi_q, jac_q) = best;
        (p, phi, jac) = (q, phi_q, jac_q);
    }
    (p, AC_MAX_ITERATIONS + 1)
}
