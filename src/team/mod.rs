//! A team of two threads for the parallel phases of a time step: the caller and
//! one persistent helper, with a join that never waits for a helper that is not
//! running.
//!
//! A soft-sphere step of a 2000-sphere bed lasts about 200 µs on one core and has
//! three parallel phases (predictor, pair forces, corrector); a split NLGS sweep
//! (`nscd::split`) of a loaded sample lasts 10–30 µs. Handing half of such a
//! phase to a sleeping worker (`rayon::join` from a quiet pool) costs a wake-up of
//! the same order as the phase itself. Here the helper thread is started once
//! and, between two jobs, spins (then yields, and sleeps only after a long idle
//! spell), so that [`Team::join`] hands over a job in well under a microsecond
//! while steps follow each other.
//!
//! The caller never waits for a half that has not started: the helper *takes*
//! a posted job before it runs it, and the caller, once its own half is done,
//! takes back a job the helper has not taken and runs it itself (the cure of
//! `rayon::join`), so a helper that is off its core costs nothing but the
//! posting. The caller waits only for a half the helper is running; if that
//! wait is long (the helper was descheduled while running it) or the machine is
//! so shared that two threads lose against one, the team measures it and runs
//! its joins in turn on the caller, with the helper asleep, until a later trial
//! finds side by side faster again (`team/choice.rs`).
//!
//! Who runs a half never changes what it computes: the numbers are the same on
//! one thread or two, in either mode.
//!
//! A team without a helper (one thread) runs both halves in order on the caller.
//!
//! The hand-over is checked by a loom model of this very code (`team/sync.rs`,
//! `tests/loom_team.rs`): `cargo test --features loom --test loom_team`.

mod choice;
mod sync;

pub use choice::TeamStats;
use choice::{Choice, Mode, Outcome};
use sync::{
    fence, spin_loop, thread, yield_now, Arc, AtomicBool, AtomicU64, Idle, JoinHandle, Mutex, Ordering, Pause,
    UnsafeCell,
};

/// The job handed to the helper: a borrowed closure whose lifetime has been
/// erased; [`Team::join`] does not return before the helper is done with it or
/// the caller has taken it back.
type Job = &'static (dyn Fn() + Sync);

struct Shared {
    /// Number of the last job posted.
    posted: AtomicU64,
    /// Number of the last job taken, by the helper (to run it) or back by the
    /// caller: whoever moves it from `n − 1` to `n` runs job `n`.
    taken: AtomicU64,
    /// Number of the last job the helper finished.
    done: AtomicU64,
    /// Set while the helper sleeps (it must then be unparked).
    sleeping: AtomicBool,
    /// Set while a join uses the helper: a join nested in one, or called from
    /// another thread meanwhile, runs its halves on its caller instead.
    busy: AtomicBool,
    /// Set while the team runs its joins in turn on the caller: the helper then
    /// sleeps at once instead of spinning.
    rest: AtomicBool,
    stop: AtomicBool,
    /// The posted job; written by the caller before `posted` is raised, read by
    /// the helper after it has taken the job, and not touched by the caller
    /// again before `done` catches up, unless the caller took the job back (then
    /// the helper never reads it).
    job: UnsafeCell<Option<Job>>,
}

// SAFETY: `job` is only accessed under the posted/taken/done hand-over described
// above (release stores, acquire loads, one winner of `taken`), so the caller and
// the helper never touch it at the same time; everything else is atomic.
unsafe impl Sync for Shared {}

struct Helper {
    shared: Arc<Shared>,
    thread: Option<JoinHandle<()>>,
    /// The mode choice, used by the holder of `busy` only (a std mutex in every
    /// build: loom need not model it).
    choice: std::sync::Mutex<Choice>,
}

impl Helper {
    fn choice(&self) -> std::sync::MutexGuard<'_, Choice> {
        self.choice.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
    }
}

/// The caller and, with two threads, one helper thread.
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
            taken: AtomicU64::new(0),
            done: AtomicU64::new(0),
            sleeping: AtomicBool::new(false),
            busy: AtomicBool::new(false),
            rest: AtomicBool::new(false),
            stop: AtomicBool::new(false),
            job: UnsafeCell::new(None),
        });
        let s = Arc::clone(&shared);
        let thread = thread::Builder::new().name("ballast-helper".into()).spawn(move || helper(&s));
        match thread {
            Ok(t) => {
                Team { helper: Some(Helper { shared, thread: Some(t), choice: std::sync::Mutex::new(Choice::new()) }) }
            }
            // No thread to be had: run on the caller alone.
            Err(_) => Team::default(),
        }
    }

    /// Threads of the team (1 or 2).
    pub fn threads(&self) -> usize {
        1 + usize::from(self.helper.is_some())
    }

    /// What the team's joins did so far (all zero without a helper).
    pub fn stats(&self) -> TeamStats {
        self.helper.as_ref().map(|h| h.choice().stats).unwrap_or_default()
    }

    /// Runs `a` on the caller and `b` on the helper at the same time, and returns
    /// both results; `b` runs on the caller after `a` if the helper has not
    /// started it by then, if the team found two threads slower than one on
    /// this machine at this time, without a helper, or while the helper is busy
    /// with another join (e.g. when called from inside `a` or `b`).
    ///
    /// # Panics
    /// If `a` or `b` panics (after the helper, if it runs `b`, has finished).
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
        // Released when this returns or unwinds, after the choice is updated.
        let _busy = Busy(&h.shared);
        let ticket = h.choice().start(now());
        let rest = ticket.mode == Mode::InTurn;
        if h.shared.rest.load(Ordering::Relaxed) != rest {
            h.shared.rest.store(rest, Ordering::Relaxed);
        }
        let (r, outcome) = if rest {
            let ra = a();
            ((ra, b()), Outcome::InTurn)
        } else {
            side_by_side(h, a, b)
        };
        h.choice().finish(ticket, outcome, now());
        r
    }
}

