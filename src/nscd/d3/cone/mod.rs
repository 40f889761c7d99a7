//! Exact solution of the single-contact 3D Signorini–Coulomb problem with its full 3×3 local Delassus block:
//! law (11) of Saussine et al. 2006 written in 3D (Jean 1999), the local law of the 3D NSCD engine's row.
//!
//! Unknowns are the impulses `P = (P_N, P_T1, P_T2)` (N·s); the local velocity is `U = U_free + W P` with
//! `W = H* M⁻¹ H` symmetric positive (semi-)definite, not diagonal: the lever arms couple the normal and the
//! tangential components. With `c = c_closed` the law is
//! `U_N ≥ c, P_N ≥ 0, (U_N − c) P_N = 0; |P_T| ≤ μ P_N; U_T ≠ 0 ⇒ P_T = −μ P_N U_T/|U_T|`, and `P = 0` when
//! `U_free_N ≥ s_open` (the thresholds of [`crate::nscd::contact`]).
//!
//! **Method of [`solve`]** (enumeration, exact to round-off). Separation when `U_free_N ≥ s_open` or
//! `U_free_N ≥ c`; sticking from the 3×3 system `U = (c, 0, 0)`, kept if it lies in the cone; otherwise
//! sliding with slip direction `d = (cos θ, sin θ)`: `P_T = −μ P_N d` and `U_N = c` give
//! `P_N = r / D(d)` with `r = c − U_free_N`, `D(d) = W_NN − μ W_NT·d`, and the slip velocity `U_T` must be a
//! positive multiple of `d`. Multiplied by `D`, the condition `d × U_T = 0` is a trigonometric polynomial of
//! degree 2 in `θ`, `g(θ)`. Its root is found by Newton in `θ` (the iterate rotated, no trigonometric
//! functions) from the row's last slip in the sweeps ([`solve_near`]), else from the sticking solution's
//! friction direction; if that fails (no convergence, or a root with `D ≤ 0` or `U_T` against `d`), all
//! roots are enumerated: on each half circle `g` times `(1 + t²)²` is a
//! quartic in `t = tan(φ/2)`, `|t| ≤ 1`, whose real roots are isolated between the roots of its derivatives
//! and bracketed; each is polished by the same Newton and checked. LMGC90's `nlgs_3D` instead runs a
//! Newton on Alart–Curnier's function (`mu_NG_solver_`, ≤ 15 undamped steps) or, in its diagonal resolution,
//! projects the diagonal sticking impulse radially on the disc; [`solve_alart_curnier`] is the former with a
//! line search, kept to measure against.
//!
//! **Measured against each other** on the same 100 000 random coupled contacts (`tests::random_case`: 29 % open,
//! 62 % sliding, 9 % sticking; `cargo test --release --lib nscd::d3::cone::tests::measure -- --ignored
//! --nocapture`, one core of this machine), the exact [`solve`] takes 90 ns per call with a largest [`residual`]
//! of 6e-15 (108 ns, side by side, before its block kept the reciprocal pivots of its sticking system and
//! Newton's last turns lost their square root), and Alart–Curnier 305 ns cold (3.9 Newton steps per closed
//! contact; 10 runs, 0.01 %, not converged within 50 steps: sticking contacts with μ ≈ 0.9–1 and strong
//! coupling, stalled near `P_N = 0`) and 180 ns warm-started from the exact impulse perturbed by 1 % (2.1
//! steps, no failure, largest residual 1.6e-12).
//! The exact solver, faster than Alart–Curnier even warm and exact to round-off, is the one recommended for
//! the engine's row; Alart–Curnier stays as a cross-check.

mod newton;
#[cfg(test)]
mod tests;

pub use newton::{solve_alart_curnier, AC_MAX_ITERATIONS, AC_TOLERANCE};

