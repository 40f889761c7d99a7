//! Viscoelastic sublayer springs (Saussine et al. 2006, §2.9, law (17)).
//!
//! A spring joins a point of body `a` to a point of body `b` or to a fixed anchor
//! in the world. With `L` its length, `L0` its rest length and `ε0` a prestrain,
//! the strain is `ε = (L − L0)/L0 − ε0`. Law (17) is written in the paper as
//! `R_N = −k_N ε + ν ε̇`; we take `R_N` as the force pushing the bodies apart
//! along the spring axis and make the dashpot dissipative,
//! `R_N = −k_N ε − ν ε̇`, `ε̇ = U_N / L0`
//! (with the paper's sign the dashpot would feed energy in). `k_N` (N) is the
//! force per unit strain and `ν` (N·s) the force per unit strain rate: a spring of
//! stiffness `k` (N/m) and damping `c` (N·s/m) has `k_N = k L0`, `ν = c L0`.
//!
//! **Implicit treatment.** The spring is a row of the NLGS, like a contact, with
//! the θ-weighted force `R = (1−θ) R_i + θ R_f`, where `R_i` is the force at the
//! start of the step and `R_f` uses the end-of-step strain
//! `ε_f = ε_m + θ h U_N / L0`. The impulse `P = h R` is affine in the final
//! relative velocity, `P = h (α − β U_N)`, `α = (1−θ) R_i − θ k_N ε_m`,
//! `β = θ (k_N θ h + ν) / L0`, and with `U_N = U_0 + w P` the local solution is exact:
//! `P = h (α − β U_0) / (1 + h β w)`. For θ = 1/2 and a linear spring this is the
//! trapezoidal rule (no numerical damping); any stiffness is stable.
//! `compression_only` makes the spring a unilateral support (`R_N ≥ 0`), the
//! "derived Signorini law" reading of §2.9.

use super::contact::{dot3, gen_dir};
use crate::geometry::{rotate, Vec2};
use serde::{Deserialize, Serialize};

/// A sublayer spring.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Spring {
    /// Body at the first end.
    pub a: usize,
    /// Attachment on `a`, relative to its centre of mass in its body frame (m).
    pub point_a: [f64; 2],
    /// Body at the second end, or `None` for a fixed anchor.
    pub b: Option<usize>,
    /// Attachment on `b` relative to its centre of mass in its body frame, or the
    /// world anchor point (m).
    pub point_b: [f64; 2],
    /// Force per unit strain `k_N` (N).
    pub k_n: f64,
    /// Force per unit strain rate `ν` (N·s).
    pub nu: f64,
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// Prestrain `ε0` (dimensionless), subtracted from the strain `(L − L0)/L0`.
    pub prestrain: f64,
    /// Only pushes (`R_N ≥ 0`).
    pub compression_only: bool,
    /// Impulse of the last step (N·s), the warm start.
    pub impulse: f64,
}

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

/// Placement of an attachment point: world point and lever arm.
#[inline]
fn attach(q: &[f64; 3], p: [f64; 2]) -> (Vec2, Vec2) {
    let r = rotate(Vec2::new(p[0], p[1]), q[2].cos(), q[2].sin());
    (Vec2::new(q[0], q[1]) + r, r)
}

impl Spring {
    /// Axis (unit, from the second end to `a`), length, lever arms of both ends.
    fn geometry(&self, q: &[[f64; 3]]) -> (Vec2, f64, Vec2, Vec2) {
        let (pa, ra) = attach(&q[self.a], self.point_a);
        let (pb, rb) = match self.b {
            Some(b) => attach(&q[b], self.point_b),
            None => (Vec2::new(self.point_b[0], self.point_b[1]), Vec2::zeros()),
        };
        let d = pa - pb;
        let l = d.norm();
        (if l > 0.0 { d / l } else { Vec2::new(0.0, 1.0) }, l, ra, rb)
    }

    /// Relative normal velocity and strain of the spring in configuration `q`, `u`.
    fn state(&self, q: &[[f64; 3]], u: &[[f64; 3]]) -> (f64, f64, [f64; 3], [f64; 3]) {
        let (n, l, ra, rb) = self.geometry(q);
        let (ha, hb) = (gen_dir(ra, n), gen_dir(rb, n));
        let un = dot3(&ha, &u[self.a]) - self.b.map_or(0.0, |b| dot3(&hb, &u[b]));
        let eps = (l - self.rest_length) / self.rest_length - self.prestrain;
        (un, eps, ha, hb)
    }

    /// Force `R_N` (N) pushing the ends apart, in configuration `q`, `u`.
    pub fn force(&self, q: &[[f64; 3]], u: &[[f64; 3]]) -> f64 {
        let (un, eps, _, _) = self.state(q, u);
        let r = -self.k_n * eps - self.nu * un / self.rest_length;
        if self.compression_only {
            r.max(0.0)
        } else {
            r
        }
    }

    /// Elastic energy (J) in configuration `q`: `½ k_N L0 ε²`, the work of the
    /// elastic part `−k_N ε` of law (17) from `ε = 0` (0 for a compression-only
    /// spring in tension, `ε > 0`).
    pub fn elastic_energy(&self, q: &[[f64; 3]]) -> f64 {
        let eps = (self.length(q) - self.rest_length) / self.rest_length - self.prestrain;
        if self.compression_only && eps > 0.0 {
            0.0
        } else {
            0.5 * self.k_n * self.rest_length * eps * eps
        }
    }

    /// Unit axis from the second end to the first (`a`) in configuration `q`: a
    /// positive `R_N` pushes `a` along it.
    pub fn axis(&self, q: &[[f64; 3]]) -> [f64; 2] {
        let n = self.geometry(q).0;
        [n.x, n.y]
    }

    /// Current length (m).
    pub fn length(&self, q: &[[f64; 3]]) -> f64 {
        self.geometry(q).1
    }

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
        let alpha = (1.0 - theta) * r_i - theta * self.k_n * eps_m;
        let beta = theta * (self.k_n * theta * h + self.nu) / self.rest_length;
        SpringRow {
            a: self.a as u32,
            b: self.b.map_or(u32::MAX, |b| b as u32),
            hn_a,
            hn_b,
            w,
            p: self.impulse,
            h_alpha: h * alpha,
            h_beta: h * beta,
            compression_only: self.compression_only,
        }
    }
}

impl SpringRow {
    /// Exact local solution given `U_0`, the relative velocity without this row's impulse.
    #[inline(always)]
    pub fn solve(&self, u0: f64) -> f64 {
        let p = (self.h_alpha - self.h_beta * u0) / (1.0 + self.h_beta * self.w);
        if self.compression_only {
            p.max(0.0)
        } else {
            p
        }
    }
}
