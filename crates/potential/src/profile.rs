//! Radial profiles: the one-dimensional view of a potential that the level-placement rules,
//! the step-energy rules and the virial coefficients work on.
//!
//! A [`Profile`] is a single-well function `U(x)`: decreasing from `+∞` (or a large value) to
//! its minimum `U_min` at `x_min`, then increasing towards `0⁻` (an attractive tail). A level
//! `u > U_min` is crossed once on the inner branch (`x < x_min`) and, if negative, once on the
//! outer branch. Which `x` a profile uses:
//!
//! - **Lennard-Jones spheres** ([`lennard_jones`]): `x = r`, the potential itself;
//! - **the rods of 003 §V** ([`rods`]): `x = r_e`, the effective distance, and `U(x)` the
//!   orientation-free part of the potential (a Lennard-Jones function of `r_e`, the same for
//!   every orientation). Every orientation sees the same levels at the same `r_e`, shifted in
//!   `r` by `δ = ζ(½ − c²)`;
//! - **any potential along a reference orientation** ([`along`]): `x = r` with fixed axes, for
//!   example Gay–Berne side by side.
//!
//! The **measure** of a shell `[x₀, x₁]` is `∫ w(x) dx` with `w(x) = ⟨(x − δ)²⟩` over the
//! distribution of shifts `δ` between `r` and `x` (the pair's relative orientations drawn
//! independently and uniformly): `w = x²` for spheres and for a fixed orientation, and for the
//! rods, with `c` uniform on `[−1, 1]`, `⟨δ⟩ = ζ/6`, `⟨δ²⟩ = 7ζ²/60`, `⟨δ³⟩ = 9ζ³/280`. The
//! measure is exact (a polynomial) for `x ≥ δ_max` (`ζ/2` for the rods), where no orientation
//! has moved the shell to negative `r`; `4π` times it is the orientation-averaged volume.

use glam::DVec3;

use crate::solve::{brent_root, golden_min};
use crate::{LennardJones, LevelSet, LjRod, PairGeometry, PairPotential, PotentialError};

/// The `x`-intervals where `U` lies on one terrace: at most one on each branch. An outer
/// interval of the terrace holding `U = 0` ends at `+∞`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Shell {
    /// `[x₀, x₁]` on the inner (repulsive) branch.
    pub inner: Option<(f64, f64)>,
    /// `[x₀, x₁]` on the outer (attractive) branch; `x₁` may be `+∞`.
    pub outer: Option<(f64, f64)>,
}

/// A single-well radial profile with the measure of its shells (module documentation).
#[derive(Clone, Debug)]
pub struct Profile<F> {
    u: F,
    x_min: f64,
    u_min: f64,
    moments: [f64; 3],
    floor: f64,
}

