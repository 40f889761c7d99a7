//! The figures of one finished 3D NSCD run, drawn from its output folder alone ([`nscd3d_figures`], through
//! [`super::draw_run_figures`]), each as `<stem>.png` + `<stem>.svg`:
//!
//! - `energies`: the kinetic energy vs time (`series.csv`; logarithmic axis, zeros left out);
//! - `overlaps`: the mean and largest overlap vs time;
//! - `settlement_cycles`: the followed body's settlement at the end of each loading cycle and its mean over the
//!   cycle (`cycles.csv`; skipped, said so, for a run without cycles) — the track section's settlement curve;
//! - `vertical_cut`: the sample cut by the vertical plane `y = ȳ` (`ȳ` the mean y of the mobile bodies'
//!   centroids), every body the plane crosses drawn as its cross-section (the convex polygon where the plane
//!   meets the polyhedron's edges, a sphere's circle), fixed ones dark; over it the force chains of the bodies
//!   whose centroid lies within one mean body radius of the plane (`contacts.csv`: a line between the centroids
//!   of a pair, or from a centroid to its contact with a wall, its width proportional to the pair's normal
//!   force), projected on the x–z plane — the 3D twin of the 2D figure of the sample with its force chains.
//!
//! The shapes come from the run's copy of its scene (`scene.toml`) or from `initial_state.json` (a system built
//! in code), placed at the positions and orientations of `final.json`.

use super::{force_lines, max_abs, read_contacts, read_final, require, RunFigures};
use crate::engine::FinalState;
use crate::error::{Error, Result};
use crate::geometry::{Pose, Solid, Vec3};
use crate::io::figures::{self, Axes, Series};
use crate::io::layout;
use crate::nscd::d3::rows::{read_cycles, read_series};
use crate::nscd::d3::system::System3;
use crate::scene::SceneFile;
use nalgebra::{Quaternion, UnitQuaternion};
use std::path::Path;

/// Sides of the polygon a sphere's cross-section is drawn as.
const CIRCLE_SIDES: usize = 32;

/// Draws the 3D NSCD figures of the run in `dir` (module doc).
///
/// # Errors
/// As [`super::draw_run_figures`].
pub fn nscd3d_figures(dir: &Path) -> Result<RunFigures> {
    let fin = read_final(dir)?;
    let rows = read_series(&require(dir, layout::SERIES)?)?;
    let mut out = RunFigures::default();
    let chart = |stem: &str, axes: Axes, series: &[Series]| -> Result<_> {
        let path = dir.join(stem);
        figures::line_chart(&path, &axes, series)?;
        Ok(path)
    };
    let line = |label: &str, points: Vec<(f64, f64)>| Series {
        label: label.into(),
        points,
        band: vec![],
        thin: false,
        points_only: false,
    };
    let time_axes = |title: &str, y: &str, log_y: bool| Axes {
        title: title.into(),
        x_label: "time (s)".into(),
        y_label: y.into(),
        log_x: false,
        log_y,
    };
    let kinetic = line("kinetic", rows.iter().map(|r| (r.time_s, r.kinetic_energy_j)).collect());
    out.wrote(chart("energies", time_axes("Kinetic energy", "energy (J)", true), &[kinetic])?);
    let (s, unit) = figures::si_scale(max_abs(rows.iter().map(|r| r.max_overlap_m)).max(1e-12), "m");
    let overlaps = [
        line("mean", rows.iter().map(|r| (r.time_s, s * r.mean_overlap_m)).collect()),
        line("max", rows.iter().map(|r| (r.time_s, s * r.max_overlap_m)).collect()),
    ];
    out.wrote(chart("overlaps", time_axes("Overlaps", &format!("overlap ({unit})"), false), &overlaps)?);

    let cycles = dir.join(layout::CYCLES);
    if cycles.is_file() {
        let rows = read_cycles(&cycles)?;
        let m = max_abs(rows.iter().flat_map(|r| [r.settlement_m, r.settlement_mean_m])).max(1e-12);
        let (s, unit) = figures::si_scale(m, "m");
        let series = [
            line("at the cycle's end", rows.iter().map(|r| (r.cycle as f64, s * r.settlement_m)).collect()),
            line("mean over the cycle", rows.iter().map(|r| (r.cycle as f64, s * r.settlement_mean_m)).collect()),
        ];
        let axes = Axes {
            title: "Settlement of the followed body per loading cycle".into(),
            x_label: "cycles".into(),
            y_label: format!("settlement ({unit})"),
            ..Axes::default()
        };
        out.wrote(chart("settlement_cycles", axes, &series)?);
    } else {
        out.skip("settlement_cycles", "no cycles.csv (the run had no loading cycles)");
    }
    vertical_cut(dir, &fin, &mut out)?;
    Ok(out)
}

