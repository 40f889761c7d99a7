//! Whether a join's two halves run side by side (the second on the helper) or
//! one after the other on the caller: chosen by timing both on the joins
//! themselves.
//!
//! On an idle machine two threads sweep a split NLGS problem in about 0.6 of one
//! thread's time. On a shared machine they can be far slower than one: with a
//! busy process beside them, three running threads share two cores, and a
//! helper that is off its core, or on the caller's core, turns every join into a
//! wait (measured: 1.7× the one-thread time beside a shell loop, up to 8× on an
//! idle machine when the scheduler put both threads on one core). Which case
//! holds depends on the scheduler, from second to second, and cannot be read
//! from the system; so the team measures it.
//!
//! Most of the time the team *exploits* its current mode. Every `period` of
//! wall time it runs a *trial* of four blocks of joins, in the order other
//! mode, current, current, other (an ABBA design: a linear drift of the work
//! per join cancels out). The first block runs until it has lasted [`BLOCK`]
//! and counted at least [`MIN_JOINS`] joins; the three others run as many
//! joins each, so the four blocks do the same mix of work (the phases of an MD
//! step, or the sweeps and checks of an NLGS step, whose work per join changes
//! slowly from step to step). Side by side is chosen if its two blocks took
//! less than `1 − MARGIN` of the two blocks in turn, else in turn: a helper
//! costs something outside the joins too (it spins for a while after each, on
//! a core the caller may need), so it must earn its place. A switch starts the
//! period again from [`MIN_PERIOD`]; a trial that keeps the mode doubles it, up
//! to [`MAX_PERIOD`]. In the trial the worse mode runs for about `BLOCK`
//! twice, so the trials cost a few per cent of the first second and a fraction
//! of a per cent after. A parallel join whose caller waited for the helper for
//! much longer than its own half took (the helper was descheduled holding its
//! half) brings the next trial forward, to no sooner than `MIN_PERIOD` after
//! the last one.
//!
//! A join's time in a trial runs from the end of the previous join (at most
//! [`GAP`] before its start) to its own end: the serial work between joins
//! (the interface rows of a split sweep, detection between two steps) is timed
//! with them, because a spinning helper slows it when it shares the caller's
//! core, while a long pause (outputs) counts only `GAP`.
//!
//! Whoever runs a half, the halves are the same computations on the same data,
//! so the numbers do not depend on the mode.

#[cfg(not(feature = "loom"))]
use std::time::{Duration, Instant};

/// What the choice reads the time from: `Instant` (nothing in the loom model).
#[cfg(not(feature = "loom"))]
pub(super) type Clock = Instant;
#[cfg(feature = "loom")]
pub(super) type Clock = ();

/// How the halves of a join run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Mode {
    /// `a` on the caller while the helper runs `b` (or the caller takes `b`
    /// back if the helper has not started it when `a` is done).
    SideBySide,
    /// `a` then `b` on the caller; the helper sleeps.
    InTurn,
}

impl Mode {
    #[cfg(not(feature = "loom"))]
    fn other(self) -> Mode {
        match self {
            Mode::SideBySide => Mode::InTurn,
            Mode::InTurn => Mode::SideBySide,
        }
    }
}

/// What happened to a join's second half.
#[derive(Debug, Clone, Copy)]
pub(super) enum Outcome {
    /// Run on the caller in turn.
    InTurn,
    /// Posted, then taken back by the caller because the helper had not
    /// started it.
    TakenBack,
    /// Run by the helper; the caller's own half ended at `own_end`, and from
    /// then to the join's end it waited for the helper.
    #[cfg_attr(feature = "loom", allow(dead_code))] // the model times nothing
    Helper { own_end: Clock },
}

/// Counts of a team's joins since it was made (see [`super::Team::stats`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct TeamStats {
    /// Joins that used the team (a join nested in another, or made meanwhile
    /// from another thread, runs on its caller and is not counted).
    pub joins: u64,
    /// Joins whose second half the helper ran.
    pub on_helper: u64,
    /// Joins whose second half was posted to the helper and taken back by the
    /// caller, the helper not having started it.
    pub taken_back: u64,
    /// Joins run in turn on the caller (the team had chosen one thread).
    pub in_turn: u64,
    /// Trials of the two modes.
    pub trials: u64,
    /// Switches of mode the trials decided.
    pub switches: u64,
}

/// A join's mode, and when it started (to time it in a trial).
pub(super) struct Ticket {
    pub(super) mode: Mode,
    #[cfg(not(feature = "loom"))]
    start: Instant,
}

