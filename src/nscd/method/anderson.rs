//! Anderson acceleration of the NLGS sweeps (`[nscd] anderson = m`; Anderson, J. ACM 12 (1965) 547; Walker &
//! Ni, SIAM J. Numer. Anal. 49 (2011) 1715, "AA(m)"), for rows of any dimension.
//!
//! **Why.** On a loaded granular packing Gauss–Seidel passes information one contact per sweep, and its slow
//! modes (a heavy sleeper on light grains, wedged grains rocking on nearly flat contacts) are nearly linear once
//! the contacts' statuses have settled: there a sweep is a linear stationary iteration, which Anderson mixing
//! accelerates as GMRES does (Walker & Ni, §2). The method never leaves the NLGS: the mixed point is projected
//! on each row's law and the sweeps go on from it, so a step is judged by the same check pass
//! ([`super::criterion`]) and ends at the same tolerance; only the path to it changes.
//!
//! **The map.** `G` is [`SWEEPS_PER_MIX`] Gauss–Seidel sweeps from the impulses `x` of every row (springs'
//! scalars, contacts' `(P_N, P_T…)`), the body velocities kept consistent with them (`u = u_free + M⁻¹ H x`).
//! Its residual `f(x) = D (G(x) − x)` is weighted by `D = diag(W)^½` (each entry the square root of the
//! diagonal of its row's Delassus block: `f` is a velocity, so light grains and the heavy sleeper are weighed
//! as the check's norms weigh them). After each application of `G` the last `m` differences of `G` and of `f`
//! give `γ = argmin ‖f_k − ΔF γ‖` (normal equations with a relative Tikhonov term [`REGULARISATION`], a
//! Cholesky of at most [`MAX_DEPTH`]² numbers) and the next point `x = G(x_k) − ΔG γ`, projected on each row's
//! law ([`ConeRow::project`], `P ≥ 0` for a compression-only spring). The bodies' velocities are mixed with the
//! same coefficients from their own history (they are affine in the impulses), so only a projection's change is
//! scattered to the bodies; at the end of the solve they are set to `u_free + M⁻¹ H P` of the final impulses.
//!
//! **Safeguard.** The mixing is a guess where contacts open, close or start to slide: when the residual grows
//! from one application of the map to the next, the history is dropped (a restart) and that point is the base
//! of the next differences, so a mix never compounds a bad one; the sweeps themselves always run.
//!
//! **Threads.** Each part of the domain split ([`super::split`]) keeps its own lane of the history; the
//! halves' dot products and mixes run side by side, the interface's after them, and the partial sums are added
//! in a fixed order (left, right, interface): the numbers do not depend on the number of threads.
//!
//! Measured in BENCHMARKS.md ("Anderson acceleration of the NLGS sweeps").

use super::apgd::{AffineRow, ConeRow};
use super::criterion::SweepNorms;
use super::gauss_seidel::{apply_impulses, iterate, pass, remove_impulses, NlgsReport, Pass};
use super::settings::NlgsSettings;
use super::split::SplitWorkspace;

/// Largest history depth `m` (`nscd.anderson`).
pub const MAX_DEPTH: usize = 8;

/// Gauss–Seidel sweeps per application of the mixed map: 2 needs the sweeps of 1 at half the mixes (measured on
/// the 200-grain section's first cycle at `quad` 3e-5 with the session's first build: 312 sweeps per step mixing
/// after every sweep, 314 after every second, 358 after every third).
pub const SWEEPS_PER_MIX: usize = 2;

/// Tikhonov term of the normal equations, relative to the largest diagonal of `ΔFᵀ ΔF`.
pub const REGULARISATION: f64 = 1e-10;

/// The dot products of one application of the map, summed over a part's rows.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Dots {
    /// `‖f‖²` of the new residual.
    residual: f64,
    /// `Δf_new · Δf_q` for each slot `q` of the history.
    gram: [f64; MAX_DEPTH],
    /// `Δf_q · f` for each slot `q`.
    rhs: [f64; MAX_DEPTH],
}

