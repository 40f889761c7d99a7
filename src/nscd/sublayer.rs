//! Viscoelastic sublayer springs (Saussine et al. 2006, §2.9, law (17)) as rows
//! of the NLGS; the spring itself and its law are [`crate::plane::springs`].
//!
//! Law (17): `R_N = −k_N ε − ν ε̇`, `ε = (L − L0)/L0 − ε0`, `ε̇ = U_N / L0`.
//!
//! **Implicit treatment.** The spring is a row of the NLGS, like a contact, with
//! the θ-weighted force `R = (1−θ) R_i + θ R_f`, where `R_i` is the force at the
//! start of the step and `R_f` uses the end-of-step strain
//! `ε_f = ε_m + θ h U_N / L0`. The impulse `P = h R` is affine in the final
//! relative velocity, `P = h (α − β U_N)`, `α = (1−θ) R_i − θ k_N ε_m`,
//! `β = θ (k_N θ h + ν) / L0`, and with `U_N = U_0 + w P` the local solution is exact:
//! `P = h (α − β U_0) / (1 + h β w)`. For θ = 1/2 and a linear spring this is the
//! trapezoidal rule (no numerical damping); any stiffness is stable.
//! A `compression_only` spring's impulse is clamped to `P ≥ 0`.

use super::contact::{apply, dot3};
use super::method::apgd::AffineRow;
use super::method::{Row, SweepNorms};
pub use crate::plane::springs::Spring;

/// The solver's record of one spring.
#[derive(Debug, Clone, Copy, Default)]
pub struct SpringRow {
    /// Index of the body at the first end.
    pub a: u32,
    /// `u32::MAX` for a world anchor.
    pub b: u32,
    /// Generalized axis direction at the first end, `(n_x, n_y, r_a × n)` (–, –, m), `n`
    /// the unit axis from the second end to the first, at `q_m`.
    pub hn_a: [f64; 3],
    /// Generalized axis direction at the second end, `(n_x, n_y, r_b × n)` (–, –, m); zero
    /// lever arm for a world anchor.
    pub hn_b: [f64; 3],
    /// Delassus scalar `w = h_n M⁻¹ h_n` of the row (1/kg): relative axial velocity per unit impulse.
    pub w: f64,
    /// Impulse `P = h R` over the step (N·s), positive pushing the ends apart.
    pub p: f64,
    /// `h α` (N·s).
    pub h_alpha: f64,
    /// `h β` (N·s per m/s).
    pub h_beta: f64,
    /// Clamp the impulse to `P ≥ 0` (unilateral support).
    pub compression_only: bool,
}

impl Spring {
    /// Builds the solver row at `q_m`; `q_i`, `u_i` give the start-of-step force.
    pub fn row(
        &self,
        (q_i, u_i): (&[[f64; 3]], &[[f64; 3]]),
        q_m: &[[f64; 3]],
        inv_m: &[[f64; 3]],
        h: f64,
        theta: f64,
    ) -> SpringRow {
        let r_i = self.force(q_i, u_i);
        let (_, eps_m, hn_a, hn_b) = self.state(q_m, u_i);
        let w = {
            let ia = &inv_m[self.a];
            let mut w = hn_a[0] * hn_a[0] * ia[0] + hn_a[1] * hn_a[1] * ia[1] + hn_a[2] * hn_a[2] * ia[2];
            if let Some(b) = self.b {
                let ib = &inv_m[b];
                w += hn_b[0] * hn_b[0] * ib[0] + hn_b[1] * hn_b[1] * ib[1] + hn_b[2] * hn_b[2] * ib[2];
            }
            w
        };
        let (h_alpha, h_beta) = law17_affine(r_i, eps_m, (self.k_n, self.nu, self.rest_length), h, theta);
        SpringRow {
            a: self.a as u32,
            b: self.b.map_or(u32::MAX, |b| b as u32),
            hn_a,
            hn_b,
            w,
            p: self.impulse,
            h_alpha,
            h_beta,
            compression_only: self.compression_only,
        }
    }
}

