//! Accelerated projected gradient (APGD) for the per-step problem, an
//! alternative to [`super::gauss_seidel`] where Gauss–Seidel stalls (method and
//! measurements: `docs/accelerated-solver.md`).
//!
//! **Method.** Nesterov's accelerated projected gradient with adaptive
//! (gradient) restart and step-size backtracking, as Chrono's APGD: Mazhar,
//! Heyn, Negrut, Tasora, *Using Nesterov's method to accelerate multibody
//! dynamics with friction and contact*, ACM TOG 34(3) 32 (2015), Algorithm 2.
//! The global Delassus operator `N = H* M⁻¹ H` is never assembled: it is applied
//! through the bodies, a change `ΔP` of the impulses adds `M⁻¹ H ΔP` to the body
//! velocities (a *scatter*, as NLGS's update) and the local velocities are read
//! back as `H* u` (a *gather*, as NLGS's `U_0`).
//!
//! **Formulation.** The exact Coulomb law with normal thresholds is not the cone
//! complementarity problem APGD solves in Chrono (whose fixed point differs: the
//! normal velocity is dilated by `μ |U_T|`). Here, with a friction bound `g_α`
//! per contact and a normal threshold `c_α`, the impulses minimise the convex
//! quadratic
//! `f(P) = ½ Pᵀ N P + Pᵀ (H* u_free − c + shift_t) + Σ_springs (P_s − hα_s)² / (2 hβ_s)`
//! over the box `P_N ≥ 0, |P_T| ≤ g_α` (springs: `P_s ≥ 0` if compression-only,
//! free otherwise). Its gradient is the vector of local velocities `U_N − c_α`,
//! `U_T + shift_t` (springs: `U_s + (P_s − hα_s)/hβ_s`), so the KKT conditions are,
//! per contact, Signorini with threshold `c_α` and Tresca friction with bound
//! `g_α`, and per spring exactly its affine law `P_s = hα_s − hβ_s U_s`
//! ([`SpringRow::solve`](crate::nscd::sublayer::SpringRow::solve); springs are therefore *in* the QP, a quadratic energy
//! with a diagonal term `1/hβ_s`). The Coulomb law is recovered as a fixed point
//! on the bound ([`FrictionBound`]): either `g_α = μ P_N` of the point being
//! projected, in every projection (one loop, [`FrictionBound::Iterate`]), or a
//! Tresca problem solved with `g_α = μ P_N` of the previous outer iterate
//! ([`FrictionBound::Outer`]); both have the NLGS solutions as their fixed
//! points. The normal law of [`crate::nscd::coulomb::solve`] is "open if
//! `U_0N ≥ s_open`, else `U_N = c_closed`" (`U_0` without the row's own impulse):
//! for `s_open = c_closed` (no restitution, every contact of the scenes so far)
//! it is Signorini with threshold `c_α = c_closed`; for `s_open < c_closed` it is
//! not monotone, and `c_α` is a label fixed during the inner iterations —
//! `c_closed` for a contact whose `U_0N < s_open`, `s_open` otherwise —
//! relabelled from the iterate at every check, the label being consistent with
//! NLGS's law at a fixed point.
//!
//! **Convergence** is judged as in NLGS with `measure = check`: the iterate is
//! written into the rows (`p`) and the body velocities (`u`), and
//! [`super::check`] (exact local solve of every row, nothing updated) is
//! evaluated with the same policy ([`crate::nscd::method::criterion::evaluate`]). The check is
//! made when a cheap proxy (the policy's norms of the change of the iterate over
//! one iteration) times the last measured check/proxy ratio meets the tolerance,
//! at least every [`ApgdOptions::check_every`] iterations, and at the cap. The
//! iterates are not monotone: a step that reaches the cap returns the best
//! checked iterate (as Chrono returns the one of least residual).
//!
//! **Work** is counted in sweep-equivalents: a scatter or a gather over all rows
//! is half a sweep (an NLGS sweep is one gather and one scatter per row), a check
//! a full one (a gather and a local solve per row). An iteration is one gather
//! (gradient at the extrapolated point) and one scatter (the projected step),
//! plus one scatter per backtracking retry; the set-up costs one scatter and the
//! exact recomputation of the velocities at the end another. The per-body vector
//! operations (momentum, backtracking test) are not counted (bodies are about a
//! third of the rows). `iterations` of the report is the rounded-up total, and
//! the cap `max_iterations` is in the same unit.

