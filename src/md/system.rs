//! The MD system and its time step.
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

use super::contact::{self, History, Kinematics};
use super::ghosts::Ghosts;
use super::integrator::{predict, Integrator};
use super::law::LawTable;
use super::neighbours::Neighbours;
use super::particles::{rotate, Particles, V3};
use super::walls::{self, Wall};
use crate::error::{Error, Result};
use crate::team::Team;
use nalgebra::{Matrix3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// Default neighbour skin of a scene, as a fraction of the mean sphere diameter (m/m).
pub const DEFAULT_SKIN_FRACTION: f64 = 0.1;

/// Run settings of the MD engine (SI). [`MdSettings::default`] gives the
/// defaults of scenes (`[simulation]` and `[md]` of the MD scene format), but
/// for the time step, which a scene must give, and the skin, whose scene
/// default follows the spheres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MdSettings {
    /// Time step (s), > 0 and below the contacts' stability limit; default 1e-6
    /// (scenes must give it).
    pub dt: f64,
    /// Gravity (m/s²); default `[0, 0, −9.81]`.
    pub gravity: V3,
    /// Integrator; default velocity Verlet (a scene's `gear` default is
    /// Karrech's set, [`super::GearSet::Karrech`]).
    pub integrator: Integrator,
    /// Neighbour skin (m), > 0; default 1e-3 here; a scene's default is
    /// [`DEFAULT_SKIN_FRACTION`] × the mean sphere diameter.
    pub skin: f64,
    /// Translational background damping `γ_b` (kg/s): `f = −γ_b v`; default 0.
    pub background_damping: f64,
    /// Rotational background damping `γ_br` (kg/s): `τ = −γ_br r² ω` on a sphere of
    /// radius `r` (Luding's form, so that `γ_br` has the unit of `γ_b`; the paper's
    /// 0.05 kg/s then relaxes spins in `2/5 m/γ_br`, 8 ms for its 1 g spheres);
    /// default 0.
    pub background_rotational_damping: f64,
}

impl Default for MdSettings {
    fn default() -> Self {
        MdSettings {
            dt: 1e-6,
            gravity: V3::new(0.0, 0.0, -9.81),
            integrator: Integrator::Verlet,
            skin: 1e-3,
            background_damping: 0.0,
            background_rotational_damping: 0.0,
        }
    }
}

/// What one step measured (forces at its evaluation, state at its end).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MdStepStats {
    /// Time at the end of the step (s).
    pub time: f64,
    /// Translational + rotational kinetic energy (J).
    pub kinetic_energy: f64,
    /// Elastic energy stored in the contacts (J); a contact with a symmetry image counts half.
    pub elastic_energy: f64,
    /// Sphere–sphere contacts (a contact with an image counts half).
    pub contacts: f64,
    /// Sphere–wall contacts.
    pub wall_contacts: usize,
    /// Largest overlap (m).
    pub max_overlap: f64,
    /// Mean overlap over all contacts (m).
    pub mean_overlap: f64,
    /// Coordination number `(2 N_c + N_w) / N`.
    pub coordination: f64,
}

/// Contact statistics of one chunk of a force evaluation.
#[derive(Debug, Clone, Copy)]
struct Tally {
    contacts: f64,
    sum_overlap: f64,
    overlaps: usize,
    max_overlap: f64,
    energy: f64,
    /// Σ f ⊗ l over contacts (N·m): the sample's stress times its volume.
    virial: Matrix3<f64>,
    /// Worst overlap relative to the smaller radius, and its sphere.
    worst: (f64, usize),
}

impl Default for Tally {
    fn default() -> Self {
        Tally {
            contacts: 0.0,
            sum_overlap: 0.0,
            overlaps: 0,
            max_overlap: 0.0,
            energy: 0.0,
            virial: Matrix3::zeros(),
            worst: (0.0, 0),
        }
    }
}

impl Tally {
    fn add(&mut self, o: &Tally) {
        self.contacts += o.contacts;
        self.sum_overlap += o.sum_overlap;
        self.overlaps += o.overlaps;
        self.max_overlap = self.max_overlap.max(o.max_overlap);
        self.energy += o.energy;
        self.virial += o.virial;
        if o.worst.0 > self.worst.0 {
            self.worst = o.worst;
        }
    }
}

/// Force buffers and statistics of one chunk of the pair loop.
#[derive(Debug, Clone, Default)]
struct Workspace {
    f: Vec<V3>,
    t: Vec<V3>,
    tally: Tally,
}

/// What one chunk of spheres reports from the last phase of a step.
#[derive(Debug, Clone, Default)]
struct Tail {
    /// Force of the chunk's spheres on each wall (N), and their number.
    wall_force: Vec<V3>,
    wall_contacts: Vec<usize>,
    /// Sphere–wall contact statistics.
    tally: Tally,
    /// Kinetic energy of the chunk after the step (J), non-finite if a position
    /// or velocity is.
    kinetic: f64,
    /// `Σ m (x · up)` over the chunk after the step (kg·m), for the gravitational energy.
    height: f64,
    /// First sphere with a non-finite force or torque.
    bad_force: Option<usize>,
}

/// A copy of the whole dynamic state, for going back to the last good step when a step fails: the spheres,
/// the walls, the neighbour list with its contact memory, the images, the integrator's derivatives, the
/// virial, the last statistics and the clock, each field of [`MdSystem`] copied whole (`clone_from` reuses
/// the buffers of the previous copy), so that a field added to one of these structures is backed up without
/// a line here. What a step only reads (settings, laws, the origins of the clock and of the energy check)
/// is not copied.
#[derive(Debug, Clone, Default)]
struct Backup {
    /// Whether a copy has been taken.
    taken: bool,
    particles: Particles,
    walls: Vec<Wall>,
    wall_hist: Vec<History>,
    neighbours: Neighbours,
    ghosts: Ghosts,
    gear_x: Vec<[V3; 6]>,
    gear_w: Vec<[V3; 6]>,
    force_x: Vec<V3>,
    virial: Matrix3<f64>,
    last: MdStepStats,
    time: f64,
    step: u64,
    drive_work: f64,
}

