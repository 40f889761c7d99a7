//! An interior-point solver for the per-step problem (`[nscd] solver =
//! "interior_point"`, feature `faer`): a converged contact solve at a fraction of
//! NLGS's cost at tight tolerances (issue 31; measurements and the variants
//! dropped: `docs/finisher-design.md` §15, BENCHMARKS.md).
//!
//! **The problem as a linear complementarity problem.** Saussine et al.'s law (11)
//! is piecewise linear in 2D: the Coulomb cone has two edges, and with a sliding
//! speed `β` every condition is linear (Stewart & Trinkle 1996). Per contact, with
//! `y_N = U_N − c` and `y_T = U_T + e_t U_T⁻` (the law of [`super::coulomb`]), the
//! unknowns `z = (P_N, f₊, f₋, β)` (the tangential impulse `P_T = f₊ − f₋`) and
//! their complements `w = (y_N, β + y_T, β − y_T, μ P_N − f₊ − f₋)` satisfy
//! `w ≥ 0, z ≥ 0, w ∘ z = 0`, and the bodies' momentum balance
//! `M (v − v_free) = Σ (g_N P_N + g_T P_T) + Σ_springs g P_s(v)` closes the
//! system. Sliding (`y_T ≠ 0`) forces `β = |y_T|` and saturates the edge opposite
//! the slip; sticking leaves `|P_T| ≤ μ P_N`: this is law (11) exactly. A
//! frictionless contact keeps `(P_N, y_N)` alone. The sublayer springs of law (17)
//! stay in the momentum balance with their affine impulse `P_s = hα − hβ U`
//! (clamped at zero when compression-only; its generalised Jacobian is used).
//!
//! **The method.** Mehrotra's predictor–corrector primal–dual interior point. Every
//! condition is linear but the products `w ∘ z`, so the Newton step is exact;
//! eliminating `w` and `z` contact by contact (a 4 × 4 system in closed form)
//! leaves `K Δv = r` with `K = M + Σ hβ g gᵀ + Σ_k [g_N g_T] S_k [g_N g_T]ᵀ`,
//! `S_k` lower triangular: its off-diagonal term is the non-associated friction
//! coupling, so `K` is not symmetric and is factorised by faer's sparse LU (`lu.rs`).
//! No contact's state is chosen before the end: every pair keeps a positive slack
//! and multiplier, and the barrier decides, where NLGS searches the stick/slip
//! states contact by contact (its stall at tight tolerances). The steps keep the
//! pairs in the wide neighbourhood `w_i z_i ≥ γ μ` (γ = 1e-3, lowered to half the
//! iterate's own centrality when it is outside), and after 3 steps shorter than 0.1
//! in a row the pairs are re-centred at the current velocities.
//!
//! **The sequence of a step** ([`InteriorOptions`]). NLGS first, with the step's
//! stopping rule, for at most 50 sweeps (a quiet step ends there); then the
//! interior point, started from NLGS's iterate with every pair shifted by its
//! scales, for at most 100 iterations; if it has not met the tolerance (the LCP is not
//! monotone: `μ P_N` enters `w_β` alone and the Delassus operator is singular in a
//! hyperstatic packing, so nothing guarantees convergence, and on the loaded
//! 536-pentagon pile 4 problems of 20 stall at 1e-5–2e-4), NLGS goes on from the
//! interior point's iterate up to the step's sweep cap. Convergence is judged as in
//! NLGS with `measure = "check"`: on the consistent pair `(u_free + M⁻¹ Σ H P, P)`
//! by [`super::nlgs::check`] and the step's policy; an impulse whose velocity
//! effect `P_N W_NN` is below its slack is dropped first (an open contact). The
//! report's `iterations` count NLGS sweeps and interior-point iterations, one each
//! (an iteration costs about 85 sweeps on the loaded pile).
//!
//! One thread; the numbers do not depend on the thread count.

#![allow(clippy::needless_range_loop)] // per-component loops over [x, y, θ] and the pairs read as the equations

pub mod lu;

use super::contact::{dot3, ContactRow};
use super::criterion::evaluate;
use super::nlgs::{apply_impulses, check, remove_impulses, solve_nlgs, NlgsReport, NlgsSettings};
use super::sublayer::SpringRow;
use lu::{local, NewtonMatrix};