impl Dots {
    /// The sums of two parts (the caller fixes the order).
    pub(crate) fn merged(mut self, other: Dots) -> Dots {
        self.residual += other.residual;
        for q in 0..MAX_DEPTH {
            self.gram[q] += other.gram[q];
            self.rhs[q] += other.rhs[q];
        }
        self
    }
}

/// Which slots of the history hold a difference, and where the next one goes.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct Slots {
    /// The slot the next difference is written to; `None` before the first application (no difference yet).
    pub(crate) new: Option<usize>,
    /// Slots that hold a difference (the new one included once written).
    pub(crate) valid: [bool; MAX_DEPTH],
}

/// One part's history. Its vectors hold the **live** entries only: the springs' scalars, then the components of
/// each contact row that has carried an impulse at the start or at an application of the map during this
/// solve, in the order the rows became live. A row that never did is zero in `x`, `G(x)` and every difference,
/// and stays zero in the mixed point, so it adds nothing to a dot product and the mix leaves it alone: on a
/// packing most points within the alert distance are open (two thirds on the seated 2 000-grain section), and
/// the passes over the history cost what the loaded points make them cost. Per live entry: the weight, the start
/// of the map, the last `G` and `f` and `m` differences of each; per component of the bodies' velocities the
/// last value at `G` and `m` differences. The differences are stored by column, each column `stride` long (the
/// part's full impulse vector), the live entries at its head, so that the dot products and the mixing are
/// passes over contiguous arrays and a row that becomes live appends its entries without moving any.
#[derive(Debug, Clone, Default)]
pub(crate) struct Lane {
    w: Vec<f64>,
    x: Vec<f64>,
    g: Vec<f64>,
    f: Vec<f64>,
    scratch: Vec<f64>,
    dg: Vec<f64>,
    df: Vec<f64>,
    ug: Vec<f64>,
    du: Vec<f64>,
    depth: usize,
    /// Length of a column of `dg` and `df`: springs plus every row's components.
    stride: usize,
    /// Where each row's entries start in the live vectors (`NOT_LIVE` for a row not live).
    at: Vec<u32>,
    /// The live rows, in the order their entries are stored.
    live: Vec<u32>,
    /// Whether the bodies' velocities are mixed from their history (false for the split's interface, whose
    /// velocities are the halves' copies).
    velocities: bool,
}

/// [`Lane::at`] of a row that is not live.
const NOT_LIVE: u32 = u32::MAX;

/// Whether an impulse is not zero.
fn carries(p: &[f64]) -> bool {
    p.iter().any(|&c| c != 0.0)
}

/// The weight `√W` of an entry whose Delassus diagonal is `d`.
fn weight(d: f64) -> f64 {
    d.max(0.0).sqrt()
}

/// `(a · b, a · c)` in one pass over `a` (it is read once for both).
fn dot_pair(a: &[f64], b: &[f64], c: &[f64]) -> (f64, f64) {
    let (mut s, mut t) = ([0.0; 4], [0.0; 4]);
    let (ca, cb, cc) = (a.chunks_exact(4), b.chunks_exact(4), c.chunks_exact(4));
    let tail = ca.remainder().iter().zip(cb.remainder()).zip(cc.remainder());
    let (ts, tt) = tail.fold((0.0, 0.0), |(s, t), ((x, y), z)| (s + x * y, t + x * z));
    for ((x, y), z) in ca.zip(cb).zip(cc) {
        for j in 0..4 {
            s[j] += x[j] * y[j];
            t[j] += x[j] * z[j];
        }
    }
    ((s[0] + s[1]) + (s[2] + s[3]) + ts, (t[0] + t[1]) + (t[2] + t[3]) + tt)
}

