//! Accelerated projected gradient (APGD) for the per-step problem, an
//! alternative to [`super::nlgs`] where Gauss–Seidel stalls (method and
//! measurements: `docs/accelerated-solver.md`).
//!
//! **Method.** Nesterov's accelerated projected gradient with adaptive
//! (gradient) restart and step-size backtracking, as Chrono's APGD: Mazhar,
//! Heyn, Negrut, Tasora, *Using Nesterov's method to accelerate multibody
//! dynamics with friction and contact*, ACM TOG 34(3) 32 (2015), Algorithm 2.
//! The global Delassus operator `N = H* M⁻¹ H` is never assembled: it is applied
//! through the bodies, a change `ΔP` of the impulses adds `M⁻¹ H ΔP` to the body
//! velocities (a *scatter*, as NLGS's update) and the local velocities are read
//! back as `H* u` (a *gather*, as NLGS's `U_0`).
//!
//! **Formulation.** The exact Coulomb law with normal thresholds is not the cone
//! complementarity problem APGD solves in Chrono (whose fixed point differs: the
//! normal velocity is dilated by `μ |U_T|`). Here, with a friction bound `g_α`
//! per contact and a normal threshold `c_α`, the impulses minimise the convex
//! quadratic
//! `f(P) = ½ Pᵀ N P + Pᵀ (H* u_free − c + shift_t) + Σ_springs (P_s − hα_s)² / (2 hβ_s)`
//! over the box `P_N ≥ 0, |P_T| ≤ g_α` (springs: `P_s ≥ 0` if compression-only,
//! free otherwise). Its gradient is the vector of local velocities `U_N − c_α`,
//! `U_T + shift_t` (springs: `U_s + (P_s − hα_s)/hβ_s`), so the KKT conditions are,
//! per contact, Signorini with threshold `c_α` and Tresca friction with bound
//! `g_α`, and per spring exactly its affine law `P_s = hα_s − hβ_s U_s`
//! ([`SpringRow::solve`]; springs are therefore *in* the QP, a quadratic energy
//! with a diagonal term `1/hβ_s`). The Coulomb law is recovered as a fixed point
//! on the bound ([`FrictionBound`]): either `g_α = μ P_N` of the point being
//! projected, in every projection (one loop, [`FrictionBound::Iterate`]), or a
//! Tresca problem solved with `g_α = μ P_N` of the previous outer iterate
//! ([`FrictionBound::Outer`]); both have the NLGS solutions as their fixed
//! points. The normal law of [`super::coulomb::solve`] is "open if
//! `U_0N ≥ s_open`, else `U_N = c_closed`" (`U_0` without the row's own impulse):
//! for `s_open = c_closed` (no restitution, every contact of the scenes so far)
//! it is Signorini with threshold `c_α = c_closed`; for `s_open < c_closed` it is
//! not monotone, and `c_α` is a label fixed during the inner iterations —
//! `c_closed` for a contact whose `U_0N < s_open`, `s_open` otherwise —
//! relabelled from the iterate at every check, the label being consistent with
//! NLGS's law at a fixed point.
//!
//! **Convergence** is judged as in NLGS with `measure = check`: the iterate is
//! written into the rows (`p`) and the body velocities (`u`), and
//! [`super::nlgs::check`] (exact local solve of every row, nothing updated) is
//! evaluated with the same policy ([`super::criterion::evaluate`]). The check is
//! made when a cheap proxy (the policy's norms of the change of the iterate over
//! one iteration) times the last measured check/proxy ratio meets the tolerance,
//! at least every [`ApgdOptions::check_every`] iterations, and at the cap. The
//! iterates are not monotone: a step that reaches the cap returns the best
//! checked iterate (as Chrono returns the one of least residual).
//!
//! **Work** is counted in sweep-equivalents: a scatter or a gather over all rows
//! is half a sweep (an NLGS sweep is one gather and one scatter per row), a check
//! a full one (a gather and a local solve per row). An iteration is one gather
//! (gradient at the extrapolated point) and one scatter (the projected step),
//! plus one scatter per backtracking retry; the set-up costs one scatter and the
//! exact recomputation of the velocities at the end another. The per-body vector
//! operations (momentum, backtracking test) are not counted (bodies are about a
//! third of the rows). `iterations` of the report is the rounded-up total, and
//! the cap `max_iterations` is in the same unit.