/// Options of the interior-point solver ([`InteriorOptions::default`] is what a
/// scene's `solver = "interior_point"` uses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct InteriorOptions {
    /// NLGS sweeps made first, with the step's stopping rule (the step ends there
    /// if they meet it); default 50.
    pub nlgs_first: usize,
    /// Interior-point iterations at most before NLGS takes over; default 100.
    pub max_iterations: usize,
    /// NLGS goes on from the interior point's iterate when it has not met the
    /// tolerance, up to the step's sweep cap; default true.
    pub nlgs_after: bool,
}

impl Default for InteriorOptions {
    fn default() -> Self {
        Self { nlgs_first: 50, max_iterations: 100, nlgs_after: true }
    }
}
/// The wide neighbourhood's `γ`.
const GAMMA: f64 = 1e-3;
/// Steps shorter than this, [`BLOCKED_COUNT`] in a row, re-centre the pairs.
const BLOCKED_STEP: f64 = 0.1;
const BLOCKED_COUNT: usize = 3;
/// The re-centring floors every pair at this fraction of its scales.
const RECENTRE: f64 = 0.1;

/// Per contact: the pairs' values `[N, +, −, β]` of one quantity.
type Quad = [f64; 4];

/// Buffers of the interior-point solver, reused across steps (a clone starts with
/// empty buffers: they hold nothing between steps).
#[derive(Debug, Default)]
pub struct InteriorWorkspace {
    k: NewtonMatrix,
    u_free: Vec<[f64; 3]>,
    v: Vec<[f64; 3]>,
    /// The contacts with a mobile component along `n` (the others keep `P = 0`).
    active: Vec<u32>,
    /// Per active contact: the normal threshold `c`, the scales of `z` and `w`.
    thr: Vec<f64>,
    zs: Vec<Quad>,
    ws: Vec<Quad>,
    /// Per active contact: slacks, multipliers, primal residual, the steps.
    w: Vec<Quad>,
    z: Vec<Quad>,
    rp: Vec<Quad>,
    dw: Vec<Quad>,
    dz: Vec<Quad>,
    rc: Vec<Quad>,
    aff: Vec<[Quad; 2]>,
    /// Body-form buffers: the dual residual, a right-hand side, a velocity step.
    fd: Vec<[f64; 3]>,
    fb: Vec<[f64; 3]>,
    dv: Vec<[f64; 3]>,
    x: Vec<f64>,
    /// Pairs in use: 4 per frictional contact, 1 per frictionless one.
    pairs: usize,
}

