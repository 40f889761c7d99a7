//! A landing that fails is rolled back, not fatal (issue 32).
//!
//! Karrech et al. (2007, Fig. 10) extrapolate a window's fit by `h` cycles and
//! relax the overlaps the jump made; nothing in the procedure guarantees that
//! the configuration it lands on is one the engine can go on from. A landing
//! is **on probation** from its jump to the next jump's attempt (the computed
//! cycles of the window after it), and it **fails** when
//! - the extrapolated or the relaxed configuration has a body out of the run's
//!   domain, or the relaxation fails or does not reach its tolerance;
//! - a computed cycle on probation fails: the engine's step diverges, the cycle
//!   does not close, or a body leaves the domain;
//! - with `rollback_rate = f`, the window after it settles at a mean rate per
//!   computed cycle more than `f` times, in absolute value, the rate the jump's
//!   fit predicted at the landing (its `landing_rate_m`).
//!
//! The driver then goes back to the state before the jump (kept in the state,
//! so in every checkpoint taken on probation: `--resume`-safe), cuts
//! `settlement.csv`, `jumps.csv` and the cycle positions back to it, writes the
//! failed jump's row to `jumps.csv` again with `rolled_back = true` and the
//! reason, and retries from the same window with half the jump's length. A jump
//! whose half length would be shorter than a window (`computed_cycles`: it would
//! gain nothing), or that has been rolled back [`MAX_RETRIES`] times from the
//! same state, has its cycles computed instead (the next jump then starts from
//! that half length and grows again by `growth`). The run ends in error only
//! when a computed cycle fails with no landing on probation. Everything is a
//! function of the state, so a rolled-back run is as deterministic as any.

use super::{sync_tables, Accelerated, Files, JumpRow, State};
use crate::engine::Engine;
use crate::error::{Error, Result};
use crate::settlement::law::ResidualLaw;
use std::path::Path;
use std::time::Instant;

/// Rollbacks of one jump from one state before its cycles are computed instead.
pub const MAX_RETRIES: u32 = 8;

/// What a jump's attempt did.
pub(super) enum Landing {
    /// The adaptive bound asked for more computed cycles: no jump.
    Waited,
    /// Landed (on probation); its row.
    Landed(JumpRow),
    /// Failed, the state partly changed; its row and the reason.
    Failed(JumpRow, String),
}

impl<E: Engine> Accelerated<E> {
    /// Attempts the jumps that are due: the window after the last landing is
    /// judged (and the landing kept or rolled back), then the next jump is made,
    /// rolled back and retried as long as it fails. Errors are fatal ones (I/O,
    /// a fit that cannot be made).
    pub(super) fn attempt_jump(
        &self,
        st: &mut State<E>,
        law: &dyn ResidualLaw,
        files: &mut Files,
        out: &Path,
        wall0: f64,
        started: &Instant,
    ) -> Result<()> {
        loop {
            let left = self.target - st.cycle;
            if left == 0 || st.since_jump < self.spec.computed_cycles || st.cycle < st.compute_until {
                return Ok(());
            }
            if st.before_jump.is_some() {
                if let Some(reason) = self.off_rate(st) {
                    self.roll_back(st, files, out, reason)?;
                    continue;
                }
                // The window after the landing is complete: the landing stands.
                st.before_jump = None;
                st.last_jump = None;
                st.retries = 0;
            }
            sync_tables(st, files)?;
            let before = Box::new(st.clone());
            match self.jump(st, law, st.since_jump, left, files, wall0, started)? {
                Landing::Waited => return Ok(()),
                Landing::Landed(row) => {
                    st.before_jump = Some(before);
                    st.last_jump = Some(row);
                    return Ok(());
                }
                Landing::Failed(row, reason) => {
                    st.before_jump = Some(before);
                    st.last_jump = Some(row);
                    self.roll_back(st, files, out, reason)?;
                }
            }
        }
    }

    /// A computed cycle failed with `error`: with a landing on probation, it is
    /// rolled back and the jump retried; without, the error is returned.
    pub(super) fn recover(
        &self,
        st: &mut State<E>,
        law: &dyn ResidualLaw,
        files: &mut Files,
        out: &Path,
        error: Error,
        (wall0, started): (f64, &Instant),
    ) -> Result<()> {
        if st.before_jump.is_none() {
            return Err(error);
        }
        let cycle = st.cycle;
        self.roll_back(st, files, out, format!("computed cycle {cycle} after it failed: {error}"))?;
        self.attempt_jump(st, law, files, out, wall0, started)
    }

    /// Whether the window after the landing on probation settled too far from
    /// the rate its jump predicted (`rollback_rate`), and how.
    fn off_rate(&self, st: &State<E>) -> Option<String> {
        let factor = self.spec.rollback_rate?;
        st.before_jump.as_ref()?;
        let s = &st.window_settlement[st.window.window_start()..];
        if s.len() < 2 {
            return None;
        }
        let rate = (s[s.len() - 1] - s[0]) / (s.len() - 1) as f64;
        (rate.abs() > factor * st.landing_rate.abs()).then(|| {
            format!(
                "the window after it settled {rate:.3e} m per cycle, more than rollback_rate = {factor} times the \
                 {:.3e} m per cycle its fit predicted",
                st.landing_rate
            )
        })
    }

    /// Goes back to the state before the jump on probation: the tables cut back
    /// to it, the jump's row written again as rolled back, and the next attempt
    /// set to half its length (or its cycles computed).
    fn roll_back(&self, st: &mut State<E>, files: &mut Files, out: &Path, reason: String) -> Result<()> {
        let (Some(before), Some(mut row)) = (st.before_jump.take(), st.last_jump.take()) else {
            return Err(Error::Scene("settlement: a rollback without the state before its jump".into()));
        };
        let rollbacks = st.rollbacks + 1;
        *st = *before;
        st.rollbacks = rollbacks;
        // Flush what is buffered before the files are cut back.
        files.rows.sync()?;
        files.jumps.sync()?;
        if let Some(p) = files.positions.as_mut() {
            p.sync()?;
        }
        *files = self.reopen(out, st)?;
        row.rolled_back = true;
        row.rollback_reason = reason;
        files.jumps.write(&row)?;
        let half = row.extrapolated_cycles as f64 / 2.0;
        st.retries += 1;
        if half < self.spec.computed_cycles as f64 || st.retries > MAX_RETRIES {
            st.compute_until = st.cycle + row.extrapolated_cycles;
            st.retries = 0;
        }
        st.h = half.max(1.0);
        Ok(())
    }
}