/// `x − Σ_q γ_q d_q` into `x`, the columns `d_q` (`stride` apart in `d`, the first `x.len()` entries of each
/// used) taken a block of entries at a time, so that `x`'s block stays in cache while the columns stream past.
fn subtract_columns(x: &mut [f64], d: &[f64], stride: usize, gamma: &[f64; MAX_DEPTH], depth: usize) {
    const BLOCK: usize = 512;
    for (b, xb) in x.chunks_mut(BLOCK).enumerate() {
        let (at, len) = (b * BLOCK, xb.len());
        for (q, &c) in gamma.iter().enumerate().take(depth) {
            if c != 0.0 {
                for (xi, di) in xb.iter_mut().zip(&d[q * stride + at..q * stride + at + len]) {
                    *xi -= c * di;
                }
            }
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    // Four partial sums: the products are independent, so the sum is not one long chain of additions.
    let mut s = [0.0; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for j in 0..4 {
            s[j] += x[j] * y[j];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

impl Lane {
    /// Starts a step's history at the rows' current impulses and the bodies' velocities `u`: the springs and the
    /// rows that carry an impulse are live.
    pub(crate) fn begin<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
        &mut self,
        depth: usize,
        velocities: bool,
        u: &[R::Dofs],
        rows: &[R],
        springs: &[S],
    ) {
        let dim = R::Impulse::default().as_ref().len();
        self.depth = depth;
        self.velocities = velocities;
        self.stride = springs.len() + dim * rows.len();
        self.w.clear();
        self.x.clear();
        for s in springs {
            self.w.push(weight(s.w()));
            self.x.push(s.impulse());
        }
        self.at.clear();
        self.at.resize(rows.len(), NOT_LIVE);
        self.live.clear();
        for (i, r) in rows.iter().enumerate() {
            let p = r.impulse();
            if carries(p.as_ref()) {
                self.enlist(i, r, self.x.len());
                self.x.extend_from_slice(p.as_ref());
            }
        }
        let k = self.x.len();
        for v in [&mut self.g, &mut self.f] {
            v.clear();
            v.resize(k, 0.0);
        }
        // Columns are written over their live head before they are read; a row made live zeroes its entries.
        for v in [&mut self.dg, &mut self.df] {
            if v.len() < self.stride * depth {
                v.resize(self.stride * depth, 0.0);
            }
        }
        self.ug.clear();
        if velocities {
            for ui in u {
                self.ug.extend_from_slice(ui.as_ref());
            }
        }
        self.du.clear();
        self.du.resize(self.ug.len() * depth, 0.0);
    }

    /// Makes row `i` live, its entries starting at `at`: its place and its weights.
    fn enlist<R: ConeRow>(&mut self, i: usize, r: &R, at: usize) {
        self.at[i] = at as u32;
        self.live.push(i as u32);
        self.w.extend(r.diagonal().as_ref().iter().map(|&d| weight(d)));
    }

    /// Takes the map's value `G(x)` from the rows and `u`: rows that carry an impulse for the first time become
    /// live (zero in the history so far); then the new residual, the new differences in `slots.new`, their dot
    /// products with the valid slots; `x` becomes `G(x)` (the start of the next map if no mix follows).
    pub(crate) fn absorb<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
        &mut self,
        slots: &Slots,
        u: &[R::Dofs],
        rows: &[R],
        springs: &[S],
    ) -> Dots {
        let mut dots = Dots::default();
        let mut g_new = std::mem::take(&mut self.scratch);
        g_new.clear();
        g_new.extend(springs.iter().map(|s| s.impulse()));
        g_new.resize(self.x.len(), 0.0);
        for (i, r) in rows.iter().enumerate() {
            let p = r.impulse();
            let p = p.as_ref();
            let at = self.at[i];
            if at != NOT_LIVE {
                let at = at as usize;
                g_new[at..at + p.len()].copy_from_slice(p);
            } else if carries(p) {
                let at = g_new.len();
                self.enlist(i, r, at);
                g_new.extend_from_slice(p);
                for v in [&mut self.x, &mut self.g, &mut self.f] {
                    v.resize(at + p.len(), 0.0);
                }
                for q in (0..self.depth).filter(|&q| slots.valid[q]) {
                    let column = q * self.stride + at;
                    self.dg[column..column + p.len()].fill(0.0);
                    self.df[column..column + p.len()].fill(0.0);
                }
            }
        }
        let n = g_new.len();
        let f = &mut self.f;
        // f ← D (G − x), kept in `x`'s buffer for a moment; then the differences and the swaps.
        for ((xi, gi), wi) in self.x.iter_mut().zip(g_new.iter()).zip(&self.w) {
            *xi = wi * (gi - *xi);
        }
        dots.residual = dot(&self.x, &self.x);
        let column = |q: usize| q * self.stride..q * self.stride + n;
        if let Some(h) = slots.new {
            let (dg, df) = (&mut self.dg[column(h)], &mut self.df[column(h)]);
            for (((d, fi), fnew), (e, (gi, gnew))) in
                df.iter_mut().zip(f.iter()).zip(&self.x).zip(dg.iter_mut().zip(self.g.iter().zip(g_new.iter())))
            {
                *d = fnew - fi;
                *e = gnew - gi;
            }
            if self.velocities {
                let nu = self.ug.len();
                let du = &mut self.du[h * nu..(h + 1) * nu];
                let mut k = 0;
                for ui in u {
                    for &c in ui.as_ref() {
                        du[k] = c - self.ug[k];
                        self.ug[k] = c;
                        k += 1;
                    }
                }
            }
        } else if self.velocities {
            self.ug.clear();
            for ui in u {
                self.ug.extend_from_slice(ui.as_ref());
            }
        }
        std::mem::swap(f, &mut self.x);
        std::mem::swap(&mut self.g, &mut g_new);
        self.scratch = g_new;
        self.x.clear();
        self.x.extend_from_slice(&self.g);
        if let Some(h) = slots.new {
            let df_h = &self.df[column(h)];
            for q in 0..self.depth {
                if slots.valid[q] {
                    (dots.gram[q], dots.rhs[q]) = dot_pair(&self.df[column(q)], df_h, &self.f);
                }
            }
        }
        dots
    }

    /// Moves the live rows to the mixed point `G(x) − ΔG γ` and the bodies' velocities to `u(G(x)) − ΔU γ` (the
    /// same combination: `u` is affine in the impulses); where a row's law projects its mixed impulse, the
    /// projection's change is scattered to `u`. `x` becomes the mixed point. The other rows carry no impulse and
    /// keep none. Called right after [`Lane::absorb`], which left `x = G(x)`.
    pub(crate) fn mix<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
        &mut self,
        gamma: &[f64; MAX_DEPTH],
        u: &mut [R::Dofs],
        inv_m: &[R::Dofs],
        rows: &mut [R],
        springs: &mut [S],
    ) {
        let x = &mut self.x;
        subtract_columns(x, &self.dg, self.stride, gamma, self.depth);
        if self.velocities {
            let um = &mut self.scratch;
            um.clear();
            um.extend_from_slice(&self.ug);
            subtract_columns(um, &self.du, self.ug.len(), gamma, self.depth);
            let mut k = 0;
            for ui in u.iter_mut() {
                for c in ui.as_mut() {
                    *c = um[k];
                    k += 1;
                }
            }
        }
        for (i, s) in springs.iter_mut().enumerate() {
            let mixed = x[i];
            let q = if s.compression_only() { mixed.max(0.0) } else { mixed };
            if q != mixed {
                s.add_impulse_of(u, inv_m, q - mixed, 1.0);
            }
            s.set_impulse(q);
            x[i] = q;
        }
        for &row in &self.live {
            let r = &mut rows[row as usize];
            let at = self.at[row as usize] as usize;
            let mut mixed = R::Impulse::default();
            let len = mixed.as_ref().len();
            mixed.as_mut().copy_from_slice(&x[at..at + len]);
            let q = r.project(mixed, None);
            if q != mixed {
                let mut d = q;
                for (dj, oj) in d.as_mut().iter_mut().zip(mixed.as_ref()) {
                    *dj -= oj;
                }
                r.add_impulse_of(u, inv_m, d, 1.0);
            }
            r.set_impulse(q);
            x[at..at + len].copy_from_slice(q.as_ref());
        }
    }
}

/// The small part of the method, shared by the lanes: the history's slots, `ΔFᵀ ΔF`, the last residual.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Mixer {
    depth: usize,
    gram: [[f64; MAX_DEPTH]; MAX_DEPTH],
    slots: Slots,
    /// The slot after the newest difference.
    head: usize,
    /// Whether a first application has been absorbed (differences can be formed).
    primed: bool,
    last_residual: f64,
    since: usize,
}

impl Mixer {
    /// The history depth `m`.
    pub(crate) fn depth(&self) -> usize {
        self.depth
    }

    pub(crate) fn new(depth: usize) -> Self {
        Self {
            depth: depth.min(MAX_DEPTH),
            gram: [[0.0; MAX_DEPTH]; MAX_DEPTH],
            slots: Slots::default(),
            head: 0,
            primed: false,
            last_residual: f64::INFINITY,
            since: 0,
        }
    }

    /// After a pass: whether the map has been applied (its sweeps made) and the lanes should absorb it; then the
    /// slots they write and read.
    pub(crate) fn due(&mut self, kind: Pass) -> Option<Slots> {
        if kind == Pass::Check {
            return None;
        }
        self.since += 1;
        if self.since < SWEEPS_PER_MIX {
            return None;
        }
        self.since = 0;
        let mut slots = self.slots;
        if self.primed {
            slots.new = Some(self.head);
            slots.valid[self.head] = true;
        }
        Some(slots)
    }

    /// Takes the lanes' summed dot products for `slots` (as [`Mixer::due`] gave them); returns the mixing
    /// coefficients `γ` per slot (zero for the others), or `None` when there is nothing to mix.
    pub(crate) fn solve(&mut self, slots: Slots, dots: &Dots) -> Option<[f64; MAX_DEPTH]> {
        let m = self.depth;
        let grew = dots.residual > self.last_residual;
        self.last_residual = dots.residual;
        if grew {
            // A restart: the history is dropped and this point becomes the base of the next differences.
            self.slots = Slots::default();
            self.head = 0;
            self.primed = true;
            return None;
        }
        self.primed = true;
        let h = slots.new?;
        self.slots = slots;
        self.slots.new = None;
        for q in 0..m {
            if slots.valid[q] {
                self.gram[h][q] = dots.gram[q];
                self.gram[q][h] = dots.gram[q];
            }
        }
        self.head = (h + 1) % m;
        let gamma = self.least_squares(&dots.rhs)?;
        Some(gamma)
    }

    /// `(ΔFᵀ ΔF + ε I) γ = ΔFᵀ f` over the valid slots, by Cholesky (a slot not in use gets the row of the
    /// identity and `γ = 0`); `None` if the matrix is not positive or `γ` not finite.
    fn least_squares(&self, rhs: &[f64; MAX_DEPTH]) -> Option<[f64; MAX_DEPTH]> {
        let valid = |q: usize| q < self.depth && self.slots.valid[q];
        let largest = (0..MAX_DEPTH).filter(|&q| valid(q)).map(|q| self.gram[q][q]).fold(0.0, f64::max);
        if !(largest > 0.0 && largest.is_finite()) {
            return None;
        }
        let a = nalgebra::SMatrix::<f64, MAX_DEPTH, MAX_DEPTH>::from_fn(|p, q| match (valid(p) && valid(q), p == q) {
            (true, true) => self.gram[p][q] + REGULARISATION * largest,
            (true, false) => self.gram[p][q],
            (false, true) => 1.0,
            (false, false) => 0.0,
        });
        let b = nalgebra::SVector::<f64, MAX_DEPTH>::from_fn(|p, _| if valid(p) { rhs[p] } else { 0.0 });
        let gamma: [f64; MAX_DEPTH] = a.cholesky()?.solve(&b).into();
        gamma.iter().all(|g| g.is_finite()).then_some(gamma)
    }
}

/// [`solve_nlgs_anderson`] on the domain split of [`super::solve_nlgs_split`] (the same rule for when to
/// split; the numbers do not depend on `threads`); [`super::solve_nlgs_split`] when the depth is 0.
#[allow(clippy::too_many_arguments)]
pub fn solve_nlgs_anderson_split<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    ws: &mut AndersonWorkspace<R::Dofs>,
    split: &mut SplitWorkspace<R, S>,
    threads: usize,
    abscissa: impl Fn(usize) -> f64,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    if settings.anderson == 0 {
        return super::solve_nlgs_split(settings, split, threads, abscissa, u, inv_m, rows, springs);
    }
    if !settings.splits(rows.len() + springs.len()) {
        return solve_nlgs_anderson(settings, ws, u, inv_m, rows, springs);
    }
    let mut mixer = Mixer::new(settings.anderson);
    ws.keep_free(u, inv_m, rows, springs);
    split.load(abscissa, u, inv_m, rows, springs);
    let report = split.run_mixed(threads, &mut mixer, |sweep| iterate(settings, sweep));
    split.store(u, rows, springs);
    ws.restore(u, inv_m, rows, springs);
    report
}

