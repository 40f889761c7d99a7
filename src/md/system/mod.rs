//! The MD system: its state (spheres, walls, contact laws, images, neighbour list, integrator history, exact
//! clock), its settings, building it ([`MdSystem::new`]) and writing a configuration back. The step is in
//! `step.rs` (its phases: [`MdSystem::step`]) and `kernels.rs` (the chunks' loops), the checks of a state read
//! back in `checks.rs` ([`MdSystem::check_state`]), the copy of the last good state in `backup.rs`.

mod backup;
mod checks;
mod kernels;
mod step;

use backup::Backup;

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

    /// Names the sphere `body` in a divergence of the step being made.
    fn diverged(&self, body: usize, what: String) -> Error {
        Error::Diverged {
            step: self.step + 1,
            body,
            name: self.particles.name.get(body).cloned().unwrap_or_default(),
            what,
        }
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
}
