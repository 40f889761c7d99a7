//! The NLGS of the 2D engine: the dimension-generic method of [`super::method`] on the 2D rows (the contact of
//! law (11), [`super::contact::ContactRow`], and the sublayer spring of law (17), [`super::sublayer::SpringRow`]),
//! under the paths the 2D engine, its examples and benchmarks use.

use super::contact::ContactRow;
use super::sublayer::SpringRow;

pub use super::method::gauss_seidel::{
    apply_impulses, check, pass, remove_impulses, solve_nlgs, solve_nlgs_split, sweep, sweep_relaxed, NlgsReport, Pass,
};
pub use super::method::settings::{
    NlgsSettings, OnStall, Solver, DEFAULT_SPLIT_MIN_ROWS, DEFAULT_STALL_MAX_ITERATIONS,
};

/// A frozen 2D problem: free velocities, inverse masses and rows with zero impulses (for benchmarks and
/// diagnostics; see [`super::System::nlgs_problem`]).
pub type NlgsProblem = super::method::NlgsProblem<ContactRow, SpringRow>;

/// The buffers of the 2D split solve ([`super::method::split`]).
pub type SplitWorkspace = super::method::SplitWorkspace<ContactRow, SpringRow>;
