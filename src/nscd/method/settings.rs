//! The settings of a step's solve ([`NlgsSettings`]: the policy and its tolerance, the sweep caps, the
//! over-relaxation, the split, the solver and what a stalled step does), the `[nscd]` keys of scenes
//! (`docs/scene-format.md`). The same for every dimension of contact.

use super::criterion::{Measure, Policy};

/// NLGS settings; [`NlgsSettings::default`] gives the defaults of scenes
/// (`[nscd]` of `docs/scene-format.md`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct NlgsSettings {
    /// Convergence policy ([`super::criterion`]); default [`Policy::Quad`].
    pub policy: Policy,
    /// Tolerance of the policy (dimensionless), in (0, 1); default 1e-4.
    pub tolerance: f64,
    /// Sweeps made at least, ≥ 1; default 1.
    pub min_iterations: usize,
    /// Sweeps made at most, ≥ `min_iterations`; default 1000. A step that
    /// reaches it without meeting the tolerance is counted as *not converged*:
    /// its impulses are those of the last sweep.
    pub max_iterations: usize,
    /// For `quad_max`: the maximum norm may reach `max_factor · tolerance`, ≥ 1;
    /// default 4.
    pub max_factor: f64,
    /// Alternate forward and backward sweeps (symmetric Gauss–Seidel); default false.
    pub symmetric: bool,
    /// Over-relaxation factor `ω` of the sweeps, in (0, 2) (dimensionless): each
    /// row's change is scaled by `ω` and projected back on its law
    /// ([`Pass::Relaxed`](super::Pass::Relaxed)); 1: plain Gauss–Seidel, the default. Safeguarded: a step
    /// whose per-sweep norm rises above twice its lowest goes on with `ω = 1`.
    #[serde(default = "default_relaxation")]
    pub relaxation: f64,
    /// Problems of at least this many rows (contacts + springs) are solved split
    /// in two halves swept side by side ([`super::split`]); 0: never; default
    /// [`DEFAULT_SPLIT_MIN_ROWS`].
    #[serde(default = "default_split_min_rows")]
    pub split_min_rows: usize,
    /// Where the policy's norms are measured ([`Measure`]); default [`Measure::Check`]
    /// (the energy policy is always measured over the sweeps).
    #[serde(default)]
    pub measure: Measure,
    /// The solver of each step ([`Solver`]); default [`Solver::Nlgs`].
    #[serde(default)]
    pub solver: Solver,
    /// What a step does when `max_iterations` sweeps have not met the tolerance
    /// ([`OnStall`]); default [`OnStall::Accept`].
    #[serde(default)]
    pub on_stall: OnStall,
    /// [`OnStall::Extend`]: sweeps made at most in all, ≥ `max_iterations`;
    /// default 10 × the default `max_iterations`.
    #[serde(default = "default_stall_max_iterations")]
    pub stall_max_iterations: usize,
    /// Depth `m` of the Anderson mixing of the sweeps ([`super::anderson`]), at most
    /// [`super::anderson::MAX_DEPTH`]; 0: plain sweeps, the default.
    #[serde(default)]
    pub anderson: usize,
}

/// The solver of each step's problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// Nonlinear Gauss–Seidel ([`super::gauss_seidel`]; the default).
    #[default]
    Nlgs,
    /// Up to 50 NLGS sweeps, then, if the step has not converged, the accelerated
    /// projected gradient of [`crate::nscd::apgd`] with its default options; the same
    /// stopping rule, `max_iterations` counted in sweep-equivalents; one thread.
    Apgd,
    /// Up to 50 NLGS sweeps, then, if the step has not converged, the interior point
    /// of `crate::nscd::interior` on the problem's complementarity form (at most 100
    /// iterations, a sparse LU each), then NLGS again up to `max_iterations` if it has
    /// not met the tolerance; the same stopping rule (residual policies only); one
    /// thread. Needs the crate's `faer` feature (on by default).
    InteriorPoint,
}

impl Solver {
    /// The name in scenes (`nlgs`, `apgd`, `interior_point`).
    pub fn name(self) -> &'static str {
        match self {
            Solver::Nlgs => "nlgs",
            Solver::Apgd => "apgd",
            Solver::InteriorPoint => "interior_point",
        }
    }

    /// The solver named `name` (as [`Solver::name`] writes it).
    pub fn from_name(name: &str) -> Option<Self> {
        [Solver::Nlgs, Solver::Apgd, Solver::InteriorPoint].into_iter().find(|s| s.name() == name)
    }

    /// Whether this build has the solver (`interior_point` needs the `faer` feature).
    pub fn available(self) -> bool {
        self != Solver::InteriorPoint || cfg!(feature = "faer")
    }

    /// Why this solver cannot stop on `policy` in this build, naming the scene key:
    /// the solvers other than NLGS stop on a residual, and `interior_point` needs `faer`.
    pub fn refusal(self, policy: Policy) -> Option<String> {
        if self != Solver::Nlgs && policy.over_sweeps() {
            return Some(format!(
                "nscd.solver: '{}' stops on a residual (strict, quad, quad_max), not on the {} criterion",
                self.name(),
                policy.name()
            ));
        }
        (!self.available()).then(|| {
            format!(
                "nscd.solver: '{}' needs the crate's `faer` feature, which this build was made without",
                self.name()
            )
        })
    }
}

