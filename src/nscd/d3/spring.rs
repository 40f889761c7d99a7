//! The 3D sublayer spring (law (17) of Saussine et al. 2006, §2.9; [`crate::space::springs::Spring3`]) as a row
//! of the shared NSCD method, treated implicitly as the 2D row is ([`crate::nscd::sublayer`]): the θ-weighted
//! force `(1 − θ) R_i + θ R_f` with the end-of-step strain `ε_m + θ h U_N / L0` makes the impulse affine in the
//! end-of-step axial velocity, `P = h α − h β U_N`, solved exactly at every visit (the shared
//! `law17_affine` / `law17_solve`); for θ = 1/2 a linear spring is integrated by the trapezoidal rule.

use crate::geometry::Pose;
use crate::nscd::method::apgd::AffineRow;
use crate::nscd::method::{Row, SweepNorms};
use crate::nscd::sublayer::{add_scalar_norms, law17_affine, law17_solve};
use crate::space::bodies::{dot6, Dofs6};
use crate::space::springs::Spring3;

/// The solver's record of one 3D spring.
#[derive(Debug, Clone, Copy)]
pub struct SpringRow3 {
    /// Body at the first end.
    pub a: u32,
    /// Body at the second end, `u32::MAX` for a world anchor.
    pub b: u32,
    /// Generalised axis direction of the first end at `q_m`.
    pub h_a: Dofs6,
    /// Generalised axis direction of the second end at `q_m` (zero for an anchor).
    pub h_b: Dofs6,
    /// Delassus scalar `w = h_a M_a⁻¹ h_a + h_b M_b⁻¹ h_b` (1/kg).
    pub w: f64,
    /// Impulse `P = h R` over the step (N·s), positive pushing the ends apart.
    pub p: f64,
    /// `h α` (N·s).
    pub h_alpha: f64,
    /// `h β` (N·s per m/s).
    pub h_beta: f64,
    /// Clamp the impulse to `P ≥ 0`.
    pub compression_only: bool,
}

impl SpringRow3 {
    /// The row of `spring` at `q_m` (`poses_m`); `(poses_i, u_i)` give the start-of-step force; warm-started
    /// from the spring's last impulse.
    pub fn new(
        spring: &Spring3,
        (poses_i, u_i): (&[Pose], &[Dofs6]),
        poses_m: &[Pose],
        inv_m: &[Dofs6],
        h: f64,
        theta: f64,
    ) -> Self {
        let r_i = spring.force(poses_i, u_i);
        let st = spring.state(poses_m);
        let eps_m = spring.strain(st.length);
        let quad = |hd: &Dofs6, im: &Dofs6| (0..6).map(|d| hd[d] * im[d] * hd[d]).sum::<f64>();
        let w = quad(&st.h_a, &inv_m[spring.a]) + spring.b.map_or(0.0, |b| quad(&st.h_b, &inv_m[b]));
        let (h_alpha, h_beta) = law17_affine(r_i, eps_m, (spring.k_n, spring.nu, spring.rest_length), h, theta);
        Self {
            a: spring.a as u32,
            b: spring.b.map_or(u32::MAX, |b| b as u32),
            h_a: st.h_a,
            h_b: st.h_b,
            w,
            p: spring.impulse,
            h_alpha,
            h_beta,
            compression_only: spring.compression_only,
        }
    }

    /// The rate `U_N` (m/s) at which the ends move apart.
    #[inline(always)]
    pub fn axial_velocity(&self, u: &[Dofs6]) -> f64 {
        let mut un = dot6(&self.h_a, &u[self.a as usize]);
        if self.b != u32::MAX {
            un -= dot6(&self.h_b, &u[self.b as usize]);
        }
        un
    }

    #[inline(always)]
    fn apply(&self, u: &mut [Dofs6], inv_m: &[Dofs6], p: f64, sign: f64) {
        let (a, im) = (self.a as usize, &inv_m[self.a as usize]);
        for d in 0..6 {
            u[a][d] += sign * im[d] * self.h_a[d] * p;
        }
        if self.b != u32::MAX {
            let (b, im) = (self.b as usize, &inv_m[self.b as usize]);
            for d in 0..6 {
                u[b][d] -= sign * im[d] * self.h_b[d] * p;
            }
        }
    }
}

impl Row for SpringRow3 {
    type Dofs = Dofs6;

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
    fn add_impulse(&self, u: &mut [Dofs6], inv_m: &[Dofs6], sign: f64) {
        self.apply(u, inv_m, self.p, sign);
    }

    #[inline(always)]
    fn visit<const UPDATE: bool>(&mut self, u: &mut [Dofs6], inv_m: &[Dofs6], omega: f64, norms: &mut SweepNorms) {
        let un = self.axial_velocity(u);
        let mut p = law17_solve(self.h_alpha, self.h_beta, self.w, un - self.w * self.p, self.compression_only);
        if omega != 1.0 {
            p = self.p + omega * (p - self.p);
            if self.compression_only {
                p = p.max(0.0);
            }
        }
        let p_old = self.p;
        let dp = p - p_old;
        if UPDATE && dp != 0.0 {
            self.p = p;
            self.apply(u, inv_m, dp, 1.0);
        }
        add_scalar_norms(norms, self.w, p_old, p, dp);
    }
}

/// The 3D sublayer spring in the accelerated projected gradient: a term of the quadratic, as the 2D one.
impl AffineRow for SpringRow3 {
    #[inline(always)]
    fn impulse(&self) -> f64 {
        self.p
    }

    #[inline(always)]
    fn set_impulse(&mut self, p: f64) {
        self.p = p;
    }

    #[inline(always)]
    fn axial_velocity(&self, u: &[Dofs6]) -> f64 {
        SpringRow3::axial_velocity(self, u)
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
        law17_solve(self.h_alpha, self.h_beta, self.w, u0, self.compression_only)
    }

    #[inline(always)]
    fn add_impulse_of(&self, u: &mut [Dofs6], inv_m: &[Dofs6], p: f64, sign: f64) {
        self.apply(u, inv_m, p, sign);
    }
}