/// The norms of a scalar row (a spring) whose impulse changes by `dp` from `p_old` to `p` (N·s) under its
/// Delassus scalar `w` ([`SweepNorms::add`]): `ΔU = w ΔP`, `P̄ = ½ (p_old + p)`, and the midpoint averages of
/// `P w P` and `(w P)²`. Shared by the 2D and 3D spring rows (`dp` as the row computed it, so that the norms are
/// those of its update to the last bit).
#[inline(always)]
pub(crate) fn add_scalar_norms(norms: &mut SweepNorms, w: f64, p_old: f64, p: f64, dp: f64) {
    let pm = 0.5 * (p_old + p);
    let du = w * dp;
    let (wp_old, wp) = (w * p_old, w * p);
    norms.add(
        du * du,
        pm * pm,
        pm * du,
        0.5 * (p_old * wp_old + p * wp),
        0.5 * (wp_old * wp_old + wp * wp),
        p * wp,
        dp != 0.0,
    );
}

/// Law (17)'s θ-weighted impulse over a step as an affine function of the end-of-step axial velocity,
/// `P = h α − h β U_N` (module doc): `(h α, h β)` from the start-of-step force `r_i` (N), the strain `eps_m` at
/// `q_m`, the spring's `(k_N, ν, L0)`, the step `h` and `θ`. Shared by the 2D and 3D rows.
pub(crate) fn law17_affine(r_i: f64, eps_m: f64, (k_n, nu, rest): (f64, f64, f64), h: f64, theta: f64) -> (f64, f64) {
    let alpha = (1.0 - theta) * r_i - theta * k_n * eps_m;
    let beta = theta * (k_n * theta * h + nu) / rest;
    (h * alpha, h * beta)
}

/// The exact local solution of law (17) given `U_0`, the axial velocity without the row's impulse, and the row's
/// Delassus scalar `w`: `P = (h α − h β U_0) / (1 + h β w)`, clamped to `P ≥ 0` when `compression_only`.
#[inline(always)]
pub(crate) fn law17_solve(h_alpha: f64, h_beta: f64, w: f64, u0: f64, compression_only: bool) -> f64 {
    let p = (h_alpha - h_beta * u0) / (1.0 + h_beta * w);
    if compression_only {
        p.max(0.0)
    } else {
        p
    }
}

impl SpringRow {
    /// Exact local solution given `U_0`, the relative velocity without this row's impulse.
    #[inline(always)]
    pub fn solve(&self, u0: f64) -> f64 {
        law17_solve(self.h_alpha, self.h_beta, self.w, u0, self.compression_only)
    }
}

/// The sublayer spring as a row of the NSCD method: its affine law (17), solved exactly ([`SpringRow::solve`]).
impl Row for SpringRow {
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
        let s = self;
        let (a, b) = (s.a as usize, s.b as usize);
        let un = s.axial_velocity(u);
        let mut p = s.solve(un - s.w * s.p);
        if omega != 1.0 {
            p = s.p + omega * (p - s.p);
            if s.compression_only {
                p = p.max(0.0);
            }
        }
        let dp = p - s.p;
        if UPDATE && dp != 0.0 {
            s.p = p;
            apply(&mut u[a], &inv_m[a], &s.hn_a, dp, &[0.0; 3], 0.0, 1.0);
            if s.b != u32::MAX {
                apply(&mut u[b], &inv_m[b], &s.hn_b, dp, &[0.0; 3], 0.0, -1.0);
            }
        }
        add_scalar_norms(norms, s.w, p - dp, p, dp);
    }
}

/// The sublayer spring in the accelerated projected gradient: a term of the quadratic.
impl AffineRow for SpringRow {
    #[inline(always)]
    fn impulse(&self) -> f64 {
        self.p
    }

    #[inline(always)]
    fn set_impulse(&mut self, p: f64) {
        self.p = p;
    }

    #[inline(always)]
    fn axial_velocity(&self, u: &[[f64; 3]]) -> f64 {
        let mut un = dot3(&self.hn_a, &u[self.a as usize]);
        if self.b != u32::MAX {
            un -= dot3(&self.hn_b, &u[self.b as usize]);
        }
        un
    }

    fn h_alpha(&self) -> f64 {
        self.h_alpha
    }

    fn h_beta(&self) -> f64 {
        self.h_beta
    }

    fn w(&self) -> f64 {
        self.w
    }

    fn compression_only(&self) -> bool {
        self.compression_only
    }

    fn solve_affine(&self, u0: f64) -> f64 {
        self.solve(u0)
    }

    #[inline(always)]
    fn add_impulse_of(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], p: f64, sign: f64) {
        apply(&mut u[self.a as usize], &inv_m[self.a as usize], &self.hn_a, p, &[0.0; 3], 0.0, sign);
        if self.b != u32::MAX {
            apply(&mut u[self.b as usize], &inv_m[self.b as usize], &self.hn_b, p, &[0.0; 3], 0.0, -sign);
        }
    }
}
