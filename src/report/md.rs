//! The figures of one finished MD run, drawn from its output folder alone
//! ([`md_figures`], through [`super::draw_run_figures`]), each as
//! `<stem>.png` + `<stem>.svg`:
//!
//! - `energies`: kinetic, elastic and potential energy vs time (from
//!   `series.csv`; logarithmic axis, zeros left out);
//! - `coordination`: the coordination number `(2 N_c + N_w) / N` vs time;
//! - `overlaps`: mean and largest overlap vs time, in the length unit that makes
//!   the numbers plain;
//! - `wall_forces`: the normal force every wall is pressed with vs time (if the
//!   scene has walls);
//! - `plate_settlement`: the displacement of every servo wall (a loading plate)
//!   along its normal into the sample vs time, and `plate_settlement_cycles`
//!   the same at each cycle end (from `cycles.csv`) when the run had cycles;
//! - `side_view`: the spheres of `final.json` projected on the x–z plane with
//!   the contact forces of `contacts.csv` as lines whose width is proportional
//!   to the normal force: between the centres of two spheres, from a sphere's
//!   centre to its contact point with a wall or a symmetry image; the walls seen
//!   edge-on (planes and discs whose normal lies in the x–z plane, cylinders
//!   whose axis does) as dark strips on their outer side, at their final place
//!   (their shapes from the copy of the scene, `scene.toml`, or
//!   `initial_state.json`; none without either).

use super::{force_lines, max_abs, read_contacts, read_final, require, RunFigures};
use crate::error::{Error, Result};
use crate::io::figures::{self, Axes, Series};
use crate::io::layout;
use crate::md::rows::{MdSeriesRow, MD_SERIES_COLUMNS};
use crate::md::{MdSystem, Shape, Wall, V3};
use crate::scene::SceneFile;
use std::path::Path;

/// Sides of the polygon a sphere is drawn as.
const CIRCLE_SIDES: usize = 32;

/// Draws the MD figures of the run in `dir` (see the module documentation).
///
/// # Errors
/// As [`super::draw_run_figures`]; [`Error::Scene`] if `final.json`
/// holds bodies without a 3D position and a radius.
pub fn md_figures(dir: &Path) -> Result<RunFigures> {
    let fin = read_final(dir)?;
    let series_path = require(dir, layout::SERIES)?;
    let (header, rows) = crate::md::rows::read_series(&series_path)?;
    let mut out = RunFigures::default();
    let curve = |label: &str, f: &dyn Fn(&MdSeriesRow) -> f64| Series {
        label: label.into(),
        points: rows.iter().map(|r| (r.time_s, f(r))).collect(),
        band: vec![],
        thin: false,
        points_only: false,
    };
    let chart = |stem: &str, title: &str, y_label: &str, log_y: bool, series: &[Series]| -> Result<_> {
        let axes =
            Axes { title: title.into(), x_label: "time (s)".into(), y_label: y_label.into(), log_x: false, log_y };
        let path = dir.join(stem);
        figures::line_chart(&path, &axes, series)?;
        Ok(path)
    };
    let energies = [
        curve("kinetic", &|r| r.kinetic_energy_j),
        curve("elastic (contacts)", &|r| r.elastic_energy_j),
        curve("potential (gravitational + elastic)", &|r| r.potential_energy_j),
    ];
    out.wrote(chart("energies", "Energies", "energy (J)", true, &energies)?);
    let coordination = [curve("", &|r| r.coordination)];
    out.wrote(chart("coordination", "Coordination number", "contacts per sphere", false, &coordination)?);
    let m = max_abs(rows.iter().map(|r| r.max_overlap_m)).max(1e-12);
    let (s, unit) = figures::si_scale(m, "m");
    let overlaps = [curve("mean", &|r| s * r.mean_overlap_m), curve("max", &|r| s * r.max_overlap_m)];
    out.wrote(chart("overlaps", "Overlaps", &format!("overlap ({unit})"), false, &overlaps)?);

    // The wall columns after the fixed ones: `<wall>_force_N` for every wall,
    // then `<wall>_position_m` for every servo wall.
    let extra = header.get(MD_SERIES_COLUMNS.len()..).unwrap_or_default();
    let column = |k: usize, suffix: &str| extra[k].strip_suffix(suffix).map(String::from);
    let forces: Vec<(usize, String)> = (0..extra.len()).filter_map(|k| Some((k, column(k, "_force_N")?))).collect();
    let servos: Vec<(usize, String)> = (0..extra.len()).filter_map(|k| Some((k, column(k, "_position_m")?))).collect();
    let wall_curves = |cols: &[(usize, String)], scale: f64| -> Vec<Series> {
        cols.iter()
            .map(|(k, name)| Series {
                label: name.clone(),
                points: rows.iter().map(|r| (r.time_s, scale * r.walls.get(*k).copied().unwrap_or(f64::NAN))).collect(),
                band: vec![],
                thin: false,
                points_only: false,
            })
            .collect()
    };
    let wall_max = |cols: &[(usize, String)]| {
        max_abs(rows.iter().flat_map(|r| cols.iter().filter_map(|c| r.walls.get(c.0).copied())))
    };
    if forces.is_empty() {
        out.skip("wall_forces", "the scene has no walls");
    } else {
        let (s, unit) = figures::si_scale(wall_max(&forces).max(1e-12), "N");
        let title = "Normal force on the walls";
        out.wrote(chart("wall_forces", title, &format!("force ({unit})"), false, &wall_curves(&forces, s))?);
    }
    if servos.is_empty() {
        out.skip("plate_settlement", "the scene has no servo wall");
    } else {
        let (s, unit) = figures::si_scale(wall_max(&servos).max(1e-12), "m");
        let title = "Settlement of the servo walls (displacement into the sample)";
        let y = format!("displacement ({unit})");
        out.wrote(chart("plate_settlement", title, &y, false, &wall_curves(&servos, s))?);
        plate_cycles(dir, &servos, &mut out)?;
    }
    side_view(dir, &fin, &mut out)?;
    Ok(out)
}

