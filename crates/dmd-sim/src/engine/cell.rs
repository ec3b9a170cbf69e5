//! The cell list: the box cut into cells no thinner than the interaction reach, so that a body
//! can only interact with bodies in its own and the 26 adjacent cells (000 §III.B).
//!
//! Along an axis with three cells or more the 27 cells around a body are distinct. A box
//! between two and three reaches wide gets two cells along that axis: the cell below and the
//! cell above are then the same cell, visited twice with shifts one box length apart. At most
//! one of the two images of a body lies within the reach (the box is at least two reaches
//! wide), so a scan that keeps only partners within the reach, as every neighbour-list scan
//! does, finds each pair once; a scan that does not look at distances must visit each cell
//! once ([`CellGrid::for_each_distinct_neighbour_cell`]).
//!
//! Bodies move between cells only at cell-crossing events, whose times come analytically from
//! the linear motion of the centre. A cell's bodies are kept in a fixed-stride slot array (one
//! contiguous run of `cap` slots per cell, `cap` doubling when some cell overflows), so that
//! scanning a neighbourhood reads a few short contiguous runs instead of chasing a linked list.
//!
//! Cell coordinates are packed into one `u32` per body (10 bits per axis, at most 1023 cells
//! along an axis; larger boxes simply get larger cells).
//!
//! The number of cells is also bounded by the number of bodies ([`max_cells`]: at most
//! `max(27, 2N)`), so that memory follows N and not the box: a dilute box, or a tiny
//! interaction reach, gets cells wider than the reach (always correct, as a cell only has to
//! be at least the reach wide) instead of billions of empty ones.

use glam::DVec3;

/// Most cells along one axis (the packed coordinates have 10 bits each).
pub const MAX_CELLS_PER_AXIS: u32 = 1023;

/// Most cells for `n_bodies` bodies: `max(27, 2N)`. A dense fluid has far fewer (about one
/// cell per 3–10 bodies), so the bound only binds in dilute boxes, where it keeps the grid at
/// about two cells per body and so its memory proportional to N.
pub fn max_cells(n_bodies: usize) -> u64 {
    (2 * n_bodies as u64).max(27)
}

/// Packs cell coordinates into one `u32`.
#[inline(always)]
pub fn pack(c: [u32; 3]) -> u32 {
    c[0] | (c[1] << 10) | (c[2] << 20)
}

/// Unpacks cell coordinates.
#[inline(always)]
pub fn unpack(p: u32) -> [u32; 3] {
    [p & 1023, (p >> 10) & 1023, p >> 20]
}

/// The grid of cells and which bodies are in each.
#[derive(Clone, Debug)]
pub struct CellGrid {
    /// Cells along each axis (≥ 2).
    n: [u32; 3],
    /// Box edge lengths.
    lengths: DVec3,
    /// `bounds[a][k]` is the lower face of cell `k` along axis `a`; `bounds[a][n]` is the box
    /// length exactly (so that a body leaves the last cell exactly at the box face).
    bounds: [Vec<f64>; 3],
    /// Slots per cell.
    cap: usize,
    /// Bodies in each cell.
    count: Vec<u32>,
    /// `slots[cell * cap .. cell * cap + count[cell]]` are the bodies of `cell`.
    slots: Vec<u32>,
    /// Position of each body in its cell's slots.
    slot_of: Vec<u32>,
}

impl CellGrid {
    /// A grid for a box of `lengths` with cells at least `reach` wide, for `n_bodies` bodies
    /// (at most [`max_cells`] cells).
    ///
    /// # Errors
    /// The axis (0, 1, 2) along which fewer than 2 cells fit.
    pub fn new(lengths: DVec3, reach: f64, n_bodies: usize) -> Result<Self, usize> {
        let n = Self::dims_for(lengths, reach, n_bodies)?;
        let bounds = std::array::from_fn(|a| {
            let w = lengths[a] / f64::from(n[a]);
            let mut b: Vec<f64> = (0..n[a]).map(|k| f64::from(k) * w).collect();
            b.push(lengths[a]);
            b
        });
        let cells = (n[0] as usize) * (n[1] as usize) * (n[2] as usize);
        let mean = n_bodies.div_ceil(cells.max(1));
        let cap = (2 * mean + 4).next_power_of_two();
        Ok(CellGrid {
            n,
            lengths,
            bounds,
            cap,
            count: vec![0; cells],
            slots: vec![u32::MAX; cells * cap],
            slot_of: vec![u32::MAX; n_bodies],
        })
    }

