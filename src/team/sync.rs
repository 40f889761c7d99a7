//! The primitives the team synchronises with: std's in normal builds, and loom's
//! under the `loom` feature, so that the model (`tests/loom_team.rs`) checks the
//! very code of `team/mod.rs`, not a copy. Everything in `mod.rs` is the same
//! code in both builds; the only differences are here:
//!
//! - `UnsafeCell`: loom's tracks every access and reports two that are not
//!   ordered by happens-before; std's is wrapped with the same `with_mut` (a
//!   zero-cost inline call).
//! - The waiting policy ([`Idle`], [`sleep`]): loom has no clock (`Instant`) and no
//!   `park_timeout`, and time-based spinning would make its state space endless.
//!   In the model, an idle helper goes straight to the sleep path, where the real
//!   code first spins for 50 µs and yields until 5 ms of idleness; and `sleep` is
//!   a `park` without timeout. A spin or yield round only goes back to the check
//!   of `stop` and `posted` at the top of the loop, so the model still goes
//!   through every place where the helper can find a job or the stop (that
//!   check, before and after each sleep, and the re-check after raising
//!   `sleeping`) and through the unparks by `join` and by `Drop`. It has no spin
//!   round of its own because to loom a spin is a yield, after which it lets the
//!   other threads run rather than preempt them for the spinning one: with one
//!   spin round, the models missed a `Drop` without unpark and a `join` without
//!   unpark on the first job (both caught as they are). And it is stricter than
//!   the real code where it matters: the 50 ms timeout of the real sleep would
//!   hide a lost wake-up as a latency, while in the model it is a deadlock, which
//!   loom reports. The caller's wait for `done` is a loop of loom yields (spin
//!   and yield are the same thing to loom).
//! - The choice between running a join's halves side by side or in turn on the
//!   caller (`super::choice`) times the joins in normal builds; in the model it
//!   always tries side by side (the protocol is the same either way: a join on
//!   the caller posts nothing).
//!
//! With the feature on, a `Team` of two threads works only inside
//! `loom::model`: the feature is for the model test alone.

#[cfg(not(feature = "loom"))]
pub(super) use std::{
    hint::spin_loop,
    sync::atomic::{fence, AtomicBool, AtomicU64, Ordering},
    sync::{Arc, Mutex},
    thread::{self, yield_now, JoinHandle},
};

#[cfg(feature = "loom")]
pub(super) use loom::{
    cell::UnsafeCell,
    hint::spin_loop,
    sync::atomic::{fence, AtomicBool, AtomicU64, Ordering},
    sync::{Arc, Mutex},
    thread::{self, yield_now, JoinHandle},
};

/// What a waiting thread does next.
pub(super) enum Pause {
    /// Busy-wait one round (`spin_loop`).
    Spin,
    /// Give the core away for one round (`yield_now`).
    #[cfg_attr(feature = "loom", allow(dead_code))] // the model's waits are spins (loom yields)
    Yield,
    /// (Helper only) sleep until unparked: [`sleep`].
    Sleep,
}

/// `std::cell::UnsafeCell` with loom's access API.
#[cfg(not(feature = "loom"))]
pub(super) struct UnsafeCell<T>(std::cell::UnsafeCell<T>);

#[cfg(not(feature = "loom"))]
impl<T> UnsafeCell<T> {
    pub(super) const fn new(value: T) -> Self {
        UnsafeCell(std::cell::UnsafeCell::new(value))
    }

    #[inline(always)]
    pub(super) fn with_mut<R>(&self, f: impl FnOnce(*mut T) -> R) -> R {
        f(self.0.get())
    }
}

#[cfg(not(feature = "loom"))]
mod idle {
    use super::Pause;
    use std::time::{Duration, Instant};

    /// How long an idle helper spins before it starts yielding its core.
    const SPIN: Duration = Duration::from_micros(50);
    /// How long an idle helper yields before it sleeps until the next job.
    const YIELD: Duration = Duration::from_millis(5);

    /// The clock of one wait.
    pub(in super::super) struct Idle {
        start: Instant,
        spins: u32,
    }

    impl Idle {
        #[inline]
        pub(in super::super) fn new() -> Self {
            Idle { start: Instant::now(), spins: 0 }
        }

        /// The helper waiting for a job: spins for 50 µs (reading the clock
        /// every 64 rounds), then yields until 5 ms, then sleeps.
        #[inline]
        pub(in super::super) fn helper_pause(&mut self) -> Pause {
            self.spins = self.spins.wrapping_add(1);
            if !self.spins.is_multiple_of(64) {
                return Pause::Spin;
            }
            let idle = self.start.elapsed();
            if idle < SPIN {
                Pause::Spin
            } else if idle < YIELD {
                Pause::Yield
            } else {
                Pause::Sleep
            }
        }

        /// The caller waiting for the helper's half: spins at least 4096
        /// rounds and 50 µs, then yields; never sleeps (nothing would wake it).
        #[inline]
        pub(in super::super) fn caller_pause(&mut self) -> Pause {
            self.spins = self.spins.saturating_add(1);
            if self.spins < 4096 || self.start.elapsed() < SPIN {
                Pause::Spin
            } else {
                Pause::Yield
            }
        }
    }

    /// The helper's sleep: until unparked, or 50 ms at most.
    pub(in super::super) fn sleep() {
        std::thread::park_timeout(Duration::from_millis(50));
    }
}

#[cfg(feature = "loom")]
mod idle {
    use super::Pause;

    /// Rounds after which the caller's wait gives up in the model.
    const ROUNDS: u32 = 10_000;

    /// The count of one wait (the model's waits are not timed).
    pub(in super::super) struct Idle {
        rounds: u32,
    }

    impl Idle {
        pub(in super::super) fn new() -> Self {
            Idle { rounds: 0 }
        }

        /// The helper waiting for a job: straight to the sleep path (see the
        /// module's documentation for why not a spin round first).
        pub(in super::super) fn helper_pause(&mut self) -> Pause {
            Pause::Sleep
        }

        /// The caller waiting for the helper's half: a loom yield each round
        /// (to loom, `spin_loop` is `yield_now`), and an abort after `ROUNDS`.
        /// Loom stops an endless wait at its branch limit (1000 by default,
        /// reached long before), but not while the thread unwinds, as the
        /// guard's wait does when `a` panicked: a helper that never finished
        /// (e.g. a lost wake-up) then made a failing model grow until the
        /// machine ran out of memory. An abort, since the guard must not
        /// panic.
        pub(in super::super) fn caller_pause(&mut self) -> Pause {
            self.rounds += 1;
            if self.rounds > ROUNDS {
                // Straight to stderr: the test harness's capture would be
                // lost with the process.
                use std::io::Write;
                let _ = writeln!(
                    std::io::stderr(),
                    "team model: the helper did not finish its job ({ROUNDS} rounds of waiting); aborting"
                );
                std::process::abort();
            }
            Pause::Spin
        }
    }

    /// The helper's sleep: until unparked, without the real code's timeout,
    /// so that a lost wake-up is a deadlock loom reports.
    pub(in super::super) fn sleep() {
        loom::thread::park();
    }
}

pub(super) use idle::{sleep, Idle};
