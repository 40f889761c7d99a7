//! The engine contract, the bottom layer of the crate: the [`Engine`] trait that the run loop
//! ([`crate::run::Runner`]) and the settlement driver ([`crate::settlement`]) drive, and the vocabulary an
//! engine speaks to them — what a step measured ([`StepSummary`], [`Energies`]), its contacts
//! ([`ContactRow`], `contacts.csv`), its final state ([`FinalState`], `final.json`), the positions a cyclic
//! driver reads and writes back ([`Configuration`], [`Boundary`]) and the relaxation service every engine's
//! functional plugs into ([`relax`], Karrech et al. 2007, §4).
//!
//! Nothing here knows an engine, a scene file or a figure: the engines (`nscd/`, `md/`) implement the contract
//! above it, the scenes build them, and the run loop, the settlement driver and the studies drive them through
//! it. Adding an engine is a folder that implements [`Engine`] (ARCHITECTURE.md, "Adding an engine").

pub mod configuration;
pub mod contacts;
pub mod contract;
pub mod final_state;
pub mod relax;
pub mod summary;

pub use configuration::{Boundary, Configuration};
pub use contacts::{ContactKind, ContactRow};
pub use contract::{CycleCheck, Energies, Engine};
pub use final_state::{BodyState, FinalState, Spin, WallState};
pub use relax::{minimise, Functional, Method, RelaxReport, RelaxSettings};
pub use summary::StepSummary;
