//! Predetection on a grid of rectangular tiles (Saussine et al. 2006, §2.3):
//! each body is replaced by its bounding box, enlarged by the alert distance, and
//! booked in every tile that box covers. Pairs are read tile by tile; a pair whose
//! boxes share several tiles is reported once, by the tile holding the lower-left
//! corner of the boxes' intersection. Cost is linear in the number of bodies.
//!
//! The tile side is the largest box of the "ordinary" bodies (walls and other
//! bodies much larger than the median are booked in all their tiles), so a body
//! touches at most four tiles. All buffers are reused from step to step.

/// An axis-aligned box `[min, max]` (m).
#[derive(Debug, Clone, Copy, Default)]
pub struct Aabb {
    /// Lower-left corner `(x_min, y_min)` (m).
    pub min: [f64; 2],
    /// Upper-right corner `(x_max, y_max)` (m).
    pub max: [f64; 2],
}

impl Aabb {
    /// Whether the two boxes intersect (closed boxes: touching counts).
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min[0] <= o.max[0] && o.min[0] <= self.max[0] && self.min[1] <= o.max[1] && o.min[1] <= self.max[1]
    }
}

/// Grid of tiles with compressed per-tile body lists.
#[derive(Debug, Clone, Default)]
pub struct Grid {
    cell_start: Vec<u32>,
    entries: Vec<u32>,
    sizes: Vec<f64>,
}

impl Grid {
    /// Fills `pairs` with the index pairs `(i, j)`, `i < j`, whose boxes overlap,
    /// skipping pairs where `skip(i, j)` is true. Pairs come out in a deterministic order.
    pub fn pairs(&mut self, boxes: &[Aabb], skip: impl Fn(usize, usize) -> bool, pairs: &mut Vec<(u32, u32)>) {
        pairs.clear();
        let n = boxes.len();
        if n < 2 {
            return;
        }
        // Tile side: the largest box among bodies no larger than 4× the median size.
        self.sizes.clear();
        self.sizes.extend(boxes.iter().map(|b| (b.max[0] - b.min[0]).max(b.max[1] - b.min[1])));
        let mut sorted = std::mem::take(&mut self.sizes);
        let mid = n / 2;
        let median = *sorted.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1;
        let cell = sorted.iter().copied().filter(|&s| s <= 4.0 * median).fold(0.0, f64::max);
        self.sizes = sorted;
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for b in boxes {
            for d in 0..2 {
                lo[d] = lo[d].min(b.min[d]);
                hi[d] = hi[d].max(b.max[d]);
            }
        }
        // Keep the tile count within a few times the body count. Extents are finite
        // (the stepper checks q_m first); the tile count is capped so that a very
        // spread-out system degrades to larger tiles, never to an overflow.
        let span = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        if !span.is_finite() {
            return;
        }
        let mut cell = cell.max(span / (4 * n + 64) as f64).max(f64::MIN_POSITIVE);
        let dims = |c: f64| {
            (
                (((hi[0] - lo[0]) / c).floor() as usize).saturating_add(1),
                (((hi[1] - lo[1]) / c).floor() as usize).saturating_add(1),
            )
        };
        let (mut nx, mut ny) = dims(cell);
        while nx.saturating_mul(ny) > 4 * n + 64 {
            cell *= 1.5;
            (nx, ny) = dims(cell);
        }
        let tile = |x: f64, d: usize| (((x - lo[d]) / cell).floor() as usize).min(if d == 0 { nx - 1 } else { ny - 1 });
        // Counting sort of (tile, body) bookings.
        self.cell_start.clear();
        self.cell_start.resize(nx * ny + 1, 0);
        for b in boxes {
            for iy in tile(b.min[1], 1)..=tile(b.max[1], 1) {
                for ix in tile(b.min[0], 0)..=tile(b.max[0], 0) {
                    self.cell_start[iy * nx + ix + 1] += 1;
                }
            }
        }
        for c in 0..nx * ny {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.entries.clear();
        self.entries.resize(self.cell_start[nx * ny] as usize, 0);
        // Fill; cell_start[c] temporarily advances as a cursor and is restored below.
        for (i, b) in boxes.iter().enumerate() {
            for iy in tile(b.min[1], 1)..=tile(b.max[1], 1) {
                for ix in tile(b.min[0], 0)..=tile(b.max[0], 0) {
                    let c = iy * nx + ix;
                    self.entries[self.cell_start[c] as usize] = i as u32;
                    self.cell_start[c] += 1;
                }
            }
        }
        for c in (1..=nx * ny).rev() {
            self.cell_start[c] = self.cell_start[c - 1];
        }
        self.cell_start[0] = 0;
        for iy in 0..ny {
            for ix in 0..nx {
                let c = iy * nx + ix;
                let list = &self.entries[self.cell_start[c] as usize..self.cell_start[c + 1] as usize];
                for (k, &i) in list.iter().enumerate() {
                    let bi = &boxes[i as usize];
                    for &j in &list[k + 1..] {
                        let bj = &boxes[j as usize];
                        if !bi.overlaps(bj) {
                            continue;
                        }
                        // Report the pair only in the tile of the intersection's lower-left corner.
                        let cx = bi.min[0].max(bj.min[0]);
                        let cy = bi.min[1].max(bj.min[1]);
                        if tile(cx, 0) != ix || tile(cy, 1) != iy {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The grid must report exactly the overlapping pairs that an all-pairs test finds.
    #[test]
    fn grid_matches_brute_force() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut boxes: Vec<Aabb> = (0..400)
            .map(|_| {
                let (x, y, r) = (rnd() * 10.0, rnd() * 10.0, 0.1 + 0.2 * rnd());
                Aabb { min: [x - r, y - r], max: [x + r, y + r] }
            })
            .collect();
        boxes.push(Aabb { min: [-1.0, -1.0], max: [11.0, 0.5] }); // a wall
        let mut grid = Grid::default();
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
        pairs.sort();
        assert_eq!(pairs, brute);
    }
}
