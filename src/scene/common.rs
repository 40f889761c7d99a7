//! The sections every scene has, whatever its engine: `[simulation]` (engine,
//! dimension, time step, duration, gravity, seed, equilibrium stop) and
//! `[output]` (rows of `series.csv`, per-cycle output). They are parsed by the
//! same serde types for NSCD and MD scenes, checked by the same functions
//! (`check_simulation`, `check_output`) and written back by the same code;
//! `run_plan` turns them into the run loop's [`RunPlan`].

use super::validate::{check_time, err, finite, positive, steps_of};
use super::write::{float, opt, string};
use crate::error::Result;
use crate::run::{CyclePlan, Equilibrium, RunPlan};
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// Default number of steps between two rows of `series.csv`.
pub const DEFAULT_OUTPUT_EVERY: u64 = 1;

/// `[simulation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Simulation {
    /// Engine name: `"nscd"` or `"md"`.
    pub engine: String,
    /// Space dimension: 2 for NSCD scenes, 3 for MD scenes (optional).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dimension: Option<i64>,
    /// Time step `h` (s), > 0.
    pub dt: f64,
    /// Simulated duration (s), > 0; the run makes `round(duration / dt)` steps.
    pub duration: f64,
    /// Gravity (m/s²): 2 components in 2D, 3 in 3D; default `[0, -9.81]` in 2D,
    /// `[0, 0, -9.81]` in 3D.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<Vec<f64>>,
    /// Out-of-plane thickness (m), > 0, 2D only; default 1. A body of area `A`
    /// (m²) and density `ρ` (kg/m³) has mass `ρ A thickness` (kg).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness: Option<f64>,
    /// Random seed, recorded in the outputs; default 0.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub seed: Option<u64>,
    /// Ends the run early at equilibrium (a deposit): see [`Equilibrium`].
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub equilibrium: Option<Equilibrium>,
}

impl Simulation {
    /// Number of time steps of the run, `round(duration / dt)` (0 if `dt` is not positive).
    pub fn steps(&self) -> u64 {
        steps_of(self.dt, self.duration)
    }

    /// Sets the run's length for one run (`ballast run --duration | --steps`):
    /// `duration` (s) as is, or `steps` time steps (`duration = steps · dt`).
    ///
    /// # Errors
    /// [`crate::Error::Scene`] naming the option if the length is not a positive
    /// number of steps the scene allows.
    pub fn set_length(&mut self, length: crate::run::RunLength) -> crate::Result<()> {
        use crate::run::RunLength;
        let duration = match length {
            RunLength::Duration(d) => d,
            RunLength::Steps(0) => return Err(crate::Error::Scene("length.steps: must be at least 1".into())),
            RunLength::Steps(n) => n as f64 * self.dt,
        };
        super::validate::check_time(self.dt, duration).map_err(|e| match (length, e) {
            (RunLength::Duration(_), crate::Error::Scene(m)) => crate::Error::Scene(format!("length.duration: {m}")),
            (RunLength::Steps(_), crate::Error::Scene(m)) => crate::Error::Scene(format!("length.steps: {m}")),
            (_, e) => e,
        })?;
        self.duration = duration;
        Ok(())
    }

    /// Random seed recorded in the outputs (default 0).
    pub fn seed(&self) -> u64 {
        self.seed.unwrap_or(0)
    }

    /// Out-of-plane thickness of a 2D scene (m); default 1.
    pub fn thickness(&self) -> f64 {
        self.thickness.unwrap_or(super::format::DEFAULT_THICKNESS)
    }

    /// The gravity of a scene of dimension `N` (m/s²): the scene's, or `default`
    /// if it has none or not `N` components (refused by the validation).
    pub fn gravity_or<const N: usize>(&self, default: [f64; N]) -> [f64; N] {
        self.gravity.as_deref().and_then(|g| g.try_into().ok()).unwrap_or(default)
    }
}