impl Clone for InteriorWorkspace {
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// The number of pairs a contact of friction `mu` uses.
#[inline(always)]
fn used(mu: f64) -> usize {
    if mu > 0.0 {
        4
    } else {
        1
    }
}

/// The relative velocity of a row, `h_a · v_a − h_b · v_b`.
#[inline(always)]
fn gather(v: &[[f64; 3]], a: u32, b: u32, ha: &[f64; 3], hb: &[f64; 3]) -> f64 {
    let mut x = dot3(ha, &v[a as usize]);
    if b != u32::MAX {
        x -= dot3(hb, &v[b as usize]);
    }
    x
}

/// Adds the generalised force of `p` along a row (`h_a p` on `a`, `−h_b p` on `b`).
#[inline(always)]
fn add(out: &mut [[f64; 3]], a: u32, b: u32, ha: &[f64; 3], hb: &[f64; 3], p: f64) {
    for d in 0..3 {
        out[a as usize][d] += ha[d] * p;
    }
    if b != u32::MAX {
        for d in 0..3 {
            out[b as usize][d] -= hb[d] * p;
        }
    }
}

/// A spring's impulse at `v` and whether its law is active (not clamped).
#[inline(always)]
fn spring_impulse(s: &SpringRow, v: &[[f64; 3]]) -> (f64, bool) {
    let p = s.h_alpha - s.h_beta * gather(v, s.a, s.b, &s.hn_a, &s.hn_b);
    if s.compression_only && p <= 0.0 {
        (0.0, false)
    } else {
        (p, true)
    }
}

/// The complements `(y_N, β + y_T, β − y_T, μ P_N − f₊ − f₋)` at `(y, z)`.
#[inline(always)]
fn complements(y: [f64; 2], z: &Quad, mu: f64) -> Quad {
    [y[0], z[3] + y[1], z[3] - y[1], mu * z[0] - z[1] - z[2]]
}

/// `C x = r` for `C = I + D B` of one contact (`D = z/w`; `B` couples `β` into `w±`
/// and `μ P_N − f₊ − f₋` into `w_β`), in closed form; the identity when frictionless.
#[inline(always)]
fn solve_c(d: &Quad, mu: f64, r: &Quad) -> Quad {
    if mu <= 0.0 {
        return [r[0], 0.0, 0.0, 0.0];
    }
    let x3 = (r[3] - d[3] * mu * r[0] + d[3] * (r[1] + r[2])) / (1.0 + d[3] * (d[1] + d[2]));
    [r[0], r[1] - d[1] * x3, r[2] - d[2] * x3, x3]
}

impl InteriorWorkspace {
    /// Numbering, pattern, free velocities and scales of a step's problem; `u` and the
    /// rows' impulses are a consistent pair. False if there is nothing to solve or the
    /// symbolic analysis failed.
    fn prepare(&mut self, u: &[[f64; 3]], inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        if !self.k.prepare(inv_m, rows, springs) {
            return false;
        }
        let nb = u.len();
        self.u_free.clear();
        self.u_free.extend_from_slice(u);
        remove_impulses(&mut self.u_free, inv_m, rows, springs);
        self.v.clear();
        self.v.extend_from_slice(u);
        for buf in [&mut self.fd, &mut self.fb, &mut self.dv] {
            buf.clear();
            buf.resize(nb, [0.0; 3]);
        }
        self.x.clear();
        self.x.resize(self.k.len(), 0.0);
        self.active.clear();
        self.active.extend((0..rows.len() as u32).filter(|&k| rows[k as usize].w.nn > 0.0));
        // The velocity scale: the free velocities' RMS over the mobile bodies (g h for
        // bodies at rest), and per contact the impulse it takes, `v_s / W_NN`.
        let (mut s2, mut n) = (0.0, 0usize);
        for (uf, im) in self.u_free.iter().zip(inv_m) {
            if im[0] > 0.0 || im[1] > 0.0 {
                s2 += uf[0] * uf[0] + uf[1] * uf[1];
                n += 1;
            }
        }
        let vs = if n > 0 && s2 > 0.0 { (s2 / n as f64).sqrt() } else { 1e-3 };
        self.thr.clear();
        self.zs.clear();
        self.ws.clear();
        for &k in &self.active {
            let r = &rows[k as usize];
            // The normal threshold: `c_closed` where the law is monotone (no restitution),
            // else the branch the free velocity takes (NLGS's law at a fixed point).
            let open = gather(&self.u_free, r.a, r.b, &r.hn_a, &r.hn_b) >= r.s_open;
            self.thr.push(if r.s_open == r.c_closed || !open { r.c_closed } else { r.s_open });
            let rho = vs / r.w.nn;
            self.zs.push([rho, r.mu * rho, r.mu * rho, vs]);
            self.ws.push([vs, vs, vs, r.mu * rho]);
        }
        let n = self.active.len();
        for buf in [&mut self.w, &mut self.z, &mut self.rp, &mut self.dw, &mut self.dz, &mut self.rc] {
            buf.clear();
            buf.resize(n, [0.0; 4]);
        }
        self.aff.clear();
        self.aff.resize(n, [[0.0; 4]; 2]);
        self.pairs = self.active.iter().map(|&k| used(rows[k as usize].mu)).sum();
        true
    }

    /// `(y_N, y_T)` of active contact `j` at the velocities `v`.
    #[inline(always)]
    fn y(&self, j: usize, r: &ContactRow, v: &[[f64; 3]]) -> [f64; 2] {
        [gather(v, r.a, r.b, &r.hn_a, &r.hn_b) - self.thr[j], gather(v, r.a, r.b, &r.ht_a, &r.ht_b) + r.shift_t]
    }

