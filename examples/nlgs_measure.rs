//! Stopping rules compared on the same problems: a scene is run with the first
//! setting, and every `EVERY` steps a copy of the system makes one step with each
//! setting (warm start and contacts as on the trajectory). A run's sweep count is
//! one draw of a chaotic trajectory; here every setting solves the very same
//! problems, so the ratios are paired.
//!
//! `cargo run --release --example nlgs_measure -- SCENE STEPS EVERY SETTING...`
//! with SETTING = `[SOLVER/]POLICY:TOLERANCE:MEASURE[:MAX_SWEEPS][@OMEGA]` (e.g. `quad:1e-4:sweep
//! quad:1e-4:check apgd/quad:1e-5:check quad:1e-5:check@1.3 quad:1e-7:check:20000`;
//! SOLVER `nlgs`, the default, or `apgd`; OMEGA the over-relaxation, default 1).
//! Writes one CSV row per sampled step and setting on standard output and the totals
//! on standard error. One thread: the ratios are of one core's work.
//!
//! The velocities each setting ends its step with are compared with those of the
//! *last* setting (give the tightest last): `max_du_m_s`, the largest difference
//! of a mobile body's translational velocity, and, if the scene has a body named
//! `sleeper`, `sleeper_dy_m`, the difference of its vertical velocity times θ h:
//! how far that step's stopping moved the sleeper's end position, the error that
//! a settlement accumulates (velocities are unique where impulses are not in a
//! hyperstatic packing).

use ballast::nscd::nlgs::Solver;
use ballast::nscd::{Measure, Policy};
use ballast::scene::Scene;
use ballast::scene::SceneFile;
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
struct Row {
    step: u64,
    setting: String,
    sweeps: usize,
    converged: bool,
    criterion: f64,
    wall_s: f64,
    max_du_m_s: f64,
    sleeper_dy_m: f64,
}

type Setting = (Solver, Policy, f64, Measure, Option<usize>, f64);

fn parse(setting: &str) -> Result<Setting, String> {
    let (setting, omega) = match setting.split_once('@') {
        Some((rest, w)) => (rest, w.parse::<f64>().map_err(|e| format!("{w}: {e}"))?),
        None => (setting, 1.0),
    };
    let (solver, setting) = match setting.split_once('/') {
        Some((name, rest)) => (Solver::from_name(name).ok_or(format!("{name}: unknown solver"))?, rest),
        None => (Solver::Nlgs, setting),
    };
    let parts: Vec<&str> = setting.split(':').collect();
    let (policy, tolerance, measure, max) = match parts[..] {
        [p, t, m] => (p, t, m, None),
        [p, t, m, x] => (p, t, m, Some(x.parse::<usize>().map_err(|e| format!("{x}: {e}"))?)),
        _ => return Err(format!("{setting}: expected POLICY:TOLERANCE:MEASURE[:MAX_SWEEPS]")),
    };
    let policy = Policy::from_name(policy).ok_or(format!("{policy}: unknown policy"))?;
    let measure = match measure {
        "sweep" => Measure::Sweep,
        "check" => Measure::Check,
        m => return Err(format!("{m}: unknown measure")),
    };
    Ok((solver, policy, tolerance.parse().map_err(|e| format!("{tolerance}: {e}"))?, measure, max, omega))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, settings @ ..] = &args[..] else {
        return Err(
            "usage: nlgs_measure SCENE STEPS EVERY [SOLVER/]POLICY:TOLERANCE:MEASURE[:MAX_SWEEPS][@OMEGA]...".into()
        );
    };
    let (steps, every): (u64, u64) = (steps.parse()?, every.parse()?);
    let settings = settings.iter().map(|s| parse(s).map(|p| (s.clone(), p))).collect::<Result<Vec<_>, _>>()?;
    if settings.is_empty() {
        return Err("give at least one setting".into());
    }
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let configure = |sys: &mut ballast::nscd::System, (solver, policy, tolerance, measure, max, omega): Setting| {
        let n = &mut sys.params.nlgs;
        (n.solver, n.policy, n.tolerance, n.measure, n.relaxation) = (solver, policy, tolerance, measure, omega);
        if let Some(max) = max {
            n.max_iterations = max;
        }
    };
    let sleeper = sys.bodies.info.iter().position(|b| b.name == "sleeper");
    let mobile: Vec<usize> = (0..sys.bodies.len()).filter(|&i| sys.bodies.inv_m[i][..2] != [0.0; 2]).collect();
    configure(&mut sys, settings[0].1);
    let mut out = csv::Writer::from_writer(std::io::stdout());
    let mut totals = vec![(0usize, 0.0f64, 0usize, 0.0f64, 0.0f64); settings.len()];
    let theta_h = sys.params.theta * sys.params.dt;
    for k in 1..=steps {
        if k % every == 0 {
            let mut rows = Vec::new();
            let mut ends = Vec::new();
            for (i, (name, setting)) in settings.iter().enumerate() {
                let mut copy = sys.clone();
                configure(&mut copy, *setting);
                let start = Instant::now();
                let st = copy.step()?;
                let wall_s = start.elapsed().as_secs_f64();
                totals[i].0 += st.iterations;
                totals[i].1 += wall_s;
                totals[i].2 += usize::from(!st.converged);
                ends.push(copy.bodies.u.clone());
                rows.push(Row {
                    step: k,
                    setting: name.clone(),
                    sweeps: st.iterations,
                    converged: st.converged,
                    criterion: st.criterion,
                    wall_s,
                    max_du_m_s: 0.0,
                    sleeper_dy_m: f64::NAN,
                });
            }
            let reference = ends.last().cloned().unwrap_or_default();
            for (i, (row, u)) in rows.iter_mut().zip(&ends).enumerate() {
                row.max_du_m_s = mobile
                    .iter()
                    .map(|&b| (u[b][0] - reference[b][0]).hypot(u[b][1] - reference[b][1]))
                    .fold(0.0, f64::max);
                if let Some(s) = sleeper {
                    row.sleeper_dy_m = theta_h * (u[s][1] - reference[s][1]);
                    totals[i].4 += row.sleeper_dy_m.abs();
                }
                totals[i].3 = totals[i].3.max(row.max_du_m_s);
                out.serialize(&*row)?;
            }
        }
        sys.step()?;
    }
    out.flush()?;
    let (base_sweeps, base_wall, ..) = totals[0];
    let sampled = (steps / every).max(1) as f64;
    for ((name, _), (sweeps, wall, capped, du, dy)) in settings.iter().zip(&totals) {
        eprintln!(
            "{name}: {sweeps} sweeps ({:.3} of the first), {wall:.2} s ({:.3} of the first), {capped} at the cap; \
             against the last: max |du| {du:.3e} m/s, mean |sleeper dy| {:.3e} m per step",
            *sweeps as f64 / base_sweeps.max(1) as f64,
            wall / base_wall.max(1e-12),
            dy / sampled
        );
    }
    Ok(())
}
