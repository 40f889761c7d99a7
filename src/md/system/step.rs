//! The time step of the MD system.
//!
//! Data flow of a step (velocity Verlet), in three phases that each run as two
//! chunks side by side on a [`Team`] (or one after the other on one thread):
//! 1. half kick and drift of every sphere, largest displacement since the last
//!    neighbour build; then, on the caller, the neighbour list rebuilt if needed
//!    ([`super::neighbours`], images of the symmetry planes re-selected with it)
//!    and the images mirrored ([`super::ghosts`]);
//! 2. pair forces ([`super::contact`], half list cut into two chunks of rows
//!    with as many pairs each, one force buffer per chunk);
//! 3. per chunk of spheres: the two buffers summed, wall forces ([`super::walls`]),
//!    background damping, second half kick; then, on the caller, the wall loads
//!    and statistics of the chunks summed and the servo walls advanced.
//!
//! With a Gear integrator the kicks are replaced by the predictor before and the
//! corrector after the force evaluation ([`super::integrator`]). The chunks are
//! the same whatever the number of threads, so are the sums: a run gives the same
//! numbers on one thread or two.

use super::kernels::*;
use super::*;

impl MdSystem {
    /// Makes one time step.
    ///
    /// # Errors
    /// [`Error::Diverged`] (the step being made and a sphere named) if a force or
    /// position becomes non-finite, two bodies overlap by more than half the
    /// smaller radius, or the energy of the spheres grows beyond what they were
    /// given ([`MdSystem::energy_start`] + [`MdSystem::drive_work`], ×
    /// [`ENERGY_GROWTH`]); the system then holds the state of the last good step:
    /// the last backup (at most a hundred steps back) is restored and the steps
    /// from it to the last good one are made again (the same numbers).
    pub fn step(&mut self) -> Result<MdStepStats> {
        if !self.energy_start.is_finite() {
            self.energy_start =
                self.particles.kinetic_energy() + self.gravitational_energy() + self.last.elastic_energy;
        }
        let good = self.step;
        match self.advance() {
            Ok(stats) => Ok(stats),
            Err(e) => {
                self.restore_backup();
                while self.step < good {
                    if self.advance().is_err() {
                        // Cannot happen (the same steps succeeded before); keep the backup.
                        self.restore_backup();
                        break;
                    }
                }
                Err(e)
            }
        }
    }

    /// One step, leaving the state as it is on failure (see [`MdSystem::step`]).
    fn advance(&mut self) -> Result<MdStepStats> {
        let n = self.particles.len();
        let parallel = self.threads > 1 && n >= CHUNKS * PAR_MIN;
        if parallel && self.team.threads() < 2 {
            self.team = Team::new(2);
        } else if !parallel && self.team.threads() > 1 {
            self.team = Team::default();
        }
        // A system read from a file without the wall contact memory starts afresh.
        let nw = self.walls.len();
        if self.wall_hist.len() != n * nw {
            self.wall_hist = vec![History::default(); n * nw];
        }
        let dt = self.settings.dt;
        let g = self.settings.gravity;
        let integrator = self.settings.integrator;
        // Phase 1: predictor, and how far the spheres went since the last build.
        let built = self.neighbours.x_build.len() == n;
        let moved2 = {
            let MdSystem { particles, gear_x, gear_w, neighbours, team, .. } = self;
            let x0 = if built { &neighbours.x_build[..] } else { &[] };
            let view = View::new(particles, gear_x, gear_w, x0);
            let (a, b) = view.halves();
            let (ma, mb) = team.join(|| first_half(a, integrator, g, dt), || first_half(b, integrator, g, dt));
            ma.max(mb)
        };
        let d = moved2.sqrt();
        let dw = self.walls.iter().map(|w| (w.s - w.s_build).abs()).fold(0.0, f64::max);
        if !built || d + d.max(dw) > self.settings.skin {
            self.rebuild();
        }
        self.ghosts.update(&self.particles);
        // Phases 2 and 3.
        let measure = (self.step + 1).is_multiple_of(self.measure_every.max(1));
        let (stats, kinetic, height) = self.forces(dt, measure, true)?;
        if !kinetic.is_finite() {
            let p = &self.particles;
            let inside = |x: &V3| x.iter().all(|c| c.abs() <= POSITION_BOUND);
            let i = (0..p.len()).find(|&i| !(inside(&p.x[i]) && p.v[i].iter().all(|c| c.is_finite()))).unwrap_or(0);
            let what = if p.x[i].iter().all(|c| c.is_finite()) && p.v[i].iter().all(|c| c.is_finite()) {
                format!("carried beyond ±{POSITION_BOUND:e} m (the bounds of a scene)")
            } else {
                "position or velocity is not finite".to_string()
            };
            return Err(self.diverged(i, what));
        }
        let t_next = self.origin.time_at(self.step + 1, dt);
        self.drive_work += walls::advance(&mut self.walls, t_next, dt);
        self.check_energy(kinetic, height)?;
        self.time = t_next;
        self.step += 1;
        let stats = if measure {
            stats
        } else {
            MdStepStats {
                contacts: stats.contacts,
                wall_contacts: stats.wall_contacts,
                coordination: stats.coordination,
                ..self.last
            }
        };
        let stats = MdStepStats { time: self.time, kinetic_energy: kinetic, ..stats };
        self.last = stats;
        if self.step.is_multiple_of(BACKUP_EVERY) {
            self.save_backup();
        }
        Ok(stats)
    }

