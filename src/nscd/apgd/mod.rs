//! The accelerated projected gradient on the 2D rows: the dimension-generic method of
//! [`super::method::apgd`] (Nesterov's APGD with restart and backtracking, the NSCD law's thresholds and
//! friction bound as fixed points; `docs/accelerated-solver.md`) on the contact of law (11), whose impulse
//! `(P_N, P_T)` is projected on `P_N ≥ 0`, `|P_T| ≤ g_α`, and the sublayer spring of law (17), under the paths
//! the 2D engine, its examples and benchmarks use.

#[cfg(test)]
mod tests;

use super::contact::ContactRow;

pub use super::method::apgd::{solve_apgd, solve_apgd_with, ApgdOptions, FrictionBound};

/// The buffers of the 2D accelerated solve.
pub type ApgdWorkspace = super::method::apgd::ApgdWorkspace<ContactRow>;
