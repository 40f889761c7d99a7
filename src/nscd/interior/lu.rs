//! The Newton matrix of the interior-point solver, `K = M + Σ_springs c g gᵀ +
//! Σ_contacts Σ c f gᵀ` over the mobile velocity components, and its sparse LU
//! factorisation (faer's supernodal LU; one symbolic analysis per step, since the
//! contacts are fixed during a step).
//!
//! A component with a zero inverse mass (a fixed body, an imposed velocity) is no
//! unknown. Each row (contact or spring) couples the six components of its two
//! bodies: the pattern holds the full 6 × 6 block of every row, values are written
//! through precomputed slots. faer's LU does not report a zero pivot; `K` keeps `M`
//! on its diagonal, and a non-finite solution is reported as a failure.

#![allow(clippy::needless_range_loop)] // per-component loops over [x, y, θ] and the pairs read as the equations

use crate::nscd::contact::ContactRow;
use crate::nscd::sublayer::SpringRow;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, LuSymbolicParams, NumericLu, SymbolicLu};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

/// No unknown, or no second body (a world anchor).
const NONE: u32 = u32::MAX;

/// The six local coefficients of a row's direction: `h_a` on body `a`, `−h_b` on `b`.
#[inline(always)]
pub fn local(ha: &[f64; 3], hb: &[f64; 3]) -> [f64; 6] {
    [ha[0], ha[1], ha[2], -hb[0], -hb[1], -hb[2]]
}

/// The matrix, its pattern and its factorisation (buffers reused across steps).
#[derive(Default)]
pub struct NewtonMatrix {
    /// Per body and component, the index of the unknown, or `NONE`.
    dof: Vec<[u32; 3]>,
    /// Per unknown, its mass (kg or kg·m²).
    mass: Vec<f64>,
    diag: Vec<u32>,
    /// Per contact, then per spring: the slots of its 36 entries (row-major, local order).
    slots: Vec<[u32; 36]>,
    contacts: usize,
    pairs: Vec<(u32, u32)>,
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    symbolic: Option<SymbolicLu<u32>>,
    numeric: NumericLu<u32, f64>,
    mem: Option<MemBuffer>,
}

impl std::fmt::Debug for NewtonMatrix {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("NewtonMatrix").field("unknowns", &self.mass.len()).field("nnz", &self.values.len()).finish()
    }
}