/// What a step does when its sweeps reach `max_iterations` without meeting the
/// tolerance (a *stalled* step).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum OnStall {
    /// Keep the impulses of the last sweep and go on; the step is counted as not
    /// converged and its final criterion reported (the default).
    #[default]
    Accept,
    /// Keep iterating, up to `stall_max_iterations` sweeps in all; a step still
    /// short of the tolerance then is accepted as with [`OnStall::Accept`].
    Extend,
    /// Stop the run with [`crate::Error::Stalled`]; the system keeps the state of
    /// the start of the step.
    Stop,
}

impl OnStall {
    /// The name in scenes (`accept`, `extend`, `stop`).
    pub fn name(self) -> &'static str {
        match self {
            OnStall::Accept => "accept",
            OnStall::Extend => "extend",
            OnStall::Stop => "stop",
        }
    }

    /// The choice named `name` (as [`OnStall::name`] writes it).
    pub fn from_name(name: &str) -> Option<Self> {
        [OnStall::Accept, OnStall::Extend, OnStall::Stop].into_iter().find(|o| o.name() == name)
    }
}

/// Default of [`NlgsSettings::stall_max_iterations`].
pub const DEFAULT_STALL_MAX_ITERATIONS: usize = 10_000;

fn default_relaxation() -> f64 {
    1.0
}

fn default_stall_max_iterations() -> usize {
    DEFAULT_STALL_MAX_ITERATIONS
}

/// Default of [`NlgsSettings::split_min_rows`]: below it a sweep is too short
/// (a few µs) for two threads to pay for their synchronisation.
pub const DEFAULT_SPLIT_MIN_ROWS: usize = 512;

fn default_split_min_rows() -> usize {
    DEFAULT_SPLIT_MIN_ROWS
}

impl NlgsSettings {
    /// The scene keys of these settings (`[nscd]` of `docs/scene-format.md`), in the order [`Self::changes`]
    /// reports them: the NSCD engines' [`crate::engine::Engine::SOLVER_KEYS`], which a run resumed with other
    /// solver settings may change ([`crate::run::solver_change`]).
    pub const SCENE_KEYS: [&'static str; 12] = [
        "nscd.criterion",
        "nscd.tolerance",
        "nscd.min_iterations",
        "nscd.max_iterations",
        "nscd.max_factor",
        "nscd.symmetric",
        "nscd.relaxation",
        "nscd.anderson",
        "nscd.measure",
        "nscd.solver",
        "nscd.on_stall",
        "nscd.stall_max_iterations",
    ];

    /// The values of [`Self::SCENE_KEYS`], as a scene writes them.
    fn scene_values(&self) -> [String; 12] {
        [
            self.policy.name().into(),
            self.tolerance.to_string(),
            self.min_iterations.to_string(),
            self.max_iterations.to_string(),
            self.max_factor.to_string(),
            self.symmetric.to_string(),
            self.relaxation.to_string(),
            self.anderson.to_string(),
            self.measure.name().into(),
            self.solver.name().into(),
            self.on_stall.name().into(),
            self.stall_max_iterations.to_string(),
        ]
    }

    /// The settings of `new` that differ from these, as `[scene key, before, after]` in the order of
    /// [`Self::SCENE_KEYS`] (what a run resumed with other solver settings records,
    /// [`crate::run::solver_change`]); `split_min_rows`, which no scene sets, last under its field name.
    pub fn changes(&self, new: &NlgsSettings) -> Vec<[String; 3]> {
        let keys = Self::SCENE_KEYS.map(String::from);
        let split = |s: &Self| s.split_min_rows.to_string();
        let pairs = keys.into_iter().zip(self.scene_values().into_iter().zip(new.scene_values()));
        pairs
            .chain(std::iter::once(("split_min_rows".to_string(), (split(self), split(new)))))
            .filter(|(_, (x, y))| x != y)
            .map(|(k, (x, y))| [k, x, y])
            .collect()
    }

    /// Whether a problem of `rows` rows (contacts + springs) is solved split in two halves
    /// ([`Self::split_min_rows`]; 0: never).
    pub fn splits(&self, rows: usize) -> bool {
        self.split_min_rows > 0 && rows >= self.split_min_rows
    }

    /// Sweeps a step may make: `max_iterations`, or under [`OnStall::Extend`] the
    /// larger of it and `stall_max_iterations`.
    pub fn sweep_cap(&self) -> usize {
        match self.on_stall {
            OnStall::Extend => self.stall_max_iterations.max(self.max_iterations),
            _ => self.max_iterations,
        }
    }
}

impl Default for NlgsSettings {
    fn default() -> Self {
        Self {
            policy: Policy::Quad,
            tolerance: 1e-4,
            min_iterations: 1,
            max_iterations: 1000,
            max_factor: 4.0,
            symmetric: false,
            relaxation: 1.0,
            split_min_rows: DEFAULT_SPLIT_MIN_ROWS,
            measure: Measure::default(),
            solver: Solver::default(),
            on_stall: OnStall::default(),
            stall_max_iterations: DEFAULT_STALL_MAX_ITERATIONS,
            anderson: 0,
        }
    }
}
