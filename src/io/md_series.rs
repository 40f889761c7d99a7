//! `series.csv` of an MD run: one row every `output.every` steps (and at the
//! last step), written with a [`super::SeriesWriter`].
//!
//! Columns, in this order ([`MD_SERIES_COLUMNS`], then the walls): `time` (s, end
//! of the step), `kinetic_energy` (J, translational + rotational),
//! `elastic_energy` (J, stored in the contacts), `potential_energy` (J,
//! gravitational above the lowest sphere bottom plus elastic,
//! [`MdSystem::potential_energy`]), `contacts` (sphere–sphere; a contact with a
//! symmetry image counts half), `wall_contacts`, `max_overlap` and
//! `mean_overlap` (m, over all contacts), `coordination` (`(2 N_c + N_w) / N`),
//! `packing_fraction` (sphere volume over container section × sample height,
//! [`MdSystem::packing_fraction_bulk`]; empty when the walls make no container);
//! then `<wall>_force` for every wall in scene order (N, the normal force the
//! spheres press it with, positive when pressed: [`MdSystem::wall_load`]; 0 for a
//! cylinder, which has no single normal), then `<wall>_position` for every servo
//! wall in scene order (m, its displacement along its normal since the start).
//! A wall name that holds a comma, a quote or a line break is quoted as CSV asks.
//! Floats are written with `{:e}` (contacts, a count that may end in .5, with
//! `{}`), the shortest text that reads back to the same `f64`.

use crate::md::{MdStepStats, MdSystem, Motion};
use std::fmt::Write as _;

/// The first columns of an MD `series.csv`, before the wall columns.
pub const MD_SERIES_COLUMNS: [&str; 10] = [
    "time",
    "kinetic_energy",
    "elastic_energy",
    "potential_energy",
    "contacts",
    "wall_contacts",
    "max_overlap",
    "mean_overlap",
    "coordination",
    "packing_fraction",
];

/// A CSV field: quoted (quotes doubled) if it holds a comma, a quote or a line break.
fn field(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The header line (without the newline) for the walls of `sys`.
pub fn md_series_header(sys: &MdSystem) -> String {
    let mut h = MD_SERIES_COLUMNS.join(",");
    for w in &sys.walls {
        let _ = write!(h, ",{}", field(&format!("{}_force", w.name)));
    }
    for w in sys.walls.iter().filter(|w| matches!(w.motion, Motion::Servo { .. })) {
        let _ = write!(h, ",{}", field(&format!("{}_position", w.name)));
    }
    h
}

/// The row (without the newline) of the step of `sys` that returned `s`.
pub fn md_series_row(sys: &MdSystem, s: &MdStepStats) -> String {
    let mut r = format!(
        "{:e},{:e},{:e},{:e},{},{},{:e},{:e},{:e},{}",
        s.time,
        s.kinetic_energy,
        s.elastic_energy,
        sys.gravitational_energy() + s.elastic_energy,
        s.contacts,
        s.wall_contacts,
        s.max_overlap,
        s.mean_overlap,
        s.coordination,
        sys.packing_fraction_bulk().map_or(String::new(), |p| format!("{p:e}"))
    );
    for w in &sys.walls {
        // 0 − F rather than −F: no `-0e0` for an untouched wall.
        let _ = write!(r, ",{:e}", 0.0 - w.normal_force());
    }
    for w in sys.walls.iter().filter(|w| matches!(w.motion, Motion::Servo { .. })) {
        let _ = write!(r, ",{:e}", w.s);
    }
    r
}
