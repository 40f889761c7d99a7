//! A prototype of the method `docs/finisher-design.md` §14 left untried (issue 31): an
//! **interior-point method that decides the contacts' states globally**, on the 2D
//! problem written as a linear complementarity problem (Stewart & Trinkle 1996: the 2D
//! Coulomb cone has two edges, and a sliding speed `β` makes every condition linear).
//!
//! `cargo run --release --features faer --example ipm_prototype -- SCENE STEPS EVERY [TOL]`
//!
//! The library's solver `[nscd] solver = "interior_point"` (`src/nscd/interior/`) is
//! this method's default variant (Mehrotra, the neighbourhood, the re-centring) with NLGS
//! sweeps before and after it; this prototype keeps the variants measured beside it.
//!
//! The scene runs with its own settings (one thread); every `EVERY` steps up to `STEPS`
//! a copy makes the step with the scene's solver (warm-started: the time to beat) and
//! another with NLGS `quad` TOL (default 1e-6, cap 20 000, warm; the reference of the
//! velocities); the interior-point method solves the very same problem
//! (`System::nlgs_problem`, cold) to the `quad` check value TOL. One CSV row per problem
//! on standard output, totals on standard error.
//!
//! **The complementarity problem.** Per contact, with `y_N = U_N − c`, `y_T = U_T + e_t U_T⁻`
//! (the law of `coulomb.rs`), unknowns `z = (P_N, f₊, f₋, β)` (the impulse `P_T = f₊ − f₋`,
//! `β` a sliding speed) and their complements
//! `w = (y_N, β + y_T, β − y_T, μ P_N − f₊ − f₋) ≥ 0`, `z ≥ 0`, `w ∘ z = 0`, with
//! `M (v − v_free) = Σ (g_N P_N + g_T P_T) + Σ_springs g P_s(v)`. Sliding (`y_T ≠ 0`) forces
//! `β = |y_T|`, the edge opposite the slip saturated (`μ P_N = f₋` when `y_T > 0`); sticking
//! leaves `|P_T| ≤ μ P_N`. This is law (11) exactly. (μ = 0: `P_N` and `y_N` alone.) The
//! springs of law (17) stay inside the momentum balance, `P_s = h α − h β U` (clamped at 0 when
//! compression-only: their generalised Jacobian is used).
//!
//! **The method.** Mehrotra's predictor–corrector primal–dual interior point (infeasible
//! start at `v_free`). Every condition is linear except the products `w ∘ z`, so the Newton
//! step is exact. Eliminating `w` and `z` contact by contact (a 4 × 4 system solved in closed
//! form) leaves `(M + Σ h β g gᵀ + Σ_k [g_N g_T] S_k [g_N g_T]ᵀ) Δv = r` with a
//! lower-triangular 2 × 2 `S_k`: its off-diagonal term is the non-associated Coulomb
//! coupling (Coulomb's law is no optimisation problem), so the matrix is not symmetric and is
//! factorised by faer's supernodal sparse LU on the pattern of `examples/common/jacobian.rs`
//! (one symbolic analysis per problem; the predictor and the corrector share the
//! factorisation). No contact's state is chosen before the end: every pair keeps a positive
//! slack and multiplier, and the barrier decides. The steps keep the pairs in the wide
//! neighbourhood `w_i z_i ≥ γ μ` (`GAMMA`, 1e-3); after 3 steps shorter than 0.1 in a row
//! (`BLOCKED=0.1,3`) the pairs are re-centred at the current velocities (`RESTART=0.1`).
//! The LCP's matrix is not monotone (`μ P_N` enters `w_β` with no counterpart, and the
//! Delassus operator is singular in a hyperstatic packing), so nothing guarantees
//! convergence (neither Lemke's method nor an interior point is guaranteed). The step is
//! judged by the library's check pass on the consistent pair `(u_free + M⁻¹ Σ H P, P)`,
//! the `quad` value NLGS stops on; an impulse whose velocity effect `P_N W_NN` is below its
//! slack is dropped first (an open contact). `PATH_FOLLOW=1` replaces Mehrotra by a barrier
//! continuation with an Armijo line search on the scaled residual; `GMRES=1` solves the
//! Newton systems by GMRES preconditioned with the Cholesky factor of the symmetric part
//! (`examples/common/gmres.rs`); `TRACE=1` prints every iteration; `ONLY=step` solves one.
//!
//! **What it measured** (2026-12-05, idle, one thread; BENCHMARKS.md "An interior point on
//! the Stewart–Trinkle LCP"). The loaded 536 pile (`loaded536_4.toml`, 20 problems, every
//! 50th step of 4 cycles, 1 183–1 321 rows): `quad` 1e-4 / 1e-5 / 1e-6 reached on 19 / 17 /
//! 16 of 20 problems in a median 29 / 32 / 34.5 iterations, 1.99 / 2.66 / 3.02 s, against
//! NLGS `quad` at the same tolerances from the trajectory's warm start, 0.86 / 4.67 / 8.33 s
//! (17 035 sweeps a problem at 1e-6, 12 of 20 at the 20 000 cap), and 0.33 s for the default
//! `energy` 1.66e-5. A problem either converges (1e-4 → 1e-6 in about 5 more iterations) or
//! stalls at 1e-5–2e-4. An iteration costs 2.1 ms, 1.6 ms of it the supernodal LU (faer's own
//! choice on step 200, simplicial: 4.5 ms; the Cholesky factor of the symmetric part: 0.4 ms, but as a
//! GMRES preconditioner it needs ~50 iterations a solve, 8 ms an iteration: the
//! non-associated term is not small). The reference sample (seed 1, 10 problems): 8 of 10,
//! 2.28 s against 4.94 s for NLGS 1e-6 and 0.12 s for the default. The 50-grain loaded sample
//! with its sublayer springs (20 problems): 20 of 20 in a median 19.5 iterations (one 170),
//! 0.073 s against 0.542 s and 0.014 s.
//!
//! **Variants measured and dropped** (the same problems). De Saxcé's shift `s = μ|y_T|`
//! frozen makes the problem a strictly convex QP in the velocities (Acary, Cadoux,
//! Lemaréchal & Malick 2011), which an interior point solves to a barrier of 1e-13 in 15
//! Cholesky factorisations; but the fixed point on `s` does not contract on the pile (shift
//! changes of 5e-3–1e-2 m/s for 12 outer iterations, the check at 5e-3–1.5e-2); updating `s`
//! at every iteration stalls at 1e-4–1e-3, and linearising a smoothed
//! `s = μ sqrt(y_T² + ε²)` stalls the same way. On the LCP: the Jacobian without the `μ P_N`
//! coupling (Tresca's, symmetric, Cholesky) converges on 0 of 20; a proximal regularisation
//! of the steps that makes them monotone (fixed or adapted Levenberg–Marquardt style) on 0 of
//! 20 (its residual falls 1 % an iteration); barrier continuation with a merit line search
//! (`PATH_FOLLOW`) 6 of 20; a fixed centring σ = 0.3 6 of 20; starting from 300 NLGS sweeps
//! with the pairs floored at a hundredth of their scales 0 of 20 (far from centred);
//! resetting slacks to their complements 9. A warm start shifted by the whole scales
//! (`WARM=1`, after `ENTRY` = 50 / 300 NLGS sweeps) converges on the same 16 of 20 in a
//! median 27 / 24 iterations instead of 34.5 (the sweeps cost about 0.6 / 3.5 iterations),
//! and so does NLGS finishing a stalled run from its iterate: 3 of 5 in 2 400–12 300 sweeps.

