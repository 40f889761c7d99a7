//! The procedure of Karrech et al. 2007, Fig. 10, over any [`Engine`]: from the
//! start state, `k_i` initial cycles, then repeat {`k` computed cycles → fit of
//! every mobile body's residual displacement → extrapolation by `h` cycles →
//! positions written back → relaxation} until the target number of cycles.
//!
//! - A cycle is computed by stepping the engine until its exact clock closes a
//!   loading cycle ([`crate::clock::cycles_at`]); an extrapolation happens at a
//!   cycle's end, at the load phase every cycle starts with. The engine's clock
//!   counts the computed time only: the loads are periodic, so skipping `h`
//!   periods changes nothing the next step sees.
//! - A window is the configurations at the ends of its computed cycles,
//!   measured from the configuration at the start of the loading: the first
//!   starts at the end of the initial cycles and has `k + 1` points; after a
//!   jump, the relaxed configuration the jump landed on is not a point (its
//!   first cycle re-seats it) and the window has the `k` ends of its computed
//!   cycles. The linear law is fitted on the last window (eq. 16); Shenton's law
//!   on the whole history since the initial cycles, each window a segment with
//!   its own constant ([`super::law`] says why).
//! - `h` is multiplied by `growth` after each jump (the paper suggests letting
//!   it grow) and cut so that the run ends at the target. With `adaptive`, `k`
//!   grows past `computed_cycles` until the Chernoff bound (eq. 15) of the
//!   window's error range is met, at most 10 × `computed_cycles`.
//! - The settlement of a configuration is the vertical displacement (positive
//!   downwards) of `settlement_body` from the start of the loading, or by default
//!   the mean over the mobile bodies. Over extrapolated cycles it follows the
//!   law fitted to the window's settlement (the same fit as the bodies': a least
//!   squares fit is linear in the data), and at the jump's end it is the
//!   relaxed configuration's.
//!
//! Outputs (`OUT/`): `settlement.csv` (one row per cycle, computed or
//! extrapolated), `jumps.csv` (one row per jump: the fit's `g_u`, `f_ξ` and
//! error range, the Chernoff cycles, the relaxation), `summary.json`
//! (`computed_cycles`, `total_cycles`, `gained` = total/computed), `final.json`,
//! the record of the input (`scene.toml` or `initial_state.json`, `run.json`),
//! with `positions` (a scene's `[output] cycles = { positions = true }`) the
//! positions of every mobile body at the end of every cycle
//! ([`crate::run::positions`]: computed, on the fitted trend over extrapolated
//! cycles, relaxed where a jump lands), and `checkpoint.json` every `checkpoint_every_s` (at a cycle's end) for
//! `--resume`; with `figures`, the figures of [`crate::report::settlement`].

pub mod rollback;
mod rows;

pub use rows::{AccelerationOutcome, AccelerationProgress, AccelerationSummary, JumpRow, SettlementRow};

use super::estimate::{chernoff_cycles, extrapolate_within, fit, trend_moves, Training};
use super::law::{Linear, ResidualLaw, Shenton, ShentonDecelerating, ShentonOrigin};
use super::smooth::Smoothing;
use super::sweep;
use crate::clock::cycles_at;
use crate::engine::{Boundary, Configuration, Engine};
use crate::engine::{RelaxReport, RelaxSettings};
use crate::error::{Error, Result};
use crate::io::layout::{self, JUMPS, SETTLEMENT};
use crate::io::table::TableWriter;
use crate::io::{self, RunInfo};
use crate::run::checkpoint::{check_origin, read_checked, write_checked};
use crate::run::folder::{self, Source};
use crate::run::positions::PositionsWriter;
use crate::run::{body_names, RunOptions};
use rollback::Landing;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The residual-displacement law of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Law {
    /// Eq. (16).
    Linear,
    /// Shenton's law with a constant, `c + a ln N + b N` (the paper's choice of
    /// law for the procedure; [`super::law`] says why the constant).
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

/// Where the procedure stands: all of it is the checkpoint.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct State<E> {
    version: String,
    engine: String,
    source_crc32: u32,
    sys: E,
    origin: Configuration,
    /// Slot of the settlement body in the configurations.
    slot: Option<usize>,
    cycle: u64,
    computed: u64,
    jumps: u64,
    /// The next jump's length before rounding and cutting.
    h: f64,
    /// Every computed cycle end since the initial cycles, one segment per
    /// window (a law with [`ResidualLaw::history`] is fitted on all of it, the
    /// others on the last window).
    window: Training,
    /// Computed cycles since the last jump (or since the initial cycles).
    since_jump: u64,
    /// Settlement at each point of the window (m).
    window_settlement: Vec<f64>,
    /// The boundaries' coordinates at the start of the loading, and at each point of the window.
    boundary_origin: Vec<f64>,
    window_boundaries: Vec<Vec<f64>>,
    last_settlement: f64,
    /// The largest overlap at the end of the last computed cycle (m).
    #[serde(default)]
    computed_overlap: f64,
    /// The settlement's per-cycle rate the last jump's fit predicted at its landing (m).
    #[serde(default)]
    landing_rate: f64,
    /// Computed cycles since the last landing left out of the window.
    #[serde(default)]
    settling: u64,
    /// The settlement's increment over the last computed cycle, if it followed
    /// a computed cycle since the last landing (m).
    #[serde(default)]
    last_increment: Option<f64>,
    wall_time_s: f64,
    /// Bytes, rows and CRC-32 of `settlement.csv` and `jumps.csv`.
    tables: [(u64, u64, u32); 2],
    /// CRC-32 of the cycle positions written (with `positions`).
    #[serde(default)]
    positions_crc32: u32,
    /// Landings rolled back so far.
    #[serde(default)]
    pub(super) rollbacks: u64,
    /// Rollbacks of the pending jump (since the state it starts from).
    #[serde(default)]
    pub(super) retries: u32,
    /// No jump before this cycle: a jump rolled back down to the shortest
    /// length has its cycles computed instead.
    #[serde(default)]
    pub(super) compute_until: u64,
    /// The state before the last jump, kept while its landing is on probation
    /// (from the jump to the next jump's attempt): a failure goes back to it.
    #[serde(default = "no_state")]
    pub(super) before_jump: Option<Box<State<E>>>,
    /// The last jump's row, written again and marked if it is rolled back.
    #[serde(default)]
    pub(super) last_jump: Option<JumpRow>,
}

