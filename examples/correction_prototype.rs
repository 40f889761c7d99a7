//! A prototype of design (c) of `docs/finisher-design.md` (issue 31): NLGS as the
//! smoother, and between its sweeps a *truncated Newton correction* on the contacts'
//! current states, solved exactly by a sparse Cholesky factorisation, the pattern of
//! the truncated nonsmooth Newton multigrid (TNNMG) of Gräser and Kornhuber: the
//! sweeps find the states (open, sticking, sliding) locally, the correction moves
//! the long force chains at once, where a sweep passes information one contact on.
//!
//! `cargo run --release --features faer --example correction_prototype -- SCENE STEPS EVERY ENTRY SMOOTH KAPPA [TOL]`
//!
//! The scene runs with its own settings; every `EVERY` steps up to `STEPS` its NLGS
//! problem (`System::nlgs_problem`, cold) gets `ENTRY` plain NLGS sweeps, then cycles
//! of one correction and `SMOOTH` sweeps until the `quad` check value is below `TOL`
//! (default 1e-6), or 60 cycles. Beside it, from the same cold start: NLGS with the
//! default `energy` 1.66e-5 (the time budget of issue 31), and NLGS to `quad` TOL
//! (cap 20 000). One CSV row per cycle on standard output.
//!
//! **The correction.** At an NLGS iterate `(u, P)` (consistent: `u = u_free + M⁻¹ H P`)
//! each contact's state is read from `P`: open if `P_N = 0` (left out), sticking if
//! `|P_T| < μ P_N` (both components free), sliding otherwise (normal free, `P_T`
//! held: the Tresca problem of the current bounds, symmetric). With `ρ = κ / W_ii`
//! per free component, the step `Δu` solves
//! `(M + Σ_free ρ g gᵀ + Σ_springs h β g gᵀ) Δu = −Σ_free g ρ y + Σ_springs g r_s`
//! (`y` the free components' law residuals `U_N − c`, `U_T + e_t U_T⁻`, `r_s` a spring's
//! residual), which is `d = −(W_FF + D⁻¹)⁻¹ y_F` in impulse space (Woodbury): the
//! proximally regularised Newton step of the face, well posed however redundant the
//! contacts. The new impulses `P_F − ρ (y_F + H_F Δu)` are projected on the law
//! (`P_N ≥ 0`, `|P_T| ≤ μ P_N`; a sliding contact keeps `P_T = ±μ P_N`) and `u` is
//! rebuilt from them; the sweeps then repair what the projection broke. A cycle
//! that does not lower the check is undone (the plain sweeps are made instead) and
//! κ multiplied by SHRINK; an accepted one multiplies κ by GROW (`KAPPA,GROW,SHRINK`).
//! Variants by environment: `LU=1` couples the sliding contacts' friction into the
//! step (the impulse along `g_N ± μ g_T`, the constraint `g_N`: a non-symmetric `J`,
//! faer's sparse LU); `SLIDE=stick` treats sliding contacts as sticking;
//! `SLIDE=keep` keeps their `P_T`; `ETA=η` (m/s) counts contacts with `P_N = 0`
//! separating by less than η, or slipping by less than η, as sticking; `DIAG=1`
//! prints the residuals left after each correction by assumed state; `CYCLES`
//! the cycles per problem (200); KAPPA = 0 gives plain NLGS in the same cycles.
//!
//! **What it measured** (2026-12-04, `loaded536_4.toml` of BENCHMARKS.md, 10 cold
//! problems, steps 100–1000, ENTRY 100, SMOOTH 10, κ = 300 fixed; BENCHMARKS.md "A
//! truncated Newton correction"): the corrections reach `quad` 1e-3 in 180–250
//! sweeps and 8–12 factorisations against 350–1360 plain sweeps, but then stop
//! helping: 1e-4 is reached on 5 of 10 problems within 200 cycles (plain NLGS: 10
//! of 10, 2050–6620 sweeps), 3e-5 on 2 (plain: 6). Larger κ (≥ 1e3) makes the
//! projection flip hundreds of contacts; the friction coupled by LU (`LU=1`) or
//! sliding contacts held sticking change nothing but the cost (an LU costs about
//! 20× a Cholesky here). After a correction the residual left is that of the
//! sliding contacts whose slip reverses and of the sticking ones (`DIAG=1`):
//! the plateau at 1e-5–1e-4, where NLGS itself wanders for thousands of sweeps,
//! is the search for the contacts' stick/slip states, not a slow linear mode.

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
use jacobian::{add_force, free_velocity, gather, local, rebuild, Jacobian, LuJacobian};
use std::time::Instant;

