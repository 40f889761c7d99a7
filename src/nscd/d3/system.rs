//! The 3D NSCD system and its step: Moreau–Jean's θ-method on the six degrees of freedom of rigid convex
//! polyhedra, spheres and fixed walls (Saussine et al. 2006 §2.4–2.7 in 3D; Jean 1999), solved by the shared
//! nonlinear Gauss–Seidel ([`crate::nscd::method`]) on the 3D contact rows ([`super::contact::ContactRow3`]).
//!
//! One step of length `h` from `(q_n, u_n)`:
//! 1. **Free velocity**: `v_free = v_n + h g`; the spin in the principal frame `ω_free = ω_n − h I⁻¹ (ω_n × I ω_n)`
//!    — the gyroscopic term of Euler's equations taken **explicitly at the start of the step, as LMGC90's
//!    RBDY3 does** (`comp_Fext_RBDY3` of its Moreau integrator). Angular momentum is therefore conserved to
//!    `O(h)` per unit time, not exactly (`tests/nscd3d.rs` measures the drift and its order).
//! 2. **Intermediate configuration** `q_m = q_n + (1 − θ) h u_n`: the centroid moved by `(1 − θ) h v_n`, the frame
//!    turned by the exact rotation `exp((1 − θ) h R_n ω_n)` (LMGC90 turns its frame by the same spin, with a
//!    linearised or Cayley map); the contacts are detected there ([`crate::space::detection`]).
//! 3. **Contact problem**: the rows at `q_m`, warm-started from the impulses of the previous step's contact with
//!    the same key (kept as world vectors and projected on the new frame), solved by the method's policies.
//! 4. **Update**: `u_{n+1}` from the solve; `q_{n+1} = q_m + θ h u_{n+1}` (centroid and frame as in 2).
//!
//! A step that produces a non-finite velocity or position returns [`Error::Diverged`] naming the step and the
//! body, and the system keeps the state of the last good step.

use super::contact::ContactRow3;
use crate::geometry::{Pose, Vec3};
use crate::nscd::contact::ContactLaw;
use crate::nscd::method::{apply_impulses, solve_nlgs, NlgsReport, NlgsSettings, Row, SweepNorms};
use crate::space::bodies::{advance, Bodies, Dofs6};
use crate::space::detection::Detector;
use crate::{Error, Result};

/// The parameters of a 3D NSCD system.
#[derive(Debug, Clone, PartialEq)]
pub struct Params3 {
    /// Time step `h` (s). Default 1e-3.
    pub dt: f64,
    /// θ of the θ-method (dimensionless, in `[1/2, 1]`). Default 1/2.
    pub theta: f64,
    /// Gravity (m/s², world). Default `(0, 0, −9.81)`.
    pub gravity: Vec3,
    /// Alert distance (m): pairs closer than this get contact points. Default 1e-3.
    pub alert_distance: f64,
    /// The Gauss–Seidel's policy, tolerance and caps ([`NlgsSettings::default`]).
    pub nlgs: NlgsSettings,
}

impl Default for Params3 {
    fn default() -> Self {
        Self {
            dt: 1e-3,
            theta: 0.5,
            gravity: Vec3::new(0.0, 0.0, -9.81),
            alert_distance: 1e-3,
            nlgs: NlgsSettings::default(),
        }
    }
}

/// A contact of the last step, with its mean force over the step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactForce3 {
    /// Candidate body.
    pub candidate: u32,
    /// Antagonist body.
    pub antagonist: u32,
    /// Contact point at the intermediate configuration (m, world).
    pub point: Vec3,
    /// Unit normal, from the antagonist towards the candidate.
    pub normal: Vec3,
    /// Gap at the intermediate configuration (m).
    pub gap: f64,
    /// Normal force `P_N / h` (N).
    pub r_n: f64,
    /// Force on the candidate, world (N): `(P_N n + P_T1 t₁ + P_T2 t₂) / h`.
    pub force: Vec3,
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats3 {
    /// Contact points in the problem.
    pub contacts: usize,
    /// The solve's report.
    pub nlgs: NlgsReport,
    /// Wall time of the detection (s): for measurements, not part of any result.
    pub detect_seconds: f64,
    /// Wall time of the contact solve, rows and warm start included (s).
    pub solve_seconds: f64,
}

/// A key that names a contact point from step to step: candidate, antagonist, point of the pair.
type Key = (u32, u32, u32);