#![allow(clippy::needless_range_loop)] // per-component loops over [x, y, θ] read as the equations

#[path = "common/gmres.rs"]
mod gmres;
#[path = "common/jacobian.rs"]
mod jacobian;

use ballast::nscd::contact::ContactRow;
use ballast::nscd::criterion::{evaluate, Policy};
use ballast::nscd::nlgs::{check, solve_nlgs, NlgsProblem, NlgsSettings};
use ballast::nscd::sublayer::SpringRow;
use ballast::nscd::Measure;
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use gmres::{gmres, Op};
use jacobian::{add_force, free_velocity, gather, local, rebuild, Jacobian, LuJacobian};
use std::time::Instant;

/// What one solve did.
#[derive(Debug, Clone, Copy, Default)]
struct Report {
    iterations: usize,
    factorizations: usize,
    restarts: usize,
    /// GMRES iterations (with `GMRES=1`).
    krylov: usize,
    check: f64,
    converged: bool,
    t_assemble: f64,
    t_factor: f64,
    t_solve: f64,
    t_check: f64,
}

/// Per contact: the pairs' values `[N, +, −, β]` of one quantity.
type Quad = [f64; 4];

/// The options (environment variables of the example).
#[derive(Debug, Clone, Copy)]
struct Options {
    /// `PATH=1`: barrier continuation with a merit line search instead of Mehrotra.
    path: bool,
    /// `GAMMA`: the wide neighbourhood `w_i z_i ≥ γ μ` the steps keep (default 1e-3).
    gamma: f64,
    /// `RESTART=f`: after blocked steps (`BLOCKED`), the pairs re-centred at the
    /// current velocities (`w = max(complement, f v_s)`, `z = max(z, f ρ)`); default 0.1, 0: never.
    restart: f64,
    /// `BLOCKED=α,n`: a restart after `n` steps shorter than `α` in a row (default 0.1,3).
    blocked_step: f64,
    blocked_count: usize,
    /// `WARM=f` (with `ENTRY=n` NLGS sweeps first): start from NLGS's iterate, every pair
    /// shifted by `f` × its scales; 0: the cold start at `v_free` (default).
    warm: f64,
    /// `TRACE=1`: one line per iteration on standard error.
    trace: bool,
}