/// The system of the run in `dir` (its bodies' shapes) at the poses of `fin`.
fn final_system(dir: &Path, fin: &FinalState) -> Result<System3> {
    #[derive(serde::Deserialize)]
    struct Input {
        system: System3,
    }
    let (scene, initial) = (dir.join(layout::SCENE), dir.join(layout::INITIAL_STATE));
    let (mut sys, source) = if scene.is_file() {
        (crate::scene::Scene3::load(&scene)?.build()?, scene)
    } else if initial.is_file() {
        (crate::io::read_json::<Input>(&initial)?.system, initial)
    } else {
        return Err(Error::Scene(format!(
            "'{}' is not the folder of a finished run: it has neither {} nor {} (the shapes of the bodies)",
            dir.display(),
            layout::SCENE,
            layout::INITIAL_STATE
        )));
    };
    if fin.bodies.len() != sys.bodies.len() {
        return Err(Error::Scene(format!(
            "{} has {} bodies, {} has {}",
            dir.join(layout::FINAL).display(),
            fin.bodies.len(),
            source.display(),
            sys.bodies.len()
        )));
    }
    for (pose, b) in sys.bodies.pose.iter_mut().zip(&fin.bodies) {
        if let (&[x, y, z], Some([w, i, j, k])) = (&b.position[..], b.orientation) {
            *pose = Pose {
                position: Vec3::new(x, y, z),
                rotation: UnitQuaternion::new_normalize(Quaternion::new(w, i, j, k)),
            };
        }
    }
    Ok(sys)
}

/// The cross-section `(x, z)` of `solid` at `pose` by the plane `y = c`, counter-clockwise; empty when the plane
/// misses it (or for a half-space, which the figure does not draw).
pub fn cross_section(solid: &Solid, pose: &Pose, c: f64) -> Vec<[f64; 2]> {
    match solid {
        Solid::Sphere { radius } => {
            let d = pose.position.y - c;
            if d.abs() >= *radius {
                return Vec::new();
            }
            let r = (radius * radius - d * d).sqrt();
            let a = |k: usize| std::f64::consts::TAU * k as f64 / CIRCLE_SIDES as f64;
            (0..CIRCLE_SIDES).map(|k| [pose.position.x + r * a(k).cos(), pose.position.z + r * a(k).sin()]).collect()
        }
        Solid::HalfSpace => Vec::new(),
        Solid::Polyhedron(p) => {
            let world: Vec<Vec3> = p.vertices.iter().map(|v| pose.position + pose.rotation * v).collect();
            let mut points: Vec<[f64; 2]> = Vec::new();
            for &[a, b] in &p.edges {
                let (va, vb) = (world[a as usize], world[b as usize]);
                let (da, db) = (va.y - c, vb.y - c);
                if (da < 0.0) != (db < 0.0) {
                    let t = da / (da - db);
                    let q = va + (vb - va) * t;
                    points.push([q.x, q.z]);
                }
            }
            if points.len() < 3 {
                return Vec::new();
            }
            let n = points.len() as f64;
            let centre = points.iter().fold([0.0, 0.0], |s, p| [s[0] + p[0] / n, s[1] + p[1] / n]);
            points.sort_by(|p, q| {
                let angle = |v: &[f64; 2]| (v[1] - centre[1]).atan2(v[0] - centre[0]);
                angle(p).total_cmp(&angle(q))
            });
            points
        }
    }
}

