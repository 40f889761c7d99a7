//! Ready-made scenes (as TOML text, so that they are saved and rerun like any
//! hand-written scene): the pentagon deposit of the Saussine ballast tests
//! ([`deposit`]), and the full Saussine sample with its sublayer, side walls or
//! free bank, and loaded sleeper ([`saussine`]).

pub mod deposit;
pub mod karrech;
pub mod luding;
pub mod md_bed;
pub mod md_text;
pub mod saussine;

pub use deposit::{pentagon_deposit, DepositSpec};
