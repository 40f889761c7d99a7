//! Loom model of the hand-over in `ballast::team::Team` (built with the `loom`
//! feature, on loom's primitives: see `mod sync` in `src/team.rs`):
//!
//! ```sh
//! cargo test --features loom --test loom_team   # or with --release
//! ```
//!
//! Each model runs `Team::join` as the crate compiles it, under every
//! interleaving of its threads (caller, helper, and in one model a second caller)
//! up to `LOOM_MAX_PREEMPTIONS` preemptions (3 unless set), and fails on a data
//! race on a loom `UnsafeCell` (the erased job slot inside the team, and the
//! `Probe`s written by the halves here), on a deadlock (among them a lost
//! wake-up of the sleeping helper: the model's sleep has no timeout), on a
//! leaked `Arc` (a helper that does not end) or on a wrong result.
//!
//! A `Probe` written by `b` on the helper and read by the caller after `join`
//! returns (or unwinds) is how the models check that `join` waits for the helper:
//! loom reports the read as a race unless the write happens before it.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Once};
use std::time::Instant;

use ballast::team::Team;
use loom::cell::UnsafeCell;

/// Runs `f` under loom with at most 3 preemptions (unless `LOOM_MAX_PREEMPTIONS`
/// says otherwise), and prints how many interleavings it went through
/// (`-- --nocapture` shows them).
fn model(name: &str, f: impl Fn() + Sync + Send + 'static) {
    let mut builder = loom::model::Builder::new();
    if builder.preemption_bound.is_none() {
        builder.preemption_bound = Some(3);
    }
    let runs = Arc::new(AtomicUsize::new(0));
    let counter = Arc::clone(&runs);
    let start = Instant::now();
    builder.check(move || {
        counter.fetch_add(1, Ordering::Relaxed);
        f();
    });
    let runs = runs.load(Ordering::Relaxed);
    eprintln!("{name}: {runs} interleavings in {:.2} s", start.elapsed().as_secs_f64());
    // Two threads meet in every model: one interleaving would mean no model.
    assert!(runs > 1, "{name}: loom explored a single interleaving");
}

/// A value written by one half and read after the join, with its accesses
/// checked by loom.
struct Probe(UnsafeCell<u32>);

// SAFETY: the point of the models: the accesses are ordered by `Team::join`, and
// loom checks that they are.
unsafe impl Sync for Probe {}

impl Probe {
    fn new() -> Self {
        Probe(UnsafeCell::new(0))
    }

    fn set(&self, v: u32) {
        // SAFETY: checked by loom (a race panics the model).
        self.0.with_mut(|p| unsafe { *p = v });
    }

    fn get(&self) -> u32 {
        // SAFETY: checked by loom.
        self.0.with(|p| unsafe { *p })
    }
}

/// The panics the models raise on purpose ("boom ...") are not printed, once per
/// interleaving; any other panic is, as usual.
fn quiet_booms() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let default = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            let boom = info.payload().downcast_ref::<&str>().is_some_and(|s| s.starts_with("boom"));
            if !boom {
                default(info);
            }
        }));
    });
}

fn message(payload: &(dyn std::any::Any + Send)) -> &str {
    payload.downcast_ref::<&str>().copied().unwrap_or("?")
}

#[test]
fn join_returns_both_halves() {
    model("join_returns_both_halves", || {
        let team = Team::new(2);
        assert_eq!(team.threads(), 2);
        let (pa, pb) = (Probe::new(), Probe::new());
        let (a, b) = team.join(
            || {
                pa.set(1);
                10
            },
            || {
                pb.set(2);
                20
            },
        );
        assert_eq!((a, b), (10, 20));
        assert_eq!((pa.get(), pb.get()), (1, 2));
    });
}

#[test]
fn each_half_runs_exactly_once() {
    // The helper takes the second half, or the caller takes it back once its own
    // half is done (a helper that has not started it costs nothing): loom goes
    // through both, and through the race between them; either way the half runs
    // once, and its write is seen by the caller after the join.
    static OUTCOMES: [AtomicUsize; 2] = [AtomicUsize::new(0), AtomicUsize::new(0)];
    model("each_half_runs_exactly_once", || {
        let team = Team::new(2);
        let runs = loom::sync::atomic::AtomicUsize::new(0);
        let probe = Probe::new();
        let (a, b) = team.join(
            || 1,
            || {
                runs.fetch_add(1, loom::sync::atomic::Ordering::Relaxed);
                probe.set(7);
                2
            },
        );
        assert_eq!((a, b), (1, 2));
        assert_eq!(probe.get(), 7);
        assert_eq!(runs.load(loom::sync::atomic::Ordering::Relaxed), 1);
        let stats = team.stats();
        assert_eq!(stats.on_helper + stats.taken_back, 1);
        OUTCOMES[usize::from(stats.taken_back == 1)].fetch_add(1, Ordering::Relaxed);
    });
    // The model went through both: the helper ran the half, the caller took it back.
    assert!(OUTCOMES.iter().all(|n| n.load(Ordering::Relaxed) > 0), "{OUTCOMES:?}");
}

