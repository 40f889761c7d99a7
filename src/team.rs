//! A team of two threads for the parallel phases of a time step: the caller and
//! one persistent helper that waits by spinning between phases.
//!
//! A soft-sphere step of a 2000-sphere bed lasts about 200 µs on one core and has
//! three parallel phases (predictor, pair forces, corrector). Handing half of each
//! phase to a sleeping worker (`rayon::join` from a quiet pool) costs a wake-up of
//! the same order as the phase itself, which is why the MD step did not speed up on
//! two cores. Here the helper thread is started once and, between two jobs, spins
//! (then yields, and sleeps only after a long idle spell), so that
//! [`Team::join`] hands over a job in well under a microsecond while steps follow
//! each other; the caller runs its own half meanwhile and then waits for the
//! helper's, so both halves always run at the same time.
//!
//! The split NLGS (`nscd::split`) uses the same team for its two half-sweeps.
//!
//! A team without a helper (one thread) runs both halves in order on the caller.
//!
//! The hand-over is checked by a loom model of this very code (`mod sync` below,
//! `tests/loom_team.rs`): `cargo test --features loom --test loom_team`.

use sync::{
    fence, spin_loop, thread, yield_now, Arc, AtomicBool, AtomicU64, Idle, JoinHandle, Mutex, Ordering, UnsafeCell,
};

/// The job handed to the helper: a borrowed closure whose lifetime has been
/// erased; [`Team::join`] does not return before the helper is done with it.
type Job = &'static (dyn Fn() + Sync);

struct Shared {
    /// Number of the last job posted.
    posted: AtomicU64,
    /// Number of the last job the helper finished.
    done: AtomicU64,
    /// Set while the helper sleeps (it must then be unparked).
    sleeping: AtomicBool,
    /// Set while a join uses the helper: a join nested in one, or called from
    /// another thread meanwhile, runs its halves on its caller instead.
    busy: AtomicBool,
    stop: AtomicBool,
    /// The posted job; written by the caller before `posted` is raised, read by
    /// the helper after it sees the raise, and not touched by the caller again
    /// before `done` catches up.
    job: UnsafeCell<Option<Job>>,
}

// SAFETY: `job` is only accessed under the posted/done hand-over described above
// (release stores, acquire loads), so the caller and the helper never touch it at
// the same time; everything else is atomic.
unsafe impl Sync for Shared {}

struct Helper {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
}

/// The caller and, with two threads, one spinning helper thread.
#[derive(Default)]
pub struct Team {
    helper: Option<Helper>,
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Team({} threads)", self.threads())
    }
}

/// A copy of a team is a team of one thread (a helper belongs to one owner).
impl Clone for Team {
    fn clone(&self) -> Self {
        Team::default()
    }
}

impl Team {
    /// A team of `threads` threads: 1 (the caller alone) or 2 (caller + helper);
    /// more are not used.
    pub fn new(threads: usize) -> Self {
        if threads < 2 {
            return Team::default();
        }
        let shared = Arc::new(Shared {
            posted: AtomicU64::new(0),
            done: AtomicU64::new(0),
            sleeping: AtomicBool::new(false),
            busy: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            job: UnsafeCell::new(None),
        });
        let s = Arc::clone(&shared);
        let thread = thread::Builder::new().name("ballast-helper".into()).spawn(move || helper(&s));
        match thread {
            Ok(t) => Team { helper: Some(Helper { shared, thread: Some(t) }) },
            // No thread to be had: run on the caller alone.
            Err(_) => Team::default(),
        }
    }

    /// Threads of the team (1 or 2).
    pub fn threads(&self) -> usize {
        1 + usize::from(self.helper.is_some())
    }

