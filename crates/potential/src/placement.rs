//! Where to put the levels and what energy to give each terrace, beyond the paper's evenly
//! spaced levels with equal steps: the rules users of stepped potentials know.
//!
//! **Placement** ([`Placement`]) works on a radial [`Profile`]. A [`Layout`] fixes how many
//! levels go on each side of zero and the first and last of them; the placement rule spaces
//! the ones in between:
//!
//! - [`Placement::EqualEnergy`]: evenly in `U` (with the paper's layout, the paper's levels
//!   `(k − ½)ΔV`);
//! - [`Placement::EqualDistance`]: evenly in `x` on the branch where the levels are crossed
//!   (negative levels on the outer, attractive branch; positive ones on the inner, repulsive
//!   branch), `U_k = U(x_k)`;
//! - [`Placement::EqualVolume`]: evenly in the shell measure `∫ w dx` (equal shell volumes).
//!
//! The negative levels between the well's bottom and zero also cut the inner branch between
//! `x_min` and the contact distance; a terrace map is a function of `U`, so those shells follow
//! from the outer branch's levels. With the same layout every rule has the same number of
//! levels, the same outermost level (so the same reach and cell size) and the same top level:
//! the comparison of rules is at equal cost in levels.
//!
//! **Step energies** ([`StepEnergy`]) give terrace `k`, holding `U_k ≤ U < U_{k+1}` on the
//! shells `I_k` (one or two `x`-intervals):
//!
//! - [`StepEnergy::Equal`]: `V_k = (k − k₀) ΔV`, the paper's equal steps;
//! - [`StepEnergy::Midpoint`]: the middle of the terrace's range, `½(max(U_k, U_min) + U_{k+1})`;
//! - [`StepEnergy::VolumeAverage`]: `∫_{I_k} U w dx / ∫_{I_k} w dx`, the shell average;
//! - [`StepEnergy::Virial`]: `−kT ln(∫_{I_k} e^{−U/kT} w dx / ∫_{I_k} w dx)`, so that the
//!   terrace's contribution to the second virial coefficient `B₂(T)` is exact at that `T`.
//!
//! The terrace holding `U = 0` extends to infinity and always gets `V = 0` (far-apart pairs
//! carry no energy), so its part of `B₂` (the tail beyond the outermost level, and the sliver
//! of the repulsive branch with `|U|` below the first levels) is left out by every rule; that
//! part shrinks only as the outermost level approaches zero.

use crate::quadrature::{Tolerance, integrate};
use crate::terrace::{LevelSet, Steps, TerraceMap, TerraceOptions};
use crate::{PotentialError, Profile};

/// How levels are spaced between the ends a [`Layout`] fixes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Placement {
    /// Evenly in `U`.
    EqualEnergy,
    /// Evenly in `x` (distance, or effective distance for the rods).
    EqualDistance,
    /// Evenly in the shell measure (equal shell volumes).
    EqualVolume,
}

impl Placement {
    /// All three rules.
    pub const ALL: [Placement; 3] = [Self::EqualEnergy, Self::EqualDistance, Self::EqualVolume];

    /// A short name for reports.
    pub fn name(self) -> &'static str {
        match self {
            Self::EqualEnergy => "equal dU",
            Self::EqualDistance => "equal dr",
            Self::EqualVolume => "equal volume",
        }
    }
}

/// How many levels lie on each side of zero, and the first and last of each group (values of
/// `U`, ascending within a group).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Layout {
    /// Negative levels: count, lowest, highest (the outermost, which sets the reach).
    pub negative: (usize, f64, f64),
    /// Positive levels: count, lowest, highest (below the core).
    pub positive: (usize, f64, f64),
}

impl Layout {
    /// The counts and ends of the paper's levels `(k − ½) ΔV` for a potential with minimum
    /// `minimum` (after the near-minimum rule of `options`).
    ///
    /// # Errors
    /// As [`LevelSet::evenly_spaced`].
    pub fn paper(
        minimum: f64,
        step: f64,
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        let set = LevelSet::evenly_spaced(minimum, step, options)?;
        Ok(Self::of(&set))
    }

    /// The counts and ends of an existing level set.
    pub fn of(set: &LevelSet) -> Self {
        let levels = set.levels();
        let z = set.zero_terrace();
        let group = |g: &[f64]| match (g.first(), g.last()) {
            (Some(&a), Some(&b)) => (g.len(), a, b),
            _ => (0, 0.0, 0.0),
        };
        Self {
            negative: group(&levels[..z]),
            positive: group(&levels[z..]),
        }
    }

