//! Ready-made scenes (as TOML text, so that they are saved and rerun like any
//! hand-written scene): the pentagon deposit of the Saussine ballast tests.

pub mod deposit;

pub use deposit::{pentagon_deposit, DepositSpec};
