//! Relaxation of an extrapolated configuration (Karrech et al. 2007, §4): a
//! functional of the mobile bodies' positions minimised, with every other body
//! held, until the largest overlap is below a tolerance.
//!
//! Each engine supplies its functional ([`Functional`]: value, gradient, largest
//! overlap, the mass of each variable); this module minimises it with a
//! limited-memory BFGS method (argmin's `LBFGS`, a More–Thuente line search that
//! enforces the strong Wolfe conditions, so the functional decreases at every
//! iteration) or, as the baseline of the paper, steepest descent with the same
//! line search. Both work in mass-scaled coordinates `y = √m x` (one variable's
//! mass `m` in kg, or its moment of inertia in kg·m² for an angle), which makes
//! the functional's curvature the same for a light grain and a heavy sleeper.
//! The functional is divided by a constant so that the first step (the
//! gradient in the mass metric, for both methods) moves the most-pushed variable
//! by half the largest overlap: a unit step is then of the right size, and the
//! line search starts where it should. The minimisation stops as soon as the
//! largest overlap is at most the tolerance (the paper's criterion), when the line search can make no more
//! progress, or at `max_iterations`.
//!
//! The functionals: MD, eq. (29) (`crate::md::relax`); NSCD, the rigid analogue
//! (`crate::nscd::relax`, docs/relaxation.md).

use crate::error::{Error, Result};
use argmin::core::{
    CostFunction, Executor, Gradient, IterState, Problem, Solver, State, TerminationReason, TerminationStatus, KV,
};
use argmin::solver::gradientdescent::SteepestDescent;
use argmin::solver::linesearch::MoreThuenteLineSearch;
use argmin::solver::quasinewton::LBFGS;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;

/// The longest step a line search may take, in unit steps (module doc).
const MAX_STEP: f64 = 10.0;

/// A functional of the positions of the bodies a relaxation moves.
pub trait Functional {
    /// The mass of each variable (kg, or kg·m² for an angle), all positive; the
    /// number of variables is its length.
    fn metric(&self) -> Vec<f64>;

    /// The functional (J) at `x` (m or rad), and its gradient (N or N·m) into `grad`.
    ///
    /// # Errors
    /// An engine's error if the configuration cannot be evaluated (a runaway overlap).
    fn evaluate(&mut self, x: &[f64], grad: &mut [f64]) -> Result<f64>;

    /// The largest overlap at `x` (m), 0 without one.
    ///
    /// # Errors
    /// As [`Functional::evaluate`].
    fn max_overlap(&mut self, x: &[f64]) -> Result<f64>;
}

/// The minimiser of a relaxation.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Limited-memory BFGS (7 pairs) with a More–Thuente line search.
    #[default]
    Lbfgs,
    /// Steepest descent with the same line search: the paper's gradient method.
    GradientDescent,
}

/// What a relaxation is asked to do.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelaxSettings {
    /// Stop when the largest overlap is at most this (m), > 0.
    pub tolerance: f64,
    /// Iterations of the minimiser at most (≥ 1).
    pub max_iterations: u64,
    /// The minimiser.
    pub method: Method,
    /// Bodies held in place besides the fixed ones (indices in the engine).
    pub held: Vec<usize>,
}

impl RelaxSettings {
    /// Relaxation to `tolerance` (m) by L-BFGS in at most 10 000 iterations, nothing else held.
    pub fn new(tolerance: f64) -> Self {
        Self { tolerance, max_iterations: 10_000, method: Method::Lbfgs, held: Vec::new() }
    }

    /// Checks the ranges; the message names the field.
    pub fn check(&self) -> Result<()> {
        if !(self.tolerance > 0.0 && self.tolerance.is_finite()) {
            return Err(Error::Scene(format!(
                "settlement.relax_tolerance: must be a positive length (m), got {}",
                self.tolerance
            )));
        }
        if self.max_iterations == 0 {
            return Err(Error::Scene("settlement.relax_max_iterations: must be at least 1, got 0".into()));
        }
        Ok(())
    }
}

