//! The landing of a jump as a sweeping process: the bodies carried from the
//! computed configuration to the extrapolated one in stages, each stage
//! relaxed before the next (Moreau's catching-up algorithm for a sweeping
//! process, applied to the extrapolated moves).
//!
//! Karrech et al. (2007, §4, Fig. 10) relax the extrapolated configuration once.
//! After a long jump its overlaps reach the size of the thinnest bodies (8.6 to
//! 10.3 mm on the reference Saussine sample at jumps of 2 650 cycles, against
//! sublayer pads 10 mm thick), and a relaxation that starts from such overlaps
//! can resolve them through a body instead of out of it: the detector sees the
//! configuration only where it has arrived, so a grain whose extrapolated
//! centre is already below the top of a pad is pushed on through. Measured on
//! the reference sample (seed 1, jump 24, `docs/settlement-driver.md`,
//! "Landings in stages"): a grain wedged in the 1 mm gap between two pads was
//! extrapolated 5.5 mm down while the pads' fits lifted them 1.4 and 3.5 mm;
//! the single relaxation pushed one pad 13.7 mm down, past the anchor of its
//! spring (a spring whose length passes through zero turns over and holds the
//! pad at its mirror position below the anchor), and the grain fell through the
//! hole ten cycles later.
//!
//! In stages each body moves by `(q̂ − q₀)/m` per stage (`q₀` the computed
//! configuration, `q̂` the extrapolated one, `m` stages) from where the last
//! stage's relaxation left it, and every stage is relaxed to the same
//! tolerance, so no stage starts from an overlap deeper than one stage's move:
//! a contact is met while it is shallow, and resolved along its true normal.
//! The number of stages makes the largest move of a point of a body in one
//! stage (its translation plus its size times its rotation) at most
//! `relax_stage` (default [`RELAX_STAGE`]) times the smallest body's size; an
//! infinite `relax_stage` is the paper's single relaxation.

use crate::engine::{Configuration, Engine};
use crate::engine::{RelaxReport, RelaxSettings};
use crate::error::Result;

/// The default `relax_stage`: a stage moves a point of a body by at most a
/// quarter of the smallest body's size (on the Saussine sample 1.1 mm, a
/// quarter of the smallest pentagon's inradius and a ninth of a pad's
/// thickness, so that no stage's overlap can reach across a body).
pub const RELAX_STAGE: f64 = 0.25;

/// The most stages of one landing (a jump that asks for more is relaxed in this
/// many: a bound on the cost, not a correctness limit).
pub const MAX_STAGES: u64 = 1000;

/// The stages of a landing from `from` to `to` (the same bodies): the largest
/// move of a point of a body — its translation (the first `dim` coordinates)
/// plus its size (`sizes`, m, one per body) times its rotation (the other
/// coordinates, rad) — divided by `stage` times the smallest positive size,
/// rounded up; at least 1, at most [`MAX_STAGES`]; 1 for an infinite `stage`.
pub fn stages(from: &Configuration, to: &Configuration, sizes: &[f64], dim: usize, stage: f64) -> u64 {
    let smallest = sizes.iter().copied().filter(|s| *s > 0.0).fold(f64::INFINITY, f64::min);
    if !(stage.is_finite() && smallest.is_finite()) {
        return 1;
    }
    let norm = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (y - x) * (y - x)).sum::<f64>().sqrt();
    let farthest = (0..from.len().min(to.len()))
        .map(|k| {
            let (a, b) = (from.body(k), to.body(k));
            norm(&a[..dim], &b[..dim]) + sizes.get(k).copied().unwrap_or(0.0) * norm(&a[dim..], &b[dim..])
        })
        .fold(0.0, f64::max);
    let m = (farthest / (stage * smallest)).ceil();
    if m.is_nan() {
        1
    } else {
        (m as u64).clamp(1, MAX_STAGES)
    }
}

/// Carries `sys` from the configuration `from` to `to` (the same bodies; `sys`
/// is at `from`) in `stages` stages, the boundaries from `boundaries.0` to
/// `boundaries.1` alongside (both empty without boundaries), each stage written
/// back ([`Engine::set_configuration`]) and relaxed with `settings`
/// ([`Engine::relax`]); stops at the first stage that does not converge. With
/// one stage it is the single relaxation of `to`. The report sums the stages'
/// iterations and evaluations; `max_overlap_before` is the deepest overlap a
/// stage started from; `max_overlap_after`, `functional`, `converged` and
/// `reason` are the last stage's; `largest_move` is the largest distance of a
/// coordinate from `to` (m or rad).
///
/// # Errors
/// The engine's, from writing a stage back or relaxing it.
pub fn relax_along<E: Engine>(
    sys: &mut E,
    from: &Configuration,
    to: &Configuration,
    boundaries: (&[f64], &[f64]),
    settings: &RelaxSettings,
    stages: u64,
) -> Result<RelaxReport> {
    let m = stages.max(1);
    let mut at = from.clone();
    let mut total: Option<RelaxReport> = None;
    for k in 1..=m {
        if m == 1 {
            at.q.copy_from_slice(&to.q);
        } else {
            at.q.iter_mut().zip(from.q.iter().zip(&to.q)).for_each(|(q, (a, b))| *q += (b - a) / m as f64);
        }
        if k == m {
            sys.set_boundaries(boundaries.1)?;
        } else {
            let s = k as f64 / m as f64;
            let b: Vec<f64> = boundaries.0.iter().zip(boundaries.1).map(|(a, b)| a + s * (b - a)).collect();
            sys.set_boundaries(&b)?;
        }
        sys.set_configuration(&at)?;
        let r = sys.relax(settings)?;
        at = sys.configuration_of(&from.bodies);
        let converged = r.converged;
        total = Some(match total {
            None => r,
            Some(t) => RelaxReport {
                iterations: t.iterations + r.iterations,
                evaluations: t.evaluations + r.evaluations,
                max_overlap_before: t.max_overlap_before.max(r.max_overlap_before),
                ..r
            },
        });
        if !converged {
            break;
        }
    }
    let mut report = total.expect("at least one stage");
    report.largest_move = at.q.iter().zip(&to.q).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok(report)
}
