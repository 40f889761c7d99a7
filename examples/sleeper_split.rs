//! Experiment (issue 31): is the loaded pile's stall the sleeper's mode?
//!
//! `cargo run --release --example sleeper_split -- SCENE STEPS EVERY [TOL]`
//! (SCENE: the loaded 536 pile, `loaded536.toml` of BENCHMARKS.md; TOL the `quad`
//! tolerance, default 1e-6; one thread).
//!
//! A heavy sleeper on light grains is the first suspect for NLGS's stall: if the
//! slow modes were the sleeper's vertical motion against the network, fixing the
//! sleeper at its converged velocity would leave a well-conditioned grain problem,
//! and a scalar outer iteration on that velocity (a Schur complement, or a domain
//! split, on the sleeper's dof) would cure the stall. Every `EVERY` steps the
//! example solves the step's NLGS problem (a) in full at TOL, cold; (b) with the
//! sleeper's vertical velocity fixed at the reference's (`quad` 1e-9) and the
//! grains solved at TOL; (c) by the secant method on `g(v) = v − v_free − Δ(v)`,
//! the sleeper's velocity balance with the grains solved at TOL for each `v`.
//! One CSV row per sampled step on standard output (sweeps, the residual `g` at
//! the reference velocity, θ h times the sleeper's velocity error of (a) and (c)).
//!
//! Measured (2026-12-04, `sleeper_split loaded536.toml 200 100`): (b) needs as many
//! sweeps as (a) or more (step 100: 7752 against 6039; step 200: 10560 against
//! 10556), and (c) 30 000–71 000 sweeps in all. The ill-conditioning is in the
//! grain network itself (long force chains), not in the sleeper's mode: a split on
//! the sleeper's dof is ruled out (docs/finisher-design.md §14).

use ballast::nscd::contact::ContactRow;
use ballast::nscd::nlgs::{solve_nlgs, NlgsProblem, NlgsSettings};
use ballast::nscd::{Measure, Policy};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use std::time::Instant;

fn settings(policy: Policy, tolerance: f64, max: usize) -> NlgsSettings {
    NlgsSettings {
        policy,
        tolerance,
        max_iterations: max,
        measure: Measure::Check,
        split_min_rows: 0,
        ..NlgsSettings::default()
    }
}

/// Velocity change of body `s`'s y component from the rows' impulses.
fn delta_y(s: usize, im: f64, rows: &[ContactRow]) -> f64 {
    let mut d = 0.0;
    for r in rows {
        if r.a as usize == s {
            d += im * (r.hn_a[1] * r.p[0] + r.ht_a[1] * r.p[1]);
        }
        if r.b as usize == s {
            d -= im * (r.hn_b[1] * r.p[0] + r.ht_b[1] * r.p[1]);
        }
    }
    d
}

struct Fixed {
    p: NlgsProblem,
    s: usize,
    im: f64,
    v_free: f64,
    sweeps: usize,
}

impl Fixed {
    fn new(problem: &NlgsProblem, s: usize) -> Self {
        let mut p = problem.clone();
        let im = p.inv_m[s][1];
        let v_free = p.u[s][1];
        p.inv_m[s] = [0.0; 3];
        Self { p, s, im, v_free, sweeps: 0 }
    }

    /// g(v) = v − v_free − Δ(v), the grains solved with the sleeper at v.
    fn g(&mut self, v: f64, st: &NlgsSettings) -> f64 {
        self.p.u[self.s][1] = v;
        let r = solve_nlgs(st, &mut self.p.u, &self.p.inv_m, &mut self.p.rows, &mut self.p.springs);
        self.sweeps += r.iterations;
        v - self.v_free - delta_y(self.s, self.im, &self.p.rows)
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, rest @ ..] = &args[..] else {
        return Err("usage: sleeper_split SCENE STEPS EVERY [TOL]".into());
    };
    let tol: f64 = rest.first().map(|t| t.parse()).transpose()?.unwrap_or(1e-6);
    let (steps, every): (u64, u64) = (steps.parse()?, every.parse()?);
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let s = sys.bodies.info.iter().position(|b| b.name == "sleeper").ok_or("no sleeper")?;
    let theta_h = sys.params.theta * sys.params.dt;
    println!("step,full_sweeps,full_conv,ref_sweeps,fixed_ref_sweeps,g_ref,outer,outer_sweeps,dy_full,dy_outer,t_full,t_outer");
    for k in 1..=steps {
        if k % every == 0 {
            let problem = sys.nlgs_problem();
            // Reference: the full problem, tight.
            let mut refp = problem.clone();
            let rr = solve_nlgs(
                &settings(Policy::Quad, 1e-9, 400_000),
                &mut refp.u,
                &refp.inv_m,
                &mut refp.rows,
                &mut refp.springs,
            );
            let v_ref = refp.u[s][1];
            // The full problem at tol, cold.
            let mut full = problem.clone();
            let t0 = Instant::now();
            let fr = solve_nlgs(
                &settings(Policy::Quad, tol, 50_000),
                &mut full.u,
                &full.inv_m,
                &mut full.rows,
                &mut full.springs,
            );
            let t_full = t0.elapsed().as_secs_f64();
            // The sleeper fixed at v_ref.
            let inner = settings(Policy::Quad, tol, 50_000);
            let mut fixed = Fixed::new(&problem, s);
            let g_ref = fixed.g(v_ref, &inner);
            let fixed_sweeps = fixed.sweeps;
            // Outer secant iteration on g, starting from 100 full sweeps.
            let t0 = Instant::now();
            let mut start = problem.clone();
            let sr = solve_nlgs(
                &settings(Policy::Quad, 1e-12, 100),
                &mut start.u,
                &start.inv_m,
                &mut start.rows,
                &mut start.springs,
            );
            let mut fx = Fixed::new(&problem, s);
            fx.p.rows = start.rows.clone();
            fx.p.springs = start.springs.clone();
            fx.p.u = start.u.clone();
            fx.sweeps = sr.iterations;
            let mut v0 = start.u[s][1];
            let mut g0 = fx.g(v0, &inner);
            // Newton-like first step with slope 1 (lower bound of g').
            let mut v1 = v0 - g0;
            let mut g1 = fx.g(v1, &inner);
            let mut outer = 2;
            while g1.abs() > 1e-3 * tol * v_ref.abs().max(1e-3) && outer < 40 {
                let v2 = v1 - g1 * (v1 - v0) / (g1 - g0);
                (v0, g0) = (v1, g1);
                v1 = v2;
                g1 = fx.g(v1, &inner);
                outer += 1;
            }
            let t_outer = t0.elapsed().as_secs_f64();
            println!(
                "{k},{},{},{},{},{:.3e},{outer},{},{:.3e},{:.3e},{t_full:.3},{t_outer:.3}",
                fr.iterations,
                fr.converged,
                rr.iterations,
                fixed_sweeps,
                g_ref,
                fx.sweeps,
                theta_h * (full.u[s][1] - v_ref),
                theta_h * (v1 - v_ref),
            );
        }
        sys.step()?;
    }
    Ok(())
}