/// No state before a jump (a checkpoint of an older build, or off probation).
fn no_state<E>() -> Option<Box<State<E>>> {
    None
}

/// An accelerated run of an engine: its start state, the procedure's settings,
/// the loading frequency and the target number of cycles.
pub struct Accelerated<E: Engine> {
    system: E,
    spec: Acceleration,
    frequency: f64,
    target: u64,
    seed: u64,
    /// The scene's text or the system's serde form.
    source: Source,
    /// What the scene resolved to, for `run.json` ([`Accelerated::with_model`]).
    model: Option<serde_json::Value>,
    /// The figures drawn at the end when [`RunOptions::figures`] asks ([`Accelerated::with_figures`]).
    figures: Option<FolderFigures>,
}

/// Draws the figures of a finished accelerated run from its folder (`ballast figures`,
/// [`crate::report::settlement::draw`]); given by whoever opens the scene ([`crate::open::settle_file`]).
pub type FolderFigures = Box<dyn Fn(&Path) -> Result<()> + Send + Sync>;

impl<E: Engine> Accelerated<E> {
    /// A run of `system` loaded at `frequency` (Hz) to `target` cycles, from the
    /// scene whose text is `text` (recorded as `scene.toml`, its CRC-32 checked on `--resume`).
    pub fn from_scene(system: E, spec: Acceleration, frequency: f64, target: u64, seed: u64, text: String) -> Self {
        Self { system, spec, frequency, target, seed, source: Source::Scene { text }, model: None, figures: None }
    }

    /// The same run, with `model` (what the scene resolved to: the planar MD
    /// engine's derived stiffness and time step) recorded in `run.json`.
    pub fn with_model(mut self, model: serde_json::Value) -> Self {
        self.model = Some(model);
        self
    }

    /// The same run, drawing its figures with `figures` at the end when [`RunOptions::figures`] asks.
    pub fn with_figures(mut self, figures: FolderFigures) -> Self {
        self.figures = Some(figures);
        self
    }

    /// A run of a system built in code (its serde form and the settings are recorded).
    ///
    /// # Errors
    /// [`Error::Io`] if the system cannot be serialised.
    pub fn from_system(system: E, spec: Acceleration, frequency: f64, target: u64) -> Result<Self> {
        let json = serde_json::to_string(&(&spec, frequency, target, &system))
            .map_err(|e| Error::Io(std::io::Error::other(e)))?;
        Ok(Self { system, spec, frequency, target, seed: 0, source: Source::Code { json }, model: None, figures: None })
    }

    fn source_crc32(&self) -> u32 {
        self.source.crc32()
    }

    fn check(&self) -> Result<()> {
        self.spec.check()?;
        if !(self.frequency > 0.0 && self.frequency.is_finite()) {
            return Err(Error::Scene(format!(
                "settlement: the loading frequency must be positive, got {} (output.cycles.frequency)",
                self.frequency
            )));
        }
        if self.target == 0 {
            return Err(Error::Scene(
                "settlement: the run has no loading cycle (simulation.duration × output.cycles.frequency < 1)".into(),
            ));
        }
        Ok(())
    }

