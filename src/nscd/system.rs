//! The NSCD system: bodies, springs, contact laws, parameters, clock and the
//! warm-start memory, all plain serde-serializable data so a driver can read and
//! set every body's state, checkpoint and resume. Scratch buffers are rebuilt
//! on demand and never serialized.

use super::bodies::Bodies;
use super::contact::{ContactGeom, ContactLaw, ContactRow};
use super::detection::Detector;
use super::nlgs::NlgsSettings;
use super::sublayer::{Spring, SpringRow};
use crate::geometry::Vec2;
use serde::{Deserialize, Serialize};

pub(crate) use crate::plane::bodies::default_alert_distance;
pub use crate::plane::bodies::DEFAULT_ALERT_FRACTION;

/// Time-stepping parameters. [`NscdParams::default`] gives the defaults of
/// scenes (`[simulation]` and `[nscd]` of `docs/scene-format.md`), but for the
/// time step, which a scene must give.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NscdParams {
    /// Time step `h` (s), > 0; default 1e-3 (scenes must give it).
    pub dt: f64,
    /// θ of the θ-method, in [0.5, 1]; default 0.5 (Saussine et al. 2006 §2.2:
    /// θ = 1/2 conserves energy between impacts).
    pub theta: f64,
    /// Gravity (m/s²); default `[0, −9.81]`.
    pub gravity: [f64; 2],
    /// Alert distance (m), ≥ 0: pairs closer than this are contacts (possibly
    /// open). Each step it is raised to `2 h v_max` if the fastest body needs it.
    /// Default 1e-4 m here, whatever the bodies; a scene's default is
    /// [`DEFAULT_ALERT_FRACTION`] × the smallest inner radius of its mobile
    /// bodies, which a system built in code gets from
    /// [`super::Bodies::default_alert_distance`].
    pub alert_distance: f64,
    /// NLGS settings ([`NlgsSettings::default`]).
    pub nlgs: NlgsSettings,
}

impl Default for NscdParams {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            theta: 0.5,
            gravity: [0.0, -9.81],
            alert_distance: crate::plane::bodies::EMPTY_ALERT_DISTANCE,
            nlgs: NlgsSettings::default(),
        }
    }
}

impl NscdParams {
    /// Checks the ranges the scheme needs; the message names the parameter.
    pub fn check(&self) -> crate::Result<()> {
        let bad = |what: &str, v: f64| Err(crate::Error::Scene(format!("{what}: out of range, got {v}")));
        if !(self.dt.is_finite() && self.dt > 0.0) {
            return bad("simulation.dt", self.dt);
        }
        if !(0.5..=1.0).contains(&self.theta) {
            return bad("nscd.theta (must be in [0.5, 1])", self.theta);
        }
        if !(self.alert_distance.is_finite() && self.alert_distance >= 0.0) {
            return bad("nscd.alert_distance", self.alert_distance);
        }
        let n = &self.nlgs;
        if !(n.tolerance.is_finite() && n.tolerance > 0.0) {
            return bad("nscd.tolerance", n.tolerance);
        }
        if n.min_iterations < 1 || n.max_iterations < n.min_iterations {
            return bad("nscd.max_iterations (must be >= min_iterations >= 1)", n.max_iterations as f64);
        }
        if !(n.relaxation > 0.0 && n.relaxation < 2.0) {
            return bad("nscd.relaxation (must be in (0, 2))", n.relaxation);
        }
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return bad("simulation.gravity", self.gravity[0] + self.gravity[1]);
        }
        if let Some(why) = n.solver.refusal(n.policy) {
            return Err(crate::Error::Scene(why));
        }
        Ok(())
    }
}

/// Statistics of one time step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StepStats {
    /// Time at the end of the step (s).
    pub time: f64,
    /// Steps made by the system, this one included.
    pub step: u64,
    /// Contacts detected (open ones within the alert distance included).
    pub contacts: usize,
    /// Contacts carrying a force or overlapping at the end of the step.
    pub active_contacts: usize,
    /// NLGS sweeps made.
    pub iterations: usize,
    /// Final value of the convergence norm.
    pub criterion: f64,
    /// Whether the policy met its tolerance before `max_iterations`.
    pub converged: bool,
    /// Mean overlap over the active contacts at the end of the step (m).
    pub mean_overlap: f64,
    /// Largest overlap at the end of the step (m).
    pub max_overlap: f64,
    /// Sum of the overlaps of all contacts at the end of the step (m): the
    /// "cumulated interpenetration" of Saussine et al. (2006), Fig. 2.
    pub total_overlap: f64,
    /// Kinetic energy at the end of the step (J).
    pub kinetic_energy: f64,
}

