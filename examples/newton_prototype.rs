//! A prototype of design (a) of `docs/finisher-design.md`, kept to reproduce its
//! measured failure (issue 31): a velocity-space augmented-Lagrangian semismooth
//! Newton method on the NLGS problem of a step, entered where NLGS stalls.
//!
//! `cargo run --release --example newton_prototype -- SCENE STEPS EVERY SWEEPS KAPPA[,GROWTH] [INNER]`
//!
//! The scene runs with its own settings; every `EVERY` steps up to `STEPS` its NLGS
//! problem (`System::nlgs_problem`, restarted cold) gets `SWEEPS` plain NLGS sweeps
//! (`quad`, judged by the check pass: the entry), then the finisher runs from that
//! iterate with penalty factor `KAPPA` (multiplied by `GROWTH` after each multiplier
//! update, up to 1e8; default 1) and at most `INNER` Newton iterations per update
//! (default 30), up to 40 factorisations; beside it NLGS continues from the same
//! entry for as long (wall time). One CSV row per multiplier update on standard
//! output: the check value (`quad`), Newton iterations, factorisations, active and
//! sticking contacts, and NLGS's check value after the same time.
//!
//! **Method.** Unknowns: the mobile velocity components. With multipliers `λ`,
//! penalties `ρ_N = κ/W_NN`, `ρ_T = κ/W_TT` and a friction bound `g = μ max(0, λ_N)`
//! held between updates, `P_N(u) = max(0, λ_N − ρ_N y_N)`,
//! `P_T(u) = clamp(λ_T − ρ_T y_T, ±g)`; `F(u) = M (u − u_free) − Σ G P(u)` is the
//! gradient of a convex piecewise quadratic, its generalised Jacobian
//! `J = M + Σ G D Gᵀ` is symmetric positive definite (faer sparse Cholesky, AMD,
//! one symbolic analysis per problem, a numeric factorisation when the contacts'
//! states change), the line search is exact (the root of the nondecreasing
//! directional derivative), and at the minimiser of a piece `λ ← P(u)`.
//!
//! **What it measured** (2026-12-04, the loaded 536 pile of `data/`, BENCHMARKS.md
//! "Toward a converged solve"): with `κ ≤ 1e2` the inner minimisation converges in
//! 1–3 factorisations per update but the multiplier iteration gains 1–5 % per
//! update on the check; with `κ ≥ 1e4` the semismooth Newton iterations flip the
//! states of hundreds of contacts (the NLGS iterate's residual times ρ dominates the
//! multipliers) and do not converge in 30 factorisations; increasing κ by 3 or 10
//! per update diverges. A frozen-state variant (states from NLGS's impulses, the law
//! made linear, the sliding friction implicit, faer sparse LU) diverges at once: in
//! a hyperstatic packing the equalities of a wrong state set are inconsistent.

#![allow(clippy::needless_range_loop)] // per-component loops over [x, y, θ] read as the equations

#[path = "common/jacobian.rs"]
mod jacobian;

use ballast::nscd::contact::ContactRow;
use ballast::nscd::criterion::{evaluate, Policy};
use ballast::nscd::nlgs::{check, solve_nlgs, NlgsSettings};
use ballast::nscd::sublayer::SpringRow;
use ballast::nscd::Measure;
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use jacobian::{add_force, free_velocity, gather, rebuild, scatter, Jacobian, NONE};
use std::time::Instant;

/// Options of the prototype.
#[derive(Debug, Clone, Copy, PartialEq)]
struct NewtonOptions {
    /// Penalty factor `κ` (dimensionless): `ρ_N = κ / W_NN`, `ρ_T = κ / W_TT`.
    kappa: f64,
    /// Factor on κ after each multiplier update (up to 1e8).
    growth: f64,
    /// Numeric factorisations at most.
    max_factorizations: usize,
    /// Multiplier updates at most.
    max_updates: usize,
    /// Newton iterations per multiplier update at most.
    max_inner: usize,
}

/// What the prototype did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct NewtonReport {
    /// Newton iterations (linear solves).
    newton_iterations: usize,
    /// Numeric Cholesky factorisations.
    factorizations: usize,
    /// Multiplier updates (each ends with a check pass).
    updates: usize,
}

/// One multiplier update.
#[derive(serde::Serialize)]
struct Row {
    step: u64,
    kappa: f64,
    update: usize,
    newton_iterations: usize,
    factorizations: usize,
    wall_s: f64,
    check: f64,
    nlgs_check_same_time: f64,
    active: usize,
    sticking: usize,
}

