//! The settings of an accelerated run (a scene's `[settlement]` table): the residual-displacement law
//! ([`Law`]), the numbers of cycles `k_i`, `k`, `h` and their growth, the adaptive window ([`Adaptive`], the
//! Chernoff bound of Karrech et al. 2007, eq. 15), the relaxation and the landing ([`Acceleration`]), with
//! their defaults and checks.

use super::*;

/// The residual-displacement law of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// Eq. (16).
    Linear,
    /// Shenton's law with a constant, `c + a ln N + b N` (the paper's choice of
    /// law for the procedure; [`crate::settlement::law`] says why the constant).
    #[default]
    Shenton,
    /// Shenton's law with a constant over `a b ≥ 0`: a window's fit that would
    /// accelerate or turn back gives way to its better one-term law.
    ShentonDecelerating,
    /// Shenton's law through the origin, eqs. (17)–(21) as printed.
    ShentonOrigin,
}

impl Law {
    /// The law's estimator.
    pub fn estimator(self) -> &'static dyn ResidualLaw {
        match self {
            Law::Linear => &Linear,
            Law::Shenton => &Shenton,
            Law::ShentonDecelerating => &ShentonDecelerating,
            Law::ShentonOrigin => &ShentonOrigin,
        }
    }

    /// The law's name in scenes and outputs.
    pub fn name(self) -> &'static str {
        self.estimator().name()
    }

    /// The law named `name` (`"linear"`, `"shenton"`, `"shenton_decelerating"`,
    /// `"shenton_origin"`);
    /// `field` names the option in the error.
    ///
    /// # Errors
    /// [`Error::Scene`] naming `field` and the accepted values.
    pub fn from_name(name: &str, field: &str) -> Result<Self> {
        match name {
            "linear" => Ok(Law::Linear),
            "shenton" => Ok(Law::Shenton),
            "shenton_decelerating" => Ok(Law::ShentonDecelerating),
            "shenton_origin" => Ok(Law::ShentonOrigin),
            _ => Err(Error::Scene(format!(
                "{field}: unknown law '{}' (expected \"linear\", \"shenton\", \"shenton_decelerating\" or \
                 \"shenton_origin\")",
                crate::error::clip(name)
            ))),
        }
    }
}

/// The number of computed cycles chosen by the Chernoff bound (eq. 15).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Adaptive {
    /// Error `ε` on a coordinate's mean residual (m), > 0.
    pub error: f64,
    /// Probability `p` of exceeding it, in (0, 1).
    pub probability: f64,
}

/// What the accelerated procedure is asked to do (a scene's `[settlement]`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Acceleration {
    /// `k_i`: cycles computed before the first window.
    pub initial_cycles: u64,
    /// `k`: computed cycles per window, ≥ 2.
    pub computed_cycles: u64,
    /// `h`: cycles extrapolated by the first jump, ≥ 1.
    pub extrapolated_cycles: u64,
    /// Factor on `h` after each jump, ≥ 1.
    pub growth: f64,
    /// The law fitted.
    pub law: Law,
    /// The relaxation after each jump.
    pub relax: RelaxSettings,
    /// Relax each jump's landing down to the largest overlap of the computed
    /// configuration the jump starts from (the last step of its last computed
    /// cycle, at the same load phase), instead of `relax.tolerance`: no contact
    /// then stores more energy than the most loaded contact the engine itself
    /// carried (docs/settlement-driver.md, "The relaxation's tolerance").
    #[serde(default)]
    pub relax_to_computed: bool,
    /// `k` from the Chernoff bound, if asked.
    pub adaptive: Option<Adaptive>,
    /// The body whose vertical displacement is the settlement (index in the
    /// engine); `None`: the mean over the mobile bodies.
    pub settlement_body: Option<usize>,
    /// A boundary ([`Engine::boundaries`], index among them: the MD loading
    /// plate) whose downward displacement is the settlement, instead of a body.
    #[serde(default)]
    pub settlement_boundary: Option<usize>,
    /// Write every mobile body's position at the end of each cycle
    /// ([`crate::run::positions`]): the computed configuration, the fitted trend
    /// over extrapolated cycles, the relaxed one where a jump lands. The
    /// configuration error of `--reference` (eq. 22) needs them in both runs.
    #[serde(default)]
    pub positions: bool,
    /// The largest move a jump may give a body, as a fraction of its size
    /// ([`Engine::body_sizes`]: NSCD √(A/π), MD the radius), > 0; default
    /// [`Acceleration::EXTRAPOLATION_LIMIT`]; never less than [`MEDIAN_MOVES`]
    /// times the median of the bodies' trend moves. A body whose trend goes
    /// further is moved that far along it (docs/settlement-driver.md).
    #[serde(default = "default_extrapolation_limit")]
    pub extrapolation_limit: f64,
    /// Smooth each jump's moves over the neighbours within a few of this
    /// length (m, > 0): the local linear kernel fit of [`Smoothing`], the
    /// settlement body and the bodies without contact left out; `None` (the
    /// paper): every body on its own fit (docs/settlement-driver.md, "Smoothed
    /// field").
    #[serde(default)]
    pub smoothing_length: Option<f64>,
    /// The computed cycles after each jump through which the landing re-seats:
    /// the window's data start at the end of the last of them (≥ 1, less than
    /// `computed_cycles`; default 1: the first cycle after the landing is the
    /// window's first point, its increment not fitted).
    #[serde(default = "default_settle_cycles")]
    pub settle_cycles: u64,
    /// Keep re-seating past `settle_cycles` while the settlement's increment
    /// (mean of the last two computed cycles since the landing) exceeds this
    /// factor times the per-cycle rate the jump's fit predicted at its landing;
    /// these cycles are computed in addition to the window's (at most
    /// `computed_cycles` of them after a landing). `None`: a fixed count
    /// (docs/settlement-driver.md, "A window starts one cycle after a landing").
    #[serde(default)]
    pub settle_rate: Option<f64>,
    /// Roll a landing back when the settlement's mean increment per computed
    /// cycle over the window after it exceeds this factor (> 0) times the
    /// per-cycle rate its fit predicted at the landing, in absolute value
    /// ([`rollback`]); `None`: landings are judged by the engine's
    /// failures and the domain only.
    #[serde(default)]
    pub rollback_rate: Option<f64>,
    /// The largest move of a point of a body in one stage of a landing, as a
    /// fraction of the smallest body's size ([`sweep`]), > 0; default
    /// [`sweep::RELAX_STAGE`]; infinite: one relaxation of the extrapolated
    /// configuration (the paper's).
    #[serde(default = "default_relax_stage")]
    pub relax_stage: f64,
    /// Hold the bodies tied to a fixed anchor by a spring
    /// ([`Engine::anchored_bodies`]: the sublayer pads) at their computed
    /// positions through each landing: not extrapolated, not moved by the
    /// relaxation. Default `false` (every body on its own fit, the paper's). A
    /// pad carries a share of a load whose mean does not change from cycle to
    /// cycle, so its residual trend is noise; the relaxation leaves the springs
    /// out, and a pad it pushes down loads its spring (docs/settlement-driver.md,
    /// "Held pads").
    #[serde(default)]
    pub hold_anchored: bool,
}