pub use crate::plane::ContactInfo;

/// Reused buffers.
#[derive(Debug, Clone, Default)]
pub(crate) struct Workspace {
    pub q_i: Vec<[f64; 3]>,
    pub u_i: Vec<[f64; 3]>,
    pub q_m: Vec<[f64; 3]>,
    pub rows: Vec<ContactRow>,
    pub geoms: Vec<ContactGeom>,
    pub spring_rows: Vec<SpringRow>,
    pub detector: Detector,
    pub split: super::nlgs::SplitWorkspace,
    /// Buffers of the Anderson mixing of the sweeps (`nscd.anderson`): the history when the problem is not
    /// split, and the step's free velocities.
    pub anderson: super::method::anderson::AndersonWorkspace<[f64; 3]>,
    /// Buffers of the accelerated solver ([`super::apgd`]).
    pub apgd: super::apgd::ApgdWorkspace,
    /// Buffers of the interior-point solver (`super::interior`).
    #[cfg(feature = "faer")]
    pub interior: super::interior::InteriorWorkspace,
    /// Threads of the NLGS sweeps (0 or 1: one); not part of the state.
    pub threads: usize,
}

/// The complete state of an NSCD simulation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct System {
    /// Time step, θ, gravity, alert distance, NLGS settings.
    pub params: NscdParams,
    /// The bodies: shapes, masses, positions `q` (x, y, θ) and velocities `u`.
    pub bodies: Bodies,
    /// Sublayer springs (law (17) of Saussine et al. 2006).
    pub springs: Vec<Spring>,
    /// Contact law of material pair `(i, j)` at `i * materials + j`.
    pub laws: Vec<ContactLaw>,
    /// Number of materials.
    pub materials: usize,
    /// Time (s) and number of steps done. The time is recomputed each step as
    /// `t_0 + (step − k_0) · dt` from [`System::origin`], never accumulated, so it does not
    /// drift over millions of steps; [`System::set_dt`] rebases the origin.
    pub time: f64,
    /// Steps done.
    pub step: u64,
    /// The clock's origin: the time and step at which the time step last changed.
    #[serde(flatten)]
    pub origin: crate::clock::Origin,
    /// Contacts of the last step and their impulses `(P_N, P_T)` (N·s), sorted by
    /// key: the warm start of the next step.
    pub contacts: Vec<ContactGeom>,
    /// Impulses `(P_N, P_T)` (N·s) of `contacts`, in the same order.
    pub impulses: Vec<[f64; 2]>,
    /// Zero of the gravitational energy, as a height along `−g` (m): the lowest
    /// point of the non-fixed bodies when the first step is made (fixed for the
    /// run, so that `E_k + E_p` is conserved without dissipation).
    #[serde(default)]
    pub gravity_reference: Option<f64>,
    #[serde(skip)]
    pub(crate) ws: Workspace,
}

impl System {
    /// An empty system with `materials` materials (indices `0..materials`) whose
    /// pairs all have the default law ([`ContactLaw::default`]: frictionless,
    /// plastic, as a scene's pairs without a `[[contact]]`); change a pair's with
    /// [`System::set_law`]. Every pair of materials interacts: there is no pair
    /// without a law. Push bodies into [`System::bodies`]
    /// ([`super::BodyInfo::polygon`] and its siblings give the mass and the
    /// centroid to push at).
    pub fn new(params: NscdParams, materials: usize) -> Self {
        Self {
            params,
            bodies: Bodies::default(),
            springs: Vec::new(),
            laws: vec![ContactLaw::default(); materials * materials],
            materials,
            time: 0.0,
            step: 0,
            origin: crate::clock::Origin::default(),
            contacts: Vec::new(),
            impulses: Vec::new(),
            gravity_reference: None,
            ws: Workspace::default(),
        }
    }

    /// Changes the time step (s) from now on, keeping the clock exact.
    pub fn set_dt(&mut self, dt: f64) {
        self.origin.rebase(self.time, self.step);
        self.params.dt = dt;
    }

    /// Sets the contact law between materials `i` and `j` (both orders); a pair
    /// never set keeps [`ContactLaw::default`] (frictionless, plastic).
    ///
    /// # Panics
    /// If `i` or `j` is not below [`System::materials`].
    pub fn set_law(&mut self, i: usize, j: usize, law: ContactLaw) {
        self.laws[i * self.materials + j] = law;
        self.laws[j * self.materials + i] = law;
    }

