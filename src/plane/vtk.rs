//! VTK snapshots of a 2D system (NSCD [`crate::nscd::System`] or planar MD) for ParaView: its bodies and its
//! contact force network, through the writer of [`crate::io::vtk`] (`.vtp` XML or `.vtk` legacy by the
//! extension; one time step of a `.pvd` is part 0 the bodies, part 1 the contacts: [`write_snapshot`]).
//! Everything is planar: z = 0 everywhere. Forces are the mean forces over the last step (N), for the
//! out-of-plane thickness of the scene.
//!
//! # Bodies file
//!
//! One polygon cell per body (`POLYGONS` / `<Polys>`), in body order, whose
//! points are the body's world vertices: centre of mass `(q[0], q[1])` plus the
//! body-frame vertices rotated by `q[2]`, counter-clockwise. A disc is written as
//! the inscribed polygon of [`DISC_VERTICES`] vertices on its circle, the first
//! at angle `q[2]` (so that the spin shows). A compound body (a rigid union of
//! convex parts) is written as one polygon cell per part, consecutive, in part
//! order; each cell data array has one value per **cell**, the body's value
//! repeated for each of its parts (so `body_id` tells which cells make one body,
//! and the number of cells exceeds the number of bodies when there are
//! compounds). Points are not shared between cells.
//! Cell data:
//!
//! | array      | kind                | unit  | meaning                                     |
//! |------------|---------------------|-------|---------------------------------------------|
//! | `body_id`  | int scalar          | –     | index of the body in the system             |
//! | `fixed`    | int scalar          | –     | 1 for a fixed body, else 0                  |
//! | `velocity` | vector (3)          | m/s   | velocity of the centre of mass, z = 0       |
//! | `spin`     | float scalar        | rad/s | angular velocity, counter-clockwise         |
//! | `radius`   | float scalar        | m     | bounding radius (disc radius, circumradius) |
//!
//! # Contacts file
//!
//! The force network of the last step ([`PlaneSystem::plane_contacts`]): points are
//! the centres of mass of all bodies (point `i` is body `i`), and each contact is
//! one line cell (`LINES` / `<Lines>`) from its candidate's centre of mass to
//! its antagonist's. No point data. Cell data:
//!
//! | array              | kind               | unit | meaning                                      |
//! |--------------------|--------------------|------|----------------------------------------------|
//! | `normal_force`     | float scalar       | N    | `r_n`, ≥ 0 (compression)                     |
//! | `tangential_force` | float scalar       | N    | `r_t`, along `t`                             |
//! | `gap`              | float scalar       | m    | gap at `q_m` (negative: overlap)             |
//! | `force`            | vector (3)         | N    | `r_n n + r_t t` on the candidate, z = 0      |
//! | `normal`           | field, 3 comps     | –    | unit normal `n`, towards the candidate       |
//! | `point`            | field, 3 comps     | m    | contact point at `q_m`, z = 0                |
//! | `candidate`        | int scalar         | –    | body on which `force` acts                   |
//! | `antagonist`       | int scalar         | –    | the other body (it feels `-force`)           |
//!
//! `t` is `n` rotated by +90°; `q_m` is the intermediate configuration of the
//! θ-method at which the contacts were detected. `normal_force` is the active
//! scalar and `force` the active vector (ParaView colours and glyphs by them by
//! default); in the bodies file they are `body_id` and `velocity`. In legacy
//! files `normal` and `point` are the arrays of a `FIELD` block of the cell
//! data; in `.vtp` files all arrays are plain `DataArray`s. A Threshold on
//! `normal_force` and a Tube filter whose radius follows it give the usual
//! force-chain picture; `point` locates the contacts themselves (the line's
//! ends are the centres of mass).
//!

use super::outputs::PlaneSystem;
use crate::error::Result;
use crate::geometry::{perp, rotate, Shape, Vec2};
use crate::io::vtk::{write_poly, Array, CellKind, PolyData, PvdCollection};
use std::path::{Path, PathBuf};

/// Number of vertices of the polygon that stands for a disc in the bodies file.
pub const DISC_VERTICES: usize = 24;

/// Writes the bodies of `sys` to `path`: one polygon cell per body with its world
/// vertices (m) and the cell arrays `body_id`, `fixed`, `velocity` (m/s), `spin`
/// (rad/s) and `radius` (m); see the [module documentation](self). The format
/// follows the extension: `.vtk` legacy, `.vtp` XML.
pub fn write_bodies(path: &Path, sys: &impl PlaneSystem) -> Result<()> {
    let title = format!("ballast 2D bodies, step {}, time {:e} s", sys.plane_step(), sys.plane_time());
    write_poly(path, &bodies_data(sys), &title)
}