    /// The cells along each axis of the grid [`new`](Self::new) builds: as many as fit at
    /// least `reach` wide, at most [`MAX_CELLS_PER_AXIS`] per axis and [`max_cells`] in all;
    /// at least 3 along an axis where 3 fit, else 2.
    ///
    /// # Errors
    /// The axis (0, 1, 2) along which fewer than 2 cells fit.
    pub fn dims_for(lengths: DVec3, reach: f64, n_bodies: usize) -> Result<[u32; 3], usize> {
        let mut fit = [0.0; 3];
        for a in 0..3 {
            fit[a] = (lengths[a] / reach).floor();
            if fit[a].is_nan() || fit[a] < 2.0 {
                return Err(a);
            }
        }
        let mut n =
            smd::capped_cell_dims(fit, 3, u64::from(MAX_CELLS_PER_AXIS), max_cells(n_bodies))
                .map(|k| k as u32);
        // `capped_cell_dims` gives at least 3; an axis two to three reaches long has room for 2.
        for a in 0..3 {
            if fit[a] < 3.0 {
                n[a] = 2;
            }
        }
        Ok(n)
    }

    /// Cells along each axis.
    pub fn dims(&self) -> [u32; 3] {
        self.n
    }

    /// The box.
    pub fn lengths(&self) -> DVec3 {
        self.lengths
    }

    /// Total number of cells.
    pub fn n_cells(&self) -> usize {
        self.count.len()
    }

    /// Slots per cell (grows when a cell overflows).
    pub fn capacity(&self) -> usize {
        self.cap
    }

    /// The linear index of packed coordinates.
    #[inline(always)]
    pub fn linear(&self, packed: u32) -> usize {
        let [x, y, z] = unpack(packed);
        (x + self.n[0] * (y + self.n[1] * z)) as usize
    }

    /// The cell holding `r` (any position; wrapped into the box first).
    pub fn locate(&self, r: DVec3) -> u32 {
        let mut c = [0u32; 3];
        for a in 0..3 {
            let l = self.lengths[a];
            // A shell crossing has wrapped the position already: no `fmod` then.
            let x = if (0.0..l).contains(&r[a]) {
                r[a]
            } else {
                r[a].rem_euclid(l)
            };
            let b = &self.bounds[a];
            let n = self.n[a] as usize;
            // The last cell whose lower face is at or below x (cell 0 if none): guessed from
            // the uniform width and settled on the stored faces, so that the answer is the
            // faces' own (a binary search over them cost ~90 instructions per axis).
            let mut k = ((x * f64::from(self.n[a]) / l) as usize).min(n - 1);
            while k > 0 && b[k] > x {
                k -= 1;
            }
            while k + 1 < n && b[k + 1] <= x {
                k += 1;
            }
            c[a] = k as u32;
        }
        pack(c)
    }

    /// Lower and upper faces of cell coordinate `k` along `axis`.
    #[inline(always)]
    pub fn faces(&self, axis: usize, k: u32) -> (f64, f64) {
        let b = &self.bounds[axis];
        (b[k as usize], b[k as usize + 1])
    }

    /// The bodies of a cell (by linear index).
    #[inline(always)]
    pub fn bodies(&self, cell: usize) -> &[u32] {
        let base = cell * self.cap;
        &self.slots[base..base + self.count[cell] as usize]
    }