/// The local Delassus block `W = H* M⁻¹ H` of one contact in its frame `(n, t1, t2)` (1/kg, i.e. m/s of
/// local velocity per N·s of impulse), symmetric positive semidefinite.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Delassus3 {
    /// `m[i][j]`: velocity component `i` per unit impulse component `j` (0: normal, 1 and 2: tangents) (1/kg).
    pub m: [[f64; 3]; 3],
    /// The reciprocals of the pivots `d_k` of `W = L D Lᵀ` (kg), computed once by [`Delassus3::new`] so that the
    /// sweeps' visits solve the sticking system without a division: `1/d_0 = 1/W_NN`, 0 when `W` has a term
    /// that is not finite or `W_NN ≤ 0` (no impulse then moves the contact); `1/d_1` and `1/d_2` are 0 when
    /// their pivot is below [`PIVOT`] of `W`'s largest diagonal term (`W` singular for the sticking system).
    inv_pivots: [f64; 3],
}

impl Default for Delassus3 {
    /// The zero block (no impulse moves the contact).
    fn default() -> Self {
        Self::new([[0.0; 3]; 3])
    }
}

impl Delassus3 {
    /// The block of `m`, symmetrised (`(m + mᵀ)/2`) to remove the round-off of its assembly, with the
    /// reciprocal pivots of its sticking system.
    pub fn new(m: [[f64; 3]; 3]) -> Self {
        let m: [[f64; 3]; 3] = std::array::from_fn(|i| std::array::from_fn(|j| 0.5 * (m[i][j] + m[j][i])));
        let mut inv_pivots = [0.0; 3];
        if m.iter().flatten().all(|x| x.is_finite()) && m[0][0] > 0.0 {
            let tiny = PIVOT * m[0][0].max(m[1][1]).max(m[2][2]);
            let (l10, l20) = (m[1][0] / m[0][0], m[2][0] / m[0][0]);
            let d1 = m[1][1] - l10 * m[1][0];
            let l21 = (m[2][1] - l20 * m[1][0]) / d1;
            let d2 = m[2][2] - l20 * m[2][0] - l21 * l21 * d1;
            inv_pivots[0] = 1.0 / m[0][0];
            if d1 > tiny && d2 > tiny {
                inv_pivots[1] = 1.0 / d1;
                inv_pivots[2] = 1.0 / d2;
            }
        }
        Self { m, inv_pivots }
    }

    /// `W P` (m/s).
    #[inline(always)]
    pub fn apply(&self, p: [f64; 3]) -> [f64; 3] {
        std::array::from_fn(|i| self.m[i][0] * p[0] + self.m[i][1] * p[1] + self.m[i][2] * p[2])
    }
}

/// A pivot of `W = L D Lᵀ` below this fraction of `W`'s largest diagonal term makes `W` singular for the
/// sticking system (a condition number beyond ~1e13).
const PIVOT: f64 = 1e-13;
/// A root of `g` is accepted when `|g|` is below this fraction of the size of its terms.
const ROOT_TOL: f64 = 1e-13;
/// A slip velocity against `d` is accepted down to this fraction of the size of its terms (a sliding at the
/// edge of sticking).
const SLIP_TOL: f64 = 1e-12;

/// Solves the local problem exactly.
///
/// - `u_free`: `(U_N, U_T1, U_T2)` without this contact's impulse (m/s);
/// - `s_open`: the contact stays open (`P = 0`) when `U_free_N ≥ s_open` (m/s);
/// - `c_closed`: the normal velocity enforced once closed (m/s);
/// - `mu`: friction coefficient (negative is read as 0).
///
/// Returns `(P_N, P_T1, P_T2)` (N·s). It is never NaN: non-finite data give `P = 0`. If no candidate satisfies
/// the law (a singular block can make the problem unsolvable, e.g. `W = q qᵀ` with `q_N − μ q_T·d ≤ 0` along
/// the only possible slip direction `d`), the result is the nearest to the law of no impulse, the sticking
/// impulse projected on the cone, the frictionless impulse and Alart–Curnier's Newton from the best of these
/// (by the absolute natural-map residual of [`residual`]); and `P = 0` if `W_NN = 0` (no impulse moves `U_N`).
/// A block whose condition exceeds ~1e13 is singular for the sticking system.
pub fn solve(w: &Delassus3, u_free: [f64; 3], s_open: f64, c_closed: f64, mu: f64) -> [f64; 3] {
    solve_near(w, u_free, s_open, c_closed, mu, [0.0; 3])
}