    /// The energy-growth check after a step with kinetic energy `kinetic` (J) and
    /// `Σ m (x · up) = height` (kg·m); the sphere of largest kinetic energy is named.
    fn check_energy(&self, kinetic: f64, height: f64) -> Result<()> {
        let gn = self.settings.gravity.norm();
        let mass: f64 = self.particles.m.iter().sum();
        let gravitational = gn * (height - mass * self.gravity_reference);
        let budget = self.energy_start + self.drive_work;
        let limit = budget + ENERGY_GROWTH * (self.energy_start.abs() + self.drive_work) + f64::MIN_POSITIVE;
        let energy = kinetic + gravitational;
        if energy <= limit {
            return Ok(());
        }
        let p = &self.particles;
        let ek = |i: usize| p.m[i] * p.v[i].norm_squared() + 0.4 * p.m[i] * p.r[i] * p.r[i] * p.w[i].norm_squared();
        let i = (0..p.len()).max_by(|&a, &b| ek(a).total_cmp(&ek(b))).unwrap_or(0);
        Err(self.diverged(
            i,
            format!(
                "runaway energy: the spheres hold {energy:.3e} J (kinetic + gravitational), more than {:.0}× the \
                 {budget:.3e} J they were given (time step too large for the contacts, or unstable damping?)",
                ENERGY_GROWTH + 1.0
            ),
        ))
    }

    /// Evaluates all forces at the current state (images already mirrored),
    /// advancing the contact memory by `dt` (s), and with `integrate` finishes
    /// the step (second half kick or corrector). Returns the statistics, the
    /// kinetic energy after the step (J) and `Σ m (x · up)` (kg·m; both 0
    /// without `integrate`).
    pub(in crate::md) fn forces(&mut self, dt: f64, measure: bool, integrate: bool) -> Result<(MdStepStats, f64, f64)> {
        let n = self.particles.len();
        let nw = self.walls.len();
        self.work.resize_with(CHUNKS, Workspace::default);
        self.tails.resize_with(CHUNKS, Tail::default);
        // Phase 2: pair forces, rows cut so that each chunk has about as many pairs.
        let total = self.neighbours.pairs();
        let mut bounds = [0usize; CHUNKS + 1];
        let mut row = 0;
        #[allow(clippy::needless_range_loop)]
        for c in 1..CHUNKS {
            let target = total * c / CHUNKS;
            while row < n && (self.neighbours.start[row] as usize) < target {
                row += 1;
            }
            bounds[c] = row;
        }
        bounds[CHUNKS] = n;
        let ctx = PairContext {
            p: &self.particles,
            g: &self.ghosts,
            laws: &self.laws,
            start: &self.neighbours.start,
            j: &self.neighbours.j,
            dt,
            measure,
        };
        run_chunks(&self.team, &ctx, &bounds, &mut self.neighbours.hist, 0, &mut self.work);
        // The centres of this evaluation, for the contact list, if the corrector
        // is about to move them.
        let corrects_x = matches!(self.settings.integrator, Integrator::Gear(set) if set.coefficients()[0] != 0.0);
        if integrate && corrects_x {
            self.force_x.clone_from(&self.particles.x);
        } else {
            self.force_x.clear();
        }
        // Phase 3: per chunk of spheres, sum, walls, damping, second half.
        let s = &self.settings;
        let ctx = TailContext {
            work: &self.work,
            walls: &self.walls,
            laws: &self.laws,
            damping: (s.background_damping, s.background_rotational_damping),
            integrator: s.integrator,
            gravity: s.gravity,
            up: self.up(),
            dt,
            integrate,
        };
        {
            let MdSystem { particles, gear_x, gear_w, team, wall_hist, tails, .. } = self;
            let view = View::new(particles, gear_x, gear_w, &[]);
            let at = view.len() / CHUNKS;
            let (a, b) = view.halves();
            let (ha, hb) = wall_hist.split_at_mut(at * nw);
            let (ta, tb) = tails.split_at_mut(1);
            team.join(|| tail(a, ha, &ctx, &mut ta[0]), || tail(b, hb, &ctx, &mut tb[0]));
        }
        // Sums over the chunks, in chunk order.
        let mut tally = Tally::default();
        for w in &self.work {
            tally.add(&w.tally);
        }
        let mut kinetic = 0.0;
        let mut height = 0.0;
        let mut bad_force = None;
        for (k, wall) in self.walls.iter_mut().enumerate() {
            wall.force = V3::zeros();
            wall.contacts = 0;
            for t in &self.tails {
                wall.force += t.wall_force[k];
                wall.contacts += t.wall_contacts[k];
            }
        }
        for t in &self.tails {
            tally.add(&t.tally);
            kinetic += t.kinetic;
            height += t.height;
            bad_force = bad_force.or(t.bad_force);
        }
        let wall_contacts = self.walls.iter().map(|w| w.contacts).sum::<usize>();
        self.virial = tally.virial;
        let (worst, worst_i) = tally.worst;
        if (worst > 0.5 && !self.relaxing) || !tally.energy.is_finite() {
            let r = self.particles.r[worst_i];
            return Err(self.diverged(
                worst_i,
                format!("runaway overlap: {:.3e} m, {:.0} % of the radius", worst * r, 100.0 * worst),
            ));
        }
        if let Some(i) = bad_force {
            return Err(self.diverged(i, "contact force is not finite".into()));
        }
        let contacts = tally.contacts;
        let stats = MdStepStats {
            time: self.time,
            kinetic_energy: 0.0,
            elastic_energy: tally.energy,
            contacts,
            wall_contacts,
            max_overlap: tally.max_overlap,
            mean_overlap: if tally.overlaps > 0 { tally.sum_overlap / tally.overlaps as f64 } else { 0.0 },
            coordination: if n > 0 { (2.0 * contacts + wall_contacts as f64) / n as f64 } else { 0.0 },
        };
        Ok((stats, kinetic, height))
    }
}
