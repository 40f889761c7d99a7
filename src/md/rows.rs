//! The output rows of the MD engine, read back with the same types; column names carry their unit (`_s`,
//! `_J`, `_m`, `_N`), counts and ratios have none.
//!
//! `series.csv`, one row every `output.every` steps and at the last step ([`MdSeriesRow`]):
//! `time_s`, `kinetic_energy_J` (translational +
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
//!
//! `cycles.csv`, one row per loading cycle ([`crate::clock::cycles_at`]):
//! [`MdCycleRow`] (the residual displacements of Karrech et al. 2007 §3,
//! taken at the end of each cycle, where the load is back to its base value):
//! `cycle`, `time_s`, `mean_displacement_x_m`, `…_y_m`, `…_z_m` (mean over the
//! spheres of the displacement since the start of the run), `max_displacement_m`
//! (the largest norm), `max_overlap_m` (largest over the cycle), then
//! `<wall>_position_m` for every servo wall.
//!
//! The per-cycle state is plain data, kept in checkpoints so that a resumed run writes the same rows.

use crate::engine::CycleCheck;
use crate::error::Result;
use serde::{Deserialize, Serialize};
use std::path::Path;

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

/// Reads an MD `series.csv`: its header (with the wall columns) and its rows.
pub fn read_series(path: &Path) -> Result<(Vec<String>, Vec<MdSeriesRow>)> {
    crate::io::table::read(path)
}
/// What an MD run keeps for its cycles.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MdCycleState {
    /// Sphere centres at the start of the run (m).
    pub x0: Vec<[f64; 3]>,
    /// Largest overlap over the cycle under way (m).
    pub max_overlap: f64,
}

impl CycleCheck for MdCycleState {
    fn check(&self, start: &Self, _bodies: usize, _cycles: u64) -> std::result::Result<(), String> {
        let same = self.x0.len() == start.x0.len()
            && self.x0.iter().flatten().zip(start.x0.iter().flatten()).all(|(a, b)| a.to_bits() == b.to_bits());
        if same {
            Ok(())
        } else {
            Err(format!("{} sphere centres at the start, not those of the scene's {}", self.x0.len(), start.x0.len()))
        }
    }
}

/// One row of an MD `cycles.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MdCycleRow {
    /// Column `cycle`: number of the cycle ended (1 for the first).
    pub cycle: u64,
    /// Column `time_s`: time at the end of the cycle (s).
    pub time_s: f64,
    /// Column `mean_displacement_x_m`: x-component of the displacement since the
    /// start of the run, mean over the spheres (m).
    pub mean_displacement_x_m: f64,
    /// Column `mean_displacement_y_m`: y-component of the mean displacement (m).
    pub mean_displacement_y_m: f64,
    /// Column `mean_displacement_z_m`: z-component of the mean displacement (m).
    pub mean_displacement_z_m: f64,
    /// Column `max_displacement_m`: largest norm of a sphere's displacement since the
    /// start of the run (m).
    pub max_displacement_m: f64,
    /// Column `max_overlap_m`: largest contact overlap over the cycle (m).
    pub max_overlap_m: f64,
    /// `<wall>_position_m` for every servo wall.
    pub walls: Vec<f64>,
}

/// The fixed columns of [`MdCycleRow`], before the servo walls.
pub const MD_CYCLE_COLUMNS: [&str; 7] = [
    "cycle",
    "time_s",
    "mean_displacement_x_m",
    "mean_displacement_y_m",
    "mean_displacement_z_m",
    "max_displacement_m",
    "max_overlap_m",
];

/// Reads an MD `cycles.csv`; the error names the file and the line.
pub fn read_cycles(path: &Path) -> Result<Vec<MdCycleRow>> {
    Ok(crate::io::table::read(path)?.1)
}
