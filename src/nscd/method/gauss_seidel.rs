//! Nonlinear block Gauss–Seidel (Saussine et al. 2006, §2.7), for rows of any dimension ([`super::Row`]).
//!
//! The body velocities `u` start at `u_free + M⁻¹ Σ H P` with the warm-start
//! impulses `P` of the previous step. Each sweep visits every row (springs, then
//! contacts) in a fixed order, computes its local velocity without its own
//! impulse, `U_0 = H* u − W P`, solves the single-row law exactly
//! (in 2D [`crate::nscd::coulomb::solve`] or the spring's affine law), and immediately
//! applies the impulse change to the two bodies' velocities. Rows are visited in
//! key order (candidate body index first); `symmetric` alternates forward and
//! backward sweeps, which was measured slower on a 536-pentagon deposit (183 vs
//! 126 sweeps per step), so it is off by default. Sweeps stop when
//! the convergence policy ([`super::criterion`]) is met after at least
//! `min_iterations` sweeps, or after `max_iterations`.
//!
//! The loop touches, per contact, one contiguous record and the velocity and
//! inverse-mass records of its two bodies; nothing is allocated.

use super::criterion::{evaluate, Measure, Policy, SweepNorms, VelocityTail};
use super::settings::NlgsSettings;
use super::split::SplitWorkspace;
use super::Row;

/// A frozen problem of one step: free velocities, inverse masses, contact rows `R` and spring rows `S` with
/// zero impulses (for benchmarks and diagnostics; in 2D see [`crate::nscd::System::nlgs_problem`]).
#[derive(Debug, Clone)]
pub struct NlgsProblem<R: Row, S: Row<Dofs = R::Dofs>> {
    /// Body velocities before any impulse, `u_free` (in 2D `[u_x, u_y, ω]`: m/s, m/s, rad/s).
    pub u: Vec<R::Dofs>,
    /// Inverse masses of the bodies (in 2D `[1/m, 1/m, 1/I]`: 1/kg, 1/kg, 1/(kg·m²)); zero
    /// for a fixed body or an imposed component.
    pub inv_m: Vec<R::Dofs>,
    /// Contact rows, impulses set to zero.
    pub rows: Vec<R>,
    /// Spring rows (the sublayer's), impulses set to zero.
    pub springs: Vec<S>,
}

/// What the iterations achieved.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct NlgsReport {
    /// Sweeps made.
    pub iterations: usize,
    /// Value of the policy's norm after the last sweep (dimensionless; see
    /// [`super::criterion::evaluate`]).
    pub criterion: f64,
    /// Whether the last sweep met the tolerance (false when `max_iterations` was reached first).
    pub converged: bool,
}

/// Adds `M⁻¹ H P` of every row to `u` (the warm start).
pub fn apply_impulses<R: Row, S: Row<Dofs = R::Dofs>>(u: &mut [R::Dofs], inv_m: &[R::Dofs], rows: &[R], springs: &[S]) {
    add_impulses(u, inv_m, rows, springs, 1.0);
}

/// Subtracts `M⁻¹ H P` of every row from `u`: the free velocity of a consistent pair.
pub fn remove_impulses<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &[R],
    springs: &[S],
) {
    add_impulses(u, inv_m, rows, springs, -1.0);
}

/// Adds `sign · M⁻¹ H P` of every row to `u`, springs first.
fn add_impulses<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &[R],
    springs: &[S],
    sign: f64,
) {
    for s in springs {
        s.add_impulse(u, inv_m, sign);
    }
    for r in rows {
        r.add_impulse(u, inv_m, sign);
    }
}

/// What one pass over the rows does.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Pass {
    /// A Gauss–Seidel sweep in key order.
    Forward,
    /// A Gauss–Seidel sweep in key order, each row's change scaled by `ω` (the
    /// factor, in (0, 2)) and the result projected back on its law
    /// (in 2D `P_N ≥ 0`, `|P_T| ≤ μ P_N`; a compression-only spring `P ≥ 0`).
    Relaxed(f64),
    /// A Gauss–Seidel sweep in reverse key order.
    Backward,
    /// LMGC90's check: every row solved from the current velocities, nothing updated.
    Check,
}

/// One sweep over all rows, forwards or backwards; returns the norms of the corrections.
#[inline(never)]
pub fn sweep<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
    backwards: bool,
) -> SweepNorms {
    if backwards {
        sweep_in::<true, _, _>(u, inv_m, rows.iter_mut().rev(), springs.iter_mut().rev(), 1.0)
    } else {
        sweep_in::<true, _, _>(u, inv_m, rows.iter_mut(), springs.iter_mut(), 1.0)
    }
}

/// One forward sweep with over-relaxation `omega` ([`Pass::Relaxed`]).
#[inline(never)]
pub fn sweep_relaxed<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
    omega: f64,
) -> SweepNorms {
    sweep_in::<true, _, _>(u, inv_m, rows.iter_mut(), springs.iter_mut(), omega)
}

/// The check pass of LMGC90 (Jean's violation, `i_check` of its NLGS): every row
/// solved exactly from the current velocities and impulses, nothing updated; the
/// norms measure the distance between the stored impulses and those local
/// solutions, i.e. the fixed-point residual of the current iterate.
#[inline(never)]
pub fn check<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> SweepNorms {
    sweep_in::<false, _, _>(u, inv_m, rows.iter_mut(), springs.iter_mut(), 1.0)
}