    /// Runs `a` on the caller and `b` on the helper at the same time, and returns
    /// both results; without a helper (or while it is busy with another join,
    /// e.g. when called from inside `a` or `b`), `a` then `b` on the caller.
    ///
    /// # Panics
    /// If `a` or `b` panics (after both have finished).
    pub fn join<RA, RB>(&self, a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> (RA, RB)
    where
        RB: Send,
    {
        let helper = self
            .helper
            .as_ref()
            .filter(|h| h.shared.busy.compare_exchange(false, true, Ordering::Acquire, Ordering::Relaxed).is_ok());
        let Some(h) = helper else {
            let ra = a();
            return (ra, b());
        };
        let task = Mutex::new(Some(b));
        let result: Mutex<Option<std::thread::Result<RB>>> = Mutex::new(None);
        let job = || {
            let b = task.lock().ok().and_then(|mut t| t.take());
            if let Some(b) = b {
                let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(b));
                if let Ok(mut slot) = result.lock() {
                    *slot = Some(r);
                }
            }
        };
        let job: &(dyn Fn() + Sync) = &job;
        // SAFETY: the helper drops its copy of the reference before it raises
        // `done`, and `Wait` (below, also on unwinding) does not let this
        // function return before `done` reaches this job's number, so the
        // closure outlives every use of the erased reference.
        let job: Job = unsafe { std::mem::transmute::<&(dyn Fn() + Sync), Job>(job) };
        let s = &h.shared;
        let number = s.posted.load(Ordering::Relaxed) + 1;
        // SAFETY: the helper finished the previous job (`done == posted`), so it
        // does not read `job` until `posted` is raised below.
        s.job.with_mut(|slot| unsafe { *slot = Some(job) });
        s.posted.store(number, Ordering::Release);
        // With the fence of the helper's sleep path, a store-buffering (Dekker)
        // hand-shake: either this load sees `sleeping` raised and unparks the
        // helper, or the helper's re-check after raising it sees this job. (SeqCst
        // fences rather than SeqCst accesses: the same guarantee, and the form
        // loom checks; it treats SeqCst accesses as AcqRel.)
        fence(Ordering::SeqCst);
        if s.sleeping.load(Ordering::Relaxed) {
            if let Some(t) = &h.thread {
                t.thread().unpark();
            }
        }
        let wait = Wait { shared: s, number };
        let ra = a();
        drop(wait);
        let rb = result.lock().ok().and_then(|mut r| r.take());
        match rb {
            Some(Ok(rb)) => (ra, rb),
            Some(Err(payload)) => std::panic::resume_unwind(payload),
            None => panic!("the helper thread did not run its half of a parallel phase"),
        }
    }
}

/// Waits, when dropped, until the helper has finished job `number`.
struct Wait<'a> {
    shared: &'a Shared,
    number: u64,
}

impl Drop for Wait<'_> {
    fn drop(&mut self) {
        // Nothing here may panic: this guard is what keeps `join` from returning
        // (or unwinding) while the helper may still use the job.
        let mut idle = Idle::new();
        while self.shared.done.load(Ordering::Acquire) < self.number {
            match idle.caller_pause() {
                Pause::Spin => spin_loop(),
                Pause::Yield | Pause::Sleep => yield_now(),
            }
        }
        self.shared.busy.store(false, Ordering::Release);
    }
}

/// The helper's loop: wait for a job (spin, yield, then sleep), run it, report.
fn helper(s: &Shared) {
    let mut seen = 0u64;
    loop {
        let mut idle = Idle::new();
        loop {
            if s.stop.load(Ordering::Acquire) {
                return;
            }
            if s.posted.load(Ordering::Acquire) > seen {
                break;
            }
            match idle.helper_pause() {
                Pause::Spin => spin_loop(),
                Pause::Yield => yield_now(),
                Pause::Sleep => {
                    // Either the caller sees `sleeping` after raising `posted` and
                    // unparks, or this sees the raise (the fences pair with the
                    // one in `join`); `Drop` unparks unconditionally after raising
                    // `stop`. An unpark that comes after this has woken up only
                    // leaves a token: the next sleep returns at once and re-checks.
                    s.sleeping.store(true, Ordering::Relaxed);
                    fence(Ordering::SeqCst);
                    if s.posted.load(Ordering::Relaxed) == seen && !s.stop.load(Ordering::SeqCst) {
                        sync::sleep();
                    }
                    s.sleeping.store(false, Ordering::Relaxed);
                }
            }
        }
        seen = s.posted.load(Ordering::Acquire);
        // SAFETY: `posted` was raised after `job` was written, and the caller
        // does not write it again before `done` reaches `seen`.
        let job = s.job.with_mut(|slot| unsafe { (*slot).take() });
        if let Some(job) = job {
            job();
        }
        s.done.store(seen, Ordering::Release);
    }
}

impl Drop for Team {
    fn drop(&mut self) {
        if let Some(h) = &mut self.helper {
            h.shared.stop.store(true, Ordering::SeqCst);
            if let Some(t) = h.thread.take() {
                t.thread().unpark();
                let _ = t.join();
            }
        }
    }
}

/// What a waiting thread does next.
enum Pause {
    /// Busy-wait one round (`spin_loop`).
    Spin,
    /// Give the core away for one round (`yield_now`).
    #[cfg_attr(feature = "loom", allow(dead_code))] // the model's waits are spins (loom yields)
    Yield,
    /// (Helper only) sleep until unparked: [`sync::sleep`].
    Sleep,
}