fn one() -> u64 {
    1
}

fn unknown() -> f64 {
    f64::NAN
}

/// Whether two vectors are the same bit for bit.
fn same_bits(a: &V3, b: &V3) -> bool {
    a.iter().zip(b.iter()).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// Spheres per chunk below which a step stays on one thread (a phase must
/// outlast the hand-over to the helper by far).
const PAR_MIN: usize = 256;

/// The work of a step is cut into this many chunks (pairs balanced by count,
/// spheres by index), run side by side when two threads are allowed and serially
/// otherwise: the floating-point sums are the same, so a run gives the same
/// numbers on one thread or two.
pub const CHUNKS: usize = 2;

/// Steps between two copies of the last good state.
const BACKUP_EVERY: u64 = 100;

/// A sphere whose centre leaves `±POSITION_BOUND` (m) on an axis ends the step
/// with a divergence: the bounds of a scene ([`crate::geometry::MAX_LENGTH`]), so
/// that the state of a run can always be written back as a valid scene.
pub const POSITION_BOUND: f64 = crate::geometry::MAX_LENGTH;

/// The energy-growth check stops a run whose spheres hold more than
/// `E_0 + W + ENERGY_GROWTH (|E_0| + W)`, with `E_0` the mechanical energy at the
/// start and `W` the work of the servo drives since: without numerical
/// instability `E_k + E_g ≤ E_0 + W` (contacts, damping and friction dissipate,
/// the elastic energy is not negative), so only a blow-up (a time step above
/// the contact time, an unstable damping) exceeds it by a factor, within a few
/// dozen steps of its exponential growth.
pub const ENERGY_GROWTH: f64 = 10.0;

/// A 3D MD system of spheres and walls.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MdSystem {
    /// Time step, integrator, damping, gravity, neighbour skin, threads.
    pub settings: MdSettings,
    /// The spheres: positions, velocities, orientations, forces, masses (struct of arrays).
    pub particles: Particles,
    /// Planes, discs, cylinders and servo walls.
    pub walls: Vec<Wall>,
    /// Contact law of every pair of materials.
    pub laws: LawTable,
    /// Symmetry planes and the images of the spheres near them.
    pub ghosts: Ghosts,
    /// Verlet neighbour list (with its skin) and the pairs' tangential memory.
    pub neighbours: Neighbours,
    /// Time (s) at the end of the last step: `t_0 + (step − k_0) dt` from [`MdSystem::origin`]
    /// ([`crate::clock`]), never accumulated.
    pub time: f64,
    /// Steps made.
    pub step: u64,
    /// The clock's origin: the time and step at which the time step last changed.
    #[serde(flatten)]
    pub origin: crate::clock::Origin,
    /// Mechanical energy `E_k + E_g + E_el` (J) when the system was built or its
    /// configuration last written ([`MdSystem::set_configuration`]): with the work
    /// of the servo drives, the budget of the energy-growth check. Read from a
    /// file without it (NaN), it is taken from the state at the next step.
    #[serde(default = "unknown")]
    pub energy_start: f64,
    /// Work of the servo walls' drives since then, in absolute value (J).
    #[serde(default)]
    pub drive_work: f64,
    /// Gear: scaled derivatives of the positions (rows 0..q).
    gear_x: Vec<[V3; 6]>,
    /// Gear: scaled derivatives of the rotation vector (rows 1..q).
    gear_w: Vec<[V3; 6]>,
    /// Sample virial `Σ f ⊗ l` of the last evaluation (N·m).
    pub virial: Matrix3<f64>,
    /// Statistics of the last step.
    pub last: MdStepStats,
    /// Zero of the gravitational energy, as a height along `−g` (m): the highest
    /// upward-facing plane wall below every sphere if there is one (a base), else
    /// the lowest sphere bottom of the initial state.
    #[serde(default)]
    pub gravity_reference: f64,
    /// Energies, virial and overlap statistics are computed on steps that are
    /// multiples of this (default 1: every step); other steps carry the last
    /// measured values in their [`MdStepStats`]. Kinetic energy is always exact.
    #[serde(default = "one")]
    pub measure_every: u64,
    /// Contact memory of the sphere–wall contacts, sphere by sphere: entry
    /// `i · walls + k` for sphere `i` and wall `k`.
    #[serde(default)]
    pub(super) wall_hist: Vec<History>,
    /// Centres of the spheres at the last force evaluation when they are not
    /// `particles.x`: with a Gear integrator whose corrector moves the centres
    /// (`gear4` to `gear6`), the predicted centres; empty otherwise (velocity
    /// Verlet drifts before the evaluation, Karrech's and `gear3`'s corrector
    /// leaves the positions) and after the derived state is rebuilt. Read only by
    /// the contact list ([`MdSystem::contact_forces`]).
    #[serde(default)]
    pub(super) force_x: Vec<V3>,
    /// Set while a relaxation evaluates trial configurations
    /// ([`super::relax`]): a runaway overlap is then a large energy, not an error.
    #[serde(skip)]
    pub(super) relaxing: bool,
    #[serde(skip)]
    threads: usize,
    #[serde(skip)]
    team: Team,
    #[serde(skip)]
    work: Vec<Workspace>,
    #[serde(skip)]
    tails: Vec<Tail>,
    #[serde(skip)]
    backup: Backup,
    /// Centres and radii of the spheres and their images, for the neighbour build.
    #[serde(skip)]
    all_x: Vec<V3>,
    #[serde(skip)]
    all_r: Vec<f64>,
}