/// A contact's state as the correction reads it from `P`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum State {
    Open,
    Stick,
    /// Sliding, `P_T = σ μ P_N` with σ = ±1.
    Slide(i8),
}

/// What one correction did.
#[derive(Debug, Clone, Copy, Default)]
struct Correction {
    /// Contacts in each state.
    open: usize,
    stick: usize,
    slide: usize,
    /// Contacts whose state the projection changed.
    projected: usize,
}

/// Buffers of the correction.
#[derive(Default)]
struct Corrector {
    jac: Jacobian,
    u_free: Vec<[f64; 3]>,
    fb: Vec<[f64; 3]>,
    rhs: Vec<f64>,
    du: Vec<[f64; 3]>,
    state: Vec<State>,
    thr: Vec<f64>,
    /// The grazing threshold η (m/s), from `ETA` (default 0).
    eta: f64,
    /// Sliding contacts keep their `P_T` (clipped), from `SLIDE=keep`; else `P_T = ±μ P_N`.
    keep_slide: bool,
    /// Sliding contacts enter as sticking (`SLIDE=stick`).
    slide_as_stick: bool,
    /// The sliding contacts' friction coupled into the step (`LU=1`): `J` is then
    /// not symmetric and is factorised by LU.
    coupled: bool,
    lu: LuJacobian,
}

impl Corrector {
    fn prepare(&mut self, u: &[[f64; 3]], inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        if !self.jac.prepare(inv_m, rows, springs) || (self.coupled && !self.lu.prepare(inv_m, rows, springs)) {
            return false;
        }
        self.u_free = free_velocity(u, inv_m, rows, springs);
        self.fb = vec![[0.0; 3]; u.len()];
        self.du = vec![[0.0; 3]; u.len()];
        self.rhs = vec![0.0; self.jac.len()];
        self.state = vec![State::Open; rows.len()];
        // The normal law's threshold: `c_closed` where the law is monotone (no
        // restitution), else the branch NLGS takes from the cold start.
        self.thr = rows
            .iter()
            .map(|r| {
                if r.s_open == r.c_closed {
                    r.c_closed
                } else {
                    let un = gather(&self.u_free, r.a, r.b, &r.hn_a, &r.hn_b);
                    if un < r.s_open {
                        r.c_closed
                    } else {
                        r.s_open
                    }
                }
            })
            .collect();
        true
    }

