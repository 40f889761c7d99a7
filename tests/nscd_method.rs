//! The NSCD method (`ballast::nscd::method`) is generic over the contact's dimension: a 3D law brings its row,
//! not a solver. Here a test-local 3D point contact between spheres (six degrees of freedom per body, impulse
//! `(P_N, P_T1, P_T2)`, exact Coulomb disc) runs through the same Gauss–Seidel, policies, check pass and split
//! as the 2D engine, against two analytic results:
//!
//! - a sphere thrown sliding without spin on a floor ends rolling at 5/7 of its speed, in the direction it was
//!   thrown: friction acts at the contact point, so the angular momentum about it, `m v R + I ω` with
//!   `I = 2/5 m R²`, is conserved, by every step of the discrete scheme too;
//! - a column of spheres at rest on a floor: the contact under sphere `k` carries the weight of the spheres
//!   above it and of itself, `(N − k) m g h` per step, which Gauss–Seidel reaches only by iterating (each sweep
//!   passes the load one contact further down).
//!
//! The accelerated projected gradient (`method::apgd`) runs on the same rows, projecting the impulse on the
//! Coulomb disc (`ConeRow`), to the same two results.

use ballast::nscd::method::apgd::{solve_apgd_with, AffineRow, ApgdOptions, ApgdWorkspace, ConeRow};
use ballast::nscd::method::{
    apply_impulses, solve_nlgs, solve_nlgs_split, NlgsReport, NlgsSettings, Policy, Row, SplitWorkspace, SweepNorms,
};

/// A body's generalised velocity or inverse mass: `(v_x, v_y, v_z, ω_x, ω_y, ω_z)`.
type Dofs = [f64; 6];

/// A 3D point contact between two spheres (or a sphere and the fixed floor), normal `n = +z` towards the
/// candidate, tangents `t1 = x`, `t2 = y`; the contact point is `R` below the candidate's centre and `R` above
/// the antagonist's (the floor's lever arm is irrelevant: it is fixed).
#[derive(Debug, Clone, Copy)]
struct PointRow3 {
    a: u32,
    b: u32,
    /// Rows of `H*` for the candidate and the antagonist: normal, first and second tangent.
    h_a: [Dofs; 3],
    h_b: [Dofs; 3],
    /// The local Delassus block `W = H* M⁻¹ H` (diagonal here: `nn`, `tt`, `tt`).
    w: [f64; 3],
    /// Impulse `(P_N, P_T1, P_T2)` (N·s).
    p: [f64; 3],
    mu: f64,
}

fn dot(h: &Dofs, u: &Dofs) -> f64 {
    (0..6).map(|d| h[d] * u[d]).sum()
}

impl PointRow3 {
    fn new((a, b): (u32, u32), radius: f64, inv_m: &[Dofs], mu: f64) -> Self {
        let r = radius;
        // r_a = −R z: r_a × x = −R y, r_a × y = +R x; r_b = +R z: the opposite signs.
        let h_a = [[0., 0., 1., 0., 0., 0.], [1., 0., 0., 0., -r, 0.], [0., 1., 0., r, 0., 0.]];
        let h_b = [[0., 0., 1., 0., 0., 0.], [1., 0., 0., 0., r, 0.], [0., 1., 0., -r, 0., 0.]];
        let wk = |k: usize| {
            let (ia, ib) = (&inv_m[a as usize], &inv_m[b as usize]);
            (0..6).map(|d| h_a[k][d] * h_a[k][d] * ia[d] + h_b[k][d] * h_b[k][d] * ib[d]).sum::<f64>()
        };
        Self { a, b, h_a, h_b, w: [wk(0), wk(1), wk(2)], p: [0.0; 3], mu }
    }

    /// The exact Signorini–Coulomb solution for a diagonal block with equal tangential terms: the normal part
    /// alone (no coupling), then the sticking tangential impulse, scaled back onto the disc `|P_T| ≤ μ P_N`.
    fn solve(&self, u0: [f64; 3]) -> [f64; 3] {
        let pn = (-u0[0] / self.w[0]).max(0.0);
        let (s1, s2) = (-u0[1] / self.w[1], -u0[2] / self.w[2]);
        let norm = s1.hypot(s2);
        let scale = if norm > self.mu * pn { self.mu * pn / norm } else { 1.0 };
        [pn, s1 * scale, s2 * scale]
    }

