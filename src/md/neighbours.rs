//! Verlet neighbour lists with a skin, built from a linked-cell grid: O(N).
//!
//! The list is a half list in compressed rows: row `i` (a real sphere) holds the
//! real spheres `j > i` and the symmetry images (ghosts, [`super::ghosts`]) whose
//! gap to `i` was below `skin` when the list was built. It is rebuilt only when
//! some sphere may have come within reach of one not listed: when the largest
//! displacement since the build plus the larger of that and the largest wall
//! displacement exceeds the skin. The contact memory ([`History`]) lives beside the
//! list, one record per listed pair, and is carried over to the new list at each
//! rebuild (rows sorted by a stable pair key, merged).

use super::contact::History;
use super::particles::V3;
use serde::{Deserialize, Serialize};

/// The grid has at most this many cells per sphere (plus [`MIN_CELLS`]): a
/// spread-out system (a sphere far away) gets larger cells, not more of them.
pub const MAX_CELLS_PER_SPHERE: usize = 8;
/// Cells the grid may always have (a 3 × 3 × 3 block).
pub const MIN_CELLS: usize = 27;

/// Cell size (m) and cells per axis of a grid over a box of extents `extent`
/// (m, each ≥ 0): cells of side `cell` (m) or larger, at most `max_cells` in
/// all (at least 1). The side grows by 1.5× until the count fits, counted in `f64` so that
/// no extent (up to infinite) overflows; an infinite extent gives one cell of
/// infinite side.
pub fn grid(extent: &V3, cell: f64, max_cells: usize) -> (f64, [usize; 3]) {
    let max_cells = max_cells.max(1);
    let span = extent.max();
    if !span.is_finite() {
        return (f64::INFINITY, [1; 3]);
    }
    let per_axis = |size: f64| extent.map(|e| (e / size).floor() + 1.0);
    // Start where one axis alone fits, then grow.
    let mut size = cell.max(span / max_cells as f64).max(f64::MIN_POSITIVE);
    let mut n = per_axis(size);
    while n.product() > max_cells as f64 {
        size *= 1.5;
        n = per_axis(size);
    }
    (size, [n[0] as usize, n[1] as usize, n[2] as usize])
}

/// The neighbour list and its per-pair contact memory.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct Neighbours {
    /// Skin (m): pairs with a gap below it are listed.
    pub skin: f64,
    /// Row starts, `n_real + 1` entries.
    pub start: Vec<u32>,
    /// Listed partner of each entry: a real sphere or a ghost (index ≥ `n_real`).
    pub j: Vec<u32>,
    /// Stable key of each entry: `mirror mask << 32 | original index`.
    pub key: Vec<u64>,
    /// Contact memory of each entry.
    pub hist: Vec<History>,
    /// Positions of the real spheres at the last build.
    pub x_build: Vec<V3>,
    /// Number of builds so far.
    pub builds: u64,
    #[serde(skip)]
    scratch: Scratch,
}

#[derive(Debug, Clone, Default)]
struct Scratch {
    cell_of: Vec<u32>,
    cell_start: Vec<u32>,
    fill: Vec<u32>,
    items: Vec<u32>,
    start: Vec<u32>,
    j: Vec<u32>,
    key: Vec<u64>,
    hist: Vec<History>,
    row: Vec<(u64, u32)>,
}

impl Neighbours {
    /// Copies `src` into `self`, reusing `self`'s buffers (no allocation once the sizes match): the backup of
    /// an MD step ([`crate::md::MdSystem`]). The destructuring names every field, so a field added to the
    /// struct does not compile until it is copied here too (a field forgotten would be a silent replay bug).
    /// The scratch buffers are not state (each build fills them before it reads them).
    pub(crate) fn copy_from(&mut self, src: &Neighbours) {
        let Neighbours { skin, start, j, key, hist, x_build, builds, scratch: _ } = src;
        self.skin = *skin;
        self.start.clone_from(start);
        self.j.clone_from(j);
        self.key.clone_from(key);
        self.hist.clone_from(hist);
        self.x_build.clone_from(x_build);
        self.builds = *builds;
    }

    /// An empty list with skin `skin` (m); call [`Neighbours::build`] before use.
    pub fn new(skin: f64) -> Self {
        Neighbours { skin, ..Default::default() }
    }

    /// Largest displacement of a real sphere since the last build (m).
    pub fn max_displacement(&self, x: &[V3]) -> f64 {
        if self.x_build.len() != x.len() {
            return f64::INFINITY;
        }
        x.iter().zip(&self.x_build).map(|(a, b)| (a - b).norm_squared()).fold(0.0, f64::max).sqrt()
    }