/// No spring rows yet in 3D (the sublayer's law (17) in 3D is not built): the type of an empty list.
#[derive(Debug, Clone, Copy)]
enum NoSpring {}

impl Row for NoSpring {
    type Dofs = Dofs6;

    fn bodies(&self) -> (u32, u32) {
        match *self {}
    }

    fn set_bodies(&mut self, _: u32, _: u32) {
        match *self {}
    }

    fn take_impulse(&mut self, _: &Self) {
        match *self {}
    }

    fn add_impulse(&self, _: &mut [Dofs6], _: &[Dofs6], _: f64) {
        match *self {}
    }

    fn visit<const UPDATE: bool>(&mut self, _: &mut [Dofs6], _: &[Dofs6], _: f64, _: &mut SweepNorms) {
        match *self {}
    }
}

/// A 3D NSCD system: its bodies, contact laws, detection and warm-start memory.
#[derive(Debug, Clone)]
pub struct System3 {
    /// Parameters.
    pub params: Params3,
    /// The bodies.
    pub bodies: Bodies,
    /// Time (s).
    pub time: f64,
    /// Steps made.
    pub steps: u64,
    materials: usize,
    laws: Vec<ContactLaw>,
    detector: Detector,
    poses_m: Vec<Pose>,
    rows: Vec<ContactRow3>,
    /// Per row: its key, point, frame `[n, t₁, t₂]` and gap.
    geometry: Vec<(Key, Vec3, [Vec3; 3], f64)>,
    /// The impulses (world, N·s) of the last step's contacts, sorted by key.
    memory: Vec<(Key, Vec3)>,
    u_begin: Vec<Dofs6>,
    u: Vec<Dofs6>,
    mobile: Vec<bool>,
    springs: Vec<NoSpring>,
}

impl System3 {
    /// An empty system with `materials` materials, every pair frictionless and plastic until [`Self::set_law`].
    pub fn new(params: Params3, materials: usize) -> Self {
        let materials = materials.max(1);
        Self {
            params,
            bodies: Bodies::default(),
            time: 0.0,
            steps: 0,
            materials,
            laws: vec![ContactLaw::default(); materials * materials],
            detector: Detector::default(),
            poses_m: Vec::new(),
            rows: Vec::new(),
            geometry: Vec::new(),
            memory: Vec::new(),
            u_begin: Vec::new(),
            u: Vec::new(),
            mobile: Vec::new(),
            springs: Vec::new(),
        }
    }

    /// Sets the law between materials `i` and `j` (both ways).
    pub fn set_law(&mut self, i: usize, j: usize, law: ContactLaw) {
        let n = self.materials;
        self.laws[i * n + j] = law;
        self.laws[j * n + i] = law;
    }

    fn law(&self, a: usize, b: usize) -> &ContactLaw {
        let (ma, mb) = (self.bodies.info[a].material as usize, self.bodies.info[b].material as usize);
        &self.laws[ma.min(self.materials - 1) * self.materials + mb.min(self.materials - 1)]
    }

    /// Checks the parameters: one-line errors naming the field.
    pub fn check(&self) -> Result<()> {
        let p = &self.params;
        if !(p.dt.is_finite() && p.dt > 0.0) {
            return Err(Error::Scene(format!("simulation.dt: must be positive and finite, got {}", p.dt)));
        }
        if !(0.5..=1.0).contains(&p.theta) {
            return Err(Error::Scene(format!("nscd.theta: must be in [0.5, 1], got {}", p.theta)));
        }
        if !(p.alert_distance.is_finite() && p.alert_distance >= 0.0) {
            return Err(Error::Scene(format!(
                "nscd.alert_distance: must be non-negative and finite, got {}",
                p.alert_distance
            )));
        }
        if !p.gravity.iter().all(|g| g.is_finite()) {
            return Err(Error::Scene("simulation.gravity: must be finite".into()));
        }
        Ok(())
    }

