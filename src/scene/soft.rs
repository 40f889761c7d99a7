//! `[soft]`: a 2D scene run by the planar MD engine ([`crate::md::planar`]) —
//! with `[simulation] engine = "md2d"` (formerly `"md"` with `dimension = 2`), or
//! `ballast run --engine md2d` on any 2D scene. The bodies, loads, springs and `[[contact]]`
//! entries (friction, restitution) are the scene's; `[soft]` gives the contact
//! stiffness and the time step, which rigid NSCD has no use for (an NSCD run
//! ignores the table, so one file runs on both engines).
//!
//! Decisions (`docs/scene-format.md`): the planar step is `soft.dt` (default
//! `"auto"`: a fraction of the contact time), not `simulation.dt` (the NSCD
//! step); the run keeps `simulation.duration`. The stiffness is
//! `normal_stiffness` or, if it is absent, derived from `max_overlap_ratio`
//! (default 1e-3) through [`crate::md::planar::stiffness`]. A pair of materials
//! without a `[[contact]]` entry is frictionless and critically damped (the NSCD
//! default: μ = 0, e = 0).

use super::format::Scene;
use super::validate::{err, num};
use crate::error::{Error, Result};
use crate::md::planar::stiffness::{self, Reference, DEFAULT_DT_FRACTION};
use crate::md::planar::{PlanarParams, PlanarSystem, SoftLaw, SoftModel};
use crate::scene::SceneFile;
use serde::{Deserialize, Serialize};

/// The default `max_overlap_ratio` when the scene gives no stiffness.
pub const DEFAULT_OVERLAP_RATIO: f64 = 1e-3;
/// The default `tangential_ratio` `k_t / k_n`.
pub const DEFAULT_TANGENTIAL_RATIO: f64 = 0.5;

/// `[soft]`: every key is optional.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SoftSection {
    /// `"linear"` (default) or `"hertz"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<String>,
    /// Pair stiffness per metre of thickness: N/m per m (`linear`), N/m^{3/2} per m (`hertz`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub normal_stiffness: Option<f64>,
    /// The overlap of a base contact under the peak load over the smallest
    /// inradius, in (0, 0.1]; the stiffness is derived from it (not with `normal_stiffness`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_overlap_ratio: Option<f64>,
    /// `k_t / k_n`, ≥ 0; default 0.5.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangential_ratio: Option<f64>,
    /// The time step (s), or `"auto"` (default): `dt_fraction` of the contact time.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<SoftDt>,
    /// `dt = "auto"`: the fraction of the contact time, in (0, 0.5]; default 0.02.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt_fraction: Option<f64>,
    /// Detection distance (m), ≥ 0; default 0 (only overlapping points matter).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alert_distance: Option<f64>,
}

/// `soft.dt`: seconds or a word (only `"auto"` is valid).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum SoftDt {
    /// A time step (s).
    Seconds(f64),
    /// `"auto"`.
    Word(String),
}

/// What `[soft]` resolves to for the scene's bodies, recorded in the run's
/// `run.json` (`model`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SoftModelInfo {
    /// `"linear"` or `"hertz"`.
    pub model: SoftModel,
    /// Pair stiffness per metre of thickness (N/m/m or N/m^{3/2}/m).
    pub normal_stiffness: f64,
    /// The same times the thickness: the stiffness of a contact (N/m or N/m^{3/2}).
    pub pair_stiffness: f64,
    /// Whether it was derived from `max_overlap_ratio` (else given).
    pub derived: bool,
    /// The target overlap ratio, if derived.
    pub max_overlap_ratio: Option<f64>,
    /// `F_ref` (N) and the columns it is spread over ([`crate::md::planar::stiffness`]).
    pub reference_load_n: f64,
    /// Columns of grains across the sample.
    pub columns: usize,
    /// The smallest inradius of the mobile bodies (m).
    pub smallest_inradius_m: f64,
    /// `k_t / k_n`.
    pub tangential_ratio: f64,
    /// The largest dashpot ratio of the pairs.
    pub damping_ratio_max: f64,
    /// Contact time `π/ω` of the stiffest oscillator (s).
    pub contact_time_s: f64,
    /// Velocity Verlet's stability limit (s).
    pub stability_limit_s: f64,
    /// The time step (s).
    pub dt_s: f64,
}