impl<F: Fn(f64) -> f64> Profile<F> {
    /// The profile `u`, whose minimum lies inside `well = (lo, hi)`, with measure `x²`.
    ///
    /// The minimum is located by sampling 400 points and golden-section refinement; the
    /// samples must show a single well below zero.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] for a bad bracket; [`PotentialError::Profile`] if the
    /// samples show no well below zero, a minimum at an end of the bracket, or more than one
    /// well.
    pub fn new(u: F, well: (f64, f64)) -> Result<Self, PotentialError> {
        let (lo, hi) = well;
        let lo = crate::error::positive("well.0", lo)?;
        let hi = crate::error::positive("well.1", hi)?;
        if hi <= lo {
            return Err(PotentialError::Parameter {
                name: "well.1",
                value: hi,
                why: "larger than well.0",
            });
        }
        const N: usize = 400;
        let xs: Vec<f64> = (0..=N)
            .map(|i| lo * (hi / lo).powf(i as f64 / N as f64))
            .collect();
        let vs: Vec<f64> = xs.iter().map(|&x| u(x)).collect();
        let (j, _) = vs
            .iter()
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(b.1))
            .expect("samples are not empty");
        if j == 0 || j == N {
            return Err(PotentialError::Profile(
                "the minimum is at an end of the bracket: widen it",
            ));
        }
        // A single well: non-increasing before the lowest sample, non-decreasing after it
        // (small round-off wiggles allowed).
        let slack = |a: f64, b: f64| 1e-12 * (a.abs() + b.abs());
        let down = vs[..=j]
            .windows(2)
            .all(|w| w[1] <= w[0] + slack(w[0], w[1]));
        let up = vs[j..].windows(2).all(|w| w[1] + slack(w[0], w[1]) >= w[0]);
        if !(down && up) {
            return Err(PotentialError::Profile(
                "the samples show more than one well",
            ));
        }
        let (x_min, u_min) = golden_min(&mut |x| u(x), xs[j - 1], xs[j + 1]);
        if u_min.is_nan() || u_min >= 0.0 {
            return Err(PotentialError::Profile("no well below zero"));
        }
        Ok(Self {
            u,
            x_min,
            u_min,
            moments: [0.0; 3],
            floor: 0.0,
        })
    }

    /// The same profile with the measure `⟨(x − δ)²⟩` of a shift distribution with moments
    /// `⟨δ⟩, ⟨δ²⟩, ⟨δ³⟩` and largest shift `δ_max` (module documentation).
    ///
    /// # Errors
    /// [`PotentialError::NotFinite`] for non-finite moments; [`PotentialError::Parameter`] for
    /// a negative `δ_max`.
    pub fn with_shifts(
        mut self,
        moments: [f64; 3],
        delta_max: f64,
    ) -> Result<Self, PotentialError> {
        if moments.iter().any(|m| !m.is_finite()) {
            return Err(PotentialError::NotFinite("shift moment"));
        }
        self.moments = moments;
        self.floor = crate::error::non_negative("delta_max", delta_max)?;
        Ok(self)
    }

    /// `U(x)`.
    #[inline]
    pub fn energy(&self, x: f64) -> f64 {
        (self.u)(x)
    }

    /// `(x_min, U_min)`.
    pub fn minimum(&self) -> (f64, f64) {
        (self.x_min, self.u_min)
    }

    /// The smallest `x` at which the measure is exact (`δ_max`).
    pub fn floor(&self) -> f64 {
        self.floor
    }

    /// The density of the measure, `w(x) = x² − 2⟨δ⟩x + ⟨δ²⟩`.
    #[inline]
    pub fn weight(&self, x: f64) -> f64 {
        let [m1, m2, _] = self.moments;
        x * x - 2.0 * m1 * x + m2
    }

    /// The measure of `[0, x]` (for `x ≥ δ_max`): `⟨(x − δ)³⟩/3`.
    #[inline]
    pub fn volume(&self, x: f64) -> f64 {
        let [m1, m2, m3] = self.moments;
        (x * x * x - 3.0 * m1 * x * x + 3.0 * m2 * x - m3) / 3.0
    }

    /// The measure of `[a, b]` (`b` may be `+∞`).
    pub fn measure(&self, a: f64, b: f64) -> f64 {
        if b.is_infinite() {
            f64::INFINITY
        } else {
            self.volume(b) - self.volume(a)
        }
    }

    /// The `x < x_min` at which `U = level` (`x_min` for `level = U_min`).
    ///
    /// # Errors
    /// [`PotentialError::LevelBelowMinimum`] for `level < U_min`;
    /// [`PotentialError::Profile`] if `U` stays below the level down to `x = 10⁻³⁰⁰`.
    pub fn inner_radius(&self, level: f64) -> Result<f64, PotentialError> {
        self.check(level)?;
        if level == self.u_min {
            return Ok(self.x_min);
        }
        let mut a = 0.5 * self.x_min;
        let mut fa = self.energy(a) - level;
        while fa.is_nan() || fa <= 0.0 {
            a *= 0.5;
            if a < 1e-300 {
                return Err(PotentialError::Profile(
                    "U stays below the level down to x = 0",
                ));
            }
            fa = self.energy(a) - level;
        }
        let mut f = |x: f64| self.energy(x) - level;
        Ok(brent_root(
            &mut f,
            a,
            self.x_min,
            fa,
            self.u_min - level,
            0.0,
        ))
    }

    /// The `x > x_min` at which `U = level`, for `U_min ≤ level < 0`; `+∞` for `level ≥ 0`
    /// (the tail stays below zero).
    ///
    /// # Errors
    /// [`PotentialError::LevelBelowMinimum`] for `level < U_min`;
    /// [`PotentialError::Profile`] if `U` stays below the level out to `10⁶ x_min`.
    pub fn outer_radius(&self, level: f64) -> Result<f64, PotentialError> {
        self.check(level)?;
        if level >= 0.0 {
            return Ok(f64::INFINITY);
        }
        if level == self.u_min {
            return Ok(self.x_min);
        }
        let mut b = 2.0 * self.x_min;
        let mut fb = self.energy(b) - level;
        while fb.is_nan() || fb <= 0.0 {
            b *= 2.0;
            if b > 1e6 * self.x_min {
                return Err(PotentialError::Profile(
                    "U stays below the level out to 10^6 x_min",
                ));
            }
            fb = self.energy(b) - level;
        }
        let mut f = |x: f64| self.energy(x) - level;
        Ok(brent_root(
            &mut f,
            self.x_min,
            b,
            self.u_min - level,
            fb,
            0.0,
        ))
    }

    fn check(&self, level: f64) -> Result<(), PotentialError> {
        if level.is_nan() {
            return Err(PotentialError::NotFinite("level"));
        }
        if level < self.u_min {
            return Err(PotentialError::LevelBelowMinimum {
                level,
                minimum: self.u_min,
            });
        }
        Ok(())
    }

    /// The shells of every terrace of `set` (`K + 1` entries) and the inner radius of the core
    /// (`U ≥ U_core` for `x` below it).
    ///
    /// # Errors
    /// As [`inner_radius`](Self::inner_radius) and [`outer_radius`](Self::outer_radius);
    /// [`PotentialError::Profile`] if a shell reaches below the floor of the measure.
    pub fn shells(&self, set: &LevelSet) -> Result<(Vec<Shell>, f64), PotentialError> {
        let levels = set.levels();
        let k = levels.len();
        let mut out = Vec::with_capacity(k + 1);
        for t in 0..=k {
            let lo = if t == 0 {
                self.u_min
            } else {
                levels[t - 1].max(self.u_min)
            };
            let hi = if t < k { levels[t] } else { set.core() };
            if hi <= self.u_min {
                out.push(Shell::default());
                continue;
            }
            let inner = Some((self.inner_radius(hi)?, self.inner_radius(lo)?));
            let outer = if lo < 0.0 {
                Some((self.outer_radius(lo)?, self.outer_radius(hi.min(0.0))?))
            } else {
                None
            };
            out.push(Shell { inner, outer });
        }
        let core = self.inner_radius(set.core())?;
        if core < self.floor {
            return Err(PotentialError::Profile(
                "the core lies below the floor of the measure (shifts move it to negative r)",
            ));
        }
        Ok((out, core))
    }
}

