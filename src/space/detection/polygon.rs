//! The contact points of two polyhedra on their common plane, after LMGC90 mod_PRPRx's `planplan`: the
//! vertices of each polyhedron within a band of the plane (its *feature*: a face, an edge or a vertex) are
//! projected on it, the convex hulls of the two projections are intersected, and the intersection is reduced
//! to at most four points.
//!
//! Differences from `planplan`: the intersection handles the degenerate hulls
//! (segment and point) exactly instead of by a shrink; the feature vertices of one shape that fall inside
//! the other's hull, and the point realising the separation (an edge crossing or GJK's closest points), are
//! candidates too, so the deepest point of a non-flat feature is never lost; every point gets its own gap
//! (LMGC90 gives all of them the common plane's); the reduction keeps the deepest point, the point farthest
//! from it, the point farthest from their line and the point adding the most area (LMGC90 keeps the four
//! sharpest corners of the hull), so that penetration is never hidden. Points are ordered by the features
//! that make them (see [`Label`]), which does not depend on the world frame and changes only when the
//! contact's topology does.

use super::placed::PolyhedronView;
use crate::geometry::{cross, Vec2, Vec3};

/// Most vertices of a feature; beyond, the ones nearest the plane are kept.
pub const CAP: usize = 24;
const CAP2: usize = 2 * CAP;
/// Most candidate points; beyond, the last ones are left out.
const MAX_CANDIDATES: usize = CAP;

/// What makes a contact point, in the order points are given: a vertex of the candidate
/// `(0, vertex, 0, 0, 0)`, a vertex of the antagonist `(1, vertex, …)`, the crossing of an edge of the
/// candidate and one of the antagonist `(2, a0, a1, b0, b1)` (vertex indices of the two hull edges, lower
/// first), anything else `(3, k, …)`.
pub type Label = (u8, u32, u32, u32, u32);

/// The vertices of one polyhedron within `band` of its extreme along the normal, projected on the plane.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Feature {
    len: usize,
    id: [u32; CAP],
    p: [Vec2; CAP],
    /// Height along the normal above the plane's origin (m).
    h: [f64; CAP],
    /// Convex hull, counter-clockwise about the normal: indices in the arrays above.
    hull: [u8; CAP],
    hull_len: usize,
    /// `1` for the candidate's feature (its lowest vertices), `−1` for the antagonist's.
    sign: f64,
}

/// The plane: origin, tangents and normal; lengths below `eps` are zero.
#[derive(Debug, Clone, Copy)]
pub struct Frame {
    /// Origin (world, m).
    pub o: Vec3,
    /// First tangent.
    pub t1: Vec3,
    /// Second tangent.
    pub t2: Vec3,
    /// Unit normal, from the antagonist to the candidate.
    pub n: Vec3,
    /// Length tolerance (m).
    pub eps: f64,
}

impl Frame {
    #[inline]
    fn project(&self, x: &Vec3) -> Vec2 {
        let d = x - self.o;
        Vec2::new(self.t1.dot(&d), self.t2.dot(&d))
    }

    #[inline]
    fn lift(&self, p: &Vec2) -> Vec3 {
        self.o + p.x * self.t1 + p.y * self.t2
    }
}

impl Feature {
    /// An empty feature (to be filled by [`Self::fill`]).
    fn empty() -> Self {
        Feature { len: 0, id: [0; CAP], p: [Vec2::zeros(); CAP], h: [0.0; CAP], hull: [0; CAP], hull_len: 0, sign: 1.0 }
    }