/// [`solve`], the sliding searched first from the slip direction of `previous` (N·s) when it slides — in the
/// Gauss–Seidel sweeps the row's impulse of the last visit, whose direction changes little from sweep to
/// sweep: Newton then needs fewer steps. The solution is the law's, as [`solve`]'s; where the law has several
/// sliding solutions (a strongly coupled block), the one nearest that direction.
#[inline(always)]
pub fn solve_near(
    w: &Delassus3,
    u_free: [f64; 3],
    s_open: f64,
    c_closed: f64,
    mu: f64,
    previous: [f64; 3],
) -> [f64; 3] {
    let m = &w.m;
    let r = c_closed - u_free[0];
    if u_free[0] >= s_open || r <= 0.0 {
        return [0.0; 3];
    }
    // After the open exit (it returns the same zero): a NaN `U_N` or `c` fails both of its tests. One sum is
    // finite only if its terms are (finite terms overflowing it, beyond 1e308 m/s, count as non-finite too).
    // `1/W_NN = 0`: a term of `W` is not finite, or no impulse moves U_N (W ⪰ 0 and W_NN = 0 make W's first
    // row 0) and the law cannot be met.
    if w.inv_pivots[0] == 0.0 || !(u_free[0] + u_free[1] + u_free[2] + c_closed).is_finite() {
        return [0.0; 3];
    }
    let mu = if mu > 0.0 { mu } else { 0.0 };
    if mu == 0.0 {
        return [r / m[0][0], 0.0, 0.0];
    }
    let a = [u_free[1], u_free[2]];
    // Sticking: U = (c, 0, 0), i.e. W P = (r, −U_free_T).
    // (The candidate tested in registers before it becomes an `Option`: built as one, it went through the
    // stack piecewise and was read back whole, a store-forwarding stall on every visit.)
    let (p, solvable) = ldl_solve(w, [r, -a[0], -a[1]]);
    if solvable && p[0] >= 0.0 && p[1] * p[1] + p[2] * p[2] <= mu * mu * p[0] * p[0] {
        return p;
    }
    let stick = solvable.then_some(p);
    let s = Slide::new(m, a, r, mu);
    // Slip direction guess: the last slip, else opposite to the sticking friction, else along the frictionless
    // slip velocity.
    let sliding_before = previous[0] > 0.0 && len2(previous[1], previous[2]) >= (1.0 - 1e-9) * mu * previous[0];
    let guess = match stick {
        _ if sliding_before => [-previous[1], -previous[2]],
        Some(p) if p[1] != 0.0 || p[2] != 0.0 => [-p[1], -p[2]],
        _ => [a[0] + r / m[0][0] * m[0][1], a[1] + r / m[0][0] * m[0][2]],
    };
    let d0 = normalize(guess).unwrap_or([1.0, 0.0]);
    if let Some(p) = s.newton(d0).and_then(|d| s.impulse(d)) {
        return p;
    }
    if let Some(p) = s.enumerate(d0) {
        return p;
    }
    best_projection(w, u_free, s_open, c_closed, mu, stick, r)
}