/// Checks the ranges of `[soft]` (what needs no bodies); one-line errors naming the key.
pub(crate) fn check_soft(s: &SoftSection) -> Result<SoftModel> {
    let model = match s.model.as_deref() {
        None => SoftModel::Linear,
        Some(name) => SoftModel::from_name(name).ok_or_else(|| {
            Error::Scene(format!(
                "soft.model: unknown model '{}', expected 'linear' or 'hertz'",
                crate::error::clip(name)
            ))
        })?,
    };
    if s.normal_stiffness.is_some() && s.max_overlap_ratio.is_some() {
        return err("soft: give normal_stiffness or max_overlap_ratio, not both".into());
    }
    if let Some(k) = s.normal_stiffness {
        if !(k.is_finite() && k > 0.0) {
            return err(format!("soft.normal_stiffness: must be positive and finite, got {}", num(k)));
        }
    }
    if let Some(r) = s.max_overlap_ratio {
        if !(r > 0.0 && r <= 0.1) {
            return err(format!("soft.max_overlap_ratio: must be in (0, 0.1], got {}", num(r)));
        }
    }
    if let Some(r) = s.tangential_ratio {
        if !(r.is_finite() && r >= 0.0) {
            return err(format!("soft.tangential_ratio: must be >= 0 and finite, got {}", num(r)));
        }
    }
    match &s.dt {
        Some(SoftDt::Seconds(dt)) if !(dt.is_finite() && *dt > 0.0) => {
            return err(format!("soft.dt: must be a positive time step (s) or \"auto\", got {}", num(*dt)));
        }
        Some(SoftDt::Word(w)) if w != "auto" => {
            return err(format!("soft.dt: must be a time step (s) or \"auto\", got '{}'", crate::error::clip(w)));
        }
        _ => {}
    }
    if let Some(f) = s.dt_fraction {
        if !(f > 0.0 && f <= 0.5) {
            return err(format!("soft.dt_fraction: must be in (0, 0.5], got {}", num(f)));
        }
        if matches!(s.dt, Some(SoftDt::Seconds(_))) {
            return err("soft.dt_fraction: only with dt = \"auto\"".into());
        }
    }
    if let Some(a) = s.alert_distance {
        if !(a.is_finite() && a >= 0.0) {
            return err(format!("soft.alert_distance: must be >= 0 and finite, got {}", num(a)));
        }
    }
    Ok(model)
}

impl Scene {
    /// Whether the scene asks for the planar MD engine (`engine = "md2d"`, or its former spelling
    /// `engine = "md"` with `dimension = 2`).
    pub fn is_planar_md(&self) -> bool {
        let sim = &self.simulation;
        sim.engine == "md2d" || (sim.engine == "md" && sim.dimension == Some(2))
    }

    /// The same scene set to run on `engine` (`"nscd"`, or `"md2d"` for the planar MD engine, also read as
    /// `"md"`: the engine a 2D scene has on the MD side), validated; the scene then names it `"nscd"` or
    /// `"md2d"`.
    ///
    /// # Errors
    /// [`Error::Scene`] for another engine name or if the scene is then invalid.
    pub fn on_engine(&self, engine: &str) -> Result<Scene> {
        let mut out = self.clone();
        // A `dimension = 2` that only spelled the planar engine goes with it.
        let dimension = self.simulation.dimension.filter(|_| self.simulation.engine != "md");
        match engine {
            "nscd" => out.simulation.engine = "nscd".into(),
            "md2d" | "md" => out.simulation.engine = "md2d".into(),
            other => {
                return err(format!(
                    "engine: unknown engine '{}', expected 'nscd', 'md2d' or 'md'",
                    crate::error::clip(other)
                ))
            }
        }
        out.simulation.dimension = dimension;
        out.validate()?;
        Ok(out)
    }