    /// Puts body `i` into cell `packed`.
    pub fn insert(&mut self, i: u32, packed: u32) {
        let cell = self.linear(packed);
        if self.count[cell] as usize == self.cap {
            self.grow();
        }
        let k = self.count[cell] as usize;
        self.slots[cell * self.cap + k] = i;
        self.slot_of[i as usize] = k as u32;
        self.count[cell] += 1;
    }

    /// Takes body `i` out of cell `packed` (where it must be).
    pub fn remove(&mut self, i: u32, packed: u32) {
        let cell = self.linear(packed);
        let base = cell * self.cap;
        let k = self.slot_of[i as usize] as usize;
        debug_assert_eq!(self.slots[base + k], i, "body {i} is not in cell {cell}");
        let last = self.count[cell] as usize - 1;
        let moved = self.slots[base + last];
        self.slots[base + k] = moved;
        self.slot_of[moved as usize] = k as u32;
        self.slots[base + last] = u32::MAX;
        self.count[cell] -= 1;
    }

    /// Doubles the slots per cell (rare: a cell holds more bodies than ever before).
    #[cold]
    fn grow(&mut self) {
        let new_cap = self.cap * 2;
        let mut slots = vec![u32::MAX; self.count.len() * new_cap];
        for (cell, &c) in self.count.iter().enumerate() {
            let c = c as usize;
            slots[cell * new_cap..cell * new_cap + c]
                .copy_from_slice(&self.slots[cell * self.cap..cell * self.cap + c]);
        }
        self.slots = slots;
        self.cap = new_cap;
    }

    /// The three cell coordinates along `axis` adjacent to (and including) `k`, each with the
    /// shift to add to a position in that cell to bring it next to cell `k` (periodic images).
    #[inline(always)]
    pub fn axis_neighbours(&self, axis: usize, k: u32) -> [(u32, f64); 3] {
        let n = self.n[axis];
        let l = self.lengths[axis];
        let below = if k == 0 { (n - 1, -l) } else { (k - 1, 0.0) };
        let above = if k + 1 == n { (0, l) } else { (k + 1, 0.0) };
        [below, (k, 0.0), above]
    }

    /// Calls `f(cell, shift)` for the 27 cells around packed cell `c` (itself included); along
    /// an axis of two cells, the other cell comes twice, with shifts a box length apart.
    #[inline(always)]
    pub fn for_each_neighbour_cell(&self, c: u32, mut f: impl FnMut(usize, DVec3)) {
        let [x, y, z] = unpack(c);
        let xs = self.axis_neighbours(0, x);
        let ys = self.axis_neighbours(1, y);
        let zs = self.axis_neighbours(2, z);
        for &(cz, sz) in &zs {
            for &(cy, sy) in &ys {
                let row = self.n[0] * (cy + self.n[1] * cz);
                for &(cx, sx) in &xs {
                    f((cx + row) as usize, DVec3::new(sx, sy, sz));
                }
            }
        }
    }