    fn apply(&self, u: &mut [Dofs], inv_m: &[Dofs], dp: [f64; 3], sign: f64) {
        for (body, h, s) in [(self.a, &self.h_a, sign), (self.b, &self.h_b, -sign)] {
            let (ub, im) = (&mut u[body as usize], &inv_m[body as usize]);
            for d in 0..6 {
                ub[d] += s * im[d] * (h[0][d] * dp[0] + h[1][d] * dp[1] + h[2][d] * dp[2]);
            }
        }
    }
}

impl Row for PointRow3 {
    type Dofs = Dofs;

    fn bodies(&self) -> (u32, u32) {
        (self.a, self.b)
    }

    fn set_bodies(&mut self, a: u32, b: u32) {
        (self.a, self.b) = (a, b);
    }

    fn take_impulse(&mut self, other: &Self) {
        self.p = other.p;
    }

    fn add_impulse(&self, u: &mut [Dofs], inv_m: &[Dofs], sign: f64) {
        self.apply(u, inv_m, self.p, sign);
    }

    fn visit<const UPDATE: bool>(&mut self, u: &mut [Dofs], inv_m: &[Dofs], omega: f64, norms: &mut SweepNorms) {
        assert_eq!(omega, 1.0, "the test law is not over-relaxed");
        let (ua, ub) = (u[self.a as usize], u[self.b as usize]);
        let u0: [f64; 3] =
            std::array::from_fn(|k| dot(&self.h_a[k], &ua) - dot(&self.h_b[k], &ub) - self.w[k] * self.p[k]);
        let (p, q) = (self.p, self.solve(u0));
        let dp: [f64; 3] = std::array::from_fn(|k| q[k] - p[k]);
        let changed = dp.iter().any(|&d| d != 0.0);
        if UPDATE && changed {
            self.p = q;
            self.apply(u, inv_m, dp, 1.0);
        }
        add_norms(norms, self.w, p, q, changed);
    }
}

/// The norms of a change of a point contact's impulse from `p` to `q` under its diagonal block `w`
/// ([`SweepNorms::add`]).
fn add_norms(norms: &mut SweepNorms, w: [f64; 3], p: [f64; 3], q: [f64; 3], changed: bool) {
    let du: [f64; 3] = std::array::from_fn(|k| w[k] * (q[k] - p[k]));
    let pm: [f64; 3] = std::array::from_fn(|k| 0.5 * (p[k] + q[k]));
    let (wp, wq): ([f64; 3], [f64; 3]) = (std::array::from_fn(|k| w[k] * p[k]), std::array::from_fn(|k| w[k] * q[k]));
    let d3 = |x: &[f64; 3], y: &[f64; 3]| x[0] * y[0] + x[1] * y[1] + x[2] * y[2];
    norms.add(
        d3(&du, &du),
        d3(&pm, &pm),
        d3(&pm, &du),
        0.5 * (d3(&p, &wp) + d3(&q, &wq)),
        0.5 * (d3(&wp, &wp) + d3(&wq, &wq)),
        d3(&q, &wq),
        changed,
    );
}

/// The point contact in the accelerated projected gradient: `(P_N, P_T1, P_T2)` projected on `P_N ≥ 0` and the
/// disc `|P_T| ≤ μ P_N` (or the given Tresca bound), radially.
impl ConeRow for PointRow3 {
    type Impulse = [f64; 3];

    fn impulse(&self) -> [f64; 3] {
        self.p
    }

    fn set_impulse(&mut self, p: [f64; 3]) {
        self.p = p;
    }

    fn normal(&self) -> f64 {
        self.p[0]
    }

    fn mu(&self) -> f64 {
        self.mu
    }

    fn local_velocity(&self, u: &[Dofs]) -> [f64; 3] {
        let (ua, ub) = (u[self.a as usize], u[self.b as usize]);
        std::array::from_fn(|k| dot(&self.h_a[k], &ua) - dot(&self.h_b[k], &ub))
    }

    fn gradient(&self, v: [f64; 3], c: f64) -> [f64; 3] {
        [v[0] - c, v[1], v[2]]
    }

    /// Contacts at zero gap, no restitution: the threshold is 0.
    fn label(&self, _u: &[Dofs]) -> f64 {
        0.0
    }

    fn diagonal(&self) -> [f64; 3] {
        self.w
    }

    fn lambda_max(&self) -> f64 {
        self.w.iter().copied().fold(0.0, f64::max)
    }

    fn project(&self, x: [f64; 3], tresca: Option<f64>) -> [f64; 3] {
        let pn = x[0].max(0.0);
        let bound = tresca.unwrap_or(self.mu * pn);
        let norm = x[1].hypot(x[2]);
        let scale = if norm > bound { bound / norm } else { 1.0 };
        [pn, x[1] * scale, x[2] * scale]
    }

