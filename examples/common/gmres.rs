//! Restarted GMRES with right preconditioning (Saad & Schultz 1986), for the
//! prototypes' non-symmetric Newton systems (`examples/ipm_prototype.rs`, issue 31).
//! Modified Gram–Schmidt Arnoldi, Givens rotations; the operator and the
//! preconditioner come through one callback so that both may borrow the caller.

#![allow(dead_code)] // each prototype uses a part

/// What the callback is asked for.
pub enum Op {
    /// `out = A x`.
    Apply,
    /// `x ← P⁻¹ x` in place (`out` unused); false on a failure.
    Precondition,
}

/// Solves `A x = b` to the relative residual `tol`, restarting every `restart`
/// iterations, at most `max` in all. `x` is the result (started from zero). Returns the
/// iterations made, or `None` if the preconditioner failed or the residual stayed above
/// `1e4 × tol`.
pub fn gmres(
    b: &[f64],
    x: &mut [f64],
    (tol, restart, max): (f64, usize, usize),
    op: &mut impl FnMut(Op, &mut [f64], &mut [f64]) -> bool,
) -> Option<usize> {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(a, b)| a * b).sum::<f64>();
    let bn = dot(b, b).sqrt();
    x.iter_mut().for_each(|v| *v = 0.0);
    if bn == 0.0 {
        return Some(0);
    }
    let (mut tmp, mut w, mut total) = (vec![0.0; n], vec![0.0; n], 0);
    loop {
        let mut xc = x.to_vec();
        op(Op::Apply, &mut xc, &mut tmp);
        let r: Vec<f64> = b.iter().zip(&tmp).map(|(b, k)| b - k).collect();
        let beta = dot(&r, &r).sqrt();
        if beta <= tol * bn || total >= max {
            return (beta <= 1e4 * tol * bn && x.iter().all(|v| v.is_finite())).then_some(total);
        }
        let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / beta).collect()];
        let mut zs: Vec<Vec<f64>> = Vec::new();
        let mut h = vec![vec![0.0; restart]; restart + 1];
        let (mut cs, mut sn, mut g) = (vec![0.0; restart], vec![0.0; restart], vec![0.0; restart + 1]);
        g[0] = beta;
        let mut used = 0;
        for k in 0..restart {
            total += 1;
            let mut z = basis[k].clone();
            if !op(Op::Precondition, &mut z, &mut tmp) {
                return None;
            }
            op(Op::Apply, &mut z, &mut w);
            zs.push(z);
            for i in 0..=k {
                h[i][k] = dot(&w, &basis[i]);
                for (wv, bv) in w.iter_mut().zip(&basis[i]) {
                    *wv -= h[i][k] * bv;
                }
            }
            let hn = dot(&w, &w).sqrt();
            h[k + 1][k] = hn;
            for i in 0..k {
                let t = cs[i] * h[i][k] + sn[i] * h[i + 1][k];
                h[i + 1][k] = -sn[i] * h[i][k] + cs[i] * h[i + 1][k];
                h[i][k] = t;
            }
            let d = h[k][k].hypot(h[k + 1][k]);
            (cs[k], sn[k]) = (h[k][k] / d, h[k + 1][k] / d);
            (h[k][k], h[k + 1][k]) = (d, 0.0);
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            used = k + 1;
            if g[k + 1].abs() <= tol * bn || hn == 0.0 || total >= max {
                break;
            }
            basis.push(w.iter().map(|v| v / hn).collect());
        }
        // x += Z y, y from the triangular least-squares system.
        let mut y = vec![0.0; used];
        for i in (0..used).rev() {
            let t = g[i] - (i + 1..used).map(|j| h[i][j] * y[j]).sum::<f64>();
            y[i] = t / h[i][i];
        }
        for (yj, z) in y.iter().zip(&zs) {
            for (xv, zv) in x.iter_mut().zip(z) {
                *xv += yj * zv;
            }
        }
    }
}