    /// Makes this the feature of `view`: its lowest vertices along `f.n` when `lower` (the candidate), else
    /// its highest. Only the first `len` entries of the arrays are written and read.
    fn fill(&mut self, view: &PolyhedronView, f: &Frame, lower: bool, band: f64) {
        let sign = if lower { 1.0 } else { -1.0 };
        // Depth of a vertex below the extreme, counted into the shape.
        let depth = |v: &Vec3| sign * f.n.dot(&(v - f.o));
        let extreme = view.vertices.iter().map(depth).fold(f64::INFINITY, f64::min);
        let s = self;
        (s.len, s.hull_len, s.sign) = (0, 0, sign);
        for (k, v) in view.vertices.iter().enumerate() {
            let d = depth(v) - extreme;
            if d > band {
                continue;
            }
            let slot = if s.len < CAP {
                s.len += 1;
                s.len - 1
            } else {
                // Full: replace the kept vertex deepest into the shape if this one is nearer the plane.
                let w = (0..CAP).max_by(|&i, &j| (sign * s.h[i]).total_cmp(&(sign * s.h[j]))).unwrap_or(0);
                if d + extreme >= sign * s.h[w] {
                    continue;
                }
                w
            };
            s.id[slot] = k as u32;
            s.p[slot] = f.project(v);
            s.h[slot] = f.n.dot(&(v - f.o));
        }
        s.build_hull(f.eps);
    }

    /// Andrew's monotone chain; points within `eps` of a hull edge's line are dropped, so a hull of 1 or 2
    /// points is a point or a segment.
    fn build_hull(&mut self, eps: f64) {
        let mut order: [u8; CAP] = [0; CAP];
        for (k, o) in order.iter_mut().enumerate().take(self.len) {
            *o = k as u8;
        }
        let (p, id) = (&self.p, &self.id);
        order[..self.len].sort_unstable_by(|&i, &j| {
            let (a, b) = (p[i as usize], p[j as usize]);
            a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)).then(id[i as usize].cmp(&id[j as usize]))
        });
        let turn = |o: u8, a: u8, b: u8| {
            let (o, a, b) = (p[o as usize], p[a as usize], p[b as usize]);
            cross(a - o, b - o) > eps * (b - o).norm()
        };
        let mut h: [u8; CAP2] = [0; CAP2];
        let mut k = 0;
        for &i in &order[..self.len] {
            while k >= 2 && !turn(h[k - 2], h[k - 1], i) {
                k -= 1;
            }
            h[k] = i;
            k += 1;
        }
        let lower = k + 1;
        for &i in order[..self.len.saturating_sub(1)].iter().rev() {
            while k >= lower && !turn(h[k - 2], h[k - 1], i) {
                k -= 1;
            }
            h[k] = i;
            k += 1;
        }
        let mut len = if self.len > 1 { k - 1 } else { k };
        if len == 2 && (p[h[0] as usize] - p[h[1] as usize]).norm_squared() <= eps * eps {
            len = 1;
        }
        self.hull[..len].copy_from_slice(&h[..len]);
        self.hull_len = len;
    }

    #[inline]
    fn hp(&self, k: usize) -> Vec2 {
        self.p[self.hull[k] as usize]
    }

    /// Whether `x` is in the hull, within `eps`.
    fn contains(&self, x: &Vec2, eps: f64) -> bool {
        match self.hull_len {
            0 => false,
            1 => (x - self.hp(0)).norm_squared() <= eps * eps,
            2 => segment_distance2(x, &self.hp(0), &self.hp(1)).0 <= eps * eps,
            n => (0..n).all(|k| {
                let (a, b) = (self.hp(k), self.hp((k + 1) % n));
                cross(b - a, x - a) >= -eps * (b - a).norm()
            }),
        }
    }

    /// What of this feature makes `x`: a vertex `(id, height)`, or a hull edge `(ids lower first, height)`.
    fn locate(&self, x: &Vec2, eps: f64) -> Option<(Option<u32>, [u32; 2], f64)> {
        // Vertices projecting on one point (an edge along the normal): the one nearest the other shape.
        let mut vertex: Option<usize> = None;
        for i in 0..self.len {
            if (x - self.p[i]).norm_squared() <= eps * eps
                && vertex.is_none_or(|j| self.sign * (self.h[i] - self.h[j]) < 0.0)
            {
                vertex = Some(i);
            }
        }
        if let Some(i) = vertex {
            return Some((Some(self.id[i]), [0, 0], self.h[i]));
        }
        let n = self.hull_len;
        let edges = if n == 2 {
            1
        } else if n > 2 {
            n
        } else {
            0
        };
        for k in 0..edges {
            let (i, j) = (self.hull[k] as usize, self.hull[(k + 1) % n] as usize);
            let (dist2, lambda) = segment_distance2(x, &self.p[i], &self.p[j]);
            if dist2 <= eps * eps {
                let ids = [self.id[i].min(self.id[j]), self.id[i].max(self.id[j])];
                return Some((None, ids, self.h[i] + lambda * (self.h[j] - self.h[i])));
            }
        }
        None
    }
}