/// What a relaxation did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RelaxReport {
    /// The minimiser.
    pub method: Method,
    /// Iterations made.
    pub iterations: u64,
    /// Evaluations of the functional and its gradient.
    pub evaluations: u64,
    /// Largest overlap before (m).
    pub max_overlap_before: f64,
    /// Largest overlap after (m).
    pub max_overlap_after: f64,
    /// The functional (J) at the start and after each iteration.
    pub functional: Vec<f64>,
    /// Whether the largest overlap reached the tolerance.
    pub converged: bool,
    /// Why the minimiser stopped.
    pub reason: String,
    /// The largest displacement of a variable (m or rad).
    pub largest_move: f64,
}

/// What the minimiser has done so far, kept outside it: argmin gives nothing
/// back when a step fails (a line search that can make no more progress), and
/// the last accepted iterate is then the result.
#[derive(Default)]
struct Record {
    /// The last accepted iterate (scaled) and the largest overlap there.
    y: Option<Vec<f64>>,
    overlap: f64,
    /// The functional after each iteration (J).
    values: Vec<f64>,
    /// The scale the minimiser's functional is divided by.
    scale: f64,
    evaluations: u64,
    /// The functional's own error, if it failed.
    failure: Option<Error>,
}

/// A point (scaled), the functional there and its gradient.
type Evaluation = (Vec<f64>, f64, Vec<f64>);

/// The functional in mass-scaled variables, with one cached evaluation (the
/// line search asks for the value and the gradient at the same point).
struct Scaled<'a> {
    inner: RefCell<&'a mut dyn Functional>,
    inv_sqrt_m: Vec<f64>,
    /// The functional is divided by this (1/s²): a unit step of the first
    /// iteration then moves the variable pushed hardest by half the largest
    /// overlap (module doc).
    scale: f64,
    cache: RefCell<Option<Evaluation>>,
    record: Rc<RefCell<Record>>,
}

impl Scaled<'_> {
    fn unscale(&self, y: &[f64]) -> Vec<f64> {
        y.iter().zip(&self.inv_sqrt_m).map(|(y, s)| y * s).collect()
    }

    fn eval(&self, y: &[f64]) -> std::result::Result<(f64, Vec<f64>), argmin::core::Error> {
        if let Some((at, v, g)) = self.cache.borrow().as_ref() {
            if at.as_slice() == y {
                return Ok((*v, g.clone()));
            }
        }
        if y.iter().any(|v| !v.is_finite()) {
            // A minimiser out of curvature information (no progress left) can
            // propose this: refused, its last accepted iterate stands.
            return Err(argmin::core::Error::msg("a trial point is not finite"));
        }
        let x = self.unscale(y);
        let mut g = vec![0.0; x.len()];
        let v = match self.inner.borrow_mut().evaluate(&x, &mut g) {
            Ok(v) => v,
            Err(e) => return Err(self.fail(e)),
        };
        self.record.borrow_mut().evaluations += 1;
        // d/dy = (d/dx) / √m, on the functional divided by `scale`.
        let v = v / self.scale;
        g.iter_mut().zip(&self.inv_sqrt_m).for_each(|(g, s)| *g *= s / self.scale);
        *self.cache.borrow_mut() = Some((y.to_vec(), v, g.clone()));
        Ok((v, g))
    }

    fn overlap(&self, y: &[f64]) -> std::result::Result<f64, argmin::core::Error> {
        let x = self.unscale(y);
        let r = self.inner.borrow_mut().max_overlap(&x);
        r.map_err(|e| self.fail(e))
    }

    fn fail(&self, e: Error) -> argmin::core::Error {
        let msg = e.to_string();
        self.record.borrow_mut().failure = Some(e);
        argmin::core::Error::msg(msg)
    }
}

impl CostFunction for Scaled<'_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, y: &Vec<f64>) -> std::result::Result<f64, argmin::core::Error> {
        self.eval(y).map(|(v, _)| v)
    }
}

impl Gradient for Scaled<'_> {
    type Param = Vec<f64>;
    type Gradient = Vec<f64>;
    fn gradient(&self, y: &Vec<f64>) -> std::result::Result<Vec<f64>, argmin::core::Error> {
        self.eval(y).map(|(_, g)| g)
    }
}

type St = IterState<Vec<f64>, Vec<f64>, (), (), (), f64>;

