//! Stopping rules compared on the same problems: a scene is run with the first
//! setting, and every `EVERY` steps a copy of the system makes one step with each
//! setting (warm start and contacts as on the trajectory). A run's sweep count is
//! one draw of a chaotic trajectory; here every setting solves the very same
//! problems, so the ratios are paired.
//!
//! `cargo run --release --example nlgs_measure -- SCENE STEPS EVERY SETTING...`
//! with SETTING = `POLICY:TOLERANCE:MEASURE` (e.g. `quad:1e-4:sweep quad:1e-4:check`).
//! Writes one CSV row per sampled step and setting on standard output and the totals
//! on standard error. One thread: the ratios are of one core's work.

use ballast::nscd::{Measure, Policy};
use ballast::scene::Scene;
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
}

fn parse(setting: &str) -> Result<(Policy, f64, Measure), String> {
    let parts: Vec<&str> = setting.split(':').collect();
    let [policy, tolerance, measure] = parts[..] else {
        return Err(format!("{setting}: expected POLICY:TOLERANCE:MEASURE"));
    };
    let policy = match policy {
        "strict" => Policy::Strict,
        "quad" => Policy::Quad,
        "quad_max" => Policy::QuadMax,
        "energy" => Policy::Energy,
        p => return Err(format!("{p}: unknown policy")),
    };
    let measure = match measure {
        "sweep" => Measure::Sweep,
        "check" => Measure::Check,
        m => return Err(format!("{m}: unknown measure")),
    };
    Ok((policy, tolerance.parse().map_err(|e| format!("{tolerance}: {e}"))?, measure))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [scene, steps, every, settings @ ..] = &args[..] else {
        return Err("usage: nlgs_measure SCENE STEPS EVERY POLICY:TOLERANCE:MEASURE...".into());
    };
    let (steps, every): (u64, u64) = (steps.parse()?, every.parse()?);
    let settings = settings.iter().map(|s| parse(s).map(|p| (s.clone(), p))).collect::<Result<Vec<_>, _>>()?;
    if settings.is_empty() {
        return Err("give at least one setting".into());
    }
    let mut sys = Scene::load(scene)?.build()?;
    sys.set_threads(1);
    let configure = |sys: &mut ballast::nscd::System, (policy, tolerance, measure): (Policy, f64, Measure)| {
        let n = &mut sys.params.nlgs;
        (n.policy, n.tolerance, n.measure) = (policy, tolerance, measure);
    };
    configure(&mut sys, settings[0].1);
    let mut out = csv::Writer::from_writer(std::io::stdout());
    let mut totals = vec![(0usize, 0.0f64, 0usize); settings.len()];
    for k in 1..=steps {
        if k % every == 0 {
            for (i, (name, setting)) in settings.iter().enumerate() {
                let mut copy = sys.clone();
                configure(&mut copy, *setting);
                let start = Instant::now();
                let st = copy.step()?;
                let wall_s = start.elapsed().as_secs_f64();
                totals[i].0 += st.iterations;
                totals[i].1 += wall_s;
                totals[i].2 += usize::from(!st.converged);
                out.serialize(Row {
                    step: k,
                    setting: name.clone(),
                    sweeps: st.iterations,
                    converged: st.converged,
                    criterion: st.criterion,
                    wall_s,
                })?;
            }
        }
        sys.step()?;
    }
    out.flush()?;
    let (base_sweeps, base_wall, _) = totals[0];
    for ((name, _), (sweeps, wall, capped)) in settings.iter().zip(&totals) {
        eprintln!(
            "{name}: {sweeps} sweeps ({:.3} of the first), {wall:.2} s ({:.3} of the first), {capped} at the cap",
            *sweeps as f64 / base_sweeps.max(1) as f64,
            wall / base_wall.max(1e-12)
        );
    }
    Ok(())
}
