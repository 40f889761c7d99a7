//! One time step of the Moreau–Jean θ-method (Saussine et al. 2006, §2.2, §2.7):
//!
//! 1. `q_m = q_i + (1 − θ) h u_i` and `t_m = t_i + (1 − θ) h`;
//! 2. contact detection at `q_m`, contact frames and `H`, `H*`, `W` frozen there;
//! 3. `u_free = u_i + h M⁻¹ F(q_m, t_m)` (gravity and external loads); imposed
//!    velocity components take their value at `t_f`;
//! 4. NLGS on `u_f = u_free + M⁻¹ Σ H P` (eq. 12–15), warm-started with the
//!    impulses of the previous step matched by contact key;
//! 5. `q_f = q_m + θ h u_f`.
//!
//! A step whose sweeps stop short of the tolerance goes on, is extended or stops
//! the run ([`super::nlgs::OnStall`]). After the step the state is checked: a non-finite value or an overlap deeper
//! than half the smaller inradius of the two bodies stops the run with an error
//! naming the step and body, and the state goes back to the start of the step.

use super::apgd::{solve_apgd_with, ApgdOptions};
use super::contact::ContactRow;
use super::nlgs::{apply_impulses, NlgsReport, NlgsSettings, OnStall, Solver};
use super::system::{StepStats, System, Workspace};
use crate::error::{Error, Result};
use crate::geometry::Vec2;

impl System {
    /// Advances by one step of `params.dt`.
    pub fn step(&mut self) -> Result<StepStats> {
        self.params.check()?;
        if self.gravity_reference.is_none() {
            self.gravity_reference = Some(self.lowest_point());
        }
        let h = self.params.dt;
        let theta = self.params.theta;
        let t_f = self.origin.time_at(self.step + 1, h);
        let t_m = t_f - theta * h;
        let mut ws = std::mem::take(&mut self.ws);
        ws.q_i.clone_from(&self.bodies.q);
        ws.u_i.clone_from(&self.bodies.u);

        // 1. Intermediate configuration.
        ws.q_m.clone_from(&self.bodies.q);
        let mut v_max: f64 = 0.0;
        for ((qm, u), info) in ws.q_m.iter_mut().zip(&self.bodies.u).zip(&self.bodies.info) {
            for (q, v) in qm.iter_mut().zip(u) {
                *q += (1.0 - theta) * h * v;
            }
            v_max = v_max.max(u[0].hypot(u[1]) + u[2].abs() * info.shape.bounding_radius());
        }
        if let Some(i) = ws.q_m.iter().position(|q| q.iter().any(|x| !x.is_finite() || x.abs() > 1e12)) {
            return Err(self.roll_back(ws, i, "non-finite or runaway position".into()));
        }
        // 2. Detection, contact and spring rows at q_m.
        self.build_rows(&mut ws, h, theta, v_max);

        // 3. Free velocity.
        self.free_velocity(h, t_m, t_f);

        // 4. The step's solve.
        let report = self.solve(&mut ws);
        if !report.converged && self.params.nlgs.on_stall == OnStall::Stop {
            self.restore_start(ws);
            return Err(Error::Stalled {
                step: self.step + 1,
                iterations: report.iterations,
                criterion: report.criterion,
                tolerance: self.params.nlgs.tolerance,
            });
        }

        // 5. Final configuration.
        for ((q, qm), u) in self.bodies.q.iter_mut().zip(&ws.q_m).zip(&self.bodies.u) {
            for d in 0..3 {
                q[d] = qm[d] + theta * h * u[d];
            }
        }

        // Statistics and sanity checks.
        let (stats, failure) = self.statistics(&ws, &report, t_f, h, theta);
        if let Some((body, what)) = failure {
            return Err(self.roll_back(ws, body, what));
        }

        // Keep the contacts and impulses for the next warm start.
        self.contacts.clear();
        self.contacts.extend_from_slice(&ws.geoms);
        self.impulses.clear();
        self.impulses.extend(ws.rows.iter().map(|r| r.p));
        for (s, row) in self.springs.iter_mut().zip(&ws.spring_rows) {
            s.impulse = row.p;
        }
        self.time = t_f;
        self.step += 1;
        self.ws = ws;
        Ok(stats)
    }

    /// Puts the bodies back at the start of the step and the workspace in place.
    fn restore_start(&mut self, ws: Workspace) {
        self.bodies.q.clone_from(&ws.q_i);
        self.bodies.u.clone_from(&ws.u_i);
        self.ws = ws;
    }