/// `[output]`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSection {
    /// Steps between two rows of `series.csv`, ≥ 1 (the last step always has a row).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub every: Option<u64>,
    /// Per-cycle output of a cyclically loaded run (`cycles.csv`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cycles: Option<CyclesSpec>,
}

/// `output.cycles`: one row of `cycles.csv` per loading cycle of `frequency` (Hz).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CyclesSpec {
    /// Loading frequency (Hz), > 0: a cycle lasts `1/frequency` s from t = 0.
    pub frequency: f64,
    /// Name of the followed body (NSCD: required, the sleeper; MD: not used).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<String>,
    /// Also write the positions of every mobile body at the end of each cycle
    /// (`cycle_bodies.csv`, `cycle_displacements.npy`); default false.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub positions: Option<bool>,
}

/// Checks `[simulation]` of a scene for `engine` in `dimension` (2 or 3); the
/// message names the field.
pub(crate) fn check_simulation(sim: &Simulation, engine: &str, dimension: i64) -> Result<()> {
    if !super::ENGINES.contains(&sim.engine.as_str()) {
        return err(format!(
            "simulation.engine: unknown engine '{}', expected 'nscd', 'md2d' or 'md'",
            crate::error::clip(&sim.engine)
        ));
    }
    if sim.engine != engine {
        let other = if engine == "md" { "scene::Scene" } else { "scene::MdScene" };
        return err(format!(
            "simulation.engine: expected '{engine}', got '{}' (read it with {other})",
            crate::error::clip(&sim.engine)
        ));
    }
    if let Some(d) = sim.dimension.filter(|&d| d != dimension) {
        let hint = if engine == "nscd" && d == 3 { " (a 3D NSCD scene is read with scene::Scene3)" } else { "" };
        return err(format!("simulation.dimension: must be {dimension} for the {engine} engine, got {d}{hint}"));
    }
    check_time(sim.dt, sim.duration)?;
    if let Some(g) = &sim.gravity {
        if g.len() != dimension as usize {
            return err(format!(
                "simulation.gravity: a {dimension}D scene needs {dimension} components, got {}",
                g.len()
            ));
        }
        for (k, &x) in g.iter().enumerate() {
            finite(&format!("simulation.gravity[{k}]"), x)?;
        }
    }
    if let Some(t) = sim.thickness {
        if dimension != 2 {
            return err("simulation.thickness: only for 2D scenes".into());
        }
        positive("simulation.thickness", t)?;
    }
    if let Some(e) = &sim.equilibrium {
        e.check()?;
    }
    Ok(())
}

/// Checks `[output]`; `body_index` resolves a body name. Returns the per-cycle
/// plan, with the followed body resolved; `need_body`: the engine follows a body.
pub(crate) fn check_output(
    out: Option<&OutputSection>,
    need_body: bool,
    body_index: impl Fn(&str) -> Option<usize>,
) -> Result<Option<CyclePlan>> {
    let Some(out) = out else { return Ok(None) };
    if out.every == Some(0) {
        return err("output.every: must be at least 1, got 0".into());
    }
    let Some(c) = &out.cycles else { return Ok(None) };
    positive("output.cycles.frequency", c.frequency)?;
    let body = match (&c.body, need_body) {
        (Some(name), true) => match body_index(name).filter(|_| !name.is_empty()) {
            Some(i) => Some(i),
            None => return err(format!("output.cycles.body: unknown body '{}'", crate::error::clip(name))),
        },
        (None, true) => return err("output.cycles.body: name the followed body (the sleeper)".into()),
        (Some(_), false) => {
            return err("output.cycles.body: not used by this engine (the cycles follow every sphere)".into())
        }
        (None, false) => None,
    };
    Ok(Some(CyclePlan { frequency: c.frequency, body, positions: c.positions.unwrap_or(false) }))
}

