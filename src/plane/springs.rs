//! Viscoelastic springs between 2D bodies or to a world anchor: the sublayer of
//! Saussine et al. 2006, §2.9, law (17), shared by both 2D engines (the NSCD
//! engine makes each an implicit NLGS row, `nscd::sublayer`; the 2D MD engine
//! applies its force explicitly).
//!
//! A spring joins a point of body `a` to a point of body `b` or to a fixed anchor
//! in the world. With `L` its length, `L0` its rest length and `ε0` a prestrain,
//! the strain is `ε = (L − L0)/L0 − ε0`. Law (17) is written in the paper as
//! `R_N = −k_N ε + ν ε̇`; we take `R_N` as the force pushing the bodies apart
//! along the spring axis and make the dashpot dissipative,
//! `R_N = −k_N ε − ν ε̇`, `ε̇ = U_N / L0`
//! (with the paper's sign the dashpot would feed energy in). `k_N` (N) is the
//! force per unit strain and `ν` (N·s) the force per unit strain rate: a spring of
//! stiffness `k` (N/m) and damping `c` (N·s/m) has `k_N = k L0`, `ν = c L0`.
//! `compression_only` makes the spring a unilateral support (`R_N ≥ 0`), the
//! "derived Signorini law" reading of §2.9.

use crate::geometry::{cross, rotate, Vec2};
use serde::{Deserialize, Serialize};

/// Dot product of two generalized 3-vectors, e.g. `h_n · u` = the normal velocity
/// contribution of one body (m/s when `u = (v_x, v_y, ω)`).
#[inline(always)]
pub fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Generalized direction `(d_x, d_y, r × d)`.
#[inline(always)]
pub fn gen_dir(r: Vec2, d: Vec2) -> [f64; 3] {
    [d.x, d.y, cross(r, d)]
}

/// A sublayer spring.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Spring {
    /// Body at the first end.
    pub a: usize,
    /// Attachment on `a`, relative to its centre of mass in its body frame (m).
    pub point_a: [f64; 2],
    /// Body at the second end, or `None` for a fixed anchor.
    pub b: Option<usize>,
    /// Attachment on `b` relative to its centre of mass in its body frame, or the
    /// world anchor point (m).
    pub point_b: [f64; 2],
    /// Force per unit strain `k_N` (N).
    pub k_n: f64,
    /// Force per unit strain rate `ν` (N·s).
    pub nu: f64,
    /// Rest length `L0` (m).
    pub rest_length: f64,
    /// Prestrain `ε0` (dimensionless), subtracted from the strain `(L − L0)/L0`.
    pub prestrain: f64,
    /// Only pushes (`R_N ≥ 0`).
    pub compression_only: bool,
    /// Impulse of the last step (N·s), the warm start.
    pub impulse: f64,
}

/// The shortest length a spring may take, as a fraction of its rest length: a
/// spring's length is a distance, so law (17) turns over where it passes
/// through zero (a pad pushed past its anchor is then pushed on, to its mirror
/// position beyond it: docs/settlement-driver.md, "Landings in stages"). A
/// spring shorter than this is crushed, and the step fails.
pub const CRUSHED: f64 = 0.1;

/// The first spring of `springs` shorter than [`CRUSHED`] times its rest length
/// in configuration `q`: the body at its first end and what happened.
pub fn crushed(springs: &[Spring], q: &[[f64; 3]]) -> Option<(usize, String)> {
    springs.iter().enumerate().find_map(|(k, s)| {
        let l = s.length(q);
        (l < CRUSHED * s.rest_length).then(|| (s.a, crushed_message(k, l, s.rest_length)))
    })
}

/// What a crushed spring `k` of length `l` and rest length `rest` (m) says ([`crushed`]; the 3D springs' too).
pub(crate) fn crushed_message(k: usize, l: f64, rest: f64) -> String {
    format!("spring {k} crushed to {l:.3e} m, below {CRUSHED} of its {rest:.3e} m rest length (law (17) turns over at zero length)")
}

