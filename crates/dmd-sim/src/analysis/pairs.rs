//! The pairs of a sampled configuration: one cell-list loop over every pair within a distance
//! at the minimum image, shared by g(r) and the smooth estimators, and the binning the g(r)s of
//! centres and of sites share.

use glam::DVec3;

/// Calls `f(i, j, d)` once for every unordered pair `{i, j}` of `pos` (positions wrapped into
/// the box `l`) closer than `r_max`, with `d = pos[i] − pos[j]` at the minimum image. When three
/// cells at least `r_max` wide fit along every axis: bodies sorted by cell (a counting sort, so
/// each cell's positions are contiguous), pairs within a cell and with the 13 cells of half the
/// stencil, each neighbour cell with its periodic shift (no pair needs its image chosen). Else
/// all pairs, the image chosen by comparisons. Never `round`: a libm call without SSE4.1, which
/// with a branch per axis and a linked list of cells made this loop the whole cost of the
/// smooth estimators.
pub(crate) fn for_each_pair(
    pos: &[DVec3],
    l: DVec3,
    r_max: f64,
    mut f: impl FnMut(usize, usize, DVec3),
) {
    let n = pos.len();
    let r2_max = r_max * r_max;
    let dims: [usize; 3] = std::array::from_fn(|a| ((l[a] / r_max).floor() as usize).max(1));
    if dims.iter().all(|&d| d >= 3) {
        let lin = |p: DVec3| -> usize {
            let c: [usize; 3] = std::array::from_fn(|a| {
                (((p[a] / l[a]) * dims[a] as f64) as usize).min(dims[a] - 1)
            });
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
        // The neighbour along axis `a` of coordinate `c` at offset `o − 1`: its coordinate and
        // the shift of its bodies' image next to this cell (three distinct cells: dims ≥ 3).
        let step = |c: usize, o: usize, a: usize| -> (usize, f64) {
            match (c + o).checked_sub(1) {
                None => (dims[a] - 1, -l[a]),
                Some(k) if k == dims[a] => (0, l[a]),
                Some(k) => (k, 0.0),
            }
        };
        for c in 0..n_cells {
            let (a, b) = (start[c], start[c + 1]);
            for k in a..b {
                for m in k + 1..b {
                    let d = sorted[k] - sorted[m];
                    if d.length_squared() < r2_max {
                        f(order[k], order[m], d);
                    }
                }
            }
            let (cx, cy, cz) = (
                c % dims[0],
                (c / dims[0]) % dims[1],
                c / (dims[0] * dims[1]),
            );
            // Half the stencil: offsets after (0, 0, 0) in (z, y, x) order.
            for (oz, oy, ox) in (0..27).map(|k| (k / 9, (k / 3) % 3, k % 3)).skip(14) {
                let (nz, sz) = step(cz, oz, 2);
                let (ny, sy) = step(cy, oy, 1);
                let (nx, sx) = step(cx, ox, 0);
                let nc = nx + dims[0] * (ny + dims[1] * nz);
                let shift = DVec3::new(sx, sy, sz);
                let (a2, b2) = (start[nc], start[nc + 1]);
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
    } else {
        let half = 0.5 * l;
        for i in 0..n {
            for j in i + 1..n {
                let mut d = pos[i] - pos[j];
                for a in 0..3 {
                    // Both in [0, L]: one shift at most.
                    if d[a] > half[a] {
                        d[a] -= l[a];
                    } else if d[a] < -half[a] {
                        d[a] += l[a];
                    }
                }
                if d.length_squared() < r2_max {
                    f(i, j, d);
                }
            }
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
