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
//!    linearised or Cayley map); the contacts are detected there ([`crate::space::detection`]), within the alert
//!    distance raised to twice what the fastest point covers in a step (as in 2D).
//! 3. **Contact problem**: the rows at `q_m`, warm-started from the impulse of the point of the previous step that
//!    each point continues — of the same pair, the nearest within the alert distance, each taken once (kept as
//!    world vectors and projected on the new frame; as LMGC90's `recup_rloc` finds a point by place when it cannot
//!    by feature) — and solved by the method's policies.
//! 4. **Update**: `u_{n+1}` from the solve; `q_{n+1} = q_m + θ h u_{n+1}` (centroid and frame as in 2).
//!
//! A step that starts from or produces a non-finite velocity or position, or leaves an overlap deeper than half
//! the smaller inradius of a pair at `q_{n+1}` (predicted to first order, `g + θ h U_N`, as the 2D engine does),
//! returns [`Error::Diverged`] naming the step and the body, and the system keeps the state of the last good step
//! (its bodies, clock, warm start and contact list).
//!
//! The system is plain serde data (a checkpoint of the run loop is its serde form): the parameters, bodies, laws,
//! clock and the last step's contacts with their impulses (the warm start of the next step) and, under
//! [`Overlaps::Held`], their reference gaps; the solver's
//! buffers and the detector are not kept (the detector's per-pair memory of the normal only lets it stop early:
//! its result does not depend on it), so a state read back steps on with the same numbers.

use super::contact::ContactRow3;
use super::overlaps::{reference_gap, Overlaps};
use super::spring::SpringRow3;
use crate::geometry::{Pose, Vec3};
use crate::nscd::contact::ContactLaw;
use crate::nscd::method::anderson::{solve_nlgs_anderson_split, AndersonWorkspace};
use crate::nscd::method::apgd::{solve_apgd_with, ApgdOptions, ApgdWorkspace};
use crate::nscd::method::split::SplitWorkspace;
use crate::nscd::method::{
    apply_impulses, check_by_row, remove_impulses, NlgsProblem, NlgsReport, NlgsSettings, OnStall, Solver, SweepNorms,
};
use crate::space::bodies::{advance, Bodies, Dofs6};
use crate::space::detection::{Detector, FaceGaps};
use crate::space::loads::LoadKind;
use crate::space::springs::Spring3;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// The parameters of a 3D NSCD system.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Params3 {
    /// Time step `h` (s). Default 1e-3.
    pub dt: f64,
    /// θ of the θ-method (dimensionless, in `[1/2, 1]`). Default 1/2.
    pub theta: f64,
    /// Gravity (m/s², world). Default `(0, 0, −9.81)`.
    pub gravity: Vec3,
    /// Alert distance (m): pairs closer than this get contact points; each step raises it to `2 h v_max`, `v_max`
    /// the largest speed of a point of a non-fixed body at the start of the step, when the fastest body needs it
    /// (as in 2D). Default 1e-3.
    pub alert_distance: f64,
    /// How the points of a face–face contact of two polyhedra get their gaps: each its own
    /// ([`FaceGaps::Exact`], the default) or, as in LMGC90, the smallest ([`FaceGaps::CommonPlane`]).
    #[serde(default)]
    pub face_gaps: FaceGaps,
    /// What a closed contact does with an overlap: keep it ([`Overlaps::Kept`], Moreau–Jean's velocity-level
    /// law, the default) or hold it from growing ([`Overlaps::Held`]).
    #[serde(default)]
    pub overlaps: Overlaps,
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
            face_gaps: FaceGaps::Exact,
            overlaps: Overlaps::Kept,
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
    /// Time at the end of the step (s).
    pub time: f64,
    /// Kinetic energy of the mobile bodies at the end of the step (J).
    pub kinetic_energy: f64,
    /// Contact points in the problem (open ones within the alert distance included).
    pub contacts: usize,
    /// Contact points carrying an impulse or overlapping at the end of the step.
    pub active_contacts: usize,
    /// Mean overlap over the active contact points at the end of the step (m), `max(0, −(g + θ h U_N))`.
    pub mean_overlap: f64,
    /// Largest overlap at the end of the step (m).
    pub max_overlap: f64,
    /// Sum of the overlaps of the contact points (m).
    pub total_overlap: f64,
    /// The solve's report.
    pub nlgs: NlgsReport,
    /// Wall time of the detection (s): for measurements, not part of any result.
    pub detect_seconds: f64,
    /// Wall time of the contact solve, rows and warm start included (s).
    pub solve_seconds: f64,
}