/// The check pass ([`check`]) row by row, for a diagnosis of which rows hold a solve: the norms of each spring row
/// and of each contact row on their own, in their order. Nothing is updated, so the rows' norms add up to the
/// check pass's.
pub fn check_by_row<R: Row, S: Row<Dofs = R::Dofs>>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> (Vec<SweepNorms>, Vec<SweepNorms>) {
    (each_checked(u, inv_m, springs), each_checked(u, inv_m, rows))
}

/// Each row of `rows` visited by the check pass on its own: its norms, in order.
fn each_checked<R: Row>(u: &mut [R::Dofs], inv_m: &[R::Dofs], rows: &mut [R]) -> Vec<SweepNorms> {
    rows.iter_mut()
        .map(|r| {
            let mut norms = SweepNorms::default();
            r.visit::<false>(u, inv_m, 1.0, &mut norms);
            norms
        })
        .collect()
}

/// One pass of the given kind.
#[inline]
pub fn pass<R: Row, S: Row<Dofs = R::Dofs>>(
    kind: Pass,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> SweepNorms {
    match kind {
        Pass::Forward => sweep(u, inv_m, rows, springs, false),
        Pass::Backward => sweep(u, inv_m, rows, springs, true),
        Pass::Relaxed(omega) => sweep_relaxed(u, inv_m, rows, springs, omega),
        Pass::Check => check(u, inv_m, rows, springs),
    }
}

/// A pass over the rows, springs first; with `UPDATE` false (the check) nothing is
/// written; `omega` ≠ 1 over-relaxes each row's change and projects it on the law.
#[inline(always)]
fn sweep_in<'r, 's, const UPDATE: bool, R: Row + 'r, S: Row<Dofs = R::Dofs> + 's>(
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: impl Iterator<Item = &'r mut R>,
    springs: impl Iterator<Item = &'s mut S>,
    omega: f64,
) -> SweepNorms {
    let mut norms = SweepNorms::default();
    for s in springs {
        s.visit::<UPDATE>(u, inv_m, omega, &mut norms);
    }
    for r in rows {
        r.visit::<UPDATE>(u, inv_m, omega, &mut norms);
    }
    norms
}

/// Runs sweeps until the policy is met.
pub fn solve_nlgs<R: Row, S: Row<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    if rows.is_empty() && springs.is_empty() {
        return NlgsReport { iterations: 0, criterion: 0.0, converged: true };
    }
    iterate(settings, |kind| pass(kind, u, inv_m, rows, springs))
}

/// [`solve_nlgs`], split in two halves at the median abscissa of the mobile
/// bodies' centres (`abscissa(i)` of body `i`) when the problem has at least `settings.split_min_rows`
/// rows ([`super::split`]), the halves swept side by side when `threads ≥ 2`
/// (same numbers as with one); `ws` keeps the buffers from call to call.
#[allow(clippy::too_many_arguments)]
pub fn solve_nlgs_split<R: Row, S: Row<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    ws: &mut SplitWorkspace<R, S>,
    threads: usize,
    abscissa: impl Fn(usize) -> f64,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    if !settings.splits(rows.len() + springs.len()) {
        return solve_nlgs(settings, u, inv_m, rows, springs);
    }
    ws.load(abscissa, u, inv_m, rows, springs);
    let report = ws.run(threads, |sweep| iterate(settings, sweep));
    ws.store(u, rows, springs);
    report
}

/// First guess of the ratio of the check norm to the sweep norm at the same sweep
/// ([`Measure::Check`]); measured 0.60–0.66 on the loaded 536-pentagon pile, taken
/// lower so that the first check comes a little early rather than late.
const FIRST_CHECK_RATIO: f64 = 0.5;

pub(super) fn iterate(settings: &NlgsSettings, mut pass: impl FnMut(Pass) -> SweepNorms) -> NlgsReport {
    let s = settings;
    let checked = s.measure == Measure::Check && !s.policy.over_sweeps();
    let mut tail = (s.policy == Policy::Velocity).then(VelocityTail::default);
    let mut ratio = FIRST_CHECK_RATIO;
    let mut previous_wpp = 0.0;
    let mut report = NlgsReport::default();
    let cap = s.sweep_cap();
    let (mut omega, mut lowest) = (s.relaxation, f64::INFINITY);
    for it in 1..=cap {
        let kind = if s.symmetric && it % 2 == 0 {
            Pass::Backward
        } else if omega != 1.0 {
            Pass::Relaxed(omega)
        } else {
            Pass::Forward
        };
        let norms = pass(kind);
        let (mut value, mut ok) = evaluate(s.policy, s.tolerance, s.max_factor, &norms, previous_wpp);
        previous_wpp = norms.sum_wpp;
        if let Some(tail) = &mut tail {
            value = tail.estimate(value);
            ok = value < s.tolerance;
        }
        // The safeguard of over-relaxation: plain sweeps once the norm rises well above its lowest.
        lowest = lowest.min(value);
        if omega != 1.0 && value > 2.0 * lowest {
            omega = 1.0;
        }
        if checked {
            // The sweep's norm predicts the check's through the last measured ratio;
            // the check runs when the prediction meets the tolerance, and at the cap.
            let due = it >= s.min_iterations && (ratio * value < s.tolerance || it == s.max_iterations || it == cap);
            if due {
                let (check, check_ok) = evaluate(s.policy, s.tolerance, s.max_factor, &pass(Pass::Check), 0.0);
                if value > 0.0 && check.is_finite() {
                    ratio = (check / value).clamp(0.05, 2.0);
                }
                (value, ok) = (check, check_ok);
            } else {
                ok = false;
            }
        }
        report = NlgsReport { iterations: it, criterion: value, converged: ok };
        if ok && it >= s.min_iterations {
            break;
        }
    }
    report
}
