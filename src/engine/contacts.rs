//! `contacts.csv`: the contact list at the end of a run (or, after a
//! divergence, of its last good step), one row per contact, written by the run
//! loop for both engines with a [`crate::io::table::TableWriter`] and read back with
//! the same row type ([`read`]).
//!
//! Columns ([`ContactRow`]), units in the names:
//! - `kind`: `pair` (two bodies that both move), `wall` (a body against
//!   something that does not move with the dynamics: an MD wall, fixed or servo,
//!   or a fixed NSCD body) or `image` (an MD sphere against a symmetry image);
//! - `a`, `a_name`: the body the force acts on (for `wall` and `image` always the
//!   moving sphere or body); `b`, `b_name`: the other one: a body index, the
//!   index and name of an MD wall (among the walls), or for `image` the real
//!   sphere whose mirror image it is;
//! - `point_x_m`, `point_y_m`, `point_z_m`: the contact point (m);
//! - `normal_x`, `normal_y`, `normal_z`: the unit normal, from `b` towards `a`;
//! - `gap_m`: the gap (m), negative when the bodies overlap;
//! - `f_n_N`: the normal force on `a` along the normal (N), positive when the
//!   bodies push each other apart;
//! - `f_t_x_N`, `f_t_y_N`, `f_t_z_N`: the tangential force on `a` (N).
//!
//! The `z` columns are empty in 2D (NSCD) runs. NSCD forces are the mean forces
//! over the last step, the impulses `r_n`, `r_t` divided by the time step, at the
//! geometry of the step's middle configuration `q_m` (the tangent is the normal
//! turned by +90°, [`crate::nscd::ContactInfo`]); an NSCD contact is listed per
//! contact point, a pair of polygons may have two. MD forces are those the last
//! force evaluation applied ([`crate::md::MdSystem::contact_forces`]; a contact
//! with a symmetry image is listed once for each real sphere, the force on it).

use crate::error::Result;
use crate::io::table::TableWriter;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// What a contact is between.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ContactKind {
    /// Two bodies that both move.
    Pair,
    /// A body and a wall (MD) or a fixed body (NSCD).
    Wall,
    /// An MD sphere and a symmetry image of a sphere.
    Image,
}

/// One row of `contacts.csv` (see the module documentation for the columns).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactRow {
    /// Column `kind`: pair, wall or image.
    pub kind: ContactKind,
    /// The body the force acts on.
    pub a: usize,
    /// Name of body `a`.
    pub a_name: String,
    /// The other body, wall or imaged sphere.
    pub b: usize,
    /// Name of `b` (a wall's or fixed body's name for a `wall` row).
    pub b_name: String,
    /// Contact point, x (m).
    pub point_x_m: f64,
    /// Contact point, y (m).
    pub point_y_m: f64,
    /// Contact point, z (m); empty in 2D.
    pub point_z_m: Option<f64>,
    /// Unit normal from `b` towards `a`, x component.
    pub normal_x: f64,
    /// Unit normal, y component.
    pub normal_y: f64,
    /// Unit normal, z component; empty in 2D.
    pub normal_z: Option<f64>,
    /// Gap (m), negative when overlapping.
    pub gap_m: f64,
    /// Normal force on `a` (N), positive when pushing the bodies apart.
    #[serde(rename = "f_n_N")]
    pub f_n: f64,
    /// Tangential force on `a`, x component (N).
    #[serde(rename = "f_t_x_N")]
    pub f_t_x: f64,
    /// Tangential force on `a`, y component (N).
    #[serde(rename = "f_t_y_N")]
    pub f_t_y: f64,
    /// Tangential force on `a`, z component (N); empty in 2D.
    #[serde(rename = "f_t_z_N")]
    pub f_t_z: Option<f64>,
}

/// The columns of [`ContactRow`].
pub const CONTACT_COLUMNS: [&str; 16] = [
    "kind",
    "a",
    "a_name",
    "b",
    "b_name",
    "point_x_m",
    "point_y_m",
    "point_z_m",
    "normal_x",
    "normal_y",
    "normal_z",
    "gap_m",
    "f_n_N",
    "f_t_x_N",
    "f_t_y_N",
    "f_t_z_N",
];

impl ContactRow {
    /// The contact point (m), `z` = 0 in 2D.
    pub fn point(&self) -> [f64; 3] {
        [self.point_x_m, self.point_y_m, self.point_z_m.unwrap_or(0.0)]
    }

    /// The unit normal, `z` = 0 in 2D.
    pub fn normal(&self) -> [f64; 3] {
        [self.normal_x, self.normal_y, self.normal_z.unwrap_or(0.0)]
    }

    /// The whole force on `a` (N), normal and tangential, `z` = 0 in 2D.
    pub fn force(&self) -> [f64; 3] {
        let n = self.normal();
        let t = [self.f_t_x, self.f_t_y, self.f_t_z.unwrap_or(0.0)];
        std::array::from_fn(|k| self.f_n * n[k] + t[k])
    }
}

/// Writes `rows` to `path` (created or truncated), header first.
pub fn write(path: &Path, rows: &[ContactRow]) -> Result<()> {
    let mut table = TableWriter::create(path, &CONTACT_COLUMNS)?;
    for r in rows {
        table.write(r)?;
    }
    table.finish()
}

/// Reads a `contacts.csv`; the error names the file and the line.
pub fn read(path: &Path) -> Result<Vec<ContactRow>> {
    Ok(crate::io::table::read(path)?.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The header is the row type's fields; 2D rows (no `z`) and names with
    /// commas read back equal.
    #[test]
    fn rows_read_back() {
        let dir = std::env::temp_dir().join(format!("ballast-contacts-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("contacts.csv");
        let rows = vec![
            ContactRow {
                kind: ContactKind::Wall,
                a: 1,
                a_name: "block, top".into(),
                b: 0,
                b_name: "floor".into(),
                point_x_m: 0.05,
                point_y_m: 1e-9,
                point_z_m: None,
                normal_x: 0.0,
                normal_y: 1.0,
                normal_z: None,
                gap_m: -2e-7,
                f_n: 132.4,
                f_t_x: -0.1 + 0.2,
                f_t_y: 0.0,
                f_t_z: None,
            },
            ContactRow {
                kind: ContactKind::Image,
                a: 3,
                a_name: "s3".into(),
                b: 3,
                b_name: "s3".into(),
                point_x_m: 0.0,
                point_y_m: 0.1,
                point_z_m: Some(0.2),
                normal_x: 1.0,
                normal_y: 0.0,
                normal_z: Some(0.0),
                gap_m: -1e-6,
                f_n: 3.0,
                f_t_x: 0.0,
                f_t_y: 0.5,
                f_t_z: Some(-0.25),
            },
        ];
        write(&path, &rows).unwrap();
        let (header, back): (Vec<String>, Vec<ContactRow>) = crate::io::table::read(&path).unwrap();
        assert_eq!(header, CONTACT_COLUMNS);
        // The constant is the row type's own header.
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(&rows[0]).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        assert_eq!(text.lines().next().unwrap(), CONTACT_COLUMNS.join(","));
        assert_eq!(back, rows);
        assert_eq!(rows[1].force(), [3.0, 0.5, -0.25]);
        write(&path, &[]).unwrap();
        assert_eq!(read(&path).unwrap(), vec![]);
        let _ = std::fs::remove_dir_all(&dir);
    }
}
