//! The velocity-space matrix `J = M + Σ_rows c G Gᵀ` of a step's NLGS problem, shared
//! by the finisher prototypes (`examples/newton_prototype.rs`,
//! `examples/correction_prototype.rs`, `examples/ipm_prototype.rs`; issue 31, `docs/finisher-design.md` §4 and §14).
//!
//! The unknowns are the mobile velocity components (a component with a zero inverse
//! mass is imposed and has none). Every contact row contributes `c_N g_N g_Nᵀ +
//! c_T g_T g_Tᵀ` and every spring `c g gᵀ`, `g` the row's six local coefficients
//! (`h_a` on body `a`, `−h_b` on body `b`), with coefficients the caller chooses per
//! factorisation (penalties, the spring's `h β`, or zero for a row left out). The
//! pattern holds every row, so one symbolic Cholesky analysis (faer, AMD) serves
//! every state of the contacts; values are written through precomputed slots.

#![allow(dead_code)] // each prototype uses a part

use ballast::nscd::contact::{dot3, ContactRow};
use ballast::nscd::sublayer::SpringRow;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky, SymmetricOrdering,
};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// No unknown, or no second body (a world anchor).
pub const NONE: u32 = u32::MAX;
/// Lower-triangle pairs `(p, q)`, `p ≤ q`, of a row's six local components.
pub const PAIRS: usize = 21;

/// The six local coefficients of a row's direction: `h_a` on body `a`, `−h_b` on `b`.
#[inline(always)]
pub fn local(ha: &[f64; 3], hb: &[f64; 3]) -> [f64; 6] {
    [ha[0], ha[1], ha[2], -hb[0], -hb[1], -hb[2]]
}

/// The relative velocity of a row, `h_a · v_a − h_b · v_b`.
#[inline(always)]
pub fn gather(v: &[[f64; 3]], a: u32, b: u32, ha: &[f64; 3], hb: &[f64; 3]) -> f64 {
    let mut x = dot3(ha, &v[a as usize]);
    if b != NONE {
        x -= dot3(hb, &v[b as usize]);
    }
    x
}

/// Adds `scale ∘ h_a p` to body `a` and subtracts `scale ∘ h_b p` from body `b`
/// (`scale` the inverse masses: an impulse's velocity change).
#[inline(always)]
pub fn scatter(out: &mut [[f64; 3]], scale: &[[f64; 3]], a: u32, b: u32, ha: &[f64; 3], hb: &[f64; 3], p: f64) {
    for d in 0..3 {
        out[a as usize][d] += scale[a as usize][d] * ha[d] * p;
    }
    if b != NONE {
        for d in 0..3 {
            out[b as usize][d] -= scale[b as usize][d] * hb[d] * p;
        }
    }
}

/// Adds the generalised force of impulse `p` along a row (`h_a p` on `a`, `−h_b p` on `b`).
#[inline(always)]
pub fn add_force(out: &mut [[f64; 3]], a: u32, b: u32, ha: &[f64; 3], hb: &[f64; 3], p: f64) {
    for d in 0..3 {
        out[a as usize][d] += ha[d] * p;
    }
    if b != NONE {
        for d in 0..3 {
            out[b as usize][d] -= hb[d] * p;
        }
    }
}

/// `u = u_free + M⁻¹ Σ H P` for the impulses stored in the rows.
pub fn rebuild(
    u: &mut [[f64; 3]],
    u_free: &[[f64; 3]],
    inv_m: &[[f64; 3]],
    rows: &[ContactRow],
    springs: &[SpringRow],
) {
    u.copy_from_slice(u_free);
    for s in springs {
        scatter(u, inv_m, s.a, s.b, &s.hn_a, &s.hn_b, s.p);
    }
    for r in rows {
        scatter(u, inv_m, r.a, r.b, &r.hn_a, &r.hn_b, r.p[0]);
        scatter(u, inv_m, r.a, r.b, &r.ht_a, &r.ht_b, r.p[1]);
    }
}