//!
//! **Dimension.** The method is written over two traits of the rows, beside [`super::Row`]: a contact
//! ([`ConeRow`]) gives its impulse as a vector, its local velocity, gradient, threshold label, the diagonal and
//! largest eigenvalue of its Delassus block, and its projection on the law's convex set (in 2D `P_N ≥ 0`,
//! `|P_T| ≤ g_α`: an interval; in 3D a disc); a spring ([`AffineRow`]) its axial velocity and affine law. The
//! 2D rows implement both (`crate::nscd::contact`, `crate::nscd::sublayer`), and so do the 3D ones
//! (`crate::nscd::d3::contact`, `crate::nscd::d3::spring`).
//!
//! Files: this one (the traits, the options and the iteration), `stages.rs` (the workspace and each stage of
//! an iteration).

mod stages;

use super::criterion::{evaluate, SweepNorms};
use super::gauss_seidel::{check, solve_nlgs, NlgsReport};
use super::settings::NlgsSettings;
use super::Row;
pub use stages::ApgdWorkspace;

/// A contact row the accelerated projected gradient solves: its impulse a vector of the contact's dimension
/// (`(P_N, P_T)` in 2D), projected on its law's convex set.
pub trait ConeRow: Row {
    /// The impulse `(P_N, P_T…)` (N·s): `[f64; 2]` in 2D, `[f64; 3]` in 3D.
    type Impulse: Copy + Default + PartialEq + Send + Sync + std::fmt::Debug + AsRef<[f64]> + AsMut<[f64]>;

    /// The row's impulse.
    fn impulse(&self) -> Self::Impulse;

    /// Sets the row's impulse.
    fn set_impulse(&mut self, p: Self::Impulse);

    /// The normal component `P_N` of the impulse (N·s).
    fn normal(&self) -> f64;

    /// The friction coefficient `μ`.
    fn mu(&self) -> f64;

    /// The local velocity `H* u` (m/s), without threshold nor shift.
    fn local_velocity(&self, u: &[Self::Dofs]) -> Self::Impulse;

    /// The gradient of the quadratic at local velocity `v` with normal threshold `c` (m/s): `U_N − c`, and the
    /// tangential components with their restitution shift.
    fn gradient(&self, v: Self::Impulse, c: f64) -> Self::Impulse;

    /// The normal threshold label of the row from the iterate `u` (module text).
    fn label(&self, u: &[Self::Dofs]) -> f64;

    /// The diagonal of the local Delassus block (1/kg), the scales of the preconditioned step.
    fn diagonal(&self) -> Self::Impulse;

    /// The largest eigenvalue of the local Delassus block (1/kg).
    fn lambda_max(&self) -> f64;

    /// `x` projected on the law's set: `P_N ≥ 0` and the tangential part within `μ P_N` of the projected point
    /// (`tresca` `None`) or within the given Tresca bound.
    fn project(&self, x: Self::Impulse, tresca: Option<f64>) -> Self::Impulse;

    /// Adds `sign · M⁻¹ H p` of the impulse `p` (not necessarily the row's) to `u`.
    fn add_impulse_of(&self, u: &mut [Self::Dofs], inv_m: &[Self::Dofs], p: Self::Impulse, sign: f64);

    /// Adds the norms of a change of the impulse from `p` to `q` ([`SweepNorms::add`]).
    fn add_norms(&self, norms: &mut SweepNorms, p: Self::Impulse, q: Self::Impulse, changed: bool);
}

