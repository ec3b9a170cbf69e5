//! The reach of a level, found numerically for any potential.
//!
//! The reach of a level `u_k` is the largest centre distance at which some orientations put
//! `U` at or below `u_k` (a negative level) or at or above it (a positive level). Beyond it a
//! pair cannot cross the level; the simulator sizes its cells with the largest reach of its
//! levels and brackets every root search with the times the centre distance spends inside it
//! (003 §V.A). The rods have it in closed form (003 Eq. 25, [`LjRod::reach`]); this module
//! finds it for any [`PairPotential`]:
//!
//! 1. along one orientation, `U(r)` is sampled on a geometric grid from `10⁻³ L` to `10³ L`
//!    (`L` the potential's [`length_scale`](PairPotential::length_scale), ratio 1.03); the
//!    outermost sample that reaches the level and the next one out bracket the crossing, which
//!    Brent's method refines to round-off. For a negative level no sample may reach a level just
//!    above the well's bottom, so the lowest sample is refined by golden section first;
//! 2. over orientations (skipped when the potential does not depend on them): with `r̂ = z`,
//!    `s_i = (sin θ_i, 0, cos θ_i)`, `s_j = (sin θ_j cos φ, sin θ_j sin φ, cos θ_j)`, a grid of
//!    9 × 9 × 8 orientations (`θ` in steps of π/8, `φ` in steps of π/4), then a compass search
//!    from the best three down to steps of `10⁻⁷` rad.
//!
//! The result is the largest reach found: exact to round-off when the maximising orientation
//! is on the grid (end-to-end, side-by-side, T and crossed pairs all are) and to about `10⁻¹²`
//! relative otherwise, for smooth potentials whose best orientations are not confined to a
//! region narrower than the grid spacing. Add a margin if a strict bound is needed.
//!
//! [`LjRod::reach`]: crate::LjRod

use std::f64::consts::PI;

use glam::DVec3;

use crate::solve::{brent_root, golden_min};
use crate::{PairGeometry, PairPotential, PotentialError};

/// Ratio between successive radial samples.
const RATIO: f64 = 1.03;
/// The radial scan covers `[SPAN⁻¹ L, SPAN L]`.
const SPAN: f64 = 1e3;

/// A reach and the configuration that attains it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reach {
    /// The reach (zero if no configuration reaches the level).
    pub distance: f64,
    /// A pair at the reach, on the level: `r_ij = distance · ẑ` and the maximising axes.
    pub geometry: PairGeometry,
}

/// The reach of `u_k` for any potential (module documentation for the method).
///
/// # Errors
/// [`PotentialError::NotFinite`] (level), [`PotentialError::LevelAtZero`],
/// [`PotentialError::Parameter`] for a non-positive length scale,
/// [`PotentialError::UnboundedReach`] if the level is still reached at `10³ L`.
pub fn numerical<P: PairPotential + ?Sized>(p: &P, u_k: f64) -> Result<f64, PotentialError> {
    numerical_detail(p, u_k).map(|r| r.distance)
}

/// [`numerical`], with the maximising configuration.
///
/// # Errors
/// As [`numerical`].
pub fn numerical_detail<P: PairPotential + ?Sized>(
    p: &P,
    u_k: f64,
) -> Result<Reach, PotentialError> {
    if !u_k.is_finite() {
        return Err(PotentialError::NotFinite("level"));
    }
    if u_k == 0.0 {
        return Err(PotentialError::LevelAtZero(u_k));
    }
    let scale = crate::error::positive("length_scale", p.length_scale())?;
    let ray = Ray::new(scale);
    if !p.depends_on_orientation() {
        let axes = axes(0.0, 0.0, 0.0);
        let d = ray.reach(p, u_k, axes)?;
        return Ok(Reach {
            distance: d,
            geometry: PairGeometry::new(DVec3::Z * d, axes.0, axes.1),
        });
    }
    let mut grid = Vec::with_capacity(9 * 9 * 8);
    for i in 0..=8 {
        for j in 0..=8 {
            for k in 0..8 {
                let angles = [
                    i as f64 * PI / 8.0,
                    j as f64 * PI / 8.0,
                    k as f64 * PI / 4.0,
                ];
                let d = ray.reach(p, u_k, axes(angles[0], angles[1], angles[2]))?;
                grid.push((d, angles));
            }
        }
    }
    // Largest first; ties keep grid order (the sort is stable), so the result is deterministic.
    grid.sort_by(|x, y| y.0.total_cmp(&x.0));
    let mut best = grid[0];
    if best.0 == 0.0 {
        return Ok(Reach {
            distance: 0.0,
            geometry: PairGeometry::new(DVec3::ZERO, DVec3::Z, DVec3::Z),
        });
    }
    for &start in grid.iter().take(3) {
        let found = compass(p, &ray, u_k, start)?;
        if found.0 > best.0 {
            best = found;
        }
    }
    let (s_i, s_j) = axes(best.1[0], best.1[1], best.1[2]);
    Ok(Reach {
        distance: best.0,
        geometry: PairGeometry::new(DVec3::Z * best.0, s_i, s_j),
    })
}

/// Axes for the angles `(θ_i, θ_j, φ)` with `r̂ = z`.
fn axes(theta_i: f64, theta_j: f64, phi: f64) -> (DVec3, DVec3) {
    let (si, ci) = theta_i.sin_cos();
    let (sj, cj) = theta_j.sin_cos();
    let (sp, cp) = phi.sin_cos();
    (DVec3::new(si, 0.0, ci), DVec3::new(sj * cp, sj * sp, cj))
}