/// Squared distance from `x` to the segment `[a, b]`, and the parameter in `[0, 1]` of the nearest point.
#[inline]
fn segment_distance2(x: &Vec2, a: &Vec2, b: &Vec2) -> (f64, f64) {
    let e = b - a;
    let ee = e.norm_squared();
    let lambda = if ee > 0.0 { ((x - a).dot(&e) / ee).clamp(0.0, 1.0) } else { 0.0 };
    ((a + lambda * e - x).norm_squared(), lambda)
}

/// A fixed-capacity list of 2D points.
#[derive(Clone, Copy)]
struct Points {
    p: [Vec2; CAP2],
    len: usize,
}

impl Points {
    fn new() -> Self {
        Self { p: [Vec2::zeros(); CAP2], len: 0 }
    }

    fn push(&mut self, x: Vec2) {
        if self.len < CAP2 {
            self.p[self.len] = x;
            self.len += 1;
        }
    }
}

/// The convex intersection of the two hulls (polygon, segment or point, each within `eps`), as its vertices.
fn intersect(a: &Feature, b: &Feature, eps: f64, out: &mut Points, bufs: &mut [Points; 2]) {
    let (na, nb) = (a.hull_len, b.hull_len);
    if na == 0 || nb == 0 {
        return;
    }
    if na < nb {
        return intersect(b, a, eps, out, bufs);
    }
    match (na, nb) {
        (_, 1) => {
            if a.contains(&b.hp(0), eps) {
                out.push(b.hp(0));
            }
        }
        (1, _) => unreachable!("na >= nb"),
        (2, 2) => segments(&a.hp(0), &a.hp(1), &b.hp(0), &b.hp(1), eps, out),
        (_, 2) => {
            // Cyrus–Beck: the segment of b clipped by a's edges.
            let (p, q) = (b.hp(0), b.hp(1));
            let d = q - p;
            // The interval inside every edge within eps (is there one?), and inside exactly (where it is).
            let (mut lo, mut hi) = (0.0f64, 1.0f64);
            let (mut lo_eps, mut hi_eps) = (0.0f64, 1.0f64);
            for k in 0..na {
                let (u, v) = (a.hp(k), a.hp((k + 1) % na));
                let e = v - u;
                // Inside when cross(e, x − u) ≥ 0 (≥ −eps |e| within eps).
                let s0 = cross(e, p - u);
                let margin = eps * e.norm();
                let ds = cross(e, d);
                if ds.abs() <= f64::EPSILON * e.norm() * d.norm() {
                    if s0 + margin < 0.0 {
                        return;
                    }
                } else if ds > 0.0 {
                    lo = lo.max(-s0 / ds);
                    lo_eps = lo_eps.max(-(s0 + margin) / ds);
                } else {
                    hi = hi.min(-s0 / ds);
                    hi_eps = hi_eps.min(-(s0 + margin) / ds);
                }
            }
            if lo_eps > hi_eps {
                return;
            }
            if lo > hi {
                // Touching within eps only: one point.
                lo = (0.5 * (lo + hi)).clamp(0.0, 1.0);
                hi = lo;
            }
            out.push(p + lo * d);
            if (hi - lo) * d.norm() > eps {
                out.push(p + hi * d);
            }
        }
        _ => {
            // Sutherland–Hodgman: a clipped by each edge of b, between two buffers in turn.
            (bufs[0].len, bufs[1].len) = (0, 0);
            for k in 0..na {
                bufs[0].push(a.hp(k));
            }
            let mut c = 0;
            for k in 0..nb {
                let [b0, b1] = &mut *bufs;
                let (cur, next) = if c == 0 { (&*b0, b1) } else { (&*b1, b0) };
                let (u, v) = (b.hp(k), b.hp((k + 1) % nb));
                let e = v - u;
                let margin = eps * e.norm();
                let side = |x: &Vec2| cross(e, x - u);
                next.len = 0;
                for i in 0..cur.len {
                    let (x, y) = (cur.p[i], cur.p[(i + 1) % cur.len]);
                    let (sx, sy) = (side(&x), side(&y));
                    // Inside within eps; a crossing is placed on the edge's line itself.
                    let (ix, iy) = (sx >= -margin, sy >= -margin);
                    if ix {
                        next.push(x);
                    }
                    if ix != iy {
                        let t = if sx != sy { (sx / (sx - sy)).clamp(0.0, 1.0) } else { 0.5 };
                        next.push(x + (y - x) * t);
                    }
                }
                c ^= 1;
                if bufs[c].len == 0 {
                    return;
                }
            }
            for i in 0..bufs[c].len {
                out.push(bufs[c].p[i]);
            }
        }
    }
}