/// The run plan of a validated scene with these sections.
pub(crate) fn run_plan(sim: &Simulation, out: Option<&OutputSection>, cycles: Option<CyclePlan>) -> RunPlan {
    RunPlan {
        steps: sim.steps(),
        output_every: out.and_then(|o| o.every).unwrap_or(DEFAULT_OUTPUT_EVERY).max(1),
        equilibrium: sim.equilibrium,
        cycles,
        seed: sim.seed(),
    }
}

/// Appends `[simulation]` as TOML (only the keys the scene has).
pub(crate) fn write_simulation(out: &mut String, sim: &Simulation) {
    out.push_str("[simulation]\n");
    let _ = writeln!(out, "engine = {}", string(&sim.engine));
    opt(out, "dimension", sim.dimension, |d| d.to_string());
    let _ = writeln!(out, "dt = {}", float(sim.dt));
    let _ = writeln!(out, "duration = {}", float(sim.duration));
    opt(out, "gravity", sim.gravity.as_ref(), |g| {
        format!("[{}]", g.iter().map(|&x| float(x)).collect::<Vec<_>>().join(", "))
    });
    opt(out, "thickness", sim.thickness, float);
    opt(out, "seed", sim.seed, |s| s.to_string());
    opt(out, "equilibrium", sim.equilibrium, |e| {
        inline(&[
            ("kinetic_energy", e.kinetic_energy.map(float)),
            ("energy_ratio", e.energy_ratio.map(float)),
            ("steps", e.steps.map(|n| n.to_string())),
        ])
    });
}

/// Appends `[output]` as TOML, if the scene has it.
pub(crate) fn write_output(out: &mut String, o: Option<&OutputSection>) {
    let Some(o) = o else { return };
    out.push_str("\n[output]\n");
    opt(out, "every", o.every, |e| e.to_string());
    opt(out, "cycles", o.cycles.as_ref(), |c| {
        inline(&[
            ("frequency", Some(float(c.frequency))),
            ("body", c.body.as_deref().map(string)),
            ("positions", c.positions.map(|p| p.to_string())),
        ])
    });
}

/// `{ k = v, … }` of the entries that are present.
pub(crate) fn inline(entries: &[(&str, Option<String>)]) -> String {
    let parts: Vec<String> = entries.iter().filter_map(|(k, v)| v.as_ref().map(|v| format!("{k} = {v}"))).collect();
    if parts.is_empty() {
        "{}".into()
    } else {
        format!("{{ {} }}", parts.join(", "))
    }
}

/// `[settlement]`: the settlement-acceleration procedure of Karrech et al. 2007
/// (Fig. 10; [`crate::settlement::driver`]) instead of a plain run, in a cyclic
/// scene of either engine (one with `[output] cycles`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SettlementSection {
    /// `k_i`: cycles computed before the first fit, ≥ 0 (≥ 1 with a Shenton law).
    pub initial_cycles: u64,
    /// `k`: computed cycles per fit, ≥ 2.
    pub computed_cycles: u64,
    /// `h`: cycles extrapolated by the first jump, ≥ 1.
    pub extrapolated_cycles: u64,
    /// Factor on `h` after each jump, ≥ 1; default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub growth: Option<f64>,
    /// `"shenton"` (default) or `"linear"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub law: Option<String>,
    /// Largest overlap left by the relaxation: a length (m), > 0, or
    /// `"computed"` (the default): at each jump, the largest overlap of the
    /// computed configuration the jump starts from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relax_tolerance: Option<RelaxTolerance>,
    /// Iterations of the relaxation at most, ≥ 1; default 10 000.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relax_max_iterations: Option<u64>,
    /// `"lbfgs"` (default) or `"gradient_descent"` (the paper's method).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relax_method: Option<String>,
    /// Adaptive `k`: the error `ε` (m) of eq. (15); with `probability`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub error: Option<f64>,
    /// Adaptive `k`: the probability `p` of eq. (15), in (0, 1); with `error`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub probability: Option<f64>,
    /// The body whose vertical displacement is the settlement (the sleeper, the
    /// plate); default: the mean over the mobile bodies.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settlement_body: Option<String>,
    /// The largest move a jump may give a body, as a fraction of its size
    /// (NSCD the equal-area radius √(A/π), MD the radius), > 0; default 0.25.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extrapolation_limit: Option<f64>,
    /// Smooth each jump's moves over the neighbours within a few of this
    /// length (m, > 0); default: none, every body on its own fit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smoothing_length: Option<f64>,
    /// Computed cycles after each jump before the window's data start (≥ 1,
    /// less than `computed_cycles`); default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_cycles: Option<u64>,
    /// Keep re-seating past `settle_cycles` while the settlement's increment
    /// exceeds this factor (> 0) times the rate predicted at the landing;
    /// default: none, a fixed count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub settle_rate: Option<f64>,
    /// Roll a landing back when the window after it settles at more than this
    /// factor (> 0) times the rate predicted at the landing, in absolute value;
    /// default: none (landings judged by the engine's failures and the domain).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rollback_rate: Option<f64>,
    /// The largest move of a point of a body in one stage of a landing, as a
    /// fraction of the smallest body's size (> 0; `inf`: one relaxation of the
    /// extrapolated configuration, the paper's); default 0.25
    /// ([`crate::settlement::sweep`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub relax_stage: Option<f64>,
    /// Hold the bodies tied to a fixed anchor by a spring (the sublayer pads) at
    /// their computed positions through each landing; default `false`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hold_anchored: Option<bool>,
}

