//! Plain NLGS against the accelerated solver ([`ballast::nscd::apgd`]) on the
//! very same problems: a scene is run with its own settings, and every `EVERY`
//! steps the problem of the next step (contacts, free velocities and the warm
//! start of the trajectory) is frozen and solved by every method, each judged by
//! its policy evaluated on LMGC90's check (`measure = check`), and by a reference
//! solve, tighter, against which the solutions are compared.
//!
//! `cargo run --release --example apgd_measure -- SCENE STEPS EVERY METHOD...`
//! with METHOD = `KIND:POLICY:TOLERANCE[:OPTION...]`, KIND `nlgs` (plain, unsplit
//! [`ballast::nscd::nlgs::solve_nlgs`]) or `apgd`, OPTION (apgd) among `outer`
//! (Tresca outer fixed point), `plain` (no diagonal preconditioning), `nlgsN`
//! (plain NLGS for at most N sweeps first; without it, none: `apgd` alone is the
//! pure accelerated solver, whereas [`ApgdOptions::default`] has `nlgs50`),
//! `norestart`, `decayX` (factor on `L` per iteration), `fallbackN` (plain NLGS
//! after N checks without progress), `checkN` (a check at least every N iterations), and for
//! both `capN` (`max_iterations`, default the scene's). The reference is
//! `--reference METHOD` (default `apgd:quad:1e-8:cap20000`), given before SCENE.
//! Sampled steps start at step `--from K` (default `EVERY`).
//!
//! Writes one CSV row per sampled step and method on standard output (sweep
//! counts in sweep-equivalents for apgd, see the module documentation; wall time
//! of the solve, the methods taking turns so that the machine's load affects
//! them alike; the largest velocity difference to the reference in m/s and the
//! relative 2-norm difference of the normal impulses) and the totals on
//! standard error. One thread.

use ballast::nscd::apgd::{solve_apgd_with, ApgdOptions, ApgdWorkspace, FrictionBound};
use ballast::nscd::nlgs::{apply_impulses, solve_nlgs, NlgsProblem, NlgsReport};
use ballast::nscd::{Measure, NlgsSettings, Policy, System};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
struct Row {
    step: u64,
    method: String,
    rows: usize,
    sweeps: usize,
    converged: bool,
    criterion: f64,
    wall_s: f64,
    du_max: f64,
    du_body: usize,
    du_energy: f64,
    dpn_rel: f64,
    reference_converged: bool,
}

#[derive(Clone)]
struct Method {
    name: String,
    settings: NlgsSettings,
    apgd: Option<ApgdOptions>,
}

fn parse(text: &str, base: &NlgsSettings) -> Result<Method, String> {
    let parts: Vec<&str> = text.split(':').collect();
    let [kind, policy, tolerance, options @ ..] = &parts[..] else {
        return Err(format!("{text}: expected KIND:POLICY:TOLERANCE[:OPTION...]"));
    };
    let policy = match *policy {
        "strict" => Policy::Strict,
        "quad" => Policy::Quad,
        "quad_max" => Policy::QuadMax,
        "energy" => Policy::Energy,
        p => return Err(format!("{p}: unknown policy")),
    };
    let tolerance = tolerance.parse().map_err(|e| format!("{tolerance}: {e}"))?;
    let mut settings = NlgsSettings { policy, tolerance, measure: Measure::Check, split_min_rows: 0, ..*base };
    let mut apgd = match *kind {
        "nlgs" => None,
        "apgd" => Some(ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() }),
        k => return Err(format!("{k}: unknown kind (nlgs or apgd)")),
    };
    for o in options {
        let number = |prefix: &str| o.strip_prefix(prefix).and_then(|n| n.parse::<usize>().ok());
        match (o, apgd.as_mut()) {
            (_, _) if number("cap").is_some() => settings.max_iterations = number("cap").unwrap_or(1),
            (&"outer", Some(a)) => a.friction = FrictionBound::Outer,
            (&"plain", Some(a)) => a.precondition = false,
            (&"norestart", Some(a)) => a.restart = false,
            (_, Some(a)) if o.starts_with("decay") => {
                a.l_decay = o["decay".len()..].parse().map_err(|e| format!("{o}: {e}"))?
            }
            (_, Some(a)) if number("nlgs").is_some() => a.nlgs_first = number("nlgs").unwrap_or(0),
            (_, Some(a)) if number("fallback").is_some() => a.fallback = number("fallback").unwrap_or(0),
            (_, Some(a)) if number("check").is_some() => a.check_every = number("check").unwrap_or(1),
            _ => return Err(format!("{o}: unknown option for {kind}")),
        }
    }
    Ok(Method { name: text.to_string(), settings, apgd })
}