/// The time the mode choice reads.
#[cfg(not(feature = "loom"))]
fn now() -> choice::Clock {
    std::time::Instant::now()
}
#[cfg(feature = "loom")]
fn now() -> choice::Clock {}

/// Posts `b` to the helper, runs `a`, then takes `b` back if the helper has not
/// taken it, or waits for the helper to finish it.
fn side_by_side<RA, RB>(h: &Helper, a: impl FnOnce() -> RA, b: impl FnOnce() -> RB + Send) -> ((RA, RB), Outcome)
where
    RB: Send,
{
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
    // SAFETY: the helper runs the job only after taking it, and drops its copy
    // of the reference before it raises `done`; `Wait` (below, also on
    // unwinding) does not let this function return before the job is taken
    // back by the caller (then the helper never reads it) or `done` reaches its
    // number, so the closure outlives every use of the erased reference.
    let job: Job = unsafe { std::mem::transmute::<&(dyn Fn() + Sync), Job>(job) };
    let s = &*h.shared;
    let number = s.posted.load(Ordering::Relaxed) + 1;
    // SAFETY: the previous job was taken back, or finished by the helper
    // (`done == posted`), so the helper does not read `job` until `posted` is
    // raised below.
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
    let mut wait = Wait { shared: s, number, settled: false };
    let ra = a();
    if wait.take_back() {
        // The helper never read the job: clear its slot, and run `b` here.
        // SAFETY: this thread won job `number`; the helper touches the slot
        // again only after a later `posted`.
        s.job.with_mut(|slot| unsafe { *slot = None });
        let b = task.lock().ok().and_then(|mut t| t.take());
        let b = b.expect("a job taken back before it ran still holds its half");
        return ((ra, b()), Outcome::TakenBack);
    }
    let outcome = Outcome::Helper { own_end: now() };
    wait.finish();
    let rb = result.lock().ok().and_then(|mut r| r.take());
    match rb {
        Some(Ok(rb)) => ((ra, rb), outcome),
        Some(Err(payload)) => std::panic::resume_unwind(payload),
        None => panic!("the helper thread did not run its half of a parallel phase"),
    }
}

/// Releases the team's `busy` flag when dropped.
struct Busy<'a>(&'a Shared);

impl Drop for Busy<'_> {
    fn drop(&mut self) {
        self.0.busy.store(false, Ordering::Release);
    }
}

/// Settles job `number`: taken back by the caller, or waited for until the
/// helper has finished it; when dropped unsettled (the caller's half
/// panicked), whichever of the two applies.
struct Wait<'a> {
    shared: &'a Shared,
    number: u64,
    settled: bool,
}

impl Wait<'_> {
    /// Takes the job back if the helper has not taken it: true if so.
    fn take_back(&mut self) -> bool {
        let n = self.number;
        let won = self.shared.taken.compare_exchange(n - 1, n, Ordering::AcqRel, Ordering::Acquire).is_ok();
        self.settled = won;
        won
    }

    /// Waits until the helper has finished the job it took.
    fn finish(&mut self) {
        // Nothing here may panic: this is what keeps `join` from returning (or
        // unwinding) while the helper may still use the job.
        let mut idle = Idle::new();
        while self.shared.done.load(Ordering::Acquire) < self.number {
            match idle.caller_pause() {
                Pause::Spin => spin_loop(),
                Pause::Yield | Pause::Sleep => yield_now(),
            }
        }
        self.settled = true;
    }
}

impl Drop for Wait<'_> {
    fn drop(&mut self) {
        if !self.settled && !self.take_back() {
            self.finish();
        }
    }
}

/// The helper's loop: wait for a job (spin, yield, then sleep; straight to
/// sleep while the team runs in turn), take it unless the caller took it
/// back, run it, report.
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
            let pause = if s.rest.load(Ordering::Relaxed) { Pause::Sleep } else { idle.helper_pause() };
            match pause {
                Pause::Spin => spin_loop(),
                Pause::Yield => yield_now(),
                Pause::Sleep => {
                    // Either the caller sees `sleeping` after raising `posted` and
                    // unparks, or this sees the raise (the fences pair with the
                    // one in `side_by_side`); `Drop` unparks unconditionally after
                    // raising `stop`. An unpark that comes after this has woken up
                    // only leaves a token: the next sleep returns at once and
                    // re-checks.
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
        // Job `seen` is the caller's only outstanding one (it posts the next only
        // once this one is taken); take it unless the caller took it back.
        if s.taken.compare_exchange(seen - 1, seen, Ordering::AcqRel, Ordering::Relaxed).is_err() {
            continue;
        }
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
    fn every_join_is_counted_once() {
        // Whether the helper ran the second half, the caller took it back, or the
        // team ran it in turn, each join is one of the three.
        let team = Team::new(2);
        for i in 0..2000u64 {
            assert_eq!(team.join(|| i, || 2 * i), (i, 2 * i));
        }
        let s = team.stats();
        assert_eq!(s.joins, 2000);
        assert_eq!(s.on_helper + s.taken_back + s.in_turn, 2000);
        assert_eq!(Team::new(1).stats(), super::TeamStats::default());
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