/// Intersection of two segments within `eps`: their crossing, or the overlap of collinear ones.
fn segments(p0: &Vec2, p1: &Vec2, q0: &Vec2, q1: &Vec2, eps: f64, out: &mut Points) {
    let (u, v) = (p1 - p0, q1 - q0);
    let (lu, lv) = (u.norm(), v.norm());
    let den = cross(u, v);
    if den.abs() > 1e-12 * lu * lv {
        let w = q0 - p0;
        let (s, t) = (cross(w, v) / den, cross(w, u) / den);
        if s >= -eps / lu && s <= 1.0 + eps / lu && t >= -eps / lv && t <= 1.0 + eps / lv {
            let (x, y) = (p0 + s.clamp(0.0, 1.0) * u, q0 + t.clamp(0.0, 1.0) * v);
            out.push(0.5 * (x + y));
        }
        return;
    }
    // Parallel: overlap of the two along u when on one line.
    if cross(u, q0 - p0).abs() > eps * lu {
        return;
    }
    let along = |x: &Vec2| (x - p0).dot(&u) / (lu * lu);
    let (a, b) = (along(q0), along(q1));
    let (lo, hi) = (a.min(b).max(0.0), a.max(b).min(1.0));
    if (lo - hi) * lu > eps {
        return;
    }
    out.push(p0 + lo * u);
    if (hi - lo) * lu > eps {
        out.push(p0 + hi * u);
    }
}

/// A candidate contact point: where, what makes it, heights of the candidate's and the antagonist's
/// surfaces above the plane's origin.
#[derive(Debug, Clone, Copy)]
struct Candidate {
    p: Vec2,
    label: Label,
    ha: f64,
    hb: f64,
}

/// The buffers of [`contact_points`], reused from one pair to the next (only the parts each step writes are
/// read, so they are never cleared).
#[derive(Clone)]
pub struct Scratch {
    fa: Feature,
    fb: Feature,
    pts: Points,
    bufs: [Points; 2],
    c: [Candidate; MAX_CANDIDATES],
}

impl Default for Scratch {
    fn default() -> Self {
        Scratch {
            fa: Feature::empty(),
            fb: Feature::empty(),
            pts: Points::new(),
            bufs: [Points::new(), Points::new()],
            c: [Candidate { p: Vec2::zeros(), label: (3, 0, 0, 0, 0), ha: 0.0, hb: 0.0 }; MAX_CANDIDATES],
        }
    }
}

impl std::fmt::Debug for Scratch {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Scratch")
    }
}