    /// Builds the planar MD system of the scene at time 0 (module doc), with
    /// what `[soft]` resolved to.
    ///
    /// # Errors
    /// [`Error::Scene`] for an invalid scene, a scene without a mobile body when
    /// the stiffness or the step must be derived, or a time step above the
    /// stability limit (both named).
    pub fn build_planar(&self) -> Result<(PlanarSystem, SoftModelInfo)> {
        let checked = super::validate::check(self)?;
        let section = self.soft.clone().unwrap_or_default();
        let model = check_soft(&section)?;
        let (bodies, springs) = self.build_bodies(&checked)?;
        let gravity = self.simulation.gravity_or(PlanarParams::default().gravity);
        let thickness = self.simulation.thickness();
        let reference = stiffness::reference(&bodies, gravity);
        let need = || {
            reference.ok_or_else(|| {
                Error::Scene("soft: no mobile body to derive the stiffness or the time step from".into())
            })
        };
        let (pair_stiffness, derived, ratio) = match section.normal_stiffness {
            Some(k) => (k * thickness, false, None),
            None => {
                let ratio = section.max_overlap_ratio.unwrap_or(DEFAULT_OVERLAP_RATIO);
                (stiffness::stiffness_for_overlap(model, &need()?, ratio), true, Some(ratio))
            }
        };
        let tangential_ratio = section.tangential_ratio.unwrap_or(DEFAULT_TANGENTIAL_RATIO);
        let materials = self.materials.len();
        let mut laws = vec![(0.0, 0.0); materials * materials];
        let index = |name: &str| self.materials.iter().position(|m| m.name == name).unwrap_or(0);
        for c in &self.contacts {
            let (a, b) = (index(&c.between[0]), index(&c.between[1]));
            let law = (c.friction, c.restitution.unwrap_or(0.0));
            laws[a * materials + b] = law;
            laws[b * materials + a] = law;
        }
        let law = |(friction, restitution): (f64, f64)| SoftLaw {
            model,
            normal_stiffness: pair_stiffness,
            tangential_ratio,
            restitution,
            friction,
        };
        let alpha = laws.iter().map(|&l| law(l).damping_ratio()).fold(0.0, f64::max);
        let r = need().ok();
        let (contact_time, limit) = match &r {
            Some(r) => stiffness::time_scales(model, pair_stiffness, alpha, r),
            None => (f64::INFINITY, f64::INFINITY),
        };
        let dt = match section.dt {
            Some(SoftDt::Seconds(dt)) => dt,
            _ => {
                need()?;
                section.dt_fraction.unwrap_or(DEFAULT_DT_FRACTION) * contact_time
            }
        };
        if dt > limit {
            return err(format!(
                "soft.dt: {} s is above the stability limit {} s of the stiffest contact (contact time {} s); \
                 use a smaller dt or dt = \"auto\"",
                num(dt),
                num(limit),
                num(contact_time)
            ));
        }
        let params = PlanarParams { dt, gravity, alert_distance: section.alert_distance.unwrap_or(0.0) };
        let mut sys = PlanarSystem::new(params, materials);
        for a in 0..materials {
            for b in a..materials {
                sys.set_law(a, b, law(laws[a * materials + b]))?;
            }
        }
        sys.bodies = bodies;
        sys.springs = springs;
        let info = SoftModelInfo {
            model,
            normal_stiffness: pair_stiffness / thickness,
            pair_stiffness,
            derived,
            max_overlap_ratio: ratio,
            reference_load_n: r.map_or(0.0, |r: Reference| r.load),
            columns: r.map_or(0, |r| r.columns),
            smallest_inradius_m: r.map_or(0.0, |r| r.inradius),
            tangential_ratio,
            damping_ratio_max: alpha,
            contact_time_s: contact_time,
            stability_limit_s: limit,
            dt_s: dt,
        };
        Ok((sys, info))
    }
}

impl Scene {
    /// The run plan of the scene on the planar MD engine, whose step is `dt`
    /// (s): as [`Scene::plan`](crate::scene::SceneFile::plan), with `round(duration / dt)` steps.
    ///
    /// # Errors
    /// [`Error::Scene`] if the scene is invalid.
    pub fn plan_planar(&self, dt: f64) -> Result<crate::run::RunPlan> {
        let mut plan = self.plan()?;
        plan.steps = super::validate::steps_of(dt, self.simulation.duration);
        Ok(plan)
    }
}