    /// Runs the procedure into `out` (module doc), calling `progress` after each
    /// cycle. `opts.resume` continues from `OUT/checkpoint.json`; `opts.stop_after`
    /// stops (with a checkpoint) at the first cycle's end after that many steps.
    ///
    /// # Errors
    /// [`Error::Scene`] for invalid settings or checkpoint; [`Error::Io`] naming a
    /// file; the engine's error if a step or a relaxation fails, after the tables
    /// and `summary.json` (`end: "diverged"`) are written.
    pub fn run(
        &self,
        out: &Path,
        opts: &RunOptions,
        progress: &mut dyn FnMut(&AccelerationProgress),
    ) -> Result<AccelerationOutcome<E>> {
        self.check()?;
        crate::run::check_options(opts)?;
        crate::run::check_built(opts)?;
        if opts.vtk_every > 0 {
            return Err(Error::Scene(format!(
                "vtk_every: an accelerated run writes no snapshots (its extrapolated cycles have no steps); got \
                 {}, use 0",
                opts.vtk_every
            )));
        }
        if opts.figures && self.figures.is_none() {
            return Err(Error::Scene(
                "figures: this run has no figure drawer (a run of a scene file draws them; a system built in \
                 code draws them after the run with ballast::report::settlement::draw)"
                    .into(),
            ));
        }
        let (mut st, mut files) = if opts.resume { self.resume(out)? } else { self.start(out)? };
        st.sys.set_threads(opts.threads.max(1));
        let law = self.spec.law.estimator();
        let started = Instant::now();
        let wall0 = st.wall_time_s;
        // Steps made by this call, rolled-back ones included (`stop_after`).
        let mut stepped = 0u64;
        let mut checkpointed = Instant::now();
        let mut end = "finished";
        let mut failure = None;
        let vertical = E::DIM - 1;
        let per_cycle = (1.0 / (self.frequency * st.sys.dt())).ceil() as u64 + 2;
        while st.cycle < self.target {
            // One computed cycle.
            let before = cycles_at(st.sys.time(), self.frequency, st.sys.dt());
            let mut made = 0;
            let mut last = None;
            while cycles_at(st.sys.time(), self.frequency, st.sys.dt()) == before {
                stepped += 1;
                match st.sys.step() {
                    Ok(stats) => last = Some(stats),
                    Err(e) => {
                        failure = Some(e);
                        break;
                    }
                }
                made += 1;
                if made > per_cycle {
                    failure = Some(Error::Scene(format!(
                        "settlement: {made} steps did not close cycle {} (frequency {} Hz, dt {} s)",
                        before + 1,
                        self.frequency,
                        st.sys.dt()
                    )));
                    break;
                }
            }
            let mut c = None;
            if failure.is_none() {
                // The largest overlap at the cycle's end (a jump's relaxation target).
                if let Some(stats) = last {
                    st.computed_overlap = E::summary(&stats).max_overlap;
                }
                st.cycle += 1;
                st.computed += 1;
                let conf = st.sys.configuration();
                match check_domain(&st.sys, &st.origin, &conf, || format!("computed cycle {}", st.cycle)) {
                    Ok(()) => c = Some(conf),
                    Err(e) => failure = Some(e),
                }
            }
            let Some(c) = c else {
                // A failure while a landing is on probation rolls it back.
                let e = failure.take().expect("a cycle without its configuration failed");
                match self.recover(&mut st, law, &mut files, out, e, (wall0, &started)) {
                    Ok(()) => continue,
                    Err(e) => {
                        failure = Some(e);
                        end = "diverged";
                        break;
                    }
                }
            };
            let bounds = st.sys.boundaries();
            let s = st.settlement(&c, &bounds, vertical, self.spec.settlement_boundary);
            let b = coordinates(&bounds);
            let increment = s - st.last_settlement;
            st.last_settlement = s;
            if let Some(p) = files.positions.as_mut() {
                p.append(&c)?;
            }
            files.rows.write(&SettlementRow {
                cycle: st.cycle,
                computed: 1,
                settlement_m: s,
                coordination: Some(st.sys.coordination()),
                max_overlap_before_relax_m: None,
                max_overlap_after_relax_m: None,
                wall_time_s: wall0 + started.elapsed().as_secs_f64(),
            })?;
            // The history starts at the end of the initial cycles (empty until then:
            // `start`; with none, it holds cycle 0).
            if st.cycle >= self.spec.initial_cycles {
                // After a jump the first `settle_cycles − 1` computed cycles are
                // not data (the landing re-seats in them), nor, with
                // `settle_rate`, the next ones while the settlement still runs
                // ahead of the landing's rate; the next one starts a new segment.
                let after_jump = (st.jumps > 0).then_some(st.since_jump + 1);
                let extra = after_jump == Some(self.spec.settle_cycles) && self.still_settling(&st, increment);
                match after_jump {
                    Some(n) if n < self.spec.settle_cycles || extra => st.settling += 1,
                    _ => {
                        if after_jump == Some(self.spec.settle_cycles) {
                            st.window.push_segment(st.cycle as f64, c);
                        } else {
                            st.window.push(st.cycle as f64, c);
                        }
                        st.window_settlement.push(s);
                        st.window_boundaries.push(b);
                    }
                }
                if st.cycle > self.spec.initial_cycles && !extra {
                    st.since_jump += 1;
                }
            }
            if st.jumps > 0 {
                st.last_increment = Some(increment);
            }
            // A jump when the window is long enough and cycles are left.
            if let Err(e) = self.attempt_jump(&mut st, law, &mut files, out, wall0, &started) {
                failure = Some(e);
                end = "diverged";
                break;
            }
            progress(&AccelerationProgress {
                cycle: st.cycle,
                target: self.target,
                computed: st.computed,
                settlement: st.last_settlement,
            });
            let stop = opts.stop_after.is_some_and(|n| stepped >= n);
            if st.cycle < self.target
                && (stop
                    || (opts.checkpoint_every_s > 0.0
                        && checkpointed.elapsed().as_secs_f64() >= opts.checkpoint_every_s))
            {
                st.wall_time_s = wall0 + started.elapsed().as_secs_f64();
                checkpoint(out, &mut st, &mut files)?;
                checkpointed = Instant::now();
                if stop {
                    end = "stopped";
                    break;
                }
            }
        }
        st.wall_time_s = wall0 + started.elapsed().as_secs_f64();
        files.rows.finish()?;
        files.jumps.finish()?;
        let summary = AccelerationSummary {
            engine: E::NAME.to_string(),
            end: end.to_string(),
            law: self.spec.law,
            computed_cycles: st.computed,
            total_cycles: st.cycle,
            gained: if st.computed > 0 { st.cycle as f64 / st.computed as f64 } else { 0.0 },
            jumps: st.jumps,
            rollbacks: st.rollbacks,
            initial_cycles: self.spec.initial_cycles,
            settlement_m: st.last_settlement,
            wall_time_s: st.wall_time_s,
            steps: st.sys.steps_done(),
        };
        io::write_json(&out.join(layout::SUMMARY), &summary)?;
        if end != "stopped" {
            st.sys.final_state().write(&out.join(layout::FINAL))?;
            io::remove_stale(out, layout::CHECKPOINT)?;
            if let (true, Some(draw)) = (opts.figures, &self.figures) {
                draw(out)?;
            }
        }
        if let Some(e) = failure {
            return Err(e);
        }
        Ok(AccelerationOutcome { summary, system: st.sys, out: out.to_path_buf() })
    }