    /// The same layout with the outermost negative level moved to `U = u_out` (a longer or
    /// shorter reach with the same number of levels).
    pub fn with_outermost(mut self, u_out: f64) -> Self {
        self.negative.2 = u_out;
        self
    }
}

/// `n` points from `a` to `b` inclusive, evenly spaced.
fn spaced(n: usize, a: f64, b: f64) -> impl Iterator<Item = f64> {
    (0..n).map(move |i| {
        if n == 1 {
            b
        } else {
            let t = i as f64 / (n - 1) as f64;
            // Hit both ends exactly.
            if i + 1 == n { b } else { a + t * (b - a) }
        }
    })
}

impl Placement {
    /// The levels this rule puts on `profile` for `layout`, ascending.
    ///
    /// # Errors
    /// As [`Profile::inner_radius`] and [`Profile::outer_radius`] (a layout end below the
    /// profile's minimum, or a negative level at or above zero).
    pub fn levels<F: Fn(f64) -> f64>(
        self,
        profile: &Profile<F>,
        layout: &Layout,
    ) -> Result<Vec<f64>, PotentialError> {
        let (n, lo, hi) = layout.negative;
        let (m, plo, phi) = layout.positive;
        if n > 0 && (hi.is_nan() || hi >= 0.0) {
            return Err(PotentialError::LevelAtZero(hi));
        }
        let mut out = Vec::with_capacity(n + m);
        match self {
            Self::EqualEnergy => {
                out.extend(spaced(n, lo, hi));
                out.extend(spaced(m, plo, phi));
            }
            Self::EqualDistance | Self::EqualVolume => {
                let to_t = |x: f64| match self {
                    Self::EqualDistance => x,
                    _ => profile.volume(x),
                };
                if n > 0 {
                    let (xa, xb) = (profile.outer_radius(lo)?, profile.outer_radius(hi)?);
                    for t in spaced(n, to_t(xa), to_t(xb)) {
                        let x = from_t(self, profile, t, xa, xb)?;
                        out.push(profile.energy(x));
                    }
                    // The ends are the layout's values exactly, not U(x(U)) with round-off.
                    out[0] = lo;
                    out[n - 1] = hi;
                }
                if m > 0 {
                    // Inner branch: x decreases as U increases.
                    let (xa, xb) = (profile.inner_radius(plo)?, profile.inner_radius(phi)?);
                    for t in spaced(m, to_t(xa), to_t(xb)) {
                        let x = from_t(self, profile, t, xb, xa)?;
                        out.push(profile.energy(x));
                    }
                    out[n] = plo;
                    out[n + m - 1] = phi;
                }
            }
        }
        Ok(out)
    }
}

/// The `x` in `[lo, hi]` whose spacing coordinate is `t` (inverts the measure for volumes).
fn from_t<F: Fn(f64) -> f64>(
    rule: Placement,
    profile: &Profile<F>,
    t: f64,
    lo: f64,
    hi: f64,
) -> Result<f64, PotentialError> {
    match rule {
        Placement::EqualVolume => {
            // The measure increases with x (w > 0 above the floor); invert by bisection-safe
            // Brent on [lo, hi].
            let (va, vb) = (profile.volume(lo) - t, profile.volume(hi) - t);
            if va >= 0.0 {
                return Ok(lo);
            }
            if vb <= 0.0 {
                return Ok(hi);
            }
            let mut f = |x: f64| profile.volume(x) - t;
            Ok(crate::solve::brent_root(&mut f, lo, hi, va, vb, 0.0))
        }
        _ => Ok(t.clamp(lo, hi)),
    }
}

/// The energy of each terrace (module documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum StepEnergy {
    /// Equal steps of this size (the paper's rule with evenly spaced levels).
    Equal(f64),
    /// The middle of each terrace's range of `U`.
    Midpoint,
    /// The shell average of `U`.
    VolumeAverage,
    /// The shell's contribution to `B₂` kept exact at this `kT`.
    Virial {
        /// `kT` (energy units of the potential).
        kt: f64,
    },
}