/// A minimiser stopped as soon as the largest overlap meets the tolerance; it
/// records each accepted iterate.
struct UntilOverlap<S> {
    inner: S,
    tolerance: f64,
    record: Rc<RefCell<Record>>,
}

impl<'a, S: Solver<Scaled<'a>, St>> Solver<Scaled<'a>, St> for UntilOverlap<S> {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn init(
        &mut self,
        problem: &mut Problem<Scaled<'a>>,
        state: St,
    ) -> std::result::Result<(St, Option<KV>), argmin::core::Error> {
        self.inner.init(problem, state)
    }

    fn next_iter(
        &mut self,
        problem: &mut Problem<Scaled<'a>>,
        state: St,
    ) -> std::result::Result<(St, Option<KV>), argmin::core::Error> {
        let (state, kv) = self.inner.next_iter(problem, state)?;
        if state.terminated() {
            // The inner solver gave up (its line search failed: argmin keeps the
            // problem then); its iterate is the last accepted one.
            return Ok((state, kv));
        }
        let y = state.get_param().cloned().unwrap_or_default();
        let overlap = problem.problem("overlap", |f| f.overlap(&y))?;
        let mut r = self.record.borrow_mut();
        let value = state.get_cost() * r.scale;
        r.values.push(value);
        r.y = Some(y);
        r.overlap = overlap;
        if overlap <= self.tolerance {
            return Ok((state.terminate_with(TerminationReason::SolverConverged), kv));
        }
        Ok((state, kv))
    }

    fn terminate_internal(&mut self, state: &St) -> TerminationStatus {
        self.inner.terminate_internal(state)
    }

    fn terminate(&mut self, state: &St) -> TerminationStatus {
        self.inner.terminate(state)
    }
}

/// Minimises `f` from `x` (overwritten with the result) until its largest
/// overlap is at most `settings.tolerance`.
///
/// # Errors
/// [`Error::Scene`] for settings out of range or a metric that is not positive;
/// the functional's own error (a configuration that cannot be evaluated).
pub fn minimise(f: &mut dyn Functional, x: &mut [f64], settings: &RelaxSettings) -> Result<RelaxReport> {
    settings.check()?;
    let m = f.metric();
    if m.len() != x.len() {
        return Err(Error::Scene(format!("relaxation: {} masses for {} variables", m.len(), x.len())));
    }
    if let Some(i) = m.iter().position(|m| !(*m > 0.0 && m.is_finite())) {
        return Err(Error::Scene(format!("relaxation: variable {i} has mass {} (must be positive)", m[i])));
    }
    let before = f.max_overlap(x)?;
    let mut g = vec![0.0; x.len()];
    let start = f.evaluate(x, &mut g)?;
    let mut report = RelaxReport {
        method: settings.method,
        iterations: 0,
        evaluations: 1,
        max_overlap_before: before,
        max_overlap_after: before,
        functional: vec![start],
        converged: before <= settings.tolerance,
        reason: "no overlap above the tolerance".into(),
        largest_move: 0.0,
    };
    if report.converged || x.is_empty() {
        return Ok(report);
    }
    let sqrt_m: Vec<f64> = m.iter().map(|m| m.sqrt()).collect();
    let y0: Vec<f64> = x.iter().zip(&sqrt_m).map(|(x, s)| x * s).collect();
    // The first step of either method is the gradient in the mass metric,
    // `Δx = −∇F/(m S)`: S makes its largest component half the largest overlap.
    let accel = g.iter().zip(&m).map(|(g, m)| (g / m).abs()).fold(0.0, f64::max);
    let scale = if accel > 0.0 && before > 0.0 { accel / (0.5 * before) } else { 1.0 };
    let record = Rc::new(RefCell::new(Record { overlap: before, scale, ..Record::default() }));
    let problem = Scaled {
        inner: RefCell::new(f),
        inv_sqrt_m: sqrt_m.iter().map(|s| 1.0 / s).collect(),
        scale,
        cache: RefCell::new(None),
        record: record.clone(),
    };
    // Steps of at most ten times the unit step: an extrapolating line search
    // would otherwise try configurations with spheres inside one another.
    let search = MoreThuenteLineSearch::new()
        .with_bounds(0.0, MAX_STEP)
        .map_err(|e| Error::Scene(format!("relaxation: {e}")))?;
    let outcome = match settings.method {
        Method::Lbfgs => {
            let solver = LBFGS::new(search, 7)
                .with_tolerance_grad(0.0)
                .and_then(|s| s.with_tolerance_cost(0.0))
                .map_err(|e| Error::Scene(format!("relaxation: {e}")))?;
            run(problem, solver, y0, settings)
        }
        Method::GradientDescent => run(problem, SteepestDescent::new(search), y0, settings),
    };
    let mut rec = std::mem::take(&mut *record.borrow_mut());
    if let Some(e) = rec.failure.take() {
        return Err(e);
    }
    report.reason = match outcome {
        Ok(reason) => reason,
        // A line search that finds no lower point: the last iterate stands.
        Err(e) => format!("the line search stopped: {e}"),
    };
    if let Some(y) = rec.y {
        for ((xi, yi), s) in x.iter_mut().zip(&y).zip(&sqrt_m) {
            let new = yi / s;
            report.largest_move = report.largest_move.max((new - *xi).abs());
            *xi = new;
        }
        report.max_overlap_after = rec.overlap;
    }
    report.iterations = rec.values.len() as u64;
    report.evaluations += rec.evaluations;
    report.functional.extend(rec.values);
    report.converged = report.max_overlap_after <= settings.tolerance;
    Ok(report)
}