fn default_relax_stage() -> f64 {
    sweep::RELAX_STAGE
}

fn default_settle_cycles() -> u64 {
    1
}

fn default_extrapolation_limit() -> f64 {
    Acceleration::EXTRAPOLATION_LIMIT
}

impl Acceleration {
    /// The default `extrapolation_limit`: a quarter of a body's size per jump
    /// (docs/settlement-driver.md, "Bounded moves").
    pub const EXTRAPOLATION_LIMIT: f64 = 0.25;

    /// `k_i`, `k`, `h` with the defaults: Shenton's law, no growth, relaxation to
    /// `relax_tolerance` (m) in at most 10 000 iterations.
    pub fn new(initial_cycles: u64, computed_cycles: u64, extrapolated_cycles: u64, relax_tolerance: f64) -> Self {
        Self {
            initial_cycles,
            computed_cycles,
            extrapolated_cycles,
            growth: 1.0,
            law: Law::Shenton,
            relax: RelaxSettings::new(relax_tolerance),
            relax_to_computed: false,
            adaptive: None,
            settlement_body: None,
            settlement_boundary: None,
            positions: false,
            extrapolation_limit: Self::EXTRAPOLATION_LIMIT,
            smoothing_length: None,
            settle_cycles: 1,
            settle_rate: None,
            rollback_rate: None,
            relax_stage: sweep::RELAX_STAGE,
            hold_anchored: false,
        }
    }

    /// Checks the ranges; the message names the `[settlement]` key.
    pub fn check(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(format!("settlement.{msg}")));
        if self.computed_cycles < 2 {
            return bad(format!("computed_cycles: a fit needs at least 2 cycles, got {}", self.computed_cycles));
        }
        if self.extrapolated_cycles == 0 {
            return bad("extrapolated_cycles: must be at least 1, got 0".into());
        }
        if self.initial_cycles == 0 && self.law != Law::Linear {
            return bad("initial_cycles: Shenton's law needs at least 1 (its ln N has no value at cycle 0)".into());
        }
        if !(self.growth >= 1.0 && self.growth.is_finite()) {
            return bad(format!("growth: must be a finite factor of at least 1, got {}", self.growth));
        }
        if let Some(a) = &self.adaptive {
            chernoff_cycles(a.error, a.probability, 1.0)?;
        }
        if self.extrapolation_limit.is_nan() || self.extrapolation_limit <= 0.0 {
            return bad(format!(
                "extrapolation_limit: must be a positive fraction of a body's size (inf: no bound), got {}",
                self.extrapolation_limit
            ));
        }
        if self.settle_cycles == 0 || self.settle_cycles >= self.computed_cycles {
            return bad(format!(
                "settle_cycles: must be at least 1 and less than computed_cycles ({}), got {}",
                self.computed_cycles, self.settle_cycles
            ));
        }
        if let Some(f) = self.settle_rate.filter(|f| !(*f > 0.0 && f.is_finite())) {
            return bad(format!("settle_rate: must be a positive factor on the predicted rate, got {f}"));
        }
        if let Some(f) = self.rollback_rate.filter(|f| !(*f > 0.0 && f.is_finite())) {
            return bad(format!("rollback_rate: must be a positive factor on the predicted rate, got {f}"));
        }
        if self.relax_stage.is_nan() || self.relax_stage <= 0.0 {
            return bad(format!(
                "relax_stage: must be a positive fraction of the smallest body's size (inf: one stage), got {}",
                self.relax_stage
            ));
        }
        if let Some(l) = self.smoothing_length.filter(|l| !(*l > 0.0 && l.is_finite())) {
            return bad(format!("smoothing_length: must be a positive length (m), got {l}"));
        }
        self.relax.check()
    }
}