impl StepEnergy {
    /// A short name for reports.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Equal(_) => "equal steps",
            Self::Midpoint => "midpoint",
            Self::VolumeAverage => "volume average",
            Self::Virial { .. } => "B2 matching",
        }
    }

    /// The energy of every terrace of `set` on `profile` (`K + 1` values, zero terrace `0`).
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] for a bad step or `kT`; the errors of
    /// [`Profile::shells`] and of the quadrature.
    pub fn energies<F: Fn(f64) -> f64>(
        &self,
        profile: &Profile<F>,
        set: &LevelSet,
    ) -> Result<Vec<f64>, PotentialError> {
        let levels = set.levels();
        let k = levels.len();
        let zero = set.zero_terrace();
        let (_, u_min) = profile.minimum();
        let range = |t: usize| {
            let lo = if t == 0 {
                u_min
            } else {
                levels[t - 1].max(u_min)
            };
            let hi = if t < k { levels[t] } else { set.core() };
            (lo, hi)
        };
        match *self {
            Self::Equal(dv) => {
                let dv = crate::error::positive("step", dv)?;
                Ok((0..=k).map(|t| (t as f64 - zero as f64) * dv).collect())
            }
            Self::Midpoint => Ok((0..=k)
                .map(|t| {
                    if t == zero {
                        0.0
                    } else {
                        let (lo, hi) = range(t);
                        0.5 * (lo + hi)
                    }
                })
                .collect()),
            Self::VolumeAverage | Self::Virial { .. } => {
                let kt = match *self {
                    Self::Virial { kt } => Some(crate::error::positive("kt", kt)?),
                    _ => None,
                };
                let (shells, _) = profile.shells(set)?;
                // A Boltzmann factor e^{−(U − lo)/kT} carries the round-off of U amplified by
                // |U|/kT; V = lo − kT ln(⋯) needs the integral only to that relative accuracy.
                let rel = boltzmann_tolerance(kt.map_or(0.0, |kt| u_min.abs() / kt));
                let mut out = Vec::with_capacity(k + 1);
                for (t, shell) in shells.iter().enumerate() {
                    if t == zero {
                        out.push(0.0);
                        continue;
                    }
                    let (lo, _) = range(t);
                    let mut w = 0.0;
                    let mut s = 0.0;
                    for (a, b) in [shell.inner, shell.outer].into_iter().flatten() {
                        w += profile.measure(a, b);
                        s += match kt {
                            None => {
                                shell_integral(|x, u| u * profile.weight(x), profile, a, b, rel)?
                            }
                            // Factor e^{−lo/kT} out: the integrand stays in [e^{−ΔU/kT}, 1]·w.
                            Some(kt) => shell_integral(
                                |x, u| (-(u - lo) / kt).exp() * profile.weight(x),
                                profile,
                                a,
                                b,
                                rel,
                            )?,
                        };
                    }
                    out.push(match kt {
                        None => s / w,
                        Some(kt) => lo - kt * (s / w).ln(),
                    });
                }
                Ok(out)
            }
        }
    }
}

/// The relative tolerance of an integral of a Boltzmann factor `e^{−U/kT}` whose exponent is
/// of order `ratio = |U|/kT`: `10⁻¹³` amplified by the exponent's round-off.
pub(crate) fn boltzmann_tolerance(ratio: f64) -> f64 {
    1e-13 * ratio.max(1.0)
}

/// `∫_a^b g(x, U(x)) dx` over a shell (`b` may be `+∞`), to `rel` relative.
pub(crate) fn shell_integral<F: Fn(f64) -> f64>(
    g: impl Fn(f64, f64) -> f64,
    profile: &Profile<F>,
    a: f64,
    b: f64,
    rel: f64,
) -> Result<f64, PotentialError> {
    let tol = Tolerance {
        rel,
        ..Tolerance::default()
    };
    if b.is_infinite() {
        return crate::quadrature::integrate_to_infinity(|x| g(x, profile.energy(x)), a, tol)
            .map(|i| i.value);
    }
    integrate(|x| g(x, profile.energy(x)), a, b, tol).map(|i| i.value)
}