/// A key that names a contact point from step to step: candidate, antagonist, point of the pair.
type Key = (u32, u32, u32);

/// A contact point of the last step as the system keeps it (in its serde form too): where it was and the impulse
/// it carried.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Contact3 {
    /// Candidate, antagonist, point of the pair.
    pub key: Key,
    /// Contact point at the intermediate configuration (m, world).
    pub point: Vec3,
    /// Local frame `[n, t₁, t₂]` (world; `n` from the antagonist towards the candidate).
    pub frame: [Vec3; 3],
    /// Gap at the intermediate configuration (m).
    pub gap: f64,
    /// Impulse `(P_N, P_T1, P_T2)` over the step (N·s).
    pub p: [f64; 3],
}

/// A 3D NSCD system: its bodies, contact laws, detection and warm-start memory (module doc: its serde form).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct System3 {
    /// Parameters.
    pub params: Params3,
    /// The bodies.
    pub bodies: Bodies,
    /// The sublayer springs (law (17) of Saussine et al. 2006, in 3D), each with its last impulse (the warm
    /// start).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub springs: Vec<Spring3>,
    /// Time (s): `t_0 + (k − k_0) h` from [`Self::origin`] after every step, never accumulated.
    pub time: f64,
    /// Steps made.
    pub steps: u64,
    /// The clock's origin `(t_0, k_0)`: the time and step at which the time step last changed
    /// ([`Self::set_dt`]).
    #[serde(flatten)]
    pub origin: crate::clock::Origin,
    materials: usize,
    laws: Vec<ContactLaw>,
    /// The impulses (world, N·s) of the last step's contacts, sorted by key (the order of [`Self::contacts`]): the
    /// next step's warm start.
    memory: Vec<(Key, Vec3)>,
    /// The last step's contact points with their impulses, sorted by key.
    contacts: Vec<Contact3>,
    /// Under [`Overlaps::Held`], the reference gap (m) of each of [`Self::contacts`] (same order); empty under
    /// [`Overlaps::Kept`].
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    held: Vec<f64>,
    #[serde(skip)]
    detector: Detector,
    #[serde(skip)]
    poses_m: Vec<Pose>,
    #[serde(skip)]
    rows: Vec<ContactRow3>,
    /// Per row: its key, point, frame `[n, t₁, t₂]` and gap.
    #[serde(skip)]
    geometry: Vec<(Key, Vec3, [Vec3; 3], f64)>,
    /// Per row under [`Overlaps::Held`]: its reference gap (m).
    #[serde(skip)]
    held_rows: Vec<f64>,
    #[serde(skip)]
    u_begin: Vec<Dofs6>,
    #[serde(skip)]
    u: Vec<Dofs6>,
    #[serde(skip)]
    mobile: Vec<bool>,
    #[serde(skip)]
    spring_rows: Vec<SpringRow3>,
    /// The domain-split solve's buffers and two-thread team ([`crate::nscd::method::split`]).
    #[serde(skip)]
    split: SplitWorkspace<ContactRow3, SpringRow3>,
    /// Buffers of the accelerated solver (`solver = "apgd"`).
    #[serde(skip)]
    apgd: ApgdWorkspace<ContactRow3>,
    /// Buffers of the Anderson mixing of the sweeps (`nscd.anderson`): the history when the problem is not
    /// split, and the step's free velocities.
    #[serde(skip)]
    anderson: AndersonWorkspace<Dofs6>,
    /// Threads of the step (0 or 1: one); not part of the state (the numbers do not depend on it).
    #[serde(skip)]
    threads: usize,
}

impl System3 {
    /// An empty system with `materials` materials, every pair frictionless and plastic until [`Self::set_law`].
    pub fn new(params: Params3, materials: usize) -> Self {
        let materials = materials.max(1);
        Self {
            params,
            bodies: Bodies::default(),
            springs: Vec::new(),
            time: 0.0,
            steps: 0,
            origin: crate::clock::Origin::default(),
            materials,
            laws: vec![ContactLaw::default(); materials * materials],
            contacts: Vec::new(),
            held: Vec::new(),
            detector: Detector::default(),
            poses_m: Vec::new(),
            rows: Vec::new(),
            geometry: Vec::new(),
            held_rows: Vec::new(),
            memory: Vec::new(),
            u_begin: Vec::new(),
            u: Vec::new(),
            mobile: Vec::new(),
            spring_rows: Vec::new(),
            split: SplitWorkspace::default(),
            apgd: ApgdWorkspace::default(),
            anderson: Default::default(),
            threads: 1,
        }
    }