/// The fallback of [`solve`] when no candidate satisfies the law: of no impulse, the sticking impulse
/// projected on the cone, the frictionless impulse and Alart–Curnier's Newton from the best of these, the one
/// nearest the law by the natural map's absolute residual (N·s; the scale-free [`residual`] would favour an
/// impulse grown without bound along a null direction of a singular `W`).
#[cold]
fn best_projection(
    w: &Delassus3,
    u_free: [f64; 3],
    s_open: f64,
    c: f64,
    mu: f64,
    stick: Option<[f64; 3]>,
    r: f64,
) -> [f64; 3] {
    let distance = |p: [f64; 3]| {
        let d = natural_map(w, u_free, s_open, c, mu, p).0;
        if d.is_finite() && p.iter().all(|x| x.is_finite()) {
            d
        } else {
            f64::INFINITY
        }
    };
    let mut best = ([0.0; 3], distance([0.0; 3]));
    let frictionless = [r / w.m[0][0], 0.0, 0.0];
    for p in [stick.map(|p| project_cone(p, mu)), Some(frictionless)].into_iter().flatten() {
        if distance(p) < best.1 {
            best = (p, distance(p));
        }
    }
    let p = solve_alart_curnier(w, u_free, s_open, c, mu, best.0).0;
    if distance(p) < best.1 {
        best = (p, distance(p));
    }
    best.0
}

#[inline(always)]
fn normalize(v: [f64; 2]) -> Option<[f64; 2]> {
    let n = len2(v[0], v[1]);
    (n > 0.0 && n.is_finite()).then(|| {
        let inv = 1.0 / n;
        [v[0] * inv, v[1] * inv]
    })
}

/// The unit vector `d` turned by `atan δ`: `(d + δ d⊥) / √(1 + δ²)`. Below `|δ| = 1e-3` (Newton's last steps)
/// the factor is its series `1 − δ²/2 + 3δ⁴/8`, whose error `5δ⁶/16 < 4e-19` is below round-off: no square root
/// nor division on the sweeps' critical path; larger turns renormalise exactly.
#[inline(always)]
fn turn(d: [f64; 2], delta: f64) -> Option<[f64; 2]> {
    let v = [d[0] - delta * d[1], d[1] + delta * d[0]];
    if delta.abs() < 1e-3 {
        let e = delta * delta;
        let k = 1.0 - e * (0.5 - 0.375 * e);
        return Some([v[0] * k, v[1] * k]);
    }
    normalize(v)
}

/// `x` with `W x = b` by `W = L D Lᵀ` (backward stable for `W ⪰ 0`: `W x − b` is round-off of `|W||x|`), with the
/// reciprocal pivots of [`Delassus3::new`], and whether the block is regular for it (`W_NN > 0` is known; a
/// singular block gives a meaningless `x`). The three terms of `L` are formed again here from `m` (products, no
/// division) rather than kept from the factorisation: kept, they took the row to seven cache lines, and that
/// version measured no faster.
#[inline(always)]
fn ldl_solve(w: &Delassus3, b: [f64; 3]) -> ([f64; 3], bool) {
    let (m, [i0, i1, i2]) = (&w.m, w.inv_pivots);
    let (l10, l20) = (m[1][0] * i0, m[2][0] * i0);
    let l21 = (m[2][1] - l20 * m[1][0]) * i1;
    let y1 = b[1] - l10 * b[0];
    let x2 = (b[2] - l20 * b[0] - l21 * y1) * i2;
    let x1 = y1 * i1 - l21 * x2;
    ([b[0] * i0 - l10 * x1 - l20 * x2, x1, x2], i1 != 0.0)
}

/// The sliding problem of one contact: for a slip direction `d`, `D(d) = W_NN − μ W_NT·d` and
/// `g(d) = d × (D a + r (W_NT − μ W_TT d))`, `D(d) U_T` being the vector in parentheses.
struct Slide {
    /// `U_free_T` (m/s), `W_NT` (1/kg), `W_TT` as `(m11, m12, m22)` (1/kg), `W_NN`, `r = c − U_free_N`, `μ`.
    a: [f64; 2],
    w: [f64; 2],
    t: [f64; 3],
    nn: f64,
    r: f64,
    mu: f64,
    /// `g = v2 cos θ − v1 sin θ + k0 cos² θ + k1 cos θ sin θ + k2 sin² θ`.
    v: [f64; 2],
    k: [f64; 3],
    /// Size of the terms of `g` (for its tolerance).
    scale: f64,
}

