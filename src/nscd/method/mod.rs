//! The NSCD method of one step, for any dimension of contact (Saussine et al. 2006, §2.7; Jean 1999): the
//! nonlinear block Gauss–Seidel over the rows of the step's problem ([`gauss_seidel`]), its convergence
//! policies and LMGC90's check pass ([`criterion`]), its settings ([`settings`]), the domain split that sweeps
//! two halves of a sample on two threads ([`split`]) and the accelerated projected gradient ([`apgd`]).
//!
//! Nothing here knows what a contact is: the method sees bodies as generalised velocities and inverse masses of
//! the dimension's degrees of freedom ([`Row::Dofs`]: `[u_x, u_y, ω]` in 2D, six components in 3D) and rows as
//! records that solve their own local law exactly from the current velocities ([`Row::visit`]). A dimension
//! brings its rows — in 2D the Signorini–Coulomb contact of law (11) with its 2×2 Delassus block
//! ([`super::contact::ContactRow`], [`super::coulomb`]) and the viscoelastic sublayer spring of law (17)
//! ([`super::sublayer::SpringRow`]) — and the method is the same code for each (a 3D engine adds its local law
//! with a 3×3 block, not a second solver; `tests/nscd_method.rs` runs it on a 3D point contact).
//!
//! The accelerated projected gradient ([`apgd`]) is the same code for every dimension too, over two more traits
//! of the rows ([`apgd::ConeRow`]: the contact's impulse vector and its projection on the law's set;
//! [`apgd::AffineRow`]: the spring's affine law). The interior point (`super::interior`) stays with the 2D law:
//! it solves the step as a linear complementarity problem, which only a polyhedral cone (2D) allows; a 3D cone
//! needs a second-order-cone form.

pub mod anderson;
pub mod apgd;
pub mod criterion;
pub mod gauss_seidel;
pub mod settings;
pub mod split;

pub use criterion::{Measure, Policy, SweepNorms};
pub use gauss_seidel::{
    apply_impulses, check, check_by_row, pass, remove_impulses, solve_nlgs, solve_nlgs_split, sweep, sweep_relaxed,
    NlgsProblem, NlgsReport, Pass,
};
pub use settings::{NlgsSettings, OnStall, Solver, DEFAULT_SPLIT_MIN_ROWS, DEFAULT_STALL_MAX_ITERATIONS};
pub use split::SplitWorkspace;

/// One row of a step's problem: a contact or a spring between two bodies, with its impulse and its local law.
///
/// The Gauss–Seidel method visits the rows in a fixed order; a visit computes the row's local velocity from the
/// two bodies' current velocities, solves the row's law exactly for its impulse with the other rows' impulses
/// held, and (when updating) writes the new impulse and adds its change, through `M⁻¹ H`, to the two bodies'
/// velocities. The norms of the convergence policies are accumulated from the change ([`SweepNorms::add`]).
pub trait Row: Copy + Send + Sync {
    /// The generalised velocity (and inverse mass) of one body in this dimension: `[f64; 3]` in 2D
    /// (`u_x, u_y, ω`), six components in 3D. A body whose inverse mass is `Default::default()` (all zero: fixed,
    /// or every component imposed) is never changed by a row.
    type Dofs: Copy + Default + PartialEq + Send + Sync + std::fmt::Debug + AsRef<[f64]> + AsMut<[f64]>;

    /// The two bodies of the row, candidate first; the second is `u32::MAX` for a world anchor.
    fn bodies(&self) -> (u32, u32);

    /// Renumbers the two bodies (the domain split gives each half its own numbering).
    fn set_bodies(&mut self, a: u32, b: u32);

    /// Takes the impulse of `other`, the same row in another numbering.
    fn take_impulse(&mut self, other: &Self);

    /// Adds `sign · M⁻¹ H P` of the row's impulse to the velocities `u` (`inv_m`: inverse masses).
    fn add_impulse(&self, u: &mut [Self::Dofs], inv_m: &[Self::Dofs], sign: f64);

    /// One visit: solves the local law from `u` and the row's impulse `P` (its velocity without its own
    /// impulse, `U_0 = H* u − W P`); with `omega` ≠ 1 the change is scaled by `omega` and projected back on
    /// the law; with `UPDATE` writes the new impulse and applies its change to `u`; adds the change's norms to
    /// `norms` (`ΔU = W ΔP` and the midpoint averages of [`SweepNorms::add`]).
    fn visit<const UPDATE: bool>(
        &mut self,
        u: &mut [Self::Dofs],
        inv_m: &[Self::Dofs],
        omega: f64,
        norms: &mut SweepNorms,
    );
}
