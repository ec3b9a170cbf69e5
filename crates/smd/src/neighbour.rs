//! Verlet neighbour lists with a skin, built from cells, rebuilt on a displacement criterion.
//!
//! A list holds every pair closer than `r_list = r_u + δ` at the time it is built, once
//! (a *half* list: partner `j > i` in the list of `i`, so Newton's third law gives the force
//! on `j` for free). Until some body has moved more than `δ/2` from where it was at the
//! build, no pair outside the list can have come within `r_u`, so the list is complete for
//! the smoothed potential, which is exactly zero beyond `r_u` (003 Eq. 26). The integrator
//! checks the displacements after every drift, before the forces, so the forces are always
//! those of the complete list (Frenkel & Smit §5.3; the criterion of Allen & Tildesley §5.3).
//!
//! At a build the positions are put back into the box and each entry records which periodic
//! image of its partner is the nearest: one `u32` packs the partner (27 bits) and the image
//! code (5 bits, 27 shifts). The force loop then computes `r_ij = r_i − r_j + shift` with no
//! rounding, which would cost a libm call per component on the baseline x86-64 target.
//! Bodies are binned into cells at least `r_list` wide (at least 3 per axis, else all pairs
//! are examined), and only the 27 cells around a body are searched.

use glam::DVec3;

use crate::System;

/// Bits of an entry that hold the image code.
const CODE_BITS: u32 = 5;
const CODE_MASK: u32 = (1 << CODE_BITS) - 1;

/// A half neighbour list in compressed-row form.
#[derive(Clone, Debug)]
pub(crate) struct NeighbourList {
    inner2: f64,
    cutoff2: f64,
    radius: f64,
    half_skin2: f64,
    /// `start[i]..start[i + 1]` are the entries of body `i`.
    pub(crate) start: Vec<u32>,
    /// `j << 5 | image code`.
    pub(crate) entries: Vec<u32>,
    /// Shift of each image code: `r_ij = r_i − r_j + shifts[code]` (32 entries so that a
    /// 5-bit code needs no bounds check; codes 27..32 are never used).
    pub(crate) shifts: [DVec3; 32],
    reference: Vec<DVec3>,
    builds: u64,
    cell: Vec<[u32; 3]>,
    cell_start: Vec<u32>,
    fill: Vec<u32>,
    members: Vec<u32>,
    member_pos: Vec<DVec3>,
    scratch: Vec<(f64, u32)>,
}

/// The partner and the image code of an entry.
#[inline(always)]
pub(crate) fn unpack(e: u32) -> (usize, usize) {
    ((e >> CODE_BITS) as usize, (e & CODE_MASK) as usize)
}

#[inline]
fn pack(j: usize, code: u32) -> u32 {
    ((j as u32) << CODE_BITS) | code
}

/// The code of shift `(sx, sy, sz)` box lengths, each in −1..=1.
#[inline]
fn code(s: [i32; 3]) -> u32 {
    ((s[0] + 1) + 3 * (s[1] + 1) + 9 * (s[2] + 1)) as u32
}

impl NeighbourList {
    /// An empty list of radius `cutoff + skin`; the caller checks the box against it.
    pub(crate) fn new(inner: f64, cutoff: f64, skin: f64) -> Self {
        Self {
            inner2: inner * inner,
            cutoff2: cutoff * cutoff,
            radius: cutoff + skin,
            half_skin2: 0.25 * skin * skin,
            start: Vec::new(),
            entries: Vec::new(),
            shifts: [DVec3::ZERO; 32],
            reference: Vec::new(),
            builds: 0,
            cell: Vec::new(),
            cell_start: Vec::new(),
            fill: Vec::new(),
            members: Vec::new(),
            member_pos: Vec::new(),
            scratch: Vec::new(),
        }
    }

    /// The list radius `r_u + δ`.
    pub(crate) fn radius(&self) -> f64 {
        self.radius
    }

    /// Builds so far.
    pub(crate) fn builds(&self) -> u64 {
        self.builds
    }

    /// Whether some body has moved more than half the skin since the last build (always true
    /// before the first).
    #[inline]
    pub(crate) fn needs_rebuild(&self, pos: &[DVec3]) -> bool {
        if self.reference.len() != pos.len() {
            return true;
        }
        let mut worst = 0.0f64;
        for (p, r) in pos.iter().zip(&self.reference) {
            worst = worst.max((*p - *r).length_squared());
        }
        // NaN positions compare false here; the integrator's own checks catch them.
        worst > self.half_skin2
    }