/// `settlement.relax_tolerance`: a length (m) or a word (`"computed"`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum RelaxTolerance {
    /// This largest overlap (m).
    Length(f64),
    /// `"computed"`: the largest overlap of the computed configuration each
    /// jump starts from ([`crate::settlement::Acceleration::relax_to_computed`]).
    Word(String),
}

/// A validated `[settlement]`: the procedure's settings, the loading frequency
/// (Hz) and the cycles to reach (`round(duration × frequency)`).
#[derive(Debug, Clone, PartialEq)]
pub struct AccelerationPlan {
    /// The procedure's settings.
    pub spec: crate::settlement::Acceleration,
    /// Loading frequency (Hz), from `[output] cycles`.
    pub frequency: f64,
    /// Cycles to reach.
    pub cycles: u64,
}

/// What `settlement.settlement_body` names: a mobile body (its index), or a
/// boundary that moves under its own dynamics (an MD servo wall: its index
/// among them).
pub(crate) enum SettlementRef {
    Body(usize),
    Boundary(usize),
}

/// Checks `[settlement]` against the scene's `[output] cycles` and duration;
/// `mobile_body` resolves the settlement body's name to a mobile body (or says
/// why not).
pub(crate) fn check_settlement(
    s: Option<&SettlementSection>,
    cycles: Option<&CyclePlan>,
    sim: &Simulation,
    mobile_body: impl Fn(&str) -> std::result::Result<SettlementRef, String>,
) -> Result<Option<AccelerationPlan>> {
    use crate::engine::Method;
    use crate::settlement::{Acceleration, Adaptive, Law};
    let Some(s) = s else { return Ok(None) };
    let Some(c) = cycles else {
        return err("settlement: needs the loading frequency of [output] cycles = { frequency = … }".into());
    };
    let (tolerance, to_computed) = match &s.relax_tolerance {
        Some(RelaxTolerance::Length(t)) => (*t, false),
        None => (f64::MAX, true),
        Some(RelaxTolerance::Word(w)) if w == "computed" => (f64::MAX, true),
        Some(RelaxTolerance::Word(w)) => {
            return err(format!("settlement.relax_tolerance: expected a length (m) or \"computed\", got '{w}'"))
        }
    };
    let mut spec = Acceleration::new(s.initial_cycles, s.computed_cycles, s.extrapolated_cycles, tolerance);
    spec.relax_to_computed = to_computed;
    spec.positions = c.positions;
    if let Some(g) = s.growth {
        spec.growth = g;
    }
    if let Some(l) = &s.law {
        spec.law = Law::from_name(l, "settlement.law")?;
    }
    if let Some(n) = s.relax_max_iterations {
        spec.relax.max_iterations = n;
    }
    if let Some(f) = s.extrapolation_limit {
        spec.extrapolation_limit = f;
    }
    spec.smoothing_length = s.smoothing_length;
    if let Some(n) = s.settle_cycles {
        spec.settle_cycles = n;
    }
    spec.settle_rate = s.settle_rate;
    spec.rollback_rate = s.rollback_rate;
    if let Some(f) = s.relax_stage {
        spec.relax_stage = f;
    }
    spec.hold_anchored = s.hold_anchored.unwrap_or(false);
    spec.relax.method = match s.relax_method.as_deref() {
        None | Some("lbfgs") => Method::Lbfgs,
        Some("gradient_descent") => Method::GradientDescent,
        Some(m) => {
            return err(format!(
                "settlement.relax_method: unknown method '{}' (expected \"lbfgs\" or \"gradient_descent\")",
                crate::error::clip(m)
            ))
        }
    };
    spec.adaptive = match (s.error, s.probability) {
        (Some(error), Some(probability)) => Some(Adaptive { error, probability }),
        (None, None) => None,
        (Some(_), None) => return err("settlement.probability: needed with settlement.error (adaptive k)".into()),
        (None, Some(_)) => return err("settlement.error: needed with settlement.probability (adaptive k)".into()),
    };
    if let Some(name) = &s.settlement_body {
        match mobile_body(name).map_err(|why| crate::Error::Scene(format!("settlement.settlement_body: {why}")))? {
            SettlementRef::Body(i) => spec.settlement_body = Some(i),
            SettlementRef::Boundary(j) => spec.settlement_boundary = Some(j),
        }
    }
    spec.check()?;
    let total = (sim.duration * c.frequency).round();
    if !(1.0..1e12).contains(&total) {
        return err(format!(
            "settlement: simulation.duration × output.cycles.frequency = {} cycles; at least 1 is needed",
            sim.duration * c.frequency
        ));
    }
    Ok(Some(AccelerationPlan { spec, frequency: c.frequency, cycles: total as u64 }))
}