impl MdSystem {
    /// A system at time 0 of `particles` (spheres, [`Particles::add_sphere`]),
    /// `walls`, the contact `laws` of the pairs of materials and the symmetry
    /// planes of `ghosts` (`Ghosts::new(Vec::new())`: none), stepped with
    /// `settings` ([`MdSettings::default`] and its fields); forces are evaluated
    /// once so that the first step starts from the right accelerations.
    ///
    /// The time step is not checked against the contacts' stability limit (MD
    /// scenes check it; [`super::law::PairLaw::contact_time`] gives the time
    /// scale a step must resolve, some 1/50 of it is safe).
    ///
    /// # Errors
    /// [`Error::Scene`] if a pair of materials that can touch (two spheres, a
    /// sphere and its symmetry image, a sphere and a wall) has no law, naming both
    /// materials and where they meet ([`LawTable::check_covers`]), or if a sphere
    /// or wall has a material index not below `laws.n`.
    pub fn new(
        settings: MdSettings,
        particles: Particles,
        walls: Vec<Wall>,
        laws: LawTable,
        ghosts: Ghosts,
    ) -> Result<Self> {
        laws.check_covers(&particles, &walls, !ghosts.planes.is_empty())?;
        let mut sys = MdSystem {
            settings,
            neighbours: Neighbours::new(settings.skin),
            particles,
            walls,
            laws,
            ghosts,
            time: 0.0,
            step: 0,
            origin: crate::clock::Origin::default(),
            energy_start: 0.0,
            drive_work: 0.0,
            gear_x: Vec::new(),
            gear_w: Vec::new(),
            virial: Matrix3::zeros(),
            last: MdStepStats::default(),
            measure_every: 1,
            gravity_reference: 0.0,
            wall_hist: Vec::new(),
            force_x: Vec::new(),
            relaxing: false,
            threads: 1,
            team: Team::default(),
            work: Vec::new(),
            tails: Vec::new(),
            backup: Backup::default(),
            all_x: Vec::new(),
            all_r: Vec::new(),
        };
        sys.gravity_reference = sys.initial_reference();
        sys.reset_derived();
        Ok(sys)
    }

    /// Rebuilds every state derived from the positions and velocities, as at the
    /// start of a run: contact memory forgotten, neighbour list and images built,
    /// forces evaluated (so that the first step starts from the right
    /// accelerations), Gear derivatives started from them, the energy budget and
    /// the backup of the last good state taken.
    fn reset_derived(&mut self) {
        let settings = self.settings;
        let skin = self.neighbours.skin;
        self.neighbours = Neighbours::new(skin);
        let n = self.particles.len();
        self.wall_hist = vec![History::default(); n * self.walls.len()];
        let sys = self;
        sys.rebuild();
        sys.ghosts.update(&sys.particles);
        let stats = sys.forces(0.0, true, false).map(|(s, _, _)| s).unwrap_or_default();
        sys.last = MdStepStats { time: sys.time, kinetic_energy: sys.particles.kinetic_energy(), ..stats };
        sys.gear_x.clear();
        sys.gear_w.clear();
        if let Integrator::Gear(set) = settings.integrator {
            let q = set.order();
            let dt = settings.dt;
            sys.gear_x = (0..n)
                .map(|i| {
                    let p = &sys.particles;
                    let mut d = [V3::zeros(); 6];
                    d[0] = p.x[i];
                    d[1] = p.v[i] * dt;
                    if q > 2 {
                        d[2] = (p.f[i] * p.inv_m[i] + settings.gravity) * (0.5 * dt * dt);
                    }
                    d
                })
                .collect();
            sys.gear_w = (0..n)
                .map(|i| {
                    let p = &sys.particles;
                    let mut d = [V3::zeros(); 6];
                    d[1] = p.w[i] * dt;
                    d[2] = p.t[i] * p.inv_i[i] * (0.5 * dt * dt);
                    d
                })
                .collect();
        }
        sys.energy_start = sys.last.kinetic_energy + sys.gravitational_energy() + sys.last.elastic_energy;
        sys.drive_work = 0.0;
        sys.save_backup();
    }

    fn initial_reference(&self) -> f64 {
        let up = self.up();
        let p = &self.particles;
        let lowest = (0..p.len()).map(|i| p.x[i].dot(&up) - p.r[i]).fold(f64::INFINITY, f64::min);
        let base = self
            .walls
            .iter()
            .filter_map(|w| Some((w.normal()?, w.point()?)))
            .filter(|(n, p)| (n - up).norm() < 1e-9 && p.dot(&up) <= lowest)
            .map(|(_, p)| p.dot(&up))
            .fold(f64::NEG_INFINITY, f64::max);
        if base.is_finite() {
            base
        } else if lowest.is_finite() {
            lowest
        } else {
            0.0
        }
    }

    /// Number of threads of a step: 1, or 2 (the caller and a helper that spins
    /// between the phases of a step; more are not used). The numbers do not
    /// depend on it: the work is always cut into the same [`CHUNKS`] chunks.
    pub fn set_threads(&mut self, threads: usize) {
        // The next step starts or stops the team's helper to match.
        self.threads = threads.clamp(1, CHUNKS);
    }

    /// Threads in use.
    pub fn threads(&self) -> usize {
        self.threads.max(1)
    }

    /// What the two-thread team of the step's phases did so far: joins run side
    /// by side, taken back by the caller, or run in turn (zero on one thread).
    pub fn team_stats(&self) -> crate::team::TeamStats {
        self.team.stats()
    }

    /// Changes the time step (s) from now on, keeping the clock exact.
    pub fn set_dt(&mut self, dt: f64) {
        self.origin.rebase(self.time, self.step);
        self.settings.dt = dt;
    }

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