    /// Puts the bodies back into the box (updating their image counters) and rebuilds the list.
    pub(crate) fn build(&mut self, sys: &mut System) {
        let l = sys.lengths;
        let n = sys.pos.len();
        for (p, img) in sys.pos.iter_mut().zip(sys.image.iter_mut()) {
            for a in 0..3 {
                let k = (p[a] / l[a]).floor();
                if k != 0.0 {
                    p[a] -= k * l[a];
                    img[a] += k;
                }
                // Round-off can leave −0 or exactly L: both are the wall at 0.
                if !(p[a] >= 0.0 && p[a] < l[a]) {
                    p[a] = 0.0;
                }
            }
        }
        for (c, shift) in self.shifts.iter_mut().take(27).enumerate() {
            let s = DVec3::new(
                (c % 3) as f64 - 1.0,
                ((c / 3) % 3) as f64 - 1.0,
                (c / 9) as f64 - 1.0,
            );
            *shift = s * l;
        }
        self.reference.clear();
        self.reference.extend_from_slice(&sys.pos);
        self.start.clear();
        self.entries.clear();
        // Cells half a list radius wide: a stencil of 5³ of them spans 125/8 cubed list radii,
        // against 27 for cells one radius wide (42 % fewer candidates), and five fit along
        // every axis whenever three radius-wide cells would. Smaller boxes: all pairs. At most
        // max(125, 2N) cells (wider ones in a dilute box).
        let fit: [f64; 3] = std::array::from_fn(|a| (2.0 * l[a] / self.radius).floor());
        if fit.iter().all(|&d| d >= 5.0) {
            let dims =
                capped_cell_dims(fit, 5, u64::MAX, (2 * n as u64).max(125)).map(|d| d as usize);
            self.build_cells(&sys.pos, l, dims, 2);
        } else {
            self.build_all_pairs(&sys.pos, l);
        }
        self.start.push(self.entries.len() as u32);
        debug_assert_eq!(self.start.len(), n + 1);
        self.builds += 1;
    }

    /// Bins the bodies into cells at least `r_list / k` wide (a counting sort, so that each
    /// cell's bodies and their positions are contiguous) and searches the half stencil of
    /// cells within `k` of each body's cell: every unordered pair is met exactly once, from
    /// the body whose cell precedes (the other's own cell: the lower index).
    fn build_cells(&mut self, pos: &[DVec3], l: DVec3, dims: [usize; 3], k: i32) {
        let n = pos.len();
        let n_cells = dims[0] * dims[1] * dims[2];
        let lin = |c: [usize; 3]| c[0] + dims[0] * (c[1] + dims[1] * c[2]);
        self.cell.clear();
        self.cell_start.clear();
        self.cell_start.resize(n_cells + 1, 0);
        for p in pos {
            let c: [u32; 3] = std::array::from_fn(|a| {
                (((p[a] / l[a]) * dims[a] as f64) as usize).min(dims[a] - 1) as u32
            });
            self.cell_start[lin(c.map(|x| x as usize)) + 1] += 1;
            self.cell.push(c);
        }
        for c in 0..n_cells {
            self.cell_start[c + 1] += self.cell_start[c];
        }
        self.fill.clear();
        self.fill.extend_from_slice(&self.cell_start[..n_cells]);
        self.members.clear();
        self.members.resize(n, 0);
        self.member_pos.clear();
        self.member_pos.resize(n, DVec3::ZERO);
        for (i, (c, p)) in self.cell.iter().zip(pos).enumerate() {
            let slot = &mut self.fill[lin(c.map(|x| x as usize))];
            self.members[*slot as usize] = i as u32;
            self.member_pos[*slot as usize] = *p;
            *slot += 1;
        }
        // Offsets lexicographically after (0, 0, 0): half of the (2k + 1)³ − 1 neighbours.
        let mut stencil = Vec::new();
        for dz in -k..=k {
            for dy in -k..=k {
                for dx in -k..=k {
                    if (dz, dy, dx) > (0, 0, 0) {
                        stencil.push([dx, dy, dz]);
                    }
                }
            }
        }
        let r2 = self.radius * self.radius;
        #[allow(clippy::needless_range_loop)] // self.cell is read while self.scratch grows
        for i in 0..n {
            self.start.push(self.entries.len() as u32);
            let (p, c) = (pos[i], self.cell[i]);
            let own = lin(c.map(|x| x as usize));
            let range = self.cell_start[own] as usize..self.cell_start[own + 1] as usize;
            for (&j, q) in self.members[range.clone()]
                .iter()
                .zip(&self.member_pos[range])
            {
                let d2 = (p - *q).length_squared();
                if j as usize > i && d2 < r2 {
                    self.scratch.push((d2, pack(j as usize, code([0, 0, 0]))));
                }
            }
            for d in &stencil {
                let (cx, sx) = wrap(c[0] as i32 + d[0], dims[0]);
                let (cy, sy) = wrap(c[1] as i32 + d[1], dims[1]);
                let (cz, sz) = wrap(c[2] as i32 + d[2], dims[2]);
                let code = code([sx, sy, sz]);
                let shift = self.shifts[code as usize];
                let cell = lin([cx, cy, cz]);
                let range = self.cell_start[cell] as usize..self.cell_start[cell + 1] as usize;
                for (&j, q) in self.members[range.clone()]
                    .iter()
                    .zip(&self.member_pos[range])
                {
                    let d2 = (p - *q + shift).length_squared();
                    if d2 < r2 {
                        self.scratch.push((d2, pack(j as usize, code)));
                    }
                }
            }
            self.flush_sorted();
        }
    }