impl Slide {
    fn new(m: &[[f64; 3]; 3], a: [f64; 2], r: f64, mu: f64) -> Self {
        let (w, t, nn) = ([m[0][1], m[0][2]], [m[1][1], m[1][2], m[2][2]], m[0][0]);
        let v = [nn * a[0] + r * w[0], nn * a[1] + r * w[1]];
        let k = [
            -mu * (w[0] * a[1] + r * t[1]),
            -mu * (w[1] * a[1] - w[0] * a[0] + r * (t[2] - t[0])),
            mu * (w[1] * a[0] + r * t[1]),
        ];
        let scale = v[0].abs() + v[1].abs() + k[0].abs() + k[1].abs() + k[2].abs();
        Self { a, w, t, nn, r, mu, v, k, scale }
    }

    /// `g(d)` and its derivative in `θ`.
    #[inline(always)]
    fn g(&self, d: [f64; 2]) -> (f64, f64) {
        let ([c, s], v, k) = (d, self.v, self.k);
        let g = v[1] * c - v[0] * s + k[0] * c * c + k[1] * c * s + k[2] * s * s;
        let dg = -v[1] * s - v[0] * c + 2.0 * (k[2] - k[0]) * c * s + k[1] * (c * c - s * s);
        (g, dg)
    }

    /// Newton on `g` in `θ` from `d`: the step `δ` turns `d` by `atan δ` (`d ← (d + δ d⊥)/|…|`), which keeps the
    /// quadratic convergence and bounds a step by 90°. `None` when it does not reach a root.
    #[inline(always)]
    fn newton(&self, mut d: [f64; 2]) -> Option<[f64; 2]> {
        let tol = ROOT_TOL * self.scale;
        for _ in 0..40 {
            let (g, dg) = self.g(d);
            if g.abs() <= 4.0 * f64::EPSILON * self.scale {
                return Some(d);
            }
            if dg == 0.0 {
                break;
            }
            let delta = (-g / dg).clamp(-1e6, 1e6);
            d = turn(d, delta)?;
            if delta.abs() <= 1e-15 {
                break;
            }
        }
        (self.g(d).0.abs() <= tol).then_some(d)
    }

    /// The impulse of the sliding along `d` (a root of `g`), or `None` if `D(d) ≤ 0` or `U_T` is against `d`.
    fn impulse(&self, d: [f64; 2]) -> Option<[f64; 3]> {
        let (w, t, mu, r) = (self.w, self.t, self.mu, self.r);
        let den = self.nn - mu * (w[0] * d[0] + w[1] * d[1]);
        if den <= 1e-14 * (self.nn + mu * len2(w[0], w[1])) {
            return None;
        }
        let td = [t[0] * d[0] + t[1] * d[1], t[1] * d[0] + t[2] * d[1]];
        let du = [den * self.a[0] + r * (w[0] - mu * td[0]), den * self.a[1] + r * (w[1] - mu * td[1])];
        let size = den * len2(self.a[0], self.a[1]) + r * (len2(w[0], w[1]) + mu * len2(td[0], td[1]));
        if du[0] * d[0] + du[1] * d[1] < -SLIP_TOL * size {
            return None;
        }
        let pn = r / den;
        Some([pn, -mu * pn * d[0], -mu * pn * d[1]])
    }

    /// All the roots of `g` on the circle, polished and checked; the valid one nearest to `d0`.
    #[cold]
    fn enumerate(&self, d0: [f64; 2]) -> Option<[f64; 3]> {
        let mut best: Option<(f64, [f64; 3])> = None;
        // Half circle d_x ≥ 0 (sign +1) and its opposite (sign −1, the data turned by π: v → −v).
        for sign in [1.0, -1.0] {
            let (v, k) = ([sign * self.v[0], sign * self.v[1]], self.k);
            // g (1 + t²)² with cos φ = (1 − t²)/(1 + t²), sin φ = 2t/(1 + t²).
            let q = [v[1] + k[0], 2.0 * (k[1] - v[0]), 4.0 * k[2] - 2.0 * k[0], -2.0 * (v[0] + k[1]), k[0] - v[1]];
            let mut roots = [0.0; 4];
            let n = poly_roots(&q, -1.0, 1.0, &mut roots);
            for &t in &roots[..n] {
                let den = 1.0 + t * t;
                let d = [sign * (1.0 - t * t) / den, sign * 2.0 * t / den];
                if let Some((d, p)) = self.newton(d).and_then(|d| Some((d, self.impulse(d)?))) {
                    let closeness = d[0] * d0[0] + d[1] * d0[1];
                    if best.is_none_or(|(c, _)| closeness > c) {
                        best = Some((closeness, p));
                    }
                }
            }
        }
        best.map(|(_, p)| p)
    }
}

