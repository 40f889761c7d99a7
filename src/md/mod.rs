//! The MD engine: soft-contact molecular dynamics (discrete elements) of 3D
//! spheres, following Karrech et al., *A computational procedure for the
//! prediction of settlement in granular materials under cyclic loading*, CMAME 197
//! (2007) 80–94, §2, and David, García-Rojo, Herrmann, Luding, *Hysteresis and
//! creep in powders and grains*, §§2–3.
//!
//! Data flow of a step: [`integrator`] (velocity Verlet or Gear predictor) →
//! [`neighbours`] (linked cells → Verlet list with skin, rebuilt when needed;
//! [`ghosts`] for symmetry planes) → [`contact`] forces with the pair's [`law`]
//! (Hertz–Mindlin or linear spring–dashpot, tangential memory) → [`walls`] →
//! integrator (second kick or corrector) → servo walls. [`measure`] turns a state
//! into the papers' quantities.

pub mod contact;
pub mod contacts;
pub mod engine;
pub mod ghosts;
pub mod integrator;
pub mod law;
pub mod measure;
pub mod neighbours;
pub mod particles;
pub mod system;
pub mod walls;

pub use contacts::{MdContactInfo, MdContactKind};
pub use ghosts::{Ghosts, SymmetryPlane};
pub use integrator::{GearSet, Integrator};
pub use law::{Damping, LawTable, Material, Model, PairLaw};
pub use particles::{Particles, V3};
pub use system::{MdSettings, MdStepStats, MdSystem};
pub use walls::{Drive, History1, Motion, Shape, Wall};