/// Appends `[settlement]` as TOML (only the keys the scene has).
pub(crate) fn write_settlement(out: &mut String, s: Option<&SettlementSection>) {
    let Some(s) = s else { return };
    out.push_str("\n[settlement]\n");
    let _ = writeln!(out, "initial_cycles = {}", s.initial_cycles);
    let _ = writeln!(out, "computed_cycles = {}", s.computed_cycles);
    let _ = writeln!(out, "extrapolated_cycles = {}", s.extrapolated_cycles);
    opt(out, "growth", s.growth, float);
    opt(out, "law", s.law.as_deref(), string);
    match &s.relax_tolerance {
        Some(RelaxTolerance::Length(t)) => {
            let _ = writeln!(out, "relax_tolerance = {}", float(*t));
        }
        Some(RelaxTolerance::Word(w)) => {
            let _ = writeln!(out, "relax_tolerance = {}", string(w));
        }
        None => {}
    }
    opt(out, "relax_max_iterations", s.relax_max_iterations, |n| n.to_string());
    opt(out, "relax_method", s.relax_method.as_deref(), string);
    opt(out, "error", s.error, float);
    opt(out, "probability", s.probability, float);
    opt(out, "settlement_body", s.settlement_body.as_deref(), string);
    opt(out, "extrapolation_limit", s.extrapolation_limit, float);
    opt(out, "smoothing_length", s.smoothing_length, float);
    opt(out, "settle_cycles", s.settle_cycles, |n| n.to_string());
    opt(out, "settle_rate", s.settle_rate, float);
    opt(out, "rollback_rate", s.rollback_rate, float);
    opt(out, "relax_stage", s.relax_stage, float);
    opt(out, "hold_anchored", s.hold_anchored, |b| b.to_string());
}
