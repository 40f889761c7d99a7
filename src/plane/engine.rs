//! The engine contract of the 2D engines, written once: what NSCD ([`crate::nscd::System`]) and planar MD
//! ([`crate::md::planar::PlanarSystem`]) have in common makes them an [`Engine`] through one blanket
//! implementation over the small trait [`PlaneEngine`], which says only what differs (the step and its
//! statistics, the threads, the state checks, the write-back and the relaxation). Their outputs are the same
//! files, written by the same code ([`super::outputs`], [`super::rows`], [`super::vtk`]): `series.csv`
//! (planar MD: `iterations` and `criterion` 0, `converged` 1, an explicit step solves nothing), `cycles.csv`
//! following the sleeper (Saussine et al. 2006 §3–4: sweeps, interpenetration, sleeper settlement),
//! `final.json`, `contacts.csv` and the VTK snapshots, so that a scene run with either engine gives files that
//! compare column by column; and their generalised positions are `(x, y, θ)` per body.

use super::outputs::{self, PlaneSystem};
use super::rows::{PlaneCycleRow, PlaneCycleState, PlaneSeriesRow, PLANE_CYCLE_COLUMNS, PLANE_SERIES_COLUMNS};
use super::springs::Spring;
use crate::engine::{Configuration, ContactRow, Energies, Engine, FinalState, RelaxReport, RelaxSettings, StepSummary};
use crate::error::Result;
use crate::io::vtk::PvdCollection;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

/// The numbers of one step that the rows of a 2D engine are made of.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlaneStep {
    /// Time at the end of the step (s).
    pub time: f64,
    /// Kinetic energy of the bodies at the end of the step (J).
    pub kinetic_energy: f64,
    /// Contacts detected (open ones within the alert distance included).
    pub contacts: usize,
    /// Contacts carrying a force or overlapping.
    pub active_contacts: usize,
    /// Mean overlap over the active contacts (m).
    pub mean_overlap: f64,
    /// Largest overlap (m).
    pub max_overlap: f64,
    /// Sum of the overlaps (m).
    pub total_overlap: f64,
    /// Solver sweeps of the step (0 for an explicit step).
    pub iterations: usize,
    /// Final value of the solver's convergence norm (0 for an explicit step).
    pub criterion: f64,
    /// Whether the solver met its tolerance (always for an explicit step).
    pub converged: bool,
}

/// What a 2D engine says for itself; the rest of [`Engine`] is the same for every 2D engine.
pub trait PlaneEngine: PlaneSystem + Clone + Send + Serialize + DeserializeOwned + 'static {
    /// The engine's name in outputs ([`Engine::NAME`]).
    const NAME: &'static str;
    /// Whether a step solves an iterative problem ([`Engine::ITERATIVE`]).
    const ITERATIVE: bool;
    /// As [`Engine::SOLVER_KEYS`] (none by default).
    const SOLVER_KEYS: &'static [&'static str] = &[];
    /// What one step measured.
    type Stats: Copy + std::fmt::Debug;

    /// Makes one time step ([`Engine::step`]).
    ///
    /// # Errors
    /// As [`Engine::step`].
    fn plane_step_once(&mut self) -> Result<Self::Stats>;

    /// The numbers of `stats` that the rows are made of.
    fn numbers(stats: &Self::Stats) -> PlaneStep;

    /// Time step (s).
    fn plane_dt(&self) -> f64;

    /// Threads of a step ([`Engine::set_threads`]).
    fn plane_set_threads(&mut self, threads: usize);

    /// The threads a step uses when `asked` were asked for ([`Engine::threads_used`]); default `asked`.
    fn plane_threads_used(&self, asked: usize) -> usize {
        asked
    }

    /// Gravitational plus elastic potential energy (J).
    fn plane_potential_energy(&self) -> f64;

    /// The sublayer springs (law (17) of Saussine et al. 2006).
    fn plane_springs(&self) -> &[Spring];

    /// As [`Engine::check_state`].
    ///
    /// # Errors
    /// As [`Engine::check_state`].
    fn plane_check_state(&self) -> Result<()>;

    /// As [`Engine::check_same_model`].
    ///
    /// # Errors
    /// As [`Engine::check_same_model`].
    fn plane_check_same_model(&self, fresh: &Self) -> Result<()>;

    /// As [`Engine::change_solver`] (the default refuses, as the trait's).
    ///
    /// # Errors
    /// As [`Engine::change_solver`].
    fn plane_change_solver(&mut self, _fresh: &Self) -> Result<Vec<[String; 3]>> {
        Err(crate::engine::contract::no_solver_settings(Self::NAME))
    }

    /// As [`Engine::set_configuration`].
    ///
    /// # Errors
    /// As [`Engine::set_configuration`].
    fn plane_set_configuration(&mut self, c: &Configuration) -> Result<()>;

    /// As [`Engine::relax`]: the mass-metric projection of [`super::relax`].
    ///
    /// # Errors
    /// As [`Engine::relax`].
    fn plane_relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport>;
}

