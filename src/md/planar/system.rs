//! The planar MD system: the 2D bodies, loads, sublayer springs and shadow-overlap
//! detection of [`crate::plane`] (shared with the NSCD engine) under explicit
//! soft-contact dynamics ([`super::law`]), integrated by velocity Verlet:
//!
//! `u_{k+½} = u_k + h/2 M⁻¹ F_k`, `q_{k+1} = q_k + h u_{k+½}`,
//! `F_{k+1} = F(q_{k+1}, u_{k+½}, t_{k+1})`, `u_{k+1} = u_{k+½} + h/2 M⁻¹ F_{k+1}`,
//!
//! with `M⁻¹` per degree of freedom (zero for a fixed body or an imposed
//! component, which takes its imposed value at `t_{k+½}` and `t_{k+1}`). The
//! dashpots see the half-step velocity (first order in `h` for them, second for
//! the conservative forces). `F` is gravity, the bodies' loads at `t`, the
//! springs' law (17) explicitly, and the contact forces: every contact point
//! that the shadow overlap gives with a negative gap `−δ` gets the normal and
//! tangential force of the pair's law at that point, on the candidate and
//! opposite on the antagonist, with the torques of the point's lever arms.
//! The tangential memory of a point is kept while the detection finds its key
//! (candidate, antagonist, feature pair) overlapping from step to step.

use super::law::SoftLaw;
use crate::clock;
use crate::error::{Error, Result};
use crate::geometry::{cross, Shape, Vec2};
use crate::md::contact::{force, History, Kinematics};
use crate::md::law::PairLaw;
use crate::plane::{Bodies, ContactInfo, ContactKey, Detector, Spring};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

type V3 = Vector3<f64>;

/// Time-stepping parameters of a planar MD system.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanarParams {
    /// Time step `h` (s).
    pub dt: f64,
    /// Gravity (m/s²).
    pub gravity: [f64; 2],
    /// Detection distance (m): the shadow overlap reports pairs with a gap below it;
    /// only overlapping points (gap < 0) carry a force. 0 by default.
    pub alert_distance: f64,
}

impl Default for PlanarParams {
    fn default() -> Self {
        Self { dt: 1e-5, gravity: [0.0, -9.81], alert_distance: 0.0 }
    }
}

/// One contact point with its memory.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
struct Point {
    key: ContactKey,
    /// The law's memory (tangential spring or force, overlap, stick/slip, the
    /// force of the last evaluation).
    hist: History,
    /// Where it was at the last evaluation (m).
    point: [f64; 2],
    /// Unit normal towards the candidate at the last evaluation.
    normal: [f64; 2],
}

/// What one step measured (its force evaluation at the end of the step).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct PlanarStepStats {
    /// Time at the end of the step (s).
    pub time: f64,
    /// Overlapping contact points.
    pub contacts: usize,
    /// Overlapping contact points whose normal force is positive.
    pub active_contacts: usize,
    /// Sum of the overlaps (m).
    pub total_overlap: f64,
    /// Largest overlap (m).
    pub max_overlap: f64,
    /// Mean overlap of the contact points (m), 0 without contacts.
    pub mean_overlap: f64,
    /// Elastic energy of the contacts and springs (J).
    pub elastic_energy: f64,
    /// Kinetic energy at the end of the step (J).
    pub kinetic_energy: f64,
}

/// A planar MD system (module doc): plain serde data, so a run can checkpoint
/// and resume to the same numbers.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PlanarSystem {
    /// Parameters.
    pub params: PlanarParams,
    /// The bodies: `q = (x, y, θ)`, `u = (vx, vy, ω)`, inverse masses per DOF.
    pub bodies: Bodies,
    /// Sublayer springs, law (17), applied explicitly.
    pub springs: Vec<Spring>,
    materials: usize,
    /// Soft law of each pair of materials (row-major, symmetric).
    laws: Vec<Option<SoftLaw>>,
    /// Per pair: the law of a point with the whole stiffness and with half.
    point_laws: Vec<Option<[PairLaw; 2]>>,
    /// The clock's origin: the time and step at which the time step last changed.
    #[serde(flatten)]
    origin: clock::Origin,
    step: u64,
    /// Height (m, along −g) of the zero of the gravitational energy: the lowest
    /// point of the mobile bodies at the first step.
    pub gravity_reference: Option<f64>,
    /// Contact points of the last evaluation, sorted by key.
    points: Vec<Point>,
    /// Their elastic energy (J).
    contact_energy: f64,
    /// Generalized forces `(F_x, F_y, M)` of the last evaluation (N, N, N·m);
    /// empty before the first.
    f: Vec<[f64; 3]>,
    #[serde(skip)]
    work: Workspace,
}