    /// One correction of the consistent pair `(u, P)`; false if the factorisation failed.
    fn correct(
        &mut self,
        kappa: f64,
        u: &mut [[f64; 3]],
        inv_m: &[[f64; 3]],
        rows: &mut [ContactRow],
        springs: &mut [SpringRow],
        c: &mut Correction,
    ) -> bool {
        *c = Correction::default();
        self.jac.reset();
        if self.coupled {
            self.lu.reset();
        }
        self.fb.iter_mut().for_each(|f| *f = [0.0; 3]);
        for (k, r) in rows.iter().enumerate() {
            let (pn, pt) = (r.p[0], r.p[1]);
            let yn = gather(u, r.a, r.b, &r.hn_a, &r.hn_b) - self.thr[k];
            let yt = gather(u, r.a, r.b, &r.ht_a, &r.ht_b) + r.shift_t;
            // A contact at `P_N = 0` that is not separating by more than η (grazing)
            // and a sliding one that is barely slipping enter as sticking: the
            // projection decides their state after the step.
            let st = if pn <= 0.0 && yn > self.eta {
                State::Open
            } else if r.mu > 0.0
                && (pn <= 0.0 || pt.abs() < r.mu * pn * (1.0 - 1e-12) || yt.abs() <= self.eta || self.slide_as_stick)
            {
                State::Stick
            } else if r.mu > 0.0 {
                State::Slide(if pt < 0.0 { -1 } else { 1 })
            } else {
                State::Slide(1)
            };
            self.state[k] = st;
            let rn = kappa / r.w.nn;
            let rt = if r.mu > 0.0 { kappa / r.w.tt } else { 0.0 };
            match st {
                State::Open => c.open += 1,
                State::Stick => {
                    c.stick += 1;
                    self.jac.add_contact(k, r, rn, rt);
                    if self.coupled {
                        let (gn, gt) = (local(&r.hn_a, &r.hn_b), local(&r.ht_a, &r.ht_b));
                        self.lu.add_contact(k, &gn, &gn, rn);
                        self.lu.add_contact(k, &gt, &gt, rt);
                    }
                    add_force(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, -rn * yn);
                    add_force(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, -rt * yt);
                }
                State::Slide(sign) => {
                    c.slide += 1;
                    self.jac.add_contact(k, r, rn, 0.0);
                    add_force(&mut self.fb, r.a, r.b, &r.hn_a, &r.hn_b, -rn * yn);
                    if self.coupled {
                        // The impulse acts along g_N + σ μ g_T, the constraint is g_N.
                        let sm = f64::from(sign) * r.mu;
                        let (gn, gt) = (local(&r.hn_a, &r.hn_b), local(&r.ht_a, &r.ht_b));
                        let f: [f64; 6] = std::array::from_fn(|i| gn[i] + sm * gt[i]);
                        self.lu.add_contact(k, &f, &gn, rn);
                        add_force(&mut self.fb, r.a, r.b, &r.ht_a, &r.ht_b, -sm * rn * yn);
                    }
                }
            }
        }
        for (k, s) in springs.iter().enumerate() {
            let us = gather(u, s.a, s.b, &s.hn_a, &s.hn_b);
            let p = s.h_alpha - s.h_beta * us;
            if s.compression_only && p <= 0.0 && s.p <= 0.0 {
                continue;
            }
            self.jac.add_spring(k, s, s.h_beta);
            if self.coupled {
                self.lu.add_spring(k, &local(&s.hn_a, &s.hn_b), s.h_beta);
            }
            add_force(&mut self.fb, s.a, s.b, &s.hn_a, &s.hn_b, p - s.p);
        }
        self.jac.gather_dofs(&self.fb, &mut self.rhs);
        let solved = if self.coupled {
            self.lu.factorize() && self.lu.solve(&mut self.rhs)
        } else {
            self.jac.factorize() && self.jac.solve(&mut self.rhs)
        };
        if !solved {
            return false;
        }
        self.jac.scatter_dofs(&self.rhs, &mut self.du);
        for (k, r) in rows.iter_mut().enumerate() {
            let st = self.state[k];
            if st == State::Open {
                continue;
            }
            let rn = kappa / r.w.nn;
            let yn = gather(u, r.a, r.b, &r.hn_a, &r.hn_b) - self.thr[k] + gather(&self.du, r.a, r.b, &r.hn_a, &r.hn_b);
            let pn = (r.p[0] - rn * yn).max(0.0);
            let pt = match st {
                State::Stick => {
                    let rt = kappa / r.w.tt;
                    let yt = gather(u, r.a, r.b, &r.ht_a, &r.ht_b)
                        + r.shift_t
                        + gather(&self.du, r.a, r.b, &r.ht_a, &r.ht_b);
                    let pt = r.p[1] - rt * yt;
                    let g = r.mu * pn;
                    if pt.abs() >= g {
                        c.projected += 1;
                    }
                    pt.clamp(-g, g)
                }
                State::Slide(sign) if !self.keep_slide => f64::from(sign) * r.mu * pn,
                State::Slide(_) => r.p[1].clamp(-r.mu * pn, r.mu * pn),
                State::Open => unreachable!(),
            };
            if pn == 0.0 {
                c.projected += 1;
            }
            r.p = [pn, pt];
        }
        for s in springs.iter_mut() {
            let us = gather(u, s.a, s.b, &s.hn_a, &s.hn_b) + gather(&self.du, s.a, s.b, &s.hn_a, &s.hn_b);
            let p = s.h_alpha - s.h_beta * us;
            s.p = if s.compression_only { p.max(0.0) } else { p };
        }
        rebuild(u, &self.u_free, inv_m, rows, springs);
        if std::env::var("DIAG").is_ok() {
            self.diagnose(u, rows, springs);
        }
        true
    }