/// The bodies tied to a fixed anchor by a spring (the sublayer pads), sorted,
/// each once: their positions follow the springs' load, not a trend of their
/// own ([`crate::engine::Engine::anchored_bodies`]).
pub fn anchored(springs: &[Spring]) -> Vec<usize> {
    anchored_ends(springs.iter().map(|s| (s.a, s.b.is_none())))
}

/// The first ends `a` of the `(a, to an anchor)` springs tied to an anchor, sorted, each once (2D and 3D).
pub(crate) fn anchored_ends(ends: impl Iterator<Item = (usize, bool)>) -> Vec<usize> {
    let mut bodies: Vec<usize> = ends.filter(|e| e.1).map(|e| e.0).collect();
    bodies.sort_unstable();
    bodies.dedup();
    bodies
}

/// Placement of an attachment point: world point and lever arm.
#[inline]
fn attach(q: &[f64; 3], p: [f64; 2]) -> (Vec2, Vec2) {
    let r = rotate(Vec2::new(p[0], p[1]), q[2].cos(), q[2].sin());
    (Vec2::new(q[0], q[1]) + r, r)
}

impl Spring {
    /// Axis (unit, from the second end to `a`), length, lever arms of both ends.
    fn geometry(&self, q: &[[f64; 3]]) -> (Vec2, f64, Vec2, Vec2) {
        let (pa, ra) = attach(&q[self.a], self.point_a);
        let (pb, rb) = match self.b {
            Some(b) => attach(&q[b], self.point_b),
            None => (Vec2::new(self.point_b[0], self.point_b[1]), Vec2::zeros()),
        };
        let d = pa - pb;
        let l = d.norm();
        (if l > 0.0 { d / l } else { Vec2::new(0.0, 1.0) }, l, ra, rb)
    }

    /// Relative normal velocity (m/s), strain and generalized axis directions
    /// `(n_x, n_y, r × n)` of both ends in configuration `q`, `u`.
    pub(crate) fn state(&self, q: &[[f64; 3]], u: &[[f64; 3]]) -> (f64, f64, [f64; 3], [f64; 3]) {
        let (n, l, ra, rb) = self.geometry(q);
        let (ha, hb) = (gen_dir(ra, n), gen_dir(rb, n));
        let un = dot3(&ha, &u[self.a]) - self.b.map_or(0.0, |b| dot3(&hb, &u[b]));
        let eps = (l - self.rest_length) / self.rest_length - self.prestrain;
        (un, eps, ha, hb)
    }

    /// Elastic energy (J) in configuration `q`: `½ k_N L0 ε²`, the work of the
    /// elastic part `−k_N ε` of law (17) from `ε = 0` (0 for a compression-only
    /// spring in tension, `ε > 0`).
    pub fn elastic_energy(&self, q: &[[f64; 3]]) -> f64 {
        let eps = (self.length(q) - self.rest_length) / self.rest_length - self.prestrain;
        if self.compression_only && eps > 0.0 {
            0.0
        } else {
            0.5 * self.k_n * self.rest_length * eps * eps
        }
    }

    /// Unit axis from the second end to the first (`a`) in configuration `q`: a
    /// positive `R_N` pushes `a` along it.
    pub fn axis(&self, q: &[[f64; 3]]) -> [f64; 2] {
        let n = self.geometry(q).0;
        [n.x, n.y]
    }

    /// Current length (m).
    pub fn length(&self, q: &[[f64; 3]]) -> f64 {
        self.geometry(q).1
    }

    /// The force `R_N` (N) pushing the ends apart in configuration `q`, `u`, with
    /// the generalized axis directions of both ends: the first body gets the
    /// generalized force `R_N h_a` (N, N, N·m), the second `−R_N h_b`.
    pub fn generalized_force(&self, q: &[[f64; 3]], u: &[[f64; 3]]) -> (f64, [f64; 3], [f64; 3]) {
        let (un, eps, ha, hb) = self.state(q, u);
        let r = -self.k_n * eps - self.nu * un / self.rest_length;
        (if self.compression_only { r.max(0.0) } else { r }, ha, hb)
    }

    /// Force `R_N` (N) pushing the ends apart, in configuration `q`, `u`.
    pub fn force(&self, q: &[[f64; 3]], u: &[[f64; 3]]) -> f64 {
        self.generalized_force(q, u).0
    }
}