/// Reused buffers (never serialized).
#[derive(Debug, Clone, Default)]
struct Workspace {
    detector: Detector,
    next: Vec<Point>,
    backup_q: Vec<[f64; 3]>,
    backup_u: Vec<[f64; 3]>,
    backup_f: Vec<[f64; 3]>,
    backup_points: Vec<Point>,
    backup_energy: f64,
}

impl PlanarSystem {
    /// An empty system with `materials` materials, no law between them.
    pub fn new(params: PlanarParams, materials: usize) -> Self {
        Self {
            params,
            bodies: Bodies::default(),
            springs: Vec::new(),
            materials,
            laws: vec![None; materials * materials],
            point_laws: vec![None; materials * materials],
            origin: clock::Origin::default(),
            step: 0,
            gravity_reference: None,
            points: Vec::new(),
            contact_energy: 0.0,
            f: Vec::new(),
            work: Workspace::default(),
        }
    }

    /// Sets the soft law between materials `a` and `b` (both ways).
    ///
    /// # Errors
    /// [`Error::Scene`] for a material out of range or a law refused by [`SoftLaw::check`].
    pub fn set_law(&mut self, a: usize, b: usize, law: SoftLaw) -> Result<()> {
        if a >= self.materials || b >= self.materials {
            return Err(Error::Scene(format!(
                "soft law: material {} does not exist ({} materials)",
                a.max(b),
                self.materials
            )));
        }
        law.check()?;
        let resolved = [law.point_law(1.0), law.point_law(0.5)];
        for (i, j) in [(a, b), (b, a)] {
            self.laws[i * self.materials + j] = Some(law);
            self.point_laws[i * self.materials + j] = Some(resolved);
        }
        Ok(())
    }

    /// The soft law between materials `a` and `b`, if set.
    pub fn law(&self, a: usize, b: usize) -> Option<&SoftLaw> {
        self.laws.get(a * self.materials + b).and_then(Option::as_ref)
    }

    /// Time (s), from the exact clock.
    pub fn time(&self) -> f64 {
        self.origin.time_at(self.step, self.params.dt)
    }

    /// Steps made.
    pub fn steps_done(&self) -> u64 {
        self.step
    }

    /// Sets the time step `dt` (s) from now on (the clock keeps the time reached).
    pub fn set_dt(&mut self, dt: f64) {
        self.origin.rebase(self.time(), self.step);
        self.params.dt = dt;
    }

