//! The simulation clock shared by both engines, and the loading-cycle clock of
//! the outputs.
//!
//! Time is never accumulated step by step (`t += h` drifts by about `k ε t` after
//! `k` steps: over 10⁷ steps more than the half step that decides which step ends
//! a loading cycle). It is computed from the step count,
//! `t_k = t_0 + (k − k_0) h`, where `(t_0, k_0)` is the time and step at which
//! the time step `h` last changed ([`time_at`]). A loading cycle of frequency `f`
//! ends at `t = c / f`; the step that ends within half a step of it, or past it,
//! closes it ([`cycles_at`]).

use serde::{Deserialize, Serialize};

/// The origin `(t_0, k_0)` of an engine's exact clock: the time and step at which its time step last changed.
/// Every engine holds one, flattened into its serde form (the keys `time_origin` and `step_origin`, 0 when
/// absent, as in states written before they existed).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Origin {
    /// Time (s) at which the time step last changed.
    #[serde(default)]
    pub time_origin: f64,
    /// Step count at which the time step last changed.
    #[serde(default)]
    pub step_origin: u64,
}

impl Origin {
    /// Time (s) after `step` steps of `dt` (s) from this origin ([`time_at`]).
    #[inline]
    pub fn time_at(&self, step: u64, dt: f64) -> f64 {
        time_at(self.time_origin, self.step_origin, step, dt)
    }

    /// Moves the origin to `(time, step)`: what changing the time step at that step does, so that the clock
    /// stays exact.
    pub fn rebase(&mut self, time: f64, step: u64) {
        (self.time_origin, self.step_origin) = (time, step);
    }

    /// Checks that a state read back is on this clock: `step` not before the origin and, if the state keeps
    /// its time, `time` the clock's time at `step` with `dt`, bit for bit. The message starts with `clock:`.
    ///
    /// # Errors
    /// The message saying what does not follow.
    pub fn check(&self, step: u64, time: Option<f64>, dt: f64) -> Result<(), String> {
        match time {
            None if step < self.step_origin => {
                Err(format!("clock: step {step} before its origin {}", self.step_origin))
            }
            Some(t) if step < self.step_origin || self.time_at(step, dt).to_bits() != t.to_bits() => {
                Err(format!("clock: time {t} s at step {step} does not follow from its origin"))
            }
            _ => Ok(()),
        }
    }

    /// Whether `other` is the same origin, bit for bit (a state and the scene it claims to come from).
    pub fn same(&self, other: &Origin) -> bool {
        self.time_origin.to_bits() == other.time_origin.to_bits() && self.step_origin == other.step_origin
    }
}

/// Time (s) after `step` steps of `dt` (s) counted from the origin
/// `(time_origin, step_origin)`: `t_0 + (k − k_0) h`.
#[inline]
pub fn time_at(time_origin: f64, step_origin: u64, step: u64, dt: f64) -> f64 {
    time_origin + step.saturating_sub(step_origin) as f64 * dt
}

/// Loading cycles of `frequency` (Hz) completed at time `t` (s) on a clock of
/// step `dt` (s): `⌊f (t + h/2)⌋`. The half step absorbs the round-off of `t`
/// and of `c / f`, so that the step ending at the cycle's end closes it, whatever
/// the engine.
#[inline]
pub fn cycles_at(t: f64, frequency: f64, dt: f64) -> u64 {
    let c = (frequency * (t + 0.5 * dt)).floor();
    if c.is_finite() && c > 0.0 {
        c as u64
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over 10⁷ steps of 1e-7 s (Karrech's time step) the exact clock ends at 1 s
    /// to round-off, while an accumulated clock drifts by 2.5e-10 s: at 50 Hz
    /// (Karrech's full load), 1.2e-8 of a cycle, more than the 1e-9 cycle that the
    /// former MD recorder allowed at a cycle boundary (the reason for the exact clock).
    #[test]
    fn exact_clock_does_not_drift() {
        let dt = 1e-7;
        let n = 10_000_000u64;
        let mut acc = 0.0;
        for _ in 0..n {
            acc += dt;
        }
        let exact = time_at(0.0, 0, n, dt);
        assert!((exact - 1.0).abs() <= 2.0 * f64::EPSILON, "{exact}");
        assert!(50.0 * (acc - 1.0).abs() > 1e-9, "the accumulated clock should drift: {acc}");
    }

    /// With 20 Hz cycles and 1e-4 s steps, cycle c is closed by step 500 c, even
    /// when the time of that step is a few ulps short of c / f.
    #[test]
    fn the_step_at_a_cycle_end_closes_it() {
        let (f, dt) = (20.0, 1e-4);
        for k in 1..=2000u64 {
            let t = time_at(0.0, 0, k, dt);
            assert_eq!(cycles_at(t, f, dt), k / 500, "step {k}");
            assert_eq!(cycles_at(t * (1.0 - 4.0 * f64::EPSILON), f, dt), k / 500, "step {k}");
        }
        assert_eq!(cycles_at(f64::NAN, f, dt), 0);
        assert_eq!(cycles_at(-1.0, f, dt), 0);
    }
}