impl Options {
    fn from_env() -> Self {
        let var = |k: &str, d: f64| std::env::var(k).ok().and_then(|v| v.parse().ok()).unwrap_or(d);
        let blocked = std::env::var("BLOCKED")
            .ok()
            .and_then(|v| {
                let (a, n) = v.split_once(',')?;
                Some((a.parse().ok()?, n.parse().ok()?))
            })
            .unwrap_or((0.1, 3));
        Self {
            path: std::env::var("PATH_FOLLOW").is_ok(),
            gamma: var("GAMMA", 1e-3),
            restart: var("RESTART", 0.1),
            blocked_step: blocked.0,
            blocked_count: blocked.1,
            warm: var("WARM", 0.0),
            trace: std::env::var("TRACE").is_ok(),
        }
    }
}

/// The velocity scale `|g| h` of the start (m/s) for the loaded piles' `h` = 2e-4 s.
const VS: f64 = 9.81 * 2e-4;

#[derive(Default)]
struct Ipm {
    /// Numbering of the unknowns (shared with the LU matrix).
    jac: Jacobian,
    lu: LuJacobian,
    u_free: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    /// The contacts with a mobile component along `n` (the others keep `P = 0`).
    active: Vec<u32>,
    /// Per active contact: the normal threshold `c`.
    thr: Vec<f64>,
    /// Per active contact: slacks `w`, multipliers `z`, primal residual, step of each.
    w: Vec<Quad>,
    z: Vec<Quad>,
    rp: Vec<Quad>,
    dw: Vec<Quad>,
    dz: Vec<Quad>,
    /// Body-form buffers: the dual residual, a right-hand side, a velocity step.
    fd: Vec<[f64; 3]>,
    fb: Vec<[f64; 3]>,
    dv: Vec<[f64; 3]>,
    x: Vec<f64>,
    /// Pairs in use: 4 per frictional contact, 1 per frictionless one.
    pairs: usize,
    /// Per active contact: `S_NN`, `S_TT`, `S_TN` of the last assembly.
    s_loc: Vec<[f64; 3]>,
    /// `GMRES=1`: the Newton systems solved by GMRES preconditioned with the Cholesky
    /// factor of `K` without its non-associated term, instead of the sparse LU of `K`.
    gmres: bool,
    /// GMRES iterations made.
    krylov: usize,
}

/// The number of pairs a contact of friction `mu` uses.
fn used(mu: f64) -> usize {
    if mu > 0.0 {
        4
    } else {
        1
    }
}

/// `C x = r` for `C = I + D B` of one contact (`D = z/w`; `B` couples `β` into `w±` and
/// `μ P_N − f₊ − f₋` into `w_β`), in closed form; `C` is the identity when frictionless.
#[inline(always)]
fn solve_c(d: &Quad, mu: f64, r: &Quad) -> Quad {
    if mu <= 0.0 {
        return [r[0], 0.0, 0.0, 0.0];
    }
    let x3 = (r[3] - d[3] * mu * r[0] + d[3] * (r[1] + r[2])) / (1.0 + d[3] * (d[1] + d[2]));
    [r[0], r[1] - d[1] * x3, r[2] - d[2] * x3, x3]
}

/// Per-pair scales of the multipliers and slacks of a contact (`ρ = v_s / W_NN`).
fn scales(r: &ContactRow) -> (Quad, Quad) {
    let rho = VS / r.w.nn;
    ([rho, r.mu * rho, r.mu * rho, VS], [VS, VS, VS, r.mu * rho])
}

impl Ipm {
    /// A spring's impulse at `v` and whether its law is active (not clamped).
    fn spring_impulse(s: &SpringRow, v: &[[f64; 3]]) -> (f64, bool) {
        let p = s.h_alpha - s.h_beta * gather(v, s.a, s.b, &s.hn_a, &s.hn_b);
        if s.compression_only && p <= 0.0 {
            (0.0, false)
        } else {
            (p, true)
        }
    }

    fn prepare(&mut self, p: &NlgsProblem) -> bool {
        if !self.jac.prepare(&p.inv_m, &p.rows, &p.springs) || !self.lu.prepare(&p.inv_m, &p.rows, &p.springs) {
            return false;
        }
        self.u_free = free_velocity(&p.u, &p.inv_m, &p.rows, &p.springs);
        self.v = self.u_free.clone();
        let nb = p.u.len();
        self.fd = vec![[0.0; 3]; nb];
        self.fb = vec![[0.0; 3]; nb];
        self.dv = vec![[0.0; 3]; nb];
        self.x = vec![0.0; self.jac.len()];
        self.active = (0..p.rows.len() as u32).filter(|&k| p.rows[k as usize].w.nn > 0.0).collect();
        // The normal threshold: `c_closed` where the law is monotone (no restitution),
        // else the branch the free velocity takes (as the other prototypes label it).
        self.thr = self
            .active
            .iter()
            .map(|&k| {
                let r = &p.rows[k as usize];
                if r.s_open == r.c_closed || gather(&self.u_free, r.a, r.b, &r.hn_a, &r.hn_b) < r.s_open {
                    r.c_closed
                } else {
                    r.s_open
                }
            })
            .collect();
        let n = self.active.len();
        for buf in [&mut self.w, &mut self.z, &mut self.rp, &mut self.dw, &mut self.dz] {
            buf.clear();
            buf.resize(n, [0.0; 4]);
        }
        self.pairs = self.active.iter().map(|&k| used(p.rows[k as usize].mu)).sum();
        true
    }

