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

use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long an idle helper spins before it starts yielding its core.
const SPIN: Duration = Duration::from_micros(50);
/// How long an idle helper yields before it sleeps until the next job.
const YIELD: Duration = Duration::from_millis(5);

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
        let thread = std::thread::Builder::new().name("ballast-helper".into()).spawn(move || helper(&s));
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
        unsafe { *s.job.get() = Some(job) };
        s.posted.store(number, Ordering::SeqCst);
        if s.sleeping.load(Ordering::SeqCst) {
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
        let start = Instant::now();
        let mut spins = 0u32;
        while self.shared.done.load(Ordering::Acquire) < self.number {
            spins += 1;
            if spins < 4096 || start.elapsed() < SPIN {
                std::hint::spin_loop();
            } else {
                std::thread::yield_now();
            }
        }
        self.shared.busy.store(false, Ordering::Release);
    }
}

/// The helper's loop: wait for a job (spin, yield, then sleep), run it, report.
fn helper(s: &Shared) {
    let mut seen = 0u64;
    loop {
        let start = Instant::now();
        let mut spins = 0u32;
        loop {
            if s.stop.load(Ordering::Acquire) {
                return;
            }
            if s.posted.load(Ordering::Acquire) > seen {
                break;
            }
            spins = spins.wrapping_add(1);
            if !spins.is_multiple_of(64) {
                std::hint::spin_loop();
                continue;
            }
            let idle = start.elapsed();
            if idle < SPIN {
                std::hint::spin_loop();
            } else if idle < YIELD {
                std::thread::yield_now();
            } else {
                s.sleeping.store(true, Ordering::SeqCst);
                if s.posted.load(Ordering::SeqCst) == seen && !s.stop.load(Ordering::SeqCst) {
                    std::thread::park_timeout(Duration::from_millis(50));
                }
                s.sleeping.store(false, Ordering::SeqCst);
            }
        }
        seen = s.posted.load(Ordering::Acquire);
        // SAFETY: `posted` was raised after `job` was written, and the caller
        // does not write it again before `done` reaches `seen`.
        let job = unsafe { (*s.job.get()).take() };
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

#[cfg(test)]
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
