//! The engine interface: what the run loop ([`crate::run::Runner`]) and a cyclic
//! driver need of an engine, implemented by [`crate::nscd::System`] (rigid 2D
//! polygons, non-smooth contact dynamics) and [`crate::md::MdSystem`] (soft 3D
//! spheres, molecular dynamics).
//!
//! An engine is plain serde data (a checkpoint is its serde form) that makes one
//! time step at a time on an exact clock (`t = t_0 + (k − k_0) h`,
//! [`crate::clock`]), reports what the step measured, and writes its own output
//! rows, final state and snapshots. For a cyclic driver (Karrech et al. 2007,
//! Fig. 10: compute k cycles, fit, extrapolate, write back, relax) it exposes the
//! generalised positions of its mobile bodies ([`Configuration`]) and takes them
//! back with the velocities zeroed and every derived state rebuilt, so that the
//! next step starts exactly from the written configuration.

use super::{Boundary, Configuration, ContactRow, FinalState, RelaxReport, RelaxSettings, StepSummary};
use crate::error::Result;
use crate::io::vtk::PvdCollection;
use serde::de::DeserializeOwned;
use serde::Serialize;
use std::path::Path;

/// Energies of the equilibrium rule ([`crate::run::Equilibrium`]) at the end of a step (J).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Energies {
    /// Kinetic energy of everything that moves (J).
    pub kinetic: f64,
    /// Potential energy, gravitational + elastic (J); 0 when not asked for.
    pub potential: f64,
}

/// The check of a per-cycle state read from a checkpoint.
pub trait CycleCheck {
    /// Checks `self`, read from a checkpoint written after `cycles` completed
    /// cycles of a system of `bodies` bodies, against `start`, the state the
    /// run started with ([`crate::engine::Engine::cycle_start`]): what the
    /// per-cycle output follows and starts from, and the shape of what it
    /// keeps. The message says what differs.
    fn check(&self, start: &Self, bodies: usize, cycles: u64) -> std::result::Result<(), String>;
}

