//! The loops of an MD step over chunks of pairs and of spheres, run side by side on a [`Team`] or one after
//! the other (the same chunks, so the same sums, on one thread or two): the pair forces ([`pair_rows`]), the
//! sphere–wall forces and the second half of the integrator ([`tail`], [`second_half`]), the first half
//! ([`first_half`]).

use super::*;

/// Read-only data of the pair loop.
pub(super) struct PairContext<'a> {
    pub(super) p: &'a Particles,
    pub(super) g: &'a Ghosts,
    pub(super) laws: &'a LawTable,
    pub(super) start: &'a [u32],
    pub(super) j: &'a [u32],
    pub(super) dt: f64,
    pub(super) measure: bool,
}

/// Runs the chunks `bounds[k]..bounds[k+1]` (rows) side by side on `team`, each
/// on its own workspace and its own slice of the contact memory (which starts at
/// entry `offset`).
pub(super) fn run_chunks(
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
pub(super) fn pair_rows(
    ctx: &PairContext,
    lo: usize,
    hi: usize,
    hist: &mut [History],
    offset: usize,
    w: &mut Workspace,
) {
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
pub(super) struct TailContext<'a> {
    /// The pair loop's force buffers, one per chunk.
    pub(super) work: &'a [Workspace],
    pub(super) walls: &'a [Wall],
    pub(super) laws: &'a LawTable,
    /// Background damping `(γ_b, γ_br)` (kg/s).
    pub(super) damping: (f64, f64),
    pub(super) integrator: Integrator,
    pub(super) gravity: V3,
    /// Unit vector against gravity.
    pub(super) up: V3,
    pub(super) dt: f64,
    /// Finish the step (second half kick or corrector) after the forces.
    pub(super) integrate: bool,
}

/// The last phase of a step on one chunk of spheres: total force and torque of
/// each sphere (pair buffers summed, walls, background damping), then the second
/// half of the integrator. `hist` is the chunk's wall contact memory.
pub(super) fn tail(c: View, hist: &mut [History], ctx: &TailContext, out: &mut Tail) {
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
pub(super) struct View<'a> {
    /// Index of the first sphere of the chunk.
    pub(super) lo: usize,
    pub(super) x: &'a mut [V3],
    pub(super) v: &'a mut [V3],
    pub(super) w: &'a mut [V3],
    pub(super) f: &'a mut [V3],
    pub(super) t: &'a mut [V3],
    pub(super) r: &'a [f64],
    pub(super) m: &'a [f64],
    pub(super) material: &'a [u32],
    pub(super) inv_m: &'a [f64],
    pub(super) inv_i: &'a [f64],
    pub(super) q: &'a mut [UnitQuaternion<f64>],
    /// Gear derivatives (empty with Verlet).
    pub(super) gx: &'a mut [[V3; 6]],
    pub(super) gw: &'a mut [[V3; 6]],
    /// Positions at the last neighbour build (empty if unused).
    pub(super) x0: &'a [V3],
}

impl<'a> View<'a> {
    pub(super) fn new(p: &'a mut Particles, gx: &'a mut [[V3; 6]], gw: &'a mut [[V3; 6]], x0: &'a [V3]) -> Self {
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

    pub(super) fn len(&self) -> usize {
        self.x.len()
    }

    /// The two chunks (always [`CHUNKS`] = 2, whatever the threads).
    pub(super) fn halves(self) -> (View<'a>, View<'a>) {
        let at = self.len() / CHUNKS;
        self.split(at)
    }

    pub(super) fn split(self, at: usize) -> (View<'a>, View<'a>) {
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
pub(super) fn first_half(c: View, integrator: Integrator, g: V3, dt: f64) -> f64 {
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
pub(super) fn second_half(c: View, integrator: Integrator, g: V3, up: V3, dt: f64) -> (f64, f64) {
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