    /// Moves the spheres of `c` to its positions (centre `x, y, z`, m; rotation
    /// vector of the orientation, rad), sets every velocity and spin to zero (and
    /// the servo walls' rates), forgets the contact memory and rebuilds every
    /// derived state — neighbour list, images, forces, Gear derivatives, energy
    /// budget, backup — so that the next step starts from this configuration
    /// exactly as a system built there would (on either integrator). The clock
    /// and the walls' positions go on.
    ///
    /// # Errors
    /// [`Error::Scene`] if `c` has not 6 coordinates per sphere, names an unknown
    /// sphere or holds a non-finite value; the system is then unchanged.
    pub fn set_configuration(&mut self, c: &crate::engine::Configuration) -> Result<()> {
        c.check(6, self.particles.len())?;
        let p = &mut self.particles;
        for (k, &i) in c.bodies.iter().enumerate() {
            let q = c.body(k);
            p.x[i] = V3::new(q[0], q[1], q[2]);
            p.q[i] = UnitQuaternion::from_scaled_axis(V3::new(q[3], q[4], q[5]));
        }
        p.v.iter_mut().chain(p.w.iter_mut()).for_each(|v| *v = V3::zeros());
        for w in &mut self.walls {
            w.s_dot = 0.0;
        }
        self.reset_derived();
        Ok(())
    }

    /// Moves the servo walls, in scene order, to the displacements `s` (m along
    /// their normals), at rest, and rebuilds the derived state as
    /// [`MdSystem::set_configuration`] does.
    ///
    /// # Errors
    /// [`Error::Scene`] if `s` has not one finite value per servo wall; the system
    /// is then unchanged.
    pub fn set_servo_positions(&mut self, s: &[f64]) -> Result<()> {
        let servo: Vec<usize> =
            (0..self.walls.len()).filter(|&k| matches!(self.walls[k].motion, walls::Motion::Servo { .. })).collect();
        if s.len() != servo.len() {
            return Err(Error::Scene(format!("boundaries: {} coordinates for {} servo walls", s.len(), servo.len())));
        }
        if let Some(k) = s.iter().position(|v| !v.is_finite()) {
            return Err(Error::Scene(format!(
                "boundaries: wall '{}': {} is not finite",
                self.walls[servo[k]].name, s[k]
            )));
        }
        for (&k, &v) in servo.iter().zip(s) {
            self.walls[k].s = v;
            self.walls[k].s_dot = 0.0;
        }
        self.reset_derived();
        Ok(())
    }