/// A spring row of the quadratic: a scalar impulse along its axis and the affine law `P = hα − hβ U`.
pub trait AffineRow: Row {
    /// The impulse (N·s).
    fn impulse(&self) -> f64;

    /// Sets the impulse.
    fn set_impulse(&mut self, p: f64);

    /// The relative axial velocity (m/s).
    fn axial_velocity(&self, u: &[Self::Dofs]) -> f64;

    /// `hα` (N·s).
    fn h_alpha(&self) -> f64;

    /// `hβ` (N·s per m/s).
    fn h_beta(&self) -> f64;

    /// The Delassus scalar `w` (1/kg).
    fn w(&self) -> f64;

    /// Whether the impulse is clamped to `P ≥ 0`.
    fn compression_only(&self) -> bool;

    /// The exact local solution given `U_0`, the velocity without the row's impulse.
    fn solve_affine(&self, u0: f64) -> f64;

    /// Adds `sign · M⁻¹ h p` of the impulse `p` to `u`.
    fn add_impulse_of(&self, u: &mut [Self::Dofs], inv_m: &[Self::Dofs], p: f64, sign: f64);
}

/// How the friction bound `g_α` of the box is set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrictionBound {
    /// `|P_T| ≤ μ P_N` with `P_N` of the projected point itself, in every
    /// projection: one loop whose fixed points are the Coulomb solutions, but the
    /// feasible set moves with the iterate (no convexity guarantee).
    Iterate,
    /// Tresca: `g_α = μ P_N` frozen during the inner (convex) iterations and
    /// updated from the iterate at every check that fails.
    Outer,
}

/// Options of the accelerated solver ([`ApgdOptions::default`] is what
/// [`solve_apgd`] uses).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApgdOptions {
    /// How the friction bound is set; default [`FrictionBound::Iterate`].
    pub friction: FrictionBound,
    /// Diagonal (Jacobi) preconditioning: row `α`'s step is scaled by
    /// `1/W_NN`, `1/W_TT` (springs `1/(w + 1/hβ)`), i.e. the method runs in the
    /// metric of the diagonal of `N`; default true.
    pub precondition: bool,
    /// "NLGS then accelerate": plain NLGS ([`super::solve_nlgs`], same
    /// policy) for at most this many sweeps, then, if it has not converged, the
    /// accelerated iterations from its iterate; 0: none; default 50 (measured
    /// best of 0, 20, 50, 200: `docs/accelerated-solver.md`).
    pub nlgs_first: usize,
    /// A check is made at least every this many iterations, ≥ 1; default 25.
    pub check_every: usize,
    /// Adaptive restart of the momentum (O'Donoghue and Candès' gradient test, as
    /// in Mazhar et al.); default true.
    pub restart: bool,
    /// Factor applied to the Lipschitz estimate `L` after every iteration, in
    /// (0, 1] (Chrono: 0.9); default 0.9.
    pub l_decay: f64,
    /// Fall back to plain NLGS (from the best checked iterate, for the rest of
    /// the sweep budget) after this many checks in a row without improving on the
    /// best; 0: never; default 0.
    pub fallback: usize,
}

impl Default for ApgdOptions {
    fn default() -> Self {
        Self {
            friction: FrictionBound::Iterate,
            precondition: true,
            nlgs_first: 50,
            check_every: 25,
            restart: true,
            l_decay: 0.9,
            fallback: 0,
        }
    }
}