    fn add_impulse_of(&self, u: &mut [Dofs], inv_m: &[Dofs], p: [f64; 3], sign: f64) {
        self.apply(u, inv_m, p, sign);
    }

    fn add_norms(&self, norms: &mut SweepNorms, p: [f64; 3], q: [f64; 3], changed: bool) {
        add_norms(norms, self.w, p, q, changed);
    }
}

/// The type of an empty list of springs: these problems have none.
#[derive(Debug, Clone, Copy)]
enum NoSpring {}

impl Row for NoSpring {
    type Dofs = Dofs;

    fn bodies(&self) -> (u32, u32) {
        match *self {}
    }

    fn set_bodies(&mut self, _: u32, _: u32) {
        match *self {}
    }

    fn take_impulse(&mut self, _: &Self) {
        match *self {}
    }

    fn add_impulse(&self, _: &mut [Dofs], _: &[Dofs], _: f64) {
        match *self {}
    }

    fn visit<const UPDATE: bool>(&mut self, _: &mut [Dofs], _: &[Dofs], _: f64, _: &mut SweepNorms) {
        match *self {}
    }
}

impl AffineRow for NoSpring {
    fn impulse(&self) -> f64 {
        match *self {}
    }

    fn set_impulse(&mut self, _: f64) {
        match *self {}
    }

    fn axial_velocity(&self, _: &[Dofs]) -> f64 {
        match *self {}
    }

    fn h_alpha(&self) -> f64 {
        match *self {}
    }

    fn h_beta(&self) -> f64 {
        match *self {}
    }

    fn w(&self) -> f64 {
        match *self {}
    }

    fn compression_only(&self) -> bool {
        match *self {}
    }

    fn solve_affine(&self, _: f64) -> f64 {
        match *self {}
    }

    fn add_impulse_of(&self, _: &mut [Dofs], _: &[Dofs], _: f64, _: f64) {
        match *self {}
    }
}

/// No springs in these problems.
fn no_springs() -> [NoSpring; 0] {
    []
}

const G: f64 = 9.81;
const H: f64 = 1e-3;

/// A granite sphere of radius `r`: inverse masses of its six dofs (`I = 2/5 m R²`) and its mass.
fn sphere(r: f64) -> (Dofs, f64) {
    let m = 2700.0 * 4.0 / 3.0 * std::f64::consts::PI * r.powi(3);
    let ii = 1.0 / (0.4 * m * r * r);
    ([1.0 / m, 1.0 / m, 1.0 / m, ii, ii, ii], m)
}

/// How a problem is solved: plain Gauss–Seidel, split in two halves on 1 or 2 threads, or the accelerated
/// projected gradient alone (no Gauss–Seidel sweeps first).
#[derive(Debug, Clone, Copy)]
enum Method {
    Nlgs,
    Split(usize),
    Apgd,
}

/// Solves the problem `(u, inv_m, rows)` by `method` with `settings`.
fn solve(
    method: Method,
    settings: &NlgsSettings,
    u: &mut [Dofs],
    inv_m: &[Dofs],
    rows: &mut [PointRow3],
) -> NlgsReport {
    let springs = &mut no_springs();
    match method {
        Method::Nlgs => solve_nlgs(settings, u, inv_m, rows, springs),
        // The split needs an abscissa per body: its index (the column stands along z).
        Method::Split(threads) => {
            let s = NlgsSettings { split_min_rows: 2, ..*settings };
            solve_nlgs_split(&s, &mut SplitWorkspace::default(), threads, |i| i as f64, u, inv_m, rows, springs)
        }
        Method::Apgd => {
            let opts = ApgdOptions { nlgs_first: 0, ..ApgdOptions::default() };
            solve_apgd_with(settings, &opts, &mut ApgdWorkspace::default(), u, inv_m, rows, springs)
        }
    }
}

fn settings(tolerance: f64) -> NlgsSettings {
    NlgsSettings { policy: Policy::Quad, tolerance, max_iterations: 100_000, ..NlgsSettings::default() }
}

#[test]
fn a_sliding_sphere_ends_rolling_at_five_sevenths_of_its_speed() {
    for method in [Method::Nlgs, Method::Apgd] {
        sliding_sphere(method);
    }
}

