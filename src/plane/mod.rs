//! What the two 2D engines share (the NSCD engine, [`crate::nscd`], and the 2D
//! soft-contact MD engine, `md::planar`): rigid convex polygons, discs
//! and compounds as flat arrays ([`bodies`]), their loads and imposed
//! velocities ([`loads`]), the sublayer springs ([`springs`]), and Moreau's
//! contact detection (Saussine et al. 2006, §2.3): the tile grid
//! ([`broad_phase`]), the shadow overlap ([`shadow_overlap`]) and the
//! polygon–disc tests ([`narrow_phase`]), driven by [`detection`].

pub mod bodies;
pub mod broad_phase;
pub mod detection;
pub mod engine;
pub mod loads;
pub mod narrow_phase;
pub mod outputs;
pub mod relax;
pub mod rows;
pub mod shadow_overlap;
pub mod springs;
pub mod vtk;

use serde::Serialize;

pub use bodies::{Bodies, BodyInfo};
pub use detection::{ContactKey, Detector};
pub use loads::{Harmonic, Imposed, Load};
pub use springs::Spring;

/// A contact of a 2D engine as seen from outside, with its force: the mean over
/// the last step (NSCD), or at the last force evaluation (planar MD).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ContactInfo {
    /// Body index of the candidate (the body the force acts on).
    pub candidate: usize,
    /// Body index of the antagonist.
    pub antagonist: usize,
    /// Contact point (m), where it was detected (NSCD: at `q_m`).
    pub point: [f64; 2],
    /// Unit normal towards the candidate.
    pub normal: [f64; 2],
    /// Gap (m), negative for an overlap.
    pub gap: f64,
    /// Normal force on the candidate (N).
    pub r_n: f64,
    /// Tangential force on the candidate (N), along the normal turned by +90°.
    pub r_t: f64,
}