/// `plate_settlement_cycles`: the servo walls' displacements at each cycle end
/// (the trailing columns of `cycles.csv`, in the order of `servos`).
fn plate_cycles(dir: &Path, servos: &[(usize, String)], out: &mut RunFigures) -> Result<()> {
    let path = dir.join(layout::CYCLES);
    if !path.is_file() {
        out.skip("plate_settlement_cycles", "no cycles.csv (the run had no loading cycles)");
        return Ok(());
    }
    let rows = crate::md::rows::read_cycles(&path)?;
    let (s, unit) = figures::si_scale(max_abs(rows.iter().flat_map(|r| r.walls.iter().copied())).max(1e-12), "m");
    let series: Vec<Series> = servos
        .iter()
        .enumerate()
        .map(|(k, (_, name))| Series {
            label: name.clone(),
            points: rows.iter().map(|r| (r.cycle as f64, s * r.walls.get(k).copied().unwrap_or(f64::NAN))).collect(),
            band: vec![],
            thin: false,
            points_only: false,
        })
        .collect();
    let axes = Axes {
        title: "Settlement of the servo walls at the end of each cycle".into(),
        x_label: "cycles".into(),
        y_label: format!("displacement ({unit})"),
        ..Axes::default()
    };
    let stem = dir.join("plate_settlement_cycles");
    figures::line_chart(&stem, &axes, &series)?;
    out.wrote(stem);
    Ok(())
}

/// `side_view`: the spheres on the x–z plane with the contact forces.
fn side_view(dir: &Path, fin: &crate::engine::FinalState, out: &mut RunFigures) -> Result<()> {
    let Some(rows) = read_contacts(dir)? else {
        out.skip("side_view", "no contacts.csv (a run of an older version)");
        return Ok(());
    };
    let mut centres = Vec::with_capacity(fin.bodies.len());
    let mut circles = Vec::with_capacity(fin.bodies.len());
    for (i, b) in fin.bodies.iter().enumerate() {
        let (Some(r), &[x, y, z]) = (b.radius, &b.position[..]) else {
            return Err(Error::Scene(format!(
                "{}: body {i} is not a sphere (a 3D position and a radius)",
                dir.join(layout::FINAL).display()
            )));
        };
        centres.push([x, y, z]);
        let circle = (0..CIRCLE_SIDES).map(|k| {
            let a = 2.0 * std::f64::consts::PI * k as f64 / CIRCLE_SIDES as f64;
            [x + r * a.cos(), z + r * a.sin()]
        });
        circles.push(circle.collect::<Vec<_>>());
    }
    let lines = force_lines(&rows, |i| centres.get(i).copied(), |p| [p[0], p[2]]);
    let title = format!("Side view (x–z) at t = {:.4} s (line width ∝ normal force)", fin.time);
    let stem = dir.join("side_view");
    let mut polygons = wall_strips(dir, fin, &circles)?;
    let mut fixed = vec![true; polygons.len()];
    fixed.resize(polygons.len() + circles.len(), false);
    polygons.extend(circles);
    figures::force_chains_with_axes(&stem, &title, ["x (m)", "z (m)"], &polygons, &fixed, &lines)?;
    out.wrote(stem);
    Ok(())
}