/// How long a trial's first block lasts (its joins and the gaps before them).
#[cfg(not(feature = "loom"))]
const BLOCK: Duration = Duration::from_millis(4);
/// The fewest joins of a trial's block.
#[cfg(not(feature = "loom"))]
const MIN_JOINS: u32 = 16;
/// The first time between two trials (and the shortest).
#[cfg(not(feature = "loom"))]
const MIN_PERIOD: Duration = Duration::from_millis(40);
/// The longest time between two trials.
#[cfg(not(feature = "loom"))]
const MAX_PERIOD: Duration = Duration::from_millis(2560);
/// Side by side must be this much faster than in turn to be chosen.
#[cfg(not(feature = "loom"))]
const MARGIN: f64 = 0.05;
/// The longest gap before a join that is timed with it.
#[cfg(not(feature = "loom"))]
const GAP: Duration = Duration::from_millis(1);

#[cfg(not(feature = "loom"))]
#[derive(Debug)]
enum Phase {
    /// The current mode from `since` until the next trial.
    Exploit { since: Instant, until: Instant },
    /// Block `block` (0–3) of a trial: joins counted in this block, joins each
    /// block after the first runs, and the time of each block.
    Trial { block: usize, joins: u32, target: u32, time: [Duration; 4] },
}

/// The mode choice of a team with a helper.
#[derive(Debug)]
pub(super) struct Choice {
    #[cfg(not(feature = "loom"))]
    current: Mode,
    #[cfg(not(feature = "loom"))]
    phase: Phase,
    #[cfg(not(feature = "loom"))]
    period: Duration,
    /// When the last join ended.
    #[cfg(not(feature = "loom"))]
    last_end: Option<Instant>,
    pub(super) stats: TeamStats,
}

#[cfg(not(feature = "loom"))]
impl Choice {
    pub(super) fn new() -> Self {
        Choice {
            current: Mode::SideBySide,
            phase: {
                let since = Instant::now();
                Phase::Exploit { since, until: since + MIN_PERIOD }
            },
            period: MIN_PERIOD,
            last_end: None,
            stats: TeamStats::default(),
        }
    }

    /// The mode of the join that starts `start` (now, but for the tests).
    pub(super) fn start(&mut self, start: Instant) -> Ticket {
        if let Phase::Exploit { until, .. } = self.phase {
            if start >= until {
                self.stats.trials += 1;
                self.phase = Phase::Trial { block: 0, joins: 0, target: 0, time: [Duration::ZERO; 4] };
            }
        }
        let mode = match self.phase {
            Phase::Exploit { .. } => self.current,
            Phase::Trial { block, .. } => self.trial_mode(block),
        };
        Ticket { mode, start }
    }

    /// The mode of block `block` of a trial: other, current, current, other.
    fn trial_mode(&self, block: usize) -> Mode {
        if block == 0 || block == 3 {
            self.current.other()
        } else {
            self.current
        }
    }

    /// Records how the join of `ticket` went; it ended `now`.
    pub(super) fn finish(&mut self, ticket: Ticket, outcome: Outcome, now: Instant) {
        self.count(outcome);
        let from = self.last_end.map_or(ticket.start, |end| end.max(ticket.start.checked_sub(GAP).unwrap_or(end)));
        self.last_end = Some(now);
        match &mut self.phase {
            Phase::Exploit { since, until } => {
                // The helper was descheduled holding its half: look again soon,
                // but not sooner than MIN_PERIOD after the last trial (a helper
                // whose half is much longer than the caller's would otherwise
                // call a trial at every join).
                if let Outcome::Helper { own_end } = outcome {
                    if now - own_end > 2 * (own_end - ticket.start) + Duration::from_micros(100) {
                        *until = (*until).min(now.max(*since + MIN_PERIOD));
                    }
                }
            }
            Phase::Trial { block, joins, target, time } => {
                time[*block] += now - from;
                *joins += 1;
                let ended = if *block == 0 { time[0] >= BLOCK && *joins >= MIN_JOINS } else { *joins >= *target };
                if !ended {
                    return;
                }
                if *block == 0 {
                    *target = *joins;
                }
                *joins = 0;
                *block += 1;
                if *block == 4 {
                    let (other, current) = ((time[0] + time[3]).as_secs_f64(), (time[1] + time[2]).as_secs_f64());
                    let (side_by_side, in_turn) = match self.current {
                        Mode::SideBySide => (current, other),
                        Mode::InTurn => (other, current),
                    };
                    let best = if side_by_side < (1.0 - MARGIN) * in_turn { Mode::SideBySide } else { Mode::InTurn };
                    if best != self.current {
                        self.current = best;
                        self.period = MIN_PERIOD;
                        self.stats.switches += 1;
                    } else {
                        self.period = (2 * self.period).min(MAX_PERIOD);
                    }
                    self.phase = Phase::Exploit { since: now, until: now + self.period };
                }
            }
        }
    }
}