/// The polynomial `Σ c_i x^i` and its derivative at `x`.
#[inline(always)]
fn horner(c: &[f64], x: f64) -> (f64, f64) {
    let (mut p, mut dp) = (0.0, 0.0);
    for &ci in c.iter().rev() {
        dp = dp * x + p;
        p = p * x + ci;
    }
    (p, dp)
}

/// The real roots in `[lo, hi]` of `Σ c_i x^i` (degree ≤ 4), increasing, into `out`; their number. The roots
/// of the derivative (recursively) cut `[lo, hi]` into intervals where the polynomial is monotone: a change of
/// sign there brackets one root (safeguarded Newton); a critical point where the polynomial vanishes to
/// round-off is a double root.
fn poly_roots(c: &[f64], lo: f64, hi: f64, out: &mut [f64; 4]) -> usize {
    let n = c.len().saturating_sub(1);
    if n == 0 {
        return 0;
    }
    if n == 1 {
        let x = -c[0] / c[1];
        if c[1] != 0.0 && (lo..=hi).contains(&x) {
            out[0] = x;
            return 1;
        }
        return 0;
    }
    let mut dc = [0.0; 4];
    for i in 1..=n {
        dc[i - 1] = i as f64 * c[i];
    }
    let mut cuts = [lo, 0.0, 0.0, 0.0, 0.0, hi];
    let mut crit = [0.0; 4];
    let m = poly_roots(&dc[..n], lo, hi, &mut crit);
    cuts[1..=m].copy_from_slice(&crit[..m]);
    cuts[m + 1] = hi;
    let size = |x: f64| c.iter().rev().fold(0.0, |s, ci| s * x.abs() + ci.abs());
    let mut k = 0;
    let mut push = |x: f64, out: &mut [f64; 4]| {
        if k < 4 && (k == 0 || x > out[k - 1]) {
            out[k] = x;
            k += 1;
        }
    };
    for i in 0..=m {
        let (x0, x1) = (cuts[i], cuts[i + 1]);
        let (f0, f1) = (horner(c, x0).0, horner(c, x1).0);
        if f0.abs() <= 8.0 * f64::EPSILON * size(x0) {
            push(x0, out);
        } else if f0 * f1 < 0.0 {
            push(bracketed_root(c, x0, x1, f0), out);
        }
    }
    if horner(c, hi).0.abs() <= 8.0 * f64::EPSILON * size(hi) {
        push(hi, out);
    }
    k
}

/// The root of `c` in `[a, b]` where it is monotone with `c(a) = fa` and `c(b)` of opposite signs: Newton's
/// step when it stays inside the bracket and shrinks it by half at least, bisection otherwise.
fn bracketed_root(c: &[f64], mut a: f64, mut b: f64, fa: f64) -> f64 {
    let mut x = 0.5 * (a + b);
    for _ in 0..100 {
        let (f, df) = horner(c, x);
        if f == 0.0 {
            return x;
        }
        if (f < 0.0) == (fa < 0.0) {
            a = x;
        } else {
            b = x;
        }
        let newton = x - f / df;
        let next = if newton > a && newton < b && (newton - x).abs() < 0.25 * (b - a) { newton } else { 0.5 * (a + b) };
        if (next - x).abs() <= 2.0 * f64::EPSILON * x.abs().max(1e-300) || b - a <= 4.0 * f64::EPSILON {
            return next;
        }
        x = next;
    }
    x
}