/// The Lennard-Jones profile `U(r)`, measure `r²`.
///
/// # Errors
/// None in practice (the well is bracketed from the parameters).
pub fn lennard_jones(
    lj: &LennardJones,
) -> Result<Profile<impl Fn(f64) -> f64 + use<>>, PotentialError> {
    let lj = *lj;
    let s = lj.sigma();
    Profile::new(move |r| lj.energy_at(r), (0.8 * s, 3.0 * s))
}

/// The rods' profile (003 Eqs. 22–23): the Lennard-Jones function of `r_e`, with the
/// orientation-averaged measure of the shifts `δ = ζ(½ − c²)`, `c` uniform on `[−1, 1]`.
///
/// # Errors
/// None in practice.
pub fn rods(rod: &LjRod) -> Result<Profile<impl Fn(f64) -> f64 + use<>>, PotentialError> {
    let rod = *rod;
    let (s, z) = (rod.sigma(), rod.zeta());
    Profile::new(move |x| rod.energy_of_effective(x), (0.8 * s, 3.0 * s))?.with_shifts(
        [z / 6.0, 7.0 * z * z / 60.0, 9.0 * z * z * z / 280.0],
        0.5 * z,
    )
}

/// `U(x ẑ)` of any potential with fixed axes `s_i`, `s_j` (a reference orientation), measure
/// `x²`; `well` brackets the minimum along that direction.
///
/// # Errors
/// As [`Profile::new`].
pub fn along<P: PairPotential>(
    potential: P,
    s_i: DVec3,
    s_j: DVec3,
    well: (f64, f64),
) -> Result<Profile<impl Fn(f64) -> f64 + use<P>>, PotentialError> {
    Profile::new(
        move |x| potential.energy(&PairGeometry::new(DVec3::Z * x, s_i, s_j)),
        well,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GayBerne, TerraceOptions};

    #[test]
    fn lennard_jones_profile_radii() {
        let p = lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap();
        let (x_min, u_min) = p.minimum();
        assert!((x_min - 2f64.powf(1.0 / 6.0)).abs() < 1e-8);
        assert!((u_min + 1.0).abs() < 1e-15);
        assert!((p.inner_radius(0.0).unwrap() - 1.0).abs() < 1e-15);
        let r = p.outer_radius(-0.25).unwrap();
        assert!((p.energy(r) + 0.25).abs() < 1e-15);
        assert_eq!(p.outer_radius(0.5).unwrap(), f64::INFINITY);
        assert!(p.inner_radius(-1.5).is_err());
        assert_eq!(p.volume(2.0), 8.0 / 3.0);
    }

    #[test]
    fn rod_measure_is_the_orientation_average() {
        let rod = LjRod::new(1.0, 1.0, 0.4).unwrap();
        let p = rods(&rod).unwrap();
        // ⟨(x − δ)³⟩/3 by Gauss–Legendre in c (δ is a polynomial in c: exact).
        let gl = crate::quadrature::GaussLegendre::new(8).unwrap();
        for x in [0.2, 0.9, 1.7] {
            let direct = gl.integrate(|c| (x - 0.4 * (0.5 - c * c)).powi(3) / 3.0, 0.0, 1.0);
            assert!((p.volume(x) - direct).abs() < 1e-15, "{x}");
        }
    }

    #[test]
    fn shells_cover_the_line_without_gaps() {
        let p = lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap();
        let set = LevelSet::evenly_spaced(-1.0, 0.3, &TerraceOptions::default()).unwrap();
        let (shells, core) = p.shells(&set).unwrap();
        // Inner intervals tile [core, x_min] and outer ones tile [x_min, ∞).
        let mut inner: Vec<(f64, f64)> = shells.iter().filter_map(|s| s.inner).collect();
        inner.sort_by(|a, b| a.0.total_cmp(&b.0));
        assert_eq!(inner[0].0, core);
        for w in inner.windows(2) {
            assert_eq!(w[0].1, w[1].0);
        }
        let outer: Vec<(f64, f64)> = shells.iter().filter_map(|s| s.outer).collect();
        assert_eq!(outer.last().unwrap().1, f64::INFINITY);
        for w in outer.windows(2) {
            assert_eq!(w[0].1, w[1].0);
        }
        assert_eq!(inner.last().unwrap().1, outer[0].0);
    }

    #[test]
    fn gay_berne_side_by_side_profile() {
        let p = along(GayBerne::default(), DVec3::X, DVec3::X, (0.5, 3.0)).unwrap();
        let (x, u) = p.minimum();
        assert!((x - 2f64.powf(1.0 / 6.0)).abs() < 1e-8);
        assert!((u + 5.0 / 3.0).abs() < 1e-14);
    }

    #[test]
    fn profiles_without_a_single_well_are_refused() {
        assert!(Profile::new(|x: f64| 1.0 / x, (0.5, 2.0)).is_err());
        assert!(Profile::new(|x: f64| (3.0 * x).sin(), (0.1, 10.0)).is_err());
        assert!(Profile::new(|x: f64| (x - 1.0).powi(2) + 1.0, (0.1, 3.0)).is_err());
    }
}