/// Buffers of the accelerated sweeps on one part (the problems too small to split), and the free velocities
/// of the step (`D`: a body's generalised velocity, [`super::Row::Dofs`]).
#[derive(Debug, Clone)]
pub struct AndersonWorkspace<D> {
    lane: Lane,
    u_free: Vec<D>,
}

impl<D> Default for AndersonWorkspace<D> {
    fn default() -> Self {
        Self { lane: Lane::default(), u_free: Vec::new() }
    }
}

impl<D: Copy> AndersonWorkspace<D> {
    /// Keeps the free velocities `u − M⁻¹ H P` of the start of the solve.
    fn keep_free<R: ConeRow<Dofs = D>, S: AffineRow<Dofs = D>>(
        &mut self,
        u: &[D],
        inv_m: &[D],
        rows: &[R],
        springs: &[S],
    ) {
        self.u_free.clear();
        self.u_free.extend_from_slice(u);
        remove_impulses(&mut self.u_free, inv_m, rows, springs);
    }

    /// Sets `u = u_free + M⁻¹ H P` of the final impulses: the mixed velocities carry the round-off of the
    /// mixing (up to 3e-10 m/s on a step of the loaded 536 pile), the impulses are the solution.
    fn restore<R: ConeRow<Dofs = D>, S: AffineRow<Dofs = D>>(
        &self,
        u: &mut [D],
        inv_m: &[D],
        rows: &[R],
        springs: &[S],
    ) {
        u.copy_from_slice(&self.u_free);
        apply_impulses(u, inv_m, rows, springs);
    }
}