    /// Checks that the state holds together (a state read from a checkpoint):
    /// array lengths, material and partner indices, the neighbour rows, finite
    /// positions and velocities, the clock, the Gear positions, and the state
    /// derived from the positions at the last neighbour build (images, neighbour
    /// list, wall candidates, their contact memory: built again from
    /// `neighbours.x_build` and the walls at `s_build`, they must come out the
    /// same). The message names what is wrong.
    pub fn check_state(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::Scene(msg));
        let p = &self.particles;
        let n = p.len();
        let lens = [p.v.len(), p.w.len(), p.f.len(), p.t.len(), p.r.len(), p.m.len(), p.inv_m.len()];
        let more = [p.inv_i.len(), p.material.len(), p.q.len(), p.name.len()];
        if lens.iter().chain(&more).any(|&l| l != n) {
            return bad(format!("spheres: arrays of different lengths for {n} spheres"));
        }
        let finite = |v: &V3| v.iter().all(|x| x.is_finite());
        if let Some(i) = (0..n).find(|&i| !(finite(&p.x[i]) && finite(&p.v[i]) && finite(&p.w[i]))) {
            return bad(format!("sphere {i}: a position or velocity is not finite"));
        }
        if let Some(i) = (0..n).find(|&i| !(p.r[i] > 0.0 && p.m[i] > 0.0 && p.inv_m[i].is_finite())) {
            return bad(format!("sphere {i}: radius or mass is not positive"));
        }
        if let Some(i) = (0..n).find(|&i| p.material[i] as usize >= self.laws.n) {
            return bad(format!("sphere {i}: material {} of {}", p.material[i], self.laws.n));
        }
        if self.laws.n.checked_mul(self.laws.n) != Some(self.laws.laws.len()) {
            return bad(format!("{} laws for {} materials", self.laws.laws.len(), self.laws.n));
        }
        if !(self.laws.names.is_empty() || self.laws.names.len() == self.laws.n) {
            return bad(format!("{} material names for {} materials", self.laws.names.len(), self.laws.n));
        }
        let gear = matches!(self.settings.integrator, Integrator::Gear(_));
        let expected = if gear { n } else { 0 };
        if self.gear_x.len() != expected || self.gear_w.len() != expected {
            return bad(format!("Gear derivatives of {} spheres for {n}", self.gear_x.len()));
        }
        // The corrector leaves the position in the first Gear row.
        if let Some(i) = (0..self.gear_x.len()).find(|&i| !same_bits(&self.gear_x[i][0], &p.x[i])) {
            return bad(format!("sphere {i}: the Gear position is not the sphere's"));
        }
        if !self.force_x.is_empty() && self.force_x.len() != n {
            return bad(format!("centres of the last force evaluation: {} for {n} spheres", self.force_x.len()));
        }
        let nw = self.walls.len();
        if self.wall_hist.len() != n * nw {
            return bad(format!(
                "wall contact memory of {} entries for {n} spheres and {nw} walls",
                self.wall_hist.len()
            ));
        }
        let nb = &self.neighbours;
        let rows_ok = nb.start.len() == n + 1
            && nb.start[0] == 0
            && nb.start.windows(2).all(|w| w[0] <= w[1])
            && nb.start[n] as usize == nb.j.len();
        if !rows_ok || nb.key.len() != nb.j.len() || nb.hist.len() != nb.j.len() {
            return bad("neighbour list: rows, partners, keys and memory do not match".into());
        }
        let n_all = n + self.ghosts.len();
        if nb.j.iter().any(|&j| j as usize >= n_all) || nb.x_build.len() != n {
            return bad("neighbour list: a partner or build position out of range".into());
        }
        if nb.skin.to_bits() != self.settings.skin.to_bits() {
            return bad(format!("neighbour list: skin {} m, the settings' is {} m", nb.skin, self.settings.skin));
        }
        let g = &self.ghosts;
        if g.mask.len() != g.len() || g.key.len() != g.len() || g.origin.iter().any(|&i| i as usize >= n) {
            return bad("symmetry images: origins, masks and keys do not match".into());
        }
        if let Some(w) = self.walls.iter().find(|w| w.candidates.iter().any(|&i| i as usize >= n)) {
            return bad(format!("wall '{}': a candidate sphere out of range", crate::error::clip(&w.name)));
        }
        if !(self.settings.dt.is_finite() && self.settings.dt > 0.0) {
            return bad(format!("time step {} s", self.settings.dt));
        }
        // The derived state, built again where it was built.
        let mut again = self.clone();
        again.particles.x.clone_from(&nb.x_build);
        for w in &mut again.walls {
            w.s = w.s_build;
        }
        again.rebuild();
        let (a, b) = (&again.neighbours, &again.ghosts);
        if a.start != nb.start || a.j != nb.j || a.key != nb.key || a.hist != nb.hist {
            return bad("neighbour list: not the list of the spheres at its build".into());
        }
        if b.origin != g.origin || b.mask != g.mask || b.key != g.key {
            return bad("symmetry images: not the images of the spheres at the last build".into());
        }
        if let Some((w, _)) = self.walls.iter().zip(&again.walls).find(|(w, v)| w.candidates != v.candidates) {
            let name = crate::error::clip(&w.name);
            return bad(format!("wall '{name}': not the candidate spheres of the last build"));
        }
        if again.wall_hist != self.wall_hist {
            return bad("wall contact memory: held for spheres that are not candidates".into());
        }
        self.origin.check(self.step, Some(self.time), self.settings.dt).or_else(bad)?;
        Ok(())
    }

    /// Checks that `self` is a state of the model `fresh` (the system built from
    /// the same scene): the same spheres (names, radii, masses, materials),
    /// walls (names, shapes, motions), laws, symmetry planes, settings,
    /// measurement period, clock origin, zero of the gravitational energy and
    /// energy at the start.
    pub fn check_same_model(&self, fresh: &MdSystem) -> Result<()> {
        let bad = |what: String| Err(Error::Scene(format!("{what} differs from the scene's")));
        let (a, b) = (&self.particles, &fresh.particles);
        if a.len() != b.len() {
            return bad(format!("the number of spheres ({})", a.len()));
        }
        for i in 0..a.len() {
            let same = a.name[i] == b.name[i]
                && a.r[i].to_bits() == b.r[i].to_bits()
                && a.m[i].to_bits() == b.m[i].to_bits()
                && a.inv_m[i].to_bits() == b.inv_m[i].to_bits()
                && a.inv_i[i].to_bits() == b.inv_i[i].to_bits()
                && a.material[i] == b.material[i];
            if !same {
                return bad(format!("sphere {i} ('{}')", crate::error::clip(&b.name[i])));
            }
        }
        if self.walls.len() != fresh.walls.len() {
            return bad(format!("the number of walls ({})", self.walls.len()));
        }
        for (w, f) in self.walls.iter().zip(&fresh.walls) {
            if w.name != f.name || w.material != f.material || w.shape != f.shape || w.motion != f.motion {
                return bad(format!("wall '{}'", crate::error::clip(&f.name)));
            }
        }
        let same = |x: &dyn Fn(&MdSystem) -> serde_json::Value| x(self) == x(fresh);
        if !same(&|s| serde_json::to_value(&s.laws).unwrap_or_default()) {
            return bad("the contact laws".into());
        }
        if !same(&|s| serde_json::to_value(&s.ghosts.planes).unwrap_or_default()) {
            return bad("the symmetry planes".into());
        }
        if self.settings != fresh.settings || self.measure_every != fresh.measure_every {
            return bad("the [md] settings, time step or measurement period".into());
        }
        // The run loop never changes the time step: the clock keeps its origin.
        if !self.origin.same(&fresh.origin) {
            return bad("the clock's origin".into());
        }
        // Set when the system is built: the zero of the gravitational energy. (The
        // energy budget of the divergence check is state: a configuration written
        // back during a run resets it.)
        if self.gravity_reference.to_bits() != fresh.gravity_reference.to_bits() {
            return bad("the zero of the gravitational energy".into());
        }
        Ok(())
    }

    /// Names the sphere `body` in a divergence of the step being made.
    fn diverged(&self, body: usize, what: String) -> Error {
        Error::Diverged {
            step: self.step + 1,
            body,
            name: self.particles.name.get(body).cloned().unwrap_or_default(),
            what,
        }
    }

    fn save_backup(&mut self) {
        let b = &mut self.backup;
        b.taken = true;
        b.particles.clone_from(&self.particles);
        b.walls.clone_from(&self.walls);
        b.wall_hist.clone_from(&self.wall_hist);
        b.neighbours.clone_from(&self.neighbours);
        b.ghosts.clone_from(&self.ghosts);
        b.gear_x.clone_from(&self.gear_x);
        b.gear_w.clone_from(&self.gear_w);
        b.force_x.clone_from(&self.force_x);
        b.virial = self.virial;
        b.last = self.last;
        b.time = self.time;
        b.step = self.step;
        b.drive_work = self.drive_work;
    }

    fn restore_backup(&mut self) {
        let b = &self.backup;
        if !b.taken || b.particles.len() != self.particles.len() {
            return;
        }
        self.particles.clone_from(&b.particles);
        self.walls.clone_from(&b.walls);
        self.wall_hist.clone_from(&b.wall_hist);
        self.neighbours.clone_from(&b.neighbours);
        self.ghosts.clone_from(&b.ghosts);
        self.ghosts.update(&self.particles);
        self.gear_x.clone_from(&b.gear_x);
        self.gear_w.clone_from(&b.gear_w);
        self.force_x.clone_from(&b.force_x);
        self.virial = b.virial;
        self.last = b.last;
        self.time = b.time;
        self.step = b.step;
        self.drive_work = b.drive_work;
    }

    /// Rebuilds the images, the neighbour list and the wall candidate lists.
    pub fn rebuild(&mut self) {
        let p = &self.particles;
        let n = p.len();
        let skin = self.settings.skin;
        let r_max = p.max_radius();
        self.ghosts.select(&p.x, 2.0 * r_max + skin);
        self.ghosts.update(p);
        // Spheres then images, in buffers kept between builds.
        let (x, r) = (&mut self.all_x, &mut self.all_r);
        x.clear();
        x.extend_from_slice(&p.x);
        x.extend_from_slice(&self.ghosts.x);
        r.clear();
        r.extend_from_slice(&p.r);
        r.extend(self.ghosts.origin.iter().map(|&i| p.r[i as usize]));
        self.neighbours.build(x, r, n, &self.ghosts.key);
        let nw = self.walls.len();
        self.wall_hist.resize(n * nw, History::default());
        for (k, w) in self.walls.iter_mut().enumerate() {
            w.candidates.clear();
            for i in 0..n {
                match w.gap(&p.x[i], p.r[i]) {
                    Some((gap, _, _)) if gap < skin => w.candidates.push(i as u32),
                    _ => self.wall_hist[i * nw + k] = History::default(),
                }
            }
            w.s_build = w.s;
        }
    }

    /// Evaluates all forces at the current state (images already mirrored),
    /// advancing the contact memory by `dt` (s), and with `integrate` finishes
    /// the step (second half kick or corrector). Returns the statistics, the
    /// kinetic energy after the step (J) and `Σ m (x · up)` (kg·m; both 0
    /// without `integrate`).
    pub(super) fn forces(&mut self, dt: f64, measure: bool, integrate: bool) -> Result<(MdStepStats, f64, f64)> {
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

/// Read-only data of the pair loop.
struct PairContext<'a> {
    p: &'a Particles,
    g: &'a Ghosts,
    laws: &'a LawTable,
    start: &'a [u32],
    j: &'a [u32],
    dt: f64,
    measure: bool,
}