/// The next step's problem of `sys`, with the warm start of the trajectory.
fn frozen_problem(sys: &System) -> Result<NlgsProblem, Box<dyn std::error::Error>> {
    let mut copy = sys.clone();
    copy.step()?;
    let mut p = copy.nlgs_problem();
    let mut prev = 0;
    for (row, geom) in p.rows.iter_mut().zip(&copy.contacts) {
        while prev < sys.contacts.len() && sys.contacts[prev].key < geom.key {
            prev += 1;
        }
        if prev < sys.contacts.len() && sys.contacts[prev].key == geom.key {
            row.p = sys.impulses[prev];
        }
    }
    for (row, spring) in p.springs.iter_mut().zip(&sys.springs) {
        row.p = spring.impulse;
    }
    apply_impulses(&mut p.u, &p.inv_m, &p.rows, &p.springs);
    Ok(p)
}

fn run(m: &Method, ws: &mut ApgdWorkspace, p: &NlgsProblem) -> (NlgsProblem, NlgsReport, f64) {
    let mut q = p.clone();
    let start = Instant::now();
    let report = match &m.apgd {
        Some(o) => solve_apgd_with(&m.settings, o, ws, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs),
        None => solve_nlgs(&m.settings, &mut q.u, &q.inv_m, &mut q.rows, &mut q.springs),
    };
    (q, report, start.elapsed().as_secs_f64())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut option = |flag: &str| -> Option<String> {
        let i = args.iter().position(|a| a == flag)?;
        let v = args.get(i + 1).cloned();
        args.drain(i..(i + 2).min(args.len()));
        v
    };
    let reference = option("--reference").unwrap_or_else(|| "apgd:quad:1e-8:cap20000".into());
    let from = option("--from");
    let [scene, steps, every, methods @ ..] = &args[..] else {
        return Err("usage: apgd_measure [--reference METHOD] [--from K] SCENE STEPS EVERY METHOD...".into());
    };
    let (steps, every): (u64, u64) = (steps.parse()?, every.parse()?);
    let from: u64 = from.map_or(Ok(every), |f| f.parse())?;
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let base = sys.params.nlgs;
    let reference = parse(&reference, &base)?;
    let methods = methods.iter().map(|m| parse(m, &base)).collect::<Result<Vec<_>, _>>()?;
    if methods.is_empty() {
        return Err("give at least one method".into());
    }
    let mut ws = ApgdWorkspace::default();
    let mut out = csv::Writer::from_writer(std::io::stdout());
    // Per method: sweeps, wall, at the cap, max du, sum of dpn_rel, samples.
    let mut totals = vec![(0usize, 0.0f64, 0usize, 0.0f64, 0.0f64, 0usize); methods.len()];
    let mut turn = 0;
    for k in 1..=steps {
        if k >= from && (k - from).is_multiple_of(every) {
            let p = frozen_problem(&sys)?;
            let (r, rr, _) = run(&reference, &mut ws, &p);
            let pn2: f64 = r.rows.iter().map(|x| x.p[0] * x.p[0]).sum();
            // Methods take turns starting with a different one at each sample.
            turn += 1;
            for j in 0..methods.len() {
                let i = (j + turn) % methods.len();
                let m = &methods[i];
                let (x, report, wall_s) = run(m, &mut ws, &p);
                let (mut du_max, mut du_body, mut e_diff, mut e_ref) = (0.0, 0, 0.0, 0.0);
                for (b, ((a, c), im)) in x.u.iter().zip(&r.u).zip(&p.inv_m).enumerate() {
                    for d in 0..3 {
                        let du = (a[d] - c[d]).abs();
                        if du > du_max {
                            (du_max, du_body) = (du, b);
                        }
                        if im[d] > 0.0 {
                            (e_diff, e_ref) = (e_diff + du * du / im[d], e_ref + c[d] * c[d] / im[d]);
                        }
                    }
                }
                let du_energy = if e_ref > 0.0 { (e_diff / e_ref).sqrt() } else { e_diff.sqrt() };
                let d2: f64 = x.rows.iter().zip(&r.rows).map(|(a, b)| (a.p[0] - b.p[0]).powi(2)).sum();
                let dpn_rel = if pn2 > 0.0 { (d2 / pn2).sqrt() } else { d2.sqrt() };
                let t = &mut totals[i];
                t.0 += report.iterations;
                t.1 += wall_s;
                t.2 += usize::from(!report.converged);
                t.3 = t.3.max(du_max);
                t.4 += dpn_rel;
                t.5 += 1;
                out.serialize(Row {
                    step: k,
                    method: m.name.clone(),
                    rows: p.rows.len() + p.springs.len(),
                    sweeps: report.iterations,
                    converged: report.converged,
                    criterion: report.criterion,
                    wall_s,
                    du_max,
                    du_body,
                    du_energy,
                    dpn_rel,
                    reference_converged: rr.converged,
                })?;
            }
        }
        sys.step()?;
    }
    out.flush()?;
    for (m, (sweeps, wall, capped, du, dpn, n)) in methods.iter().zip(&totals) {
        let n = (*n).max(1) as f64;
        eprintln!(
            "{}: {:.1} sweeps/step, {capped} of {n} at the cap, {:.2} ms/step, max |du| {du:.2e} m/s, mean dPN/PN {:.2e}",
            m.name,
            *sweeps as f64 / n,
            1e3 * wall / n,
            dpn / n
        );
    }
    Ok(())
}