    /// Whether the landing still re-seats in the computed cycle whose settlement
    /// increment is `increment` (m), the `settle_cycles`-th after it or later:
    /// with `settle_rate`, while the mean increment of the last two computed
    /// cycles since the landing exceeds `settle_rate` times the rate the jump's
    /// fit predicted there, for at most `computed_cycles` cycles past the fixed count.
    fn still_settling(&self, st: &State<E>, increment: f64) -> bool {
        let Some(factor) = self.spec.settle_rate else { return false };
        let extra = (st.settling + 1).saturating_sub(self.spec.settle_cycles);
        if extra >= self.spec.computed_cycles {
            return false;
        }
        let mean = match st.last_increment {
            Some(previous) => 0.5 * (previous + increment),
            None => increment,
        };
        mean > factor * st.landing_rate.abs()
    }

    /// Fits the window, extrapolates, writes back and relaxes; the rows of the
    /// extrapolated cycles and the jump's row. Leaves the window as it is when
    /// the adaptive bound asks for more computed cycles. A landing that fails
    /// (a body out of the domain, a relaxation that fails or does not converge)
    /// is [`Landing::Failed`], with the state partly changed: the caller rolls
    /// it back ([`rollback`]).
    #[allow(clippy::too_many_arguments)]
    fn jump(
        &self,
        st: &mut State<E>,
        law: &dyn ResidualLaw,
        k: u64,
        left: u64,
        files: &mut Files,
        wall0: f64,
        started: &Instant,
    ) -> Result<Landing> {
        // The law's training data: the whole history, or the last window (the
        // points since the last jump).
        let first = if law.history() { 0 } else { st.window.window_start() };
        let window = if first == 0 { Cow::Borrowed(&st.window) } else { Cow::Owned(st.window.last_segment()) };
        let (settlements, boundary_points) = (&st.window_settlement[first..], &st.window_boundaries[first..]);
        let f = fit(law, &window, E::EXTRAPOLATED, E::DIM)?;
        let chernoff = match &self.spec.adaptive {
            Some(a) => {
                let need = chernoff_cycles(a.error, a.probability, f.xi_range)?;
                let cap = 10 * self.spec.computed_cycles;
                if k < need.min(cap) && left > need.min(cap) - k {
                    return Ok(Landing::Waited);
                }
                Some(need)
            }
            None => None,
        };
        let h = (st.h.round() as u64).clamp(1, left);
        let (n, segments) = (&window.cycles, &window.segments);
        let n_last = *n.last().expect("a window has points");
        let sc = law.fit(n, settlements, segments);
        // The fitted settlement's increment over the jump's last cycle.
        let landing_rate = law.trend(&sc, n_last + h as f64) - law.trend(&sc, n_last + (h - 1) as f64);
        // Bounded moves: a body without a force-carrying contact is held, the
        // others move at most `extrapolation_limit` of their size or
        // `MEDIAN_MOVES` times the median trend move, whichever is larger
        // (docs/settlement-driver.md, "Bounded moves").
        let bodies = &window.origin.bodies;
        let contacts = st.sys.contact_counts(bodies);
        let mut moves = trend_moves(law, &window, &f, h as f64);
        let coherent = MEDIAN_MOVES * median(&mut moves);
        // With `hold_anchored`, the sprung pads stay where the computed cycle
        // left them, through the extrapolation and the relaxation alike.
        let anchored = if self.spec.hold_anchored { st.sys.anchored_bodies() } else { Vec::new() };
        let pinned: Vec<bool> =
            (bodies.iter().zip(&contacts)).map(|(b, &n)| n == 0 || anchored.binary_search(b).is_ok()).collect();
        let max_move: Vec<f64> = (st.sys.body_sizes(bodies).iter().zip(&pinned))
            .map(|(size, &pin)| if pin { 0.0 } else { (self.spec.extrapolation_limit * size).max(coherent) })
            .collect();
        let held = pinned.iter().filter(|&&pin| pin).count() as u64;
        let smoothing = self.spec.smoothing_length.map(|length| {
            let last = window.configurations.last().expect("a fitted window has points");
            let excluded: Vec<bool> =
                (bodies.iter().zip(&pinned)).map(|(&b, &pin)| pin || Some(b) == self.spec.settlement_body).collect();
            Smoothing::new(last, E::DIM, length, &excluded)
        });
        for j in 1..h {
            if let Some(p) = files.positions.as_mut() {
                p.append(&extrapolate_within(law, &window, &f, j as f64, &max_move, smoothing.as_ref()).0)?;
            }
            files.rows.write(&SettlementRow {
                cycle: st.cycle + j,
                computed: 0,
                settlement_m: law.extrapolate(&sc, n_last, st.last_settlement, j as f64),
                coordination: None,
                max_overlap_before_relax_m: None,
                max_overlap_after_relax_m: None,
                wall_time_s: wall0 + started.elapsed().as_secs_f64(),
            })?;
        }
        let (target, limited) = extrapolate_within(law, &window, &f, h as f64, &max_move, smoothing.as_ref());
        let mut row = JumpRow {
            jump: st.jumps + 1,
            from_cycle: st.cycle,
            to_cycle: st.cycle + h,
            computed_cycles: k,
            extrapolated_cycles: h,
            chernoff_cycles: chernoff,
            g_u_m: f.g_u,
            f_xi_m: f.f_xi,
            xi_range_m: f.xi_range,
            relax_tolerance_m: self.spec.relax.tolerance,
            relax_iterations: 0,
            relax_evaluations: 0,
            relax_converged: false,
            max_overlap_before_relax_m: 0.0,
            max_overlap_after_relax_m: 0.0,
            relax_largest_move: 0.0,
            relax_wall_time_s: 0.0,
            held_bodies: held,
            limited_bodies: limited as u64,
            settling_cycles: st.settling,
            landing_rate_m: landing_rate,
            rolled_back: false,
            rollback_reason: String::new(),
            relax_stages: 1,
        };
        if let Err(e) =
            check_domain(&st.sys, &st.origin, &target, || format!("the extrapolation of jump {}", st.jumps + 1))
        {
            return Ok(Landing::Failed(row, e.to_string()));
        }
        // The boundaries (the MD plate) follow the same law.
        let mut series = vec![0.0; n.len()];
        let boundaries: Vec<f64> = (0..st.boundary_origin.len())
            .map(|j| {
                series.iter_mut().zip(boundary_points).for_each(|(v, b)| *v = b[j] - st.boundary_origin[j]);
                let c = law.fit(n, &series, segments);
                st.boundary_origin[j] + law.extrapolate(&c, n_last, series[series.len() - 1], h as f64)
            })
            .collect();
        // The landing, in stages (`sweep`): from the computed configuration the
        // window ends on (the system's) to the extrapolated one.
        let from = window.configurations.last().expect("a fitted window has points").clone();
        let stages = sweep::stages(&from, &target, &st.sys.body_sizes(bodies), E::DIM, self.spec.relax_stage);
        row.relax_stages = stages;
        let boundaries_from = coordinates(&st.sys.boundaries());
        let t0 = Instant::now();
        let mut relax = self.spec.relax.clone();
        for &b in &anchored {
            if !relax.held.contains(&b) {
                relax.held.push(b);
            }
        }
        if self.spec.relax_to_computed {
            // A floor for a configuration without contacts: a millionth of the
            // smallest body (any overlap a jump makes there is spurious).
            let smallest = st.sys.body_sizes(bodies).iter().copied().fold(f64::INFINITY, f64::min);
            let floor = if smallest.is_finite() { 1e-6 * smallest } else { f64::MIN_POSITIVE };
            relax.tolerance = st.computed_overlap.max(floor);
        }
        row.relax_tolerance_m = relax.tolerance;
        let report: RelaxReport =
            match sweep::relax_along(&mut st.sys, &from, &target, (&boundaries_from, &boundaries), &relax, stages) {
                Ok(r) => r,
                Err(e) => return Ok(Landing::Failed(row, format!("its relaxation failed: {e}"))),
            };
        row.relax_iterations = report.iterations;
        row.relax_evaluations = report.evaluations;
        row.relax_converged = report.converged;
        row.max_overlap_before_relax_m = report.max_overlap_before;
        row.max_overlap_after_relax_m = report.max_overlap_after;
        row.relax_largest_move = report.largest_move;
        row.relax_wall_time_s = t0.elapsed().as_secs_f64();
        if !report.converged {
            return Ok(Landing::Failed(
                row,
                format!(
                    "its relaxation did not reach {:.3e} m ({:.3e} m left after {} iterations: {})",
                    relax.tolerance, report.max_overlap_after, report.iterations, report.reason
                ),
            ));
        }
        if let Err(e) = check_domain(&st.sys, &st.origin, &st.sys.configuration(), || {
            format!("the relaxation of jump {}", st.jumps + 1)
        }) {
            return Ok(Landing::Failed(row, e.to_string()));
        }
        st.cycle += h;
        st.jumps += 1;
        st.h *= self.spec.growth;
        let c = st.sys.configuration();
        let bounds = st.sys.boundaries();
        let s = st.settlement(&c, &bounds, E::DIM - 1, self.spec.settlement_boundary);
        st.last_settlement = s;
        if let Some(p) = files.positions.as_mut() {
            p.append(&c)?;
        }
        files.rows.write(&SettlementRow {
            cycle: st.cycle,
            computed: 0,
            settlement_m: s,
            coordination: None,
            max_overlap_before_relax_m: Some(report.max_overlap_before),
            max_overlap_after_relax_m: Some(report.max_overlap_after),
            wall_time_s: wall0 + started.elapsed().as_secs_f64(),
        })?;
        files.jumps.write(&row)?;
        st.landing_rate = landing_rate;
        st.settling = 0;
        st.last_increment = None;
        // The next window starts at the end of the first computed cycle after
        // the landing (the relaxed configuration re-seats in that cycle).
        st.since_jump = 0;
        Ok(Landing::Landed(row))
    }