/// `u_free = u − M⁻¹ Σ H P`: the free velocity of a consistent pair.
pub fn free_velocity(u: &[[f64; 3]], inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> Vec<[f64; 3]> {
    let mut v = u.to_vec();
    for s in springs {
        scatter(&mut v, inv_m, s.a, s.b, &s.hn_a, &s.hn_b, -s.p);
    }
    for r in rows {
        scatter(&mut v, inv_m, r.a, r.b, &r.hn_a, &r.hn_b, -r.p[0]);
        scatter(&mut v, inv_m, r.a, r.b, &r.ht_a, &r.ht_b, -r.p[1]);
    }
    v
}

/// Numbers the mobile velocity components: per body the unknown of each
/// component (`NONE` where the inverse mass is zero), and each unknown's mass.
fn number(inv_m: &[[f64; 3]]) -> (Vec<[u32; 3]>, Vec<f64>) {
    let (mut dof, mut mass) = (Vec::with_capacity(inv_m.len()), Vec::new());
    for im in inv_m {
        let mut ix = [NONE; 3];
        for d in 0..3 {
            if im[d] > 0.0 {
                ix[d] = mass.len() as u32;
                mass.push(1.0 / im[d]);
            }
        }
        dof.push(ix);
    }
    (dof, mass)
}

/// The unknowns of a row's six local components (bodies `a` and `b`).
fn row_dofs(dof: &[[u32; 3]], a: u32, b: u32) -> [u32; 6] {
    let mut l = [NONE; 6];
    l[..3].copy_from_slice(&dof[a as usize]);
    if b != NONE {
        l[3..].copy_from_slice(&dof[b as usize]);
    }
    l
}

/// The CSC pattern of `n` columns from `(column, row)` pairs (sorted, deduplicated here).
fn csc(n: usize, pairs: &mut Vec<(u32, u32)>) -> (Vec<u32>, Vec<u32>) {
    pairs.sort_unstable();
    pairs.dedup();
    let mut col_ptr = vec![0u32; n + 1];
    let mut row_idx = Vec::with_capacity(pairs.len());
    for &(c, r) in pairs.iter() {
        col_ptr[c as usize + 1] += 1;
        row_idx.push(r);
    }
    for j in 0..n {
        col_ptr[j + 1] += col_ptr[j];
    }
    (col_ptr, row_idx)
}

/// The slot of entry (row `r`, column `c`) in a CSC pattern.
fn slot(col_ptr: &[u32], row_idx: &[u32], r: u32, c: u32) -> u32 {
    let (lo, hi) = (col_ptr[c as usize] as usize, col_ptr[c as usize + 1] as usize);
    lo as u32 + row_idx[lo..hi].binary_search(&r).expect("pattern holds every pair") as u32
}

fn push_pairs(pairs: &mut Vec<(u32, u32)>, l: &[u32; 6]) {
    for p in 0..6 {
        for q in p..6 {
            let (i, j) = (l[p], l[q]);
            if i != NONE && j != NONE && i != j {
                pairs.push((i.min(j), i.max(j)));
            }
        }
    }
}

/// Adds `cn gn gnᵀ + ct gt gtᵀ` to the lower-triangle slots of a row's block.
#[inline(always)]
fn add_block(values: &mut [f64], slots: &[u32; PAIRS], gn: &[f64; 6], cn: f64, gt: &[f64; 6], ct: f64) {
    let mut k = 0;
    for p in 0..6 {
        for q in p..6 {
            if slots[k] != NONE {
                values[slots[k] as usize] += cn * gn[p] * gn[q] + ct * gt[p] * gt[q];
            }
            k += 1;
        }
    }
}

/// The pattern, values and Cholesky factor of `J`.
#[derive(Default)]
pub struct Jacobian {
    /// Per body and component, the index of the unknown, or `NONE`.
    pub dof: Vec<[u32; 3]>,
    /// Per unknown: its mass (kg or kg·m²).
    pub mass: Vec<f64>,
    diag: Vec<u32>,
    /// Per contact: the unknowns of its six local components and the slots of its 21 pairs.
    cdof: Vec<[u32; 6]>,
    cslot: Vec<[u32; PAIRS]>,
    sdof: Vec<[u32; 6]>,
    sslot: Vec<[u32; PAIRS]>,
    /// Lower-triangle pattern (CSC) of `J` and its values.
    col_ptr: Vec<u32>,
    row_idx: Vec<u32>,
    values: Vec<f64>,
    pairs: Vec<(u32, u32)>,
    symbolic: Option<SymbolicCholesky<u32>>,
    l_values: Vec<f64>,
    mem: Option<MemBuffer>,
}

impl Jacobian {
    /// Numbers the unknowns, builds the pattern of every row and its symbolic
    /// Cholesky factorisation; false if there is no unknown or the analysis fails.
    pub fn prepare(&mut self, inv_m: &[[f64; 3]], rows: &[ContactRow], springs: &[SpringRow]) -> bool {
        (self.dof, self.mass) = number(inv_m);
        let n = self.mass.len();
        if n == 0 {
            return false;
        }
        self.pairs.clear();
        self.pairs.extend((0..n as u32).map(|k| (k, k)));
        self.cdof = rows.iter().map(|r| row_dofs(&self.dof, r.a, r.b)).collect();
        self.sdof = springs.iter().map(|s| row_dofs(&self.dof, s.a, s.b)).collect();
        for l in self.cdof.iter().chain(&self.sdof) {
            push_pairs(&mut self.pairs, l);
        }
        // (column, row) with row ≥ column.
        (self.col_ptr, self.row_idx) = csc(n, &mut self.pairs);
        self.values.clear();
        self.values.resize(self.row_idx.len(), 0.0);
        // The lower triangle: (i, j) is stored as (max, min).
        let slot = |col_ptr: &[u32], row_idx: &[u32], i: u32, j: u32| slot(col_ptr, row_idx, i.max(j), i.min(j));
        self.diag.clear();
        for k in 0..n as u32 {
            self.diag.push(slot(&self.col_ptr, &self.row_idx, k, k));
        }
        let slots = |l: &[u32; 6], col_ptr: &[u32], row_idx: &[u32]| {
            let mut out = [NONE; PAIRS];
            let mut k = 0;
            for p in 0..6 {
                for q in p..6 {
                    if l[p] != NONE && l[q] != NONE {
                        out[k] = slot(col_ptr, row_idx, l[p], l[q]);
                    }
                    k += 1;
                }
            }
            out
        };
        self.cslot.clear();
        for l in &self.cdof {
            self.cslot.push(slots(l, &self.col_ptr, &self.row_idx));
        }
        self.sslot.clear();
        for l in &self.sdof {
            self.sslot.push(slots(l, &self.col_ptr, &self.row_idx));
        }
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let Ok(symbolic) =
            factorize_symbolic_cholesky(sym, Side::Lower, SymmetricOrdering::Amd, CholeskySymbolicParams::default())
        else {
            return false;
        };
        self.l_values.clear();
        self.l_values.resize(symbolic.len_val(), 0.0);
        let req = StackReq::any_of(&[
            symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()),
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

    /// Starts a new assembly: `J = M`.
    pub fn reset(&mut self) {
        self.values.iter_mut().for_each(|x| *x = 0.0);
        for (k, &m) in self.mass.iter().enumerate() {
            self.values[self.diag[k] as usize] += m;
        }
    }

    /// Adds `cn g_N g_Nᵀ + ct g_T g_Tᵀ` of contact `k`.
    pub fn add_contact(&mut self, k: usize, r: &ContactRow, cn: f64, ct: f64) {
        if cn != 0.0 || ct != 0.0 {
            add_block(&mut self.values, &self.cslot[k], &local(&r.hn_a, &r.hn_b), cn, &local(&r.ht_a, &r.ht_b), ct);
        }
    }

    /// Adds `c1 f1 f1ᵀ + c2 f2 f2ᵀ` on contact `k`'s block, `f1`, `f2` any two directions in
    /// the row's six local components (the interior-point prototype's `g_N ± μ g_T`).
    pub fn add_contact_dirs(&mut self, k: usize, f1: &[f64; 6], c1: f64, f2: &[f64; 6], c2: f64) {
        add_block(&mut self.values, &self.cslot[k], f1, c1, f2, c2);
    }

    /// Adds `c g gᵀ` of spring `k`.
    pub fn add_spring(&mut self, k: usize, s: &SpringRow, c: f64) {
        if c != 0.0 {
            add_block(&mut self.values, &self.sslot[k], &local(&s.hn_a, &s.hn_b), c, &[0.0; 6], 0.0);
        }
    }

    /// The numeric Cholesky factorisation of the assembled values; false on a failure.
    pub fn factorize(&mut self) -> bool {
        let (Some(symbolic), Some(mem)) = (&self.symbolic, &mut self.mem) else { return false };
        let n = self.mass.len();
        let sym = SymbolicSparseColMatRef::new_checked(n, n, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(sym, &self.values);
        symbolic
            .factorize_numeric_llt::<f64>(
                &mut self.l_values,
                a,
                Side::Lower,
                Default::default(),
                Par::Seq,
                MemStack::new(mem),
                Default::default(),
            )
            .is_ok()
    }

    /// `x ← J⁻¹ x` with the last factor; false if the result is not finite.
    pub fn solve(&mut self, x: &mut [f64]) -> bool {
        let (Some(symbolic), Some(mem)) = (&self.symbolic, &mut self.mem) else { return false };
        let n = self.mass.len();
        let llt = LltRef::new(symbolic, &self.l_values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(mem),
        );
        x.iter().all(|v| v.is_finite())
    }

    /// Writes a dof vector in body form (zero on imposed components).
    pub fn scatter_dofs(&self, x: &[f64], out: &mut [[f64; 3]]) {
        for (i, ix) in self.dof.iter().enumerate() {
            for d in 0..3 {
                out[i][d] = if ix[d] != NONE { x[ix[d] as usize] } else { 0.0 };
            }
        }
    }

    /// Gathers a body-form vector into dof form.
    pub fn gather_dofs(&self, v: &[[f64; 3]], out: &mut [f64]) {
        for (i, ix) in self.dof.iter().enumerate() {
            for d in 0..3 {
                if ix[d] != NONE {
                    out[ix[d] as usize] = v[i][d];
                }
            }
        }
    }
}

/// The same unknowns with a general (non-symmetric) matrix `J = M + Σ c f gᵀ`, `f`
/// the direction an impulse acts along and `g` the constraint's (a sliding contact's
/// impulse acts along `g_N ± μ g_T` while its constraint is `g_N`): the library's
/// Newton matrix of the interior-point solver (faer's supernodal sparse LU, one
/// symbolic analysis per problem; `correction_prototype`'s measurement of an LU at
/// about 20× a Cholesky was made with faer's own choice, the simplicial LU).
#[allow(unused_imports)] // newton_prototype uses the Cholesky matrix only
pub use ballast::nscd::interior::lu::NewtonMatrix as LuJacobian;
