//! Per-contact records for the solver, and the contact law data.
//!
//! A contact α found at `q_m` carries its local frame `(n, t)` (n towards the
//! candidate, `t = n` rotated by +90°) and the maps `H*` of eq. (5): for each of
//! its two bodies the generalized directions `h_n = (n_x, n_y, r × n)` and
//! `h_t = (t_x, t_y, r × t)`, `r` being the lever arm from the centre of mass to
//! the contact point. The relative velocity of candidate `a` with respect to
//! antagonist `b` is `U_N = h_n^a · u_a − h_n^b · u_b` (same for `U_T`), and the
//! impulse `P` adds `M⁻¹ h P` to `u_a` and subtracts it from `u_b` (eq. 6, 12).
//!
//! **Gap prediction.** A contact open at `q_m` (`g_m > 0`) closes only if it
//! would reach the next step's intermediate configuration overlapping: the normal
//! law acts on the gap predicted there, `g_m + h U_N ≥ 0`, i.e. `U_N ≥ −g_m/h`.
//! The end-of-step gap is then `g_f = g_m + θ h U_N ≥ (1 − θ) g_m ≥ 0`, and the
//! next detection finds the contact at zero gap, where `U_N ≥ 0` holds it
//! (an impact completes over two steps, without overlap). Enforcing `g_f ≥ 0`
//! instead (`U_N ≥ −g_m/(θh)`) would close the gap at `q_f` but keep the approach
//! velocity, so the next `q_m` overlaps by `(1 − θ) h |U_N|` and that overlap
//! would stay. A contact already overlapping at `q_m` (round-off, rotation,
//! solver tolerance) obeys the velocity Signorini law `U_N ≥ 0` (eq. 8): its
//! overlap does not grow and no energy is injected to push it out.
//!
//! **Restitution (§2.8).** The law is applied to the weighted mean `U⁺ + e U⁻`
//! (eq. 11 with `U⁺` replaced). Normally: a contact that closes with `U_N⁻ < 0`
//! leaves with `U_N⁺ = −e_n U_N⁻`. Tangentially the Coulomb law acts on
//! `U_T⁺ + e_t U_T⁻`.

use super::coulomb::{solve, Delassus};
use super::method::apgd::ConeRow;
use super::method::{Row, SweepNorms};
use crate::geometry::{perp, Vec2};
use serde::{Deserialize, Serialize};

pub use crate::plane::detection::ContactKey;
pub use crate::plane::springs::{dot3, gen_dir};

/// The solver's record of one contact: contiguous, everything one update needs.
#[derive(Debug, Clone, Copy, Default)]
pub struct ContactRow {
    /// Index of the candidate body (the normal points towards it).
    pub a: u32,
    /// Index of the antagonist body.
    pub b: u32,
    /// Generalized normal direction of the candidate, `h_n = (n_x, n_y, r_a × n)`
    /// (dimensionless, dimensionless, m): the row of `H*` of eq. (5) for `U_N`.
    pub hn_a: [f64; 3],
    /// Generalized tangent direction of the candidate, `h_t = (t_x, t_y, r_a × t)` (–, –, m).
    pub ht_a: [f64; 3],
    /// Generalized normal direction of the antagonist, `(n_x, n_y, r_b × n)` (–, –, m);
    /// enters `U_N` with a minus sign.
    pub hn_b: [f64; 3],
    /// Generalized tangent direction of the antagonist, `(t_x, t_y, r_b × t)` (–, –, m).
    pub ht_b: [f64; 3],
    /// Local Delassus block `W = H* M⁻¹ H` of the contact (1/kg, i.e. m/s per N·s).
    pub w: Delassus,
    /// Impulse `(P_N, P_T)` (N·s).
    pub p: [f64; 2],
    /// Open while `U_N ≥ s_open` (m/s).
    pub s_open: f64,
    /// Normal velocity enforced once closed (m/s).
    pub c_closed: f64,
    /// `e_t U_T⁻` added to `U_T` (m/s).
    pub shift_t: f64,
    /// Coulomb friction coefficient `μ` of law (11) (dimensionless).
    pub mu: f64,
}

/// Cold per-contact data, parallel to the rows.
#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
pub struct ContactGeom {
    /// Identity of the contact across steps: candidate, antagonist, feature pair
    /// (used to warm-start its impulse).
    pub key: ContactKey,
    /// Contact point at `q_m` (m).
    pub point: Vec2,
    /// Unit normal towards the candidate.
    pub normal: Vec2,
    /// Gap at `q_m` (m).
    pub gap: f64,
}

/// Friction and restitution between two materials.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ContactLaw {
    /// Coulomb friction coefficient `μ` (dimensionless), law (11) of Saussine et al. 2006.
    pub friction: f64,
    /// Normal restitution coefficient `e_n` (dimensionless, §2.8): a contact closing at
    /// `U_N⁻ < 0` leaves at `U_N⁺ = −e_n U_N⁻`; 0 makes impacts fully inelastic.
    pub restitution_n: f64,
    /// Tangential restitution coefficient `e_t` (dimensionless, §2.8): Coulomb's law acts
    /// on `U_T⁺ + e_t U_T⁻`.
    pub restitution_t: f64,
}