    /// Restores the state of the start of the failed step and names the culprit.
    fn roll_back(&mut self, ws: Workspace, body: usize, what: String) -> Error {
        self.restore_start(ws);
        Error::Diverged { step: self.step + 1, body, name: self.bodies.info[body].name.clone(), what }
    }
}

/// The stages of a step, in the order [`System::step`] calls them (`ws` is the workspace, taken out of the
/// system for the step).
impl System {
    /// Stage 2: detection at `q_m` within the alert distance (at least the distance covered in two steps at the
    /// largest speed `v_max`), the contact rows with their frames, Delassus blocks and thresholds, warm-started
    /// with the impulses of the previous step matched by contact key, and the sublayer springs' rows.
    fn build_rows(&self, ws: &mut Workspace, h: f64, theta: f64, v_max: f64) {
        let alert = self.params.alert_distance.max(2.0 * h * v_max);
        ws.detector.run(&self.bodies, &ws.q_m, alert);
        ws.rows.clear();
        ws.geoms.clear();
        let mut prev = 0;
        for (key, c) in &ws.detector.found {
            let (a, b) = (key.0 as usize, key.1 as usize);
            let ga = Vec2::new(ws.q_m[a][0], ws.q_m[a][1]);
            let gb = Vec2::new(ws.q_m[b][0], ws.q_m[b][1]);
            let mut row = ContactRow::new(
                (key.0, key.1),
                c.point,
                c.normal,
                (ga, gb),
                (&self.bodies.inv_m[a], &self.bodies.inv_m[b]),
                (&ws.u_i[a], &ws.u_i[b]),
                c.gap,
                h,
                self.law(a, b),
            );
            // Warm start: both lists are sorted by key.
            while prev < self.contacts.len() && self.contacts[prev].key < *key {
                prev += 1;
            }
            if prev < self.contacts.len() && self.contacts[prev].key == *key {
                row.p = self.impulses[prev];
            }
            ws.rows.push(row);
            ws.geoms.push(super::contact::ContactGeom { key: *key, point: c.point, normal: c.normal, gap: c.gap });
        }
        ws.spring_rows.clear();
        for s in &self.springs {
            ws.spring_rows.push(s.row((&ws.q_i, &ws.u_i), &ws.q_m, &self.bodies.inv_m, h, theta));
        }
    }

    /// Stage 3: `u_free = u_i + h M⁻¹ F(q_m, t_m)` (gravity and the loads at `t_m`); imposed velocity
    /// components take their value at `t_f`.
    fn free_velocity(&mut self, h: f64, t_m: f64, t_f: f64) {
        let n = self.bodies.len();
        let g = self.params.gravity;
        for i in 0..n {
            let info = &self.bodies.info[i];
            if info.fixed {
                continue;
            }
            let mut f = [info.mass * g[0], info.mass * g[1], 0.0];
            for load in &info.loads {
                let l = load.at(t_m);
                f[0] += l[0];
                f[1] += l[1];
            }
            let im = self.bodies.inv_m[i];
            let u = &mut self.bodies.u[i];
            for d in 0..3 {
                u[d] += h * im[d] * f[d];
                if let Some(v) = info.imposed.dof[d] {
                    u[d] = v.at(t_f);
                }
            }
        }
    }

    /// Stage 4: the step's problem solved by the scene's solver, from `u_free` plus the warm-start impulses.
    fn solve(&mut self, ws: &mut Workspace) -> NlgsReport {
        apply_impulses(&mut self.bodies.u, &self.bodies.inv_m, &ws.rows, &ws.spring_rows);
        let settings = &self.params.nlgs;
        match settings.solver {
            // Plain sweeps when `anderson` is 0.
            Solver::Nlgs => super::method::anderson::solve_nlgs_anderson_split(
                settings,
                &mut ws.anderson,
                &mut ws.split,
                ws.threads,
                |i| ws.q_m[i][0],
                &mut self.bodies.u,
                &self.bodies.inv_m,
                &mut ws.rows,
                &mut ws.spring_rows,
            ),
            Solver::Apgd => {
                // The accelerated solver has one cap: an extended step gets the larger.
                let s = NlgsSettings { max_iterations: settings.sweep_cap(), ..*settings };
                solve_apgd_with(
                    &s,
                    &ApgdOptions::default(),
                    &mut ws.apgd,
                    &mut self.bodies.u,
                    &self.bodies.inv_m,
                    &mut ws.rows,
                    &mut ws.spring_rows,
                )
            }
            #[cfg(feature = "faer")]
            Solver::InteriorPoint => {
                let s = NlgsSettings { max_iterations: settings.sweep_cap(), ..*settings };
                super::interior::solve_interior(
                    &s,
                    &Default::default(),
                    &mut ws.interior,
                    &mut self.bodies.u,
                    &self.bodies.inv_m,
                    &mut ws.rows,
                    &mut ws.spring_rows,
                )
            }
            // `params.check` (the first thing a step does) refuses a solver this build
            // does not have, so this arm is never taken.
            #[cfg(not(feature = "faer"))]
            Solver::InteriorPoint => NlgsReport { iterations: 0, criterion: f64::INFINITY, converged: false },
        }
    }