/// The walls of the run in `dir` (from `scene.toml` or `initial_state.json`),
/// `None` if it has neither.
fn walls_of(dir: &Path) -> Result<Option<Vec<Wall>>> {
    #[derive(serde::Deserialize)]
    struct Input {
        system: MdSystem,
    }
    let (scene, initial) = (dir.join(layout::SCENE), dir.join(layout::INITIAL_STATE));
    if scene.is_file() {
        Ok(Some(crate::scene::MdScene::load(&scene)?.build()?.walls))
    } else if initial.is_file() {
        Ok(Some(crate::io::read_json::<Input>(&initial)?.system.walls))
    } else {
        Ok(None)
    }
}

/// The walls seen edge-on in the x–z plane as strips (m, in x–z) on their outer
/// side, as long as the spheres' extent (`circles`) and 2 % of it thick, at their
/// displacement in `fin`.
fn wall_strips(dir: &Path, fin: &crate::engine::FinalState, circles: &[Vec<[f64; 2]>]) -> Result<Vec<Vec<[f64; 2]>>> {
    let Some(walls) = walls_of(dir)? else { return Ok(Vec::new()) };
    let points = circles.iter().flatten();
    let (lo, hi) = points.fold(([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]), |(lo, hi), p| {
        ([lo[0].min(p[0]), lo[1].min(p[1])], [hi[0].max(p[0]), hi[1].max(p[1])])
    });
    if lo[0] > hi[0] {
        return Ok(Vec::new());
    }
    let centre = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0];
    let size = (hi[0] - lo[0]).hypot(hi[1] - lo[1]);
    let thick = 0.02 * size;
    // A strip along the line through `p` (x–z) with unit direction `t`, from
    // `a` to `b` along it, on the side `out` (unit).
    let strip = |p: [f64; 2], t: [f64; 2], a: f64, b: f64, out: [f64; 2]| {
        let at = |s: f64, d: f64| [p[0] + s * t[0] + d * out[0], p[1] + s * t[1] + d * out[1]];
        vec![at(a, 0.0), at(b, 0.0), at(b, thick), at(a, thick)]
    };
    let in_view = |v: V3| v.y.abs() < 1e-9 * v.norm();
    let mut out = Vec::new();
    for (k, w) in walls.iter().enumerate() {
        let s = fin.walls.get(k).map_or(0.0, |w| w.displacement);
        match w.shape {
            Shape::Plane { point, normal } | Shape::Disc { point, normal, .. } if in_view(normal) => {
                let p = point + normal * s;
                let n = [normal.x, normal.z];
                let t = [-n[1], n[0]];
                let (a, b) = match w.shape {
                    Shape::Disc { radius, .. } => (-radius, radius),
                    _ => {
                        // The spheres' centre projected on the line, ± half their extent.
                        let c = (centre[0] - p.x) * t[0] + (centre[1] - p.z) * t[1];
                        (c - 0.55 * size, c + 0.55 * size)
                    }
                };
                out.push(strip([p.x, p.z], t, a, b, [-n[0], -n[1]]));
            }
            Shape::Cylinder { axis_point, axis, radius } if in_view(axis) => {
                let t = [axis.x, axis.z];
                let side = [t[1], -t[0]];
                let c = (centre[0] - axis_point.x) * t[0] + (centre[1] - axis_point.z) * t[1];
                for sign in [1.0, -1.0] {
                    let out_dir = [sign * side[0], sign * side[1]];
                    let p = [axis_point.x + radius * out_dir[0], axis_point.z + radius * out_dir[1]];
                    out.push(strip(p, t, c - 0.55 * size, c + 0.55 * size, out_dir));
                }
            }
            _ => {}
        }
    }
    Ok(out)
}