use super::contact::{dot3, ContactRow};
use super::criterion::{evaluate, SweepNorms};
use super::nlgs::{check, solve_nlgs, NlgsReport, NlgsSettings};
use super::sublayer::SpringRow;

/// How the friction bound `g_α` of the box is set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionBound {
    /// `|P_T| ≤ μ P_N` with `P_N` of the projected point itself, in every
    /// projection: one loop whose fixed points are the Coulomb solutions, but the
    /// feasible set moves with the iterate (no convexity guarantee).
    Iterate,
    /// Tresca: `g_α = μ P_N` frozen during the inner (convex) iterations and
    /// updated from the iterate at every check that fails.
    Outer,
}

/// Options of the accelerated solver ([`ApgdOptions::default`] is what
/// [`solve_apgd`] uses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApgdOptions {
    /// How the friction bound is set; default [`FrictionBound::Iterate`].
    pub friction: FrictionBound,
    /// Diagonal (Jacobi) preconditioning: row `α`'s step is scaled by
    /// `1/W_NN`, `1/W_TT` (springs `1/(w + 1/hβ)`), i.e. the method runs in the
    /// metric of the diagonal of `N`; default true.
    pub precondition: bool,
    /// "NLGS then accelerate": plain NLGS ([`super::nlgs::solve_nlgs`], same
    /// policy) for at most this many sweeps, then, if it has not converged, the
    /// accelerated iterations from its iterate; 0: none; default 50 (measured
    /// best of 0, 20, 50, 200: `docs/accelerated-solver.md`).
    pub nlgs_first: usize,
    /// A check is made at least every this many iterations, ≥ 1; default 25.
    pub check_every: usize,
    /// Adaptive restart of the momentum (O'Donoghue and Candès' gradient test, as
    /// in Mazhar et al.); default true.
    pub restart: bool,
    /// Factor applied to the Lipschitz estimate `L` after every iteration, in
    /// (0, 1] (Chrono: 0.9); default 0.9.
    pub l_decay: f64,
    /// Fall back to plain NLGS (from the best checked iterate, for the rest of
    /// the sweep budget) after this many checks in a row without improving on the
    /// best; 0: never; default 0.
    pub fallback: usize,
}

impl Default for ApgdOptions {
    fn default() -> Self {
        Self {
            friction: FrictionBound::Iterate,
            precondition: true,
            nlgs_first: 50,
            check_every: 25,
            restart: true,
            l_decay: 0.9,
            fallback: 0,
        }
    }
}

/// Buffers of [`solve_apgd_with`], kept from call to call (sized at the start of
/// a call; nothing is allocated inside the iterations).
#[derive(Debug, Clone, Default)]
pub struct ApgdWorkspace {
    /// Free velocities `u_free` of the bodies.
    u_free: Vec<[f64; 3]>,
    /// Body velocities of the extrapolated point `y`.
    uy: Vec<[f64; 3]>,
    /// Body velocities of the previous iterate.
    u_prev: Vec<[f64; 3]>,
    /// Extrapolated point, previous iterate, gradient at `y`, step scales of the contacts.
    y: Vec<[f64; 2]>,
    x_prev: Vec<[f64; 2]>,
    g: Vec<[f64; 2]>,
    scale: Vec<[f64; 2]>,
    /// Normal threshold `c_α` and friction bound `g_α` (Outer) of the contacts.
    c: Vec<f64>,
    bound: Vec<f64>,
    /// The same for the springs.
    ys: Vec<f64>,
    xs_prev: Vec<f64>,
    gs: Vec<f64>,
    scale_s: Vec<f64>,
    /// Best checked iterate (contacts, springs), returned if the cap is reached.
    best: Vec<[f64; 2]>,
    best_s: Vec<f64>,
}