    /// The start from the consistent pair in the rows: every multiplier and slack
    /// shifted by `shift` times its scale (re-centring uses the same with the
    /// current multipliers and the floor instead of the shift).
    fn start(&mut self, rows: &[ContactRow], shift: f64, recentre: bool) {
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let y = self.y(j, r, &self.v);
            let z = if recentre { self.z[j] } else { [r.p[0], r.p[1].max(0.0), (-r.p[1]).max(0.0), y[1].abs()] };
            let c = complements(y, &z, r.mu);
            let (zs, ws) = (self.zs[j], self.ws[j]);
            for i in 0..4 {
                if i >= used(r.mu) {
                    (self.z[j][i], self.w[j][i]) = (0.0, 0.0);
                } else if recentre {
                    self.z[j][i] = z[i].max(shift * zs[i]);
                    self.w[j][i] = c[i].max(shift * ws[i]);
                } else {
                    self.z[j][i] = z[i].max(0.0) + shift * zs[i];
                    self.w[j][i] = c[i].max(0.0) + shift * ws[i];
                }
            }
        }
    }

    /// The barrier `μ_c = w·z / pairs`.
    fn barrier(&self) -> f64 {
        let s: f64 = self.w.iter().zip(&self.z).map(|(w, z)| (0..4).map(|i| w[i] * z[i]).sum::<f64>()).sum();
        s / self.pairs as f64
    }