#[test]
fn two_successive_joins() {
    // Between the two, the helper goes back to waiting (spin, then the sleep
    // path); the second job is posted wherever it is, and the job slot is
    // written again only after the helper has taken the first job out of it.
    model("two_successive_joins", || {
        let team = Team::new(2);
        let probe = Probe::new();
        for round in 1..=2u32 {
            let (a, b) = team.join(
                || round,
                || {
                    probe.set(probe.get() + round);
                    10 * round
                },
            );
            assert_eq!((a, b), (round, 10 * round));
        }
        assert_eq!(probe.get(), 3);
    });
}

#[test]
fn a_panic_in_b_reaches_the_caller_and_the_team_goes_on() {
    quiet_booms();
    model("a_panic_in_b_reaches_the_caller_and_the_team_goes_on", || {
        let team = Team::new(2);
        let probe = Probe::new();
        let r = catch_unwind(AssertUnwindSafe(|| {
            team.join(
                || probe.set(1),
                || -> u32 {
                    panic!("boom b");
                },
            )
        }));
        let payload = r.expect_err("the panic of b must reach the caller");
        assert_eq!(message(&*payload), "boom b");
        assert_eq!(probe.get(), 1);
        // The helper survived and the busy flag was released.
        assert_eq!(team.join(|| 1, || 2), (1, 2));
    });
}

#[test]
fn a_panic_in_a_waits_for_b_or_takes_it_back() {
    // The wait-on-drop guard: `join` unwinds only once the helper is done with
    // the job (which borrows this frame), or once the caller has taken back a
    // job the helper had not started (then `b` never runs, not even later: the
    // probe is unchanged once the helper has ended).
    quiet_booms();
    model("a_panic_in_a_waits_for_b_or_takes_it_back", || {
        let team = Team::new(2);
        let probe = Probe::new();
        let r = catch_unwind(AssertUnwindSafe(|| {
            team.join(
                || -> u32 {
                    panic!("boom a");
                },
                || probe.set(2),
            )
        }));
        let payload = r.expect_err("the panic of a must reach the caller");
        assert_eq!(message(&*payload), "boom a");
        let seen = probe.get();
        assert!(seen == 0 || seen == 2, "{seen}");
        let stats = team.stats();
        drop(team);
        assert_eq!(probe.get(), seen, "b ran after the join had unwound");
        // An unwinding join is not counted (the choice is not updated).
        assert_eq!(stats.joins, 0);
    });
}

#[test]
fn both_halves_panic() {
    // The caller's panic goes on; the helper's is caught, kept and dropped.
    quiet_booms();
    model("both_halves_panic", || {
        let team = Team::new(2);
        let r = catch_unwind(AssertUnwindSafe(|| {
            team.join(
                || -> u32 {
                    panic!("boom a");
                },
                || -> u32 {
                    panic!("boom b");
                },
            )
        }));
        assert_eq!(message(&*r.expect_err("a panic must reach the caller")), "boom a");
        assert_eq!(team.join(|| 1, || 2), (1, 2));
    });
}

#[test]
fn drop_while_idle_ends_the_helper() {
    // The helper may not have started, be spinning, or be asleep: `Drop` must
    // end it in every case (else `Drop` deadlocks on its join, or its `Arc`
    // leaks, and loom reports either).
    model("drop_while_idle_ends_the_helper", || {
        drop(Team::new(2));
    });
}

#[test]
fn nested_joins_run_on_their_caller() {
    // A join inside `a` (caller thread) and one inside `b` (helper thread) find
    // the team busy and run both their halves themselves.
    model("nested_joins_run_on_their_caller", || {
        let team = Team::new(2);
        let probe = Probe::new();
        let (a, (b, c)) = team.join(
            || team.join(|| 1, || 2),
            || {
                let r = team.join(|| 3, || 4);
                probe.set(5);
                r
            },
        );
        assert_eq!((a, b, c), ((1, 2), 3, 4));
        assert_eq!(probe.get(), 5);
    });
}

#[test]
fn a_join_from_another_thread_meanwhile() {
    // Two callers race for the helper through the busy flag: whichever loses runs
    // both halves itself; both get their results, and whichever wins sees the
    // helper's write.
    model("a_join_from_another_thread_meanwhile", || {
        let team = Arc::new(Team::new(2));
        let other = {
            let team = Arc::clone(&team);
            loom::thread::spawn(move || {
                let probe = Probe::new();
                let r = team.join(|| 1, || probe.set(3));
                assert_eq!(probe.get(), 3);
                r
            })
        };
        let probe = Probe::new();
        let r = team.join(|| 2, || probe.set(4));
        assert_eq!(probe.get(), 4);
        assert_eq!(r.0, 2);
        assert_eq!(other.join().unwrap().0, 1);
    });
}
