//! The figures of one run, drawn from its output folder and its final state
//! (`ballast run --figures`, the Saussine studies, the example):
//!
//! - `settlement.{png,svg}`: the followed body's settlement vs cycles, mean over
//!   each cycle and at the load minimum (from `cycles.csv`; Saussine et al. 2006,
//!   Figs. 6, 11);
//! - `interpenetration.{png,svg}`: mean and max overlap vs time (from
//!   `series.csv`; Figs. 3–4);
//! - `force_chains.{png,svg}`: the final state with the normal forces of its last
//!   step (Figs. 8–10);
//! - `displacements.{png,svg}`: the grains' displacements from the end of the
//!   first cycle to the end of the run (Figs. 8–9), when that state is known.

use super::figures::{self, Arrow, Axes, Series};
use crate::error::Result;
use crate::nscd::System;
use std::path::{Path, PathBuf};

/// Series of a settlement curve in millimetres, from `cycles.csv` rows.
pub fn settlement_series(rows: &[super::cycles::NscdCycleRow], label: &str) -> [Series; 2] {
    let pick = |f: fn(&super::cycles::NscdCycleRow) -> f64| rows.iter().map(|r| (r.cycle as f64, 1e3 * f(r))).collect();
    let sep = if label.is_empty() { "" } else { ", " };
    [
        Series {
            label: format!("{label}{sep}mean over the cycle"),
            points: pick(|r| r.settlement_mean_m),
            band: vec![],
        },
        Series {
            label: format!("{label}{sep}at the load minimum"),
            points: pick(|r| r.settlement_at_min_load_m),
            band: vec![],
        },
    ]
}

/// One arrow per non-fixed body of `sys`, from its centre in `q0` (m) to its centre now.
pub fn displacement_arrows(q0: &[[f64; 3]], sys: &System) -> Vec<Arrow> {
    q0.iter()
        .zip(&sys.bodies.q)
        .zip(&sys.bodies.info)
        .filter(|(_, info)| !info.fixed)
        .map(|((a, b), _)| Arrow { from: [a[0], a[1]], displacement: [b[0] - a[0], b[1] - a[1]] })
        .collect()
}

/// Writes the figures of the run in `dir` (see the module doc); `first_cycle_q` are
/// the positions at the end of the first cycle, if known. Returns the stems written.
pub fn write_run_figures(dir: &Path, sys: &System, first_cycle_q: Option<&[[f64; 3]]>) -> Result<Vec<PathBuf>> {
    let mut written = Vec::new();
    let cycles_path = dir.join("cycles.csv");
    if cycles_path.exists() {
        let rows = super::cycles::read_nscd(&cycles_path)?;
        let stem = dir.join("settlement");
        let axes = Axes {
            title: "Settlement of the sleeper".into(),
            x_label: "cycles".into(),
            y_label: "settlement (mm)".into(),
            ..Axes::default()
        };
        figures::line_chart(&stem, &axes, &settlement_series(&rows, ""))?;
        written.push(stem);
    }
    let series_path = dir.join("series.csv");
    if series_path.exists() {
        let rows = super::series::read_nscd(&series_path)?;
        let pick = |f: fn(&super::series::NscdSeriesRow) -> f64| rows.iter().map(|r| (r.time_s, 1e6 * f(r))).collect();
        let stem = dir.join("interpenetration");
        let axes = Axes {
            title: "Interpenetration".into(),
            x_label: "time (s)".into(),
            y_label: "overlap (µm)".into(),
            ..Axes::default()
        };
        let curves = [
            Series { label: "mean over the active contacts".into(), points: pick(|r| r.mean_overlap_m), band: vec![] },
            Series { label: "max".into(), points: pick(|r| r.max_overlap_m), band: vec![] },
        ];
        figures::line_chart(&stem, &axes, &curves)?;
        written.push(stem);
    }
    let (polygons, fixed) = figures::polygons_of(sys);
    let stem = dir.join("force_chains");
    let title = format!("Force chains at t = {:.3} s (line width ∝ normal force)", sys.time);
    figures::force_chains(&stem, &title, &polygons, &fixed, &figures::force_lines_of(sys))?;
    written.push(stem);
    if let Some(q0) = first_cycle_q.filter(|q| q.len() == sys.bodies.len()) {
        let arrows = displacement_arrows(q0, sys);
        // Arrows of the largest displacement drawn a tenth of the sample's width.
        let xs = sys.bodies.q.iter().map(|q| q[0]);
        let width = xs.clone().fold(f64::NEG_INFINITY, f64::max) - xs.fold(f64::INFINITY, f64::min);
        let umax = arrows.iter().map(|a| a.displacement[0].hypot(a.displacement[1])).fold(0.0, f64::max);
        let scale = if umax > 0.0 && width > 0.0 { 0.1 * width / umax } else { 1.0 };
        let stem = dir.join("displacements");
        let title = format!("Grain displacements from the end of cycle 1 to t = {:.3} s", sys.time);
        figures::displacement_field(&stem, &title, &polygons, &fixed, &arrows, scale)?;
        written.push(stem);
    }
    Ok(written)
}