impl TerraceMap {
    /// A map on a profile: levels placed by `placement` in `layout`, checked with `options`
    /// against the profile's minimum, energies by `energy`.
    ///
    /// ```
    /// use potential::{profile, Layout, LennardJones, Placement, StepEnergy, TerraceMap,
    ///                 TerraceOptions};
    ///
    /// let lj = LennardJones::new(1.0, 1.0)?;
    /// let prof = profile::lennard_jones(&lj)?;
    /// let opts = TerraceOptions::default();
    /// // The paper's counts for ΔV = kT/2 at T* = 1, spaced evenly in r, B2-matched at T* = 1.
    /// let layout = Layout::paper(-1.0, 0.5, &opts)?;
    /// let map = TerraceMap::from_profile(&prof, Placement::EqualDistance, &layout,
    ///                                    StepEnergy::Virial { kt: 1.0 }, &opts)?;
    /// assert_eq!(map.levels().len(), layout.negative.0 + layout.positive.0);
    /// assert_eq!(map.energy(map.zero_terrace())?, 0.0);
    /// # Ok::<(), potential::PotentialError>(())
    /// ```
    ///
    /// # Errors
    /// As [`Placement::levels`], [`LevelSet::new`] and [`StepEnergy::energies`].
    pub fn from_profile<F: Fn(f64) -> f64>(
        profile: &Profile<F>,
        placement: Placement,
        layout: &Layout,
        energy: StepEnergy,
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        let levels = placement.levels(profile, layout)?;
        let set = LevelSet::new(profile.minimum().1, &levels, options)?;
        let energies = energy.energies(profile, &set)?;
        TerraceMap::new(set, Steps::Energies(&energies))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LennardJones, profile};

    fn lj_profile() -> Profile<impl Fn(f64) -> f64> {
        profile::lennard_jones(&LennardJones::new(1.0, 1.0).unwrap()).unwrap()
    }

    #[test]
    fn equal_energy_with_the_paper_layout_is_the_paper() {
        let p = lj_profile();
        let opts = TerraceOptions::default();
        let set = LevelSet::evenly_spaced(-1.0, 0.3, &opts).unwrap();
        let layout = Layout::of(&set);
        let ours = Placement::EqualEnergy.levels(&p, &layout).unwrap();
        assert_eq!(ours.len(), set.levels().len());
        for (a, b) in ours.iter().zip(set.levels()) {
            assert!((a - b).abs() < 1e-13, "{a} {b}");
        }
    }

    #[test]
    fn radial_rules_space_the_radii_evenly() {
        let p = lj_profile();
        let layout = Layout::paper(-1.0, 0.2, &TerraceOptions::default()).unwrap();
        let n = layout.negative.0;
        let d = Placement::EqualDistance.levels(&p, &layout).unwrap();
        let radii: Vec<f64> = d[..n].iter().map(|&u| p.outer_radius(u).unwrap()).collect();
        let gap = radii[1] - radii[0];
        for w in radii.windows(2) {
            assert!((w[1] - w[0] - gap).abs() < 1e-10, "{w:?}");
        }
        let v = Placement::EqualVolume.levels(&p, &layout).unwrap();
        let vols: Vec<f64> = v[..n]
            .iter()
            .map(|&u| p.volume(p.outer_radius(u).unwrap()))
            .collect();
        let gap = vols[1] - vols[0];
        for w in vols.windows(2) {
            assert!((w[1] - w[0] - gap).abs() < 1e-10 * gap, "{w:?}");
        }
        // Same ends as the paper's.
        assert_eq!((d[0], d[n - 1]), (layout.negative.1, layout.negative.2));
        assert_eq!(v.last(), Some(&layout.positive.2));
    }

    #[test]
    fn virial_rule_tends_to_the_volume_average_and_to_the_lower_edge() {
        let p = lj_profile();
        let set = LevelSet::evenly_spaced(-1.0, 0.3, &TerraceOptions::default()).unwrap();
        let vol = StepEnergy::VolumeAverage.energies(&p, &set).unwrap();
        let hot = StepEnergy::Virial { kt: 1e7 }.energies(&p, &set).unwrap();
        let cold = StepEnergy::Virial { kt: 1e-5 }.energies(&p, &set).unwrap();
        for t in 0..vol.len() {
            if t == set.zero_terrace() {
                continue;
            }
            let lo = if t == 0 { -1.0 } else { set.levels()[t - 1] };
            let hi = set.levels().get(t).copied().unwrap_or(set.core());
            assert!((hot[t] - vol[t]).abs() < 1e-5 * (1.0 + vol[t].abs()), "{t}");
            // kT ≪ ΔU: Boltzmann-weighted, the lowest U of the shell dominates.
            assert!(
                cold[t] >= lo && cold[t] - lo < 1e-3 * (hi - lo),
                "{t}: {}",
                cold[t]
            );
            assert!(vol[t] > lo && vol[t] < hi, "{t}");
        }
    }
}
