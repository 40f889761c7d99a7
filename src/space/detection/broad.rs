//! Broad phase: a uniform grid of cubic cells, the 3D form of the 2D engines' tile grid
//! ([`crate::plane::broad_phase`]; LMGC90's 3D modules also book bodies in boxes of a regular grid,
//! mod_PRPRx's `creation_tab_visu`). Each finite body is replaced by its bounding box, enlarged by the alert
//! distance, and booked in every cell that box covers; then each box, in order, lists the higher boxes it
//! meets in those cells (each once, by a mark), sorted, so that the pairs come out sorted. The cell side is the largest box of the ordinary bodies (those
//! no larger than four times the median), so such a box covers at most 2 × 2 × 2 cells; the cell count is
//! capped at a few times the body count. Cost is linear in the number of bodies; all buffers are reused.

/// An axis-aligned box (m).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Aabb3 {
    /// Lowest corner.
    pub min: [f64; 3],
    /// Highest corner.
    pub max: [f64; 3],
}

impl Aabb3 {
    /// Whether the two closed boxes intersect.
    #[inline]
    pub fn overlaps(&self, o: &Aabb3) -> bool {
        (0..3).all(|d| self.min[d] <= o.max[d] && o.min[d] <= self.max[d])
    }
}

/// Grid of cells with compressed per-cell lists.
#[derive(Debug, Clone, Default)]
pub struct Grid3 {
    cell_start: Vec<u32>,
    entries: Vec<u32>,
    sizes: Vec<f64>,
    /// For each box, the last box whose neighbours listed it (to list each pair once).
    mark: Vec<u32>,
    /// The neighbours of one box, sorted before they are appended.
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
        if n < 2 {
            (0..n).for_each(|i| each(i as u32, &[]));
            return;
        }
        self.sizes.clear();
        self.sizes.extend(boxes.iter().map(|b| (0..3).map(|d| b.max[d] - b.min[d]).fold(0.0, f64::max)));
        let median = *self.sizes.select_nth_unstable_by(n / 2, |a, b| a.total_cmp(b)).1;
        let cell = self.sizes.iter().copied().filter(|&s| s <= 4.0 * median).fold(0.0, f64::max);
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for b in boxes {
            for d in 0..3 {
                lo[d] = lo[d].min(b.min[d]);
                hi[d] = hi[d].max(b.max[d]);
            }
        }
        let span = (0..3).map(|d| hi[d] - lo[d]).fold(0.0, f64::max);
        if !span.is_finite() {
            (0..n).for_each(|i| each(i as u32, &[]));
            return;
        }
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
        // `x ≥ lo`: the truncation is the floor.
        let at = |x: f64, d: usize| (((x - lo[d]) / cell) as usize).min(dim[d] - 1);
        let index = |i: [usize; 3]| (i[2] * dim[1] + i[1]) * dim[0] + i[0];
        let range = |b: &Aabb3| -> [std::ops::RangeInclusive<usize>; 3] {
            std::array::from_fn(|d| at(b.min[d], d)..=at(b.max[d], d))
        };
        let each_cell = |b: &Aabb3, f: &mut dyn FnMut(usize)| {
            let [rx, ry, rz] = range(b);
            for z in rz {
                for y in ry.clone() {
                    for x in rx.clone() {
                        f(index([x, y, z]));
                    }
                }
            }
        };
        // Counting sort of the (cell, body) bookings.
        self.cell_start.clear();
        self.cell_start.resize(cells + 1, 0);
        for b in boxes {
            each_cell(b, &mut |c| self.cell_start[c + 1] += 1);
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.entries.clear();
        self.entries.resize(self.cell_start[cells] as usize, 0);
        for (i, b) in boxes.iter().enumerate() {
            let (start, entries) = (&mut self.cell_start, &mut self.entries);
            each_cell(b, &mut |c| {
                entries[start[c] as usize] = i as u32;
                start[c] += 1;
            });
        }
        for c in (1..=cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
        // Each box's higher neighbours, from the cells it covers, each once.
        self.mark.clear();
        self.mark.resize(n, u32::MAX);
        let (cell_start, entries, mark, around) = (&self.cell_start, &self.entries, &mut self.mark, &mut self.around);
        for (i, bi) in boxes.iter().enumerate() {
            around.clear();
            each_cell(bi, &mut |c| {
                for &j in &entries[cell_start[c] as usize..cell_start[c + 1] as usize] {
                    if j as usize <= i || mark[j as usize] == i as u32 {
                        continue;
                    }
                    mark[j as usize] = i as u32;
                    if bi.overlaps(&boxes[j as usize]) && !skip(i, j as usize) {
                        around.push(j);
                    }
                }
            });
            around.sort_unstable();
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
}
