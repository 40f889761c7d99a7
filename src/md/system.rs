//! The MD system and its time step.
//!
//! Data flow of a step (velocity Verlet): half kick and drift of every sphere →
//! neighbour list rebuilt if needed ([`super::neighbours`], images of the symmetry
//! planes re-selected with it) → images mirrored ([`super::ghosts`]) → pair forces
//! ([`super::contact`], half list, one force buffer per thread, summed) → wall
//! forces ([`super::walls`]) → background damping → second half kick → servo walls
//! advanced. With a Gear integrator the kicks are replaced by the predictor before
//! and the corrector after the force evaluation ([`super::integrator`]).

use super::contact::{self, History, Kinematics};
use super::ghosts::Ghosts;
use super::integrator::{predict, Integrator};
use super::law::LawTable;
use super::neighbours::Neighbours;
use super::particles::{rotate, Particles, V3};
use super::walls::{self, Wall};
use crate::error::{Error, Result};
use nalgebra::{Matrix3, UnitQuaternion};
use serde::{Deserialize, Serialize};

/// Run settings of the MD engine (SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MdSettings {
    /// Time step (s).
    pub dt: f64,
    /// Gravity (m/s²).
    pub gravity: V3,
    pub integrator: Integrator,
    /// Neighbour skin (m).
    pub skin: f64,
    /// Translational background damping `γ_b` (kg/s): `f = −γ_b v`.
    pub background_damping: f64,
    /// Rotational background damping `γ_br` (kg/s): `τ = −γ_br r² ω` on a sphere of
    /// radius `r` (Luding's form, so that `γ_br` has the unit of `γ_b`; the paper's
    /// 0.05 kg/s then relaxes spins in `2/5 m/γ_br`, 8 ms for its 1 g spheres).
    pub background_rotational_damping: f64,
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

/// Per-thread accumulators of a force evaluation.
#[derive(Debug, Clone, Default)]
struct Workspace {
    f: Vec<V3>,
    t: Vec<V3>,
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

/// A copy of the state, for keeping the last good one when a step fails.
#[derive(Debug, Clone, Default)]
struct Backup {
    x: Vec<V3>,
    v: Vec<V3>,
    w: Vec<V3>,
    q: Vec<UnitQuaternion<f64>>,
    walls: Vec<(f64, f64)>,
    time: f64,
    step: u64,
}

fn one() -> u64 {
    1
}

/// Spheres per chunk below which the per-sphere loops stay serial.
const PAR_MIN: usize = 512;

/// The work of a step is cut into this many chunks (pairs balanced by count,
/// spheres by index), run side by side when two threads are allowed and serially
/// otherwise: the floating-point sums are the same, so a run gives the same
/// numbers on one thread or two.
pub const CHUNKS: usize = 2;

/// Steps between two copies of the last good state.
const BACKUP_EVERY: u64 = 100;

/// A 3D MD system of spheres and walls.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MdSystem {
    pub settings: MdSettings,
    pub particles: Particles,
    pub walls: Vec<Wall>,
    pub laws: LawTable,
    pub ghosts: Ghosts,
    pub neighbours: Neighbours,
    /// Time (s).
    pub time: f64,
    /// Steps made.
    pub step: u64,
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
    #[serde(skip)]
    threads: usize,
    #[serde(skip)]
    work: Vec<Workspace>,
    #[serde(skip)]
    backup: Backup,
    /// Centres and radii of the spheres and their images, for the neighbour build.
    #[serde(skip)]
    all_x: Vec<V3>,
    #[serde(skip)]
    all_r: Vec<f64>,
}

