//! VTK snapshots of a 3D NSCD system ([`super::system::System3`]) for ParaView: its bodies and its contact
//! forces, through the writer of [`crate::io::vtk`] (`.vtp` XML or `.vtk` legacy by the extension; one time step
//! of a `.pvd` is part 0 the bodies, part 1 the contacts, as for the 2D engines: [`write_snapshot`]).
//!
//! # Bodies file
//!
//! Polygon cells (`POLYGONS` / `<Polys>`), body after body in body order, each body's points its own (not
//! shared with another body's):
//!
//! - a polyhedron: one polygon per face, its vertices counter-clockwise seen from outside, at their world
//!   positions (`x + R v`);
//! - a sphere: the polyhedron of [`SPHERE_RINGS`] × [`SPHERE_SEGMENTS`] faces on its surface (triangles at the
//!   poles, quadrilaterals between; poles on the body's third principal axis), turning with the body so that
//!   its spin shows: [`SPHERE_FACES`] polygons;
//! - a half-space (a floor, a wall): one square in its plane, centred at the projection of the mobile bodies'
//!   mean centroid, its half side 1.5 × the largest in-plane distance from there to a mobile body's bounding
//!   sphere (1 m without mobile bodies).
//!
//! Point data:
//!
//! | array      | kind           | unit  | meaning                                                      |
//! |------------|----------------|-------|--------------------------------------------------------------|
//! | `velocity` | vector (3)     | m/s   | velocity of the material point, `v + ω × (p − x)` (world)    |
//! | `spin`     | field, 3 comps | rad/s | the body's angular velocity (world)                          |
//!
//! Cell data: `body_id` (int, the body's index), `fixed` (int, 1 for a fixed body). `body_id` is the active
//! scalar, `velocity` the active vector.
//!
//! # Contacts file
//!
//! One line cell (`LINES` / `<Lines>`) per contact point of the last step, from the point `p` (at the
//! intermediate configuration `q_m`, where it was detected) to `p + s r_n n`: along the normal `n` (from the
//! antagonist towards the candidate), its length proportional to the normal force `r_n` (N, the mean over the
//! step). The scale `s` (m/N) is fixed by the model so that the snapshots of a run compare: a force equal to
//! the mean weight of the mobile bodies draws a line as long as their smallest bounding radius (without
//! gravity: the largest force of the snapshot does). No point data. Cell data:
//!
//! | array              | kind           | unit | meaning                                              |
//! |--------------------|----------------|------|------------------------------------------------------|
//! | `normal_force`     | float scalar   | N    | `r_n`, ≥ 0 (compression)                             |
//! | `tangential_force` | float scalar   | N    | magnitude of the friction force                      |
//! | `gap`              | float scalar   | m    | gap at `q_m` (negative: overlap)                     |
//! | `force`            | vector (3)     | N    | the whole force on the candidate (world)             |
//! | `normal`           | field, 3 comps | –    | unit normal, towards the candidate                   |
//! | `candidate`        | int scalar     | –    | body on which `force` acts                           |
//! | `antagonist`       | int scalar     | –    | the other body (it feels `−force`)                   |
//!
//! The scale is in the file's title (an XML comment: `force scale … m/N`).

use super::system::System3;
use crate::error::Result;
use crate::geometry::{Pose, Solid, Vec3};
use crate::io::vtk::{write_poly, Array, CellKind, PolyData, PvdCollection};
use std::path::{Path, PathBuf};

/// Latitude bands of the polyhedron that stands for a sphere.
pub const SPHERE_RINGS: usize = 8;
/// Longitude segments of the polyhedron that stands for a sphere.
pub const SPHERE_SEGMENTS: usize = 12;
/// Polygons of a sphere in the bodies file.
pub const SPHERE_FACES: usize = SPHERE_RINGS * SPHERE_SEGMENTS;

/// The number of polygon cells of body `solid` in the bodies file.
pub fn polygons_of(solid: &Solid) -> usize {
    match solid {
        Solid::Polyhedron(p) => p.faces.len(),
        Solid::Sphere { .. } => SPHERE_FACES,
        Solid::HalfSpace => 1,
    }
}