    #[inline]
    pub(crate) fn law(&self, a: usize, b: usize) -> &ContactLaw {
        &self.laws[self.bodies.info[a].material * self.materials + self.bodies.info[b].material]
    }

    /// Contacts of the last step with their mean forces (N).
    pub fn contact_forces(&self) -> impl Iterator<Item = ContactInfo> + '_ {
        let h = self.params.dt;
        self.contacts.iter().zip(&self.impulses).map(move |(g, p)| ContactInfo {
            candidate: g.key.0 as usize,
            antagonist: g.key.1 as usize,
            point: [g.point.x, g.point.y],
            normal: [g.normal.x, g.normal.y],
            gap: g.gap,
            r_n: p[0] / h,
            r_t: p[1] / h,
        })
    }

    /// Resultant contact force (N) on body `i` over the last step.
    pub fn contact_resultant(&self, i: usize) -> [f64; 2] {
        let mut f = Vec2::zeros();
        for c in self.contact_forces() {
            let n = Vec2::new(c.normal[0], c.normal[1]);
            let r = n * c.r_n + crate::geometry::perp(n) * c.r_t;
            if c.candidate == i {
                f += r;
            } else if c.antagonist == i {
                f -= r;
            }
        }
        [f.x, f.y]
    }

    /// Sweeps large NLGS problems on `threads` threads (two halves side by side,
    /// [`super::split`]; more than 2 are used as 2). The numbers do not depend on
    /// it. Not part of the state: a system read from a checkpoint uses one.
    pub fn set_threads(&mut self, threads: usize) {
        self.ws.threads = threads;
    }

    /// What the two-thread team of the split sweeps did so far: joins run side by
    /// side, taken back by the caller, or run in turn (zero on one thread).
    pub fn team_stats(&self) -> crate::team::TeamStats {
        self.ws.split.team_stats()
    }

    /// The NLGS problem of the last step, restarted cold: `u = u_free` and all
    /// impulses zero. Benchmarks time sweeps on it.
    pub fn nlgs_problem(&self) -> super::nlgs::NlgsProblem {
        let mut rows = self.ws.rows.clone();
        let mut springs = self.ws.spring_rows.clone();
        // u_free = u_f − M⁻¹ Σ H P.
        let mut u = self.bodies.u.clone();
        super::nlgs::remove_impulses(&mut u, &self.bodies.inv_m, &rows, &springs);
        rows.iter_mut().for_each(|r| r.p = [0.0; 2]);
        springs.iter_mut().for_each(|s| s.p = 0.0);
        super::nlgs::NlgsProblem { u, inv_m: self.bodies.inv_m.clone(), rows, springs }
    }

    /// Mean force (N) of each spring over the last step, pushing its ends apart.
    pub fn spring_forces(&self) -> impl Iterator<Item = f64> + '_ {
        self.springs.iter().map(move |s| s.impulse / self.params.dt)
    }
}

impl System {
    /// The unit vector against gravity (`+y` without gravity).
    fn up(&self) -> [f64; 2] {
        crate::plane::bodies::up(self.params.gravity)
    }

    /// The lowest point of the non-fixed bodies along `−g` (m; their bounding
    /// circles), 0 if there is none.
    pub fn lowest_point(&self) -> f64 {
        self.bodies.lowest_point(self.up())
    }

    /// Gravitational energy `Σ m |g| h` of the non-fixed bodies (J), `h` the
    /// height of the centre of mass above [`System::gravity_reference`] (the
    /// lowest point now if no step has set it).
    pub fn gravitational_energy(&self) -> f64 {
        let reference = self.gravity_reference.unwrap_or_else(|| self.lowest_point());
        self.bodies.gravitational_energy(self.params.gravity, reference)
    }

    /// Elastic energy of the sublayer springs (J): `½ k_N L0 ε²` each (law (17),
    /// [`super::sublayer`]), 0 for a compression-only spring in tension.
    pub fn spring_energy(&self) -> f64 {
        self.springs.iter().map(|s| s.elastic_energy(&self.bodies.q)).sum()
    }

    /// Potential energy `E_p` (J): gravitational plus the springs'.
    pub fn potential_energy(&self) -> f64 {
        self.gravitational_energy() + self.spring_energy()
    }