    /// A fresh run: the folder prepared, the records and table headers written.
    fn start(&self, out: &Path) -> Result<(State<E>, Files)> {
        folder::prepare(
            out,
            &[layout::CHECKPOINT, layout::SUMMARY, layout::FINAL, layout::SCENE, layout::INITIAL_STATE],
        )?;
        let steps = (self.target as f64 / (self.frequency * self.system.dt())).round() as u64;
        let info = RunInfo {
            seed: self.seed,
            engine: E::NAME.into(),
            version: env!("CARGO_PKG_VERSION").into(),
            steps,
            dt: self.system.dt(),
            model: self.model.clone(),
        };
        self.source.write_records(out, &info)?;
        let origin = self.system.configuration();
        let slot = match self.spec.settlement_body {
            Some(b) => Some(origin.bodies.iter().position(|&i| i == b).ok_or_else(|| {
                Error::Scene(format!("settlement.settlement_body: body {b} is not a mobile body of the scene"))
            })?),
            None => None,
        };
        let boundary_origin = coordinates(&self.system.boundaries());
        if let Some(j) = self.spec.settlement_boundary.filter(|&j| j >= boundary_origin.len()) {
            return Err(Error::Scene(format!(
                "settlement.settlement_body: boundary {j} does not exist ({} boundaries)",
                boundary_origin.len()
            )));
        }
        let mut window = Training::new(origin.clone());
        if self.spec.initial_cycles == 0 {
            window.push(0.0, origin.clone());
        }
        let st = State {
            version: env!("CARGO_PKG_VERSION").into(),
            engine: E::NAME.into(),
            source_crc32: self.source_crc32(),
            sys: self.system.clone(),
            slot,
            cycle: 0,
            computed: 0,
            jumps: 0,
            h: self.spec.extrapolated_cycles as f64,
            since_jump: 0,
            window_settlement: if self.spec.initial_cycles == 0 { vec![0.0] } else { Vec::new() },
            window_boundaries: if self.spec.initial_cycles == 0 { vec![boundary_origin.clone()] } else { Vec::new() },
            boundary_origin,
            window,
            origin,
            last_settlement: 0.0,
            computed_overlap: 0.0,
            landing_rate: 0.0,
            settling: 0,
            last_increment: None,
            wall_time_s: 0.0,
            tables: [(0, 0, 0); 2],
            positions_crc32: 0,
            rollbacks: 0,
            retries: 0,
            compute_until: 0,
            before_jump: None,
            last_jump: None,
        };
        let rows = TableWriter::create(&out.join(layout::SETTLEMENT), SettlementRow::COLUMNS)?;
        let jumps = TableWriter::create(&out.join(layout::JUMPS), JumpRow::COLUMNS)?;
        for stale in [layout::CYCLE_BODIES, layout::CYCLE_DISPLACEMENTS] {
            io::remove_stale(out, stale)?;
        }
        let positions = if self.spec.positions {
            let names = body_names(&self.system, &st.origin.bodies);
            Some(PositionsWriter::create(out, st.origin.clone(), &names)?)
        } else {
            None
        };
        Ok((st, Files { rows, jumps, positions }))
    }