/// Runs the chunks `bounds[k]..bounds[k+1]` (rows) side by side on `team`, each
/// on its own workspace and its own slice of the contact memory (which starts at
/// entry `offset`).
fn run_chunks(
    team: &Team,
    ctx: &PairContext,
    bounds: &[usize],
    hist: &mut [History],
    offset: usize,
    work: &mut [Workspace],
) {
    let chunks = bounds.len() - 1;
    if chunks == 1 {
        pair_rows(ctx, bounds[0], bounds[1], hist, offset, &mut work[0]);
        return;
    }
    let mid = chunks / 2;
    let split = ctx.start[bounds[mid]] as usize - offset;
    let (h0, h1) = hist.split_at_mut(split);
    let (w0, w1) = work.split_at_mut(mid);
    team.join(
        || run_chunks(team, ctx, &bounds[..=mid], h0, offset, w0),
        || run_chunks(team, ctx, &bounds[mid..], h1, offset + split, w1),
    );
}

/// Forces of the pairs of rows `lo..hi` into `w` (cleared first).
#[inline(never)]
fn pair_rows(ctx: &PairContext, lo: usize, hi: usize, hist: &mut [History], offset: usize, w: &mut Workspace) {
    let p = ctx.p;
    let n = p.len();
    let dt = ctx.dt;
    w.f.clear();
    w.f.resize(n, V3::zeros());
    w.t.clear();
    w.t.resize(n, V3::zeros());
    let mut tally = Tally::default();
    for i in lo..hi {
        let (xi, vi, wi, ri, mi, mati) = (p.x[i], p.v[i], p.w[i], p.r[i], p.m[i], p.material[i] as usize);
        let mut fi = V3::zeros();
        let mut ti = V3::zeros();
        let (e0, e1) = (ctx.start[i] as usize, ctx.start[i + 1] as usize);
        for (&j, h) in ctx.j[e0..e1].iter().zip(&mut hist[e0 - offset..e1 - offset]) {
            let j = j as usize;
            let ghost = j >= n;
            let (xj, o) = if ghost {
                let g = j - n;
                (ctx.g.x[g], ctx.g.origin[g] as usize)
            } else {
                (p.x[j], j)
            };
            let rj = p.r[o];
            let d = xi - xj;
            let dist2 = d.norm_squared();
            let rs = ri + rj;
            if dist2 >= rs * rs {
                if h.delta != 0.0 {
                    *h = History::default();
                }
                continue;
            }
            let Some(law) = ctx.laws.get(mati, p.material[o] as usize) else { continue };
            let (vj, wj) = if ghost { (ctx.g.v[j - n], ctx.g.w[j - n]) } else { (p.v[j], p.w[j]) };
            let dist = dist2.sqrt();
            let nrm = if dist > 0.0 { d * (1.0 / dist) } else { V3::z() };
            let delta = rs - dist;
            let ai = ri - 0.5 * delta;
            let aj = rj - 0.5 * delta;
            let v_rel = vi - vj + nrm.cross(&(wi * ai + wj * aj));
            let mj = p.m[o];
            let inv = 1.0 / (rs * (mi + mj));
            let k = Kinematics {
                n: nrm,
                delta,
                v_rel,
                // R* = ri rj / (ri + rj), m* = mi mj / (mi + mj): one division.
                r_star: ri * rj * (mi + mj) * inv,
                m_star: mi * mj * rs * inv,
                measure: ctx.measure,
            };
            let cf = contact::force(law, &k, h, dt);
            h.force = cf.force;
            fi += cf.force;
            let arm = nrm.cross(&cf.tangential);
            ti -= arm * ai;
            let weight = if ghost { 0.5 } else { 1.0 };
            tally.contacts += weight;
            if ctx.measure {
                // Branch vector from j's centre to i's centre.
                tally.virial += (cf.force * weight) * d.transpose();
                tally.energy += cf.energy * weight;
                tally.sum_overlap += delta;
                tally.overlaps += 1;
                tally.max_overlap = tally.max_overlap.max(delta);
            }
            if delta > 0.5 * ri.min(rj) {
                let rel = delta / ri.min(rj);
                if rel > tally.worst.0 {
                    tally.worst = (rel, i);
                }
            }
            if !ghost {
                w.f[j] -= cf.force;
                w.t[j] -= arm * aj;
            }
        }
        w.f[i] += fi;
        w.t[i] += ti;
    }
    w.tally = tally;
}