/// The law of a pair of materials nobody set: frictionless (μ = 0) and plastic
/// (`e_n = e_t = 0`), as in a scene without a `[[contact]]` for the pair.
impl Default for ContactLaw {
    fn default() -> Self {
        Self { friction: 0.0, restitution_n: 0.0, restitution_t: 0.0 }
    }
}

#[inline(always)]
fn wdot(h: &[f64; 3], im: &[f64; 3], g: &[f64; 3]) -> f64 {
    h[0] * im[0] * g[0] + h[1] * im[1] * g[1] + h[2] * im[2] * g[2]
}

impl ContactRow {
    /// Builds the row of a contact at point `p` with normal `n` between bodies with
    /// centres `ga`, `gb`, inverse masses `im_a`, `im_b`, velocities at the start of
    /// the step `ua`, `ub` (for `U⁻`), gap `gap` at `q_m`, time step `h` (s).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        (a, b): (u32, u32),
        p: Vec2,
        n: Vec2,
        (ga, gb): (Vec2, Vec2),
        (im_a, im_b): (&[f64; 3], &[f64; 3]),
        (ua, ub): (&[f64; 3], &[f64; 3]),
        gap: f64,
        h: f64,
        law: &ContactLaw,
    ) -> Self {
        let t = perp(n);
        let (ra, rb) = (p - ga, p - gb);
        let (hn_a, ht_a, hn_b, ht_b) = (gen_dir(ra, n), gen_dir(ra, t), gen_dir(rb, n), gen_dir(rb, t));
        let w = Delassus {
            nn: wdot(&hn_a, im_a, &hn_a) + wdot(&hn_b, im_b, &hn_b),
            nt: wdot(&hn_a, im_a, &ht_a) + wdot(&hn_b, im_b, &ht_b),
            tt: wdot(&ht_a, im_a, &ht_a) + wdot(&ht_b, im_b, &ht_b),
        };
        let un_minus = dot3(&hn_a, ua) - dot3(&hn_b, ub);
        let ut_minus = dot3(&ht_a, ua) - dot3(&ht_b, ub);
        let s_open = if gap > 0.0 { -gap / h } else { 0.0 };
        let c_closed =
            if law.restitution_n > 0.0 && un_minus < 0.0 { s_open.max(-law.restitution_n * un_minus) } else { s_open };
        Self {
            a,
            b,
            hn_a,
            ht_a,
            hn_b,
            ht_b,
            w,
            p: [0.0; 2],
            s_open,
            c_closed,
            shift_t: law.restitution_t * ut_minus,
            mu: law.friction,
        }
    }
}

/// Adds `sign · M⁻¹ (h_n ΔP_N + h_t ΔP_T)` to one body's velocity `u` (`im`: its inverse mass).
#[inline(always)]
pub(crate) fn apply(u: &mut [f64; 3], im: &[f64; 3], hn: &[f64; 3], dn: f64, ht: &[f64; 3], dt: f64, sign: f64) {
    for d in 0..3 {
        u[d] += sign * im[d] * (hn[d] * dn + ht[d] * dt);
    }
}

/// The norms of one contact row whose impulse goes from `p` to `q` (N·s) under its local Delassus block `w`
/// ([`SweepNorms::add`]): `ΔU = W (q − p)`, `P̄ = ½ (p + q)`, and the midpoint averages of `P·WP` and `|WP|²`.
#[inline(always)]
pub fn add_contact_norms(norms: &mut SweepNorms, w: Delassus, p: [f64; 2], q: [f64; 2], changed: bool) {
    let ([pn, pt], [qn, qt]) = (p, q);
    let (dn, dt) = (qn - pn, qt - pt);
    let (dun, dut) = (w.nn * dn + w.nt * dt, w.nt * dn + w.tt * dt);
    let (wpn, wpt) = (w.nn * pn + w.nt * pt, w.nt * pn + w.tt * pt);
    let (wqn, wqt) = (w.nn * qn + w.nt * qt, w.nt * qn + w.tt * qt);
    let (mn, mt) = (0.5 * (pn + qn), 0.5 * (pt + qt));
    let wqq = qn * wqn + qt * wqt;
    norms.add(
        dun * dun + dut * dut,
        mn * mn + mt * mt,
        mn * dun + mt * dut,
        0.5 * (pn * wpn + pt * wpt + wqq),
        0.5 * (wpn * wpn + wpt * wpt + wqn * wqn + wqt * wqt),
        wqq,
        changed,
    );
}

/// The 2D contact as a row of the NSCD method: Signorini with the gap prediction and restitution thresholds,
/// and exact Coulomb friction ([`super::coulomb::solve`]), over the 2×2 Delassus block.
impl Row for ContactRow {
    type Dofs = [f64; 3];

    #[inline(always)]
    fn bodies(&self) -> (u32, u32) {
        (self.a, self.b)
    }