/// Writes the bodies of `sys` to `path` (module doc); `.vtk` legacy or `.vtp` XML by the extension.
///
/// # Errors
/// An unknown extension or a failed write, naming the file.
pub fn write_bodies(path: &Path, sys: &System3) -> Result<()> {
    let title = format!("ballast 3D NSCD bodies, step {}, time {:e} s", sys.steps, sys.time);
    write_poly(path, &bodies_data(sys), &title)
}

/// Writes the contacts of the last step of `sys` to `path` (module doc); `.vtk` legacy or `.vtp` XML by the
/// extension.
///
/// # Errors
/// An unknown extension or a failed write, naming the file.
pub fn write_contacts(path: &Path, sys: &System3) -> Result<()> {
    let (data, scale) = contacts_data(sys);
    let title =
        format!("ballast 3D NSCD contacts, step {}, time {:e} s, force scale {scale:e} m/N", sys.steps, sys.time);
    write_poly(path, &data, &title)
}

/// Writes `dir/bodies_SSSSSSSSS.vtp` and `dir/contacts_SSSSSSSSS.vtp` (`S`: the step number, 9 digits or more)
/// for the current state of `sys`, adds them to `pvd` at time `sys.time` (s) and returns their paths. The
/// `.pvd` itself is written by [`PvdCollection::write`].
///
/// # Errors
/// A failed write, naming the file.
pub fn write_snapshot(pvd: &mut PvdCollection, dir: &Path, sys: &System3) -> Result<(PathBuf, PathBuf)> {
    let bodies = dir.join(format!("bodies_{:09}.vtp", sys.steps));
    let contacts = dir.join(format!("contacts_{:09}.vtp", sys.steps));
    write_bodies(&bodies, sys)?;
    write_contacts(&contacts, sys)?;
    pvd.push(sys.time, bodies.clone(), contacts.clone());
    Ok((bodies, contacts))
}

/// The points (body frame) and faces of the polyhedron standing for a sphere of radius `r`.
fn sphere_mesh(r: f64) -> (Vec<Vec3>, Vec<Vec<usize>>) {
    let (rings, segments) = (SPHERE_RINGS, SPHERE_SEGMENTS);
    let mut points = vec![Vec3::new(0.0, 0.0, -r)];
    for k in 1..rings {
        let polar = std::f64::consts::PI * k as f64 / rings as f64;
        for j in 0..segments {
            let azimuth = std::f64::consts::TAU * j as f64 / segments as f64;
            points.push(r * Vec3::new(polar.sin() * azimuth.cos(), polar.sin() * azimuth.sin(), -polar.cos()));
        }
    }
    points.push(Vec3::new(0.0, 0.0, r));
    let top = points.len() - 1;
    let at = |k: usize, j: usize| 1 + (k - 1) * segments + j % segments;
    let mut faces = Vec::with_capacity(SPHERE_FACES);
    // Counter-clockwise seen from outside: around the bottom pole seen from below, then upwards.
    for j in 0..segments {
        faces.push(vec![0, at(1, j + 1), at(1, j)]);
    }
    for k in 1..rings - 1 {
        for j in 0..segments {
            faces.push(vec![at(k, j), at(k, j + 1), at(k + 1, j + 1), at(k + 1, j)]);
        }
    }
    for j in 0..segments {
        faces.push(vec![top, at(rings - 1, j), at(rings - 1, j + 1)]);
    }
    (points, faces)
}

/// The square standing for the half-space of pose `pose` (module doc), in its body frame.
fn half_space_square(sys: &System3, pose: &Pose) -> (Vec<Vec3>, Vec<Vec<usize>>) {
    let b = &sys.bodies;
    let mobile: Vec<usize> = (0..b.len()).filter(|&i| b.is_mobile(i)).collect();
    // Centroids in the plane's frame, projected on it.
    let local = |i: usize| {
        let x = pose.rotation.inverse_transform_vector(&(b.pose[i].position - pose.position));
        Vec3::new(x.x, x.y, 0.0)
    };
    let (centre, half) = if mobile.is_empty() {
        (Vec3::zeros(), 1.0)
    } else {
        let centre = mobile.iter().map(|&i| local(i)).sum::<Vec3>() / mobile.len() as f64;
        let reach = mobile.iter().map(|&i| (local(i) - centre).norm() + b.info[i].solid.radius()).fold(0.0, f64::max);
        (centre, 1.5 * reach)
    };
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    (corners.iter().map(|&(s, t)| centre + Vec3::new(s * half, t * half, 0.0)).collect(), vec![vec![0, 1, 2, 3]])
}