/// Writes the contacts of the last step of `sys` to `path`: one line cell per
/// contact, from the candidate's centre of mass to the antagonist's, with the
/// cell arrays `candidate`, `antagonist`, `normal_force` (N), `tangential_force`
/// (N), `gap` (m), `force` (N), `normal` and `point` (m); see the
/// [module documentation](self). The format follows the extension: `.vtk`
/// legacy, `.vtp` XML.
pub fn write_contacts(path: &Path, sys: &impl PlaneSystem) -> Result<()> {
    let title = format!("ballast 2D contacts, step {}, time {:e} s", sys.plane_step(), sys.plane_time());
    write_poly(path, &contacts_data(sys), &title)
}

/// Writes `dir/bodies_SSSSSSSSS.vtp` and `dir/contacts_SSSSSSSSS.vtp` (`S`: the step number, 9 digits or more)
/// for the current state of `sys`, adds them to `pvd` at time `sys.plane_time()` (s) and returns their paths.
/// The `.pvd` itself is written by [`PvdCollection::write`].
///
/// # Errors
/// A failed write, naming the file.
pub fn write_snapshot(pvd: &mut PvdCollection, dir: &Path, sys: &impl PlaneSystem) -> Result<(PathBuf, PathBuf)> {
    let bodies = dir.join(format!("bodies_{:09}.vtp", sys.plane_step()));
    let contacts = dir.join(format!("contacts_{:09}.vtp", sys.plane_step()));
    write_bodies(&bodies, sys)?;
    write_contacts(&contacts, sys)?;
    pvd.push(sys.plane_time(), bodies.clone(), contacts.clone());
    Ok((bodies, contacts))
}

fn bodies_data(sys: &impl PlaneSystem) -> PolyData {
    let b = sys.plane_bodies();
    let mut d = PolyData {
        points: Vec::new(),
        kind: CellKind::Polys,
        connectivity: Vec::new(),
        offsets: Vec::with_capacity(b.len()),
        cell_data: Vec::new(),
        point_data: Vec::new(),
    };
    // Body of each cell: a compound has one cell per part.
    let mut owner: Vec<usize> = Vec::with_capacity(b.len());
    for (i, (info, q)) in b.info.iter().zip(&b.q).enumerate() {
        let centre = Vec2::new(q[0], q[1]);
        let (sin, cos) = q[2].sin_cos();
        let mut cell = |vertices: &mut dyn Iterator<Item = Vec2>| {
            for v in vertices {
                let w = centre + rotate(v, cos, sin);
                d.connectivity.push(d.points.len());
                d.points.push([w.x, w.y, 0.0]);
            }
            d.offsets.push(d.connectivity.len());
            owner.push(i);
        };
        match &info.shape {
            Shape::Polygon(p) => cell(&mut p.vertices.iter().copied()),
            Shape::Disc(r) => cell(&mut (0..DISC_VERTICES).map(|k| {
                let a = std::f64::consts::TAU * k as f64 / DISC_VERTICES as f64;
                Vec2::new(r * a.cos(), r * a.sin())
            })),
            Shape::Compound(c) => c.parts.iter().for_each(|p| cell(&mut p.vertices.iter().copied())),
        }
    }
    d.cell_data = vec![
        Array::int("body_id", owner.iter().map(|&i| i as i64).collect()),
        Array::int("fixed", owner.iter().map(|&i| i64::from(b.info[i].fixed)).collect()),
        Array::vectors("velocity", owner.iter().map(|&i| [b.u[i][0], b.u[i][1], 0.0]).collect()),
        Array::float("spin", owner.iter().map(|&i| b.u[i][2]).collect()),
        Array::float("radius", owner.iter().map(|&i| b.info[i].shape.bounding_radius()).collect()),
    ];
    d
}

fn contacts_data(sys: &impl PlaneSystem) -> PolyData {
    let contacts = sys.plane_contacts();
    let mut connectivity = Vec::with_capacity(2 * contacts.len());
    for c in &contacts {
        connectivity.extend([c.candidate, c.antagonist]);
    }
    let force = |c: &super::ContactInfo| {
        let n = Vec2::new(c.normal[0], c.normal[1]);
        let f = n * c.r_n + perp(n) * c.r_t;
        [f.x, f.y, 0.0]
    };
    PolyData {
        points: sys.plane_bodies().q.iter().map(|q| [q[0], q[1], 0.0]).collect(),
        kind: CellKind::Lines,
        connectivity,
        offsets: (1..=contacts.len()).map(|k| 2 * k).collect(),
        cell_data: vec![
            Array::float("normal_force", contacts.iter().map(|c| c.r_n).collect()),
            Array::float("tangential_force", contacts.iter().map(|c| c.r_t).collect()),
            Array::float("gap", contacts.iter().map(|c| c.gap).collect()),
            Array::vectors("force", contacts.iter().map(force).collect()),
            Array::field3("normal", contacts.iter().map(|c| [c.normal[0], c.normal[1], 0.0]).collect()),
            Array::field3("point", contacts.iter().map(|c| [c.point[0], c.point[1], 0.0]).collect()),
            Array::int("candidate", contacts.iter().map(|c| c.candidate as i64).collect()),
            Array::int("antagonist", contacts.iter().map(|c| c.antagonist as i64).collect()),
        ],
        point_data: Vec::new(),
    }
}