fn sliding_sphere(method: Method) {
    let r = 0.02;
    let (im, _) = sphere(r);
    // Body 0: the fixed floor; body 1: the sphere, thrown at 1.2 m/s along (3, 4)/5, no spin.
    let inv_m = vec![[0.0; 6], im];
    let (v0, dir) = (1.2, [0.6, 0.8]);
    let mut u = vec![[0.0; 6], [v0 * dir[0], v0 * dir[1], 0.0, 0.0, 0.0, 0.0]];
    let mut rows = vec![PointRow3::new((1, 0), r, &inv_m, 0.3)];
    // Sliding lasts 2 v0 / (7 μ g) = 0.082 s: 200 steps reach rolling.
    for _ in 0..200 {
        u[1][2] -= G * H; // u_free: gravity
        apply_impulses(&mut u, &inv_m, &rows, &no_springs());
        let report = solve(method, &settings(1e-12), &mut u, &inv_m, &mut rows);
        assert!(report.converged, "{method:?}: {report:?}");
    }
    let v = u[1][0].hypot(u[1][1]);
    // Round-off only: each step's impulse conserves the angular momentum about the contact point exactly.
    assert!((v - 5.0 / 7.0 * v0).abs() < 1e-9, "{method:?}: {v} m/s against 5/7 × {v0}");
    assert!((u[1][0] * dir[1] - u[1][1] * dir[0]).abs() < 1e-12, "{method:?}: the direction turned: {:?}", u[1]);
    // Rolling: the contact point is at rest (v_x − R ω_y = 0, v_y + R ω_x = 0), and the sphere does not sink.
    assert!((u[1][0] - r * u[1][4]).abs() < 1e-9 && (u[1][1] + r * u[1][3]).abs() < 1e-9, "{method:?}: {:?}", u[1]);
    assert!(u[1][2].abs() < 1e-12, "{method:?}: {:?}", u[1]);
}

/// A column of `n` spheres on the floor, cold (`P = 0`), solved to `tolerance`: the bodies' velocities, the
/// rows and the report.
fn column(n: usize, method: Method) -> (Vec<Dofs>, Vec<PointRow3>, f64) {
    let r = 0.02;
    let (im, m) = sphere(r);
    let mut inv_m = vec![[0.0; 6]];
    inv_m.extend(std::iter::repeat_n(im, n));
    let mut u = vec![[0.0; 6]; n + 1];
    u.iter_mut().skip(1).for_each(|ui| ui[2] = -G * H);
    let mut rows: Vec<PointRow3> = (1..=n).map(|k| PointRow3::new((k as u32, k as u32 - 1), r, &inv_m, 0.5)).collect();
    let report = solve(method, &settings(1e-10), &mut u, &inv_m, &mut rows);
    assert!(report.converged, "{method:?}: {report:?}");
    if !matches!(method, Method::Apgd) {
        assert!(report.iterations > n, "Gauss–Seidel passes the load one contact per sweep: {report:?}");
    }
    (u, rows, m)
}

#[test]
fn a_column_of_spheres_carries_its_weight_contact_by_contact() {
    let n = 12;
    for method in [Method::Nlgs, Method::Apgd] {
        let (u, rows, m) = column(n, method);
        for (k, row) in rows.iter().enumerate() {
            // Under sphere k + 1: the n − k spheres from it up. The policy's 1e-10 bounds the relative error of
            // the impulses' velocity; 1e-6 of the weight leaves room for the slow modes of the chain.
            let weight = (n - k) as f64 * m * G * H;
            assert!(
                (row.p[0] - weight).abs() < 1e-6 * weight,
                "{method:?}, contact {k}: {} N·s for {weight}",
                row.p[0]
            );
            assert!(row.p[1].abs() + row.p[2].abs() < 1e-15, "{method:?}, contact {k}: {:?}", row.p);
        }
        for ui in &u[1..] {
            assert!(ui.iter().all(|v| v.abs() < 1e-8), "{method:?}: {ui:?}");
        }
    }
    let (_, rows, _) = column(n, Method::Nlgs);
    // The split method (two halves of the column swept side by side, the interface after) gives the same
    // solution, and the same numbers on one thread or two.
    let (u1, rows1, _) = column(n, Method::Split(1));
    let (u2, rows2, _) = column(n, Method::Split(2));
    assert_eq!(u1, u2);
    assert!(rows1.iter().zip(&rows2).all(|(a, b)| a.p == b.p));
    for (a, b) in rows.iter().zip(&rows1) {
        assert!((a.p[0] - b.p[0]).abs() < 1e-6 * a.p[0], "{:?} {:?}", a.p, b.p);
    }
}