    /// The run continued from `OUT/checkpoint.json`.
    fn resume(&self, out: &Path) -> Result<(State<E>, Files)> {
        folder::checkpoint_to_resume(out)?;
        let (path, st): (PathBuf, State<E>) = read_checked(out)?;
        check_origin(&path, (&st.engine, &st.version, st.source_crc32), (E::NAME, self.source_crc32()))?;
        let bad = |msg: String| folder::invalid_checkpoint(&path, msg);
        folder::check_resumed(&path, "", &st.sys, &self.system)?;
        if let Some(b) = &st.before_jump {
            folder::check_resumed(&path, "before_jump: ", &b.sys, &self.system)?;
            if b.before_jump.is_some()
                || b.cycle > st.cycle
                || b.jumps > st.jumps
                || st.last_jump.is_none()
                || b.window.configurations.len() != b.window_settlement.len()
                || b.window.segments.len() != b.window.cycles.len()
                || b.tables[0].1 != b.cycle
                || b.tables[1].1 != b.jumps + b.rollbacks
            {
                return Err(bad("before_jump: not the state before its last jump".into()));
            }
        }
        if st.origin != self.system.configuration() {
            return Err(bad("its start configuration is not the scene's".into()));
        }
        if st.computed > st.cycle
            || st.cycle > self.target
            || st.window.configurations.len() != st.window_settlement.len()
            || st.window.segments.len() != st.window.cycles.len()
        {
            return Err(bad(format!("{} computed of {} cycles, target {}", st.computed, st.cycle, self.target)));
        }
        let [(_, rr, _), (_, jr, _)] = st.tables;
        if rr != st.cycle || jr != st.jumps + st.rollbacks {
            return Err(bad(format!(
                "{rr} rows of {SETTLEMENT} for {} cycles, {jr} of {JUMPS} for {} jumps and {} rollbacks",
                st.cycle, st.jumps, st.rollbacks
            )));
        }
        let files = self.reopen(out, &st)?;
        io::remove_stale(out, layout::SUMMARY)?;
        Ok((st, files))
    }