impl<T: PlaneEngine> Engine for T {
    const NAME: &'static str = <T as PlaneEngine>::NAME;
    const DOF: usize = 3;
    const DIM: usize = 2;
    const EXTRAPOLATED: usize = 2;
    const ITERATIVE: bool = <T as PlaneEngine>::ITERATIVE;
    const SOLVER_KEYS: &'static [&'static str] = <T as PlaneEngine>::SOLVER_KEYS;
    type Stats = <T as PlaneEngine>::Stats;
    type Row = PlaneSeriesRow;
    type CycleState = PlaneCycleState;
    type CycleRow = PlaneCycleRow;

    fn step(&mut self) -> Result<Self::Stats> {
        self.plane_step_once()
    }

    fn time(&self) -> f64 {
        self.plane_time()
    }

    fn steps_done(&self) -> u64 {
        self.plane_step()
    }

    fn dt(&self) -> f64 {
        self.plane_dt()
    }

    fn set_threads(&mut self, threads: usize) {
        self.plane_set_threads(threads);
    }

    fn threads_used(&self, asked: usize) -> usize {
        self.plane_threads_used(asked)
    }

    fn body_count(&self) -> usize {
        self.plane_bodies().len()
    }

    fn summary(stats: &Self::Stats) -> StepSummary {
        let s = T::numbers(stats);
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

    fn energies(&self, stats: &Self::Stats, potential: bool) -> Energies {
        let kinetic = T::numbers(stats).kinetic_energy;
        Energies { kinetic, potential: if potential { self.plane_potential_energy() } else { 0.0 } }
    }

    fn series_header(&self) -> Vec<String> {
        PLANE_SERIES_COLUMNS.iter().map(|s| s.to_string()).collect()
    }

    fn series_row(&self, stats: &Self::Stats) -> PlaneSeriesRow {
        let s = T::numbers(stats);
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
        outputs::final_state(self, <T as PlaneEngine>::NAME)
    }

    /// One row per contact point ([`outputs::contact_rows`]).
    fn contact_rows(&self) -> Vec<ContactRow> {
        outputs::contact_rows(self)
    }

    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()> {
        super::vtk::write_snapshot(pvd, dir, self).map(|_| ())
    }

    fn check_state(&self) -> Result<()> {
        self.plane_check_state()
    }

    fn check_same_model(&self, fresh: &Self) -> Result<()> {
        self.plane_check_same_model(fresh)
    }

    fn change_solver(&mut self, fresh: &Self) -> Result<Vec<[String; 3]>> {
        self.plane_change_solver(fresh)
    }

    fn cycle_start(&self, body: Option<usize>) -> Result<PlaneCycleState> {
        outputs::cycle_start(self, body)
    }

    fn cycle_step(&self, c: &mut PlaneCycleState, stats: &Self::Stats) {
        let s = T::numbers(stats);
        outputs::cycle_step(
            self,
            c,
            outputs::CycleStepStats {
                contacts: s.contacts,
                iterations: s.iterations,
                max_overlap: s.max_overlap,
                mean_overlap: s.mean_overlap,
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
        outputs::coordination(self, &outputs::mobile_bodies(self.plane_bodies()), 0.0).z
    }

    fn mobile_bodies(&self) -> Vec<usize> {
        outputs::mobile_bodies(self.plane_bodies())
    }

    fn configuration_of(&self, bodies: &[usize]) -> Configuration {
        outputs::configuration_of(self.plane_bodies(), bodies)
    }

    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64> {
        outputs::body_sizes(self.plane_bodies(), bodies)
    }

    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize> {
        let count = outputs::neighbour_counts(self, 0.0);
        bodies.iter().map(|&i| count[i]).collect()
    }

    fn anchored_bodies(&self) -> Vec<usize> {
        super::springs::anchored(self.plane_springs())
    }

    fn set_configuration(&mut self, c: &Configuration) -> Result<()> {
        self.plane_set_configuration(c)
    }

    fn relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport> {
        self.plane_relax(settings)
    }
}