    /// All pairs, for boxes narrower than three list radii (but wider than two).
    fn build_all_pairs(&mut self, pos: &[DVec3], l: DVec3) {
        let r2 = self.radius * self.radius;
        for i in 0..pos.len() {
            self.start.push(self.entries.len() as u32);
            for (j, q) in pos.iter().enumerate().skip(i + 1) {
                let d = pos[i] - *q;
                // Both positions are in [0, L): the nearest image is at most one box away.
                let s: [i32; 3] = std::array::from_fn(|a| {
                    if d[a] > 0.5 * l[a] {
                        -1
                    } else if d[a] < -0.5 * l[a] {
                        1
                    } else {
                        0
                    }
                });
                let code = code(s);
                let d2 = (d + self.shifts[code as usize]).length_squared();
                if d2 < r2 {
                    self.scratch.push((d2, pack(j, code)));
                }
            }
            self.flush_sorted();
        }
    }

    /// Appends the candidates of one body in three bands of their distance at the build:
    /// inside `r_l`, in the switching window of 003 Eq. 26, beyond `r_u`. Distances change
    /// little until the next build, so the force loop's branches on the distance then go the
    /// same way for runs of entries instead of at random (measured: 13 % per step for
    /// Lennard-Jones spheres against unordered entries; a full sort by distance did no better).
    fn flush_sorted(&mut self) {
        let (inner2, cutoff2) = (self.inner2, self.cutoff2);
        let bands: [&dyn Fn(f64) -> bool; 3] = [
            &|d2| d2 <= inner2,
            &|d2| d2 > inner2 && d2 < cutoff2,
            &|d2| d2 >= cutoff2,
        ];
        for band in bands {
            self.entries
                .extend(self.scratch.iter().filter(|x| band(x.0)).map(|x| x.1));
        }
        self.scratch.clear();
    }
}

/// A neighbouring cell coordinate wrapped into `0..dim`, and the shift (in box lengths) that
/// brings a partner found there next to the body: `+1` if the cell wrapped below zero (the
/// partner sits near the far wall, its image one box down is the near one), `−1` above.
#[inline]
fn wrap(c: i32, dim: usize) -> (usize, i32) {
    let d = dim as i32;
    if c < 0 {
        ((c + d) as usize, 1)
    } else if c >= d {
        ((c - d) as usize, -1)
    } else {
        (c as usize, 0)
    }
}

