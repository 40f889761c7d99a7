//! The figures and the errors of an accelerated run, from its folder alone
//! (`settlement.csv`, `jumps.csv`; `ballast figures DIR` and the end of a run):
//!
//! - `settlement_accelerated`: settlement vs cycles, every cycle of the run and
//!   its computed cycles marked (Karrech et al. 2007, Fig. 11 style), with the
//!   full run's curve when a reference folder is given;
//! - `fit_quality`: `g_u` and `f_ξ` (eqs. 13–14) of each jump's window;
//! - with a reference (`--reference DIR`, a full run of the same scene: its
//!   `settlement.csv`, or its `cycles.csv` at the load minimum), `errors.csv`: per
//!   cycle the two settlements and the error on what accrued after the initial
//!   cycles, `|s_acc(N) − s_full(N)| / |s_full(N) − s_full(k_i)|` (the total is
//!   dominated by the first cycles and would hide a wrong extrapolation), the
//!   relative error of the coordination number on the computed cycles, and,
//!   when both folders hold the cycle positions ([`crate::run::positions`]), the
//!   relative configuration error `E_r` of eq. (22) over the translations.

use super::RunFigures;
use crate::error::{Error, Result};
use crate::io::figures::{self, Axes, Series};
use crate::io::layout::{self, SETTLEMENT};
use crate::run::positions::{self, CyclePositions};
use crate::settlement::driver::{JumpRow, SettlementRow};
use crate::settlement::estimate::configuration_error;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of `errors.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorRow {
    /// Cycle.
    pub cycle: u64,
    /// 1 if the accelerated run computed it.
    pub computed: u8,
    /// The accelerated run's settlement (m).
    pub settlement_m: f64,
    /// The reference's (m).
    pub reference_settlement_m: f64,
    /// `|s_acc − s_full| / |s_full − s_full(k_i)|` after the initial cycles (empty before).
    pub accrued_error: Option<f64>,
    /// `|z_acc − z_full| / z_full` on computed cycles with both coordinations.
    pub coordination_error: Option<f64>,
    /// Eq. (22), `‖u_full − u_acc‖ / ‖u_full‖` over every mobile body's
    /// translations since the start of the loading (both runs' cycle positions).
    pub configuration_error: Option<f64>,
}

/// A reference run's settlement and coordination per cycle (index = cycle − 1).
pub fn reference_settlement(dir: &Path) -> Result<Vec<(f64, Option<f64>)>> {
    let s = dir.join(layout::SETTLEMENT);
    if s.is_file() {
        let rows: Vec<SettlementRow> = crate::io::read_csv(&s)?;
        return Ok(rows.iter().map(|r| (r.settlement_m, r.coordination)).collect());
    }
    let c = dir.join(layout::CYCLES);
    if c.is_file() {
        let cols = crate::io::table::read_columns(&c, &["settlement_at_min_load_m"]).map_err(|e| {
            Error::Scene(format!(
                "reference: {e} (an MD run's cycles.csv has no settlement: give the folder of a full run made \
                 through the driver, --accelerate K_I,N+1,1)"
            ))
        })?;
        return Ok(cols[0].iter().map(|&v| (v, None)).collect());
    }
    Err(Error::Scene(format!(
        "reference: '{}' has neither {SETTLEMENT} nor cycles.csv (the folder of a full run of the same scene)",
        dir.display()
    )))
}

/// The rows of `errors.csv` of `rows` (an accelerated run with `initial_cycles`
/// initial cycles) against `reference`, over the cycles both have.
pub fn errors(rows: &[SettlementRow], reference: &[(f64, Option<f64>)], initial_cycles: u64) -> Vec<ErrorRow> {
    let base = match initial_cycles {
        0 => Some(0.0),
        k => reference.get(k as usize - 1).map(|r| r.0),
    };
    rows.iter()
        .filter_map(|r| {
            let (full, z) = *reference.get((r.cycle as usize).checked_sub(1)?)?;
            let accrued = base.filter(|_| r.cycle > initial_cycles).map(|b| full - b);
            Some(ErrorRow {
                cycle: r.cycle,
                computed: r.computed,
                settlement_m: r.settlement_m,
                reference_settlement_m: full,
                accrued_error: accrued.filter(|a| *a != 0.0).map(|a| (r.settlement_m - full).abs() / a.abs()),
                coordination_error: match (r.coordination, z) {
                    (Some(a), Some(b)) if b != 0.0 => Some((a - b).abs() / b.abs()),
                    _ => None,
                },
                configuration_error: None,
            })
        })
        .collect()
}

/// Eq. (22) per cycle of `rows` (their `configuration_error`) from the cycle
/// positions of the accelerated run and of the reference, over the cycles both have.
///
/// # Errors
/// [`Error::Scene`] if the two runs do not follow the same bodies from the same start.
pub fn add_configuration_errors(rows: &mut [ErrorRow], run: &CyclePositions, reference: &CyclePositions) -> Result<()> {
    let (a, b) = (&run.reference, &reference.reference);
    let same = a.bodies == b.bodies && a.dof == b.dof && a.q.iter().zip(&b.q).all(|(x, y)| (x - y).abs() <= 1e-12);
    if !same {
        return Err(Error::Scene(
            "reference: the two runs' cycle positions do not follow the same bodies from the same start".into(),
        ));
    }
    // The translations: 2 of (x, y, θ) in 2D, 3 of (x, y, z, r) in 3D.
    let dim = if a.dof == 3 { 2 } else { 3 };
    for r in rows {
        let at = r.cycle as usize - 1;
        if let (Some(c), Some(f)) = (run.cycles.get(at), reference.cycles.get(at)) {
            r.configuration_error = Some(configuration_error(a, f, c, dim)).filter(|e| e.is_finite());
        }
    }
    Ok(())
}

/// Draws the figures of the accelerated run in `dir` (module doc), with the full
/// run in `reference` if given (then also writes `errors.csv`, measured after the
/// run's `initial_cycles` of its `summary.json`).
///
/// # Errors
/// [`Error::Scene`] if `dir` has no `settlement.csv` or the reference no
/// settlement; [`Error::Io`] naming a file; without the `figures` feature, its error.
pub fn draw(dir: &Path, reference: Option<&Path>) -> Result<RunFigures> {
    figures::require()?;
    let path = dir.join(layout::SETTLEMENT);
    if !path.is_file() {
        return Err(Error::Scene(format!("'{}' has no {SETTLEMENT}", dir.display())));
    }
    let rows: Vec<SettlementRow> = crate::io::read_csv(&path)?;
    let mut out = RunFigures::default();
    let mm = |v: f64| 1e3 * v;
    let mut series = vec![
        Series {
            label: "accelerated".into(),
            points: rows.iter().map(|r| (r.cycle as f64, mm(r.settlement_m))).collect(),
            ..Series::default()
        },
        Series {
            label: "computed cycles".into(),
            points: rows.iter().filter(|r| r.computed == 1).map(|r| (r.cycle as f64, mm(r.settlement_m))).collect(),
            points_only: true,
            ..Series::default()
        },
    ];
    if let Some(reference) = reference {
        let full = reference_settlement(reference)?;
        series.insert(
            0,
            Series {
                label: "full run".into(),
                points: full.iter().enumerate().map(|(k, r)| ((k + 1) as f64, mm(r.0))).collect(),
                ..Series::default()
            },
        );
        let summary: crate::settlement::AccelerationSummary = crate::io::read_json(&dir.join(layout::SUMMARY))?;
        let mut table = errors(&rows, &full, summary.initial_cycles);
        if dir.join(layout::CYCLE_DISPLACEMENTS).is_file() && reference.join(layout::CYCLE_DISPLACEMENTS).is_file() {
            add_configuration_errors(&mut table, &positions::read(dir)?, &positions::read(reference)?)?;
        }
        crate::io::table::write_all(&dir.join(layout::ERRORS), &table)?;
    }
    let stem = dir.join("settlement_accelerated");
    let axes = Axes {
        title: "Settlement, accelerated run".into(),
        x_label: "cycles".into(),
        y_label: "settlement (mm)".into(),
        ..Axes::default()
    };
    figures::line_chart(&stem, &axes, &series)?;
    out.wrote(stem);
    let jumps_path = dir.join(layout::JUMPS);
    let jumps: Vec<JumpRow> = if jumps_path.is_file() { crate::io::read_csv(&jumps_path)? } else { Vec::new() };
    if jumps.is_empty() {
        out.skip("fit_quality", "no jump");
    } else {
        let stem = dir.join("fit_quality");
        let pick = |f: fn(&JumpRow) -> f64| jumps.iter().map(|j| (j.from_cycle as f64, f(j))).collect();
        let series = [
            Series { label: "g_u (eq. 13)".into(), points: pick(|j| j.g_u_m), ..Series::default() },
            Series { label: "f_xi (eq. 14)".into(), points: pick(|j| j.f_xi_m), ..Series::default() },
        ];
        let axes = Axes {
            title: "Fit of each window".into(),
            x_label: "last computed cycle of the window".into(),
            y_label: "m".into(),
            log_y: true,
            ..Axes::default()
        };
        figures::line_chart(&stem, &axes, &series)?;
        out.wrote(stem);
    }
    Ok(out)
}
