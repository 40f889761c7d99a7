//! The stages of one APGD solve ([`super::solve_apgd_with`]): the set-up of the free velocities, labels and step
//! scales, the gradient (one gather), the projected step with backtracking on the Lipschitz estimate (one
//! scatter per try), the proxy norms and restart test, Nesterov's extrapolation, the outer updates of the labels
//! and Tresca bounds, and the last recomputation of the velocities. The method and its equations: the module
//! text of [`super`]. The contacts' impulses are projected by their law ([`ConeRow::project`]); the springs are
//! in the quadratic with their diagonal term `1/hβ`.

use super::{AffineRow, ApgdOptions, ConeRow, FrictionBound};
use crate::nscd::method::SweepNorms;

/// Buffers of [`super::solve_apgd_with`] for contact rows `R`, kept from call to call (sized at the start of a
/// call; nothing is allocated inside the iterations).
#[derive(Debug, Clone)]
pub struct ApgdWorkspace<R: ConeRow> {
    /// Free velocities `u_free` of the bodies.
    pub(super) u_free: Vec<R::Dofs>,
    /// Body velocities of the extrapolated point `y`.
    pub(super) uy: Vec<R::Dofs>,
    /// Body velocities of the previous iterate.
    pub(super) u_prev: Vec<R::Dofs>,
    /// Extrapolated point, previous iterate, gradient at `y`, step scales of the contacts.
    pub(super) y: Vec<R::Impulse>,
    pub(super) x_prev: Vec<R::Impulse>,
    pub(super) g: Vec<R::Impulse>,
    pub(super) scale: Vec<R::Impulse>,
    /// Normal threshold `c_α` and friction bound `g_α` (Outer) of the contacts.
    pub(super) c: Vec<f64>,
    pub(super) bound: Vec<f64>,
    /// The same for the springs.
    pub(super) ys: Vec<f64>,
    pub(super) xs_prev: Vec<f64>,
    pub(super) gs: Vec<f64>,
    pub(super) scale_s: Vec<f64>,
    /// Best checked iterate (contacts, springs), returned if the cap is reached.
    pub(super) best: Vec<R::Impulse>,
    pub(super) best_s: Vec<f64>,
}

impl<R: ConeRow> Default for ApgdWorkspace<R> {
    fn default() -> Self {
        Self {
            u_free: Vec::new(),
            uy: Vec::new(),
            u_prev: Vec::new(),
            y: Vec::new(),
            x_prev: Vec::new(),
            g: Vec::new(),
            scale: Vec::new(),
            c: Vec::new(),
            bound: Vec::new(),
            ys: Vec::new(),
            xs_prev: Vec::new(),
            gs: Vec::new(),
            scale_s: Vec::new(),
            best: Vec::new(),
            best_s: Vec::new(),
        }
    }
}

/// `a − b`, component by component.
#[inline(always)]
fn minus<I: Copy + AsMut<[f64]> + AsRef<[f64]>>(mut a: I, b: &I) -> I {
    for (x, y) in a.as_mut().iter_mut().zip(b.as_ref()) {
        *x -= *y;
    }
    a
}

/// Adds `sign · M⁻¹ H P` of every row to `u`, `P` being the rows' impulses, less the given ones if any.
pub(super) fn scatter<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &[R],
    springs: &[S],
    dp: Option<(&[R::Impulse], &[f64])>,
    sign: f64,
) {
    for (j, s) in springs.iter().enumerate() {
        let p = s.impulse() - dp.map_or(0.0, |d| d.1[j]);
        if p == 0.0 {
            continue;
        }
        s.add_impulse_of(u, inv_m, p, sign);
    }
    for (i, r) in rows.iter().enumerate() {
        let p = match dp {
            Some(d) => minus(r.impulse(), &d.0[i]),
            None => r.impulse(),
        };
        if p.as_ref().iter().all(|&x| x == 0.0) {
            continue;
        }
        r.add_impulse_of(u, inv_m, p, sign);
    }
}