    /// The threads of the step, 1 or 2: the detection's narrow phase shares the pairs between two threads
    /// ([`crate::space::detection`]), and problems of at least `nlgs.split_min_rows` rows are split in two halves
    /// along x swept side by side ([`crate::nscd::method::split`]); neither changes the numbers.
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads;
        self.detector.set_threads(threads);
    }

    /// What the split solve's two-thread team did so far (joins side by side, taken back, in turn).
    pub fn team_stats(&self) -> crate::team::TeamStats {
        self.split.team_stats()
    }

    /// What the detection's two-thread team did so far.
    pub fn detection_team_stats(&self) -> crate::team::TeamStats {
        self.detector.team_stats()
    }

    /// Sets the law between materials `i` and `j` (both ways).
    pub fn set_law(&mut self, i: usize, j: usize, law: ContactLaw) {
        let n = self.materials;
        self.laws[i * n + j] = law;
        self.laws[j * n + i] = law;
    }

    /// Changes the time step (s) from now on, keeping the clock exact (the origin moves to now).
    pub fn set_dt(&mut self, dt: f64) {
        self.origin.rebase(self.time, self.steps);
        self.params.dt = dt;
    }

    /// The number of materials.
    pub fn materials(&self) -> usize {
        self.materials
    }

    /// The contact laws, pair `(i, j)` at `i * materials + j`.
    pub fn laws(&self) -> &[ContactLaw] {
        &self.laws
    }

    /// The check pass of the last step's solve, point by point (a diagnosis of which contact points hold a solve,
    /// `examples/nscd3d_residuals.rs`): the norms of each spring row in the springs' order, and each contact
    /// point's key with its own norms in key order, at the step's final impulses and velocities (`sum_dvdv` =
    /// `|ΔU|²`, `sum_dvdvrr` = `|ΔU|² |P̄|²`, … of [`SweepNorms`]). Together they add up to the check pass's sums.
    /// Both empty before the first step of this system and after a failed step.
    #[allow(clippy::type_complexity)]
    pub fn check_by_point(&self) -> (Vec<SweepNorms>, Vec<((u32, u32, u32), SweepNorms)>) {
        if !self.rows_kept() {
            return (Vec::new(), Vec::new());
        }
        let (mut u, mut rows, mut springs) = (self.bodies.u.clone(), self.rows.clone(), self.spring_rows.clone());
        let (of_springs, norms) = check_by_row(&mut u, &self.bodies.inv_m, &mut rows, &mut springs);
        (of_springs, self.contacts.iter().map(|c| c.key).zip(norms).collect())
    }

    /// The last step's problem with its solution (as [`crate::nscd::System::nlgs_problem`] in 2D, for
    /// benchmarks and solver prototypes, `examples/socp_prototype.rs`): the free velocities
    /// `u_free = u − M⁻¹ Σ H P` recovered from the end velocities, the inverse masses, and the contact and spring
    /// rows with the impulses the solve found (zero them for a cold start). `None` before the first step and
    /// after a failed one, as [`Self::check_by_point`].
    pub fn nlgs_problem(&self) -> Option<NlgsProblem<ContactRow3, SpringRow3>> {
        if !self.rows_kept() || self.steps == 0 {
            return None;
        }
        let (rows, springs) = (self.rows.clone(), self.spring_rows.clone());
        let mut u = self.bodies.u.clone();
        remove_impulses(&mut u, &self.bodies.inv_m, &rows, &springs);
        Some(NlgsProblem { u, inv_m: self.bodies.inv_m.clone(), rows, springs })
    }

    /// Whether the rows are those of the kept step: they match its contact list point for point and its springs'
    /// impulses spring for spring (a failed step rebuilt and re-solved them without keeping anything; before the
    /// first step there are no spring rows).
    fn rows_kept(&self) -> bool {
        self.rows.len() == self.contacts.len()
            && self.rows.iter().zip(&self.contacts).all(|(r, c)| (r.a, r.b) == (c.key.0, c.key.1) && r.p == c.p)
            && self.spring_rows.len() == self.springs.len()
            && self.spring_rows.iter().zip(&self.springs).all(|(r, s)| r.p == s.impulse)
    }

    /// The warm-start memory: the world impulses (N·s) of the last step's contact points, sorted by key.
    pub fn warm_start(&self) -> &[((u32, u32, u32), Vec3)] {
        &self.memory
    }

    /// The last step's contact points with their impulses, sorted by key.
    pub fn contacts(&self) -> &[Contact3] {
        &self.contacts
    }

    /// The contact law between bodies `a` and `b` (that of their materials' pair).
    pub fn law(&self, a: usize, b: usize) -> &ContactLaw {
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
        if p.nlgs.solver == Solver::InteriorPoint {
            return Err(Error::Scene("nscd.solver: 'interior_point' is 2D only: use 'nlgs' or 'apgd' in 3D".into()));
        }
        Ok(())
    }

    /// One θ-method step (module doc). On an error the state is the one before the step.
    pub fn step(&mut self) -> Result<StepStats3> {
        self.check()?;
        let (h, theta) = (self.params.dt, self.params.theta);
        let n = self.bodies.len();
        // A non-finite start (a body given a NaN) is refused before the detection sees it.
        for i in 0..n {
            let (pose, u) = (&self.bodies.pose[i], &self.bodies.u[i]);
            if !pose.position.iter().chain(pose.rotation.coords.iter()).chain(u).all(|x| x.is_finite()) {
                return Err(self.diverged(i, "non-finite position or velocity at the start of the step"));
            }
        }
        // 1. Free velocity: gravity, the loads at t_m, the explicit gyroscopic term; imposed components take
        //    their values at the end of the step. The intermediate configuration q_m (step 2) first: the imposed
        //    spin is turned into its frame.
        self.u_begin.clear();
        self.u_begin.extend_from_slice(&self.bodies.u);
        self.poses_m.clear();
        for i in 0..n {
            self.poses_m.push(advance(&self.bodies.pose[i], &self.u_begin[i], (1.0 - theta) * h));
        }
        self.u.clear();
        self.u.extend_from_slice(&self.bodies.u);
        let g = self.params.gravity;
        let (t_m, t_f) = (self.time + (1.0 - theta) * h, self.origin.time_at(self.steps + 1, h));
        for i in 0..n {
            let info = &self.bodies.info[i];
            if info.fixed {
                continue;
            }
            let (u, inertia, im) = (&mut self.u[i], info.inertia, &self.bodies.inv_m[i]);
            let w = Vec3::new(u[3], u[4], u[5]);
            let mut force = Vec3::zeros();
            let mut torque = -w.cross(&inertia.component_mul(&w));
            for load in &info.loads {
                match load.kind {
                    LoadKind::Force => force += load.at(t_m),
                    // A world moment, in the principal frame at the start of the step (where ω is taken).
                    LoadKind::Moment => torque += self.bodies.pose[i].rotation.inverse_transform_vector(&load.at(t_m)),
                }
            }
            // Gravity as an acceleration (bit for bit h g), the loads through the inverse mass; imposed components
            // (zero inverse mass) are set below.
            for d in 0..3 {
                if im[d] > 0.0 {
                    u[d] += h * (g[d] + im[d] * force[d]);
                }
                if im[d + 3] > 0.0 {
                    u[d + 3] += h * torque[d] / inertia[d];
                }
            }
            // The imposed spin in the principal frame of the end of the step is not known before the step; it
            // is taken in the frame at q_m, where the contacts are (the difference is O(h) in a turning body).
            info.impose(u, &self.poses_m[i], t_f);
        }
        // 2. Detection at the intermediate configuration.
        let clock = std::time::Instant::now();
        self.mobile.clear();
        self.mobile.extend((0..n).map(|i| self.bodies.is_free(i)));
        let alert = self.params.alert_distance.max(2.0 * h * self.fastest_point_speed());
        self.detector.set_face_gaps(self.params.face_gaps);
        self.detector.run(&self.bodies.info, &self.poses_m, &self.mobile, alert);
        let detect_seconds = clock.elapsed().as_secs_f64();
        // 3. Rows, warm start, solve.
        let clock = std::time::Instant::now();
        self.rows.clear();
        self.geometry.clear();
        self.held_rows.clear();
        let held = self.params.overlaps == Overlaps::Held;
        // The pair being read, where its last points start in `contacts` (both lists are sorted by key, so the
        // start only moves forward) and which of them an earlier point of the pair has continued.
        let (mut pair, mut start, mut taken) = ((u32::MAX, u32::MAX), 0, 0u8);
        for f in &self.detector.found {
            let (a, b) = (f.key.0 as usize, f.key.1 as usize);
            let frame = [f.normal, f.t1, f.t2];
            if (f.key.0, f.key.1) != pair {
                pair = (f.key.0, f.key.1);
                start += self.contacts[start..].partition_point(|c| (c.key.0, c.key.1) < pair);
                taken = 0;
            }
            let same_pair = self.contacts[start..].iter().take_while(|c| (c.key.0, c.key.1) == pair);
            let last = previous_point(same_pair, &f.position, alert, &mut taken).map(|j| start + j);
            let g_ref = held.then(|| reference_gap(f.gap, last.and_then(|k| self.held.get(k).copied())));
            let mut row = ContactRow3::new(
                (f.key.0, f.key.1),
                f.position,
                frame,
                (&self.poses_m[a], &self.poses_m[b]),
                (&self.bodies.inv_m[a], &self.bodies.inv_m[b]),
                (&self.u_begin[a], &self.u_begin[b]),
                f.gap,
                h,
                g_ref,
                self.law(a, b),
            );
            if let Some(g_ref) = g_ref {
                self.held_rows.push(g_ref);
            }
            // `memory` runs alongside `contacts` (`check_state`); an emptied one is a cold start.
            if let Some(&(_, pw)) = last.and_then(|k| self.memory.get(k).filter(|m| m.0 == self.contacts[k].key)) {
                row.p = crate::nscd::d3::cone::project_cone([pw.dot(&f.normal), pw.dot(&f.t1), pw.dot(&f.t2)], row.mu);
            }
            self.rows.push(row);
            self.geometry.push((f.key, f.position, frame, f.gap));
        }
        self.spring_rows.clear();
        for s in &self.springs {
            let start = (&self.bodies.pose[..], &self.u_begin[..]);
            self.spring_rows.push(SpringRow3::new(s, start, &self.poses_m, &self.bodies.inv_m, h, theta));
        }
        apply_impulses(&mut self.u, &self.bodies.inv_m, &self.rows, &self.spring_rows);
        let poses_m = &self.poses_m;
        let settings = &self.params.nlgs;
        let report = match settings.solver {
            Solver::Apgd => solve_apgd_with(
                // The accelerated solver has one cap: an extended step gets the larger (as in 2D).
                &NlgsSettings { max_iterations: settings.sweep_cap(), ..*settings },
                &ApgdOptions::default(),
                &mut self.apgd,
                &mut self.u,
                &self.bodies.inv_m,
                &mut self.rows,
                &mut self.spring_rows,
            ),
            // `check` refuses the interior point (a polyhedral cone's LCP, 2D only) before a step runs.
            // Plain sweeps when `anderson` is 0.
            Solver::Nlgs | Solver::InteriorPoint => solve_nlgs_anderson_split(
                settings,
                &mut self.anderson,
                &mut self.split,
                self.threads,
                |i| poses_m[i].position.x,
                &mut self.u,
                &self.bodies.inv_m,
                &mut self.rows,
                &mut self.spring_rows,
            ),
        };
        let solve_seconds = clock.elapsed().as_secs_f64();
        // A stalled solve under `on_stall = "stop"` ends the run here, the bodies, springs and warm start still
        // those of the start of the step (as in 2D).
        if !report.converged && settings.on_stall == OnStall::Stop {
            return Err(Error::Stalled {
                step: self.steps + 1,
                iterations: report.iterations,
                criterion: report.criterion,
                tolerance: settings.tolerance,
            });
        }
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
        let overlaps = self.overlaps_at_end()?;
        if let Some((body, what)) = crate::space::springs::crushed(&self.springs, &self.poses_m) {
            return Err(self.diverged(body, &what));
        }
        std::mem::swap(&mut self.bodies.pose, &mut self.poses_m);
        for (s, row) in self.springs.iter_mut().zip(&self.spring_rows) {
            s.impulse = row.p;
        }
        std::mem::swap(&mut self.bodies.u, &mut self.u);
        self.memory.clear();
        self.contacts.clear();
        std::mem::swap(&mut self.held, &mut self.held_rows);
        for (row, &(key, point, frame, gap)) in self.rows.iter().zip(&self.geometry) {
            let pw = frame[0] * row.p[0] + frame[1] * row.p[1] + frame[2] * row.p[2];
            self.memory.push((key, pw));
            self.contacts.push(Contact3 { key, point, frame, gap, p: row.p });
        }
        self.steps += 1;
        self.time = self.origin.time_at(self.steps, self.params.dt);
        Ok(StepStats3 {
            time: self.time,
            kinetic_energy: self.bodies.kinetic_energy(),
            contacts: self.rows.len(),
            active_contacts: overlaps.0,
            mean_overlap: if overlaps.0 > 0 { overlaps.1 / overlaps.0 as f64 } else { 0.0 },
            max_overlap: overlaps.2,
            total_overlap: overlaps.1,
            nlgs: report,
            detect_seconds,
            solve_seconds,
        })
    }

    /// The overlaps of the solved rows at the end of the step, `max(0, −(g + θ h U_N))` with `U_N` from the new
    /// velocities (`self.u`): the active rows (an impulse or an overlap), the sum and the largest; a runaway
    /// overlap (beyond half the smaller inradius of the pair, [`inradius`]) or a non-finite one is
    /// [`Error::Diverged`] naming the body that moved into the other (the candidate unless it is fixed).
    fn overlaps_at_end(&self) -> Result<(usize, f64, f64)> {
        let th = self.params.theta * self.params.dt;
        let (mut active, mut sum, mut max) = (0, 0.0, 0.0f64);
        for (row, g) in self.rows.iter().zip(&self.geometry) {
            let gap_end = g.3 + th * row.normal_velocity(&self.u);
            let overlap = (-gap_end).max(0.0);
            if row.p[0] > 0.0 || overlap > 0.0 {
                active += 1;
                sum += overlap;
            }
            max = max.max(overlap);
            let (a, b) = (row.a as usize, row.b as usize);
            let limit = 0.5 * inradius(&self.bodies.info[a].solid).min(inradius(&self.bodies.info[b].solid));
            if overlap > limit || !gap_end.is_finite() {
                let (culprit, other) = if self.bodies.is_mobile(a) { (a, b) } else { (b, a) };
                return Err(self.diverged(culprit, &format!("runaway overlap {overlap:.3e} m with body {other}")));
            }
        }
        Ok((active, sum, max))
    }

    /// The largest speed of a point of a non-fixed body at the start of the step (m/s): `|v| + |ω| r` with `r`
    /// the radius of the sphere about the centroid holding the body. The detection's alert distance is at least
    /// twice the distance it covers in a step (as in 2D), so that a pair left out at `q_m` cannot close before the
    /// next detection.
    fn fastest_point_speed(&self) -> f64 {
        let mut v_max: f64 = 0.0;
        for (info, u) in self.bodies.info.iter().zip(&self.u_begin) {
            let radius = info.solid.radius();
            if info.fixed || !radius.is_finite() {
                continue;
            }
            let (v, w) = (Vec3::new(u[0], u[1], u[2]).norm(), Vec3::new(u[3], u[4], u[5]).norm());
            v_max = v_max.max(v + w * radius);
        }
        v_max
    }

    fn diverged(&self, body: usize, what: &str) -> Error {
        Error::Diverged { step: self.steps + 1, body, name: self.bodies.info[body].name.clone(), what: what.into() }
    }

    /// The force `R_N` (N) of each spring pushing its ends apart, in the current state (law (17)).
    pub fn spring_forces(&self) -> impl Iterator<Item = f64> + '_ {
        self.springs.iter().map(|s| s.force(&self.bodies.pose, &self.bodies.u))
    }

    /// The elastic energy of the springs in the current configuration (J).
    pub fn spring_energy(&self) -> f64 {
        self.springs.iter().map(|s| s.elastic_energy(&self.bodies.pose)).sum()
    }

    /// The contacts of the last step with their mean forces over it.
    pub fn contact_forces(&self) -> impl Iterator<Item = ContactForce3> + '_ {
        let h = self.params.dt;
        self.contacts.iter().map(move |c| ContactForce3 {
            candidate: c.key.0,
            antagonist: c.key.1,
            point: c.point,
            normal: c.frame[0],
            gap: c.gap,
            r_n: c.p[0] / h,
            force: (c.frame[0] * c.p[0] + c.frame[1] * c.p[1] + c.frame[2] * c.p[2]) / h,
        })
    }
}

