//! The figures of a finished run of a 2D engine (NSCD, or planar MD, which writes the same files), drawn from
//! its folder ([`nscd_figures`], through [`super::draw_run_figures`]), as `<stem>.png` + `<stem>.svg`:
//!
//! - `settlement`: the followed body's settlement vs cycles, mean over each
//!   cycle and at the load minimum (from `cycles.csv`; Saussine et al. 2006,
//!   Figs. 6, 11);
//! - `interpenetration`: mean and max overlap vs time (from `series.csv`;
//!   Figs. 3–4), in the length unit that makes the numbers plain;
//! - `force_chains`: the final state (the shapes from the copy of the scene,
//!   `scene.toml`, or `initial_state.json` for a system built in code; the
//!   positions from `final.json`) with the normal forces of the last step (from
//!   `contacts.csv`; Figs. 8–10);
//! - `displacements`: the grains' displacements from the end of the first cycle
//!   to the end of the run (Figs. 8–9), when that state is known (the positions
//!   files of `output.cycles.positions`, or the run loop's own record).

use super::{force_lines, max_abs, read_contacts, read_final, require, RunFigures};
use crate::engine::FinalState;
use crate::error::Result;
use crate::io::figures::{self, Arrow, Axes, ForceLine, Series};
use crate::io::layout;
use crate::nscd::System;
use crate::scene::SceneFile;
use std::path::Path;