/// Buffers of the prototype.
#[derive(Default)]
struct NewtonWorkspace {
    /// The unknowns and the matrix `J`.
    jac: Jacobian,
    /// Per unknown: `F`, the step `d`.
    f: Vec<f64>,
    d: Vec<f64>,
    /// Body form: the Newton iterate, the free velocity, the step, `F`.
    v: Vec<[f64; 3]>,
    v_free: Vec<[f64; 3]>,
    dv: Vec<[f64; 3]>,
    fb: Vec<[f64; 3]>,
    /// Per contact: multiplier, threshold `c`, bound `g`, penalties, `y` and `Gᵀd`, states.
    lam: Vec<[f64; 2]>,
    thr: Vec<f64>,
    bound: Vec<f64>,
    rho: Vec<[f64; 2]>,
    y: Vec<[f64; 2]>,
    dy: Vec<[f64; 2]>,
    state: Vec<u8>,
    fstate: Vec<u8>,
    /// Per spring: `U_s`, `g_sᵀ d`, active, active in the factor.
    sy: Vec<f64>,
    sdy: Vec<f64>,
    sstate: Vec<u8>,
    sfstate: Vec<u8>,
}

impl std::fmt::Debug for NewtonWorkspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NewtonWorkspace").field("unknowns", &self.jac.len()).finish_non_exhaustive()
    }
}

impl Clone for NewtonWorkspace {
    /// Buffers only: a clone starts empty.
    fn clone(&self) -> Self {
        Self::default()
    }
}

/// State bits of a contact: normal active, tangential sticking (both enter `J`),
/// sliding positive / negative (for the line search only through `P`).
const NORMAL: u8 = 1;
const STICK: u8 = 2;

/// `P(y)` of a contact under multiplier `lam`, penalties `rho` and bound `g`, and its state.
#[inline(always)]
fn impulse(lam: [f64; 2], rho: [f64; 2], g: f64, y: [f64; 2]) -> ([f64; 2], u8) {
    let xn = lam[0] - rho[0] * y[0];
    let xt = lam[1] - rho[1] * y[1];
    let mut state = 0;
    let pn = if xn > 0.0 {
        state |= NORMAL;
        xn
    } else {
        0.0
    };
    let pt = if rho[1] > 0.0 && xt.abs() < g {
        state |= STICK;
        xt
    } else if rho[1] > 0.0 {
        g.copysign(xt)
    } else {
        0.0
    };
    ([pn, pt], state)
}

/// `P_s(U)` of a spring and whether it is active (not clamped).
#[inline(always)]
fn spring_impulse(s: &SpringRow, u: f64) -> (f64, u8) {
    let p = s.h_alpha - s.h_beta * u;
    if s.compression_only && p <= 0.0 {
        (0.0, 0)
    } else {
        (p, 1)
    }
}

impl NewtonWorkspace {
    /// Numbers the unknowns, rebuilds `u_free` from `u` and the rows' impulses,
    /// builds the pattern of `J` and its symbolic Cholesky factorisation.
    fn prepare(&mut self, u: &[[f64; 3]], inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        if !self.jac.prepare(inv_m, rows, springs) {
            return false;
        }
        let (nb, n) = (u.len(), self.jac.len());
        self.v.clear();
        self.v.extend_from_slice(u);
        self.v_free = free_velocity(u, inv_m, rows, springs);
        self.dv.clear();
        self.dv.resize(nb, [0.0; 3]);
        self.fb.clear();
        self.fb.resize(nb, [0.0; 3]);
        self.f.clear();
        self.f.resize(n, 0.0);
        self.d.clear();
        self.d.resize(n, 0.0);
        let nc = rows.len();
        self.lam.clear();
        self.lam.extend(rows.iter().map(|r| r.p));
        self.rho.clear();
        self.thr.clear();
        self.bound.clear();
        self.y.clear();
        self.y.resize(nc, [0.0; 2]);
        self.dy.clear();
        self.dy.resize(nc, [0.0; 2]);
        self.state.clear();
        self.state.resize(nc, 0);
        self.fstate.clear();
        self.fstate.resize(nc, u8::MAX);
        self.sy.clear();
        self.sy.resize(springs.len(), 0.0);
        self.sdy.clear();
        self.sdy.resize(springs.len(), 0.0);
        self.sstate.clear();
        self.sstate.resize(springs.len(), 0);
        self.sfstate.clear();
        self.sfstate.resize(springs.len(), u8::MAX);
        true
    }