    /// The primal residual `rp = w(v, z) − w` and the dual residual
    /// `F = M (v − v_free) − Σ g P_s(v) − Σ (g_N P_N + g_T P_T)` (body form, in `fd`).
    fn residuals(&mut self, inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let c = complements(self.y(j, r, &self.v), &self.z[j], r.mu);
            for i in 0..4 {
                self.rp[j][i] = if i < used(r.mu) { c[i] - self.w[j][i] } else { 0.0 };
            }
        }
        for i in 0..self.v.len() {
            for d in 0..3 {
                let im = inv_m[i][d];
                self.fd[i][d] = if im > 0.0 { (self.v[i][d] - self.u_free[i][d]) / im } else { 0.0 };
            }
        }
        for s in springs {
            let p = spring_impulse(s, &self.v).0;
            add(&mut self.fd, s.a, s.b, &s.hn_a, &s.hn_b, -p);
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let z = &self.z[j];
            add(&mut self.fd, r.a, r.b, &r.hn_a, &r.hn_b, -z[0]);
            add(&mut self.fd, r.a, r.b, &r.ht_a, &r.ht_b, -(z[1] - z[2]));
        }
    }

    /// `D = z/w` of active contact `j` (zero on the unused pairs).
    #[inline(always)]
    fn d(&self, j: usize, mu: f64) -> Quad {
        let (w, z) = (&self.w[j], &self.z[j]);
        std::array::from_fn(|i| if i < used(mu) { z[i] / w[i] } else { 0.0 })
    }

    /// Assembles `K` (module doc) and factorises it; false on a failure.
    fn factorize(&mut self, rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        self.k.reset();
        for (k, s) in springs.iter().enumerate() {
            if spring_impulse(s, &self.v).1 {
                self.k.add_spring(k, &local(&s.hn_a, &s.hn_b), s.h_beta);
            }
        }
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let d = self.d(j, r.mu);
            let (gn, gt) = (local(&r.hn_a, &r.hn_b), local(&r.ht_a, &r.ht_b));
            // S = Tᵀ C⁻¹ D T column by column: S_NT = 0, S_TN the non-associated term.
            let c0 = solve_c(&d, r.mu, &[d[0], 0.0, 0.0, 0.0]);
            self.k.add_contact(k as usize, &gn, &gn, c0[0]);
            if r.mu > 0.0 {
                let c1 = solve_c(&d, r.mu, &[0.0, d[1], -d[2], 0.0]);
                self.k.add_contact(k as usize, &gt, &gt, c1[1] - c1[2]);
                self.k.add_contact(k as usize, &gt, &gn, c0[1] - c0[2]);
            }
        }
        self.k.factorize()
    }

    /// The Newton direction for the complementarity right-hand side in `rc`
    /// (`z_i Δw_i + w_i Δz_i = rc_i`), into `dv`, `dw`, `dz`; false if the solve failed.
    fn direction(&mut self, rows: &[ContactRow]) -> bool {
        for i in 0..self.fb.len() {
            self.fb[i] = [-self.fd[i][0], -self.fd[i][1], -self.fd[i][2]];
        }
        // The right-hand side: −F + E C⁻¹ (W⁻¹ rc − D rp).
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let (d, nu) = (self.d(j, r.mu), used(r.mu));
            let q: Quad =
                std::array::from_fn(|i| if i < nu { self.rc[j][i] / self.w[j][i] - d[i] * self.rp[j][i] } else { 0.0 });
            let x = solve_c(&d, r.mu, &q);
            add(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, x[0]);
            add(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, x[1] - x[2]);
        }
        self.k.gather(&self.fb, &mut self.x);
        if !self.k.solve(&mut self.x) {
            return false;
        }
        self.k.scatter(&self.x, &mut self.dv);
        for (j, &k) in self.active.iter().enumerate() {
            let r = &rows[k as usize];
            let (d, nu) = (self.d(j, r.mu), used(r.mu));
            let dun = gather(&self.dv, r.a, r.b, &r.hn_a, &r.hn_b);
            let dut = gather(&self.dv, r.a, r.b, &r.ht_a, &r.ht_b);
            let ldv: Quad = [dun, dut, -dut, 0.0];
            let q: Quad = std::array::from_fn(|i| {
                if i < nu {
                    self.rc[j][i] / self.w[j][i] - d[i] * (self.rp[j][i] + ldv[i])
                } else {
                    0.0
                }
            });
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
        for (j, w) in self.w.iter().enumerate() {
            for i in 0..4 {
                if self.dw[j][i] < 0.0 {
                    a = a.min(-w[i] / self.dw[j][i]);
                }
                if self.dz[j][i] < 0.0 {
                    a = a.min(-self.z[j][i] / self.dz[j][i]);
                }
            }
        }
        a
    }

    /// The smallest pair product over their mean at `α` along the direction.
    fn centrality(&self, rows: &[ContactRow], a: f64) -> f64 {
        let (mut lo, mut sum) = (f64::INFINITY, 0.0);
        for (j, &k) in self.active.iter().enumerate() {
            for i in 0..used(rows[k as usize].mu) {
                let x = (self.w[j][i] + a * self.dw[j][i]) * (self.z[j][i] + a * self.dz[j][i]);
                lo = lo.min(x);
                sum += x;
            }
        }
        lo / (sum / self.pairs as f64)
    }

    /// Moves by `a` along the direction.
    fn advance(&mut self, a: f64) {
        for (v, dv) in self.v.iter_mut().zip(&self.dv) {
            for d in 0..3 {
                v[d] += a * dv[d];
            }
        }
        for j in 0..self.w.len() {
            for i in 0..4 {
                self.w[j][i] += a * self.dw[j][i];
                self.z[j][i] += a * self.dz[j][i];
            }
        }
    }

    /// The impulses into the rows and springs and `u = u_free + M⁻¹ Σ H P`; an impulse
    /// whose velocity effect `P_N W_NN` is below its slack is dropped (an open contact).
    fn write_back(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], rows: &mut [ContactRow], springs: &mut [SpringRow]) {
        rows.iter_mut().for_each(|r| r.p = [0.0; 2]);
        for (j, &k) in self.active.iter().enumerate() {
            let r = &mut rows[k as usize];
            let z = &self.z[j];
            if z[0] * r.w.nn >= self.w[j][0] {
                r.p = [z[0], if r.mu > 0.0 { z[1] - z[2] } else { 0.0 }];
            }
        }
        for s in springs.iter_mut() {
            s.p = spring_impulse(s, &self.v).0;
        }
        u.copy_from_slice(&self.u_free);
        apply_impulses(u, inv_m, rows, springs);
    }

    /// One Mehrotra iteration from the current residuals and barrier `mu`: the step
    /// length taken, or `None` if a factorisation or a solve failed.
    fn iterate(&mut self, rows: &[ContactRow], springs: &[SpringRow], mu: f64) -> Option<f64> {
        if !self.factorize(rows, springs) {
            return None;
        }
        // Predictor.
        for (rc, (w, z)) in self.rc.iter_mut().zip(self.w.iter().zip(&self.z)) {
            *rc = std::array::from_fn(|i| -w[i] * z[i]);
        }
        if !self.direction(rows) {
            return None;
        }
        let a = self.to_boundary();
        let mut mu_aff = 0.0;
        for j in 0..self.w.len() {
            for i in 0..4 {
                mu_aff += (self.w[j][i] + a * self.dw[j][i]) * (self.z[j][i] + a * self.dz[j][i]);
            }
        }
        let sigma = (mu_aff / self.pairs as f64 / mu).powi(3).min(1.0);
        for j in 0..self.w.len() {
            self.aff[j] = [self.dw[j], self.dz[j]];
        }
        // Corrector, with the centring σ μ on the pairs in use.
        for (j, &k) in self.active.iter().enumerate() {
            for i in 0..4 {
                self.rc[j][i] = if i < used(rows[k as usize].mu) {
                    -self.w[j][i] * self.z[j][i] - self.aff[j][0][i] * self.aff[j][1][i] + sigma * mu
                } else {
                    0.0
                };
            }
        }
        if !self.direction(rows) {
            return None;
        }
        let mut a = (0.995 * self.to_boundary()).min(1.0);
        let gamma = GAMMA.min(0.5 * self.centrality(rows, 0.0));
        for _ in 0..30 {
            if self.centrality(rows, a) >= gamma {
                break;
            }
            a *= 0.7;
        }
        self.advance(a);
        Some(a)
    }
}