/// Series of a settlement curve from `cycles.csv` rows, multiplied by `scale`
/// (1e3 for millimetres, or from [`figures::si_scale`]).
pub fn settlement_series(rows: &[crate::plane::rows::PlaneCycleRow], label: &str, scale: f64) -> [Series; 2] {
    let pick = |f: fn(&crate::plane::rows::PlaneCycleRow) -> f64| {
        rows.iter().map(|r| (r.cycle as f64, scale * f(r))).collect()
    };
    let sep = if label.is_empty() { "" } else { ", " };
    [
        Series {
            label: format!("{label}{sep}mean over the cycle"),
            points: pick(|r| r.settlement_mean_m),
            band: vec![],
            thin: false,
            points_only: false,
        },
        Series {
            label: format!("{label}{sep}at the load minimum"),
            points: pick(|r| r.settlement_at_min_load_m),
            band: vec![],
            thin: false,
            points_only: false,
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

/// The NSCD system of the run in `dir` at its end: the bodies of `scene.toml`
/// (or of `initial_state.json`) moved to their positions in `fin`.
fn nscd_final_system(dir: &Path, fin: &FinalState) -> Result<System> {
    let build = |path: &Path| crate::scene::Scene::load(path)?.build();
    let mut sys = super::input_system(dir, fin, build, |s: &System| s.bodies.len())?;
    for (q, b) in sys.bodies.q.iter_mut().zip(&fin.bodies) {
        if let [x, y] = b.position[..] {
            *q = [x, y, b.angle.unwrap_or(q[2])];
        }
    }
    sys.time = fin.time;
    Ok(sys)
}

/// The positions `(x, y, θ)` of every body at the end of the first cycle from
/// the positions files of the run in `dir`, if it has them (the other bodies,
/// fixed, where `sys` has them).
fn first_cycle_from_files(dir: &Path, sys: &System) -> Result<Option<Vec<[f64; 3]>>> {
    if !dir.join(layout::CYCLE_DISPLACEMENTS).is_file() {
        return Ok(None);
    }
    let positions = crate::run::positions::read(dir)?;
    let Some(first) = positions.cycles.first().filter(|c| c.dof == 3) else { return Ok(None) };
    let mut q = sys.bodies.q.clone();
    for (k, &i) in first.bodies.iter().enumerate() {
        if let Some(qi) = q.get_mut(i) {
            qi.copy_from_slice(first.body(k));
        }
    }
    Ok(Some(q))
}

/// Draws the NSCD figures of the run in `dir` (see the module documentation);
/// `first_cycle_q` are the positions of every body at the end of the first
/// cycle if the caller knows them (else they are read from the positions files,
/// if any).
///
/// # Errors
/// As [`super::draw_run_figures`].
pub fn nscd_figures(dir: &Path, first_cycle_q: Option<&[[f64; 3]]>) -> Result<RunFigures> {
    let fin = read_final(dir)?;
    let series_path = require(dir, layout::SERIES)?;
    let mut out = RunFigures::default();
    let cycles_path = dir.join(layout::CYCLES);
    if cycles_path.is_file() {
        let rows = crate::plane::rows::read_cycles(&cycles_path)?;
        let m = max_abs(rows.iter().flat_map(|r| [r.settlement_mean_m, r.settlement_at_min_load_m]));
        let (scale, unit) = figures::si_scale(m.max(1e-6), "m");
        let stem = dir.join("settlement");
        let axes = Axes {
            title: "Settlement of the sleeper".into(),
            x_label: "cycles".into(),
            y_label: format!("settlement ({unit})"),
            ..Axes::default()
        };
        figures::line_chart(&stem, &axes, &settlement_series(&rows, "", scale))?;
        out.wrote(stem);
    } else {
        out.skip("settlement", "no cycles.csv (the run had no loading cycles)");
    }
    let rows = crate::plane::rows::read_series(&series_path)?;
    // A run without overlaps (or contacts) still gets an axis in µm.
    let (scale, unit) = figures::si_scale(max_abs(rows.iter().map(|r| r.max_overlap_m)).max(1e-12), "m");
    let pick =
        |f: fn(&crate::plane::rows::PlaneSeriesRow) -> f64| rows.iter().map(|r| (r.time_s, scale * f(r))).collect();
    let stem = dir.join("interpenetration");
    let axes = Axes {
        title: "Interpenetration".into(),
        x_label: "time (s)".into(),
        y_label: format!("overlap ({unit})"),
        ..Axes::default()
    };
    let curves = [
        Series {
            label: "mean over the active contacts".into(),
            points: pick(|r| r.mean_overlap_m),
            band: vec![],
            thin: false,
            points_only: false,
        },
        Series {
            label: "max".into(),
            points: pick(|r| r.max_overlap_m),
            band: vec![],
            thin: false,
            points_only: false,
        },
    ];
    figures::line_chart(&stem, &axes, &curves)?;
    out.wrote(stem);
    let sys = nscd_final_system(dir, &fin)?;
    let (polygons, fixed) = polygons_of(&sys);
    match read_contacts(dir)? {
        Some(rows) => {
            let q = &sys.bodies.q;
            let lines = force_lines(&rows, |i| q.get(i).map(|q| [q[0], q[1], 0.0]), |p| [p[0], p[1]]);
            let stem = dir.join("force_chains");
            let title = format!("Force chains at t = {:.3} s (line width ∝ normal force)", fin.time);
            figures::force_chains(&stem, &title, &polygons, &fixed, &lines)?;
            out.wrote(stem);
        }
        None => out.skip("force_chains", "no contacts.csv (a run of an older version)"),
    }
    let from_files;
    let first = match first_cycle_q {
        Some(q) => Some(q),
        None => {
            from_files = first_cycle_from_files(dir, &sys)?;
            from_files.as_deref()
        }
    };
    match first.filter(|q| q.len() == sys.bodies.len()) {
        Some(q0) => {
            let arrows = displacement_arrows(q0, &sys);
            // Arrows of the largest displacement drawn a tenth of the sample's width.
            let xs = sys.bodies.q.iter().map(|q| q[0]);
            let width = xs.clone().fold(f64::NEG_INFINITY, f64::max) - xs.fold(f64::INFINITY, f64::min);
            let umax = arrows.iter().map(|a| a.displacement[0].hypot(a.displacement[1])).fold(0.0, f64::max);
            let scale = if umax > 0.0 && width > 0.0 { 0.1 * width / umax } else { 1.0 };
            let stem = dir.join("displacements");
            let title = format!("Grain displacements from the end of cycle 1 to t = {:.3} s", fin.time);
            figures::displacement_field(&stem, &title, &polygons, &fixed, &arrows, scale)?;
            out.wrote(stem);
        }
        None => out.skip(
            "displacements",
            "the positions at the end of the first cycle are not known (no cycle ended, or no \
             output.cycles.positions)",
        ),
    }
    Ok(out)
}

/// World vertices (m) of the bodies of `sys` and whether each is fixed: one
/// polygon per body (a disc as a 32-gon), except a compound, which gives one per
/// part (so the lists follow the bodies' order but not their indices).
pub fn polygons_of(sys: &System) -> (Vec<Vec<[f64; 2]>>, Vec<bool>) {
    let (mut polygons, mut fixed) = (Vec::new(), Vec::new());
    for (i, info) in sys.bodies.info.iter().enumerate() {
        for part in crate::nscd::measure::world_parts(sys, i) {
            polygons.push(part);
            fixed.push(info.fixed);
        }
    }
    (polygons, fixed)
}

/// Force chain segments of the last step of `sys` ([`force_lines`] of its
/// contact list): between the centres of two moving bodies, from a body's
/// centre to its contact points with a fixed one.
pub fn force_lines_of(sys: &System) -> Vec<ForceLine> {
    let rows = crate::engine::Engine::contact_rows(sys);
    let q = &sys.bodies.q;
    force_lines(&rows, |i| q.get(i).map(|q| [q[0], q[1], 0.0]), |p| [p[0], p[1]])
}