impl MdSystem {
    /// A system at time 0; forces are evaluated once so that the first step starts
    /// from the right accelerations.
    pub fn new(settings: MdSettings, particles: Particles, walls: Vec<Wall>, laws: LawTable, ghosts: Ghosts) -> Self {
        let mut sys = MdSystem {
            settings,
            neighbours: Neighbours::new(settings.skin),
            particles,
            walls,
            laws,
            ghosts,
            time: 0.0,
            step: 0,
            gear_x: Vec::new(),
            gear_w: Vec::new(),
            virial: Matrix3::zeros(),
            last: MdStepStats::default(),
            measure_every: 1,
            gravity_reference: 0.0,
            threads: 1,
            work: Vec::new(),
            backup: Backup::default(),
            all_x: Vec::new(),
            all_r: Vec::new(),
        };
        let n = sys.particles.len();
        for w in &mut sys.walls {
            w.hist = vec![History::default(); n];
        }
        sys.gravity_reference = sys.initial_reference();
        sys.rebuild();
        let stats = sys.evaluate(0.0, true).unwrap_or_default();
        sys.last = MdStepStats { time: 0.0, kinetic_energy: sys.particles.kinetic_energy(), ..stats };
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
        sys.save_backup();
        sys
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

    /// Number of force-evaluation threads (chunks of the pair list). The numbers
    /// depend on it only through the order of floating-point sums of forces.
    pub fn set_threads(&mut self, threads: usize) {
        self.threads = threads.max(1);
    }

    /// Threads in use.
    pub fn threads(&self) -> usize {
        self.threads.max(1)
    }

    /// Makes one time step.
    ///
    /// # Errors
    /// [`Error::Diverged`] if a force or position becomes non-finite or two bodies
    /// overlap by more than half the smaller radius; the system then holds the
    /// last good state (at most [`BACKUP_EVERY`] steps back).
    pub fn step(&mut self) -> Result<MdStepStats> {
        if self.threads == 0 {
            self.threads = 1;
        }
        let dt = self.settings.dt;
        let g = self.settings.gravity;
        let threads = self.threads;
        let integrator = self.settings.integrator;
        {
            let mut view = self.view();
            par_for(&mut view, threads, &|c: View| first_half(c, integrator, g, dt));
        }
        if self.needs_rebuild() {
            self.rebuild();
        }
        let measure = (self.step + 1).is_multiple_of(self.measure_every.max(1));
        let stats = match self.evaluate(dt, measure) {
            Ok(s) => s,
            Err(e) => {
                self.restore_backup();
                return Err(e);
            }
        };
        let kinetic = {
            let mut view = self.view();
            par_for(&mut view, threads, &|c: View| second_half(c, integrator, g, dt))
        };
        walls::advance(&mut self.walls, self.time + dt, dt);
        self.time += dt;
        self.step += 1;
        if !kinetic.is_finite() {
            let p = &self.particles;
            let i = (0..p.len())
                .find(|&i| !(p.x[i].iter().all(|c| c.is_finite()) && p.v[i].iter().all(|c| c.is_finite())))
                .unwrap_or(0);
            let e = self.diverged(i, "position or velocity is not finite".into());
            self.restore_backup();
            return Err(e);
        }
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

    /// The integrator's view of the sphere arrays.
    fn view(&mut self) -> View<'_> {
        let p = &mut self.particles;
        View {
            x: &mut p.x,
            v: &mut p.v,
            w: &mut p.w,
            f: &p.f,
            t: &p.t,
            inv_m: &p.inv_m,
            inv_i: &p.inv_i,
            q: &mut p.q,
            gx: &mut self.gear_x,
            gw: &mut self.gear_w,
        }
    }

    fn diverged(&self, body: usize, what: String) -> Error {
        Error::Diverged {
            step: self.step,
            body,
            name: self.particles.name.get(body).cloned().unwrap_or_default(),
            what,
        }
    }

    fn save_backup(&mut self) {
        let p = &self.particles;
        let b = &mut self.backup;
        b.x.clone_from(&p.x);
        b.v.clone_from(&p.v);
        b.w.clone_from(&p.w);
        b.q.clone_from(&p.q);
        b.walls = self.walls.iter().map(|w| (w.s, w.s_dot)).collect();
        b.time = self.time;
        b.step = self.step;
    }

    fn restore_backup(&mut self) {
        let b = &self.backup;
        if b.x.len() != self.particles.len() {
            return;
        }
        self.particles.x.clone_from(&b.x);
        self.particles.v.clone_from(&b.v);
        self.particles.w.clone_from(&b.w);
        self.particles.q.clone_from(&b.q);
        for (w, &(s, sd)) in self.walls.iter_mut().zip(&b.walls) {
            w.s = s;
            w.s_dot = sd;
        }
        self.time = b.time;
        self.step = b.step;
    }

    /// True if some pair may have come within reach since the last build.
    fn needs_rebuild(&self) -> bool {
        let d = self.neighbours.max_displacement(&self.particles.x);
        let dw = self.walls.iter().map(|w| (w.s - w.s_build).abs()).fold(0.0, f64::max);
        d + d.max(dw) > self.settings.skin
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
        for w in &mut self.walls {
            w.candidates.clear();
            for i in 0..n {
                match w.gap(&p.x[i], p.r[i]) {
                    Some((gap, _, _)) if gap < skin => w.candidates.push(i as u32),
                    _ => w.hist[i] = History::default(),
                }
            }
            w.s_build = w.s;
        }
    }

    /// Evaluates all forces at the current state, advancing the contact memory
    /// by `dt` (s).
    fn evaluate(&mut self, dt: f64, measure: bool) -> Result<MdStepStats> {
        self.ghosts.update(&self.particles);
        let n = self.particles.len();
        let threads = self.threads.max(1);
        self.work.resize_with(CHUNKS, Workspace::default);
        for w in &mut self.work {
            w.f.clear();
            w.f.resize(n, V3::zeros());
            w.t.clear();
            w.t.resize(n, V3::zeros());
            w.contacts = 0.0;
            w.sum_overlap = 0.0;
            w.overlaps = 0;
            w.max_overlap = 0.0;
            w.energy = 0.0;
            w.virial = Matrix3::zeros();
            w.worst = (0.0, 0);
        }
        // Rows split so that each chunk has about the same number of pairs.
        let total = self.neighbours.pairs();
        let ctx = PairContext {
            p: &self.particles,
            g: &self.ghosts,
            laws: &self.laws,
            start: &self.neighbours.start,
            j: &self.neighbours.j,
            dt,
            measure,
        };
        let mut bounds = [0usize; CHUNKS + 1];
        let chunks = CHUNKS;
        let mut row = 0;
        #[allow(clippy::needless_range_loop)]
        for c in 1..chunks {
            let target = total * c / chunks;
            while row < n && (self.neighbours.start[row] as usize) < target {
                row += 1;
            }
            bounds[c] = row;
        }
        bounds[chunks] = n;
        run_chunks(&ctx, &bounds[..=chunks], &mut self.neighbours.hist, 0, &mut self.work[..chunks], threads > 1);
        // Sum the per-thread buffers into the first one.
        let (first, rest) = self.work.split_at_mut(1);
        let w0 = &mut first[0];
        for w in rest.iter() {
            for i in 0..n {
                w0.f[i] += w.f[i];
                w0.t[i] += w.t[i];
            }
            w0.contacts += w.contacts;
            w0.sum_overlap += w.sum_overlap;
            w0.overlaps += w.overlaps;
            w0.max_overlap = w0.max_overlap.max(w.max_overlap);
            w0.energy += w.energy;
            w0.virial += w.virial;
            if w.worst.0 > w0.worst.0 {
                w0.worst = w.worst;
            }
        }
        std::mem::swap(&mut self.particles.f, &mut w0.f);
        std::mem::swap(&mut self.particles.t, &mut w0.t);
        // Walls.
        let p = &mut self.particles;
        let mut wall_contacts = 0;
        for wall in &mut self.walls {
            wall.force = V3::zeros();
            wall.contacts = 0;
            let vw = wall.velocity();
            for &i in &wall.candidates {
                let i = i as usize;
                let touching = wall.gap(&p.x[i], p.r[i]).filter(|g| g.0 < 0.0);
                let h = &mut wall.hist[i];
                let Some((gap, nrm, r_star)) = touching else {
                    *h = History::default();
                    continue;
                };
                let Some(law) = self.laws.get(p.material[i] as usize, wall.material as usize) else { continue };
                let delta = -gap;
                let a = p.r[i] - delta;
                let v_rel = p.v[i] + nrm.cross(&p.w[i]) * a - vw;
                let k = Kinematics { n: nrm, delta, v_rel, r_star, m_star: p.m[i], measure: true };
                let cf = contact::force(law, &k, h, dt);
                p.f[i] += cf.force;
                p.t[i] += nrm.cross(&cf.tangential) * (-a);
                wall.force -= cf.force;
                wall.contacts += 1;
                w0.sum_overlap += delta;
                w0.overlaps += 1;
                w0.max_overlap = w0.max_overlap.max(delta);
                w0.energy += cf.energy;
                if delta / p.r[i] > w0.worst.0 {
                    w0.worst = (delta / p.r[i], i);
                }
            }
            wall_contacts += wall.contacts;
        }
        let (gb, gr) = (self.settings.background_damping, self.settings.background_rotational_damping);
        if gb != 0.0 || gr != 0.0 {
            for i in 0..n {
                p.f[i] -= p.v[i] * gb;
                p.t[i] -= p.w[i] * (gr * p.r[i] * p.r[i]);
            }
        }
        self.virial = w0.virial;
        let (worst, worst_i) = w0.worst;
        let summary = (w0.contacts, w0.energy, w0.max_overlap, w0.sum_overlap, w0.overlaps);
        if worst > 0.5 || !summary.1.is_finite() {
            let r = p.r[worst_i];
            return Err(self.diverged(
                worst_i,
                format!("runaway overlap: {:.3e} m, {:.0} % of the radius", worst * r, 100.0 * worst),
            ));
        }
        if let Some(i) =
            (0..n).find(|&i| !(p.f[i].iter().all(|c| c.is_finite()) && p.t[i].iter().all(|c| c.is_finite())))
        {
            return Err(self.diverged(i, "contact force is not finite".into()));
        }
        let (contacts, energy, max_overlap, sum_overlap, overlaps) = summary;
        Ok(MdStepStats {
            time: self.time,
            kinetic_energy: 0.0,
            elastic_energy: energy,
            contacts,
            wall_contacts,
            max_overlap,
            mean_overlap: if overlaps > 0 { sum_overlap / overlaps as f64 } else { 0.0 },
            coordination: if n > 0 { (2.0 * contacts + wall_contacts as f64) / n as f64 } else { 0.0 },
        })
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

/// Runs the chunks `bounds[k]..bounds[k+1]` (rows) side by side, each on its own
/// workspace and its own slice of the contact memory (which starts at entry `offset`).
fn run_chunks(
    ctx: &PairContext,
    bounds: &[usize],
    hist: &mut [History],
    offset: usize,
    work: &mut [Workspace],
    parallel: bool,
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
    let mut a = || run_chunks(ctx, &bounds[..=mid], h0, offset, w0, parallel);
    let mut b = || run_chunks(ctx, &bounds[mid..], h1, offset + split, w1, parallel);
    if parallel && ctx.start.len() > PAR_MIN {
        rayon::join(a, b);
    } else {
        a();
        b();
    }
}

/// Forces of the pairs of rows `lo..hi` into `w`.
#[inline(never)]
fn pair_rows(ctx: &PairContext, lo: usize, hi: usize, hist: &mut [History], offset: usize, w: &mut Workspace) {
    let p = ctx.p;
    let n = p.len();
    let dt = ctx.dt;
    for i in lo..hi {
        let (xi, vi, wi, ri, mi, mati) = (p.x[i], p.v[i], p.w[i], p.r[i], p.m[i], p.material[i] as usize);
        let mut fi = V3::zeros();
        let mut ti = V3::zeros();
        for e in ctx.start[i] as usize..ctx.start[i + 1] as usize {
            let j = ctx.j[e] as usize;
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
            let h = &mut hist[e - offset];
            if dist2 >= rs * rs {
                if h.delta != 0.0 {
                    *h = History::default();
                }
                continue;
            }
            let Some(law) = ctx.laws.get(mati, p.material[o] as usize) else { continue };
            let (vj, wj) = if ghost { (ctx.g.v[j - n], ctx.g.w[j - n]) } else { (p.v[j], p.w[j]) };
            let dist = dist2.sqrt();
            let nrm = if dist > 0.0 { d / dist } else { V3::z() };
            let delta = rs - dist;
            let ai = ri - 0.5 * delta;
            let aj = rj - 0.5 * delta;
            let v_rel = vi - vj + nrm.cross(&wi) * ai + nrm.cross(&wj) * aj;
            let mj = p.m[o];
            let k = Kinematics {
                n: nrm,
                delta,
                v_rel,
                r_star: ri * rj / rs,
                m_star: mi * mj / (mi + mj),
                measure: ctx.measure,
            };
            let cf = contact::force(law, &k, h, dt);
            fi += cf.force;
            ti -= nrm.cross(&cf.tangential) * ai;
            let weight = if ghost { 0.5 } else { 1.0 };
            w.contacts += weight;
            if ctx.measure {
                // Branch vector from j's centre to i's centre.
                w.virial += (cf.force * weight) * d.transpose();
                w.energy += cf.energy * weight;
                w.sum_overlap += delta;
                w.overlaps += 1;
                w.max_overlap = w.max_overlap.max(delta);
            }
            if delta > 0.5 * ri.min(rj) {
                let rel = delta / ri.min(rj);
                if rel > w.worst.0 {
                    w.worst = (rel, i);
                }
            }
            if !ghost {
                w.f[j] -= cf.force;
                w.t[j] -= nrm.cross(&cf.tangential) * aj;
            }
        }
        w.f[i] += fi;
        w.t[i] += ti;
    }
}

/// The per-sphere arrays the integrator touches, split into chunks for threads.
struct View<'a> {
    x: &'a mut [V3],
    v: &'a mut [V3],
    w: &'a mut [V3],
    f: &'a [V3],
    t: &'a [V3],
    inv_m: &'a [f64],
    inv_i: &'a [f64],
    q: &'a mut [UnitQuaternion<f64>],
    /// Gear derivatives (empty with Verlet).
    gx: &'a mut [[V3; 6]],
    gw: &'a mut [[V3; 6]],
}

impl<'a> View<'a> {
    fn len(&self) -> usize {
        self.x.len()
    }

    fn split(self, at: usize) -> (View<'a>, View<'a>) {
        let (x0, x1) = self.x.split_at_mut(at);
        let (v0, v1) = self.v.split_at_mut(at);
        let (w0, w1) = self.w.split_at_mut(at);
        let (f0, f1) = self.f.split_at(at);
        let (t0, t1) = self.t.split_at(at);
        let (m0, m1) = self.inv_m.split_at(at);
        let (i0, i1) = self.inv_i.split_at(at);
        let (q0, q1) = self.q.split_at_mut(at);
        let g = at.min(self.gx.len());
        let (gx0, gx1) = self.gx.split_at_mut(g);
        let (gw0, gw1) = self.gw.split_at_mut(g);
        (
            View { x: x0, v: v0, w: w0, f: f0, t: t0, inv_m: m0, inv_i: i0, q: q0, gx: gx0, gw: gw0 },
            View { x: x1, v: v1, w: w1, f: f1, t: t1, inv_m: m1, inv_i: i1, q: q1, gx: gx1, gw: gw1 },
        )
    }

    fn reborrow(&mut self) -> View<'_> {
        View {
            x: self.x,
            v: self.v,
            w: self.w,
            f: self.f,
            t: self.t,
            inv_m: self.inv_m,
            inv_i: self.inv_i,
            q: self.q,
            gx: self.gx,
            gw: self.gw,
        }
    }
}

/// Runs `body` on `threads` chunks of `view` side by side (serially for small
/// systems) and sums what the chunks return.
fn par_for(view: &mut View, threads: usize, body: &(dyn Fn(View) -> f64 + Sync)) -> f64 {
    // Always the same CHUNKS chunks, whatever the threads: the same sums.
    let at = view.len() / CHUNKS;
    let (a, b) = view.reborrow().split(at);
    let (x, y) = if threads > 1 && at >= PAR_MIN { rayon::join(|| body(a), || body(b)) } else { (body(a), body(b)) };
    x + y
}

/// Before the force evaluation: half kick and drift (Verlet) or predictor (Gear).
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
    0.0
}

/// After the force evaluation: second half kick (Verlet) or corrector (Gear),
/// orientations; returns the kinetic energy of the chunk (J), non-finite if a
/// position or velocity is.
fn second_half(c: View, integrator: Integrator, g: V3, dt: f64) -> f64 {
    let mut kinetic = 0.0;
    let mut finite = true;
    match integrator {
        Integrator::Verlet => {
            for i in 0..c.x.len() {
                c.v[i] += (c.f[i] * c.inv_m[i] + g) * (0.5 * dt);
                c.w[i] += c.t[i] * (c.inv_i[i] * 0.5 * dt);
                rotate(&mut c.q[i], &c.w[i], dt);
                kinetic += 0.5 * (c.v[i].norm_squared() / c.inv_m[i] + c.w[i].norm_squared() / c.inv_i[i]);
                finite &= c.x[i].iter().all(|a| a.is_finite());
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
                kinetic += 0.5 * (c.v[i].norm_squared() / c.inv_m[i] + c.w[i].norm_squared() / c.inv_i[i]);
                finite &= c.x[i].iter().all(|a| a.is_finite());
            }
        }
    }
    if finite {
        kinetic
    } else {
        f64::NAN
    }
}