impl NewtonMatrix {
    /// Numbers the unknowns, builds the pattern of every row and its symbolic LU;
    /// false if there is no unknown or the analysis fails.
    pub fn prepare(&mut self, inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        self.dof.clear();
        self.mass.clear();
        for im in inv_m {
            let mut ix = [NONE; 3];
            for d in 0..3 {
                if im[d] > 0.0 {
                    ix[d] = self.mass.len() as u32;
                    self.mass.push(1.0 / im[d]);
                }
            }
            self.dof.push(ix);
        }
        let n = self.mass.len();
        if n == 0 {
            return false;
        }
        let dof = &self.dof;
        let row_dofs = |a: u32, b: u32| {
            let mut l = [NONE; 6];
            l[..3].copy_from_slice(&dof[a as usize]);
            if b != NONE {
                l[3..].copy_from_slice(&dof[b as usize]);
            }
            l
        };
        let locals: Vec<[u32; 6]> =
            rows.iter().map(|r| row_dofs(r.a, r.b)).chain(springs.iter().map(|s| row_dofs(s.a, s.b))).collect();
        // (column, row) pairs of the full pattern, sorted and deduplicated.
        self.pairs.clear();
        self.pairs.extend((0..n as u32).map(|k| (k, k)));
        for l in &locals {
            for &i in l.iter().filter(|&&i| i != NONE) {
                for &j in l.iter().filter(|&&j| j != NONE) {
                    self.pairs.push((j, i));
                }
            }
        }
        self.pairs.sort_unstable();
        self.pairs.dedup();
        self.col_ptr.clear();
        self.col_ptr.resize(n + 1, 0);
        self.row_idx.clear();
        for &(c, r) in &self.pairs {
            self.col_ptr[c as usize + 1] += 1;
            self.row_idx.push(r);
        }
        for j in 0..n {
            self.col_ptr[j + 1] += self.col_ptr[j];
        }
        self.values.clear();
        self.values.resize(self.row_idx.len(), 0.0);
        let (col_ptr, row_idx) = (&self.col_ptr, &self.row_idx);
        let slot = |r: u32, c: u32| {
            let (lo, hi) = (col_ptr[c as usize] as usize, col_ptr[c as usize + 1] as usize);
            // Every pair of a row's unknowns is in the pattern by construction.
            lo as u32 + row_idx[lo..hi].binary_search(&r).unwrap_or(0) as u32
        };
        self.diag = (0..n as u32).map(|k| slot(k, k)).collect();
        self.slots.clear();
        for l in &locals {
            let mut out = [NONE; 36];
            for p in 0..6 {
                for q in 0..6 {
                    if l[p] != NONE && l[q] != NONE {
                        out[6 * p + q] = slot(l[p], l[q]);
                    }
                }
            }
            self.slots.push(out);
        }
        self.contacts = rows.len();
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        // The supernodal LU: faer's flop estimate picks the simplicial one on the
        // loaded 536-pentagon pile, 2.8× slower there (BENCHMARKS.md).
        let params = LuSymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            ..Default::default()
        };
        let Ok(symbolic) = factorize_symbolic_lu(sym, params) else {
            return false;
        };
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()),
            symbolic.solve_in_place_scratch::<f64>(1, Par::Seq),
        ]);
        self.mem = Some(MemBuffer::new(req));
        self.symbolic = Some(symbolic);
        true
    }

    /// The number of unknowns.
    pub fn len(&self) -> usize {
        self.mass.len()
    }

    /// True when there is no unknown (nothing to factorise).
    pub fn is_empty(&self) -> bool {
        self.mass.is_empty()
    }

    /// Starts a new assembly: `K = M`.
    pub fn reset(&mut self) {
        self.values.iter_mut().for_each(|x| *x = 0.0);
        for (k, &m) in self.mass.iter().enumerate() {
            self.values[self.diag[k] as usize] += m;
        }
    }

    /// Adds `c f gᵀ` (local coefficients) to contact `k`'s block.
    pub fn add_contact(&mut self, k: usize, f: &[f64; 6], g: &[f64; 6], c: f64) {
        add_full(&mut self.values, &self.slots[k], f, g, c);
    }

    /// Adds `c g gᵀ` to spring `k`'s block.
    pub fn add_spring(&mut self, k: usize, g: &[f64; 6], c: f64) {
        add_full(&mut self.values, &self.slots[self.contacts + k], g, g, c);
    }

    /// The numeric LU factorisation of the assembled values; false on a failure.
    pub fn factorize(&mut self) -> bool {
        let (Some(symbolic), Some(mem)) = (&self.symbolic, &mut self.mem) else { return false };
        let n = self.mass.len();
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(sym, &self.values);
        symbolic.factorize_numeric_lu(&mut self.numeric, a, Par::Seq, MemStack::new(mem), Default::default()).is_ok()
    }

    /// `x ← K⁻¹ x` with the last factorisation; false if the result is not finite.
    pub fn solve(&mut self, x: &mut [f64]) -> bool {
        let (Some(symbolic), Some(mem)) = (&self.symbolic, &mut self.mem) else { return false };
        let n = self.mass.len();
        // `numeric` is the output of `symbolic.factorize_numeric_lu` on this pattern,
        // as `new_unchecked` requires.
        let lu = LuRef::new_unchecked(symbolic, &self.numeric);
        lu.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(mem),
        );
        x.iter().all(|v| v.is_finite())
    }

    /// A body-form vector gathered into dof form.
    pub fn gather(&self, v: &[[f64; 3]], out: &mut [f64]) {
        for (i, ix) in self.dof.iter().enumerate() {
            for d in 0..3 {
                if ix[d] != NONE {
                    out[ix[d] as usize] = v[i][d];
                }
            }
        }
    }

    /// A dof vector scattered into body form (zero on the components that are no unknowns).
    pub fn scatter(&self, x: &[f64], out: &mut [[f64; 3]]) {
        for (i, ix) in self.dof.iter().enumerate() {
            for d in 0..3 {
                out[i][d] = if ix[d] != NONE { x[ix[d] as usize] } else { 0.0 };
            }
        }
    }
}

/// Adds `c f gᵀ` to the slots of a 6 × 6 block (`K[i][j] += c f_i g_j`).
#[inline(always)]
fn add_full(values: &mut [f64], slots: &[u32; 36], f: &[f64; 6], g: &[f64; 6], c: f64) {
    if c == 0.0 {
        return;
    }
    for p in 0..6 {
        for q in 0..6 {
            let s = slots[6 * p + q];
            if s != NONE {
                values[s as usize] += c * f[p] * g[q];
            }
        }
    }
}
