//! The planar MD system as an [`Engine`] of the run loop and of the settlement
//! driver. Its outputs are those of the NSCD engine, written by the same code
//! ([`crate::plane::outputs`]): `series.csv` with the NSCD columns (`iterations`
//! and `criterion` 0, `converged` 1: an explicit step solves nothing),
//! `cycles.csv` following the sleeper, `final.json`, `contacts.csv` and the
//! VTK snapshots of the 2D bodies, so that a scene run with either engine gives
//! files that compare column by column.

use super::system::{PlanarStepStats, PlanarSystem};
use crate::engine::contacts::ContactRow;
use crate::engine::final_state::FinalState;
use crate::engine::StepSummary;
use crate::engine::{Configuration, Energies, Engine};
use crate::error::Result;
use crate::io::vtk::PvdCollection;
use crate::plane::outputs::{self, PlaneSystem};
use crate::plane::rows::{PlaneCycleRow, PlaneCycleState, PLANE_CYCLE_COLUMNS};
use crate::plane::rows::{PlaneSeriesRow, PLANE_SERIES_COLUMNS};
use crate::plane::{Bodies, ContactInfo};
use std::path::Path;

impl PlaneSystem for PlanarSystem {
    fn plane_bodies(&self) -> &Bodies {
        &self.bodies
    }

    fn plane_time(&self) -> f64 {
        self.time()
    }

    fn plane_step(&self) -> u64 {
        self.steps_done()
    }

    fn plane_contacts(&self) -> Vec<ContactInfo> {
        self.contact_forces().collect()
    }
}

impl Engine for PlanarSystem {
    const NAME: &'static str = "md2d";
    const DOF: usize = 3;
    const DIM: usize = 2;
    const EXTRAPOLATED: usize = 2;
    const ITERATIVE: bool = false;
    type Stats = PlanarStepStats;
    type Row = PlaneSeriesRow;
    type CycleState = PlaneCycleState;
    type CycleRow = PlaneCycleRow;

    fn step(&mut self) -> Result<PlanarStepStats> {
        PlanarSystem::step(self)
    }

    fn time(&self) -> f64 {
        PlanarSystem::time(self)
    }

    fn steps_done(&self) -> u64 {
        PlanarSystem::steps_done(self)
    }

    fn dt(&self) -> f64 {
        self.params.dt
    }

    fn set_threads(&mut self, _threads: usize) {}

    fn body_count(&self) -> usize {
        self.bodies.len()
    }

    fn summary(s: &PlanarStepStats) -> StepSummary {
        StepSummary {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts as f64,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            iterations: 0,
            converged: true,
            criterion: 0.0,
        }
    }

    fn energies(&self, stats: &PlanarStepStats, potential: bool) -> Energies {
        Energies { kinetic: stats.kinetic_energy, potential: if potential { self.potential_energy() } else { 0.0 } }
    }

    fn series_header(&self) -> Vec<String> {
        PLANE_SERIES_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn series_row(&self, s: &PlanarStepStats) -> PlaneSeriesRow {
        PlaneSeriesRow {
            time_s: s.time,
            kinetic_energy_j: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            iterations: 0,
            criterion: 0.0,
            converged: 1,
            mean_overlap_m: s.mean_overlap,
            max_overlap_m: s.max_overlap,
            total_overlap_m: s.total_overlap,
        }
    }

    fn final_state(&self) -> FinalState {
        outputs::final_state(self, Self::NAME)
    }

    fn contact_rows(&self) -> Vec<ContactRow> {
        outputs::contact_rows(self)
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        crate::plane::vtk::write_snapshot(pvd, dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        PlanarSystem::check_state(self)
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        PlanarSystem::check_same_model(self, fresh)
    }

    fn cycle_start(&self, body: Option<usize>) -> Result<PlaneCycleState> {
        outputs::cycle_start(self, body)
    }

    fn cycle_step(&self, c: &mut PlaneCycleState, stats: &PlanarStepStats) {
        outputs::cycle_step(
            self,
            c,
            outputs::CycleStepStats {
                contacts: stats.contacts,
                iterations: 0,
                max_overlap: stats.max_overlap,
                mean_overlap: stats.mean_overlap,
            },
        );
    }

    fn cycle_end(&self, c: &mut PlaneCycleState, cycle: u64) -> PlaneCycleRow {
        outputs::cycle_end(self, c, cycle)
    }

    fn cycle_header(&self) -> Vec<String> {
        PLANE_CYCLE_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn settlement(&self, c: &PlaneCycleState) -> Option<f64> {
        outputs::settlement(self, c)
    }

    fn coordination(&self) -> f64 {
        outputs::coordination(self, &outputs::mobile_bodies(&self.bodies), 0.0).z
    }

    fn mobile_bodies(&self) -> Vec<usize> {
        outputs::mobile_bodies(&self.bodies)
    }

    fn configuration_of(&self, bodies: &[usize]) -> Configuration {
        outputs::configuration_of(&self.bodies, bodies)
    }

    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64> {
        outputs::body_sizes(&self.bodies, bodies)
    }

    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize> {
        let count = outputs::neighbour_counts(self, 0.0);
        bodies.iter().map(|&i| count[i]).collect()
    }

    fn anchored_bodies(&self) -> Vec<usize> {
        crate::plane::springs::anchored(&self.springs)
    }

    fn set_configuration(&mut self, c: &Configuration) -> Result<()> {
        PlanarSystem::set_configuration(self, c)
    }

    fn relax(&mut self, settings: &crate::engine::RelaxSettings) -> Result<crate::engine::RelaxReport> {
        PlanarSystem::relax(self, settings)
    }
}