    /// `(y_N, y_T)` of active contact `j` at `v`.
    fn y(&self, j: usize, r: &ContactRow, v: &[[f64; 3]]) -> [f64; 2] {
        [gather(v, r.a, r.b, &r.hn_a, &r.hn_b) - self.thr[j], gather(v, r.a, r.b, &r.ht_a, &r.ht_b) + r.shift_t]
    }

    /// The complements' values `(y_N, β + y_T, β − y_T, μ P_N − f₊ − f₋)` at `(v, z)`.
    fn complements(y: [f64; 2], z: &Quad, mu: f64) -> Quad {
        [y[0], z[3] + y[1], z[3] - y[1], mu * z[0] - z[1] - z[2]]
    }

    /// The start at `v = v_free`: multipliers at their scales (friction a quarter of the
    /// cone each side), slacks the complements raised to their scales.
    fn start(&mut self, p: &NlgsProblem, warm: f64) {
        if warm > 0.0 {
            // From the iterate in `p` (NLGS's `(u, P)`): every multiplier and slack shifted
            // by `warm` × its scale.
            self.v.copy_from_slice(&p.u);
            for (j, &k) in self.active.iter().enumerate() {
                let r = &p.rows[k as usize];
                let (zs, ws) = scales(r);
                let y = self.y(j, r, &self.v);
                let z = [r.p[0], r.p[1].max(0.0), (-r.p[1]).max(0.0), y[1].abs()];
                let c = Self::complements(y, &z, r.mu);
                for i in 0..used(r.mu) {
                    self.z[j][i] = z[i].max(0.0) + warm * zs[i];
                    self.w[j][i] = c[i].max(0.0) + warm * ws[i];
                }
            }
            return;
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (zs, ws) = scales(r);
            self.z[j] = if r.mu > 0.0 { [zs[0], 0.25 * zs[1], 0.25 * zs[2], zs[3]] } else { [zs[0], 0.0, 0.0, 0.0] };
            let c = Self::complements(self.y(j, r, &self.v), &self.z[j], r.mu);
            for i in 0..used(r.mu) {
                self.w[j][i] = c[i].max(if i == 3 { 0.5 * ws[3] } else { ws[i] });
            }
        }
    }

