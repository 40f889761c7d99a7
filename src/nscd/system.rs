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

/// Time-stepping parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NscdParams {
    /// Time step `h` (s).
    pub dt: f64,
    /// θ of the θ-method, in [0.5, 1].
    pub theta: f64,
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Alert distance (m): pairs closer than this are contacts (possibly open).
    /// Each step it is raised to `2 h v_max` if the fastest body needs it.
    pub alert_distance: f64,
    pub nlgs: NlgsSettings,
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
        if self.gravity.iter().any(|g| !g.is_finite()) {
            return bad("simulation.gravity", self.gravity[0] + self.gravity[1]);
        }
        Ok(())
    }
}

/// Statistics of one time step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct StepStats {
    /// Time at the end of the step (s).
    pub time: f64,
    pub step: u64,
    /// Contacts detected (open ones within the alert distance included).
    pub contacts: usize,
    /// Contacts carrying a force or overlapping at the end of the step.
    pub active_contacts: usize,
    pub iterations: usize,
    /// Final value of the convergence norm.
    pub criterion: f64,
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

/// A contact as seen from outside, with its force over the last step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ContactInfo {
    pub candidate: usize,
    pub antagonist: usize,
    /// Point (m) and unit normal towards the candidate, at `q_m`.
    pub point: [f64; 2],
    pub normal: [f64; 2],
    /// Gap at `q_m` (m).
    pub gap: f64,
    /// Mean normal and tangential force on the candidate over the step (N).
    pub r_n: f64,
    pub r_t: f64,
}

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
    pub split: super::split::SplitWorkspace,
    /// Threads of the NLGS sweeps (0 or 1: one); not part of the state.
    pub threads: usize,
}

/// The complete state of an NSCD simulation.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct System {
    pub params: NscdParams,
    pub bodies: Bodies,
    pub springs: Vec<Spring>,
    /// Contact law of material pair `(i, j)` at `i * materials + j`.
    pub laws: Vec<ContactLaw>,
    pub materials: usize,
    /// Time (s) and number of steps done. The time is recomputed each step as
    /// `time_origin + (step − step_origin) · dt`, never accumulated, so it does not
    /// drift over millions of steps; [`System::set_dt`] rebases the origin.
    pub time: f64,
    pub step: u64,
    #[serde(default)]
    pub time_origin: f64,
    #[serde(default)]
    pub step_origin: u64,
    /// Contacts of the last step and their impulses `(P_N, P_T)` (N·s), sorted by
    /// key: the warm start of the next step.
    pub contacts: Vec<ContactGeom>,
    pub impulses: Vec<[f64; 2]>,
    #[serde(skip)]
    pub(crate) ws: Workspace,
}

impl System {
    /// An empty system with `materials` materials and frictionless, plastic contacts.
    pub fn new(params: NscdParams, materials: usize) -> Self {
        Self {
            params,
            bodies: Bodies::default(),
            springs: Vec::new(),
            laws: vec![ContactLaw::default(); materials * materials],
            materials,
            time: 0.0,
            step: 0,
            time_origin: 0.0,
            step_origin: 0,
            contacts: Vec::new(),
            impulses: Vec::new(),
            ws: Workspace::default(),
        }
    }

    /// Changes the time step (s) from now on, keeping the clock exact.
    pub fn set_dt(&mut self, dt: f64) {
        self.time_origin = self.time;
        self.step_origin = self.step;
        self.params.dt = dt;
    }

    /// Sets the contact law between materials `i` and `j` (both orders).
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

    /// The NLGS problem of the last step, restarted cold: `u = u_free` and all
    /// impulses zero. Benchmarks time sweeps on it.
    pub fn nlgs_problem(&self) -> super::nlgs::NlgsProblem {
        let mut rows = self.ws.rows.clone();
        let mut springs = self.ws.spring_rows.clone();
        // u_free = u_f − M⁻¹ Σ H P.
        let mut u = self.bodies.u.clone();
        for r in rows.iter_mut() {
            r.p = [-r.p[0], -r.p[1]];
        }
        for s in springs.iter_mut() {
            s.p = -s.p;
        }
        super::nlgs::apply_impulses(&mut u, &self.bodies.inv_m, &rows, &springs);
        rows.iter_mut().for_each(|r| r.p = [0.0; 2]);
        springs.iter_mut().for_each(|s| s.p = 0.0);
        super::nlgs::NlgsProblem { u, inv_m: self.bodies.inv_m.clone(), rows, springs }
    }

    /// Mean force (N) of each spring over the last step, pushing its ends apart.
    pub fn spring_forces(&self) -> impl Iterator<Item = f64> + '_ {
        self.springs.iter().map(move |s| s.impulse / self.params.dt)
    }
}