    /// Rebuilds the list over `x`/`r` (real spheres first, `n_real` of them, then
    /// ghosts with keys `ghost_key`), keeping the memory of pairs listed before.
    pub fn build(&mut self, x: &[V3], r: &[f64], n_real: usize, ghost_key: &[u64]) {
        let n_all = x.len();
        let s = &mut self.scratch;
        let r_max = r.iter().cloned().fold(0.0, f64::max);
        let cell = (2.0 * r_max + self.skin).max(1e-12);
        // Grid over the bounding box of the finite centres (a non-finite one, which
        // the step then reports, falls in a corner cell).
        let mut lo = V3::repeat(f64::INFINITY);
        let mut hi = V3::repeat(f64::NEG_INFINITY);
        for p in x.iter().filter(|p| p.iter().all(|c| c.is_finite())) {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
        if lo[0] > hi[0] {
            lo = V3::zeros();
            hi = V3::zeros();
        }
        let (size, dims) = grid(&(hi - lo), cell, MAX_CELLS_PER_SPHERE * n_all + MIN_CELLS);
        let n_cells = dims[0] * dims[1] * dims[2];
        let cell_index = |p: &V3| -> [usize; 3] {
            let mut c = [0usize; 3];
            for a in 0..3 {
                c[a] = (((p[a] - lo[a]) / size) as usize).min(dims[a] - 1);
            }
            c
        };
        s.cell_of.clear();
        s.cell_start.clear();
        s.cell_start.resize(n_cells + 1, 0);
        for p in x {
            let c = cell_index(p);
            let id = (c[2] * dims[1] + c[1]) * dims[0] + c[0];
            s.cell_of.push(id as u32);
            s.cell_start[id + 1] += 1;
        }
        for k in 0..n_cells {
            s.cell_start[k + 1] += s.cell_start[k];
        }
        s.items.clear();
        s.items.resize(n_all, 0);
        s.fill.clear();
        s.fill.extend_from_slice(&s.cell_start);
        for (i, &c) in s.cell_of.iter().enumerate() {
            s.items[s.fill[c as usize] as usize] = i as u32;
            s.fill[c as usize] += 1;
        }
        // Rows, each sorted by key, with the memory of the old list merged in.
        s.start.clear();
        s.j.clear();
        s.key.clear();
        s.hist.clear();
        s.start.push(0);
        let key_of = |j: usize| -> u64 {
            if j < n_real {
                j as u64
            } else {
                ghost_key[j - n_real]
            }
        };
        for i in 0..n_real {
            let c = cell_index(&x[i]);
            s.row.clear();
            for dz in -1i64..=1 {
                for dy in -1i64..=1 {
                    for dx in -1i64..=1 {
                        let (cx, cy, cz) = (c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz);
                        if cx < 0 || cy < 0 || cz < 0 {
                            continue;
                        }
                        let (cx, cy, cz) = (cx as usize, cy as usize, cz as usize);
                        if cx >= dims[0] || cy >= dims[1] || cz >= dims[2] {
                            continue;
                        }
                        let id = (cz * dims[1] + cy) * dims[0] + cx;
                        for &j in &s.items[s.cell_start[id] as usize..s.cell_start[id + 1] as usize] {
                            let j = j as usize;
                            if j < n_real && j <= i {
                                continue;
                            }
                            let reach = r[i] + r[j] + self.skin;
                            if (x[i] - x[j]).norm_squared() < reach * reach {
                                s.row.push((key_of(j), j as u32));
                            }
                        }
                    }
                }
            }
            s.row.sort_unstable();
            // Merge with the old row of i (also sorted by key).
            let (a, b) =
                if i + 1 < self.start.len() { (self.start[i] as usize, self.start[i + 1] as usize) } else { (0, 0) };
            let mut o = a;
            for &(k, j) in &s.row {
                while o < b && self.key[o] < k {
                    o += 1;
                }
                let h = if o < b && self.key[o] == k { self.hist[o] } else { History::default() };
                s.j.push(j);
                s.key.push(k);
                s.hist.push(h);
            }
            s.start.push(s.j.len() as u32);
        }
        std::mem::swap(&mut self.start, &mut s.start);
        std::mem::swap(&mut self.j, &mut s.j);
        std::mem::swap(&mut self.key, &mut s.key);
        std::mem::swap(&mut self.hist, &mut s.hist);
        self.x_build.clear();
        self.x_build.extend_from_slice(&x[..n_real]);
        self.builds += 1;
    }

    /// Number of listed pairs.
    pub fn pairs(&self) -> usize {
        self.j.len()
    }
}