/// A time-stepping engine driven by the run loop and by cyclic drivers.
pub trait Engine: Clone + Send + Serialize + DeserializeOwned + 'static {
    /// The engine's name in scenes and outputs (`"nscd"`, `"md"`).
    const NAME: &'static str;
    /// Generalised coordinates per body in a [`Configuration`].
    const DOF: usize;
    /// Degrees of translation: the first `DIM` coordinates of a body (m); the
    /// last of them is the vertical (y in 2D, z in 3D), along which gravity pulls.
    const DIM: usize;
    /// The leading coordinates of a body a settlement driver extrapolates: NSCD
    /// 2 (x, y: a pentagon turns by rolling events, not by a creep a law can
    /// extrapolate; docs/settlement-driver.md), MD 3 (x, y, z: a sphere's
    /// orientation does not matter).
    const EXTRAPOLATED: usize;
    /// Whether a step solves an iterative problem (NSCD: NLGS sweeps), whose
    /// iterations and unconverged steps the summary reports.
    const ITERATIVE: bool;
    /// The scene keys (`table.key`) of the per-step solve's settings, which a run may change when it resumes
    /// ([`Engine::change_solver`], [`crate::run::RunOptions::change_solver`]); none by default.
    const SOLVER_KEYS: &'static [&'static str] = &[];
    /// What one step measured.
    type Stats: Copy + std::fmt::Debug;
    /// One row of `series.csv` (serde, written by the run loop and read back by the engine's rows module, e.g.
    /// [`crate::plane::rows`]; the columns carry their unit in their name).
    type Row: Serialize + DeserializeOwned + Clone + std::fmt::Debug;
    /// What the per-cycle output accumulates over the steps of a cycle (kept in
    /// checkpoints, checked on resume against the state [`Engine::cycle_start`]
    /// gives: [`CycleCheck`]).
    type CycleState: Clone + std::fmt::Debug + Serialize + DeserializeOwned + Send + CycleCheck;
    /// One row of `cycles.csv`.
    type CycleRow: Serialize + DeserializeOwned + Clone + std::fmt::Debug;

    /// Makes one time step.
    ///
    /// # Errors
    /// [`crate::Error::Diverged`] (step and body named) on a non-finite value, a
    /// runaway overlap or runaway energy; the engine then holds the state of the
    /// last good step.
    fn step(&mut self) -> Result<Self::Stats>;

    /// Time at the end of the last step (s), on the exact clock.
    fn time(&self) -> f64;

    /// Steps made since the engine was built.
    fn steps_done(&self) -> u64;

    /// Time step (s).
    fn dt(&self) -> f64;

    /// Threads of a step (1 or 2); the numbers do not depend on it.
    fn set_threads(&mut self, threads: usize);

    /// The threads a step uses when `asked` were asked for ([`Engine::set_threads`]), as the run's summary
    /// records them: `asked` unless the engine runs on fewer.
    fn threads_used(&self, asked: usize) -> usize {
        asked
    }

    /// Number of bodies (bodies or spheres, walls not included).
    fn body_count(&self) -> usize;

    /// The numbers every engine reports for a step.
    fn summary(stats: &Self::Stats) -> StepSummary;

    /// What the state as built measures before the first step (MD: the overlaps
    /// present at the start), folded into the run's summary; `None` if nothing.
    fn initial_summary(&self) -> Option<StepSummary> {
        None
    }

    /// The energies of the equilibrium rule after the step that returned
    /// `stats`; the potential energy only if `potential` (it may cost a loop).
    fn energies(&self, stats: &Self::Stats, potential: bool) -> Energies;

    /// The header of `series.csv` (the row's columns, then any per-wall columns).
    fn series_header(&self) -> Vec<String>;

    /// The row of `series.csv` of the step that returned `stats`.
    fn series_row(&self, stats: &Self::Stats) -> Self::Row;

    /// The state of every body (and wall) for `final.json`.
    fn final_state(&self) -> FinalState;

    /// The contacts of the last step with their forces, for `contacts.csv`
    /// ([`crate::engine::contacts`]).
    fn contact_rows(&self) -> Vec<ContactRow>;

    /// Writes a ParaView snapshot of the current state into `dir` and lists it in `pvd`.
    fn snapshot(&self, dir: &Path, pvd: &mut PvdCollection) -> Result<()>;

    /// Checks that the state is internally consistent (array lengths, indices,
    /// clock): a state read from a checkpoint must pass before it runs.
    fn check_state(&self) -> Result<()>;

    /// Checks that `self` (read from a checkpoint) is a state of the model `fresh`
    /// (built from the scene): same bodies, materials and walls.
    fn check_same_model(&self, fresh: &Self) -> Result<()>;

    /// Takes the settings of the per-step solve from `fresh`, the system built from the scene a run resumes
    /// with ([`crate::run::RunOptions::change_solver`]), and returns those that changed as `[scene key, before,
    /// after]`. The default refuses: the engine has no such settings (the MD engines).
    ///
    /// # Errors
    /// [`crate::Error::Scene`] naming the engine when it has no solver settings to change.
    fn change_solver(&mut self, _fresh: &Self) -> Result<Vec<[String; 3]>> {
        Err(no_solver_settings(Self::NAME))
    }

    /// Starts the per-cycle output: `body` is the index of the followed body
    /// (NSCD: the sleeper, required; MD: none).
    fn cycle_start(&self, body: Option<usize>) -> Result<Self::CycleState>;

    /// Adds the step that returned `stats` to the cycle under way.
    fn cycle_step(&self, state: &mut Self::CycleState, stats: &Self::Stats);

    /// Closes cycle `cycle` (1, 2, …) at the current step: its row; the
    /// accumulators start again.
    fn cycle_end(&self, state: &mut Self::CycleState, cycle: u64) -> Self::CycleRow;

    /// The header of `cycles.csv`.
    fn cycle_header(&self) -> Vec<String>;

    /// The settlement shown by a progress display (m, positive downwards), if the
    /// cycle output follows one.
    fn settlement(&self, _state: &Self::CycleState) -> Option<f64> {
        None
    }

    /// The coordination number of the current state, as the engine measures it
    /// (NSCD: force-carrying neighbours per non-rattler grain,
    /// [`crate::nscd::measure::coordination`]; MD: `(2 N_c + N_w)/N` of the last
    /// force evaluation).
    fn coordination(&self) -> f64;

    /// The bodies a driver may move: every body that is not fixed (NSCD) or
    /// every sphere (MD).
    fn mobile_bodies(&self) -> Vec<usize>;

    /// The generalised positions of `bodies` ([`Configuration`]).
    fn configuration_of(&self, bodies: &[usize]) -> Configuration;

    /// A length per body of `bodies` (m), the scale a settlement driver bounds
    /// an extrapolated move by: NSCD the radius of the disc of the shape's area
    /// (`√(A/π)`), MD the sphere's radius.
    fn body_sizes(&self, bodies: &[usize]) -> Vec<f64>;

    /// Per body of `bodies`, the number of bodies and walls it touches with a
    /// contact that carries a force in the last step (NSCD `r_n > 0` summed
    /// over the pair's contact points; MD a touching pair, image or wall).
    fn contact_counts(&self, bodies: &[usize]) -> Vec<usize>;

    /// The bodies tied to a fixed anchor by a spring (NSCD and planar MD:
    /// the sublayer pads of law (17) of Saussine et al. 2006), engine indices,
    /// sorted; none by default (3D MD). A settlement driver may hold them at
    /// their computed positions through a landing
    /// ([`crate::settlement::Acceleration::hold_anchored`]).
    fn anchored_bodies(&self) -> Vec<usize> {
        Vec::new()
    }

    /// The generalised positions of every mobile body.
    fn configuration(&self) -> Configuration {
        self.configuration_of(&self.mobile_bodies())
    }

    /// Moves the bodies of `c` to its positions, sets every velocity to zero
    /// (an imposed velocity component to its value now) and rebuilds every
    /// derived state (contact memory, warm start, neighbour lists, forces,
    /// integrator history), so that the next step starts exactly from this
    /// configuration, as a system built there would. The clock goes on.
    ///
    /// # Errors
    /// [`crate::Error::Scene`] if `c` does not fit the engine (coordinates per
    /// body, unknown or fixed body, non-finite value); the engine is then unchanged.
    fn set_configuration(&mut self, c: &Configuration) -> Result<()>;

    /// The boundary bodies that move under their own dynamics ([`Boundary`]);
    /// none by default (NSCD: every moving body is in the configuration).
    fn boundaries(&self) -> Vec<Boundary> {
        Vec::new()
    }

    /// Moves the boundaries of [`Engine::boundaries`] to the coordinates `s` (m), at
    /// rest, and rebuilds the derived state as [`Engine::set_configuration`] does.
    ///
    /// # Errors
    /// [`crate::Error::Scene`] if `s` does not have one finite value per boundary;
    /// the engine is then unchanged.
    fn set_boundaries(&mut self, s: &[f64]) -> Result<()> {
        if s.is_empty() {
            Ok(())
        } else {
            Err(crate::Error::Scene(format!("boundaries: {} coordinates, the engine has none", s.len())))
        }
    }

    /// Relaxes the overlaps of the current configuration until the largest is at
    /// most `settings.tolerance` (Karrech et al. 2007, §4; the settlement
    /// driver's step after an extrapolation), moving the mobile bodies not in
    /// `settings.held`, then writes the result back as
    /// [`Engine::set_configuration`] does. NSCD: the projection that moves the
    /// rigid bodies least ([`crate::nscd::relax`]); MD: the minimum of the
    /// potential energy, eq. (29) ([`crate::md::relax`]).
    ///
    /// # Errors
    /// [`crate::Error::Scene`] for settings out of range; an engine error if a
    /// configuration tried cannot be evaluated. The positions are then unchanged.
    fn relax(&mut self, settings: &RelaxSettings) -> Result<RelaxReport>;
}

/// The refusal of [`Engine::change_solver`] by an engine without solver settings.
pub fn no_solver_settings(engine: &str) -> crate::Error {
    crate::Error::Scene(format!(
        "change_solver: the {engine} engine has no solver settings to change; resume with the scene the run \
         started from"
    ))
}
