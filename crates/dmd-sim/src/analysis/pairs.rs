//! The pairs of a sampled configuration: one loop (by cells, or over all pairs in small boxes)
//! over every pair within a distance at the minimum image, shared by g(r) and the smooth
//! estimators, and the binning the g(r)s of centres and of sites share.

use glam::DVec3;

/// Calls `f(i, j, d)` once for every unordered pair `{i, j}` of `pos` (positions wrapped into
/// the box `l`) closer than `r_max`, with `d = pos[i] − pos[j]` at the minimum image. When three
/// cells at least `r_max` wide fit along every axis and the 27 cells around one hold less than
/// a quarter of the box: [`cell_pairs`]. Else all pairs, [`all_pairs`]: with fewer cells the
/// stencil checks nearly every pair anyway, one at a time, where all pairs go four or eight to
/// a vector instruction. Both visit the pairs in a fixed order, so sums over them are
/// reproducible.
pub(crate) fn for_each_pair(
    pos: &[DVec3],
    l: DVec3,
    r_max: f64,
    f: impl FnMut(usize, usize, DVec3),
) {
    let dims: [usize; 3] = std::array::from_fn(|a| ((l[a] / r_max).floor() as usize).max(1));
    if dims.iter().all(|&d| d >= 3) && dims.iter().product::<usize>() > 4 * 27 {
        cell_pairs(pos, l, r_max, dims, f);
    } else {
        all_pairs(pos, l, r_max, f);
    }
}

