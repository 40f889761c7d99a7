//! The NSCD system as an [`Engine`] of the run loop and of cyclic drivers: its
//! rows of `series.csv` and `cycles.csv` (Saussine et al. 2006 §3–4: sweeps,
//! interpenetration, sleeper settlement), final state, snapshots and figures,
//! and its generalised positions `(x, y, θ)` per body, read and written back
//! ([`System::set_configuration`]).

use super::system::{StepStats, System};
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

impl PlaneSystem for System {
    fn plane_bodies(&self) -> &Bodies {
        &self.bodies
    }

    fn plane_time(&self) -> f64 {
        self.time
    }

    fn plane_step(&self) -> u64 {
        self.step
    }

    fn plane_contacts(&self) -> Vec<ContactInfo> {
        self.contact_forces().collect()
    }
}

impl Engine for System {
    const NAME: &'static str = "nscd";
    const DOF: usize = 3;
    const DIM: usize = 2;
    const EXTRAPOLATED: usize = 2;
    const ITERATIVE: bool = true;
    type Stats = StepStats;
    type Row = PlaneSeriesRow;
    type CycleState = PlaneCycleState;
    type CycleRow = PlaneCycleRow;

    fn step(&mut self) -> Result<StepStats> {
        System::step(self)
    }

    fn time(&self) -> f64 {
        self.time
    }

    fn steps_done(&self) -> u64 {
        self.step
    }

    fn dt(&self) -> f64 {
        self.params.dt
    }

    fn set_threads(&mut self, threads: usize) {
        System::set_threads(self, threads);
    }

    fn body_count(&self) -> usize {
        self.bodies.len()
    }

    fn summary(s: &StepStats) -> StepSummary {
        StepSummary {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts as f64,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            iterations: s.iterations as u64,
            converged: s.converged,
            criterion: s.criterion,
        }
    }

    fn energies(&self, stats: &StepStats, potential: bool) -> Energies {
        Energies { kinetic: stats.kinetic_energy, potential: if potential { self.potential_energy() } else { 0.0 } }
    }

    fn series_header(&self) -> Vec<String> {
        PLANE_SERIES_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn series_row(&self, s: &StepStats) -> PlaneSeriesRow {
        PlaneSeriesRow {
            time_s: s.time,
            kinetic_energy_j: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            iterations: s.iterations,
            criterion: s.criterion,
            converged: u8::from(s.converged),
            mean_overlap_m: s.mean_overlap,
            max_overlap_m: s.max_overlap,
            total_overlap_m: s.total_overlap,
        }
    }

    fn final_state(&self) -> FinalState {
        outputs::final_state(self, Self::NAME)
    }

    /// One row per contact point ([`outputs::contact_rows`]).
    fn contact_rows(&self) -> Vec<ContactRow> {
        outputs::contact_rows(self)
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        crate::plane::vtk::write_snapshot(pvd, dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        System::check_state(self)
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        System::check_same_model(self, fresh)
    }

    fn cycle_start(&self, body: Option<usize>) -> Result<PlaneCycleState> {
        outputs::cycle_start(self, body)
    }

    fn cycle_step(&self, c: &mut PlaneCycleState, stats: &StepStats) {
        outputs::cycle_step(
            self,
            c,
            outputs::CycleStepStats {
                contacts: stats.contacts,
                iterations: stats.iterations,
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
        System::set_configuration(self, c)
    }

    fn relax(&mut self, settings: &crate::engine::RelaxSettings) -> Result<crate::engine::RelaxReport> {
        System::relax(self, settings)
    }
}