/// NLGS ([`super::solve_nlgs`]) with Anderson mixing of depth `settings.anderson` on the whole problem, one
/// thread; plain NLGS when the depth is 0. The velocities `u` returned are `u_free + M⁻¹ H P` of the final
/// impulses.
pub fn solve_nlgs_anderson<R: ConeRow, S: AffineRow<Dofs = R::Dofs>>(
    settings: &NlgsSettings,
    ws: &mut AndersonWorkspace<R::Dofs>,
    u: &mut [R::Dofs],
    inv_m: &[R::Dofs],
    rows: &mut [R],
    springs: &mut [S],
) -> NlgsReport {
    if settings.anderson == 0 || (rows.is_empty() && springs.is_empty()) {
        return super::solve_nlgs(settings, u, inv_m, rows, springs);
    }
    let mut mixer = Mixer::new(settings.anderson);
    ws.keep_free(u, inv_m, rows, springs);
    ws.lane.begin(mixer.depth, true, u, rows, springs);
    let report = iterate(settings, |kind| {
        let norms: SweepNorms = pass(kind, u, inv_m, rows, springs);
        if let Some(slots) = mixer.due(kind) {
            let dots = ws.lane.absorb(&slots, u, rows, springs);
            if let Some(gamma) = mixer.solve(slots, &dots) {
                ws.lane.mix(&gamma, u, inv_m, rows, springs);
            }
        }
        norms
    });
    ws.restore(u, inv_m, rows, springs);
    report
}
