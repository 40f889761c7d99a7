//! The 3D contact point as a row of the shared NSCD method ([`crate::nscd::method::Row`]): Signorini with the
//! gap prediction and restitution thresholds of the 2D row (`crate::nscd::contact`, Saussine et al. 2006 §2.3,
//! §2.8), and exact Coulomb friction on the 3D cone ([`super::cone::solve_near`], the slip searched from the row's last
//! one) over the 3×3 Delassus block.
//!
//! A contact point `p` with local frame `(n, t₁, t₂)` (n from the antagonist towards the candidate) maps a body's
//! generalised velocity `u = (v, ω)` — `ω` in the body's principal frame, `R` its rotation — to the relative
//! velocity by the rows of `H*`: for a direction `d`, `d · (v + R (ω × ρ)) = d · v + ω · (ρ × Rᵀ d)` with
//! `ρ = Rᵀ (p − x)` the lever arm in the body frame, so `h_d = (d, ρ × Rᵀ d)`. The candidate's rows count
//! positively, the antagonist's negatively: `U = H*_a u_a − H*_b u_b`, and an impulse `P` adds `M⁻¹ H_a P` to
//! `u_a` and subtracts `M⁻¹ H_b P` from `u_b`. The Delassus block is `W = H*_a M_a⁻¹ H_a + H*_b M_b⁻¹ H_b`.

use super::cone::{project_cone, project_disc, solve_near, Delassus3};
use crate::geometry::{Pose, Vec3};
use crate::nscd::contact::ContactLaw;
use crate::nscd::method::apgd::ConeRow;
use crate::nscd::method::{Row, SweepNorms};
use crate::space::bodies::Dofs6;

/// The solver's record of one 3D contact point: contiguous, everything one visit needs, the fields an open
/// point's visit reads (bodies, thresholds, impulse, the normal rows) in its first 120 bytes — two cache lines,
/// the record being aligned on them. The rows of `H*` are stored by their parts: a direction `d` of the frame
/// gives `h_d = (d, ρ × Rᵀ d)` on each body (the module doc), whose first half is the same `d` on both.
#[derive(Debug, Clone, Copy)]
#[repr(C, align(64))]
pub struct ContactRow3 {
    /// Candidate body.
    pub a: u32,
    /// Antagonist body.
    pub b: u32,
    /// The contact stays open when `U_0N ≥ s_open` (m/s): `−g_m / h` for a gap `g_m > 0` at `q_m`, else 0; under
    /// [`super::overlaps::Overlaps::Held`], `−(g_m − g_ref) / h` ([`super::overlaps::opening_threshold`]).
    pub s_open: f64,
    /// The normal velocity enforced once closed (m/s): `max(s_open, −e_n U_N⁻)`.
    pub c_closed: f64,
    /// Impulse `(P_N, P_T1, P_T2)` (N·s).
    pub p: [f64; 3],
    /// The normal `n` (world).
    pub n: [f64; 3],
    /// `ρ_a × R_aᵀ n`: the candidate's angular part of the normal row (m).
    pub an_a: [f64; 3],
    /// `ρ_b × R_bᵀ n`: the antagonist's (m).
    pub an_b: [f64; 3],
    /// The tangents `t₁`, `t₂` (world).
    pub t: [[f64; 3]; 2],
    /// The candidate's angular parts of the tangent rows (m).
    pub at_a: [[f64; 3]; 2],
    /// The antagonist's (m).
    pub at_b: [[f64; 3]; 2],
    /// The local Delassus block (1/kg), symmetric.
    pub w: Delassus3,
    /// `e_t U_T⁻` (m/s), added to the tangential velocity the law acts on.
    pub shift_t: [f64; 2],
    /// Coulomb friction coefficient.
    pub mu: f64,
}

// Six cache lines: the block's reciprocal pivots (`Delassus3`) filled the padding after `mu`; a field more
// would add a seventh line to every active visit.
const _: () = assert!(std::mem::size_of::<ContactRow3>() == 384);

pub use crate::space::bodies::{dot6, gen_dir};