    /// Penalties from `κ`, thresholds from the current pair (`u` consistent with
    /// the rows' impulses) and bounds from the multipliers.
    fn relabel(&mut self, kappa: f64, u: &[[f64; 3]], rows: &[ContactRow]) {
        self.rho.clear();
        self.thr.clear();
        self.bound.clear();
        for (r, lam) in rows.iter().zip(&self.lam) {
            let w = r.w;
            let rn = if w.nn > 0.0 { kappa / w.nn } else { 0.0 };
            let rt = if w.tt > 0.0 && rn > 0.0 { kappa / w.tt } else { 0.0 };
            self.rho.push([rn, rt]);
            let c = if r.s_open == r.c_closed {
                r.c_closed
            } else {
                // Not monotone (restitution): the branch NLGS's law takes from U_0.
                let un = gather(u, r.a, r.b, &r.hn_a, &r.hn_b);
                let u0n = un - (w.nn * r.p[0] + w.nt * r.p[1]);
                if u0n < r.s_open {
                    r.c_closed
                } else {
                    r.s_open
                }
            };
            self.thr.push(c);
            self.bound.push(r.mu * lam[0].max(0.0));
        }
    }

    /// `y` and states at the iterate `v`, `F` (dof form), and whether the states
    /// differ from the factor's.
    fn evaluate(&mut self, rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        for (i, fb) in self.fb.iter_mut().enumerate() {
            let (v, vf, ix) = (&self.v[i], &self.v_free[i], &self.jac.dof[i]);
            for d in 0..3 {
                fb[d] = if ix[d] != NONE { self.jac.mass[ix[d] as usize] * (v[d] - vf[d]) } else { 0.0 };
            }
        }
        let mut changed = false;
        for (k, s) in springs.iter().enumerate() {
            let us = gather(&self.v, s.a, s.b, &s.hn_a, &s.hn_b);
            self.sy[k] = us;
            let (p, st) = spring_impulse(s, us);
            self.sstate[k] = st;
            changed |= st != self.sfstate[k];
            add_force(&mut self.fb, s.a, s.b, &s.hn_a, &s.hn_b, -p);
        }
        for (k, r) in rows.iter().enumerate() {
            let un = gather(&self.v, r.a, r.b, &r.hn_a, &r.hn_b);
            let ut = gather(&self.v, r.a, r.b, &r.ht_a, &r.ht_b);
            let y = [un - self.thr[k], ut + r.shift_t];
            self.y[k] = y;
            let (p, st) = impulse(self.lam[k], self.rho[k], self.bound[k], y);
            self.state[k] = st;
            changed |= st != self.fstate[k];
            add_force(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, -p[0]);
            add_force(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, -p[1]);
        }
        self.jac.gather_dofs(&self.fb, &mut self.f);
        changed
    }

    /// Assembles `J` for the current states and factorises it; false on a failure.
    fn factorize(&mut self, rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        self.jac.reset();
        for (k, r) in rows.iter().enumerate() {
            let st = self.state[k];
            let cn = if st & NORMAL != 0 { self.rho[k][0] } else { 0.0 };
            let ct = if st & STICK != 0 { self.rho[k][1] } else { 0.0 };
            self.jac.add_contact(k, r, cn, ct);
        }
        for (k, s) in springs.iter().enumerate() {
            if self.sstate[k] != 0 && s.h_beta > 0.0 {
                self.jac.add_spring(k, s, s.h_beta);
            }
        }
        self.fstate.copy_from_slice(&self.state);
        self.sfstate.copy_from_slice(&self.sstate);
        self.jac.factorize()
    }

    /// `d = −J⁻¹ F` with the current factor, scattered into `dv`, and `Gᵀd` per row.
    fn newton_step(&mut self, rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        for (d, f) in self.d.iter_mut().zip(&self.f) {
            *d = -f;
        }
        if !self.jac.solve(&mut self.d) {
            return false;
        }
        self.jac.scatter_dofs(&self.d, &mut self.dv);
        for (k, r) in rows.iter().enumerate() {
            self.dy[k] = [gather(&self.dv, r.a, r.b, &r.hn_a, &r.hn_b), gather(&self.dv, r.a, r.b, &r.ht_a, &r.ht_b)];
        }
        for (k, s) in springs.iter().enumerate() {
            self.sdy[k] = gather(&self.dv, s.a, s.b, &s.hn_a, &s.hn_b);
        }
        true
    }