    /// Standard error: the squared local residuals (impulse units) by the state the
    /// correction assumed.
    fn diagnose(&self, u: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) {
        let mut sum = [0.0f64; 6];
        let mut pp = 0.0;
        for (k, r) in rows.iter().enumerate() {
            let yn = gather(u, r.a, r.b, &r.hn_a, &r.hn_b) - self.thr[k];
            let yt = gather(u, r.a, r.b, &r.ht_a, &r.ht_b) + r.shift_t;
            let (en, et) = (yn / r.w.nn, yt / r.w.tt);
            pp += r.p[0] * r.p[0] + r.p[1] * r.p[1];
            let pn = r.p[0];
            match self.state[k] {
                State::Open => sum[0] += en.min(0.0).powi(2),
                State::Stick => {
                    sum[1] += if pn > 0.0 { en * en } else { en.min(0.0).powi(2) };
                    // Sticking: every slip is a residual; at the bound, a reversed one.
                    if (pn > 0.0 && r.p[1].abs() < r.mu * pn) || r.p[1] * yt > 0.0 {
                        sum[2] += et * et
                    }
                }
                State::Slide(_) => {
                    sum[3] += if pn > 0.0 { en * en } else { en.min(0.0).powi(2) };
                    if r.p[1] * yt > 0.0 {
                        sum[4] += et * et
                    }
                }
            }
        }
        for s in springs {
            let us = gather(u, s.a, s.b, &s.hn_a, &s.hn_b);
            let p = s.h_alpha - s.h_beta * us;
            let p = if s.compression_only { p.max(0.0) } else { p };
            sum[5] += (p - s.p).powi(2);
        }
        let n = (rows.len() + springs.len()) as f64;
        let f = |x: f64| (x / n).sqrt() / (pp / rows.len() as f64).sqrt();
        eprintln!(
            "  residual: open-penetrating {:.2e}, stick N {:.2e} T {:.2e}, slide N {:.2e} T-reversed {:.2e}, springs {:.2e}",
            f(sum[0]),
            f(sum[1]),
            f(sum[2]),
            f(sum[3]),
            f(sum[4]),
            f(sum[5])
        );
    }
}

/// One cycle.
#[derive(serde::Serialize)]
struct Row {
    step: u64,
    rows: usize,
    kappa: f64,
    cycle: usize,
    accepted: bool,
    sweeps: usize,
    factorizations: usize,
    wall_s: f64,
    check_after_correction: f64,
    check: f64,
    open: usize,
    stick: usize,
    slide: usize,
    projected: usize,
    energy_default_sweeps: usize,
    energy_default_s: f64,
    nlgs_tol_sweeps: usize,
    nlgs_tol_s: f64,
}