/// Cells along each axis of a grid whose cells must be at least as wide as one `fit[a]`-th of
/// each box edge (`fit[a]` ≥ `min`): at least `min` and at most `max_per_axis` per axis, and at
/// most `max_total` (≥ `min`³) in all. The grids of both engines bound `max_total` by the
/// number of bodies, so that their memory follows N and not the box: a dilute box or a tiny
/// interaction range gets cells wider than needed (always correct for a neighbour search)
/// instead of billions of empty ones. When the bound binds, the axes shrink in proportion
/// (cells stay as near their shape as the minimum allows), computed in logarithms so that any
/// finite `fit` works.
pub fn capped_cell_dims(fit: [f64; 3], min: u64, max_per_axis: u64, max_total: u64) -> [u64; 3] {
    let lo = (min as f64).ln();
    let budget = (max_total.max(min * min * min) as f64).ln();
    let mut d: [f64; 3] = fit.map(|f| f.max(min as f64).ln());
    // Shrink the axes above the minimum together; an axis that reaches it stays there.
    for _ in 0..3 {
        let excess = d.iter().sum::<f64>() - budget;
        if excess <= 0.0 {
            break;
        }
        let free = d.iter().filter(|&&x| x > lo).count();
        for x in &mut d {
            if *x > lo {
                *x = (*x - excess / free as f64).max(lo);
            }
        }
    }
    let mut n: [u64; 3] = d.map(|x| ((x.exp() + 1e-9).floor() as u64).clamp(min, max_per_axis));
    // Round-off in the logarithms: lose cells along the longest axis until the grid fits.
    while n[0].saturating_mul(n[1]).saturating_mul(n[2]) > max_total.max(min * min * min) {
        let a = (0..3).max_by_key(|&a| n[a]).expect("three axes");
        n[a] -= 1;
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cell_grids_are_bounded_by_the_number_of_bodies() {
        // 108 bodies at density 1e-9 with a list radius of 1.3: 10⁴ cells per axis unbounded.
        let fit = [(108.0f64 / 1e-9).cbrt() / 1.3; 3];
        assert_eq!(capped_cell_dims(fit, 3, 1023, 216), [6, 6, 6]);
        assert_eq!(capped_cell_dims(fit, 5, u64::MAX, 216), [6, 6, 6]);
        assert_eq!(capped_cell_dims(fit, 5, u64::MAX, 200), [5, 5, 5]);
        // Proportions kept; the thin axis stays at its minimum.
        let d = capped_cell_dims([1e6, 4.0, 2e6], 3, 1023, 2000);
        assert!(
            d[1] == 3 && d[2] > d[0] && d.iter().product::<u64>() > 1500,
            "{d:?}"
        );
        assert!(d.iter().product::<u64>() <= 2000, "{d:?}");
        // Absurd fits work, and a grid within the bound is untouched.
        assert_eq!(capped_cell_dims([1e300; 3], 3, 1023, 27), [3, 3, 3]);
        assert_eq!(
            capped_cell_dims([12.0, 7.0, 9.0], 5, u64::MAX, 2000),
            [12, 7, 9]
        );
    }
    use crate::{BodyModel, Setup};

    /// Every pair closer than the radius (minimum image, brute force) is in the list exactly
    /// once, with the shift of its nearest image; nothing farther is.
    #[allow(clippy::needless_range_loop)] // a pair table indexed both ways
    fn check_complete(sys: &mut System, radius: f64) {
        let mut list = NeighbourList::new(radius - 1.0, radius - 0.3, 0.3);
        list.build(sys);
        let l = sys.lengths;
        let n = sys.n();
        let mut found = vec![vec![None; n]; n];
        for i in 0..n {
            for &e in &list.entries[list.start[i] as usize..list.start[i + 1] as usize] {
                let (j, c) = unpack(e);
                let d = sys.pos[i] - sys.pos[j] + list.shifts[c];
                let (a, b, d) = if i < j { (i, j, d) } else { (j, i, -d) };
                assert!(found[a][b].is_none(), "pair {i} {j} twice");
                found[a][b] = Some(d);
            }
        }
        for i in 0..n {
            for j in i + 1..n {
                let mut d = sys.pos[i] - sys.pos[j];
                for a in 0..3 {
                    d[a] -= l[a] * (d[a] / l[a]).round();
                }
                match found[i][j] {
                    Some(e) => {
                        assert!((e - d).length() < 1e-12, "{i} {j}: {e} vs {d}");
                        assert!(d.length() < radius);
                    }
                    None => assert!(d.length() >= radius, "{i} {j} missing at {}", d.length()),
                }
            }
        }
    }

    #[test]
    fn cell_and_all_pairs_builds_find_exactly_the_pairs_within_the_radius() {
        let body = BodyModel::sphere(1.0).unwrap();
        // 500 bodies at ρ = 0.5: L = 10; radii 2.5, 3.2 and 4.0 give 8, 6 and 5 cells per
        // axis, 4.5 too few (all pairs).
        for radius in [2.5, 3.2, 4.0, 4.5] {
            let mut sys = System::new(&Setup::new(500, 0.5, body, 1.0)).unwrap();
            // Scatter the bodies (some outside the box) so that images matter.
            for (k, p) in sys.pos.iter_mut().enumerate() {
                let f = k as f64;
                *p += DVec3::new((f * 0.37).sin(), (f * 1.3).cos(), (f * 0.11).sin()) * 3.0;
            }
            check_complete(&mut sys, radius);
            // Wrapped back into the box, with the image counters saying how far each went.
            for i in 0..sys.n() {
                assert!(sys.pos[i].cmpge(DVec3::ZERO).all() && sys.pos[i].cmplt(sys.lengths).all());
            }
        }
    }

    #[test]
    fn displacement_criterion() {
        let body = BodyModel::sphere(1.0).unwrap();
        let mut sys = System::new(&Setup::new(108, 0.5, body, 1.0)).unwrap();
        let mut list = NeighbourList::new(2.0, 2.5, 0.4);
        assert!(list.needs_rebuild(&sys.pos));
        list.build(&mut sys);
        assert!(!list.needs_rebuild(&sys.pos));
        sys.pos[7].x += 0.199;
        assert!(!list.needs_rebuild(&sys.pos));
        sys.pos[7].x += 0.002;
        assert!(list.needs_rebuild(&sys.pos));
        assert_eq!(list.builds(), 1);
    }
}