/// The contact points of candidate `a` and antagonist `b` on the plane `f`: features within `band` of the
/// plane, their intersection, candidates kept when their gap is at most `alert`, reduced to four; `witness`
/// is the pair of points realising the separation, when known. Calls `emit(position, gap)` in label order;
/// returns whether the projections met (else a single point half-way between their nearest points is given).
pub fn contact_points(
    a: &PolyhedronView,
    b: &PolyhedronView,
    f: &Frame,
    band: f64,
    alert: f64,
    witness: Option<(Vec3, Vec3)>,
    emit: impl FnMut(Vec3, f64),
) -> bool {
    contact_points_in(&mut Scratch::default(), a, b, f, band, alert, witness, emit)
}

/// [`contact_points`] in the buffers `scratch`.
#[allow(clippy::too_many_arguments)]
pub(crate) fn contact_points_in(
    scratch: &mut Scratch,
    a: &PolyhedronView,
    b: &PolyhedronView,
    f: &Frame,
    band: f64,
    alert: f64,
    witness: Option<(Vec3, Vec3)>,
    mut emit: impl FnMut(Vec3, f64),
) -> bool {
    let Scratch { fa, fb, pts, bufs, c } = scratch;
    fa.fill(a, f, true, band);
    fb.fill(b, f, false, band);
    let (fa, fb) = (&*fa, &*fb);
    let eps = f.eps;
    pts.len = 0;
    intersect(fa, fb, eps, pts, bufs);
    let mut len = 0;
    let mut add = |p: Vec2, hw: Option<(f64, f64)>, c: &mut [Candidate]| {
        if len == MAX_CANDIDATES || c[..len].iter().any(|q| (q.p - p).norm_squared() <= eps * eps) {
            return;
        }
        let (la, lb) = (fa.locate(&p, eps), fb.locate(&p, eps));
        let x = f.lift(&p);
        let ha = la.map_or_else(|| hw.map_or_else(|| a.entry(&x, &f.n), |h| h.0), |l| l.2);
        let hb = lb.map_or_else(|| hw.map_or_else(|| b.exit(&x, &f.n), |h| h.1), |l| l.2);
        if !(ha - hb).is_finite() {
            return; // a line missing a shape: rounding at a silhouette
        }
        let label = match (la, lb) {
            (Some((Some(v), _, _)), _) => (0, v, 0, 0, 0),
            (_, Some((Some(w), _, _))) => (1, w, 0, 0, 0),
            (Some((None, ea, _)), Some((None, eb, _))) => (2, ea[0], ea[1], eb[0], eb[1]),
            _ => (3, len as u32, 0, 0, 0),
        };
        c[len] = Candidate { p, label, ha, hb };
        len += 1;
    };
    for &p in &pts.p[..pts.len] {
        add(p, None, c);
    }
    if pts.len > 0 {
        // Vertices inside their own hull (a feature that is not flat) inside the other's: the hull vertices
        // inside the other hull are already corners of the intersection.
        for (s, o) in [(fa, fb), (fb, fa)] {
            for k in 0..s.len {
                if !s.hull[..s.hull_len].contains(&(k as u8)) && o.contains(&s.p[k], eps) {
                    add(s.p[k], None, c);
                }
            }
        }
        if let Some((wa, wb)) = witness {
            let p = f.project(&(0.5 * (wa + wb)));
            if fa.contains(&p, eps) && fb.contains(&p, eps) {
                add(p, Some((f.n.dot(&(wa - f.o)), f.n.dot(&(wb - f.o)))), c);
            }
        }
    } else if fa.hull_len > 0 && fb.hull_len > 0 {
        // Missed by rounding: one point half-way between the nearest points of the two hulls.
        let (pa, pb) = nearest(fa, fb);
        let (ha, hb) = (a.entry(&f.lift(&pa), &f.n), b.exit(&f.lift(&pb), &f.n));
        if (ha - hb).is_finite() {
            c[0] = Candidate { p: 0.5 * (pa + pb), label: (3, 0, 0, 0, 0), ha, hb };
            len = 1;
        }
    }
    // Keep the points within the alert distance.
    let mut kept = 0;
    for k in 0..len {
        if c[k].ha - c[k].hb <= alert {
            c[kept] = c[k];
            kept += 1;
        }
    }
    let sel = reduce(&mut c[..kept], eps);
    let chosen = &mut c[..sel];
    chosen.sort_unstable_by(|q, r| q.label.cmp(&r.label).then(q.p.x.total_cmp(&r.p.x)).then(q.p.y.total_cmp(&r.p.y)));
    for q in chosen.iter() {
        emit(f.lift(&q.p) + 0.5 * (q.ha + q.hb) * f.n, q.ha - q.hb);
    }
    pts.len > 0
}