    /// The run's files reopened at the lengths `st` recorded (`st.tables`, its
    /// cycles of positions): cut back to them, checked against their CRCs.
    fn reopen(&self, out: &Path, st: &State<E>) -> Result<Files> {
        let [(rb, rr, rc), (jb, jr, jc)] = st.tables;
        let rows = TableWriter::resume(&out.join(layout::SETTLEMENT), rb, rr, rc)?;
        let jumps = TableWriter::resume(&out.join(layout::JUMPS), jb, jr, jc)?;
        let positions = if self.spec.positions {
            let names = body_names(&self.system, &st.origin.bodies);
            Some(PositionsWriter::resume(out, st.origin.clone(), &names, st.cycle, st.positions_crc32)?)
        } else {
            None
        };
        Ok(Files { rows, jumps, positions })
    }
}

/// The files a run appends to.
pub(super) struct Files {
    pub(super) rows: TableWriter,
    pub(super) jumps: TableWriter,
    pub(super) positions: Option<PositionsWriter>,
}

/// Writes the checkpoint of the run in progress.
fn checkpoint<E: Engine>(out: &Path, st: &mut State<E>, files: &mut Files) -> Result<()> {
    sync_tables(st, files)?;
    write_checked(out, st)?;
    Ok(())
}

/// Flushes the tables and records their lengths and CRCs in `st`.
pub(super) fn sync_tables<E>(st: &mut State<E>, files: &mut Files) -> Result<()> {
    let (rows, jumps) = (&mut files.rows, &mut files.jumps);
    st.tables = [(rows.sync()?, rows.rows(), rows.crc32()), (jumps.sync()?, jumps.rows(), jumps.crc32())];
    if let Some(p) = files.positions.as_mut() {
        p.sync()?;
        st.positions_crc32 = p.crc32();
    }
    Ok(())
}