fn bodies_data(sys: &System3) -> PolyData {
    let b = &sys.bodies;
    let mut d = PolyData {
        points: Vec::new(),
        kind: CellKind::Polys,
        connectivity: Vec::new(),
        offsets: Vec::new(),
        cell_data: Vec::new(),
        point_data: Vec::new(),
    };
    let (mut owner, mut velocity, mut spin) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..b.len() {
        let pose = &b.pose[i];
        let (points, faces) = match &b.info[i].solid {
            Solid::Polyhedron(p) => {
                (p.vertices.clone(), p.faces.iter().map(|f| f.vertices.iter().map(|&v| v as usize).collect()).collect())
            }
            Solid::Sphere { radius } => sphere_mesh(*radius),
            Solid::HalfSpace => half_space_square(sys, pose),
        };
        let first = d.points.len();
        let w = b.world_velocity(i).1;
        for v in &points {
            let p = pose.point(v);
            d.points.push(p.into());
            velocity.push(b.point_velocity(i, &p).into());
            spin.push(w.into());
        }
        for f in faces {
            d.connectivity.extend(f.iter().map(|&v| first + v));
            d.offsets.push(d.connectivity.len());
            owner.push(i);
        }
    }
    d.cell_data = vec![
        Array::int("body_id", owner.iter().map(|&i| i as i64).collect()),
        Array::int("fixed", owner.iter().map(|&i| i64::from(b.info[i].fixed)).collect()),
    ];
    d.point_data = vec![Array::vectors("velocity", velocity), Array::field3("spin", spin)];
    d
}

/// The force scale of the contacts file (m/N; module doc): the smallest bounding radius of the mobile bodies
/// over their mean weight, or over the largest normal force without gravity; 0 when neither is defined.
pub fn force_scale(sys: &System3) -> f64 {
    let b = &sys.bodies;
    let mobile: Vec<usize> = (0..b.len()).filter(|&i| b.is_mobile(i)).collect();
    let length = mobile.iter().map(|&i| b.info[i].solid.radius()).fold(f64::INFINITY, f64::min);
    let weight =
        mobile.iter().map(|&i| b.info[i].mass).sum::<f64>() / mobile.len().max(1) as f64 * sys.params.gravity.norm();
    let force = if weight > 0.0 { weight } else { sys.contact_forces().map(|c| c.r_n).fold(0.0, f64::max) };
    let s = length / force;
    if s.is_finite() {
        s
    } else {
        0.0
    }
}

fn contacts_data(sys: &System3) -> (PolyData, f64) {
    let scale = force_scale(sys);
    let contacts: Vec<_> = sys.contact_forces().collect();
    let mut points = Vec::with_capacity(2 * contacts.len());
    for c in &contacts {
        points.push(c.point.into());
        points.push((c.point + c.normal * (scale * c.r_n)).into());
    }
    let tangential = |c: &super::system::ContactForce3| (c.force - c.normal * c.r_n).norm();
    let data = PolyData {
        points,
        kind: CellKind::Lines,
        connectivity: (0..2 * contacts.len()).collect(),
        offsets: (1..=contacts.len()).map(|k| 2 * k).collect(),
        cell_data: vec![
            Array::float("normal_force", contacts.iter().map(|c| c.r_n).collect()),
            Array::float("tangential_force", contacts.iter().map(tangential).collect()),
            Array::float("gap", contacts.iter().map(|c| c.gap).collect()),
            Array::vectors("force", contacts.iter().map(|c| c.force.into()).collect()),
            Array::field3("normal", contacts.iter().map(|c| c.normal.into()).collect()),
            Array::int("candidate", contacts.iter().map(|c| i64::from(c.candidate)).collect()),
            Array::int("antagonist", contacts.iter().map(|c| i64::from(c.antagonist)).collect()),
        ],
        point_data: Vec::new(),
    };
    (data, scale)
}