/// Solves a step's problem (module doc): the same contract as
/// [`super::nlgs::solve_nlgs`] — on entry `u = u_free + M⁻¹ Σ H P` with the rows'
/// warm-start impulses, on return the impulses in the rows and springs and `u`
/// consistent with them; `settings.policy` must be a residual policy (`strict`,
/// `quad`, `quad_max`: the scene check refuses the others).
pub fn solve_interior(
    settings: &NlgsSettings,
    opts: &InteriorOptions,
    ws: &mut InteriorWorkspace,
    u: &mut [[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &mut [ContactRow],
    springs: &mut [SpringRow],
) -> NlgsReport {
    let s = settings;
    let cap = s.max_iterations.max(1);
    let r = if opts.nlgs_first > 0 {
        let first = NlgsSettings { max_iterations: opts.nlgs_first.min(cap), ..*s };
        let r = solve_nlgs(&first, u, inv_m, rows, springs);
        if r.converged || r.iterations >= cap {
            return r;
        }
        r
    } else {
        NlgsReport { iterations: 0, criterion: f64::INFINITY, converged: false }
    };
    if rows.is_empty() {
        let rest = solve_nlgs(&NlgsSettings { max_iterations: cap - r.iterations, ..*s }, u, inv_m, rows, springs);
        return NlgsReport { iterations: r.iterations + rest.iterations, ..rest };
    }
    let mut sweeps = r.iterations;
    if !ws.prepare(u, inv_m, rows, springs) || ws.pairs == 0 {
        let rest = solve_nlgs(&NlgsSettings { max_iterations: cap - sweeps, ..*s }, u, inv_m, rows, springs);
        return NlgsReport { iterations: sweeps + rest.iterations, ..rest };
    }
    ws.start(rows, 1.0, false);
    let mut blocked = 0;
    let mut iterations = 0;
    let mut criterion = r.criterion;
    while iterations < opts.max_iterations {
        ws.residuals(inv_m, rows, springs);
        let mu = ws.barrier();
        ws.write_back(u, inv_m, rows, springs);
        let (value, converged) = evaluate(s.policy, s.tolerance, s.max_factor, &check(u, inv_m, rows, springs), 0.0);
        criterion = value;
        if converged && sweeps + iterations >= s.min_iterations {
            return NlgsReport { iterations: sweeps + iterations, criterion, converged: true };
        }
        iterations += 1;
        let Some(a) = ws.iterate(rows, springs, mu) else { break };
        blocked = if a < BLOCKED_STEP { blocked + 1 } else { 0 };
        if blocked >= BLOCKED_COUNT {
            blocked = 0;
            ws.start(rows, RECENTRE, true);
        }
    }
    // Not converged: NLGS from the interior point's last consistent pair.
    if !opts.nlgs_after || !criterion.is_finite() || sweeps >= cap {
        return NlgsReport { iterations: sweeps + iterations, criterion, converged: false };
    }
    let rest = solve_nlgs(&NlgsSettings { max_iterations: cap - sweeps, ..*s }, u, inv_m, rows, springs);
    sweeps += rest.iterations;
    NlgsReport { iterations: sweeps + iterations, ..rest }
}
