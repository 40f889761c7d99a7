//! The settlement-acceleration procedure of Karrech et al. 2007 (§3–5, Fig. 10)
//! over either engine: compute k loading cycles, fit each mobile body's residual
//! displacement, extrapolate h cycles, write the positions back, relax the
//! overlaps, repeat.
//!
//! - [`law`]: the residual-displacement laws (linear, eq. 16; Shenton's
//!   logarithmic law, eqs. 17–21, through the origin or with a constant) behind
//!   one trait;
//! - [`estimate`]: the fit of a window of computed cycles, the extrapolation, the
//!   accuracy measures `g_u` and `f_ξ` (eqs. 13–14), the Chernoff bound (eq. 15)
//!   and the relative configuration error `E_r` (eq. 22);
//! - [`driver`]: the procedure of Fig. 10 over any [`crate::engine::Engine`]
//!   ([`Accelerated`]), its tables (`settlement.csv`, `jumps.csv`), summary and
//!   checkpoints;
//! - the figures and the errors against a full run are drawn from the folder ([`crate::report::settlement`]);
//! - a scene file's `[settlement]` table is run through it by [`crate::open::settle_file`] (`ballast run`);
//! - the relaxation after a jump is the engines' service ([`crate::engine::relax`]: an engine's functional
//!   minimised by L-BFGS, or the paper's steepest descent, until the largest overlap is below a tolerance).

pub mod driver;
pub mod estimate;
pub mod law;
pub mod smooth;
pub mod sweep;

pub use driver::{
    Accelerated, Acceleration, AccelerationOutcome, AccelerationProgress, AccelerationSummary, Adaptive, FolderFigures,
    JumpRow, Law, SettlementRow,
};
pub use estimate::{
    chernoff_cycles, chernoff_probability, configuration_error, extrapolate, extrapolate_within, fit, trend_moves, Fit,
    Training,
};
pub use law::{law_named, Linear, ResidualLaw, Shenton, ShentonDecelerating, ShentonOrigin};
pub use smooth::Smoothing;
