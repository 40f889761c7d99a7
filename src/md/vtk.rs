//! VTK snapshots of an MD system for ParaView, through the writer of [`crate::io::vtk`] (`.vtp` XML or `.vtk`
//! legacy by the extension; one time step of a `.pvd` is part 0 the spheres: [`write_snapshot`]).
//!
//! # Spheres file
//!
//! [`write_spheres`]: one point per sphere at its centre (m), in sphere order, each
//! a vertex cell (`VERTICES` / `<Verts>`), so ParaView shows them as points; a
//! Glyph filter with a sphere source, scaled by `radius` (scale factor 2: the
//! glyph is a unit-diameter sphere), draws the spheres at their size. No cell
//! data. Point data:
//!
//! | array      | kind           | unit  | meaning                         |
//! |------------|----------------|-------|---------------------------------|
//! | `radius`   | float scalar   | m     | radius                          |
//! | `id`       | int scalar     | –     | index of the sphere             |
//! | `material` | int scalar     | –     | index of its material           |
//! | `velocity` | vector (3)     | m/s   | velocity of the centre          |
//! | `spin`     | field, 3 comps | rad/s | angular velocity                |
//!
//! `radius` is the active scalar and `velocity` the active vector.

use super::MdSystem;
use crate::error::Result;
use crate::io::vtk::{write_poly, Array, CellKind, PolyData, PvdCollection, PvdPart};
use std::path::{Path, PathBuf};

/// Writes the spheres of `sys` to `path`: one vertex cell per sphere at its centre
/// (m) with the point arrays `radius` (m), `id`, `material`, `velocity` (m/s) and
/// `spin` (rad/s); see the [module documentation](self). The format follows the
/// extension: `.vtk` legacy, `.vtp` XML.
pub fn write_spheres(path: &Path, sys: &MdSystem) -> Result<()> {
    let title = format!("ballast MD spheres, step {}, time {:e} s", sys.step, sys.time);
    write_poly(path, &spheres_data(sys), &title)
}

/// Writes `dir/spheres_SSSSSSSSS.vtp` (`S`: the step number, 9 digits or more) for the current state of `sys`,
/// adds it to `pvd` as part `spheres` at time `sys.time` (s) and returns its path. The `.pvd` itself is
/// written by [`PvdCollection::write`].
///
/// # Errors
/// A failed write, naming the file.
pub fn write_snapshot(pvd: &mut PvdCollection, dir: &Path, sys: &MdSystem) -> Result<PathBuf> {
    let file = dir.join(format!("spheres_{:09}.vtp", sys.step));
    write_spheres(&file, sys)?;
    pvd.push_parts(sys.time, vec![PvdPart { name: "spheres".into(), file: file.clone() }]);
    Ok(file)
}

fn spheres_data(sys: &MdSystem) -> PolyData {
    let p = &sys.particles;
    let n = p.len();
    let v3 = |v: &crate::md::V3| [v[0], v[1], v[2]];
    PolyData {
        points: p.x.iter().map(v3).collect(),
        kind: CellKind::Verts,
        connectivity: (0..n).collect(),
        offsets: (1..=n).collect(),
        cell_data: Vec::new(),
        point_data: vec![
            Array::float("radius", p.r.clone()),
            Array::int("id", (0..n as i64).collect()),
            Array::int("material", p.material.iter().map(|&m| i64::from(m)).collect()),
            Array::vectors("velocity", p.v.iter().map(v3).collect()),
            Array::field3("spin", p.w.iter().map(v3).collect()),
        ],
    }
}
