//! The NSCD engine: non-smooth contact dynamics of rigid 2D convex polygons and
//! discs (Moreau–Jean), following Saussine, Cholet, Gautier, Dubois, Bohatier,
//! Moreau, *Modelling ballast behaviour under dynamic loading. Part 1*, CMAME
//! 195 (2006) 2841–2859, §2.
//!
//! Data flow of a step: [`stepper`] (θ-method) → [`detection`] ([`broad_phase`]
//! grid, [`shadow_overlap`] / [`narrow_phase`]) → [`contact`] rows → [`nlgs`]
//! ([`coulomb`] local solver, [`sublayer`] springs, [`criterion`]; [`split`]:
//! two halves swept side by side on large problems).

pub mod bodies;
pub mod broad_phase;
pub mod contact;
pub mod coulomb;
pub mod criterion;
pub mod detection;
pub mod engine;
pub mod loads;
pub mod measure;
pub mod narrow_phase;
pub mod nlgs;
pub mod shadow_overlap;
pub mod split;
pub mod stepper;
pub mod sublayer;
pub mod system;

pub use bodies::{Bodies, BodyInfo};
pub use contact::ContactLaw;
pub use criterion::Policy;
pub use loads::{Harmonic, Imposed, Load};
pub use nlgs::NlgsSettings;
pub use sublayer::Spring;
pub use system::{ContactInfo, NscdParams, StepStats, System};