/// The pairs by cells: bodies sorted by cell (a counting sort, so each cell's positions are
/// contiguous), pairs within a cell and with the 13 cells of half the stencil, each neighbour
/// cell with its periodic shift (no pair needs its image chosen). The neighbours along each
/// axis come from a table and empty cells are skipped before their stencil: in a gas (a cell
/// or two per body) the stencil's index arithmetic, not the distances, was the loop's cost.
fn cell_pairs(
    pos: &[DVec3],
    l: DVec3,
    r_max: f64,
    dims: [usize; 3],
    mut f: impl FnMut(usize, usize, DVec3),
) {
    let n = pos.len();
    let r2_max = r_max * r_max;
    let lin = |p: DVec3| -> usize {
        let c: [usize; 3] =
            std::array::from_fn(|a| (((p[a] / l[a]) * dims[a] as f64) as usize).min(dims[a] - 1));
        c[0] + dims[0] * (c[1] + dims[1] * c[2])
    };
    let n_cells = dims[0] * dims[1] * dims[2];
    let cell: Vec<usize> = pos.iter().map(|&p| lin(p)).collect();
    let mut start = vec![0usize; n_cells + 1];
    for &c in &cell {
        start[c + 1] += 1;
    }
    for c in 0..n_cells {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut order = vec![0usize; n];
    let mut sorted = vec![DVec3::ZERO; n];
    for (i, &c) in cell.iter().enumerate() {
        order[fill[c]] = i;
        sorted[fill[c]] = pos[i];
        fill[c] += 1;
    }
    // Along axis `a`, the neighbour of coordinate `c` at offset `o − 1` (o = 0, 1, 2): its
    // coordinate and the shift of its bodies' image next to this cell (three distinct cells:
    // dims ≥ 3), at `near[a][3c + o]`.
    let near: [Vec<(usize, f64)>; 3] = std::array::from_fn(|a| {
        (0..3 * dims[a])
            .map(|k| {
                let (c, o) = (k / 3, k % 3);
                match (c + o).checked_sub(1) {
                    None => (dims[a] - 1, -l[a]),
                    Some(m) if m == dims[a] => (0, l[a]),
                    Some(m) => (m, 0.0),
                }
            })
            .collect()
    });
    // Half the stencil: the offsets after (0, 0, 0) in (z, y, x) order.
    const HALF: [(usize, usize, usize); 13] = [
        (1, 1, 2),
        (1, 2, 0),
        (1, 2, 1),
        (1, 2, 2),
        (2, 0, 0),
        (2, 0, 1),
        (2, 0, 2),
        (2, 1, 0),
        (2, 1, 1),
        (2, 1, 2),
        (2, 2, 0),
        (2, 2, 1),
        (2, 2, 2),
    ];
    let mut c = 0;
    for cz in 0..dims[2] {
        for cy in 0..dims[1] {
            for cx in 0..dims[0] {
                let (a, b) = (start[c], start[c + 1]);
                c += 1;
                if a == b {
                    continue;
                }
                for k in a..b {
                    for m in k + 1..b {
                        let d = sorted[k] - sorted[m];
                        if d.length_squared() < r2_max {
                            f(order[k], order[m], d);
                        }
                    }
                }
                for &(oz, oy, ox) in &HALF {
                    let (nz, sz) = near[2][3 * cz + oz];
                    let (ny, sy) = near[1][3 * cy + oy];
                    let (nx, sx) = near[0][3 * cx + ox];
                    let nc = nx + dims[0] * (ny + dims[1] * nz);
                    let (a2, b2) = (start[nc], start[nc + 1]);
                    if a2 == b2 {
                        continue;
                    }
                    let shift = DVec3::new(sx, sy, sz);
                    for k in a..b {
                        // r_i − (r_j + shift).
                        let q = sorted[k] - shift;
                        for m in a2..b2 {
                            let d = q - sorted[m];
                            if d.length_squared() < r2_max {
                                f(order[k], order[m], d);
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Every pair, for boxes too small for [`cell_pairs`] to pay. The distances of a block of
/// partners are computed first, from coordinates in separate arrays and with the image chosen
/// by a comparison turned into a factor (no branch; never `round`, a libm call without
/// SSE4.1), so the loop runs in vector registers; `f` is then called for the pairs within
/// `r_max`, with the same `d` recomputed. A branch per axis, taken at random, made this loop
/// ten times slower than its arithmetic.
fn all_pairs(pos: &[DVec3], l: DVec3, r_max: f64, mut f: impl FnMut(usize, usize, DVec3)) {
    const BLOCK: usize = 64;
    let n = pos.len();
    let r2_max = r_max * r_max;
    let half = 0.5 * l;
    let axis = |a: usize| -> Vec<f64> { pos.iter().map(|p| p[a]).collect() };
    let (xs, ys, zs) = (axis(0), axis(1), axis(2));
    // Both in [0, L]: one shift at most, −L where d > L/2, +L where d < −L/2.
    let image =
        |d: f64, h: f64, l: f64| d - l * (f64::from(u8::from(d > h)) - f64::from(u8::from(d < -h)));
    let mut r2 = [0.0f64; BLOCK];
    for (i, &p) in pos.iter().enumerate() {
        let mut j0 = i + 1;
        while j0 < n {
            let j1 = (j0 + BLOCK).min(n);
            let m = j1 - j0;
            for (k, r) in r2[..m].iter_mut().enumerate() {
                let j = j0 + k;
                let dx = image(p.x - xs[j], half.x, l.x);
                let dy = image(p.y - ys[j], half.y, l.y);
                let dz = image(p.z - zs[j], half.z, l.z);
                *r = dx * dx + dy * dy + dz * dz;
            }
            for (k, &r) in r2[..m].iter().enumerate() {
                if r < r2_max {
                    let j = j0 + k;
                    let d = DVec3::new(
                        image(p.x - xs[j], half.x, l.x),
                        image(p.y - ys[j], half.y, l.y),
                        image(p.z - zs[j], half.z, l.z),
                    );
                    f(i, j, d);
                }
            }
            j0 = j1;
        }
    }
}

/// `p` wrapped into the box `[0, l)`.
pub(crate) fn wrap(p: DVec3, l: DVec3) -> DVec3 {
    DVec3::new(
        p.x.rem_euclid(l.x),
        p.y.rem_euclid(l.y),
        p.z.rem_euclid(l.z),
    )
}

/// Index of the unordered pair of kinds `a ≤ b` among `kinds`: `(0,0), (0,1), …, (1,1), …`.
pub(crate) fn pair_index(a: usize, b: usize, kinds: usize) -> usize {
    let (a, b) = if a <= b { (a, b) } else { (b, a) };
    // The pairs (i, ·) with i < a come first: k + (k − 1) + … + (k − a + 1) of them.
    a * (2 * kinds + 1 - a) / 2 + (b - a)
}

/// Volume of the shell of bin `k` of bins `width` wide from 0.
pub(crate) fn shell_volume(width: f64, k: usize) -> f64 {
    let (a, b) = (k as f64 * width, (k + 1) as f64 * width);
    4.0 / 3.0 * std::f64::consts::PI * (b * b * b - a * a * a)
}

/// `count / ideal`, 0 where the ideal count is 0 (a species of one body, an empty shell).
pub(crate) fn ratio(count: u64, ideal: f64) -> f64 {
    if ideal > 0.0 {
        count as f64 / ideal
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Every pair within `r_max` by the definition: the nearest image by rounding.
    fn brute(pos: &[DVec3], l: DVec3, r_max: f64) -> Vec<(usize, usize, DVec3)> {
        let mut out = Vec::new();
        for i in 0..pos.len() {
            for j in i + 1..pos.len() {
                let mut d = pos[i] - pos[j];
                d -= l * (d / l).round();
                if d.length_squared() < r_max * r_max {
                    out.push((i, j, d));
                }
            }
        }
        out
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]
        /// Both paths (cells in boxes many cut-offs wide, all pairs in small ones) find exactly
        /// the pairs within the cut-off, each once, with the minimum-image separation, in
        /// dilute and crowded boxes, cubic or not.
        #[test]
        fn every_pair_within_the_cut_off_once_at_its_minimum_image(
            n in 0usize..160,
            sides in (4.0f64..40.0, 4.0f64..40.0, 4.0f64..40.0),
            r_max in 0.5f64..12.0,
            seed in any::<u64>(),
        ) {
            use rand::{RngExt, SeedableRng};
            let l = DVec3::new(sides.0, sides.1, sides.2);
            let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
            let pos: Vec<DVec3> = (0..n)
                .map(|_| wrap(DVec3::new(rng.random(), rng.random(), rng.random()) * l, l))
                .collect();
            // A cut-off above half a side has two images in range: not this function's case.
            let r_max = r_max.min(0.499 * l.min_element());
            let mut found = Vec::new();
            for_each_pair(&pos, l, r_max, |i, j, d| {
                found.push(if i < j { (i, j, d) } else { (j, i, -d) });
            });
            found.sort_by_key(|a| (a.0, a.1));
            let want = brute(&pos, l, r_max);
            prop_assert_eq!(found.len(), want.len());
            for (a, b) in found.iter().zip(&want) {
                prop_assert_eq!((a.0, a.1), (b.0, b.1));
                prop_assert!((a.2 - b.2).length() < 1e-9 * l.max_element(), "{:?} {:?}", a, b);
            }
        }
    }
}
