//! The NSCD system as a 2D engine ([`PlaneEngine`], hence an [`crate::engine::Engine`] of the run loop and of
//! cyclic drivers through [`crate::plane::engine`]): its step (NLGS sweeps, their criterion and convergence in
//! the rows: Saussine et al. 2006 §3), threads, state checks, write-back of `(x, y, θ)` per body
//! ([`System::set_configuration`]) and relaxation.

use super::system::{StepStats, System};
use crate::engine::{Configuration, RelaxReport, RelaxSettings};
use crate::error::Result;
use crate::plane::engine::{PlaneEngine, PlaneStep};
use crate::plane::outputs::PlaneSystem;
use crate::plane::springs::Spring;
use crate::plane::{Bodies, ContactInfo};

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

impl PlaneEngine for System {
    const NAME: &'static str = "nscd";
    const ITERATIVE: bool = true;
    const SOLVER_KEYS: &'static [&'static str] = &crate::nscd::method::NlgsSettings::SCENE_KEYS;
    type Stats = StepStats;

    fn plane_step_once(&mut self) -> Result<StepStats> {
        System::step(self)
    }

    fn numbers(s: &StepStats) -> PlaneStep {
        PlaneStep {
            time: s.time,
            kinetic_energy: s.kinetic_energy,
            contacts: s.contacts,
            active_contacts: s.active_contacts,
            mean_overlap: s.mean_overlap,
            max_overlap: s.max_overlap,
            total_overlap: s.total_overlap,
            iterations: s.iterations,
            criterion: s.criterion,
            converged: s.converged,
        }
    }

    fn plane_dt(&self) -> f64 {
        self.params.dt
    }

    fn plane_set_threads(&mut self, threads: usize) {
        System::set_threads(self, threads);
    }

    fn plane_potential_energy(&self) -> f64 {
        self.potential_energy()
    }

    fn plane_springs(&self) -> &[Spring] {
        &self.springs
    }

    fn plane_check_state(&self) -> Result<()> {
        System::check_state(self)
    }

    fn plane_check_same_model(&self, fresh: &Self) -> Result<()> {
        System::check_same_model(self, fresh)
    }

    fn plane_change_solver(&mut self, fresh: &Self) -> Result<Vec<[String; 3]>> {
        let changes = self.params.nlgs.changes(&fresh.params.nlgs);
        self.params.nlgs = fresh.params.nlgs;
        Ok(changes)
    }

    fn plane_set_configuration(&mut self, c: &Configuration) -> Result<()> {
        System::set_configuration(self, c)
    }

    fn plane_relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport> {
        System::relax(self, settings)
    }
}
