//! Broad phase: a uniform grid of cubic cells, the 3D form of the 2D engines' tile grid
//! ([`crate::plane::broad_phase`]; LMGC90's 3D modules also book bodies in boxes of a regular grid,
//! mod_PRPRx's `creation_tab_visu`). Each finite body is replaced by its bounding box, enlarged by the alert
//! distance, and booked in every cell that box covers; a pair is read in the cell holding the lowest corner
//! of the two boxes' intersection, so once. The cell side is the largest box of the ordinary bodies (those
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
}

impl Grid3 {
    /// Fills `pairs` with the index pairs `(i, j)`, `i < j`, whose boxes overlap, skipping those where
    /// `skip(i, j)`; the order is deterministic (cell by cell).
    pub fn pairs(&mut self, boxes: &[Aabb3], skip: impl Fn(usize, usize) -> bool, pairs: &mut Vec<(u32, u32)>) {
        pairs.clear();
        let n = boxes.len();
        if n < 2 {
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
        let at = |x: f64, d: usize| (((x - lo[d]) / cell).floor() as usize).min(dim[d] - 1);
        let index = |i: [usize; 3]| (i[2] * dim[1] + i[1]) * dim[0] + i[0];
        let range = |b: &Aabb3| -> [std::ops::RangeInclusive<usize>; 3] {
            std::array::from_fn(|d| at(b.min[d], d)..=at(b.max[d], d))
        };
        let each = |b: &Aabb3, f: &mut dyn FnMut(usize)| {
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
            each(b, &mut |c| self.cell_start[c + 1] += 1);
        }
        for c in 0..cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.entries.clear();
        self.entries.resize(self.cell_start[cells] as usize, 0);
        for (i, b) in boxes.iter().enumerate() {
            let (start, entries) = (&mut self.cell_start, &mut self.entries);
            each(b, &mut |c| {
                entries[start[c] as usize] = i as u32;
                start[c] += 1;
            });
        }
        for c in (1..=cells).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
        for c in 0..cells {
            let list = &self.entries[self.cell_start[c] as usize..self.cell_start[c + 1] as usize];
            for (k, &i) in list.iter().enumerate() {
                let bi = &boxes[i as usize];
                for &j in &list[k + 1..] {
                    let bj = &boxes[j as usize];
                    if !bi.overlaps(bj) {
                        continue;
                    }
                    let corner: [usize; 3] = std::array::from_fn(|d| at(bi.min[d].max(bj.min[d]), d));
                    if index(corner) != c {
                        continue;
                    }
                    let (a, b) = if i < j { (i, j) } else { (j, i) };
                    if !skip(a as usize, b as usize) {
                        pairs.push((a, b));
                    }
                }
            }
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