impl System3 {
    /// Checks that the state holds together (a state read from a checkpoint): one pose, velocity and inverse mass
    /// per body, the inverse masses those of the bodies' descriptions, finite positions and velocities, unit
    /// quaternions (to 1e-9), one law per pair of materials, the warm start and the contact list sorted by key and
    /// naming existing bodies, the parameters' ranges and the clock. The message names the body or what is wrong.
    ///
    /// # Errors
    /// [`Error::Scene`] with that message.
    pub fn check_state(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(msg));
        let b = &self.bodies;
        let n = b.len();
        if b.pose.len() != n || b.u.len() != n || b.inv_m.len() != n {
            let (p, u, m) = (b.pose.len(), b.u.len(), b.inv_m.len());
            return bad(format!("bodies: {n} descriptions, {p} poses, {u} velocities, {m} inverse masses"));
        }
        for i in 0..n {
            let name = crate::error::clip(&b.info[i].name);
            let (pose, u) = (&b.pose[i], &b.u[i]);
            if !pose.position.iter().all(|x| x.is_finite()) {
                return bad(format!("body {i} ('{name}'): its position is not finite"));
            }
            if !u.iter().all(|x| x.is_finite()) {
                return bad(format!("body {i} ('{name}'): its velocity is not finite"));
            }
            let (norm, off) = (pose.rotation.coords.norm(), (pose.rotation.coords.norm() - 1.0).abs());
            if off.is_nan() || off > 1e-9 {
                return bad(format!("body {i} ('{name}'): its orientation is not a unit quaternion (norm {norm})"));
            }
            if b.inv_m[i].iter().zip(b.info[i].inverse_mass()).any(|(a, c)| a.to_bits() != c.to_bits()) {
                return bad(format!("body {i} ('{name}'): its inverse masses are not those of its mass and inertia"));
            }
        }
        if self.materials == 0 || self.materials.checked_mul(self.materials) != Some(self.laws.len()) {
            return bad(format!("{} contact laws for {} materials", self.laws.len(), self.materials));
        }
        let in_range = |k: &Key| (k.0 as usize) < n && (k.1 as usize) < n;
        if !self.memory.iter().all(|(k, _)| in_range(k)) || self.memory.windows(2).any(|w| w[0].0 >= w[1].0) {
            return bad("warm start: bodies out of range or keys not sorted".into());
        }
        if !self.contacts.iter().all(|c| in_range(&c.key)) || self.contacts.windows(2).any(|w| w[0].key >= w[1].key) {
            return bad("last contacts: bodies out of range or keys not sorted".into());
        }
        if self.memory.len() != self.contacts.len() || self.memory.iter().zip(&self.contacts).any(|(m, c)| m.0 != c.key)
        {
            return bad("warm start and last contacts: not the same keys".into());
        }
        if !(self.held.is_empty() || self.held.len() == self.contacts.len())
            || !self.held.iter().all(|g| *g <= 0.0 && g.is_finite())
        {
            return bad("held: not one reference gap (≤ 0, finite) per last contact".into());
        }
        for (k, s) in self.springs.iter().enumerate() {
            if s.a >= n || s.b.is_some_and(|b| b >= n) {
                return bad(format!("spring {k}: body out of range ({n} bodies)"));
            }
            if !(s.rest_length > 0.0 && s.rest_length.is_finite() && s.impulse.is_finite()) {
                return bad(format!("spring {k}: its rest length or impulse is not a positive, finite number"));
            }
        }
        self.check()?;
        self.origin.check(self.steps, Some(self.time), self.params.dt).or_else(bad)
    }

    /// Checks that `self` (read from a checkpoint) is a state of the model `fresh` (the system built from the
    /// same scene or code): the same bodies (names, shapes, materials, masses, inertia, fixed flags, imposed
    /// velocities, loads, inverse masses), springs but their impulses, materials and contact laws, parameters and
    /// clock origin.
    ///
    /// # Errors
    /// [`Error::Scene`] "… differs from the scene's", naming the body.
    pub fn check_same_model(&self, fresh: &System3) -> Result<()> {
        let bad = |what: String| Err(Error::Scene(format!("{what} differs from the scene's")));
        let (a, b) = (&self.bodies, &fresh.bodies);
        if a.len() != b.len() {
            return bad(format!("the number of bodies ({})", a.len()));
        }
        for i in 0..a.len() {
            let same_inverse = a.inv_m[i].iter().zip(&b.inv_m[i]).all(|(x, y)| x.to_bits() == y.to_bits());
            if !same(&a.info[i], &b.info[i]) || !same_inverse {
                return bad(format!("body {i} ('{}')", crate::error::clip(&b.info[i].name)));
            }
        }
        let law = |s: &Spring3| Spring3 { impulse: 0.0, ..s.clone() };
        if self.springs.len() != fresh.springs.len() {
            return bad(format!("the number of springs ({})", self.springs.len()));
        }
        for (k, (a, b)) in self.springs.iter().zip(&fresh.springs).enumerate() {
            if !same(&law(a), &law(b)) {
                return bad(format!("spring {k}"));
            }
        }
        if self.materials != fresh.materials || !same(&self.laws, &fresh.laws) {
            return bad("the contact laws".into());
        }
        if !same(&self.params, &fresh.params) {
            return bad("the 3D NSCD parameters or time step".into());
        }
        if !self.origin.same(&fresh.origin) {
            return bad("the clock's origin".into());
        }
        Ok(())
    }

    /// Moves every body of `bodies` to its position `x` (centroid, m) and orientation `rotations` (unit
    /// quaternions, renormalised), sets the velocity of every mobile body to zero (a fixed body keeps the
    /// velocity imposed on it) and forgets the warm start and
    /// the contact list (and the detector's memory), so that the next step starts from this configuration as a
    /// system built there would. The clock goes on.
    ///
    /// # Errors
    /// [`Error::Scene`] naming the body if one does not exist, is fixed, or a value is not finite or the
    /// quaternion is zero; the system is then unchanged. An imposed velocity component takes its value now.
    pub fn place(&mut self, bodies: &[usize], x: &[Vec3], rotations: &[nalgebra::Quaternion<f64>]) -> Result<()> {
        let n = self.bodies.len();
        let bad = |msg: String| Err(Error::Scene(format!("configuration: {msg}")));
        if x.len() != bodies.len() || rotations.len() != bodies.len() {
            return bad(format!("{} bodies, {} positions, {} orientations", bodies.len(), x.len(), rotations.len()));
        }
        let mut poses = Vec::with_capacity(bodies.len());
        for ((&i, x), q) in bodies.iter().zip(x).zip(rotations) {
            if i >= n {
                return bad(format!("body {i} does not exist (the engine has {n})"));
            }
            let name = crate::error::clip(&self.bodies.info[i].name);
            if self.bodies.info[i].fixed {
                return bad(format!("body {i} ('{name}') is fixed"));
            }
            if !x.iter().chain(q.coords.iter()).all(|v| v.is_finite()) {
                return bad(format!("body {i} ('{name}'): a coordinate is not finite"));
            }
            let norm = q.norm();
            if !(norm > 0.0 && norm.is_finite()) {
                return bad(format!("body {i} ('{name}'): its orientation is a zero quaternion"));
            }
            poses.push(Pose { position: *x, rotation: nalgebra::UnitQuaternion::from_quaternion(q / norm) });
        }
        for (&i, pose) in bodies.iter().zip(poses) {
            self.bodies.pose[i] = pose;
        }
        let b = &mut self.bodies;
        for ((info, u), pose) in b.info.iter().zip(b.u.iter_mut()).zip(&b.pose) {
            if !info.fixed {
                *u = [0.0; 6];
                info.impose(u, pose, self.time);
            }
        }
        self.memory.clear();
        self.contacts.clear();
        self.held.clear();
        self.detector = Detector::with_threads(self.threads);
        Ok(())
    }
}

