//! The stages of one APGD solve ([`super::solve_apgd_with`]): the set-up of the free velocities, labels and step
//! scales, the gradient (one gather), the projected step with backtracking on the Lipschitz estimate (one
//! scatter per try), the proxy norms and restart test, Nesterov's extrapolation, the outer updates of the labels
//! and Tresca bounds, and the last recomputation of the velocities. The method and its equations: the module
//! text of [`super`]. On the 2D law: the rows' impulses `(P_N, P_T)` are projected on `P_N ≥ 0`, `|P_T| ≤ g_α`.

use super::{ApgdOptions, FrictionBound};
use crate::nscd::contact::{add_contact_norms, apply, dot3, ContactRow};
use crate::nscd::criterion::SweepNorms;
use crate::nscd::sublayer::SpringRow;

/// Buffers of [`super::solve_apgd_with`], kept from call to call (sized at the start of
/// a call; nothing is allocated inside the iterations).
#[derive(Debug, Clone, Default)]
pub struct ApgdWorkspace {
    /// Free velocities `u_free` of the bodies.
    pub(super) u_free: Vec<[f64; 3]>,
    /// Body velocities of the extrapolated point `y`.
    pub(super) uy: Vec<[f64; 3]>,
    /// Body velocities of the previous iterate.
    pub(super) u_prev: Vec<[f64; 3]>,
    /// Extrapolated point, previous iterate, gradient at `y`, step scales of the contacts.
    pub(super) y: Vec<[f64; 2]>,
    pub(super) x_prev: Vec<[f64; 2]>,
    pub(super) g: Vec<[f64; 2]>,
    pub(super) scale: Vec<[f64; 2]>,
    /// Normal threshold `c_α` and friction bound `g_α` (Outer) of the contacts.
    pub(super) c: Vec<f64>,
    pub(super) bound: Vec<f64>,
    /// The same for the springs.
    pub(super) ys: Vec<f64>,
    pub(super) xs_prev: Vec<f64>,
    pub(super) gs: Vec<f64>,
    pub(super) scale_s: Vec<f64>,
    /// Best checked iterate (contacts, springs), returned if the cap is reached.
    pub(super) best: Vec<[f64; 2]>,
    pub(super) best_s: Vec<f64>,
}