    #[inline(always)]
    fn set_bodies(&mut self, a: u32, b: u32) {
        (self.a, self.b) = (a, b);
    }

    #[inline(always)]
    fn take_impulse(&mut self, other: &Self) {
        self.p = other.p;
    }

    #[inline(always)]
    fn add_impulse(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], sign: f64) {
        self.add_impulse_of(u, inv_m, self.p, sign);
    }

    #[inline(always)]
    fn visit<const UPDATE: bool>(
        &mut self,
        u: &mut [[f64; 3]],
        inv_m: &[[f64; 3]],
        omega: f64,
        norms: &mut SweepNorms,
    ) {
        let r = self;
        let (a, b) = (r.a as usize, r.b as usize);
        let [un, ut] = r.local_velocity(u);
        let w = r.w;
        let [pn, pt] = r.p;
        let u0n = un - (w.nn * pn + w.nt * pt);
        let u0t = ut - (w.nt * pn + w.tt * pt) + r.shift_t;
        let [mut qn, mut qt] = solve(w, [u0n, u0t], r.s_open, r.c_closed, r.mu);
        if omega != 1.0 {
            qn = (pn + omega * (qn - pn)).max(0.0);
            qt = (pt + omega * (qt - pt)).clamp(-r.mu * qn, r.mu * qn);
        }
        let (dn, dt) = (qn - pn, qt - pt);
        let changed = dn != 0.0 || dt != 0.0;
        if UPDATE && changed {
            r.p = [qn, qt];
            apply(&mut u[a], &inv_m[a], &r.hn_a, dn, &r.ht_a, dt, 1.0);
            apply(&mut u[b], &inv_m[b], &r.hn_b, dn, &r.ht_b, dt, -1.0);
        }
        add_contact_norms(norms, w, [pn, pt], [qn, qt], changed);
    }
}

/// Largest eigenvalue of a symmetric 2×2 block.
fn lambda_max(nn: f64, nt: f64, tt: f64) -> f64 {
    0.5 * (nn + tt) + (0.25 * (nn - tt) * (nn - tt) + nt * nt).sqrt()
}

/// The 2D contact in the accelerated projected gradient: `(P_N, P_T)` projected on `P_N ≥ 0`, `|P_T| ≤ g_α`.
impl ConeRow for ContactRow {
    type Impulse = [f64; 2];

    #[inline(always)]
    fn impulse(&self) -> [f64; 2] {
        self.p
    }

    #[inline(always)]
    fn set_impulse(&mut self, p: [f64; 2]) {
        self.p = p;
    }

    #[inline(always)]
    fn normal(&self) -> f64 {
        self.p[0]
    }

    #[inline(always)]
    fn mu(&self) -> f64 {
        self.mu
    }

    #[inline(always)]
    fn local_velocity(&self, u: &[[f64; 3]]) -> [f64; 2] {
        let (ua, ub) = (&u[self.a as usize], &u[self.b as usize]);
        [dot3(&self.hn_a, ua) - dot3(&self.hn_b, ub), dot3(&self.ht_a, ua) - dot3(&self.ht_b, ub)]
    }

    #[inline(always)]
    fn gradient(&self, v: [f64; 2], c: f64) -> [f64; 2] {
        [v[0] - c, v[1] + self.shift_t]
    }

    /// `c_closed` for a contact whose `U_0N < s_open`, `s_open` otherwise (`c_closed` when the two agree).
    #[inline]
    fn label(&self, u: &[[f64; 3]]) -> f64 {
        if self.s_open >= self.c_closed {
            return self.c_closed;
        }
        let u0n = self.local_velocity(u)[0] - (self.w.nn * self.p[0] + self.w.nt * self.p[1]);
        if u0n < self.s_open {
            self.c_closed
        } else {
            self.s_open
        }
    }

    #[inline(always)]
    fn diagonal(&self) -> [f64; 2] {
        [self.w.nn, self.w.tt]
    }

    fn lambda_max(&self) -> f64 {
        lambda_max(self.w.nn, self.w.nt, self.w.tt)
    }

    #[inline(always)]
    fn project(&self, x: [f64; 2], tresca: Option<f64>) -> [f64; 2] {
        let pn = x[0].max(0.0);
        let bound = tresca.unwrap_or(self.mu * pn);
        [pn, x[1].clamp(-bound, bound)]
    }

    #[inline(always)]
    fn add_impulse_of(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], p: [f64; 2], sign: f64) {
        let (a, b) = (self.a as usize, self.b as usize);
        apply(&mut u[a], &inv_m[a], &self.hn_a, p[0], &self.ht_a, p[1], sign);
        apply(&mut u[b], &inv_m[b], &self.hn_b, p[0], &self.ht_b, p[1], -sign);
    }

    #[inline(always)]
    fn add_norms(&self, norms: &mut SweepNorms, p: [f64; 2], q: [f64; 2], changed: bool) {
        add_contact_norms(norms, self.w, p, q, changed);
    }
}
