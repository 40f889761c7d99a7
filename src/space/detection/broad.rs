//! Broad phase: a uniform grid of cubic cells, the 3D form of the 2D engines' tile grid
//! ([`crate::plane::broad_phase`]; LMGC90's 3D modules also book bodies in boxes of a regular grid,
//! mod_PRPRx's `creation_tab_visu`). Each finite body is replaced by its bounding box, enlarged by the alert
//! distance. The cell side is the largest box of the ordinary bodies (those no larger than four times the
//! median; the cell count is capped at a few times the body count); each box no larger than a cell is booked
//! in the cell of its lowest corner, so that a box meeting box `i` is booked between the cells of
//! `min_i − cell` and `max_i`, a few cells per axis; larger boxes are tested against every box. Each box,
//! in order, lists the higher boxes it meets, sorted, so the pairs come out sorted. Cost is linear in the
//! number of bodies (and in the number of large ones times that); all buffers are reused.

/// An axis-aligned box (m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Aabb3 {
    /// Lowest corner.
    pub min: [f64; 3],
    /// Highest corner.
    pub max: [f64; 3],
}

impl Aabb3 {
    /// Whether `o` lies in this box (closed).
    #[inline]
    pub fn contains(&self, o: &Aabb3) -> bool {
        (self.min[0] <= o.min[0])
            & (o.max[0] <= self.max[0])
            & (self.min[1] <= o.min[1])
            & (o.max[1] <= self.max[1])
            & (self.min[2] <= o.min[2])
            & (o.max[2] <= self.max[2])
    }

    /// Whether the two closed boxes intersect.
    #[inline]
    pub fn overlaps(&self, o: &Aabb3) -> bool {
        // Without branches: the six comparisons are cheaper than mispredicting them.
        (self.min[0] <= o.max[0])
            & (o.min[0] <= self.max[0])
            & (self.min[1] <= o.max[1])
            & (o.min[1] <= self.max[1])
            & (self.min[2] <= o.max[2])
            & (o.min[2] <= self.max[2])
    }
}

/// Grid of cells with compressed per-cell lists.
#[derive(Debug, Clone, Default)]
pub struct Grid3 {
    cell_start: Vec<u32>,
    entries: Vec<u32>,
    sizes: Vec<f64>,
    /// The boxes larger than a cell.
    large: Vec<u32>,
    /// The higher neighbours of one box, sorted before they are given.
    around: Vec<u32>,
}

impl Grid3 {
    /// Fills `pairs` with the index pairs `(i, j)`, `i < j`, whose boxes overlap, skipping those where
    /// `skip(i, j)`, sorted.
    pub fn pairs(&mut self, boxes: &[Aabb3], skip: impl Fn(usize, usize) -> bool, pairs: &mut Vec<(u32, u32)>) {
        pairs.clear();
        self.pairs_with(boxes, skip, |i, around| pairs.extend(around.iter().map(|&j| (i, j))));
    }