/// Adds `sign · M⁻¹ H P` of every row to `u`, `P` being the rows' or the given impulses.
pub(super) fn scatter(
    u: &mut [[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &[ContactRow],
    springs: &[SpringRow],
    dp: Option<(&[[f64; 2]], &[f64])>,
    sign: f64,
) {
    for (j, s) in springs.iter().enumerate() {
        let p = s.p - dp.map_or(0.0, |d| d.1[j]);
        if p == 0.0 {
            continue;
        }
        apply(&mut u[s.a as usize], &inv_m[s.a as usize], &s.hn_a, p, &[0.0; 3], 0.0, sign);
        if s.b != u32::MAX {
            apply(&mut u[s.b as usize], &inv_m[s.b as usize], &s.hn_b, p, &[0.0; 3], 0.0, -sign);
        }
    }
    for (i, r) in rows.iter().enumerate() {
        let (pn, pt) = match dp {
            Some(d) => (r.p[0] - d.0[i][0], r.p[1] - d.0[i][1]),
            None => (r.p[0], r.p[1]),
        };
        if pn == 0.0 && pt == 0.0 {
            continue;
        }
        apply(&mut u[r.a as usize], &inv_m[r.a as usize], &r.hn_a, pn, &r.ht_a, pt, sign);
        apply(&mut u[r.b as usize], &inv_m[r.b as usize], &r.hn_b, pn, &r.ht_b, pt, -sign);
    }
}

/// Local velocities `(U_N, U_T)` of a contact (without threshold and shift).
#[inline(always)]
fn local(r: &ContactRow, u: &[[f64; 3]]) -> (f64, f64) {
    let (ua, ub) = (&u[r.a as usize], &u[r.b as usize]);
    (dot3(&r.hn_a, ua) - dot3(&r.hn_b, ub), dot3(&r.ht_a, ua) - dot3(&r.ht_b, ub))
}

/// Axial relative velocity of a spring.
#[inline(always)]
fn local_s(s: &SpringRow, u: &[[f64; 3]]) -> f64 {
    let mut un = dot3(&s.hn_a, &u[s.a as usize]);
    if s.b != u32::MAX {
        un -= dot3(&s.hn_b, &u[s.b as usize]);
    }
    un
}

/// Threshold label of a contact from the current iterate (see the module text).
#[inline]
fn label(r: &ContactRow, u: &[[f64; 3]]) -> f64 {
    if r.s_open >= r.c_closed {
        return r.c_closed;
    }
    let u0n = local(r, u).0 - (r.w.nn * r.p[0] + r.w.nt * r.p[1]);
    if u0n < r.s_open {
        r.c_closed
    } else {
        r.s_open
    }
}

/// Largest eigenvalue of a symmetric 2×2 block.
fn lambda_max(nn: f64, nt: f64, tt: f64) -> f64 {
    0.5 * (nn + tt) + (0.25 * (nn - tt) * (nn - tt) + nt * nt).sqrt()
}

impl ApgdWorkspace {
    /// The set-up (one scatter): fixes the impulse of springs without stiffness nor damping, stores the free
    /// velocities, labels the contacts and sets their Tresca bounds and the step scales; returns the first
    /// Lipschitz estimate `L`.
    pub(super) fn set_up(
        &mut self,
        opts: &ApgdOptions,
        u: &mut [[f64; 3]],
        inv_m: &[[f64; 3]],
        rows: &[ContactRow],
        springs: &mut [SpringRow],
    ) -> f64 {
        let ws = self;
        let (n, m, nb) = (rows.len(), springs.len(), u.len());
        ws.u_free.clear();
        ws.u_free.extend_from_slice(u);
        // A spring without stiffness nor damping has a fixed impulse.
        for sp in springs.iter_mut().filter(|sp| sp.h_beta <= 0.0) {
            let p = sp.solve(0.0);
            let dp = p - sp.p;
            sp.p = p;
            apply(&mut u[sp.a as usize], &inv_m[sp.a as usize], &sp.hn_a, dp, &[0.0; 3], 0.0, 1.0);
            if sp.b != u32::MAX {
                apply(&mut u[sp.b as usize], &inv_m[sp.b as usize], &sp.hn_b, dp, &[0.0; 3], 0.0, -1.0);
            }
        }
        ws.u_free.copy_from_slice(u);
        scatter(&mut ws.u_free, inv_m, rows, springs, None, -1.0);
        ws.c.clear();
        ws.c.extend(rows.iter().map(|r| label(r, u)));
        ws.bound.clear();
        ws.bound.extend(rows.iter().map(|r| r.mu * r.p[0].max(0.0)));
        let inv = |w: f64| if w > 0.0 { 1.0 / w } else { 0.0 };
        let on = |w: f64| if w > 0.0 { 1.0 } else { 0.0 };
        ws.scale.clear();
        ws.scale_s.clear();
        let mut l = if opts.precondition { 1.0 } else { 0.0 };
        for r in rows.iter() {
            if opts.precondition {
                ws.scale.push([inv(r.w.nn), inv(r.w.tt)]);
            } else {
                ws.scale.push([on(r.w.nn), on(r.w.tt)]);
                l = f64::max(l, lambda_max(r.w.nn, r.w.nt, r.w.tt));
            }
        }
        for sp in springs.iter() {
            let d = if sp.h_beta > 0.0 { sp.w + 1.0 / sp.h_beta } else { 0.0 };
            if opts.precondition {
                ws.scale_s.push(inv(d));
            } else {
                ws.scale_s.push(on(d));
                l = l.max(d);
            }
        }
        if l.is_nan() || l <= 0.0 {
            l = 1.0;
        }
        ws.y.clear();
        ws.y.extend(rows.iter().map(|r| r.p));
        ws.x_prev.clone_from(&ws.y);
        ws.g.clear();
        ws.g.resize(n, [0.0; 2]);
        ws.ys.clear();
        ws.ys.extend(springs.iter().map(|sp| sp.p));
        ws.xs_prev.clone_from(&ws.ys);
        ws.gs.clear();
        ws.gs.resize(m, 0.0);
        ws.uy.clear();
        ws.uy.extend_from_slice(u);
        ws.u_prev.clone_from(&ws.uy);
        debug_assert_eq!(ws.uy.len(), nb);
        l
    }

    /// The gradient at the extrapolated point `y` (one gather: the local velocities), and the iterate kept as
    /// the previous one.
    pub(super) fn gradient(&mut self, u: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
        let ws = self;
        for (i, r) in rows.iter().enumerate() {
            let (un, ut) = local(r, &ws.uy);
            ws.g[i] = [un - ws.c[i], ut + r.shift_t];
        }
        for (j, sp) in springs.iter().enumerate() {
            ws.gs[j] = if sp.h_beta > 0.0 { local_s(sp, &ws.uy) + (ws.ys[j] - sp.h_alpha) / sp.h_beta } else { 0.0 };
        }
        for (xp, r) in ws.x_prev.iter_mut().zip(rows.iter()) {
            *xp = r.p;
        }
        for (xp, sp) in ws.xs_prev.iter_mut().zip(springs.iter()) {
            *xp = sp.p;
        }
        ws.u_prev.copy_from_slice(u);
    }

    /// The projected step from `y` with backtracking on `l` (one scatter per try, counted in `halves`, which
    /// stops the tries at `cap`): the rows' impulses and `u` become the new iterate.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn projected_step(
        &self,
        opts: &ApgdOptions,
        l: &mut f64,
        (halves, cap): (&mut usize, usize),
        u: &mut [[f64; 3]],
        inv_m: &[[f64; 3]],
        rows: &mut [ContactRow],
        springs: &mut [SpringRow],
    ) {
        let ws = self;
        loop {
            let t = 1.0 / *l;
            let mut norm2 = 0.0; // |x − y|² in the metric of the step scales
            for (i, r) in rows.iter_mut().enumerate() {
                let ([yn, yt], [gn, gt], [sn, st]) = (ws.y[i], ws.g[i], ws.scale[i]);
                let pn = (yn - t * sn * gn).max(0.0);
                let bound = match opts.friction {
                    FrictionBound::Iterate => r.mu * pn,
                    FrictionBound::Outer => ws.bound[i],
                };
                let pt = (yt - t * st * gt).clamp(-bound, bound);
                r.p = [pn, pt];
                let (dn, dt) = (pn - yn, pt - yt);
                if sn > 0.0 {
                    norm2 += dn * dn / sn;
                }
                if st > 0.0 {
                    norm2 += dt * dt / st;
                }
            }
            let mut quad = 0.0; // (x − y)ᵀ N (x − y), springs' diagonal term included
            for (j, sp) in springs.iter_mut().enumerate() {
                let (yj, sj) = (ws.ys[j], ws.scale_s[j]);
                if sj == 0.0 {
                    continue;
                }
                let mut p = yj - t * sj * ws.gs[j];
                if sp.compression_only {
                    p = p.max(0.0);
                }
                sp.p = p;
                let d = p - yj;
                norm2 += d * d / sj;
                quad += d * d / sp.h_beta;
            }
            u.copy_from_slice(&ws.uy);
            scatter(u, inv_m, rows, springs, Some((&ws.y, &ws.ys)), 1.0);
            *halves += 1;
            for ((ux, uy), im) in u.iter().zip(&ws.uy).zip(inv_m) {
                for d in 0..3 {
                    if im[d] > 0.0 {
                        let du = ux[d] - uy[d];
                        quad += du * du / im[d];
                    }
                }
            }
            // f(x) ≤ f(y) + ∇f(y)·(x − y) + L/2 |x − y|², f quadratic.
            if quad <= *l * norm2 * (1.0 + 1e-12) || norm2 == 0.0 || *halves >= cap {
                break;
            }
            *l *= 2.0;
        }
    }

    /// The proxy norms (the policy's norms of the change of the iterate over the iteration) and the restart test's
    /// product (the gradient mapping against the last move; positive: restart).
    pub(super) fn proxy(&self, rows: &[ContactRow], springs: &[SpringRow]) -> (SweepNorms, f64) {
        let ws = self;
        let mut proxy = SweepNorms::default();
        let mut restart_dot = 0.0;
        for (i, r) in rows.iter().enumerate() {
            let ([pn, pt], [qn, qt], [yn, yt], [sn, st]) = (ws.x_prev[i], r.p, ws.y[i], ws.scale[i]);
            let w = r.w;
            let (dn, dt) = (qn - pn, qt - pt);
            if sn > 0.0 {
                restart_dot += (yn - qn) * dn / sn;
            }
            if st > 0.0 {
                restart_dot += (yt - qt) * dt / st;
            }
            add_contact_norms(&mut proxy, w, [pn, pt], [qn, qt], dn != 0.0 || dt != 0.0);
        }
        for (j, sp) in springs.iter().enumerate() {
            let (p_old, p, sj) = (ws.xs_prev[j], sp.p, ws.scale_s[j]);
            let dp = p - p_old;
            if sj > 0.0 {
                restart_dot += (ws.ys[j] - p) * dp / sj;
            }
            let du = sp.w * dp;
            let pm = 0.5 * (p_old + p);
            proxy.add(
                du * du,
                pm * pm,
                pm * du,
                0.5 * sp.w * (p_old * p_old + p * p),
                0.5 * sp.w * sp.w * (p_old * p_old + p * p),
                sp.w * p * p,
                dp != 0.0,
            );
        }
        (proxy, restart_dot)
    }

    /// Nesterov's extrapolation from the momentum `theta`; returns the next `theta`.
    pub(super) fn extrapolate(
        &mut self,
        theta: f64,
        u: &[[f64; 3]],
        rows: &[ContactRow],
        springs: &[SpringRow],
    ) -> f64 {
        let ws = self;
        let t2 = theta * theta;
        let theta_new = 0.5 * (-t2 + theta * (t2 + 4.0).sqrt());
        let beta = theta * (1.0 - theta) / (t2 + theta_new);
        for (i, r) in rows.iter().enumerate() {
            let xp = ws.x_prev[i];
            ws.y[i] = [r.p[0] + beta * (r.p[0] - xp[0]), r.p[1] + beta * (r.p[1] - xp[1])];
        }
        for (j, sp) in springs.iter().enumerate() {
            ws.ys[j] = sp.p + beta * (sp.p - ws.xs_prev[j]);
        }
        for ((uy, ux), up) in ws.uy.iter_mut().zip(u.iter()).zip(&ws.u_prev) {
            for d in 0..3 {
                uy[d] = ux[d] + beta * (ux[d] - up[d]);
            }
        }
        theta_new
    }

    /// Momentum dropped: `y = x`.
    pub(super) fn restart(&mut self, u: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
        for (y, r) in self.y.iter_mut().zip(rows) {
            *y = r.p;
        }
        for (y, sp) in self.ys.iter_mut().zip(springs) {
            *y = sp.p;
        }
        self.uy.copy_from_slice(u);
    }

    /// Keeps the current iterate as the best checked one.
    pub(super) fn keep_best(&mut self, rows: &[ContactRow], springs: &[SpringRow]) {
        self.best.clear();
        self.best.extend(rows.iter().map(|r| r.p));
        self.best_s.clear();
        self.best_s.extend(springs.iter().map(|sp| sp.p));
    }

    /// Takes back the best checked iterate's impulses.
    pub(super) fn take_best(&self, rows: &mut [ContactRow], springs: &mut [SpringRow]) {
        for (r, p) in rows.iter_mut().zip(&self.best) {
            r.p = *p;
        }
        for (sp, p) in springs.iter_mut().zip(&self.best_s) {
            sp.p = *p;
        }
    }

    /// The outer updates after a failed check: threshold labels from the iterate and, for
    /// [`FrictionBound::Outer`], the Tresca bounds `μ P_N`; whether any changed.
    pub(super) fn outer_update(&mut self, opts: &ApgdOptions, u: &[[f64; 3]], rows: &[ContactRow]) -> bool {
        let ws = self;
        let mut changed = false;
        for (i, r) in rows.iter().enumerate() {
            let c = label(r, u);
            changed |= c != ws.c[i];
            ws.c[i] = c;
        }
        if opts.friction == FrictionBound::Outer {
            for (i, r) in rows.iter().enumerate() {
                let b = r.mu * r.p[0];
                changed |= b != ws.bound[i];
                ws.bound[i] = b;
            }
        }
        changed
    }

    /// The velocities recomputed from the free ones and the impulses (no drift of the increments; one scatter).
    pub(super) fn recompute(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
        u.copy_from_slice(&self.u_free);
        scatter(u, inv_m, rows, springs, None, 1.0);
    }
}