#[inline(always)]
fn dot3(x: &[f64; 3], y: &[f64]) -> f64 {
    x[0] * y[0] + x[1] * y[1] + x[2] * y[2]
}

impl ContactRow3 {
    /// The row of a contact at point `point` (world) with the frame `frame = [n, t₁, t₂]` between candidate
    /// `a` at `pose_a` and antagonist `b` at `pose_b` (the intermediate configuration), their inverse masses and
    /// start-of-step velocities (for `U⁻`), the gap `gap` (m) at `q_m`, the time step `h` (s) and, under
    /// [`super::overlaps::Overlaps::Held`], the point's reference gap `held` (m; `None`: the velocity-level law).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        (a, b): (u32, u32),
        point: Vec3,
        frame: [Vec3; 3],
        (pose_a, pose_b): (&Pose, &Pose),
        (im_a, im_b): (&Dofs6, &Dofs6),
        (ua, ub): (&Dofs6, &Dofs6),
        gap: f64,
        h: f64,
        held: Option<f64>,
        law: &ContactLaw,
    ) -> Self {
        let rho_a = pose_a.rotation.inverse_transform_vector(&(point - pose_a.position));
        let rho_b = pose_b.rotation.inverse_transform_vector(&(point - pose_b.position));
        let h_a: [Dofs6; 3] = std::array::from_fn(|k| gen_dir(pose_a, &rho_a, &frame[k]));
        let h_b: [Dofs6; 3] = std::array::from_fn(|k| gen_dir(pose_b, &rho_b, &frame[k]));
        let wdot =
            |h: &[Dofs6; 3], im: &Dofs6, i: usize, j: usize| (0..6).map(|d| h[i][d] * im[d] * h[j][d]).sum::<f64>();
        let wm: [[f64; 3]; 3] =
            std::array::from_fn(|i| std::array::from_fn(|j| wdot(&h_a, im_a, i, j) + wdot(&h_b, im_b, i, j)));
        let minus: [f64; 3] = std::array::from_fn(|k| dot6(&h_a[k], ua) - dot6(&h_b[k], ub));
        let s_open = match held {
            Some(g_ref) => super::overlaps::opening_threshold(gap, g_ref, h),
            None if gap > 0.0 => -gap / h,
            None => 0.0,
        };
        let c_closed =
            if law.restitution_n > 0.0 && minus[0] < 0.0 { s_open.max(-law.restitution_n * minus[0]) } else { s_open };
        let lin = |k: usize| [frame[k].x, frame[k].y, frame[k].z];
        let ang = |h: &[Dofs6; 3], k: usize| [h[k][3], h[k][4], h[k][5]];
        Self {
            a,
            b,
            s_open,
            c_closed,
            p: [0.0; 3],
            n: lin(0),
            an_a: ang(&h_a, 0),
            an_b: ang(&h_b, 0),
            t: [lin(1), lin(2)],
            at_a: [ang(&h_a, 1), ang(&h_a, 2)],
            at_b: [ang(&h_b, 1), ang(&h_b, 2)],
            w: Delassus3::new(wm),
            shift_t: [law.restitution_t * minus[1], law.restitution_t * minus[2]],
            mu: law.friction,
        }
    }

    /// The normal relative velocity `U_N` (m/s), the first component of [`Self::local_velocity`].
    #[inline(always)]
    pub fn normal_velocity(&self, u: &[Dofs6]) -> f64 {
        self.normal_of(&u[self.a as usize], &u[self.b as usize])
    }

    #[inline(always)]
    fn normal_of(&self, ua: &Dofs6, ub: &Dofs6) -> f64 {
        let dv = [ua[0] - ub[0], ua[1] - ub[1], ua[2] - ub[2]];
        dot3(&self.n, &dv) + dot3(&self.an_a, &ua[3..]) - dot3(&self.an_b, &ub[3..])
    }

    /// The relative velocity `H*_a u_a − H*_b u_b` in the local frame (m/s).
    #[inline(always)]
    pub fn local_velocity(&self, u: &[Dofs6]) -> [f64; 3] {
        let (ua, ub) = (&u[self.a as usize], &u[self.b as usize]);
        let dv = [ua[0] - ub[0], ua[1] - ub[1], ua[2] - ub[2]];
        let tangent = |k: usize| dot3(&self.t[k], &dv) + dot3(&self.at_a[k], &ua[3..]) - dot3(&self.at_b[k], &ub[3..]);
        [self.normal_of(ua, ub), tangent(0), tangent(1)]
    }

    /// Adds `sign · M⁻¹ H p` to the candidate and subtracts it from the antagonist.
    #[inline(always)]
    fn apply(&self, u: &mut [Dofs6], inv_m: &[Dofs6], p: [f64; 3], sign: f64) {
        let (n, t) = (&self.n, &self.t);
        let force: [f64; 3] = std::array::from_fn(|d| sign * (n[d] * p[0] + t[0][d] * p[1] + t[1][d] * p[2]));
        for (body, an, at, s) in [(self.a, &self.an_a, &self.at_a, 1.0), (self.b, &self.an_b, &self.at_b, -1.0)] {
            let (ub, im) = (&mut u[body as usize], &inv_m[body as usize]);
            for d in 0..3 {
                ub[d] += s * im[d] * force[d];
                ub[d + 3] += s * sign * im[d + 3] * (an[d] * p[0] + at[0][d] * p[1] + at[1][d] * p[2]);
            }
        }
    }
}