    /// Re-centres the pairs at the current velocities: `w = max(complement, f × scale)`,
    /// `z = max(z, f × scale)`.
    fn recentre(&mut self, p: &NlgsProblem, f: f64) {
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (zs, ws) = scales(r);
            let c = Self::complements(self.y(j, r, &self.v), &self.z[j], r.mu);
            for i in 0..used(r.mu) {
                self.z[j][i] = self.z[j][i].max(f * zs[i]);
                self.w[j][i] = c[i].max(f * ws[i]);
            }
        }
    }

    /// The barrier `μ_c = w·z / pairs`.
    fn barrier(&self) -> f64 {
        let s: f64 = self.w.iter().zip(&self.z).map(|(w, z)| (0..4).map(|i| w[i] * z[i]).sum::<f64>()).sum();
        s / self.pairs as f64
    }

    /// The primal residual `rp = w(v, z) − w` into `rp`, and the dual residual
    /// `F = M (v − v_free) − Σ g P_s(v) − Σ (g_N P_N + g_T P_T)` (body form) into `fd`.
    fn residuals(&mut self, p: &NlgsProblem) {
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let c = Self::complements(self.y(j, r, &self.v), &self.z[j], r.mu);
            for i in 0..4 {
                self.rp[j][i] = if i < used(r.mu) { c[i] - self.w[j][i] } else { 0.0 };
            }
        }
        for i in 0..self.v.len() {
            for d in 0..3 {
                let im = p.inv_m[i][d];
                self.fd[i][d] = if im > 0.0 { (self.v[i][d] - self.u_free[i][d]) / im } else { 0.0 };
            }
        }
        for s in &p.springs {
            let (ps, _) = Self::spring_impulse(s, &self.v);
            add_force(&mut self.fd, s.a, s.b, &s.hn_a, &s.hn_b, -ps);
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let z = &self.z[j];
            add_force(&mut self.fd, r.a, r.b, &r.hn_a, &r.hn_b, -z[0]);
            add_force(&mut self.fd, r.a, r.b, &r.ht_a, &r.ht_b, -(z[1] - z[2]));
        }
    }

    /// The scaled squared norm of the system perturbed by the barrier `kappa`: the dual
    /// residual per unknown over `m v_s`, the primal one per pair over its slack's scale,
    /// `w z − κ` over the product of the scales (after [`Ipm::residuals`]).
    fn merit(&self, p: &NlgsProblem, kappa: f64) -> f64 {
        let mut s = 0.0;
        for (f, im) in self.fd.iter().zip(&p.inv_m) {
            for d in 0..3 {
                if im[d] > 0.0 {
                    let x = f[d] * im[d] / VS;
                    s += x * x;
                }
            }
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (zs, ws) = scales(r);
            for i in 0..used(r.mu) {
                let a = self.rp[j][i] / ws[i];
                let b = (self.w[j][i] * self.z[j][i] - kappa) / (ws[i] * zs[i]);
                s += a * a + b * b;
            }
        }
        s
    }

    /// `K = M + Σ_active h β g gᵀ + Σ_k G S_k Gᵀ`, `S_k = Tᵀ C⁻¹ D T`, into the LU matrix.
    fn assemble(&mut self, p: &NlgsProblem) {
        self.s_loc.resize(self.active.len(), [0.0; 3]);
        if self.gmres {
            self.jac.reset();
        } else {
            self.lu.reset();
        }
        for (k, s) in p.springs.iter().enumerate() {
            if Self::spring_impulse(s, &self.v).1 {
                if self.gmres {
                    self.jac.add_spring(k, s, s.h_beta);
                } else {
                    self.lu.add_spring(k, &local(&s.hn_a, &s.hn_b), s.h_beta);
                }
            }
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (w, z) = (&self.w[j], &self.z[j]);
            let d: Quad = std::array::from_fn(|i| if i < used(r.mu) { z[i] / w[i] } else { 0.0 });
            let (gn, gt) = (local(&r.hn_a, &r.hn_b), local(&r.ht_a, &r.ht_b));
            // S column by column; lower triangular (S_NT = 0), S_TN the non-associated term.
            let c0 = solve_c(&d, r.mu, &[d[0], 0.0, 0.0, 0.0]);
            let c1 = solve_c(&d, r.mu, &[0.0, d[1], -d[2], 0.0]);
            let sl = if r.mu > 0.0 { [c0[0], c1[1] - c1[2], c0[1] - c0[2]] } else { [c0[0], 0.0, 0.0] };
            self.s_loc[j] = sl;
            if self.gmres {
                self.jac.add_contact(k as usize, r, sl[0], sl[1]);
                continue;
            }
            self.lu.add_contact(k as usize, &gn, &gn, sl[0]);
            if r.mu > 0.0 {
                self.lu.add_contact(k as usize, &gt, &gt, sl[1]);
                self.lu.add_contact(k as usize, &gt, &gn, sl[2]);
            }
        }
    }

    /// `y = K x` (dof form) with the last assembly's `S`.
    fn apply_k(&mut self, p: &NlgsProblem, x: &[f64], y: &mut [f64]) {
        self.jac.scatter_dofs(x, &mut self.dv);
        for i in 0..self.fb.len() {
            for d in 0..3 {
                let im = p.inv_m[i][d];
                self.fb[i][d] = if im > 0.0 { self.dv[i][d] / im } else { 0.0 };
            }
        }
        for s in &p.springs {
            if Self::spring_impulse(s, &self.v).1 {
                let u = gather(&self.dv, s.a, s.b, &s.hn_a, &s.hn_b);
                add_force(&mut self.fb, s.a, s.b, &s.hn_a, &s.hn_b, s.h_beta * u);
            }
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let sl = self.s_loc[j];
            let un = gather(&self.dv, r.a, r.b, &r.hn_a, &r.hn_b);
            let ut = gather(&self.dv, r.a, r.b, &r.ht_a, &r.ht_b);
            add_force(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, sl[0] * un);
            add_force(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, sl[1] * ut + sl[2] * un);
        }
        self.jac.gather_dofs(&self.fb, y);
    }

    /// `x ← K⁻¹ x`: the LU's solve, or right-preconditioned GMRES (restart 40, relative
    /// residual 1e-10, at most 200 iterations) with the Cholesky factor of `K − N`.
    fn solve_k(&mut self, p: &NlgsProblem, x: &mut [f64]) -> bool {
        if !self.gmres {
            return self.lu.solve(x);
        }
        let b = x.to_vec();
        let mut op = |op: Op, v: &mut [f64], out: &mut [f64]| match op {
            Op::Apply => {
                self.apply_k(p, v, out);
                true
            }
            Op::Precondition => self.jac.solve(v),
        };
        match gmres(&b, x, (1e-10, 40, 200), &mut op) {
            Some(k) => {
                self.krylov += k;
                true
            }
            None => false,
        }
    }

    /// The Newton direction for the complementarity right-hand side `rc`
    /// (`z_i Δw_i + w_i Δz_i = rc_i`), into `dv`, `dw`, `dz`; false if the solve failed.
    fn direction(&mut self, p: &NlgsProblem, rc: &[Quad]) -> bool {
        for i in 0..self.fb.len() {
            self.fb[i] = [-self.fd[i][0], -self.fd[i][1], -self.fd[i][2]];
        }
        // The right-hand side: −F + E C⁻¹ (W⁻¹ rc − D rp).
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (w, z) = (&self.w[j], &self.z[j]);
            let nu = used(r.mu);
            let d: Quad = std::array::from_fn(|i| if i < nu { z[i] / w[i] } else { 0.0 });
            let q: Quad = std::array::from_fn(|i| if i < nu { rc[j][i] / w[i] - d[i] * self.rp[j][i] } else { 0.0 });
            let x = solve_c(&d, r.mu, &q);
            add_force(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, x[0]);
            add_force(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, x[1] - x[2]);
        }
        self.jac.gather_dofs(&self.fb, &mut self.x);
        let mut x = std::mem::take(&mut self.x);
        let ok = self.solve_k(p, &mut x);
        self.x = x;
        if !ok {
            return false;
        }
        self.jac.scatter_dofs(&self.x, &mut self.dv);
        for (j, &k) in self.active.iter().enumerate() {
            let r = &p.rows[k as usize];
            let (w, z) = (&self.w[j], &self.z[j]);
            let nu = used(r.mu);
            let dun = gather(&self.dv, r.a, r.b, &r.hn_a, &r.hn_b);
            let dut = gather(&self.dv, r.a, r.b, &r.ht_a, &r.ht_b);
            let ldv: Quad = [dun, dut, -dut, 0.0];
            let d: Quad = std::array::from_fn(|i| if i < nu { z[i] / w[i] } else { 0.0 });
            let q: Quad =
                std::array::from_fn(|i| if i < nu { rc[j][i] / w[i] - d[i] * (self.rp[j][i] + ldv[i]) } else { 0.0 });
            let dz = solve_c(&d, r.mu, &q);
            // Δw = L Δv + B Δz + rp.
            let bdz = [0.0, dz[3], dz[3], r.mu * dz[0] - dz[1] - dz[2]];
            for i in 0..4 {
                self.dz[j][i] = if i < nu { dz[i] } else { 0.0 };
                self.dw[j][i] = if i < nu { ldv[i] + bdz[i] + self.rp[j][i] } else { 0.0 };
            }
        }
        true
    }

    /// The largest step in (0, 1] keeping `w + α Δw ≥ 0` and `z + α Δz ≥ 0`.
    fn to_boundary(&self) -> f64 {
        let mut a: f64 = 1.0;
        for j in 0..self.w.len() {
            for i in 0..4 {
                if self.dw[j][i] < 0.0 {
                    a = a.min(-self.w[j][i] / self.dw[j][i]);
                }
                if self.dz[j][i] < 0.0 {
                    a = a.min(-self.z[j][i] / self.dz[j][i]);
                }
            }
        }
        a
    }

    /// The smallest pair product over the mean at `α` along the direction.
    fn centrality(&self, p: &NlgsProblem, a: f64) -> f64 {
        let (mut lo, mut sum) = (f64::INFINITY, 0.0);
        for (j, &k) in self.active.iter().enumerate() {
            for i in 0..used(p.rows[k as usize].mu) {
                let x = (self.w[j][i] + a * self.dw[j][i]) * (self.z[j][i] + a * self.dz[j][i]);
                lo = lo.min(x);
                sum += x;
            }
        }
        lo / (sum / self.pairs as f64)
    }

    /// Shortens `a` until every pair keeps `w_i z_i ≥ γ μ` at the new point (γ lowered to
    /// half the current centrality when the iterate is already outside).
    fn neighbourhood(&self, p: &NlgsProblem, mut a: f64, gamma: f64) -> f64 {
        let gamma = gamma.min(0.5 * self.centrality(p, 0.0));
        for _ in 0..30 {
            if self.centrality(p, a) >= gamma {
                break;
            }
            a *= 0.7;
        }
        a
    }

    /// Moves by `a` along the direction.
    fn advance(&mut self, a: f64) {
        for b in 0..self.v.len() {
            for d in 0..3 {
                self.v[b][d] += a * self.dv[b][d];
            }
        }
        for j in 0..self.w.len() {
            for i in 0..4 {
                self.w[j][i] += a * self.dw[j][i];
                self.z[j][i] += a * self.dz[j][i];
            }
        }
    }

    /// The impulses into the rows and springs, and `u` rebuilt from them; an impulse
    /// whose velocity effect `P_N W_NN` is below its slack is dropped (an open contact).
    fn write_back(&self, p: &mut NlgsProblem) {
        for r in p.rows.iter_mut() {
            r.p = [0.0; 2];
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &mut p.rows[k as usize];
            let z = &self.z[j];
            if z[0] * r.w.nn < self.w[j][0] {
                continue;
            }
            r.p = [z[0], if r.mu > 0.0 { z[1] - z[2] } else { 0.0 }];
        }
        for s in p.springs.iter_mut() {
            s.p = Self::spring_impulse(s, &self.v).0;
        }
        rebuild(&mut p.u, &self.u_free, &p.inv_m, &p.rows, &p.springs);
    }

    /// Solves `p` to the `quad` check value `tol`, at most `max_it` iterations.
    fn solve(&mut self, p: &mut NlgsProblem, tol: f64, max_it: usize, o: &Options) -> Report {
        let mut rep = Report { check: f64::INFINITY, ..Report::default() };
        if !self.prepare(p) || self.active.is_empty() {
            return rep;
        }
        self.start(p, o.warm);
        self.krylov = 0;
        let n = self.active.len();
        let mut rc = vec![[0.0; 4]; n];
        let mut aff = (vec![[0.0; 4]; n], vec![[0.0; 4]; n]);
        let mut blocked = 0;
        let mut kappa = self.barrier();
        for it in 0..max_it {
            rep.iterations = it + 1;
            let t0 = Instant::now();
            self.residuals(p);
            let mu = self.barrier();
            rep.t_assemble += t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            self.write_back(p);
            let value =
                evaluate(Policy::Quad, 1.0, 4.0, &check(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs), 0.0).0;
            rep.t_check += t0.elapsed().as_secs_f64();
            rep.check = value;
            rep.krylov = self.krylov;
            if value <= tol {
                rep.converged = true;
                break;
            }
            let t0 = Instant::now();
            self.assemble(p);
            rep.t_assemble += t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let ok = if self.gmres { self.jac.factorize() } else { self.lu.factorize() };
            rep.krylov = self.krylov;
            if !ok {
                return rep;
            }
            rep.factorizations += 1;
            rep.t_factor += t0.elapsed().as_secs_f64();
            let t0 = Instant::now();
            let (a, sigma) = if o.path {
                // Barrier continuation: Newton on the system perturbed by κ, the step
                // shortened until the merit falls (Armijo), κ lowered by how far it went.
                for j in 0..n {
                    for i in 0..4 {
                        rc[j][i] = kappa - self.w[j][i] * self.z[j][i];
                    }
                }
                if !self.direction(p, &rc) {
                    return rep;
                }
                let phi0 = self.merit(p, kappa);
                let mut a = self.neighbourhood(p, (0.99 * self.to_boundary()).min(1.0), o.gamma);
                let saved = (self.v.clone(), self.w.clone(), self.z.clone(), self.rp.clone(), self.fd.clone());
                let mut accepted = false;
                for _ in 0..20 {
                    self.advance(a);
                    self.residuals(p);
                    if self.merit(p, kappa) <= (1.0 - 1e-4 * a) * phi0 {
                        accepted = true;
                        break;
                    }
                    self.v.clone_from(&saved.0);
                    self.w.clone_from(&saved.1);
                    self.z.clone_from(&saved.2);
                    a *= 0.5;
                }
                if !accepted {
                    // Take the shortest step: the restart below takes over if it keeps failing.
                    self.advance(a);
                    a = 0.0;
                }
                self.rp.clone_from(&saved.3);
                self.fd.clone_from(&saved.4);
                let old = kappa;
                kappa *= if a >= 0.9 {
                    0.1
                } else if a >= 0.5 {
                    0.3
                } else {
                    1.0
                };
                (a, kappa / old)
            } else {
                // Mehrotra's predictor–corrector.
                for j in 0..n {
                    for i in 0..4 {
                        rc[j][i] = -self.w[j][i] * self.z[j][i];
                    }
                }
                if !self.direction(p, &rc) {
                    return rep;
                }
                let a = self.to_boundary();
                let mut mu_aff = 0.0;
                for j in 0..n {
                    for i in 0..4 {
                        mu_aff += (self.w[j][i] + a * self.dw[j][i]) * (self.z[j][i] + a * self.dz[j][i]);
                    }
                }
                mu_aff /= self.pairs as f64;
                let sigma = (mu_aff / mu).powi(3).min(1.0);
                aff.0.copy_from_slice(&self.dw);
                aff.1.copy_from_slice(&self.dz);
                for (j, &k) in self.active.iter().enumerate() {
                    for i in 0..used(p.rows[k as usize].mu) {
                        rc[j][i] = -self.w[j][i] * self.z[j][i] - aff.0[j][i] * aff.1[j][i] + sigma * mu;
                    }
                }
                if !self.direction(p, &rc) {
                    return rep;
                }
                let a = self.neighbourhood(p, (0.995 * self.to_boundary()).min(1.0), o.gamma);
                self.advance(a);
                (a, sigma)
            };
            blocked = if a < o.blocked_step { blocked + 1 } else { 0 };
            if o.restart > 0.0 && blocked >= o.blocked_count {
                blocked = 0;
                rep.restarts += 1;
                self.recentre(p, o.restart);
                kappa = self.barrier();
            }
            rep.t_solve += t0.elapsed().as_secs_f64();
            if o.trace {
                let rpn = self.rp.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
                eprintln!("  it {it}: mu {mu:.2e} sigma {sigma:.2e} step {a:.3} |rp| {rpn:.2e} check {value:.2e}");
            }
        }
        rep
    }
}