/// Runs the executor; the reason it stopped, or its error.
fn run<'a, S: Solver<Scaled<'a>, St>>(
    problem: Scaled<'a>,
    solver: S,
    y0: Vec<f64>,
    settings: &RelaxSettings,
) -> std::result::Result<String, argmin::core::Error> {
    let record = problem.record.clone();
    let wrapped = UntilOverlap { inner: solver, tolerance: settings.tolerance, record };
    let result = Executor::new(problem, wrapped).configure(|s| s.param(y0).max_iters(settings.max_iterations)).run()?;
    Ok(result.state.get_termination_reason().map_or("stopped".to_string(), |r| r.text().to_string()))
}

/// A penalised projection of rigid bodies (the 2D [`crate::plane::relax`] and 3D [`crate::space::relax`]
/// relaxations): a [`Functional`] whose penalty stiffness can be set.
pub trait Penalty: Functional {
    /// The heaviest free body's mass (kg): the stiffness's scale.
    fn heaviest(&self) -> f64;
    /// The penalty stiffness (N/m per contact point).
    fn stiffness(&self) -> f64;
    /// Sets the penalty stiffness (N/m per contact point).
    fn set_stiffness(&mut self, k: f64);
}

/// The rigid bodies' relaxation on a penalised projection (docs/relaxation.md): the stiffness starts at
/// `k = 10 m_max δ₀ / tol` and is raised tenfold, up to three times, while the minimiser stops short of the
/// tolerance within the iterations left; `x` goes from the start to the result. The report's `max_overlap_before`
/// is the start's; its `largest_move` the largest change of a variable (m or rad).
///
/// # Errors
/// As [`minimise`].
pub fn penalised_projection(p: &mut dyn Penalty, x: &mut [f64], settings: &RelaxSettings) -> Result<RelaxReport> {
    let start = x.to_vec();
    let before = p.max_overlap(x)?;
    p.set_stiffness(10.0 * p.heaviest().max(f64::MIN_POSITIVE) * (before / settings.tolerance).max(1.0));
    let mut report = minimise(p, x, settings)?;
    let mut raises = 0;
    while !report.converged && raises < 3 && report.iterations < settings.max_iterations {
        raises += 1;
        p.set_stiffness(p.stiffness() * 10.0);
        let left = RelaxSettings { max_iterations: settings.max_iterations - report.iterations, ..settings.clone() };
        let next = minimise(p, x, &left)?;
        report.iterations += next.iterations;
        report.evaluations += next.evaluations;
        // A raised stiffness is a new functional: its own sequence.
        report.functional = next.functional;
        report.max_overlap_after = next.max_overlap_after;
        report.converged = next.converged;
        report.reason = next.reason;
    }
    report.max_overlap_before = before;
    report.largest_move = x.iter().zip(&start).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    Ok(report)
}