/// Read-only data of the last phase of a step.
struct TailContext<'a> {
    /// The pair loop's force buffers, one per chunk.
    work: &'a [Workspace],
    walls: &'a [Wall],
    laws: &'a LawTable,
    /// Background damping `(γ_b, γ_br)` (kg/s).
    damping: (f64, f64),
    integrator: Integrator,
    gravity: V3,
    /// Unit vector against gravity.
    up: V3,
    dt: f64,
    /// Finish the step (second half kick or corrector) after the forces.
    integrate: bool,
}

/// The last phase of a step on one chunk of spheres: total force and torque of
/// each sphere (pair buffers summed, walls, background damping), then the second
/// half of the integrator. `hist` is the chunk's wall contact memory.
fn tail(c: View, hist: &mut [History], ctx: &TailContext, out: &mut Tail) {
    let (lo, len) = (c.lo, c.len());
    let nw = ctx.walls.len();
    let dt = ctx.dt;
    out.wall_force.clear();
    out.wall_force.resize(nw, V3::zeros());
    out.wall_contacts.clear();
    out.wall_contacts.resize(nw, 0);
    out.bad_force = None;
    out.kinetic = 0.0;
    let mut tally = Tally::default();
    for i in 0..len {
        let mut f = V3::zeros();
        let mut t = V3::zeros();
        for w in ctx.work {
            f += w.f[lo + i];
            t += w.t[lo + i];
        }
        c.f[i] = f;
        c.t[i] = t;
    }
    for (k, wall) in ctx.walls.iter().enumerate() {
        let cand = &wall.candidates;
        let a = cand.partition_point(|&i| (i as usize) < lo);
        let b = cand.partition_point(|&i| (i as usize) < lo + len);
        let vw = wall.velocity();
        for &gi in &cand[a..b] {
            let i = gi as usize - lo;
            let touching = wall.gap(&c.x[i], c.r[i]).filter(|g| g.0 < 0.0);
            let h = &mut hist[i * nw + k];
            let Some((gap, nrm, r_star)) = touching else {
                *h = History::default();
                continue;
            };
            let Some(law) = ctx.laws.get(c.material[i] as usize, wall.material as usize) else { continue };
            let delta = -gap;
            let a = c.r[i] - delta;
            let v_rel = c.v[i] + nrm.cross(&c.w[i]) * a - vw;
            let k_ = Kinematics { n: nrm, delta, v_rel, r_star, m_star: c.m[i], measure: true };
            let cf = contact::force(law, &k_, h, dt);
            h.force = cf.force;
            c.f[i] += cf.force;
            c.t[i] += nrm.cross(&cf.tangential) * (-a);
            out.wall_force[k] -= cf.force;
            out.wall_contacts[k] += 1;
            tally.sum_overlap += delta;
            tally.overlaps += 1;
            tally.max_overlap = tally.max_overlap.max(delta);
            tally.energy += cf.energy;
            if delta / c.r[i] > tally.worst.0 {
                tally.worst = (delta / c.r[i], lo + i);
            }
        }
    }
    let (gb, gr) = ctx.damping;
    if gb != 0.0 || gr != 0.0 {
        for i in 0..len {
            c.f[i] -= c.v[i] * gb;
            c.t[i] -= c.w[i] * (gr * c.r[i] * c.r[i]);
        }
    }
    out.bad_force = (0..len).find(|&i| !(c.f[i].iter().all(|a| a.is_finite()) && c.t[i].iter().all(|a| a.is_finite())));
    out.bad_force = out.bad_force.map(|i| lo + i);
    out.tally = tally;
    if ctx.integrate {
        (out.kinetic, out.height) = second_half(c, ctx.integrator, ctx.gravity, ctx.up, dt);
    }
}

/// The per-sphere arrays the integrator touches, split into chunks for threads.
struct View<'a> {
    /// Index of the first sphere of the chunk.
    lo: usize,
    x: &'a mut [V3],
    v: &'a mut [V3],
    w: &'a mut [V3],
    f: &'a mut [V3],
    t: &'a mut [V3],
    r: &'a [f64],
    m: &'a [f64],
    material: &'a [u32],
    inv_m: &'a [f64],
    inv_i: &'a [f64],
    q: &'a mut [UnitQuaternion<f64>],
    /// Gear derivatives (empty with Verlet).
    gx: &'a mut [[V3; 6]],
    gw: &'a mut [[V3; 6]],
    /// Positions at the last neighbour build (empty if unused).
    x0: &'a [V3],
}

impl<'a> View<'a> {
    fn new(p: &'a mut Particles, gx: &'a mut [[V3; 6]], gw: &'a mut [[V3; 6]], x0: &'a [V3]) -> Self {
        View {
            lo: 0,
            x: &mut p.x,
            v: &mut p.v,
            w: &mut p.w,
            f: &mut p.f,
            t: &mut p.t,
            r: &p.r,
            m: &p.m,
            material: &p.material,
            inv_m: &p.inv_m,
            inv_i: &p.inv_i,
            q: &mut p.q,
            gx,
            gw,
            x0,
        }
    }