fn quad(u: &mut [[f64; 3]], inv_m: &[[f64; 3]], rows: &mut [ContactRow], springs: &mut [SpringRow]) -> f64 {
    evaluate(Policy::Quad, 1.0, 4.0, &check(u, inv_m, rows, springs), 0.0).0
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, entry, smooth, kappa, rest @ ..] = &args[..] else {
        return Err("usage: correction_prototype SCENE STEPS EVERY ENTRY SMOOTH KAPPA [TOL]".into());
    };
    let (steps, every, entry, smooth): (u64, u64, usize, usize) =
        (steps.parse()?, every.parse()?, entry.parse()?, smooth.parse()?);
    // KAPPA[,GROW,SHRINK]: κ after an accepted cycle and after a rejected one,
    // relative to before (default 2 and 1/4).
    let mut parts = kappa.split(',').map(|x| x.parse::<f64>());
    let kappa0 = parts.next().ok_or("KAPPA")??;
    let grow = parts.next().transpose()?.unwrap_or(2.0);
    let shrink = parts.next().transpose()?.unwrap_or(0.25);
    let tol: f64 = rest.first().map(|t| t.parse()).transpose()?.unwrap_or(1e-6);
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let base = NlgsSettings { measure: Measure::Check, split_min_rows: 0, ..sys.params.nlgs };
    let fixed = |n: usize| NlgsSettings {
        policy: Policy::Quad,
        tolerance: 1e-300,
        max_iterations: n,
        min_iterations: 1,
        ..base
    };
    let default = NlgsSettings { policy: Policy::Energy, tolerance: 1.66e-5, max_iterations: 2000, ..base };
    let to_tol = NlgsSettings { policy: Policy::Quad, tolerance: tol, max_iterations: 20_000, ..base };
    // Cycles per problem at most: `CYCLES`, default 200.
    let max_cycles: usize = std::env::var("CYCLES").map_or(Ok(200), |v| v.parse())?;
    let mut out = csv::Writer::from_writer(std::io::stdout());
    let mut cor = Corrector {
        eta: std::env::var("ETA").map_or(Ok(0.0), |v| v.parse())?,
        keep_slide: std::env::var("SLIDE").is_ok_and(|v| v == "keep"),
        slide_as_stick: std::env::var("SLIDE").is_ok_and(|v| v == "stick"),
        coupled: std::env::var("LU").is_ok(),
        ..Corrector::default()
    };
    for k in 1..=steps {
        sys.step()?;
        if k % every != 0 {
            continue;
        }
        let p0 = sys.nlgs_problem();
        let mut p = p0.clone();
        let t0 = Instant::now();
        let d = solve_nlgs(&default, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        let t_default = t0.elapsed().as_secs_f64();
        let mut p = p0.clone();
        let t0 = Instant::now();
        let n = solve_nlgs(&to_tol, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        let t_tol = t0.elapsed().as_secs_f64();

        let mut p = p0.clone();
        let t0 = Instant::now();
        let mut sweeps = solve_nlgs(&fixed(entry), &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs).iterations;
        if !cor.prepare(&p.u, &p.inv_m, &p.rows, &p.springs) {
            return Err("the Jacobian's analysis failed".into());
        }
        let mut kappa = kappa0;
        let mut prev = quad(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
        let (mut saved_u, mut saved_rows, mut saved_springs) = (p.u.clone(), p.rows.clone(), p.springs.clone());
        let mut factorizations = 0;
        for cycle in 1..=max_cycles {
            let mut c = Correction::default();
            factorizations += usize::from(kappa0 > 0.0);
            // κ = 0: no correction, plain NLGS in cycles of SMOOTH sweeps (the baseline).
            if kappa0 > 0.0 && !cor.correct(kappa, &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs, &mut c) {
                return Err("a factorisation failed".into());
            }
            let after = quad(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
            sweeps += solve_nlgs(&fixed(smooth), &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs).iterations;
            let value = quad(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
            // The safeguard: a cycle that did not lower the check is undone and
            // κ quartered; one that did doubles κ.
            let accepted = value < prev || kappa0 == 0.0;
            if accepted {
                prev = value;
                kappa = (kappa * grow).min(1e8);
            } else {
                // Undone: the plain sweeps from the last accepted iterate instead.
                p.u.copy_from_slice(&saved_u);
                p.rows.copy_from_slice(&saved_rows);
                p.springs.copy_from_slice(&saved_springs);
                sweeps += solve_nlgs(&fixed(smooth), &mut p.u, &p.inv_m, &mut p.rows, &mut p.springs).iterations;
                prev = quad(&mut p.u, &p.inv_m, &mut p.rows, &mut p.springs);
                kappa = (kappa * shrink).max(1.0);
            }
            saved_u.copy_from_slice(&p.u);
            saved_rows.copy_from_slice(&p.rows);
            saved_springs.copy_from_slice(&p.springs);
            let wall_s = t0.elapsed().as_secs_f64();
            out.serialize(Row {
                step: k,
                rows: p.rows.len(),
                kappa,
                cycle,
                accepted,
                sweeps,
                factorizations,
                wall_s,
                check_after_correction: after,
                check: prev,
                open: c.open,
                stick: c.stick,
                slide: c.slide,
                projected: c.projected,
                energy_default_sweeps: d.iterations,
                energy_default_s: t_default,
                nlgs_tol_sweeps: n.iterations,
                nlgs_tol_s: t_tol,
            })?;
            if prev <= tol || !prev.is_finite() || cycle == max_cycles {
                eprintln!(
                    "step {k}: {} rows; corrected: check {prev:.2e} after {cycle} cycles, {sweeps} sweeps, {:.4} s; \
                     NLGS to {tol:e}: {} sweeps, {:.4} s; energy 1.66e-5: {} sweeps, {:.4} s",
                    p.rows.len(),
                    wall_s,
                    n.iterations,
                    t_tol,
                    d.iterations,
                    t_default
                );
                break;
            }
        }
        out.flush()?;
    }
    Ok(())
}