/// How far `p` is from the law, scale-free, in `[0, 1]`: the natural-map residual of De Saxcé's bipotential
/// form, `|P − proj_K(P − ρ Ũ)| / (|P| + ρ |U − c e_N|)` with `K` the Coulomb cone and De Saxcé's modified
/// velocity `Ũ = (U_N − c + μ |U_T|, U_T)` (the law is exactly `K ∋ P ⊥ Ũ ∈ K*`, which the residual tests for
/// any `ρ > 0`), `ρ = 3 / tr W` (kg). When `U_free_N ≥ s_open` the law is `P = 0`: `|P| / (|P| + ρ |U − c e_N|)`.
/// 0 when numerator and denominator vanish; infinite for non-finite data.
pub fn residual(w: &Delassus3, u_free: [f64; 3], s_open: f64, c_closed: f64, mu: f64, p: [f64; 3]) -> f64 {
    let (n, d) = natural_map(w, u_free, s_open, c_closed, mu, p);
    if !(n.is_finite() && d.is_finite()) {
        f64::INFINITY
    } else if n == 0.0 {
        0.0
    } else {
        n / d
    }
}

/// The numerator and the denominator of [`residual`] (N·s).
fn natural_map(w: &Delassus3, u_free: [f64; 3], s_open: f64, c_closed: f64, mu: f64, p: [f64; 3]) -> (f64, f64) {
    let trace = w.m[0][0] + w.m[1][1] + w.m[2][2];
    let rho = if trace > 0.0 { 3.0 / trace } else { 1.0 };
    let wp = w.apply(p);
    let u: [f64; 3] = std::array::from_fn(|i| u_free[i] + wp[i]);
    let du = [u[0] - c_closed, u[1], u[2]];
    let den = norm3(p) + rho * norm3(du);
    if u_free[0] >= s_open {
        return (norm3(p), den);
    }
    let mu = mu.max(0.0);
    let un = du[0] + mu * len2(u[1], u[2]);
    let q = project_cone([p[0] - rho * un, p[1] - rho * du[1], p[2] - rho * du[2]], mu);
    (norm3([p[0] - q[0], p[1] - q[1], p[2] - q[2]]), den)
}

#[inline(always)]
fn norm3(v: [f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

/// `|(x, y)|` without `hypot`'s care for overflow (several times slower; the values here are far from it).
#[inline(always)]
fn len2(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}

/// The Euclidean projection of `p` on the Coulomb cone `{|P_T| ≤ μ P_N}` (closed form): `p` inside, 0 in the
/// polar cone (`μ |P_T| ≤ −P_N`), else the nearest point of the cone's boundary ray through `P_T`.
/// `μ ≤ 0` projects on the half-line `P_N ≥ 0, P_T = 0`.
#[inline]
pub fn project_cone(p: [f64; 3], mu: f64) -> [f64; 3] {
    let s = len2(p[1], p[2]);
    if mu <= 0.0 {
        return [p[0].max(0.0), 0.0, 0.0];
    }
    if s <= mu * p[0] {
        return p;
    }
    if mu * s <= -p[0] {
        return [0.0; 3];
    }
    let pn = (p[0] + mu * s) / (1.0 + mu * mu);
    let scale = mu * pn / s;
    [pn, p[1] * scale, p[2] * scale]
}

/// The projection on the Tresca set `{P_N ≥ 0, |P_T| ≤ bound}` (a half-line times a disc; a negative bound is
/// read as 0), for the accelerated projected gradient's fixed bound `μ P_N` of the outer iterate.
#[inline]
pub fn project_disc(p: [f64; 3], bound: f64) -> [f64; 3] {
    let bound = bound.max(0.0);
    let s = len2(p[1], p[2]);
    let scale = if s > bound { bound / s } else { 1.0 };
    [p[0].max(0.0), p[1] * scale, p[2] * scale]
}