/// In the loom model: always side by side, nothing timed.
#[cfg(feature = "loom")]
impl Choice {
    pub(super) fn new() -> Self {
        Choice { stats: TeamStats::default() }
    }

    pub(super) fn start(&mut self, _now: Clock) -> Ticket {
        Ticket { mode: Mode::SideBySide }
    }

    pub(super) fn finish(&mut self, _ticket: Ticket, outcome: Outcome, _now: Clock) {
        self.count(outcome);
    }
}

impl Choice {
    fn count(&mut self, outcome: Outcome) {
        let s = &mut self.stats;
        s.joins += 1;
        match outcome {
            Outcome::InTurn => s.in_turn += 1,
            Outcome::TakenBack => s.taken_back += 1,
            Outcome::Helper { .. } => s.on_helper += 1,
        }
    }
}

#[cfg(all(test, not(feature = "loom")))]
mod tests {
    use super::*;

    /// Runs `joins` joins whose duration depends on the mode, one after the
    /// other on a synthetic clock that starts at `*now`.
    fn drive(choice: &mut Choice, now: &mut Instant, joins: usize, cost: impl Fn(Mode) -> Duration) {
        for _ in 0..joins {
            let t = choice.start(*now);
            let d = cost(t.mode);
            *now += d;
            let outcome = match t.mode {
                Mode::InTurn => Outcome::InTurn,
                Mode::SideBySide => Outcome::Helper { own_end: *now },
            };
            choice.finish(t, outcome, *now);
        }
    }

    #[test]
    fn the_faster_mode_wins_and_stays() {
        // In turn twice as fast as side by side (a helper sharing the caller's
        // core): the first trial switches, the later ones keep it.
        let mut c = Choice::new();
        let mut now = Instant::now() + MIN_PERIOD;
        drive(&mut c, &mut now, 200, |m| Duration::from_micros(if m == Mode::InTurn { 100 } else { 200 }));
        assert_eq!(c.current, Mode::InTurn);
        assert_eq!((c.stats.trials, c.stats.switches), (1, 1));
        // Later trials keep it: 40 ms of joins to the second trial, 80 to the third.
        drive(&mut c, &mut now, 2000, |m| Duration::from_micros(if m == Mode::InTurn { 100 } else { 200 }));
        assert_eq!((c.stats.trials, c.stats.switches), (3, 1));
        assert_eq!(c.period, 4 * MIN_PERIOD);
        // Side by side faster again: the next trial switches back.
        now += c.period;
        drive(&mut c, &mut now, 200, |m| Duration::from_micros(if m == Mode::InTurn { 200 } else { 100 }));
        assert_eq!(c.current, Mode::SideBySide);
        assert_eq!((c.stats.trials, c.stats.switches), (4, 2));
        assert_eq!(c.stats.joins, 2400);
        assert_eq!(c.stats.in_turn + c.stats.on_helper, 2400);
    }

    #[test]
    fn equal_modes_choose_one_thread_and_the_period_grows() {
        // Side by side is kept only if it is faster by the margin.
        let mut c = Choice::new();
        let mut now = Instant::now();
        for _ in 0..3 {
            now += c.period;
            drive(&mut c, &mut now, 200, |_| Duration::from_micros(100));
        }
        assert_eq!(c.current, Mode::InTurn);
        assert_eq!(c.stats.switches, 1);
        assert_eq!(c.stats.trials, 3);
        assert_eq!(c.period, 4 * MIN_PERIOD);
    }

    #[test]
    fn a_long_wait_for_the_helper_brings_the_trial_forward() {
        let mut c = Choice::new();
        let now = Instant::now();
        c.phase = Phase::Exploit { since: now, until: now + Duration::from_secs(60) };
        let long = |c: &mut Choice, at: Instant| {
            let t = c.start(at);
            assert_eq!(t.mode, Mode::SideBySide);
            let own_end = at + Duration::from_micros(10);
            c.finish(t, Outcome::Helper { own_end }, own_end + Duration::from_millis(1));
        };
        // Within MIN_PERIOD of the last trial: the trial comes at MIN_PERIOD.
        long(&mut c, now);
        assert!(matches!(c.phase, Phase::Exploit { until, .. } if until == now + MIN_PERIOD));
        // Long after the last trial: at once.
        let later = now + 3 * MIN_PERIOD;
        c.phase = Phase::Exploit { since: now, until: later + Duration::from_secs(60) };
        long(&mut c, later);
        let t = c.start(later + Duration::from_millis(2));
        assert!(matches!(c.phase, Phase::Trial { .. }));
        assert_eq!(t.mode, Mode::InTurn);
    }
}