/// Compass search maximising the reach over the three angles from `start`.
fn compass<P: PairPotential + ?Sized>(
    p: &P,
    ray: &Ray,
    u_k: f64,
    start: (f64, [f64; 3]),
) -> Result<(f64, [f64; 3]), PotentialError> {
    let mut best = start;
    let mut step = PI / 16.0;
    while step > 1e-7 {
        let mut improved = false;
        for dim in 0..3 {
            for sign in [1.0, -1.0] {
                let mut a = best.1;
                a[dim] += sign * step;
                if dim < 2 {
                    a[dim] = a[dim].clamp(0.0, PI);
                }
                let d = ray.reach(p, u_k, axes(a[0], a[1], a[2]))?;
                if d > best.0 {
                    best = (d, a);
                    improved = true;
                }
            }
        }
        if !improved {
            step *= 0.5;
        }
    }
    Ok(best)
}

/// The radial grid of one search.
struct Ray {
    radii: Vec<f64>,
}

impl Ray {
    fn new(scale: f64) -> Self {
        let n = ((SPAN * SPAN).ln() / RATIO.ln()).ceil() as usize;
        let lo = scale / SPAN;
        let radii = (0..=n).map(|j| lo * RATIO.powi(j as i32)).collect();
        Self { radii }
    }

    /// The outermost distance along `r̂ = z` with these axes at which the level is reached.
    fn reach<P: PairPotential + ?Sized>(
        &self,
        p: &P,
        u_k: f64,
        (s_i, s_j): (DVec3, DVec3),
    ) -> Result<f64, PotentialError> {
        let mut u = |r: f64| p.energy(&PairGeometry::new(DVec3::Z * r, s_i, s_j));
        let below = u_k < 0.0;
        let reached = |v: f64| if below { v <= u_k } else { v >= u_k };
        let n = self.radii.len();
        let mut outer: Option<usize> = None;
        let mut lowest = (f64::INFINITY, 0usize);
        let mut values = Vec::with_capacity(n);
        for (j, &r) in self.radii.iter().enumerate() {
            let v = u(r);
            if reached(v) {
                outer = Some(j);
            }
            if v < lowest.0 {
                lowest = (v, j);
            }
            values.push(v);
        }
        // Signed distance to the level, positive outside the reached region.
        let side = |v: f64| if below { v - u_k } else { u_k - v };
        let (start, end) = match outer {
            Some(j) if j + 1 == n => {
                return Err(PotentialError::UnboundedReach {
                    level: u_k,
                    searched_to: self.radii[j],
                });
            }
            Some(j) => (j, j + 1),
            None if below && lowest.0.is_finite() => {
                // The well may dip below the level between two samples.
                let j = lowest.1;
                let (a, b) = (
                    self.radii[j.saturating_sub(1)],
                    self.radii[(j + 1).min(n - 1)],
                );
                let (r_min, v_min) = golden_min(&mut u, a, b);
                if !reached(v_min) {
                    return Ok(0.0);
                }
                let hi = (j + 1).min(n - 1);
                let f_hi = side(values[hi]);
                let mut g = |r: f64| side(u(r));
                return Ok(brent_root(
                    &mut g,
                    r_min,
                    self.radii[hi],
                    side(v_min),
                    f_hi,
                    0.0,
                ));
            }
            None => return Ok(0.0),
        };
        let mut g = |r: f64| side(u(r));
        let (a, b) = (self.radii[start], self.radii[end]);
        Ok(brent_root(
            &mut g,
            a,
            b,
            side(values[start]),
            side(values[end]),
            0.0,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GayBerne, LennardJones, LjRod};

    #[test]
    fn numerical_reach_of_lennard_jones_matches_the_closed_form() {
        let lj = LennardJones::new(1.0, 1.0).unwrap();
        for level in [-0.999_999_999, -0.7, -0.05, -1e-6, 0.3, 100.0] {
            let exact = lj.reach(level).unwrap();
            let num = numerical(&lj, level).unwrap();
            assert!(
                (num - exact).abs() <= 1e-13 * exact,
                "{level}: {num} {exact}"
            );
        }
        assert_eq!(numerical(&lj, -1.5).unwrap(), 0.0);
        assert!(numerical(&lj, 0.0).is_err());
        // A level so close to zero that the tail reaches it beyond 1000 σ.
        assert!(matches!(
            numerical(&lj, -1e-19),
            Err(PotentialError::UnboundedReach { .. })
        ));
    }

    #[test]
    fn numerical_reach_of_the_rods_matches_eq_25() {
        let rod = LjRod::new(1.0, 1.0, 0.33).unwrap();
        for level in [-0.9, -0.25, -0.01, 2.0] {
            let exact = rod.reach(level).unwrap();
            let r = numerical_detail(&rod, level).unwrap();
            assert!(
                (r.distance - exact).abs() <= 1e-12 * exact,
                "{level}: {} {exact}",
                r.distance
            );
            // Attained by parallel (or antiparallel) rods.
            assert!((r.geometry.s_i.dot(r.geometry.s_j).abs() - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn gay_berne_reach_is_attained_and_not_exceeded() {
        let gb = GayBerne::default();
        for level in [-0.2, -0.02] {
            let r = numerical_detail(&gb, level).unwrap();
            let u = gb.energy(&r.geometry);
            assert!((u - level).abs() < 1e-10, "{level}: U = {u}");
        }
    }
}
