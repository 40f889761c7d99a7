//! `series.csv`: one row of step statistics every `output.every` steps (and at
//! the last step), written with a [`super::table::TableWriter`]. Column names
//! carry their unit (`_s`, `_J`, `_m`, `_N`); counts and ratios have none.
//!
//! NSCD ([`NscdSeriesRow`]): `time_s`, `kinetic_energy_J`, `contacts` (detected,
//! open ones within the alert distance included), `active_contacts` (carrying a
//! force or overlapping), `iterations` (NLGS sweeps), `criterion` (final value of
//! the convergence norm), `converged` (1, or 0 when the step hit the iteration
//! cap), `mean_overlap_m` (over the active contacts), `max_overlap_m`,
//! `total_overlap_m` (sum over the contacts: the cumulated interpenetration of
//! Saussine et al. 2006, Fig. 2).
//!
//! MD ([`MdSeriesRow`]): `time_s`, `kinetic_energy_J` (translational +
//! rotational), `elastic_energy_J` (stored in the contacts), `potential_energy_J`
//! (gravitational above the reference height plus elastic,
//! [`crate::md::MdSystem::potential_energy`]), `contacts` (sphere–sphere; a
//! contact with a symmetry image counts half), `wall_contacts`, `max_overlap_m`,
//! `mean_overlap_m` (over all contacts), `coordination` (`(2 N_c + N_w) / N`),
//! `packing_fraction` (sphere volume over container section × sample height;
//! empty when the walls make no container); then `<wall>_force_N` for every
//! wall in scene order (the normal force the spheres press it with, positive
//! when pressed; 0 for a cylinder), then `<wall>_position_m` for every servo wall
//! (its displacement along its normal since the start).

use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// One row of an NSCD `series.csv`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NscdSeriesRow {
    /// Column `time_s`: time at the end of the step (s).
    pub time_s: f64,
    /// Column `kinetic_energy_J`: kinetic energy of the non-fixed bodies, translational plus
    /// rotational, at the end of the step (J).
    #[serde(rename = "kinetic_energy_J")]
    pub kinetic_energy_j: f64,
    /// Column `contacts`: contacts detected, open ones within the alert distance included.
    pub contacts: usize,
    /// Column `active_contacts`: contacts carrying an impulse or overlapping at the end of the step.
    pub active_contacts: usize,
    /// Column `iterations`: NLGS sweeps made in the step.
    pub iterations: usize,
    /// Column `criterion`: final value of the convergence norm of the policy
    /// ([`crate::nscd::criterion::evaluate`]; dimensionless, converged below the tolerance).
    pub criterion: f64,
    /// Column `converged`: 1 if the iterations converged, 0 if they hit the iteration cap.
    pub converged: u8,
    /// Column `mean_overlap_m`: mean overlap over the active contacts at the end of the step (m).
    pub mean_overlap_m: f64,
    /// Column `max_overlap_m`: largest overlap at the end of the step (m).
    pub max_overlap_m: f64,
    /// Column `total_overlap_m`: sum of the overlaps of all contacts (m), the cumulated
    /// interpenetration of Saussine et al. 2006, Fig. 2.
    pub total_overlap_m: f64,
}

/// The columns of [`NscdSeriesRow`].
pub const NSCD_SERIES_COLUMNS: [&str; 10] = [
    "time_s",
    "kinetic_energy_J",
    "contacts",
    "active_contacts",
    "iterations",
    "criterion",
    "converged",
    "mean_overlap_m",
    "max_overlap_m",
    "total_overlap_m",
];

/// One row of an MD `series.csv`: the fixed columns, then the wall columns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MdSeriesRow {
    /// Column `time_s`: time at the end of the step (s).
    pub time_s: f64,
    /// Column `kinetic_energy_J`: translational plus rotational kinetic energy of the spheres (J).
    #[serde(rename = "kinetic_energy_J")]
    pub kinetic_energy_j: f64,
    /// Column `elastic_energy_J`: elastic energy stored in the contacts (J); a contact
    /// with a symmetry image counts half.
    #[serde(rename = "elastic_energy_J")]
    pub elastic_energy_j: f64,
    /// Column `potential_energy_J`: gravitational energy above the fixed reference height
    /// plus `elastic_energy_J` (J; [`crate::md::MdSystem::potential_energy`]).
    #[serde(rename = "potential_energy_J")]
    pub potential_energy_j: f64,
    /// Column `contacts`: sphere–sphere contacts (a contact with a symmetry image counts half).
    pub contacts: f64,
    /// Column `wall_contacts`: sphere–wall contacts.
    pub wall_contacts: usize,
    /// Column `max_overlap_m`: largest overlap `δ` of any contact (m).
    pub max_overlap_m: f64,
    /// Column `mean_overlap_m`: mean overlap over all contacts (m).
    pub mean_overlap_m: f64,
    /// Column `coordination`: coordination number `(2 N_c + N_w) / N` (dimensionless;
    /// Karrech et al. 2007, Fig. 3).
    pub coordination: f64,
    /// Column `packing_fraction`: sphere volume over container section × sample height
    /// (dimensionless, [`crate::md::MdSystem::packing_fraction_bulk`]); empty without a container.
    pub packing_fraction: Option<f64>,
    /// `<wall>_force_N` for every wall, then `<wall>_position_m` for every servo wall.
    pub walls: Vec<f64>,
}

/// The fixed columns of [`MdSeriesRow`], before the wall columns.
pub const MD_SERIES_COLUMNS: [&str; 10] = [
    "time_s",
    "kinetic_energy_J",
    "elastic_energy_J",
    "potential_energy_J",
    "contacts",
    "wall_contacts",
    "max_overlap_m",
    "mean_overlap_m",
    "coordination",
    "packing_fraction",
];

/// Reads an NSCD `series.csv`; the error names the file and the line.
pub fn read_nscd(path: &Path) -> Result<Vec<NscdSeriesRow>> {
    Ok(super::table::read(path)?.1)
}

/// Reads an MD `series.csv`: its header (with the wall columns) and its rows.
pub fn read_md(path: &Path) -> Result<(Vec<String>, Vec<MdSeriesRow>)> {
    super::table::read(path)
}
