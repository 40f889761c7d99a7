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

mod folder;
mod jump;
pub mod rollback;
mod rows;
mod settings;

pub use jump::MEDIAN_MOVES;
pub use rows::{AccelerationOutcome, AccelerationProgress, AccelerationSummary, JumpRow, SettlementRow};
pub use settings::{Acceleration, Adaptive, Law};

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
use crate::run::folder::{self as run_folder, Source};
use crate::run::positions::PositionsWriter;
use crate::run::{body_names, RunOptions};
use folder::{checkpoint, Files};
use jump::check_domain;
use rollback::Landing;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

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
    /// [`Error::Scene`] for invalid settings; [`Error::Checkpoint`] for a refused or missing checkpoint;
    /// [`Error::Io`] naming a
    /// file; the engine's error if a step or a relaxation fails, after the tables
    /// and `summary.json` (`end: "diverged"`) are written.
    pub fn run(
        &self,
        out: &Path,
        opts: &RunOptions,
        progress: &mut dyn FnMut(&AccelerationProgress),
    ) -> Result<AccelerationOutcome<E>> {
        self.run_with(out, opts, &mut |p| {
            progress(p);
            ControlFlow::Continue(())
        })
    }

    /// [`Accelerated::run`] with a `control` callback after each cycle that may stop the run: its
    /// [`ControlFlow::Break`] stops it as `opts.stop_after` does (a checkpoint to resume from, `end`
    /// `"stopped"`) unless the target is reached.
    ///
    /// # Errors
    /// As [`Accelerated::run`].
    pub fn run_with(
        &self,
        out: &Path,
        opts: &RunOptions,
        control: &mut dyn FnMut(&AccelerationProgress) -> ControlFlow<()>,
    ) -> Result<AccelerationOutcome<E>> {
        self.check_run(opts)?;
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
        while st.cycle < self.target {
            let c = match self.computed_cycle(&mut st, &mut stepped) {
                Ok(c) => c,
                // A failure while a landing is on probation rolls it back.
                Err(e) => match self.recover(&mut st, law, &mut files, out, e, (wall0, &started)) {
                    Ok(()) => continue,
                    Err(e) => {
                        failure = Some(e);
                        end = "diverged";
                        break;
                    }
                },
            };
            self.record_cycle(&mut st, &mut files, c, wall0 + started.elapsed().as_secs_f64())?;
            // A jump when the window is long enough and cycles are left.
            if let Err(e) = self.attempt_jump(&mut st, law, &mut files, out, wall0, &started) {
                failure = Some(e);
                end = "diverged";
                break;
            }
            let flow = control(&AccelerationProgress {
                cycle: st.cycle,
                target: self.target,
                computed: st.computed,
                settlement: st.last_settlement,
            });
            let stop = flow.is_break() || opts.stop_after.is_some_and(|n| stepped >= n);
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
        let summary = self.finish(out, opts, &mut st, files, end)?;
        if let Some(e) = failure {
            return Err(e);
        }
        Ok(AccelerationOutcome { summary, system: st.sys, out: out.to_path_buf() })
    }

    /// The run options an accelerated run honours, or the one it refuses, named.
    fn check_run(&self, opts: &RunOptions) -> Result<()> {
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
        Ok(())
    }

    /// One computed cycle: steps until the engine's clock closes the loading cycle (counted in `stepped`);
    /// returns the configuration at its end, checked, or the failure (a step's, a cycle that does not close, a
    /// body out of the domain).
    fn computed_cycle(&self, st: &mut State<E>, stepped: &mut u64) -> Result<Configuration> {
        let per_cycle = (1.0 / (self.frequency * st.sys.dt())).ceil() as u64 + 2;
        let before = cycles_at(st.sys.time(), self.frequency, st.sys.dt());
        let mut made = 0;
        let mut last = None;
        while cycles_at(st.sys.time(), self.frequency, st.sys.dt()) == before {
            *stepped += 1;
            last = Some(st.sys.step()?);
            made += 1;
            if made > per_cycle {
                return Err(Error::Scene(format!(
                    "settlement: {made} steps did not close cycle {} (frequency {} Hz, dt {} s)",
                    before + 1,
                    self.frequency,
                    st.sys.dt()
                )));
            }
        }
        // The largest overlap at the cycle's end (a jump's relaxation target).
        if let Some(stats) = last {
            st.computed_overlap = E::summary(&stats).max_overlap;
        }
        st.cycle += 1;
        st.computed += 1;
        let conf = st.sys.configuration();
        check_domain(&st.sys, &st.origin, &conf, || format!("computed cycle {}", st.cycle))?;
        Ok(conf)
    }

    /// Records a computed cycle ending on `c`: its settlement row (and positions), and its place in the fit's
    /// window (a point, a new segment's first point after a landing, or a landing's re-seating cycle).
    fn record_cycle(&self, st: &mut State<E>, files: &mut Files, c: Configuration, wall_time_s: f64) -> Result<()> {
        let vertical = E::DIM - 1;
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
            wall_time_s,
        })?;
        // The history starts at the end of the initial cycles (empty until then:
        // `start`; with none, it holds cycle 0).
        if st.cycle >= self.spec.initial_cycles {
            // After a jump the first `settle_cycles − 1` computed cycles are
            // not data (the landing re-seats in them), nor, with
            // `settle_rate`, the next ones while the settlement still runs
            // ahead of the landing's rate; the next one starts a new segment.
            let after_jump = (st.jumps > 0).then_some(st.since_jump + 1);
            let extra = after_jump == Some(self.spec.settle_cycles) && self.still_settling(st, increment);
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
        Ok(())
    }

    /// The end of a run: the tables closed, `summary.json`, and unless stopped `final.json`, the checkpoint
    /// removed and the figures drawn.
    fn finish(
        &self,
        out: &Path,
        opts: &RunOptions,
        st: &mut State<E>,
        files: Files,
        end: &str,
    ) -> Result<AccelerationSummary> {
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
        Ok(summary)
    }
}

/// Flushes the tables and records their lengths and CRCs in `st`.
fn sync_tables<E>(st: &mut State<E>, files: &mut Files) -> Result<()> {
    let (rows, jumps) = (&mut files.rows, &mut files.jumps);
    st.tables = [(rows.sync()?, rows.rows(), rows.crc32()), (jumps.sync()?, jumps.rows(), jumps.crc32())];
    if let Some(p) = files.positions.as_mut() {
        p.sync()?;
        st.positions_crc32 = p.crc32();
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