    /// Calls `f(cell)` once for each distinct cell of the 27 around packed cell `c` (itself
    /// included): the 27 themselves where every axis has three cells or more, fewer where an
    /// axis has two and its cells below and above are one.
    pub fn for_each_distinct_neighbour_cell(&self, c: u32, mut f: impl FnMut(usize)) {
        let [x, y, z] = unpack(c);
        let distinct = |axis: usize, k: u32| {
            let [below, own, above] = self.axis_neighbours(axis, k);
            let n = if below.0 == above.0 { 2 } else { 3 };
            ([below.0, own.0, above.0], n)
        };
        let (xs, nx) = distinct(0, x);
        let (ys, ny) = distinct(1, y);
        let (zs, nz) = distinct(2, z);
        for &cz in &zs[..nz] {
            for &cy in &ys[..ny] {
                let row = self.n[0] * (cy + self.n[1] * cz);
                for &cx in &xs[..nx] {
                    f((cx + row) as usize);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The reference: the last cell whose lower face is at or below the wrapped coordinate.
    fn located_by_search(g: &CellGrid, r: DVec3) -> [u32; 3] {
        std::array::from_fn(|a| {
            let x = r[a].rem_euclid(g.lengths[a]);
            let k = g.bounds[a][..g.n[a] as usize].partition_point(|&f| f <= x);
            (k.max(1) - 1) as u32
        })
    }

    proptest::proptest! {
        /// The guessed-and-settled cell is the faces' own, on faces, beside them and outside
        /// the box.
        #[test]
        fn locate_agrees_with_a_search_of_the_faces(
            l in (3.0f64..40.0, 3.0f64..40.0, 3.0f64..40.0),
            reach in 0.3f64..1.0,
            pick in proptest::collection::vec((0usize..3, 0u32..64, -2i32..3, -3.0f64..3.0), 1..40),
        ) {
            let lengths = DVec3::new(l.0, l.1, l.2);
            let g = CellGrid::new(lengths, reach, 1000).unwrap();
            for (a, k, ulps, far) in pick {
                let n = g.n[a];
                let face = g.bounds[a][(k % (n + 1)) as usize];
                // A face, a few ulps either side of it, and a point up to 3 boxes away.
                let x = f64::from_bits((face.to_bits() as i64 + i64::from(ulps)).max(0) as u64);
                for x in [x, x + far * lengths[a], -x] {
                    let mut r = lengths * 0.5;
                    r[a] = x;
                    proptest::prop_assert_eq!(unpack(g.locate(r)), located_by_search(&g, r));
                }
            }
        }
    }

    #[test]
    fn small_boxes_are_refused_per_axis() {
        assert_eq!(
            CellGrid::new(DVec3::new(10.0, 1.99, 10.0), 1.0, 10).unwrap_err(),
            1
        );
        let g = CellGrid::new(DVec3::new(10.0, 3.0, 7.5), 1.0, 105).unwrap();
        assert_eq!(g.dims(), [10, 3, 7]);
        // Two to three reaches: two cells along that axis, the others as before.
        let g = CellGrid::new(DVec3::new(10.0, 2.9, 7.5), 1.0, 105).unwrap();
        assert_eq!(g.dims(), [10, 2, 7]);
        let g = CellGrid::new(DVec3::splat(2.5), 1.0, 105).unwrap();
        assert_eq!(g.dims(), [2, 2, 2]);
    }

    #[test]
    fn cells_are_bounded_by_the_number_of_bodies() {
        // (The sizes are asked of `dims_for`, so that nothing large is allocated if the bound
        // is ever lost.) 108 bodies at density 1e-9: a box of 4.8e3 per edge would hold 1023³
        // cells, 27 GB of slots.
        let l = (108.0f64 / 1e-9).cbrt();
        assert_eq!(CellGrid::dims_for(DVec3::splat(l), 1.0, 108), Ok([6, 6, 6]));
        // A tiny reach (hard spheres of diameter 1e-8 at density 0.5).
        assert_eq!(
            CellGrid::dims_for(DVec3::splat(6.0), 5e-8, 108),
            Ok([6, 6, 6])
        );
        // At least 3 per axis, and 27 cells whatever N.
        assert_eq!(
            CellGrid::dims_for(DVec3::new(1e6, 3.5, 1e6), 1.0, 2),
            Ok([3, 3, 3])
        );
        let [x, y, z] = CellGrid::dims_for(DVec3::new(1e6, 4.0, 2e6), 1.0, 1000).unwrap();
        let cells = x * y * z;
        assert!(
            cells <= 2000 && cells > 1500 && y == 3 && z > x && x >= 3,
            "{x} {y} {z}"
        );
        // A dense box is not touched: 4000 bodies at density 0.9 with cells 1.5 wide.
        let l = (4000.0f64 / 0.9).cbrt();
        let k = (l / 1.5).floor() as u32;
        assert_eq!(
            CellGrid::dims_for(DVec3::splat(l), 1.5, 4000),
            Ok([k, k, k])
        );
        let g = CellGrid::new(DVec3::splat(l), 1.5, 4000).unwrap();
        assert_eq!(g.dims(), [k, k, k]);
        assert_eq!(g.n_cells(), (k * k * k) as usize);
    }

    #[test]
    fn locate_insert_remove_and_grow() {
        let mut g = CellGrid::new(DVec3::splat(4.0), 1.0, 100).unwrap();
        let c = g.locate(DVec3::new(3.999, 0.0, -0.5));
        assert_eq!(unpack(c), [3, 0, 3]);
        assert_eq!(unpack(g.locate(DVec3::new(4.0, 1.0, 2.5))), [0, 1, 2]);
        let cap = g.capacity();
        for i in 0..(cap as u32 + 3) {
            g.insert(i, c);
        }
        assert!(g.capacity() > cap);
        let cell = g.linear(c);
        assert_eq!(g.bodies(cell).len(), cap + 3);
        g.remove(0, c);
        g.remove(5, c);
        let mut left: Vec<u32> = g.bodies(cell).to_vec();
        left.sort_unstable();
        let expect: Vec<u32> = (1..(cap as u32 + 3)).filter(|&i| i != 5).collect();
        assert_eq!(left, expect);
    }

    #[test]
    fn neighbourhoods_are_27_distinct_cells_with_periodic_shifts() {
        let g = CellGrid::new(DVec3::new(3.0, 4.0, 5.0), 1.0, 30).unwrap();
        let mut seen = Vec::new();
        g.for_each_neighbour_cell(pack([0, 3, 2]), |cell, shift| seen.push((cell, shift)));
        assert_eq!(seen.len(), 27);
        let mut cells: Vec<usize> = seen.iter().map(|s| s.0).collect();
        cells.sort_unstable();
        cells.dedup();
        assert_eq!(cells.len(), 27);
        // The cell below x = 0 is x = 2 with shift −3; above y = 3 is y = 0 with shift +4.
        let below_x = g.linear(pack([2, 3, 2]));
        assert!(
            seen.iter()
                .any(|&(c, s)| c == below_x && s == DVec3::new(-3.0, 0.0, 0.0))
        );
        let above_y = g.linear(pack([0, 0, 2]));
        assert!(
            seen.iter()
                .any(|&(c, s)| c == above_y && s == DVec3::new(0.0, 4.0, 0.0))
        );
    }

    #[test]
    fn an_axis_of_two_cells_visits_the_other_cell_twice_and_distinct_once() {
        let g = CellGrid::new(DVec3::new(2.5, 4.0, 5.0), 1.0, 30).unwrap();
        assert_eq!(g.dims(), [2, 4, 5]);
        for x in 0..2 {
            let c = pack([x, 1, 2]);
            let mut seen = Vec::new();
            g.for_each_neighbour_cell(c, |cell, shift| seen.push((cell, shift)));
            assert_eq!(seen.len(), 27);
            // The other x cell, with shifts 0 and ∓2.5 (below and above are one cell).
            let other = g.linear(pack([1 - x, 1, 2]));
            let mut shifts: Vec<f64> = seen
                .iter()
                .filter(|s| s.0 == other)
                .map(|s| s.1.x)
                .collect();
            shifts.sort_by(f64::total_cmp);
            let expect = if x == 0 { [-2.5, 0.0] } else { [0.0, 2.5] };
            assert_eq!(shifts, expect);
            let mut distinct = Vec::new();
            g.for_each_distinct_neighbour_cell(c, |cell| distinct.push(cell));
            let mut cells: Vec<usize> = seen.iter().map(|s| s.0).collect();
            cells.sort_unstable();
            cells.dedup();
            assert_eq!(distinct.len(), 18);
            distinct.sort_unstable();
            assert_eq!(distinct, cells);
        }
        // Three cells or more on every axis: the 27, each once.
        let g = CellGrid::new(DVec3::new(3.0, 4.0, 5.0), 1.0, 30).unwrap();
        let mut distinct = Vec::new();
        g.for_each_distinct_neighbour_cell(pack([0, 3, 2]), |cell| distinct.push(cell));
        distinct.sort_unstable();
        distinct.dedup();
        assert_eq!(distinct.len(), 27);
    }
}