/// `vertical_cut` (module doc).
fn vertical_cut(dir: &Path, fin: &FinalState, out: &mut RunFigures) -> Result<()> {
    let Some(rows) = read_contacts(dir)? else {
        out.skip("vertical_cut", "no contacts.csv (a run of an older version)");
        return Ok(());
    };
    let sys = final_system(dir, fin)?;
    let b = &sys.bodies;
    let mobile: Vec<usize> = (0..b.len()).filter(|&i| b.is_mobile(i)).collect();
    if mobile.is_empty() {
        out.skip("vertical_cut", "no mobile body");
        return Ok(());
    }
    let n = mobile.len() as f64;
    let c = mobile.iter().map(|&i| b.pose[i].position.y).sum::<f64>() / n;
    let size = |i: usize| (3.0 * b.info[i].solid.mass_properties().0 / (4.0 * std::f64::consts::PI)).cbrt();
    let slab = mobile.iter().map(|&i| size(i)).sum::<f64>() / n;
    let (mut polygons, mut fixed) = (Vec::new(), Vec::new());
    for i in 0..b.len() {
        let section = cross_section(&b.info[i].solid, &b.pose[i], c);
        if !section.is_empty() {
            polygons.push(section);
            fixed.push(!b.is_mobile(i));
        }
    }
    let centre = |i: usize| {
        let p = b.pose.get(i)?.position;
        ((p.y - c).abs() <= slab).then_some([p.x, p.y, p.z])
    };
    let lines = force_lines(&rows, centre, |p| [p[0], p[2]]);
    let title = format!(
        "Vertical cut at y = {c:.4} m, t = {:.4} s (forces of the bodies within {slab:.3} m; width ∝ normal force)",
        fin.time
    );
    let stem = dir.join("vertical_cut");
    figures::force_chains_with_axes(&stem, &title, ["x (m)", "z (m)"], &polygons, &fixed, &lines)?;
    out.wrote(stem);
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Polyhedron;

    fn area(p: &[[f64; 2]]) -> f64 {
        0.5 * (0..p.len())
            .map(|k| {
                let (a, b) = (p[k], p[(k + 1) % p.len()]);
                a[0] * b[1] - a[1] * b[0]
            })
            .sum::<f64>()
    }

    /// A cube of side `a` turned 45° about z and cut through its centre by `y = c`: a rectangle `a√2 × a`
    /// (counter-clockwise, positive area); off-centre by `d`, `(a√2 − 2d) × a`; missed beyond `a/√2`. A sphere of
    /// radius r cut at distance d: the circle of radius √(r² − d²) (a 32-gon's area, `½ n r² sin(2π/n)`). The
    /// shoelace sums products of coordinates near 3 m: round-off ~1e-15 per term, 1e-13 on 32 terms.
    #[test]
    fn cross_sections_have_the_areas_of_their_closed_forms() {
        let a = 0.1;
        let cube = Solid::Polyhedron(Polyhedron::cuboid([a / 2.0; 3]).unwrap());
        let pose = Pose {
            position: Vec3::new(1.0, 2.0, 3.0),
            rotation: UnitQuaternion::from_axis_angle(&Vec3::z_axis(), std::f64::consts::FRAC_PI_4),
        };
        let s2 = std::f64::consts::SQRT_2;
        assert!((area(&cross_section(&cube, &pose, 2.0)) - a * s2 * a).abs() < 1e-13);
        let d = 0.01;
        assert!((area(&cross_section(&cube, &pose, 2.0 + d)) - (a * s2 - 2.0 * d) * a).abs() < 1e-13);
        assert!(cross_section(&cube, &pose, 2.0 + a / s2 + 1e-9).is_empty());
        let (r, d) = (0.05, 0.03);
        let circle = cross_section(&Solid::Sphere { radius: r }, &pose, 2.0 + d);
        let rc2 = r * r - d * d;
        let n = CIRCLE_SIDES as f64;
        assert!((area(&circle) - 0.5 * n * rc2 * (std::f64::consts::TAU / n).sin()).abs() < 1e-13);
    }
}