/// The norms of one 3D contact whose impulse goes from `p` to `q` (N·s) under its block `w`, with `wp = W p`
/// ([`SweepNorms::add`]): `ΔU = W (q − p)`, `P̄ = ½ (p + q)`, and the midpoint averages of `P·WP` and `|WP|²`.
#[inline(always)]
fn add_norms(norms: &mut SweepNorms, w: &Delassus3, p: [f64; 3], wp: [f64; 3], q: [f64; 3], changed: bool) {
    let d3 = |x: &[f64; 3], y: &[f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    let du = w.apply(std::array::from_fn(|k| q[k] - p[k]));
    let wq: [f64; 3] = std::array::from_fn(|k| wp[k] + du[k]);
    let pm: [f64; 3] = std::array::from_fn(|k| 0.5 * (p[k] + q[k]));
    let wqq = d3(&q, &wq);
    norms.add(
        d3(&du, &du),
        d3(&pm, &pm),
        d3(&pm, &du),
        0.5 * (d3(&p, &wp) + wqq),
        0.5 * (d3(&wp, &wp) + d3(&wq, &wq)),
        wqq,
        changed,
    );
}

impl Row for ContactRow3 {
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
        if self.p == [0.0; 3] {
            // An open point that stays open (most of a packing's points within the alert distance): its normal
            // velocity alone decides it, and nothing changes — the law, the update and the norms all give zero.
            let un = self.normal_velocity(u);
            if un >= self.s_open || self.c_closed - un <= 0.0 {
                return;
            }
        }
        let v = self.local_velocity(u);
        let p = self.p;
        let wp = self.w.apply(p);
        let u0 = [v[0] - wp[0], v[1] - wp[1] + self.shift_t[0], v[2] - wp[2] + self.shift_t[1]];
        let mut q = solve_near(&self.w, u0, self.s_open, self.c_closed, self.mu, p);
        if omega != 1.0 {
            q = project_cone(std::array::from_fn(|k| p[k] + omega * (q[k] - p[k])), self.mu);
        }
        let dp: [f64; 3] = std::array::from_fn(|k| q[k] - p[k]);
        let changed = dp.iter().any(|&d| d != 0.0);
        if UPDATE && changed {
            self.p = q;
            self.apply(u, inv_m, dp, 1.0);
        }
        add_norms(norms, &self.w, p, wp, q, changed);
    }
}

