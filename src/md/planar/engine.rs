//! The planar MD system as a 2D engine ([`PlaneEngine`], hence an [`crate::engine::Engine`] of the run loop
//! and of the settlement driver through [`crate::plane::engine`]). Its outputs are those of the NSCD engine,
//! written by the same code: `series.csv` with `iterations` and `criterion` 0 and `converged` 1 (an explicit
//! step solves nothing), so that a scene run with either engine gives files that compare column by column.

use super::system::{PlanarStepStats, PlanarSystem};
use crate::engine::{Configuration, RelaxReport, RelaxSettings};
use crate::error::Result;
use crate::plane::engine::{PlaneEngine, PlaneStep};
use crate::plane::outputs::PlaneSystem;
use crate::plane::springs::Spring;
use crate::plane::{Bodies, ContactInfo};

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

impl PlaneEngine for PlanarSystem {
    const NAME: &'static str = "md2d";
    const ITERATIVE: bool = false;
    type Stats = PlanarStepStats;

    fn plane_step_once(&mut self) -> Result<PlanarStepStats> {
        PlanarSystem::step(self)
    }

    fn numbers(s: &PlanarStepStats) -> PlaneStep {
        PlaneStep {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            total_overlap: s.total_overlap,
            iterations: 0,
            criterion: 0.0,
            converged: true,
        }
    }

    fn plane_dt(&self) -> f64 {
        self.params.dt
    }

    /// One thread: the explicit step is not split.
    fn plane_set_threads(&mut self, _threads: usize) {}

    /// One, whatever was asked: the run's summary and `cycle_times.csv` say so.
    fn plane_threads_used(&self, _asked: usize) -> usize {
        1
    }

    fn plane_potential_energy(&self) -> f64 {
        self.potential_energy()
    }

    fn plane_springs(&self) -> &[Spring] {
        &self.springs
    }

    fn plane_check_state(&self) -> Result<()> {
        PlanarSystem::check_state(self)
    }

    fn plane_check_same_model(&self, fresh: &Self) -> Result<()> {
        PlanarSystem::check_same_model(self, fresh)
    }

    fn plane_set_configuration(&mut self, c: &Configuration) -> Result<()> {
        PlanarSystem::set_configuration(self, c)
    }

    fn plane_relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport> {
        PlanarSystem::relax(self, settings)
    }
}