/// The primitives the team synchronises with: std's in normal builds, and loom's
/// under the `loom` feature, so that the model (`tests/loom_team.rs`) checks this
/// very code, not a copy. Everything above is the same code in both builds; the
/// only differences are here:
///
/// - `UnsafeCell`: loom's tracks every access and reports two that are not
///   ordered by happens-before; std's is wrapped with the same `with_mut` (a
///   zero-cost inline call).
/// - The waiting policy ([`Idle`], [`sleep`]): loom has no clock (`Instant`) and no
///   `park_timeout`, and time-based spinning would make its state space endless.
///   In the model, an idle helper goes straight to the sleep path, where the real
///   code first spins for 50 µs and yields until 5 ms of idleness; and `sleep` is
///   a `park` without timeout. A spin or yield round only goes back to the check
///   of `stop` and `posted` at the top of the loop, so the model still goes
///   through every place where the helper can find a job or the stop (that
///   check, before and after each sleep, and the re-check after raising
///   `sleeping`) and through the unparks by `join` and by `Drop`. It has no spin
///   round of its own because to loom a spin is a yield, after which it lets the
///   other threads run rather than preempt them for the spinning one: with one
///   spin round, the models missed a `Drop` without unpark and a `join` without
///   unpark on the first job (both caught as they are). And it is stricter than
///   the real code where it matters: the 50 ms timeout of the real sleep would
///   hide a lost wake-up as a latency, while in the model it is a deadlock, which
///   loom reports. The caller's wait for `done` is a loop of loom yields (spin
///   and yield are the same thing to loom).
///
/// With the feature on, a `Team` of two threads works only inside
/// `loom::model`: the feature is for the model test alone.
mod sync {
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

    use super::Pause;

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
}

#[cfg(all(test, not(feature = "loom")))]
mod tests {
    use super::Team;

    #[test]
    fn both_halves_run_and_return() {
        for threads in [1, 2] {
            let team = Team::new(threads);
            let mut data = vec![0u64; 1000];
            for round in 0..200u64 {
                let (lo, hi) = data.split_at_mut(500);
                let (a, b) = team.join(
                    || {
                        lo.iter_mut().for_each(|x| *x += round);
                        lo.iter().sum::<u64>()
                    },
                    || {
                        hi.iter_mut().for_each(|x| *x += 2 * round);
                        hi.iter().sum::<u64>()
                    },
                );
                let t = round * (round + 1) / 2;
                assert_eq!((a, b), (500 * t, 1000 * t));
            }
        }
    }

    #[test]
    fn the_helper_runs_on_another_thread_at_the_same_time() {
        // The caller's half waits for a flag only the helper's half sets: this
        // finishes only if the halves really run concurrently.
        use std::sync::atomic::{AtomicBool, Ordering};
        let team = Team::new(2);
        let flag = AtomicBool::new(false);
        let caller = std::thread::current().id();
        let (_, other) = team.join(
            || {
                while !flag.load(Ordering::Acquire) {
                    std::hint::spin_loop();
                }
            },
            || {
                flag.store(true, Ordering::Release);
                std::thread::current().id()
            },
        );
        assert_ne!(other, caller);
    }

    #[test]
    fn nested_and_concurrent_joins_run_on_their_caller() {
        let team = Team::new(2);
        let (a, (b, c)) = team.join(|| team.join(|| 1, || 2), || team.join(|| 3, || 4));
        assert_eq!((a, b, c), ((1, 2), 3, 4));
        // Two threads sharing the team: each join either gets the helper or runs
        // both halves itself; every result comes back.
        std::thread::scope(|s| {
            let t: Vec<_> = (0..2u64)
                .map(|k| {
                    let team = &team;
                    s.spawn(move || (0..500u64).map(|i| team.join(|| i, || k * i)).map(|(x, y)| x + y).sum::<u64>())
                })
                .collect();
            let sums: Vec<u64> = t.into_iter().map(|h| h.join().unwrap()).collect();
            assert_eq!(sums, vec![124_750, 249_500]);
        });
    }

    #[test]
    fn a_panic_in_the_helper_reaches_the_caller() {
        let team = Team::new(2);
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| team.join(|| 1, || panic!("boom"))));
        assert!(r.is_err());
        // The team still works afterwards.
        assert_eq!(team.join(|| 1, || 2), (1, 2));
    }
}