/// Which of a pair's last points (`last`, the last step's points of the pair in rank order) a new point of the
/// pair at `position` continues: of those not yet `taken` by an earlier point of the pair this step (bit `j` for
/// the `j`-th; at most 8 are told apart, a pair has at most 4), the nearest to `position` if within `within` (m),
/// ties to the lower rank; marks it taken. By place, not by rank: a rank follows the features that make the point
/// ([`crate::space::detection`]), and where two faces are flush their corners come from either body as the bodies
/// shift by round-off, so the same corner changes rank from step to step.
fn previous_point<'c>(
    last: impl Iterator<Item = &'c Contact3>,
    position: &Vec3,
    within: f64,
    taken: &mut u8,
) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (j, c) in last.enumerate().take(8) {
        let d = (c.point - position).norm();
        if *taken & (1 << j) == 0 && d <= within && best.is_none_or(|(_, b)| d < b) {
            best = Some((j, d));
        }
    }
    best.map(|(j, _)| {
        *taken |= 1 << j;
        j
    })
}

/// Whether two values serialise to the same JSON (floats bit for bit through serde_json's shortest round trip).
fn same<T: Serialize>(a: &T, b: &T) -> bool {
    serde_json::to_value(a).ok() == serde_json::to_value(b).ok()
}

/// The radius of the largest sphere about the centroid inside a solid (m): a polyhedron's inradius, a sphere's
/// radius, infinite for a half-space. Half of the smaller of a pair's is the deepest overlap a step may leave.
pub fn inradius(solid: &crate::geometry::Solid) -> f64 {
    match solid {
        crate::geometry::Solid::Polyhedron(p) => p.inradius,
        crate::geometry::Solid::Sphere { radius } => *radius,
        crate::geometry::Solid::HalfSpace => f64::INFINITY,
    }
}