    /// One θ-method step (module doc). On an error the state is the one before the step.
    pub fn step(&mut self) -> Result<StepStats3> {
        self.check()?;
        let (h, theta) = (self.params.dt, self.params.theta);
        let n = self.bodies.len();
        // 1. Free velocity, explicit gyroscopic term.
        self.u_begin.clear();
        self.u_begin.extend_from_slice(&self.bodies.u);
        self.u.clear();
        self.u.extend_from_slice(&self.bodies.u);
        let g = self.params.gravity;
        for i in 0..n {
            if !self.bodies.is_mobile(i) {
                continue;
            }
            let (u, inertia) = (&mut self.u[i], self.bodies.info[i].inertia);
            let w = Vec3::new(u[3], u[4], u[5]);
            let gyro = -w.cross(&inertia.component_mul(&w));
            u[0] += h * g.x;
            u[1] += h * g.y;
            u[2] += h * g.z;
            u[3] += h * gyro.x / inertia.x;
            u[4] += h * gyro.y / inertia.y;
            u[5] += h * gyro.z / inertia.z;
        }
        // 2. Intermediate configuration and detection.
        self.poses_m.clear();
        for i in 0..n {
            self.poses_m.push(advance(&self.bodies.pose[i], &self.u_begin[i], (1.0 - theta) * h));
        }
        let clock = std::time::Instant::now();
        self.mobile.clear();
        self.mobile.extend((0..n).map(|i| self.bodies.is_mobile(i)));
        self.detector.run(&self.bodies.info, &self.poses_m, &self.mobile, self.params.alert_distance);
        let detect_seconds = clock.elapsed().as_secs_f64();
        // 3. Rows, warm start, solve.
        let clock = std::time::Instant::now();
        self.rows.clear();
        self.geometry.clear();
        for f in &self.detector.found {
            let (a, b) = (f.key.0 as usize, f.key.1 as usize);
            let frame = [f.normal, f.t1, f.t2];
            let mut row = ContactRow3::new(
                (f.key.0, f.key.1),
                f.position,
                frame,
                (&self.poses_m[a], &self.poses_m[b]),
                (&self.bodies.inv_m[a], &self.bodies.inv_m[b]),
                (&self.u_begin[a], &self.u_begin[b]),
                f.gap,
                h,
                self.law(a, b),
            );
            if let Ok(k) = self.memory.binary_search_by(|(key, _)| key.cmp(&f.key)) {
                let pw = self.memory[k].1;
                row.p = crate::nscd::d3::cone::project_cone([pw.dot(&f.normal), pw.dot(&f.t1), pw.dot(&f.t2)], row.mu);
            }
            self.rows.push(row);
            self.geometry.push((f.key, f.position, frame, f.gap));
        }
        apply_impulses(&mut self.u, &self.bodies.inv_m, &self.rows, &self.springs);
        let report = solve_nlgs(&self.params.nlgs, &mut self.u, &self.bodies.inv_m, &mut self.rows, &mut self.springs);
        let solve_seconds = clock.elapsed().as_secs_f64();
        // 4. Update, checked before it is kept.
        for i in 0..n {
            if self.u[i].iter().any(|x| !x.is_finite()) {
                return Err(self.diverged(i, "non-finite velocity"));
            }
            let pose = advance(&self.poses_m[i], &self.u[i], theta * h);
            if !pose.position.iter().all(|x| x.is_finite()) {
                return Err(self.diverged(i, "non-finite position"));
            }
            self.poses_m[i] = pose;
        }
        std::mem::swap(&mut self.bodies.pose, &mut self.poses_m);
        std::mem::swap(&mut self.bodies.u, &mut self.u);
        self.memory.clear();
        for (row, (key, _, frame, _)) in self.rows.iter().zip(&self.geometry) {
            let pw = frame[0] * row.p[0] + frame[1] * row.p[1] + frame[2] * row.p[2];
            self.memory.push((*key, pw));
        }
        self.steps += 1;
        self.time = self.params.dt * self.steps as f64;
        Ok(StepStats3 { contacts: self.rows.len(), nlgs: report, detect_seconds, solve_seconds })
    }

    fn diverged(&self, body: usize, what: &str) -> Error {
        Error::Diverged { step: self.steps + 1, body, name: self.bodies.info[body].name.clone(), what: what.into() }
    }

    /// The contacts of the last step with their mean forces over it.
    pub fn contact_forces(&self) -> impl Iterator<Item = ContactForce3> + '_ {
        let h = self.params.dt;
        self.rows.iter().zip(&self.geometry).map(move |(row, (key, point, frame, gap))| ContactForce3 {
            candidate: key.0,
            antagonist: key.1,
            point: *point,
            normal: frame[0],
            gap: *gap,
            r_n: row.p[0] / h,
            force: (frame[0] * row.p[0] + frame[1] * row.p[1] + frame[2] * row.p[2]) / h,
        })
    }
}