#[derive(serde::Serialize)]
struct Row {
    step: u64,
    rows: usize,
    default_sweeps: usize,
    default_s: f64,
    nlgs_tol_sweeps: usize,
    nlgs_tol_converged: bool,
    nlgs_tol_s: f64,
    ipm_iterations: usize,
    ipm_factorizations: usize,
    ipm_restarts: usize,
    ipm_krylov: usize,
    ipm_check: f64,
    ipm_converged: bool,
    ipm_s: f64,
    /// NLGS sweeps to TOL from a stalled interior point's iterate (0 when it converged).
    finish_sweeps: usize,
    ipm_assemble_s: f64,
    ipm_factor_s: f64,
    ipm_solve_s: f64,
    ipm_check_s: f64,
    /// Largest difference of a mobile body's translational velocity, IPM against NLGS TOL (m/s).
    max_du_m_s: f64,
    /// θ h × the sleeper's vertical velocity difference, IPM against NLGS TOL (m).
    sleeper_dy_m: f64,
    /// The same for the default against NLGS TOL (m).
    default_sleeper_dy_m: f64,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, rest @ ..] = &args[..] else {
        return Err("usage: ipm_prototype SCENE STEPS EVERY [TOL]".into());
    };
    let (steps, every): (u64, u64) = (steps.parse()?, every.parse()?);
    let tol: f64 = rest.first().map(|t| t.parse()).transpose()?.unwrap_or(1e-6);
    let max_it: usize = std::env::var("MAX_IT").map_or(Ok(200), |v| v.parse())?;
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let sleeper = sys.bodies.info.iter().position(|b| b.name == "sleeper");
    let mobile: Vec<usize> = (0..sys.bodies.len()).filter(|&i| sys.bodies.inv_m[i][..2] != [0.0; 2]).collect();
    let theta_h = sys.params.theta * sys.params.dt;
    let only: Option<u64> = std::env::var("ONLY").ok().and_then(|v| v.parse().ok());
    let options = Options::from_env();
    let entry: usize = std::env::var("ENTRY").map_or(Ok(0), |v| v.parse())?;
    let mut ipm = Ipm { gmres: std::env::var("GMRES").is_ok(), ..Ipm::default() };
    let mut out = csv::Writer::from_writer(std::io::stdout());
    let (mut t_def, mut t_tol, mut t_ipm, mut n_conv, mut n) = (0.0, 0.0, 0.0, 0, 0);
    for k in 1..=steps {
        if k % every == 0 && only.is_none_or(|o| o == k) {
            let mut d = sys.clone();
            let t0 = Instant::now();
            let sd = d.step()?;
            let default_s = t0.elapsed().as_secs_f64();
            let mut r = sys.clone();
            {
                let s = &mut r.params.nlgs;
                (s.policy, s.tolerance, s.measure, s.max_iterations) = (Policy::Quad, tol, Measure::Check, 20_000);
            }
            let t0 = Instant::now();
            let sr = r.step()?;
            let nlgs_tol_s = t0.elapsed().as_secs_f64();
            let mut prob = d.nlgs_problem();
            let t0 = Instant::now();
            let entry_settings = NlgsSettings {
                policy: Policy::Quad,
                tolerance: tol,
                measure: Measure::Check,
                max_iterations: entry,
                split_min_rows: 0,
                ..r.params.nlgs
            };
            if entry > 0 {
                solve_nlgs(&entry_settings, &mut prob.u, &prob.inv_m, &mut prob.rows, &mut prob.springs);
            }
            let rep = ipm.solve(&mut prob, tol, max_it, &options);
            // A problem the interior point left above TOL is finished by NLGS from its iterate
            // (the consistent pair `write_back` left in `prob`): the sweeps it takes.
            let finish_sweeps = if rep.converged {
                0
            } else {
                let s = NlgsSettings {
                    policy: Policy::Quad,
                    tolerance: tol,
                    measure: Measure::Check,
                    max_iterations: 20_000,
                    split_min_rows: 0,
                    ..r.params.nlgs
                };
                solve_nlgs(&s, &mut prob.u, &prob.inv_m, &mut prob.rows, &mut prob.springs).iterations
            };
            let ipm_s = t0.elapsed().as_secs_f64();
            let refu = &r.bodies.u;
            let max_du = mobile
                .iter()
                .map(|&b| (prob.u[b][0] - refu[b][0]).hypot(prob.u[b][1] - refu[b][1]))
                .fold(0.0, f64::max);
            let dy = |u: &[[f64; 3]]| sleeper.map_or(f64::NAN, |s| theta_h * (u[s][1] - refu[s][1]));
            t_def += default_s;
            t_tol += nlgs_tol_s;
            t_ipm += ipm_s;
            n += 1;
            n_conv += usize::from(rep.converged);
            out.serialize(Row {
                step: k,
                rows: prob.rows.len(),
                default_sweeps: sd.iterations,
                default_s,
                nlgs_tol_sweeps: sr.iterations,
                nlgs_tol_converged: sr.converged,
                nlgs_tol_s,
                ipm_iterations: rep.iterations,
                ipm_factorizations: rep.factorizations,
                ipm_restarts: rep.restarts,
                ipm_krylov: rep.krylov,
                ipm_check: rep.check,
                ipm_converged: rep.converged,
                ipm_s,
                finish_sweeps,
                ipm_assemble_s: rep.t_assemble,
                ipm_factor_s: rep.t_factor,
                ipm_solve_s: rep.t_solve,
                ipm_check_s: rep.t_check,
                max_du_m_s: max_du,
                sleeper_dy_m: dy(&prob.u),
                default_sleeper_dy_m: dy(&d.bodies.u),
            })?;
            out.flush()?;
        }
        sys.step()?;
    }
    eprintln!(
        "{n} problems: default {t_def:.3} s; NLGS quad {tol:e} {t_tol:.3} s; interior point {t_ipm:.3} s \
         ({n_conv} reached {tol:e}; {:.2}x the default's time)",
        t_ipm / t_def.max(1e-12)
    );
    Ok(())
}