/// The nearest points of two hulls (vertex against vertex or edge, both ways).
fn nearest(a: &Feature, b: &Feature) -> (Vec2, Vec2) {
    let mut best = (f64::INFINITY, Vec2::zeros(), Vec2::zeros());
    for (s, t, flip) in [(a, b, false), (b, a, true)] {
        for i in 0..s.hull_len {
            let x = s.hp(i);
            for k in 0..t.hull_len {
                let (u, v) = (t.hp(k), t.hp((k + 1) % t.hull_len));
                let (d, l) = segment_distance2(&x, &u, &v);
                if d < best.0 {
                    let y = u + l * (v - u);
                    best = if flip { (d, y, x) } else { (d, x, y) };
                }
            }
        }
    }
    (best.1, best.2)
}

/// Moves the (at most four) points kept to the front of `c` and returns how many: all of them up to four,
/// else the deepest, the farthest from it, the farthest from their line and the one adding the most area to
/// the triangle. A value within `tol` of the best is a tie, won by the lower label.
pub(crate) fn reduce_points<T: Labelled>(
    c: &mut [T],
    tol: f64,
    p: impl Fn(&T) -> Vec2,
    gap: impl Fn(&T) -> f64,
) -> usize {
    if c.len() <= 4 {
        return c.len();
    }
    let pick = |c: &[T], from: usize, score: &dyn Fn(&T) -> f64| {
        let best = c[from..].iter().map(score).fold(f64::NEG_INFINITY, f64::max);
        let mut k = from;
        for i in from..c.len() {
            if score(&c[i]) >= best - tol && (score(&c[k]) < best - tol || c[i].label() < c[k].label()) {
                k = i;
            }
        }
        k
    };
    let k = pick(c, 0, &|q| -gap(q));
    c.swap(0, k);
    let p0 = p(&c[0]);
    let k = pick(c, 1, &|q| (p(q) - p0).norm());
    c.swap(1, k);
    let p1 = p(&c[1]);
    let e = p1 - p0;
    let len = e.norm().max(f64::MIN_POSITIVE);
    let k = pick(c, 2, &|q| cross(e, p(q) - p0).abs() / len);
    c.swap(2, k);
    let p2 = p(&c[2]);
    // Orient the triangle counter-clockwise; the area a point adds lies beyond one of its edges.
    let (p1, p2) = if cross(p1 - p0, p2 - p0) >= 0.0 { (p1, p2) } else { (p2, p1) };
    let tri = [(p0, p1), (p1, p2), (p2, p0)];
    let added = |q: &T| {
        let x = p(q);
        tri.iter().map(|(u, v)| (-cross(v - u, x - u)).max(0.0)).fold(0.0, f64::max)
    };
    let k = pick(c, 3, &|q| added(q) / len);
    c.swap(3, k);
    4
}

/// Something with a [`Label`].
pub(crate) trait Labelled {
    fn label(&self) -> Label;
}

impl Labelled for Candidate {
    fn label(&self) -> Label {
        self.label
    }
}

fn reduce(c: &mut [Candidate], eps: f64) -> usize {
    reduce_points(c, eps, |q| q.p, |q| q.ha - q.hb)
}