    /// [`Self::pairs`], each box's sorted list of the higher boxes it meets given to `each(i, list)` in the
    /// order of the boxes (every box, lists empty or not).
    pub(crate) fn pairs_with(
        &mut self,
        boxes: &[Aabb3],
        skip: impl Fn(usize, usize) -> bool,
        mut each: impl FnMut(u32, &[u32]),
    ) {
        let n = boxes.len();
        let size = |b: &Aabb3| (0..3).map(|d| b.max[d] - b.min[d]).fold(0.0, f64::max);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for b in boxes {
            for d in 0..3 {
                lo[d] = lo[d].min(b.min[d]);
                hi[d] = hi[d].max(b.max[d]);
            }
        }
        let span = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
        if n < 2 || !span.is_finite() {
            // Nothing to pair (or a box not finite: it meets nothing).
            (0..n).for_each(|i| each(i as u32, &[]));
            return;
        }
        self.sizes.clear();
        self.sizes.extend(boxes.iter().map(size));
        let median = *self.sizes.select_nth_unstable_by(n / 2, |a, b| a.total_cmp(b)).1;
        let cell = self.sizes.iter().copied().filter(|&s| s <= 4.0 * median).fold(0.0, f64::max);
        let limit = 4 * n + 64;
        let mut cell = cell.max(span / limit as f64).max(f64::MIN_POSITIVE);
        let dims = |c: f64| -> [usize; 3] {
            std::array::from_fn(|d| (((hi[d] - lo[d]) / c).floor() as usize).saturating_add(1))
        };
        let mut dim = dims(cell);
        while dim[0].saturating_mul(dim[1]).saturating_mul(dim[2]) > limit {
            cell *= 1.5;
            dim = dims(cell);
        }
        let cells = dim[0] * dim[1] * dim[2];
        // The cell of `x` along axis `d` (below `lo`, the first: the cast of a negative number is 0).
        let at = |x: f64, d: usize| (((x - lo[d]) / cell) as usize).min(dim[d] - 1);
        let index = |x: usize, y: usize, z: usize| (z * dim[1] + y) * dim[0] + x;
        let corner = |b: &Aabb3| index(at(b.min[0], 0), at(b.min[1], 1), at(b.min[2], 2));
        // Counting sort of the ordinary boxes by the cell of their lowest corner.
        self.large.clear();
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        for (i, b) in boxes.iter().enumerate() {
            if size(b) <= cell {
                self.cell_start[corner(b) + 1] += 1;
            } else {
                self.large.push(i as u32);
            }
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.entries.clear();
        self.entries.resize(self.cell_start[cells] as usize, 0);
        for (i, b) in boxes.iter().enumerate() {
            if size(b) <= cell {
                let c = &mut self.cell_start[corner(b)];
                self.entries[*c as usize] = i as u32;
                *c += 1;
            }
        }
        for c in (1..=cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
        // A box no larger than a cell that meets box i has its lowest corner above `min_i − cell` (made a
        // little lower against the rounding of the sizes) and below `max_i`.
        let reach = cell * (1.0 + 1e-9);
        let (cell_start, entries, large, around) = (&self.cell_start, &self.entries, &self.large, &mut self.around);
        // Each candidate is written, and kept (the length moved on) when it is a pair: no branch to
        // mispredict on whether boxes meet.
        let scan = |i: usize, js: &[u32], bi: &Aabb3, around: &mut Vec<u32>| {
            let mut len = around.len();
            around.resize(len + js.len(), 0);
            for &j in js {
                around[len] = j;
                let keep = (j as usize > i) & bi.overlaps(&boxes[j as usize]) & !skip(i, j as usize);
                len += usize::from(keep);
            }
            around.truncate(len);
        };
        let mut next_large = 0;
        for (i, bi) in boxes.iter().enumerate() {
            around.clear();
            if large.get(next_large) == Some(&(i as u32)) {
                next_large += 1;
                for (j, bj) in boxes.iter().enumerate().skip(i + 1) {
                    if bi.overlaps(bj) && !skip(i, j) {
                        around.push(j as u32);
                    }
                }
            } else {
                let r: [_; 3] = std::array::from_fn(|d| (at(bi.min[d] - reach, d), at(bi.max[d], d)));
                for z in r[2].0..=r[2].1 {
                    for y in r[1].0..=r[1].1 {
                        let row =
                            cell_start[index(r[0].0, y, z)] as usize..cell_start[index(r[0].1, y, z) + 1] as usize;
                        scan(i, &entries[row], bi, around);
                    }
                }
                scan(i, large, bi, around);
                around.sort_unstable();
            }
            each(i as u32, around);
        }
    }
}

/// The grid's pairs kept from call to call, as a Verlet list: the grid is run on the boxes enlarged by a
/// margin, and while every box stays inside its enlarged box of that run, two boxes that meet have enlarged
/// boxes that met then (the comparisons chain: `hull_i.min ≤ box_i.min ≤ box_j.max ≤ hull_j.max`), so the
/// pairs are those of the list whose boxes meet now: the same pairs as the grid's, found by a pass over
/// the list instead of a grid. A box leaving its enlarged box, or a change in the number of boxes, runs
/// the grid again.
#[derive(Debug, Clone, Default)]
pub struct Broad3 {
    grid: Grid3,
    /// The boxes of the last grid run, enlarged by the margin.
    hulls: Vec<Aabb3>,
    /// Each box's higher neighbours by the hulls: `near[start[i]..start[i + 1]]`, sorted.
    start: Vec<u32>,
    near: Vec<u32>,
    around: Vec<u32>,
    /// Calls and grid runs so far.
    calls: u64,
    builds: u64,
}

impl Broad3 {
    /// Calls to [`Self::pairs_with`] so far, and how many ran the grid.
    pub fn builds(&self) -> (u64, u64) {
        (self.calls, self.builds)
    }

    /// As `Grid3::pairs_with` (the same lists), the grid run only when a box has left the box it had at
    /// the last run enlarged by `margin` (m, on every side; the margin of a new run).
    pub fn pairs_with(
        &mut self,
        boxes: &[Aabb3],
        margin: f64,
        skip: impl Fn(usize, usize) -> bool,
        mut each: impl FnMut(u32, &[u32]),
    ) {
        self.calls += 1;
        let inside = self.hulls.len() == boxes.len() && boxes.iter().zip(&self.hulls).all(|(b, h)| h.contains(b));
        if !inside {
            self.builds += 1;
            let m = if margin.is_finite() { margin.max(0.0) } else { 0.0 };
            self.hulls.clear();
            self.hulls.extend(boxes.iter().map(|b| Aabb3 { min: b.min.map(|x| x - m), max: b.max.map(|x| x + m) }));
            let Broad3 { grid, hulls, start, near, .. } = self;
            start.clear();
            near.clear();
            grid.pairs_with(
                hulls,
                |_, _| false,
                |_, list| {
                    start.push(near.len() as u32);
                    near.extend_from_slice(list);
                },
            );
            start.push(near.len() as u32);
        }
        let Broad3 { start, near, around, .. } = self;
        for (i, bi) in boxes.iter().enumerate() {
            let list = &near[start[i] as usize..start[i + 1] as usize];
            // As in the grid's scan: every candidate written, the length moved on for a pair.
            around.clear();
            around.resize(list.len(), 0);
            let mut len = 0;
            for &j in list {
                around[len] = j;
                len += usize::from(bi.overlaps(&boxes[j as usize]) & !skip(i, j as usize));
            }
            around.truncate(len);
            each(i as u32, around);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid reports exactly the overlapping pairs an all-pairs test finds.
    #[test]
    fn grid_matches_brute_force() {
        let mut seed = 987654321u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes: Vec<Aabb3> = (0..500)
            .map(|_| {
                let c = [rnd() * 5.0, rnd() * 5.0, rnd() * 5.0];
                let r = 0.1 + 0.3 * rnd();
                Aabb3 { min: c.map(|x| x - r), max: c.map(|x| x + r) }
            })
            .collect();
        boxes.push(Aabb3 { min: [-1.0, -1.0, -1.0], max: [6.0, 6.0, 0.2] }); // a large fixed body
        let mut grid = Grid3::default();
        let mut pairs = Vec::new();
        grid.pairs(&boxes, |_, _| false, &mut pairs);
        let mut brute = Vec::new();
        for i in 0..boxes.len() {
            for j in i + 1..boxes.len() {
                if boxes[i].overlaps(&boxes[j]) {
                    brute.push((i as u32, j as u32));
                }
            }
        }
        pairs.sort_unstable();
        assert_eq!(pairs, brute);
    }

    /// The Verlet list gives the grid's pairs, whether it runs the grid again or keeps its list while the
    /// boxes move a little, with a skip rule applied at each call.
    #[test]
    fn verlet_list_matches_the_grid() {
        let mut seed = 123456789u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes: Vec<Aabb3> = (0..400)
            .map(|_| {
                let c = [rnd() * 5.0, rnd() * 5.0, rnd() * 5.0];
                let r = 0.1 + 0.3 * rnd();
                Aabb3 { min: c.map(|x| x - r), max: c.map(|x| x + r) }
            })
            .collect();
        boxes.push(Aabb3 { min: [-1.0, -1.0, -1.0], max: [6.0, 6.0, 0.2] });
        let (mut grid, mut broad, mut pairs) = (Grid3::default(), Broad3::default(), Vec::new());
        for step in 0..12 {
            let skip = |i: usize, j: usize| (i + j + step).is_multiple_of(7);
            let mut kept = Vec::new();
            broad.pairs_with(&boxes, 0.05, skip, |i, list| kept.extend(list.iter().map(|&j| (i, j))));
            grid.pairs(&boxes, skip, &mut pairs);
            assert_eq!(kept, pairs, "step {step}");
            for b in &mut boxes {
                let shift = [0.0; 3].map(|_: f64| 0.02 * (rnd() - 0.5));
                for (d, s) in shift.iter().enumerate() {
                    b.min[d] += s;
                    b.max[d] += s;
                }
            }
        }
        let (calls, builds) = broad.builds();
        assert!(calls == 12 && builds > 1 && builds < 12, "{calls} calls, {builds} grid runs");
    }
}
