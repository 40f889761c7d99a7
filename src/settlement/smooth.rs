//! A spatially smoothed extrapolation field: each body's fitted move over a
//! jump replaced by the local linear kernel fit of the moves of the bodies
//! around it (an option of this crate, not of Karrech et al. 2007, whose §3
//! extrapolates every body on its own fit).
//!
//! Why: under cyclic load a grain's cycle-end position is the sample's slow,
//! spatially coherent compaction plus a rattle of its own (measured on the
//! Karrech sample: median 4–5 µm a cycle per sphere where the plate settles
//! 2.5 µm). A window of `k` cycles fits part of that rattle as trend, and `h`
//! cycles of it drive neighbours into each other (overlaps of up to two thirds
//! of a radius after a 60-cycle jump); the relaxation then lands a packing
//! whose contact network the load recompacts. The mean of the moves over a
//! neighbourhood keeps the coherent part and averages the rattle out
//! (docs/settlement-driver.md, "Smoothed field").
//!
//! The smoothed move of body `i` is the value at `x_i` of the affine field
//! `a + G (x − x_i)` fitted to its neighbours' moves by weighted least squares
//! (local linear kernel regression), the weight of body `j` `exp(−r²/(2ℓ²))`,
//! `r` the distance between their positions at the end of the window
//! (straight, not across periodic boundaries), cut at `r = 3ℓ`. An affine
//! field (a uniform strain: the compaction of a confined sample) is kept
//! exactly, at the walls too, where a plain mean would shift it by the one-sided
//! neighbourhood; a body whose neighbours do not span the space (fewer than
//! `dim + 2`, or on a line) takes their weighted mean. Bodies marked as excluded
//! (the settlement body, bodies without contact) neither take part in the
//! others' fits nor take one: they keep their own move.

use crate::engine::Configuration;
use std::collections::HashMap;

/// The cut-off of the Gaussian weights, in smoothing lengths.
const CUTOFF: f64 = 3.0;

/// The neighbours and weights of each body, computed once per jump from the
/// positions at the end of the window.
#[derive(Debug, Clone, PartialEq)]
pub struct Smoothing {
    /// Per body: `(other body, weight)`, itself included; empty for an excluded body.
    neighbours: Vec<Vec<(u32, f64)>>,
}

impl Smoothing {
    /// The weights of smoothing length `length` (m, > 0) over the first `dim`
    /// coordinates of `positions` (the translations); `excluded[b]` keeps body
    /// `b` out (one flag per body, or empty: none excluded).
    ///
    /// # Panics
    /// If `excluded` is neither empty nor one flag per body, or `dim` exceeds the
    /// coordinates per body.
    pub fn new(positions: &Configuration, dim: usize, length: f64, excluded: &[bool]) -> Self {
        let n = positions.len();
        assert!(excluded.is_empty() || excluded.len() == n, "one flag per body");
        assert!(dim <= positions.dof && dim <= 3, "dim translations of dof coordinates");
        let out = |b: usize| excluded.get(b).copied().unwrap_or(false);
        let cell_size = CUTOFF * length;
        let cell = |b: usize| {
            let mut c = [0i64; 3];
            for (d, cd) in c.iter_mut().enumerate().take(dim) {
                *cd = (positions.body(b)[d] / cell_size).floor() as i64;
            }
            c
        };
        let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
        for b in (0..n).filter(|&b| !out(b)) {
            grid.entry(cell(b)).or_default().push(b as u32);
        }
        let reach: Vec<i64> = (0..3).map(|d| if d < dim { 1 } else { 0 }).collect();
        let (cut2, two_l2) = ((CUTOFF * length).powi(2), 2.0 * length * length);
        let neighbours = (0..n)
            .map(|i| {
                if out(i) {
                    return Vec::new();
                }
                let (ci, pi) = (cell(i), &positions.body(i)[..dim]);
                let mut list = Vec::new();
                for dx in -reach[0]..=reach[0] {
                    for dy in -reach[1]..=reach[1] {
                        for dz in -reach[2]..=reach[2] {
                            let Some(members) = grid.get(&[ci[0] + dx, ci[1] + dy, ci[2] + dz]) else { continue };
                            for &j in members {
                                let pj = &positions.body(j as usize)[..dim];
                                let r2: f64 = pi.iter().zip(pj).map(|(a, b)| (a - b) * (a - b)).sum();
                                if r2 <= cut2 {
                                    list.push((j, (-r2 / two_l2).exp()));
                                }
                            }
                        }
                    }
                }
                list.sort_unstable_by_key(|&(j, _)| j);
                local_linear(&mut list, positions, i, dim, length);
                list
            })
            .collect();
        Self { neighbours }
    }