    /// The potential's derivative along `d` at `v + t d`: `F(v + t d)·d`.
    fn slope(&self, t: f64, rows: &[ContactRow], springs: &[SpringRow]) -> f64 {
        let mut s = 0.0;
        for (i, ix) in self.jac.dof.iter().enumerate() {
            for d in 0..3 {
                if ix[d] != NONE {
                    let k = ix[d] as usize;
                    let dd = self.d[k];
                    s += self.jac.mass[k] * (self.v[i][d] + t * dd - self.v_free[i][d]) * dd;
                }
            }
        }
        for k in 0..rows.len() {
            let (y, dy) = (self.y[k], self.dy[k]);
            let (p, _) = impulse(self.lam[k], self.rho[k], self.bound[k], [y[0] + t * dy[0], y[1] + t * dy[1]]);
            s -= p[0] * dy[0] + p[1] * dy[1];
        }
        for (k, sp) in springs.iter().enumerate() {
            let (p, _) = spring_impulse(sp, self.sy[k] + t * self.sdy[k]);
            s -= p * self.sdy[k];
        }
        s
    }

    /// Exact line search on the convex potential: the root of its nondecreasing
    /// derivative along `d` in (0, 1] (1 if the derivative is still negative there),
    /// by the Illinois variant of regula falsi; returns `t` and the trials made.
    fn line_search(&self, rows: &[ContactRow], springs: &[SpringRow]) -> (f64, usize) {
        let s0 = self.slope(0.0, rows, springs);
        let s1 = self.slope(1.0, rows, springs);
        if s0 >= 0.0 || s1 <= 0.0 {
            return (1.0, 2);
        }
        let (mut a, mut fa, mut b, mut fb) = (0.0, s0, 1.0, s1);
        let mut trials = 2;
        let mut side = 0;
        for _ in 0..40 {
            let t = (a * fb - b * fa) / (fb - fa);
            let ft = self.slope(t, rows, springs);
            trials += 1;
            if ft.abs() <= 1e-3 * s0.abs() {
                return (t, trials);
            }
            if ft < 0.0 {
                (a, fa) = (t, ft);
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                (b, fb) = (t, ft);
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
        }
        (a.max(1e-12), trials)
    }

    /// Writes the consistent pair: the impulses `P(v)` into the rows and
    /// `u = u_free + M⁻¹ Σ H P` into `u`.
    fn write_pair(&self, u: &mut [[f64; 3]], inv_m: &[[f64; 3]], rows: &mut [ContactRow], springs: &mut [SpringRow]) {
        u.copy_from_slice(&self.v_free);
        for (k, s) in springs.iter_mut().enumerate() {
            s.p = spring_impulse(s, self.sy[k]).0;
            scatter(u, inv_m, s.a, s.b, &s.hn_a, &s.hn_b, s.p);
        }
        for (k, r) in rows.iter_mut().enumerate() {
            r.p = impulse(self.lam[k], self.rho[k], self.bound[k], self.y[k]).0;
            scatter(u, inv_m, r.a, r.b, &r.hn_a, &r.hn_b, r.p[0]);
            scatter(u, inv_m, r.a, r.b, &r.ht_a, &r.ht_b, r.p[1]);
        }
    }
}

/// The finisher from an NLGS iterate (`u` consistent with the rows' impulses):
/// one row per multiplier update in `out`, each with the time since the start.
#[allow(clippy::too_many_arguments)]
fn finish(
    settings: &NlgsSettings,
    opts: &NewtonOptions,
    ws: &mut NewtonWorkspace,
    u: &mut [[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &mut [ContactRow],
    springs: &mut [SpringRow],
    mut out: impl FnMut(&NewtonReport, f64, &NewtonWorkspace),
) {
    let mut report = NewtonReport::default();
    if !ws.prepare(u, inv_m, rows, springs) {
        return;
    }
    let s = settings;
    let judge = |u: &mut [[f64; 3]], rows: &mut [ContactRow], springs: &mut [SpringRow]| {
        evaluate(s.policy, s.tolerance, s.max_factor, &check(u, inv_m, rows, springs), 0.0)
    };
    // The entry made exactly consistent.
    rebuild(u, &ws.v_free, inv_m, rows, springs);
    let mut kappa = opts.kappa;
    ws.relabel(kappa, u, rows);
    'outer: for _ in 0..opts.max_updates {
        let mut full = false;
        for _ in 0..opts.max_inner {
            let changed = ws.evaluate(rows, springs);
            if full && !changed {
                // A full step on the factor's piece that stayed on it: F = 0 there.
                break;
            }
            if changed {
                if report.factorizations >= opts.max_factorizations {
                    break 'outer;
                }
                report.factorizations += 1;
                if !ws.factorize(rows, springs) {
                    break 'outer;
                }
            }
            if !ws.newton_step(rows, springs) {
                break 'outer;
            }
            report.newton_iterations += 1;
            let (t, _) = ws.line_search(rows, springs);
            for (v, dv) in ws.v.iter_mut().zip(&ws.dv) {
                for d in 0..3 {
                    v[d] += t * dv[d];
                }
            }
            full = t == 1.0;
        }
        ws.evaluate(rows, springs);
        if !ws.v.iter().all(|v| v.iter().all(|x| x.is_finite())) {
            break;
        }
        ws.write_pair(u, inv_m, rows, springs);
        report.updates += 1;
        let (value, ok) = judge(u, rows, springs);
        out(&report, value, ws);
        if ok {
            break;
        }
        // Method of multipliers: λ ← P(v), the Coulomb bound from the new λ_N.
        for (l, r) in ws.lam.iter_mut().zip(rows.iter()) {
            *l = r.p;
        }
        let next = (kappa * opts.growth).min(1e8);
        if next != kappa {
            kappa = next;
            ws.fstate.iter_mut().for_each(|s| *s = u8::MAX);
        }
        ws.relabel(kappa, u, rows);
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, sweeps, kappa, rest @ ..] = &args[..] else {
        return Err("usage: newton_prototype SCENE STEPS EVERY SWEEPS KAPPA[,GROWTH] [INNER]".into());
    };
    let (steps, every, sweeps): (u64, u64, usize) = (steps.parse()?, every.parse()?, sweeps.parse()?);
    let (kappa, growth) = match kappa.split_once(',') {
        Some((k, g)) => (k.parse()?, g.parse()?),
        None => (kappa.parse()?, 1.0),
    };
    let max_inner = rest.first().map(|x| x.parse()).transpose()?.unwrap_or(30);
    let opts = NewtonOptions { kappa, growth, max_factorizations: 40, max_updates: 200, max_inner };
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let settings = NlgsSettings {
        policy: Policy::Quad,
        tolerance: 1e-6,
        measure: Measure::Check,
        max_iterations: sweeps,
        ..sys.params.nlgs
    };
    let mut ws = NewtonWorkspace::default();
    let mut out = csv::Writer::from_writer(std::io::stdout());
    for k in 1..=steps {
        sys.step()?;
        if k % every != 0 {
            continue;
        }
        let mut p = sys.nlgs_problem();
        let entry = solve_nlgs(&settings, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        eprintln!(
            "step {k}: {} rows, entry after {} sweeps: check {:.3e}",
            p.rows.len(),
            entry.iterations,
            entry.criterion
        );
        let (u0, rows0, springs0) = (p.u.clone(), p.rows.clone(), p.springs.clone());
        let mut updates = Vec::new();
        let start = Instant::now();
        finish(&settings, &opts, &mut ws, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs, |r, value, ws| {
            let active = ws.state.iter().filter(|&&s| s & NORMAL != 0).count();
            let sticking = ws.state.iter().filter(|&&s| s & STICK != 0).count();
            updates.push((*r, value, start.elapsed().as_secs_f64(), active, sticking));
        });
        // NLGS from the same entry, checked at the same wall times.
        let (mut u, mut rows, mut springs) = (u0, rows0, springs0);
        let one = NlgsSettings { max_iterations: 10, tolerance: 1e-300, ..settings };
        let start = Instant::now();
        for (r, value, wall_s, active, sticking) in updates {
            while start.elapsed().as_secs_f64() < wall_s {
                solve_nlgs(&one, &mut u, &p.inv_m, &mut rows, &mut springs);
            }
            let nlgs = evaluate(
                settings.policy,
                1.0,
                settings.max_factor,
                &check(&mut u, &p.inv_m, &mut rows, &mut springs),
                0.0,
            )
            .0;
            out.serialize(Row {
                step: k,
                kappa,
                update: r.updates,
                newton_iterations: r.newton_iterations,
                factorizations: r.factorizations,
                wall_s,
                check: value,
                nlgs_check_same_time: nlgs,
                active,
                sticking,
            })?;
        }
        out.flush()?;
    }
    Ok(())
}