impl<R: ConeRow> ApgdWorkspace<R> {
    /// The set-up (one scatter): fixes the impulse of springs without stiffness nor damping, stores the free
    /// velocities, labels the contacts and sets their Tresca bounds and the step scales; returns the first
    /// Lipschitz estimate `L`.
    pub(super) fn set_up<S: AffineRow<Dofs = R::Dofs>>(
        &mut self,
        opts: &ApgdOptions,
        u: &mut [R::Dofs],
        inv_m: &[R::Dofs],
        rows: &[R],
        springs: &mut [S],
    ) -> f64 {
        let ws = self;
        let (n, m, nb) = (rows.len(), springs.len(), u.len());
        ws.u_free.clear();
        ws.u_free.extend_from_slice(u);
        // A spring without stiffness nor damping has a fixed impulse.
        for sp in springs.iter_mut().filter(|sp| sp.h_beta() <= 0.0) {
            let p = sp.solve_affine(0.0);
            let dp = p - sp.impulse();
            sp.set_impulse(p);
            sp.add_impulse_of(u, inv_m, dp, 1.0);
        }
        ws.u_free.copy_from_slice(u);
        scatter(&mut ws.u_free, inv_m, rows, springs, None, -1.0);
        ws.c.clear();
        ws.c.extend(rows.iter().map(|r| r.label(u)));
        ws.bound.clear();
        ws.bound.extend(rows.iter().map(|r| r.mu() * r.normal().max(0.0)));
        let inv = |w: f64| if w > 0.0 { 1.0 / w } else { 0.0 };
        let on = |w: f64| if w > 0.0 { 1.0 } else { 0.0 };
        ws.scale.clear();
        ws.scale_s.clear();
        let mut l = if opts.precondition { 1.0 } else { 0.0 };
        for r in rows.iter() {
            let mut s = r.diagonal();
            if opts.precondition {
                s.as_mut().iter_mut().for_each(|w| *w = inv(*w));
            } else {
                s.as_mut().iter_mut().for_each(|w| *w = on(*w));
                l = f64::max(l, r.lambda_max());
            }
            ws.scale.push(s);
        }
        for sp in springs.iter() {
            let d = if sp.h_beta() > 0.0 { sp.w() + 1.0 / sp.h_beta() } else { 0.0 };
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
        ws.y.extend(rows.iter().map(|r| r.impulse()));
        ws.x_prev.clone_from(&ws.y);
        ws.g.clear();
        ws.g.resize(n, R::Impulse::default());
        ws.ys.clear();
        ws.ys.extend(springs.iter().map(|sp| sp.impulse()));
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
    pub(super) fn gradient<S: AffineRow<Dofs = R::Dofs>>(&mut self, u: &[R::Dofs], rows: &[R], springs: &[S]) {
        let ws = self;
        for (i, r) in rows.iter().enumerate() {
            ws.g[i] = r.gradient(r.local_velocity(&ws.uy), ws.c[i]);
        }
        for (j, sp) in springs.iter().enumerate() {
            let (h_alpha, h_beta) = (sp.h_alpha(), sp.h_beta());
            ws.gs[j] = if h_beta > 0.0 { sp.axial_velocity(&ws.uy) + (ws.ys[j] - h_alpha) / h_beta } else { 0.0 };
        }
        for (xp, r) in ws.x_prev.iter_mut().zip(rows.iter()) {
            *xp = r.impulse();
        }
        for (xp, sp) in ws.xs_prev.iter_mut().zip(springs.iter()) {
            *xp = sp.impulse();
        }
        ws.u_prev.copy_from_slice(u);
    }

    /// The projected step from `y` with backtracking on `l` (one scatter per try, counted in `halves`, which
    /// stops the tries at `cap`): the rows' impulses and `u` become the new iterate.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn projected_step<S: AffineRow<Dofs = R::Dofs>>(
        &self,
        opts: &ApgdOptions,
        l: &mut f64,
        (halves, cap): (&mut usize, usize),
        u: &mut [R::Dofs],
        inv_m: &[R::Dofs],
        rows: &mut [R],
        springs: &mut [S],
    ) {
        let ws = self;
        loop {
            let t = 1.0 / *l;
            let mut norm2 = 0.0; // |x − y|² in the metric of the step scales
            for (i, r) in rows.iter_mut().enumerate() {
                let (y, g, s) = (ws.y[i], ws.g[i], ws.scale[i]);
                let mut x = y;
                for ((x, g), s) in x.as_mut().iter_mut().zip(g.as_ref()).zip(s.as_ref()) {
                    *x -= t * s * g;
                }
                let tresca = match opts.friction {
                    FrictionBound::Iterate => None,
                    FrictionBound::Outer => Some(ws.bound[i]),
                };
                let p = r.project(x, tresca);
                r.set_impulse(p);
                for ((p, y), s) in p.as_ref().iter().zip(y.as_ref()).zip(s.as_ref()) {
                    let d = p - y;
                    if *s > 0.0 {
                        norm2 += d * d / s;
                    }
                }
            }
            let mut quad = 0.0; // (x − y)ᵀ N (x − y), springs' diagonal term included
            for (j, sp) in springs.iter_mut().enumerate() {
                let (yj, sj) = (ws.ys[j], ws.scale_s[j]);
                if sj == 0.0 {
                    continue;
                }
                let mut p = yj - t * sj * ws.gs[j];
                if sp.compression_only() {
                    p = p.max(0.0);
                }
                sp.set_impulse(p);
                let d = p - yj;
                norm2 += d * d / sj;
                quad += d * d / sp.h_beta();
            }
            u.copy_from_slice(&ws.uy);
            scatter(u, inv_m, rows, springs, Some((&ws.y, &ws.ys)), 1.0);
            *halves += 1;
            for ((ux, uy), im) in u.iter().zip(&ws.uy).zip(inv_m) {
                for ((x, y), im) in ux.as_ref().iter().zip(uy.as_ref()).zip(im.as_ref()) {
                    if *im > 0.0 {
                        let du = x - y;
                        quad += du * du / im;
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
    pub(super) fn proxy<S: AffineRow<Dofs = R::Dofs>>(&self, rows: &[R], springs: &[S]) -> (SweepNorms, f64) {
        let ws = self;
        let mut proxy = SweepNorms::default();
        let mut restart_dot = 0.0;
        for (i, r) in rows.iter().enumerate() {
            let (p, q, y, s) = (ws.x_prev[i], r.impulse(), ws.y[i], ws.scale[i]);
            let mut changed = false;
            for (((p, q), y), s) in p.as_ref().iter().zip(q.as_ref()).zip(y.as_ref()).zip(s.as_ref()) {
                let d = q - p;
                if *s > 0.0 {
                    restart_dot += (y - q) * d / s;
                }
                changed |= d != 0.0;
            }
            r.add_norms(&mut proxy, p, q, changed);
        }
        for (j, sp) in springs.iter().enumerate() {
            let (p_old, p, sj) = (ws.xs_prev[j], sp.impulse(), ws.scale_s[j]);
            let dp = p - p_old;
            if sj > 0.0 {
                restart_dot += (ws.ys[j] - p) * dp / sj;
            }
            let w = sp.w();
            let du = w * dp;
            let pm = 0.5 * (p_old + p);
            proxy.add(
                du * du,
                pm * pm,
                pm * du,
                0.5 * w * (p_old * p_old + p * p),
                0.5 * w * w * (p_old * p_old + p * p),
                w * p * p,
                dp != 0.0,
            );
        }
        (proxy, restart_dot)
    }

    /// Nesterov's extrapolation from the momentum `theta`; returns the next `theta`.
    pub(super) fn extrapolate<S: AffineRow<Dofs = R::Dofs>>(
        &mut self,
        theta: f64,
        u: &[R::Dofs],
        rows: &[R],
        springs: &[S],
    ) -> f64 {
        let ws = self;
        let t2 = theta * theta;
        let theta_new = 0.5 * (-t2 + theta * (t2 + 4.0).sqrt());
        let beta = theta * (1.0 - theta) / (t2 + theta_new);
        for (i, r) in rows.iter().enumerate() {
            let (p, xp) = (r.impulse(), ws.x_prev[i]);
            let mut y = p;
            for ((y, p), xp) in y.as_mut().iter_mut().zip(p.as_ref()).zip(xp.as_ref()) {
                *y = p + beta * (p - xp);
            }
            ws.y[i] = y;
        }
        for (j, sp) in springs.iter().enumerate() {
            ws.ys[j] = sp.impulse() + beta * (sp.impulse() - ws.xs_prev[j]);
        }
        for ((uy, ux), up) in ws.uy.iter_mut().zip(u.iter()).zip(&ws.u_prev) {
            for ((y, x), p) in uy.as_mut().iter_mut().zip(ux.as_ref()).zip(up.as_ref()) {
                *y = x + beta * (x - p);
            }
        }
        theta_new
    }

    /// Momentum dropped: `y = x`.
    pub(super) fn restart<S: AffineRow<Dofs = R::Dofs>>(&mut self, u: &[R::Dofs], rows: &[R], springs: &[S]) {
        for (y, r) in self.y.iter_mut().zip(rows) {
            *y = r.impulse();
        }
        for (y, sp) in self.ys.iter_mut().zip(springs) {
            *y = sp.impulse();
        }
        self.uy.copy_from_slice(u);
    }

    /// Keeps the current iterate as the best checked one.
    pub(super) fn keep_best<S: AffineRow<Dofs = R::Dofs>>(&mut self, rows: &[R], springs: &[S]) {
        self.best.clear();
        self.best.extend(rows.iter().map(|r| r.impulse()));
        self.best_s.clear();
        self.best_s.extend(springs.iter().map(|sp| sp.impulse()));
    }

    /// Takes back the best checked iterate's impulses.
    pub(super) fn take_best<S: AffineRow<Dofs = R::Dofs>>(&self, rows: &mut [R], springs: &mut [S]) {
        for (r, p) in rows.iter_mut().zip(&self.best) {
            r.set_impulse(*p);
        }
        for (sp, p) in springs.iter_mut().zip(&self.best_s) {
            sp.set_impulse(*p);
        }
    }

    /// The outer updates after a failed check: threshold labels from the iterate and, for
    /// [`FrictionBound::Outer`], the Tresca bounds `μ P_N`; whether any changed.
    pub(super) fn outer_update(&mut self, opts: &ApgdOptions, u: &[R::Dofs], rows: &[R]) -> bool {
        let ws = self;
        let mut changed = false;
        for (i, r) in rows.iter().enumerate() {
            let c = r.label(u);
            changed |= c != ws.c[i];
            ws.c[i] = c;
        }
        if opts.friction == FrictionBound::Outer {
            for (i, r) in rows.iter().enumerate() {
                let b = r.mu() * r.normal();
                changed |= b != ws.bound[i];
                ws.bound[i] = b;
            }
        }
        changed
    }

    /// The velocities recomputed from the free ones and the impulses (no drift of the increments; one scatter).
    pub(super) fn recompute<S: AffineRow<Dofs = R::Dofs>>(
        &self,
        u: &mut [R::Dofs],
        inv_m: &[R::Dofs],
        rows: &[R],
        springs: &[S],
    ) {
        u.copy_from_slice(&self.u_free);
        scatter(u, inv_m, rows, springs, None, 1.0);
    }
}