#[inline(always)]
fn add3(u: &mut [f64; 3], im: &[f64; 3], hn: &[f64; 3], dn: f64, ht: &[f64; 3], dt: f64, sign: f64) {
    for d in 0..3 {
        u[d] += sign * im[d] * (hn[d] * dn + ht[d] * dt);
    }
}

/// Adds `sign · M⁻¹ H P` of every row to `u`, `P` being the rows' or the given impulses.
fn scatter(
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
        add3(&mut u[s.a as usize], &inv_m[s.a as usize], &s.hn_a, p, &[0.0; 3], 0.0, sign);
        if s.b != u32::MAX {
            add3(&mut u[s.b as usize], &inv_m[s.b as usize], &s.hn_b, p, &[0.0; 3], 0.0, -sign);
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
        add3(&mut u[r.a as usize], &inv_m[r.a as usize], &r.hn_a, pn, &r.ht_a, pt, sign);
        add3(&mut u[r.b as usize], &inv_m[r.b as usize], &r.hn_b, pn, &r.ht_b, pt, -sign);
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

/// Solves the step's problem by APGD with the default options ([`ApgdOptions`])
/// and a fresh workspace. Same contract as [`super::nlgs::solve_nlgs`]: `u` comes
/// in as `u_free + M⁻¹ H P` of the rows' warm-start impulses and leaves as the
/// final velocities, the rows' `p` as the impulses; `iterations` counts
/// sweep-equivalents (module text).
pub fn solve_apgd(
    settings: &NlgsSettings,
    u: &mut [[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &mut [ContactRow],
    springs: &mut [SpringRow],
) -> NlgsReport {
    solve_apgd_with(settings, &ApgdOptions::default(), &mut ApgdWorkspace::default(), u, inv_m, rows, springs)
}

/// [`solve_apgd`] with options and a reused workspace.
#[allow(clippy::too_many_arguments)]
pub fn solve_apgd_with(
    settings: &NlgsSettings,
    opts: &ApgdOptions,
    ws: &mut ApgdWorkspace,
    u: &mut [[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &mut [ContactRow],
    springs: &mut [SpringRow],
) -> NlgsReport {
    if rows.is_empty() && springs.is_empty() {
        return NlgsReport { iterations: 0, criterion: 0.0, converged: true };
    }
    let s = settings;
    let cap = 2 * s.max_iterations.max(1);
    let mut halves = 0usize; // work in half sweeps
    let report = |halves: usize, criterion: f64, converged: bool| NlgsReport {
        iterations: halves.div_ceil(2),
        criterion,
        converged,
    };

    // "NLGS then accelerate": plain NLGS (same stopping rule) for at most
    // `nlgs_first` sweeps, the accelerated iterations only if it has not converged.
    if opts.nlgs_first > 0 {
        let first = NlgsSettings { max_iterations: opts.nlgs_first.min(s.max_iterations), ..*s };
        let r = solve_nlgs(&first, u, inv_m, rows, springs);
        if r.converged || r.iterations >= s.max_iterations {
            return r;
        }
        halves += 2 * r.iterations;
    }

    // Set-up: buffers, free velocities, labels, bounds, step scales.
    let (n, m, nb) = (rows.len(), springs.len(), u.len());
    ws.u_free.clear();
    ws.u_free.extend_from_slice(u);
    // A spring without stiffness nor damping has a fixed impulse.
    for sp in springs.iter_mut().filter(|sp| sp.h_beta <= 0.0) {
        let p = sp.solve(0.0);
        let dp = p - sp.p;
        sp.p = p;
        add3(&mut u[sp.a as usize], &inv_m[sp.a as usize], &sp.hn_a, dp, &[0.0; 3], 0.0, 1.0);
        if sp.b != u32::MAX {
            add3(&mut u[sp.b as usize], &inv_m[sp.b as usize], &sp.hn_b, dp, &[0.0; 3], 0.0, -1.0);
        }
    }
    ws.u_free.copy_from_slice(u);
    scatter(&mut ws.u_free, inv_m, rows, springs, None, -1.0);
    halves += 1;
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

    let mut theta: f64 = 1.0;
    let mut ratio = 1.0;
    let mut since_check = 0usize;
    let mut previous_wpp = 0.0;
    let mut last;
    let mut best_value = f64::INFINITY;
    let mut stagnant = 0usize;
    let mut fall_back = false;
    loop {
        // Gradient at y: the local velocities (one gather).
        for (i, r) in rows.iter().enumerate() {
            let (un, ut) = local(r, &ws.uy);
            ws.g[i] = [un - ws.c[i], ut + r.shift_t];
        }
        for (j, sp) in springs.iter().enumerate() {
            ws.gs[j] = if sp.h_beta > 0.0 { local_s(sp, &ws.uy) + (ws.ys[j] - sp.h_alpha) / sp.h_beta } else { 0.0 };
        }
        halves += 1;
        for (xp, r) in ws.x_prev.iter_mut().zip(rows.iter()) {
            *xp = r.p;
        }
        for (xp, sp) in ws.xs_prev.iter_mut().zip(springs.iter()) {
            *xp = sp.p;
        }
        ws.u_prev.copy_from_slice(u);

        // Projected step from y with backtracking on L.
        loop {
            let t = 1.0 / l;
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
            halves += 1;
            for ((ux, uy), im) in u.iter().zip(&ws.uy).zip(inv_m) {
                for d in 0..3 {
                    if im[d] > 0.0 {
                        let du = ux[d] - uy[d];
                        quad += du * du / im[d];
                    }
                }
            }
            // f(x) ≤ f(y) + ∇f(y)·(x − y) + L/2 |x − y|², f quadratic.
            if quad <= l * norm2 * (1.0 + 1e-12) || norm2 == 0.0 || halves >= cap {
                break;
            }
            l *= 2.0;
        }

        // Proxy norms (the policy's norms of the change of the iterate) and the
        // restart test (gradient mapping against the last move).
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
            proxy.add_contact(w, [pn, pt], [qn, qt], dn != 0.0 || dt != 0.0);
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

        // Nesterov's extrapolation, or a restart.
        if opts.restart && restart_dot > 0.0 {
            theta = 1.0;
            restart(ws, u, rows, springs);
        } else {
            let t2 = theta * theta;
            let theta_new = 0.5 * (-t2 + theta * (t2 + 4.0).sqrt());
            let beta = theta * (1.0 - theta) / (t2 + theta_new);
            theta = theta_new;
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
        }
        l *= opts.l_decay;

        // Convergence, judged by NLGS's check.
        let (value, _) = evaluate(s.policy, s.tolerance, s.max_factor, &proxy, previous_wpp);
        previous_wpp = proxy.sum_wpp;
        since_check += 1;
        let at_cap = halves + 2 >= cap;
        if at_cap || ratio * value < s.tolerance || since_check >= opts.check_every.max(1) {
            let norms = check(u, inv_m, rows, springs);
            halves += 2;
            since_check = 0;
            last = evaluate(s.policy, s.tolerance, s.max_factor, &norms, 0.0);
            if value > 0.0 && last.0.is_finite() {
                ratio = (last.0 / value).clamp(1e-3, 1e3);
            }
            if (last.1 && halves.div_ceil(2) >= s.min_iterations) || at_cap {
                break;
            }
            stagnant += 1;
            if last.0 < best_value {
                stagnant = 0;
                best_value = last.0;
                ws.best.clear();
                ws.best.extend(rows.iter().map(|r| r.p));
                ws.best_s.clear();
                ws.best_s.extend(springs.iter().map(|sp| sp.p));
            }
            if opts.fallback > 0 && stagnant >= opts.fallback {
                fall_back = true;
                break;
            }
            // Outer updates: threshold labels, Tresca bounds.
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
            if changed {
                theta = 1.0;
                restart(ws, u, rows, springs);
            }
        }
    }

    // APGD is not monotone: at the cap, the best checked iterate is returned.
    if (fall_back || !last.1) && best_value < last.0 {
        last.0 = best_value;
        for (r, p) in rows.iter_mut().zip(&ws.best) {
            r.p = *p;
        }
        for (sp, p) in springs.iter_mut().zip(&ws.best_s) {
            sp.p = *p;
        }
    }
    // Velocities recomputed from the impulses (no drift of the increments).
    u.copy_from_slice(&ws.u_free);
    scatter(u, inv_m, rows, springs, None, 1.0);
    halves += 1;
    if fall_back {
        let done = halves.div_ceil(2);
        let rest = NlgsSettings { max_iterations: s.max_iterations.saturating_sub(done).max(1), ..*s };
        let r = solve_nlgs(&rest, u, inv_m, rows, springs);
        return NlgsReport { iterations: done + r.iterations, ..r };
    }
    report(halves, last.0, last.1)
}

/// Momentum dropped: `y = x`.
fn restart(ws: &mut ApgdWorkspace, u: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
    for (y, r) in ws.y.iter_mut().zip(rows) {
        *y = r.p;
    }
    for (y, sp) in ws.ys.iter_mut().zip(springs) {
        *y = sp.p;
    }
    ws.uy.copy_from_slice(u);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{ConvexPolygon, Shape, Vec2};
    use crate::nscd::contact::ContactLaw;
    use crate::nscd::nlgs::{apply_impulses, solve_nlgs, NlgsProblem};
    use crate::nscd::{BodyInfo, Measure, NscdParams, Policy, Spring, System};

    fn settings(tolerance: f64) -> NlgsSettings {
        NlgsSettings {
            policy: Policy::Quad,
            tolerance,
            max_iterations: 200_000,
            split_min_rows: 0,
            measure: Measure::Check,
            ..NlgsSettings::default()
        }
    }

    /// Fifteen pentagons settled in a box for 0.3 s (friction 0.5), one of them
    /// hung from a world anchor by a damped spring: the problem of the last step.
    fn small_pile() -> NlgsProblem {
        let mut nlgs = settings(1e-8);
        nlgs.max_iterations = 20_000;
        let mut sys = System::new(NscdParams { dt: 1e-3, alert_distance: 5e-4, nlgs, ..NscdParams::default() }, 1);
        sys.set_law(0, 0, ContactLaw { friction: 0.5, ..ContactLaw::default() });
        let rect = |x0: f64, y0: f64, x1: f64, y1: f64| [[x0, y0], [x1, y0], [x1, y1], [x0, y1]];
        for (name, v) in [
            ("floor", rect(-0.3, -0.1, 0.3, 0.0)),
            ("left", rect(-0.4, 0.0, -0.3, 1.0)),
            ("right", rect(0.3, 0.0, 0.4, 1.0)),
        ] {
            let (b, q) = BodyInfo::polygon(name, &v, 0, 2700.0, 1.0).unwrap();
            sys.bodies.push(b.into_fixed(), q, [0.0; 3]);
        }
        for k in 0..15 {
            let (i, j) = (k % 5, k / 5);
            let shape = Shape::Polygon(ConvexPolygon::regular(5, 0.045).unwrap());
            let b = BodyInfo::new("p", shape, 0, 2400.0, 1.0).unwrap();
            let x = -0.24 + 0.12 * i as f64 + 0.01 * j as f64;
            sys.bodies.push(b, [x, 0.05 + 0.1 * j as f64, 0.37 * k as f64], [0.0; 3]);
        }
        sys.springs.push(Spring {
            a: 3,
            point_a: [0.0, 0.0],
            b: None,
            point_b: [-0.24, 0.9],
            k_n: 200.0,
            nu: 5.0,
            rest_length: 0.8,
            prestrain: 0.0,
            compression_only: false,
            impulse: 0.0,
        });
        for _ in 0..300 {
            sys.step().unwrap();
        }
        sys.nlgs_problem()
    }

    fn solve(p: &NlgsProblem, s: &NlgsSettings, apgd: Option<ApgdOptions>) -> (NlgsProblem, NlgsReport) {
        let mut q = p.clone();
        let r = match apgd {
            Some(o) => {
                solve_apgd_with(s, &o, &mut ApgdWorkspace::default(), &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs)
            }
            None => solve_nlgs(s, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs),
        };
        (q, r)
    }

    /// On a small pile APGD (every variant) reaches NLGS's solution. The
    /// reference is NLGS to `quad` 1e-12. A solve to tolerance τ is within about
    /// κ τ |W P| of the solution, κ the conditioning: measured on this pile, NLGS
    /// to τ = 1e-9 is 6.8e-9 m/s from the reference (velocities), so every
    /// variant, solved to 1e-9, must be within 2e-8 m/s (3× NLGS's own distance),
    /// and the spring's impulse (a function of its velocity) within the
    /// corresponding `hβ · 2e-8` plus round-off. Individual contact impulses are
    /// not compared: the packing is hyperstatic (pentagons touching edge to edge
    /// or wedged between walls), so they are not unique — NLGS to 1e-9 and APGD
    /// to 1e-9 differ by 2.4e-5 N·s on some normal impulse while both satisfy
    /// the law to the tolerance, and APGD stays at that distance when both are
    /// tightened. The per-body resultants `H P` are unique: their difference is
    /// the velocities' times the masses, tested through the velocities.
    #[test]
    fn reaches_the_nlgs_solution_on_a_small_pile() {
        let p = small_pile();
        assert!(p.rows.len() > 20 && p.springs.len() == 1, "{} rows", p.rows.len());
        let (reference, r0) = solve(&p, &settings(1e-12), None);
        assert!(r0.converged, "{r0:?}");
        let s = settings(1e-9);
        let (nlgs, r1) = solve(&p, &s, None);
        let distance = |x: &NlgsProblem| {
            x.u.iter().zip(&reference.u).flat_map(|(a, b)| (0..3).map(move |d| (a[d] - b[d]).abs())).fold(0.0, f64::max)
        };
        let d_nlgs = distance(&nlgs);
        assert!(r1.converged && d_nlgs < 1e-8, "{r1:?}: {d_nlgs:e}");
        for (friction, precondition, nlgs_first) in [
            (FrictionBound::Iterate, true, 0),
            (FrictionBound::Iterate, false, 0),
            (FrictionBound::Outer, true, 0),
            (FrictionBound::Iterate, true, 5),
            (FrictionBound::Iterate, true, 50),
        ] {
            let o = ApgdOptions { friction, precondition, nlgs_first, ..ApgdOptions::default() };
            let (x, r) = solve(&p, &s, Some(o));
            assert!(r.converged, "{o:?}: {r:?}");
            let du = distance(&x);
            assert!(du < 2e-8, "{o:?}: velocities {du:e} m/s from the reference (NLGS: {d_nlgs:e})");
            let ds = (x.springs[0].p - reference.springs[0].p).abs();
            assert!(ds < p.springs[0].h_beta * 2e-8 + 1e-12, "{o:?}: spring impulses differ by {ds:e} N·s");
            // The velocities are those of the impulses.
            let mut u = p.u.clone();
            apply_impulses(&mut u, &p.inv_m, &x.rows, &x.springs);
            let drift =
                u.iter().zip(&x.u).flat_map(|(a, b)| (0..3).map(move |d| (a[d] - b[d]).abs())).fold(0.0, f64::max);
            assert!(drift < 1e-12, "{drift:e}");
        }
    }

    /// A 2 kg block (inertia 0.01 kg·m²) on a fixed floor, one contact at `point`,
    /// coming down at 1 m/s and sliding at `vx`.
    fn block(point: [f64; 2], vx: f64, friction: f64) -> NlgsProblem {
        let inv_m = vec![[0.5, 0.5, 100.0], [0.0; 3]];
        let u = vec![[vx, -1.0, 0.0], [0.0; 3]];
        let row = ContactRow::new(
            (0, 1),
            Vec2::new(point[0], point[1]),
            Vec2::new(0.0, 1.0),
            (Vec2::new(0.0, 0.05), Vec2::new(0.0, -0.05)),
            (&inv_m[0], &inv_m[1]),
            (&u[0], &u[1]),
            0.0,
            1e-3,
            &ContactLaw { friction, ..ContactLaw::default() },
        );
        NlgsProblem { u, inv_m, rows: vec![row], springs: Vec::new() }
    }

    /// Frictionless contact off the centre: `P_N = (c − U_free,N) / W_NN`, exactly.
    #[test]
    fn single_frictionless_contact_matches_the_closed_form() {
        let p = block([0.03, 0.0], 0.4, 0.0);
        let w_nn = 0.5 + 100.0 * 0.03 * 0.03; // 1/m + (r × n)² / I
        let exact = 1.0 / w_nn;
        assert!((p.rows[0].w.nn - w_nn).abs() < 1e-12);
        let apgd = ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() };
        for o in [apgd, ApgdOptions { precondition: false, ..apgd }] {
            let (x, r) = solve(&p, &settings(1e-10), Some(o));
            assert!(r.converged, "{r:?}");
            assert!((x.rows[0].p[0] - exact).abs() < 1e-10 * exact, "{} vs {exact}", x.rows[0].p[0]);
            assert_eq!(x.rows[0].p[1], 0.0);
            let un = x.u[0][1] + 0.03 * x.u[0][2]; // h_n · u = v_y + (r × n) ω
            assert!(un.abs() < 1e-10, "{un}");
        }
    }

    /// A block sliding at 2 m/s, contact under its centre (`W_NT = 0`), μ = 0.3:
    /// friction saturated, `P_N = m`, `P_T = μ m` against the motion, and the block
    /// leaves at `2 − μ` m/s, spun by the friction's moment.
    #[test]
    fn sliding_block_saturates_friction() {
        let p = block([0.0, 0.0], 2.0, 0.3);
        assert_eq!(p.rows[0].w.nt, 0.0);
        for friction in [FrictionBound::Iterate, FrictionBound::Outer] {
            let o = ApgdOptions { friction, nlgs_first: 0, ..ApgdOptions::default() };
            let (x, r) = solve(&p, &settings(1e-10), Some(o));
            assert!(r.converged, "{o:?}: {r:?}");
            let [pn, pt] = x.rows[0].p;
            assert!((pn - 2.0).abs() < 1e-9, "{pn}");
            // t = (−1, 0): the block's U_T = −2 < 0, so P_T = +μ P_N pushes along t, against the motion.
            assert!((pt - 0.6).abs() < 1e-9, "{pt}");
            assert!((x.u[0][0] - 1.7).abs() < 1e-9 && x.u[0][1].abs() < 1e-9, "{:?}", x.u[0]);
            // r × t = (0, −0.05) × (−1, 0) = −0.05: ω = 100 × (−0.05) × 0.6.
            assert!((x.u[0][2] + 3.0).abs() < 1e-8, "{:?}", x.u[0]);
        }
    }

    /// A reused workspace gives the same numbers as a fresh one.
    #[test]
    fn workspace_reuse_is_transparent() {
        let p = small_pile();
        let s = settings(1e-6);
        let o = ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() };
        let mut ws = ApgdWorkspace::default();
        let mut runs = Vec::new();
        for _ in 0..2 {
            let mut q = p.clone();
            let r = solve_apgd_with(&s, &o, &mut ws, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs);
            runs.push((r, q.u, q.rows.iter().map(|r| r.p).collect::<Vec<_>>()));
        }
        assert_eq!(runs[0].0, runs[1].0);
        assert_eq!(runs[0].1, runs[1].1);
        assert_eq!(runs[0].2, runs[1].2);
    }
}