/// The largest eigenvalue of a symmetric 3×3 block (1/kg), in closed form (the trigonometric solution of the
/// characteristic cubic).
fn lambda_max3(m: &[[f64; 3]; 3]) -> f64 {
    let off = m[0][1] * m[0][1] + m[0][2] * m[0][2] + m[1][2] * m[1][2];
    let q = (m[0][0] + m[1][1] + m[2][2]) / 3.0;
    let dev = [m[0][0] - q, m[1][1] - q, m[2][2] - q];
    let p = ((dev[0] * dev[0] + dev[1] * dev[1] + dev[2] * dev[2] + 2.0 * off) / 6.0).sqrt();
    if p.is_nan() || p <= 0.0 {
        return q; // a multiple of the identity (or not finite: q carries it)
    }
    let b = |i: usize, j: usize| if i == j { dev[i] / p } else { m[i][j] / p };
    let det = b(0, 0) * (b(1, 1) * b(2, 2) - b(1, 2) * b(1, 2)) - b(0, 1) * (b(0, 1) * b(2, 2) - b(1, 2) * b(0, 2))
        + b(0, 2) * (b(0, 1) * b(1, 2) - b(1, 1) * b(0, 2));
    let phi = (0.5 * det).clamp(-1.0, 1.0).acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

/// The 3D contact in the accelerated projected gradient ([`crate::nscd::method::apgd`]): `(P_N, P_T1, P_T2)`
/// projected on `P_N ≥ 0` and the disc `|P_T| ≤ g_α` (the 2D row's interval turned about the normal).
impl ConeRow for ContactRow3 {
    type Impulse = [f64; 3];

    #[inline(always)]
    fn impulse(&self) -> [f64; 3] {
        self.p
    }

    #[inline(always)]
    fn set_impulse(&mut self, p: [f64; 3]) {
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
    fn local_velocity(&self, u: &[Dofs6]) -> [f64; 3] {
        ContactRow3::local_velocity(self, u)
    }

    #[inline(always)]
    fn gradient(&self, v: [f64; 3], c: f64) -> [f64; 3] {
        [v[0] - c, v[1] + self.shift_t[0], v[2] + self.shift_t[1]]
    }

    /// `c_closed` for a contact whose `U_0N < s_open`, `s_open` otherwise (`c_closed` when the two agree).
    #[inline]
    fn label(&self, u: &[Dofs6]) -> f64 {
        if self.s_open >= self.c_closed {
            return self.c_closed;
        }
        let u0n = self.normal_velocity(u) - self.w.apply(self.p)[0];
        if u0n < self.s_open {
            self.c_closed
        } else {
            self.s_open
        }
    }

    #[inline(always)]
    fn diagonal(&self) -> [f64; 3] {
        [self.w.m[0][0], self.w.m[1][1], self.w.m[2][2]]
    }

    fn lambda_max(&self) -> f64 {
        lambda_max3(&self.w.m)
    }

    #[inline(always)]
    fn project(&self, x: [f64; 3], tresca: Option<f64>) -> [f64; 3] {
        project_disc(x, tresca.unwrap_or(self.mu * x[0].max(0.0)))
    }

    #[inline(always)]
    fn add_impulse_of(&self, u: &mut [Dofs6], inv_m: &[Dofs6], p: [f64; 3], sign: f64) {
        self.apply(u, inv_m, p, sign);
    }

    #[inline(always)]
    fn add_norms(&self, norms: &mut SweepNorms, p: [f64; 3], q: [f64; 3], changed: bool) {
        add_norms(norms, &self.w, p, self.w.apply(p), q, changed);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The closed form against the characteristic polynomial and nalgebra's symmetric eigensolver.
    #[test]
    fn the_largest_eigenvalue_of_a_block() {
        let blocks = [
            [[2.0, 0.0, 0.0], [0.0, 2.0, 0.0], [0.0, 0.0, 2.0]],
            [[3.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 2.0]],
            [[4.0, 1.0, -0.5], [1.0, 3.0, 0.25], [-0.5, 0.25, 1.0]],
            [[1e-3, 2e-4, 0.0], [2e-4, 5e-4, 1e-4], [0.0, 1e-4, 5e-4]],
            [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]],
        ];
        for m in blocks {
            let expected = nalgebra::Matrix3::from_fn(|i, j| m[i][j]).symmetric_eigenvalues().max();
            let got = lambda_max3(&m);
            // Round-off of a dozen operations on entries of the block's size.
            assert!((got - expected).abs() <= 1e-12 * expected.abs().max(m[0][0]), "{m:?}: {got} vs {expected}");
        }
    }
}
