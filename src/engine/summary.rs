//! [`StepSummary`]: the numbers every engine reports for one step, which the run loop folds into a run's
//! summary (`summary.json`, [`crate::run::RunSummary`]) and the statistics of Saussine et al. (2006), §3.2 (average
//! number of iterations) and §3.3 (interpenetration) are made of.

use serde::{Deserialize, Serialize};

/// The numbers every engine reports for one step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct StepSummary {
    /// Time at the end of the step (s).
    pub time: f64,
    /// Kinetic energy of the bodies at the end of the step (J).
    pub kinetic_energy: f64,
    /// Contacts (NSCD: detected, open ones within the alert distance included;
    /// MD: sphere–sphere, a contact with a symmetry image counting half, plus
    /// sphere–wall).
    pub contacts: f64,
    /// Mean overlap over the active contacts (m).
    pub mean_overlap: f64,
    /// Largest overlap (m).
    pub max_overlap: f64,
    /// NLGS sweeps of the step (NSCD; 0 for MD).
    pub iterations: u64,
    /// Whether the solver met its tolerance (NSCD; always true for MD).
    pub converged: bool,
    /// Final value of the solver's convergence norm (NSCD, dimensionless, to
    /// compare with its tolerance; 0 for MD).
    #[serde(default)]
    pub criterion: f64,
}