    /// The contact points of the last force evaluation with their forces.
    pub fn contact_forces(&self) -> impl Iterator<Item = ContactInfo> + '_ {
        self.points.iter().map(|p| {
            let n = Vec2::new(p.normal[0], p.normal[1]);
            let f = Vec2::new(p.hist.force.x, p.hist.force.y);
            ContactInfo {
                candidate: p.key.0 as usize,
                antagonist: p.key.1 as usize,
                point: p.point,
                normal: p.normal,
                gap: -p.hist.delta,
                r_n: f.dot(&n),
                r_t: cross(n, f),
            }
        })
    }

    /// Gravitational energy `Σ m |g| h` of the non-fixed bodies (J), `h` the height
    /// of the centre of mass above [`PlanarSystem::gravity_reference`] (the lowest
    /// point now if no step has set it).
    pub fn gravitational_energy(&self) -> f64 {
        let up = crate::plane::bodies::up(self.params.gravity);
        let reference = self.gravity_reference.unwrap_or_else(|| self.bodies.lowest_point(up));
        self.bodies.gravitational_energy(self.params.gravity, reference)
    }

    /// Elastic energy of the springs (J).
    pub fn spring_energy(&self) -> f64 {
        self.springs.iter().map(|s| s.elastic_energy(&self.bodies.q)).sum()
    }

    /// Elastic energy of the contact points at the last force evaluation (J).
    pub fn contact_energy(&self) -> f64 {
        self.contact_energy
    }

    /// Potential energy `E_p` (J): gravitational plus the springs' and the contacts'.
    pub fn potential_energy(&self) -> f64 {
        self.gravitational_energy() + self.spring_energy() + self.contact_energy()
    }

    /// Moves the bodies of `c` to its positions `(x, y, θ)`, sets every velocity to
    /// zero (an imposed component to its value now) and forgets the contact
    /// memory and the forces, so that the next step starts from this
    /// configuration as a system built there would. The clock goes on.
    ///
    /// # Errors
    /// [`Error::Scene`] if `c` has not 3 coordinates per body, names an unknown or
    /// fixed body or holds a non-finite value; the system is then unchanged.
    pub fn set_configuration(&mut self, c: &crate::engine::Configuration) -> Result<()> {
        self.bodies.place(c, self.time())?;
        self.points.clear();
        self.contact_energy = 0.0;
        self.f.clear();
        Ok(())
    }

    /// Removes the overlaps beyond `settings.tolerance` by the mass-metric
    /// projection of both 2D engines ([`crate::plane::relax`]), then writes the
    /// result back as [`PlanarSystem::set_configuration`] does.
    ///
    /// # Errors
    /// [`Error::Scene`] for settings out of range or a held body that does not exist.
    pub fn relax(&mut self, settings: &crate::engine::RelaxSettings) -> Result<crate::engine::RelaxReport> {
        let (report, q) = crate::plane::relax::project(&self.bodies, settings)?;
        let mobile = crate::plane::outputs::mobile_bodies(&self.bodies);
        let mut c = crate::plane::outputs::configuration_of(&self.bodies, &mobile);
        for (k, &i) in mobile.iter().enumerate() {
            c.body_mut(k).copy_from_slice(&q[i]);
        }
        self.set_configuration(&c)?;
        Ok(report)
    }

    /// Checks that the state holds together (a state read from a checkpoint):
    /// bodies and springs ([`crate::plane::outputs::check_bodies`]), laws, contact
    /// keys sorted and in range, forces, parameters and clock.
    ///
    /// # Errors
    /// [`Error::Scene`] naming what is wrong.
    pub fn check_state(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(msg));
        crate::plane::outputs::check_bodies(&self.bodies, self.materials, &self.springs)?;
        let m2 = self.materials * self.materials;
        if self.laws.len() != m2 || self.point_laws.len() != m2 {
            return bad(format!("{} soft laws for {} materials", self.laws.len(), self.materials));
        }
        let n = self.bodies.len();
        if self.points.iter().any(|p| p.key.0 as usize >= n || p.key.1 as usize >= n)
            || self.points.windows(2).any(|w| w[0].key >= w[1].key)
        {
            return bad("contact points: bodies out of range or keys not sorted".into());
        }
        if !(self.f.is_empty() || self.f.len() == n) || self.f.iter().flatten().any(|x| !x.is_finite()) {
            return bad(format!("forces: {} entries for {n} bodies, or not finite", self.f.len()));
        }
        check_params(&self.params)?;
        self.origin.check(self.step, None, self.params.dt).or_else(bad)?;
        Ok(())
    }

    /// Checks that `self` is a state of the model `fresh` (built from the same
    /// scene): bodies, springs, laws, parameters, clock origin.
    ///
    /// # Errors
    /// [`Error::Scene`] "… differs from the scene's".
    pub fn check_same_model(&self, fresh: &Self) -> Result<()> {
        use crate::plane::outputs::same;
        let bad = |what: &str| Err(Error::Scene(format!("{what} differs from the scene's")));
        crate::plane::outputs::check_same_bodies((&self.bodies, &self.springs), (&fresh.bodies, &fresh.springs))?;
        if self.materials != fresh.materials || !same(&self.laws, &fresh.laws) {
            return bad("the soft laws");
        }
        if self.params != fresh.params {
            return bad("the [soft] parameters or time step");
        }
        if !self.origin.same(&fresh.origin) {
            return bad("the clock's origin");
        }
        let up = crate::plane::bodies::up(fresh.params.gravity);
        let reference = match fresh.gravity_reference {
            None if self.step > fresh.step => Some(fresh.bodies.lowest_point(up)),
            r => r,
        };
        if !same(&self.gravity_reference, &reference) {
            return bad("the zero of the gravitational energy");
        }
        Ok(())
    }

    /// One velocity-Verlet step (module doc).
    ///
    /// # Errors
    /// [`Error::Scene`] when two materials without a soft law touch;
    /// [`Error::Diverged`] for a non-finite state or an overlap beyond half the
    /// smaller inradius of the pair, naming the step and a body. On an error the
    /// system is back at the start of the step.
    pub fn step(&mut self) -> Result<PlanarStepStats> {
        let n = self.bodies.len();
        if self.gravity_reference.is_none() {
            self.gravity_reference = Some(self.bodies.lowest_point(crate::plane::bodies::up(self.params.gravity)));
        }
        if self.f.len() != n {
            self.f = vec![[0.0; 3]; n];
            self.evaluate(self.time())?;
        }
        let w = &mut self.work;
        w.backup_q.clone_from(&self.bodies.q);
        w.backup_u.clone_from(&self.bodies.u);
        w.backup_f.clone_from(&self.f);
        w.backup_points.clone_from(&self.points);
        w.backup_energy = self.contact_energy;
        let h = self.params.dt;
        let t0 = self.time();
        self.kick(0.5 * h);
        self.impose(t0 + 0.5 * h);
        for (q, u) in self.bodies.q.iter_mut().zip(&self.bodies.u) {
            q.iter_mut().zip(u).for_each(|(q, u)| *q += h * u);
        }
        self.step += 1;
        let t1 = self.time();
        let outcome = self.evaluate(t1).and_then(|mut stats| {
            self.kick(0.5 * h);
            self.impose(t1);
            self.check()?;
            stats.kinetic_energy = self.bodies.kinetic_energy();
            stats.time = t1;
            Ok(stats)
        });
        if outcome.is_err() {
            let w = &mut self.work;
            self.bodies.q.clone_from(&w.backup_q);
            self.bodies.u.clone_from(&w.backup_u);
            self.f.clone_from(&w.backup_f);
            self.points.clone_from(&w.backup_points);
            self.contact_energy = w.backup_energy;
            self.step -= 1;
        }
        outcome
    }

    /// `u += dt M⁻¹ F`.
    fn kick(&mut self, dt: f64) {
        for ((u, im), f) in self.bodies.u.iter_mut().zip(&self.bodies.inv_m).zip(&self.f) {
            for d in 0..3 {
                u[d] += dt * im[d] * f[d];
            }
        }
    }

    /// Imposed velocity components at time `t` (s).
    fn impose(&mut self, t: f64) {
        for (info, u) in self.bodies.info.iter().zip(self.bodies.u.iter_mut()) {
            if info.fixed {
                continue;
            }
            for (u, v) in u.iter_mut().zip(&info.imposed.dof) {
                if let Some(v) = v {
                    *u = v.at(t);
                }
            }
        }
    }

    /// A non-finite coordinate or velocity, or a crushed spring
    /// ([`crate::plane::springs::crushed`]), stops the step, naming the body.
    fn check(&self) -> Result<()> {
        for (i, (q, u)) in self.bodies.q.iter().zip(&self.bodies.u).enumerate() {
            if q.iter().chain(u).any(|v| !v.is_finite()) {
                return Err(self.diverged(i, "non-finite position or velocity".into()));
            }
        }
        if let Some((body, what)) = crate::plane::springs::crushed(&self.springs, &self.bodies.q) {
            return Err(self.diverged(body, what));
        }
        Ok(())
    }

    fn diverged(&self, body: usize, what: String) -> Error {
        Error::Diverged { step: self.step, body, name: self.bodies.info[body].name.clone(), what }
    }

    /// The forces at the current `q`, `u` and time `t` (s) into `self.f`, the
    /// contact points' memory advanced by one step.
    fn evaluate(&mut self, t: f64) -> Result<PlanarStepStats> {
        let g = self.params.gravity;
        let bodies = &self.bodies;
        for (info, f) in bodies.info.iter().zip(self.f.iter_mut()) {
            *f = [info.mass * g[0], info.mass * g[1], 0.0];
            for load in &info.loads {
                let l = load.at(t);
                f[0] += l[0];
                f[1] += l[1];
            }
        }
        let mut stats = PlanarStepStats::default();
        for s in &self.springs {
            let (r, ha, hb) = s.generalized_force(&bodies.q, &bodies.u);
            self.f[s.a].iter_mut().zip(ha).for_each(|(f, h)| *f += r * h);
            if let Some(b) = s.b {
                self.f[b].iter_mut().zip(hb).for_each(|(f, h)| *f -= r * h);
            }
            stats.elastic_energy += s.elastic_energy(&bodies.q);
        }
        let w = &mut self.work;
        w.detector.run(bodies, &bodies.q, self.params.alert_distance);
        w.next.clear();
        let dt = self.params.dt;
        let mut old = self.points.iter().peekable();
        let mut contact_energy = 0.0;
        for &(key, cp) in &w.detector.found {
            if cp.gap >= 0.0 {
                continue;
            }
            let (a, b) = (key.0 as usize, key.1 as usize);
            let (ia, ib) = (&bodies.info[a], &bodies.info[b]);
            let delta = -cp.gap;
            let limit = 0.5 * ia.shape.inner_radius().min(ib.shape.inner_radius());
            if delta > limit {
                let body = if bodies.is_mobile(a) { a } else { b };
                return Err(Error::Diverged {
                    step: self.step,
                    body,
                    name: bodies.info[body].name.clone(),
                    what: format!("overlap {delta:e} m with body {} beyond half the smaller inradius", a + b - body),
                });
            }
            let laws = self.point_laws[ia.material * self.materials + ib.material].as_ref().ok_or_else(|| {
                Error::Scene(format!(
                    "bodies {a} ('{}') and {b} ('{}') touch, but there is no soft law between their materials {} and {}",
                    crate::error::clip(&ia.name),
                    crate::error::clip(&ib.name),
                    ia.material,
                    ib.material
                ))
            })?;
            let law = &laws[usize::from(share(&ia.shape, &ib.shape) < 1.0)];
            while old.peek().is_some_and(|p| p.key < key) {
                old.next();
            }
            let mut hist = match old.peek() {
                Some(p) if p.key == key => p.hist,
                _ => History::default(),
            };
            let (qa, qb) = (bodies.q[a], bodies.q[b]);
            let (ua, ub) = (bodies.u[a], bodies.u[b]);
            let ra = cp.point - Vec2::new(qa[0], qa[1]);
            let rb = cp.point - Vec2::new(qb[0], qb[1]);
            let va = Vec2::new(ua[0] - ua[2] * ra.y, ua[1] + ua[2] * ra.x);
            let vb = Vec2::new(ub[0] - ub[2] * rb.y, ub[1] + ub[2] * rb.x);
            let v = va - vb;
            let inv = |i: usize| if bodies.info[i].fixed { 0.0 } else { 1.0 / bodies.info[i].mass };
            let m_star = 1.0 / (inv(a) + inv(b));
            let k = Kinematics {
                n: V3::new(cp.normal.x, cp.normal.y, 0.0),
                delta,
                v_rel: V3::new(v.x, v.y, 0.0),
                r_star: 1.0,
                m_star,
                measure: true,
            };
            let c = force(law, &k, &mut hist, dt);
            hist.force = c.force;
            let fv = Vec2::new(c.force.x, c.force.y);
            let (fa, fb) = (&mut self.f[a], cross(ra, fv));
            fa[0] += fv.x;
            fa[1] += fv.y;
            fa[2] += fb;
            let fbod = &mut self.f[b];
            fbod[0] -= fv.x;
            fbod[1] -= fv.y;
            fbod[2] -= cross(rb, fv);
            stats.contacts += 1;
            stats.active_contacts += usize::from(c.normal > 0.0);
            stats.total_overlap += delta;
            stats.max_overlap = stats.max_overlap.max(delta);
            stats.elastic_energy += c.energy;
            contact_energy += c.energy;
            w.next.push(Point { key, hist, point: [cp.point.x, cp.point.y], normal: [cp.normal.x, cp.normal.y] });
        }
        if stats.contacts > 0 {
            stats.mean_overlap = stats.total_overlap / stats.contacts as f64;
        }
        std::mem::swap(&mut self.points, &mut w.next);
        self.contact_energy = contact_energy;
        Ok(stats)
    }
}

/// The share of a pair's stiffness one contact point carries: 1/2 between two
/// polygons (or compound parts), 1 with a disc ([`super::law`]).
fn share(a: &Shape, b: &Shape) -> f64 {
    if matches!(a, Shape::Disc(_)) || matches!(b, Shape::Disc(_)) {
        1.0
    } else {
        0.5
    }
}

/// Checks the parameters' ranges (one-line errors naming the field).
///
/// # Errors
/// [`Error::Scene`].
pub fn check_params(p: &PlanarParams) -> Result<()> {
    if !(p.dt.is_finite() && p.dt > 0.0) {
        return Err(Error::Scene(format!("soft: dt must be positive and finite, got {} s", p.dt)));
    }
    if p.gravity.iter().any(|g| !g.is_finite()) {
        return Err(Error::Scene("simulation.gravity: not finite".into()));
    }
    if !(p.alert_distance.is_finite() && p.alert_distance >= 0.0) {
        return Err(Error::Scene(format!("soft: alert_distance must be >= 0, got {} m", p.alert_distance)));
    }
    Ok(())
}