    fn len(&self) -> usize {
        self.x.len()
    }

    /// The two chunks (always [`CHUNKS`] = 2, whatever the threads).
    fn halves(self) -> (View<'a>, View<'a>) {
        let at = self.len() / CHUNKS;
        self.split(at)
    }

    fn split(self, at: usize) -> (View<'a>, View<'a>) {
        let (x0, x1) = self.x.split_at_mut(at);
        let (v0, v1) = self.v.split_at_mut(at);
        let (w0, w1) = self.w.split_at_mut(at);
        let (f0, f1) = self.f.split_at_mut(at);
        let (t0, t1) = self.t.split_at_mut(at);
        let (r0, r1) = self.r.split_at(at);
        let (mm0, mm1) = self.m.split_at(at);
        let (c0, c1) = self.material.split_at(at);
        let (m0, m1) = self.inv_m.split_at(at);
        let (i0, i1) = self.inv_i.split_at(at);
        let (q0, q1) = self.q.split_at_mut(at);
        let g = at.min(self.gx.len());
        let (gx0, gx1) = self.gx.split_at_mut(g);
        let (gw0, gw1) = self.gw.split_at_mut(g);
        let b = at.min(self.x0.len());
        let (b0, b1) = self.x0.split_at(b);
        let lo = self.lo;
        (
            View {
                lo,
                x: x0,
                v: v0,
                w: w0,
                f: f0,
                t: t0,
                r: r0,
                m: mm0,
                material: c0,
                inv_m: m0,
                inv_i: i0,
                q: q0,
                gx: gx0,
                gw: gw0,
                x0: b0,
            },
            View {
                lo: lo + at,
                x: x1,
                v: v1,
                w: w1,
                f: f1,
                t: t1,
                r: r1,
                m: mm1,
                material: c1,
                inv_m: m1,
                inv_i: i1,
                q: q1,
                gx: gx1,
                gw: gw1,
                x0: b1,
            },
        )
    }
}

/// Before the force evaluation: half kick and drift (Verlet) or predictor (Gear).
/// Returns the largest squared displacement since the last neighbour build (m²;
/// 0 if the view has no build positions).
fn first_half(c: View, integrator: Integrator, g: V3, dt: f64) -> f64 {
    match integrator {
        Integrator::Verlet => {
            for i in 0..c.x.len() {
                c.v[i] += (c.f[i] * c.inv_m[i] + g) * (0.5 * dt);
                c.w[i] += c.t[i] * (c.inv_i[i] * 0.5 * dt);
                c.x[i] += c.v[i] * dt;
            }
        }
        Integrator::Gear(set) => {
            let q = set.order();
            for i in 0..c.x.len() {
                predict(&mut c.gx[i], 0, q);
                predict(&mut c.gw[i], 1, q);
                c.x[i] = c.gx[i][0];
                c.v[i] = c.gx[i][1] / dt;
                c.w[i] = c.gw[i][1] / dt;
            }
        }
    }
    if c.x0.len() != c.x.len() {
        return 0.0;
    }
    // A non-finite position is skipped here (no rebuild over it); the force
    // evaluation reports it.
    c.x.iter().zip(c.x0).map(|(a, b)| (a - b).norm_squared()).fold(0.0, f64::max)
}

/// After the force evaluation: second half kick (Verlet) or corrector (Gear),
/// orientations; returns the kinetic energy of the chunk (J), non-finite if a
/// velocity is or a position is not within [`POSITION_BOUND`], and `Σ m (x · up)` (kg·m).
fn second_half(c: View, integrator: Integrator, g: V3, up: V3, dt: f64) -> (f64, f64) {
    let mut kinetic = 0.0;
    let mut height = 0.0;
    let mut finite = true;
    match integrator {
        Integrator::Verlet => {
            for i in 0..c.x.len() {
                c.v[i] += (c.f[i] * c.inv_m[i] + g) * (0.5 * dt);
                c.w[i] += c.t[i] * (c.inv_i[i] * 0.5 * dt);
                rotate(&mut c.q[i], &c.w[i], dt);
                // Solid sphere: I = 2/5 m r².
                kinetic += 0.5 * c.m[i] * (c.v[i].norm_squared() + 0.4 * c.r[i] * c.r[i] * c.w[i].norm_squared());
                height += c.m[i] * c.x[i].dot(&up);
                finite &= c.x[i].iter().all(|a| a.abs() <= POSITION_BOUND);
            }
        }
        Integrator::Gear(set) => {
            let coef = set.coefficients();
            let h2 = 0.5 * dt * dt;
            for i in 0..c.x.len() {
                let dx = (c.f[i] * c.inv_m[i] + g) * h2 - c.gx[i][2];
                let dw = c.t[i] * (c.inv_i[i] * h2) - c.gw[i][2];
                for (k, ck) in coef.iter().enumerate() {
                    c.gx[i][k] += dx * *ck;
                    if k > 0 {
                        c.gw[i][k] += dw * *ck;
                    }
                }
                c.x[i] = c.gx[i][0];
                c.v[i] = c.gx[i][1] / dt;
                c.w[i] = c.gw[i][1] / dt;
                rotate(&mut c.q[i], &c.w[i], dt);
                // Solid sphere: I = 2/5 m r².
                kinetic += 0.5 * c.m[i] * (c.v[i].norm_squared() + 0.4 * c.r[i] * c.r[i] * c.w[i].norm_squared());
                height += c.m[i] * c.x[i].dot(&up);
                finite &= c.x[i].iter().all(|a| a.abs() <= POSITION_BOUND);
            }
        }
    }
    if finite {
        (kinetic, height)
    } else {
        (f64::NAN, height)
    }
}