/// The factor on the median of the bodies' trend moves below which a jump does
/// not bound a move: the coherent motion of the sample (the grains under the
/// sleeper follow it) is never cut, only the outliers.
pub const MEDIAN_MOVES: f64 = 3.0;

/// The median of `x` (reordered; 0 if empty).
fn median(x: &mut [f64]) -> f64 {
    if x.is_empty() {
        return 0.0;
    }
    let mid = x.len() / 2;
    let (_, m, _) = x.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Checks that every body of `c` is inside the run's domain: the box of the
/// translations of `origin` (the start of the loading) widened on every side
/// by half its largest side. A body outside has left the container (through a
/// wall or over it): its motion is no settlement, and a fit would extrapolate
/// its fall. `what` says what moved it there.
fn check_domain<E: Engine>(
    sys: &E,
    origin: &Configuration,
    c: &Configuration,
    what: impl FnOnce() -> String,
) -> Result<()> {
    let dim = E::DIM;
    let (mut lo, mut hi) = (vec![f64::INFINITY; dim], vec![f64::NEG_INFINITY; dim]);
    for b in 0..origin.len() {
        for (d, &x) in origin.body(b)[..dim].iter().enumerate() {
            lo[d] = lo[d].min(x);
            hi[d] = hi[d].max(x);
        }
    }
    let margin = 0.5 * (0..dim).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
    for b in 0..c.len() {
        let x = &c.body(b)[..dim];
        if (0..dim).all(|d| x[d] >= lo[d] - margin && x[d] <= hi[d] + margin) {
            continue;
        }
        let body = c.bodies[b];
        let box_ = (0..dim).map(|d| format!("[{:.4}, {:.4}]", lo[d] - margin, hi[d] + margin)).collect::<Vec<_>>();
        return Err(Error::Diverged {
            step: sys.steps_done(),
            body,
            name: body_names(sys, &[body]).pop().unwrap_or_default(),
            what: format!(
                "{} carried it out of the domain, to {x:?} (m); the domain is {} (m), the box of the bodies at the \
                 start of the loading widened by half its size (docs/settlement-driver.md, \"Bounded moves\")",
                what(),
                box_.join(" × ")
            ),
        });
    }
    Ok(())
}

/// The coordinates of boundaries (m).
fn coordinates(boundaries: &[Boundary]) -> Vec<f64> {
    boundaries.iter().map(|b| b.s).collect()
}

impl<E: Engine> State<E> {
    /// The settlement (m, positive downwards) of the configuration `c` with the
    /// boundaries `bounds`: of the settlement boundary if there is one, else of
    /// the settlement body or the mean over the mobile bodies.
    fn settlement(&self, c: &Configuration, bounds: &[Boundary], vertical: usize, boundary: Option<usize>) -> f64 {
        match boundary {
            Some(j) => (bounds[j].s - self.boundary_origin[j]) * bounds[j].down,
            None => settlement(&self.origin, c, self.slot, vertical),
        }
    }
}

/// The settlement of `c` (m, positive downwards) from `origin` along axis `vertical`:
/// of the body at `slot`, or the mean over every body of the configuration.
pub fn settlement(origin: &Configuration, c: &Configuration, slot: Option<usize>, vertical: usize) -> f64 {
    match slot {
        Some(k) => origin.body(k)[vertical] - c.body(k)[vertical],
        None if c.is_empty() => 0.0,
        None => (0..c.len()).map(|k| origin.body(k)[vertical] - c.body(k)[vertical]).sum::<f64>() / c.len() as f64,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn median_of_odd_and_even_counts() {
        // Odd: the middle value; even: the upper middle (the bound only needs a
        // robust scale); empty: 0.
        assert_eq!(super::median(&mut [3.0, 1e-3, 2.0, 0.5, 1e3]), 2.0);
        assert_eq!(super::median(&mut [4.0, 1.0, 3.0, 2.0]), 3.0);
        assert_eq!(super::median(&mut []), 0.0);
    }
}