    /// The step's statistics at `q_f` and the first failure found (the body to name and what went wrong): a
    /// runaway overlap (beyond half the smaller inradius of the pair), a non-finite state, a crushed spring, a
    /// body beyond the scene's bounds or a kinetic energy overflow.
    fn statistics(
        &self,
        ws: &Workspace,
        report: &NlgsReport,
        t_f: f64,
        h: f64,
        theta: f64,
    ) -> (StepStats, Option<(usize, String)>) {
        let n = self.bodies.len();
        let mut stats = StepStats {
            time: t_f,
            step: self.step + 1,
            contacts: ws.rows.len(),
            iterations: report.iterations,
            criterion: report.criterion,
            converged: report.converged,
            ..Default::default()
        };
        let mut sum_overlap = 0.0;
        let mut failure = None;
        for (r, geom) in ws.rows.iter().zip(&ws.geoms) {
            let (ua, ub) = (&self.bodies.u[r.a as usize], &self.bodies.u[r.b as usize]);
            let un = super::contact::dot3(&r.hn_a, ua) - super::contact::dot3(&r.hn_b, ub);
            let g_f = geom.gap + theta * h * un;
            let overlap = (-g_f).max(0.0);
            if r.p[0] > 0.0 || overlap > 0.0 {
                stats.active_contacts += 1;
                sum_overlap += overlap;
            }
            stats.max_overlap = stats.max_overlap.max(overlap);
            let limit = 0.5
                * self.bodies.info[r.a as usize]
                    .shape
                    .inner_radius()
                    .min(self.bodies.info[r.b as usize].shape.inner_radius());
            if (overlap > limit || !g_f.is_finite()) && failure.is_none() {
                // Name the body that moved into the other (the candidate unless it is fixed).
                let (culprit, other) = if self.bodies.is_mobile(r.a as usize) { (r.a, r.b) } else { (r.b, r.a) };
                failure = Some((culprit as usize, format!("runaway overlap {overlap:.3e} m with body {other}")));
            }
        }
        stats.total_overlap = sum_overlap;
        if stats.active_contacts > 0 {
            stats.mean_overlap = sum_overlap / stats.active_contacts as f64;
        }
        if let Some(i) = (0..n).find(|&i| self.bodies.q[i].iter().chain(&self.bodies.u[i]).any(|x| !x.is_finite())) {
            failure = Some((i, "non-finite position or velocity".to_string()));
        }
        if failure.is_none() {
            failure = crate::plane::springs::crushed(&self.springs, &self.bodies.q);
        }
        // Scenes place bodies within ±MAX_LENGTH (the detection grid and the
        // restart scene, `final_scene.toml`, rely on it): a body carried beyond
        // has run away.
        let far = crate::geometry::MAX_LENGTH;
        if let Some(i) = (0..n).find(|&i| failure.is_none() && self.bodies.q[i][..2].iter().any(|x| x.abs() > far)) {
            failure = Some((i, format!("runaway position: its centre of mass is beyond ±{far:e} m")));
        }
        stats.kinetic_energy = self.bodies.kinetic_energy();
        if failure.is_none() && !stats.kinetic_energy.is_finite() {
            let speed = |i: usize| self.bodies.u[i][0].hypot(self.bodies.u[i][1]);
            let i = (0..n).max_by(|&a, &b| speed(a).total_cmp(&speed(b))).unwrap_or(0);
            failure = Some((i, "kinetic energy overflow".to_string()));
        }
        (stats, failure)
    }
}