    /// Moves the bodies of `c` to its positions `(x, y, θ)` (centre of mass, m;
    /// angle, rad), sets every velocity to zero (an imposed component to its
    /// value now) and forgets the warm start (contact and spring impulses), so
    /// that the next step starts from this configuration exactly as a system
    /// built there would. The clock goes on.
    ///
    /// # Errors
    /// [`crate::Error::Scene`] if `c` has not 3 coordinates per body, names an unknown
    /// or fixed body or holds a non-finite value; the system is then unchanged.
    pub fn set_configuration(&mut self, c: &crate::engine::Configuration) -> crate::Result<()> {
        self.bodies.place(c, self.time)?;
        self.contacts.clear();
        self.impulses.clear();
        for s in &mut self.springs {
            s.impulse = 0.0;
        }
        Ok(())
    }

    /// Checks that the state holds together (a state read from a checkpoint):
    /// array lengths, body and material indices, warm-start keys sorted and in
    /// range, finite positions and velocities, the parameters' ranges and the
    /// clock. The message names what is wrong.
    pub fn check_state(&self) -> crate::Result<()> {
        let bad = |msg: String| Err(crate::Error::Scene(msg));
        crate::plane::outputs::check_bodies(&self.bodies, self.materials, &self.springs)?;
        if self.materials.checked_mul(self.materials) != Some(self.laws.len()) {
            return bad(format!("{} contact laws for {} materials", self.laws.len(), self.materials));
        }
        let n = self.bodies.len();
        if self.impulses.len() != self.contacts.len() {
            return bad(format!("{} warm-start impulses for {} contacts", self.impulses.len(), self.contacts.len()));
        }
        if self.contacts.iter().any(|c| c.key.0 as usize >= n || c.key.1 as usize >= n)
            || self.contacts.windows(2).any(|w| w[0].key >= w[1].key)
        {
            return bad("warm-start contacts: bodies out of range or keys not sorted".into());
        }
        self.params.check()?;
        self.origin.check(self.step, Some(self.time), self.params.dt).or_else(bad)?;
        Ok(())
    }

    /// Checks that `self` is a state of the model `fresh` (the system built from
    /// the same scene): the same bodies (names, shapes, materials, masses,
    /// inverse masses, fixed, imposed, loads), springs (but their impulses),
    /// contact laws, parameters, clock origin and zero of the gravitational
    /// energy.
    pub fn check_same_model(&self, fresh: &System) -> crate::Result<()> {
        let bad = |what: String| Err(crate::Error::Scene(format!("{what} differs from the scene's")));
        crate::plane::outputs::check_same_bodies((&self.bodies, &self.springs), (&fresh.bodies, &fresh.springs))?;
        if self.materials != fresh.materials || !same(&self.laws, &fresh.laws) {
            return bad("the contact laws".into());
        }
        if self.params != fresh.params {
            return bad("the [nscd] parameters or time step".into());
        }
        // The run loop never changes the time step: the clock keeps its origin.
        if !self.origin.same(&fresh.origin) {
            return bad("the clock's origin".into());
        }
        // The zero of the gravitational energy is set by the first step, from
        // the state the run starts from.
        let reference = match fresh.gravity_reference {
            None if self.step > fresh.step => Some(fresh.lowest_point()),
            r => r,
        };
        if !same(&self.gravity_reference, &reference) {
            return bad("the zero of the gravitational energy".into());
        }
        Ok(())
    }
}

pub(crate) use crate::plane::outputs::same;

impl System {
    /// Removes the overlaps of the current configuration, moving the bodies as
    /// little as possible in the metric of their masses ([`crate::plane::relax`]),
    /// until the largest overlap is at most `settings.tolerance`; then writes the
    /// result back as [`System::set_configuration`] does (velocities zeroed, warm
    /// start forgotten). On an error the configuration is unchanged.
    ///
    /// # Errors
    /// [`crate::Error::Scene`] for settings out of range or a held body that does not exist.
    pub fn relax(&mut self, settings: &crate::engine::RelaxSettings) -> crate::Result<crate::engine::RelaxReport> {
        let (report, q) = crate::plane::relax::project(&self.bodies, settings)?;
        let mut c = crate::engine::Engine::configuration(self);
        for (k, &i) in c.bodies.clone().iter().enumerate() {
            c.body_mut(k).copy_from_slice(&q[i]);
        }
        self.set_configuration(&c)?;
        Ok(report)
    }
}