/// Solves the step's problem by APGD with the default options ([`ApgdOptions`])
/// and a fresh workspace. Same contract as [`super::solve_nlgs`]: `u` comes
/// in as `u_free + M⁻¹ H P` of the rows' warm-start impulses and leaves as the
/// final velocities, the rows' `p` as the impulses; `iterations` counts
/// sweep-equivalents (module text).
pub fn solve_apgd<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    solve_apgd_with(settings, &ApgdOptions::default(), &mut ApgdWorkspace::default(), u, inv_m, rows, springs)
}
/// [`solve_apgd`] with options and a reused workspace.
#[allow(clippy::too_many_arguments)]
pub fn solve_apgd_with<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    opts: &ApgdOptions,
    ws: &mut ApgdWorkspace<R>,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    if rows.is_empty() && springs.is_empty() {
        return NlgsReport { iterations: 0, criterion: 0.0, converged: true };
    }
    let s = settings;
    let cap = 2 * s.max_iterations.max(1);
    let mut halves = 0usize; // work in half sweeps
    let report = |halves: usize, criterion: f64, converged: bool| NlgsReport {
        iterations: halves.div_ceil(2),
        criterion,
        converged,
    };

    // "NLGS then accelerate": plain NLGS (same stopping rule) for at most
    // `nlgs_first` sweeps, the accelerated iterations only if it has not converged.
    if opts.nlgs_first > 0 {
        let first = NlgsSettings { max_iterations: opts.nlgs_first.min(s.max_iterations), ..*s };
        let r = solve_nlgs(&first, u, inv_m, rows, springs);
        if r.converged || r.iterations >= s.max_iterations {
            return r;
        }
        halves += 2 * r.iterations;
    }

    let mut l = ws.set_up(opts, u, inv_m, rows, springs);
    halves += 1;
    let mut theta: f64 = 1.0;
    let mut ratio = 1.0;
    let mut since_check = 0usize;
    let mut previous_wpp = 0.0;
    let mut last;
    let mut best_value = f64::INFINITY;
    let mut stagnant = 0usize;
    let mut fall_back = false;
    loop {
        ws.gradient(u, rows, springs);
        halves += 1;
        ws.projected_step(opts, &mut l, (&mut halves, cap), u, inv_m, rows, springs);
        let (proxy, restart_dot) = ws.proxy(rows, springs);
        if opts.restart && restart_dot > 0.0 {
            theta = 1.0;
            ws.restart(u, rows, springs);
        } else {
            theta = ws.extrapolate(theta, u, rows, springs);
        }
        l *= opts.l_decay;

        // Convergence, judged by NLGS's check.
        let (value, _) = evaluate(s.policy, s.tolerance, s.max_factor, &proxy, previous_wpp);
        previous_wpp = proxy.sum_wpp;
        since_check += 1;
        let at_cap = halves + 2 >= cap;
        if at_cap || ratio * value < s.tolerance || since_check >= opts.check_every.max(1) {
            let norms = check(u, inv_m, rows, springs);
            halves += 2;
            since_check = 0;
            last = evaluate(s.policy, s.tolerance, s.max_factor, &norms, 0.0);
            if value > 0.0 && last.0.is_finite() {
                ratio = (last.0 / value).clamp(1e-3, 1e3);
            }
            if (last.1 && halves.div_ceil(2) >= s.min_iterations) || at_cap {
                break;
            }
            stagnant += 1;
            if last.0 < best_value {
                stagnant = 0;
                best_value = last.0;
                ws.keep_best(rows, springs);
            }
            if opts.fallback > 0 && stagnant >= opts.fallback {
                fall_back = true;
                break;
            }
            if ws.outer_update(opts, u, rows) {
                theta = 1.0;
                ws.restart(u, rows, springs);
            }
        }
    }

    // APGD is not monotone: at the cap, the best checked iterate is returned.
    if (fall_back || !last.1) && best_value < last.0 {
        last.0 = best_value;
        ws.take_best(rows, springs);
    }
    ws.recompute(u, inv_m, rows, springs);
    halves += 1;
    if fall_back {
        let done = halves.div_ceil(2);
        let rest = NlgsSettings { max_iterations: s.max_iterations.saturating_sub(done).max(1), ..*s };
        let r = solve_nlgs(&rest, u, inv_m, rows, springs);
        return NlgsReport { iterations: done + r.iterations, ..r };
    }
    report(halves, last.0, last.1)
}