    /// Replaces the first `dim` of every `stride` values of `moves` (body-major:
    /// body `b`'s move is `moves[b * stride..][..dim]`, m) by the local linear
    /// fit over the body's neighbours; excluded bodies keep theirs.
    ///
    /// # Panics
    /// If `moves` does not hold `stride` values per body.
    pub fn apply(&self, moves: &mut [f64], stride: usize, dim: usize) {
        assert_eq!(moves.len(), self.neighbours.len() * stride, "stride values per body");
        let raw = moves.to_vec();
        for (i, list) in self.neighbours.iter().enumerate() {
            if list.is_empty() {
                continue;
            }
            let total: f64 = list.iter().map(|&(_, w)| w).sum();
            // 1 for a local linear fit (to rounding), the Gaussian sum for a mean.
            for d in 0..dim {
                let sum: f64 = list.iter().map(|&(j, w)| w * raw[j as usize * stride + d]).sum();
                moves[i * stride + d] = sum / total;
            }
        }
    }
}

/// Turns the Gaussian weights `w_j` of body `i`'s neighbours into the weights
/// of its local linear fit: `a = e₁ᵀ M⁻¹ Σ_j w_j [1, x_j − x_i] m_j` with `M =
/// Σ_j w_j [1, x_j − x_i][1, x_j − x_i]ᵀ`, i.e. `w_j e₁ᵀ M⁻¹ [1, x_j − x_i]`
/// (they sum to 1; offsets in units of the smoothing length `length`, so that
/// `M` is of order one). Leaves the Gaussian weights (a weighted mean) if `M` is
/// singular or too poorly conditioned to trust.
fn local_linear(list: &mut [(u32, f64)], positions: &Configuration, i: usize, dim: usize, length: f64) {
    use nalgebra::{Matrix4, Vector4};
    if list.len() < dim + 2 {
        return;
    }
    let xi = positions.body(i);
    let basis = |j: u32| {
        let xj = positions.body(j as usize);
        let mut v = Vector4::new(1.0, 0.0, 0.0, 0.0);
        for d in 0..dim {
            v[d + 1] = (xj[d] - xi[d]) / length;
        }
        v
    };
    let mut m = Matrix4::zeros();
    for &(j, w) in list.iter() {
        let v = basis(j);
        m += w * v * v.transpose();
    }
    // The unused coordinates (2D) decoupled with a unit diagonal.
    let scale = (1..=dim).map(|d| m[(d, d)]).fold(0.0, f64::max).max(f64::MIN_POSITIVE);
    for d in dim + 1..4 {
        m[(d, d)] = scale;
    }
    let Some(inv) = m.try_inverse() else { return };
    // A neighbourhood on a line (or a plane in 3D) makes `M` nearly singular:
    // its smallest eigenvalue tiny against the largest.
    let eig = m.symmetric_eigenvalues();
    if eig.min() <= 1e-6 * eig.max() {
        return;
    }
    let row = inv.row(0).transpose();
    for (j, w) in list.iter_mut() {
        *w *= row.dot(&basis(*j));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn bodies(points: &[[f64; 3]]) -> Configuration {
        Configuration { dof: 3, bodies: (0..points.len()).collect(), q: points.iter().flatten().copied().collect() }
    }

    fn line(xs: &[f64]) -> Configuration {
        bodies(&xs.iter().map(|&x| [x, 0.0, 0.0]).collect::<Vec<_>>())
    }

    /// A jittered cubic (3D) or square (2D, z = 0) lattice of `n` a side, 1 mm apart.
    fn lattice(n: usize, dim: usize) -> Vec<[f64; 3]> {
        let mut p = Vec::new();
        for i in 0..n {
            for j in 0..n {
                for k in 0..if dim == 3 { n } else { 1 } {
                    let jitter = 1e-4 * (((i * 7 + j * 13 + k * 29) % 11) as f64 / 11.0 - 0.5);
                    p.push([i as f64 * 1e-3 + jitter, j as f64 * 1e-3 - jitter, k as f64 * 1e-3 + 0.5 * jitter]);
                }
            }
        }
        p
    }

    #[test]
    fn an_affine_field_is_kept_exactly_at_the_walls_too() {
        // A confined sample's compaction: u = (0.1 ε x, −ε y) in 2D, u_z = −ε z
        // with a shear in 3D. A local linear fit reproduces an affine field
        // exactly (to rounding: 1e-12 of the moves, about 1e-18 m), at the
        // lattice's edges and corners as in its interior.
        for dim in [2, 3] {
            let p = lattice(if dim == 2 { 12 } else { 7 }, dim);
            let s = Smoothing::new(&bodies(&p), dim, 1.5e-3, &[]);
            let eps = 1e-3;
            let field = |x: &[f64; 3]| {
                if dim == 2 {
                    [0.1 * eps * x[0] + 2e-7, -eps * x[1] - 1e-7, 0.0]
                } else {
                    [0.2 * eps * x[2], 0.1 * eps * x[0], -eps * x[2] - 3e-7]
                }
            };
            let exact: Vec<f64> = p.iter().flat_map(field).collect();
            let mut moves = exact.clone();
            s.apply(&mut moves, 3, dim);
            for (b, (m, e)) in moves.iter().zip(&exact).enumerate() {
                assert!((m - e).abs() < 1e-17, "dim {dim}, body {}, coordinate {}: {m} vs {e}", b / 3, b % 3);
            }
        }
    }

    #[test]
    fn a_rattle_is_averaged_out() {
        // ±1 µm of checkerboard rattle on a uniform −5 µm settlement, 12 × 12
        // bodies 1 mm apart, ℓ = 1.5 mm: in the interior (3ℓ from the edges)
        // the fit of a sign alternating from one neighbour to the next keeps
        // below a tenth of the rattle (the Gaussian sum of an alternating
        // series at this ℓ is about 1e-3 of the plain sum).
        let p = lattice(12, 2);
        let s = Smoothing::new(&bodies(&p), 2, 1.5e-3, &[]);
        let rattle = |b: usize| if (b / 12 + b % 12).is_multiple_of(2) { 1e-6 } else { -1e-6 };
        let mut moves: Vec<f64> = (0..p.len()).flat_map(|b| [0.0, -5e-6 + rattle(b), 0.0]).collect();
        s.apply(&mut moves, 3, 2);
        for b in (0..p.len()).filter(|b| (5..7).contains(&(b / 12)) && (5..7).contains(&(b % 12))) {
            assert!((moves[b * 3 + 1] + 5e-6).abs() < 1e-7, "body {b}: {}", moves[b * 3 + 1]);
        }
    }

    #[test]
    fn bodies_on_a_line_take_the_weighted_mean() {
        // A neighbourhood on a line cannot fix a 2D gradient: the weighted mean,
        // exact for a uniform move; a coordinate past `dim` is left alone.
        let xs: Vec<f64> = (0..20).map(|i| i as f64 * 1e-3).collect();
        let s = Smoothing::new(&line(&xs), 2, 2e-3, &[]);
        let mut uniform: Vec<f64> = (0..20).flat_map(|_| [1e-6, -2e-6, 0.3]).collect();
        s.apply(&mut uniform, 3, 2);
        assert!(uniform.chunks(3).all(|m| (m[0] - 1e-6).abs() < 1e-18 && (m[1] + 2e-6).abs() < 1e-18 && m[2] == 0.3));
    }

    #[test]
    fn excluded_bodies_keep_their_move_and_weigh_nothing() {
        let s = Smoothing::new(&line(&[0.0, 1e-3, 2e-3]), 2, 1e-3, &[false, true, false]);
        let mut moves = vec![1.0, 0.0, 0.0, 100.0, 0.0, 0.0, 3.0, 0.0, 0.0];
        s.apply(&mut moves, 3, 2);
        assert_eq!(moves[3], 100.0);
        // Bodies 0 and 2 are 2 mm = 2ℓ apart: weight exp(−2) each way (two
        // bodies: a mean, not a fit).
        let w = (-2.0f64).exp();
        assert!((moves[0] - (1.0 + 3.0 * w) / (1.0 + w)).abs() < 1e-12);
        assert!((moves[6] - (3.0 + w) / (1.0 + w)).abs() < 1e-12);
    }
}
