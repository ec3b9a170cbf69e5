//! The terrace map of 003 Eq. 7: a smooth potential `U` turned into a staircase `V(U)`.
//!
//! ```text
//! V(U) = V_min + Σ_k Θ(U − U_k) ΔV_k
//! ```
//!
//! Levels `U_1 < … < U_K` split the values of `U` into terraces `0..=K`: terrace `k` holds
//! `U_k ≤ U < U_{k+1}` (with `U_0 = −∞`), and a pair on it has potential energy `V_k`. Above
//! the top terrace sits the **hard core** `U_core`: crossing it costs `ΔV = +∞`, so terraced
//! bodies never overlap whatever their energy. `V_min` is chosen so that the terrace holding
//! `U = 0` (far-apart pairs) has `V = 0` exactly.
//!
//! **Tie rule.** A value exactly at a level lies on the terrace above it (`Θ(0) = 1`):
//! [`TerraceMap::terrace_of`] counts the levels `≤ U`. A simulator should call it only to set up
//! a pair; afterwards the terrace is stored per pair and changed only by executed events
//! (recomputing it at an event, where `U = U_k` up to round-off, flips on round-off).
//!
//! **Levels the map refuses** ([`LevelSet::new`]): non-finite levels, levels not strictly
//! increasing or within round-off of each other, a level at `U = 0` (its reach would be
//! infinite and far pairs would sit on it), levels at or above the core, levels below the
//! potential's minimum (never crossed), and levels within a tolerance of the minimum: the
//! terrace below such a level has (nearly) zero width (003 §V), so pairs would cross two levels
//! almost at once at a tangency. [`NearMinimum::Shift`] moves such a level a quarter of the way
//! to the next level above instead of refusing it.

use crate::{PairPotential, PotentialError};

/// Most levels a map accepts (a guard against a step far smaller than intended).
pub const MAX_LEVELS: usize = 10_000_000;

/// Default hard core, in units of the well depth: `U_core = 100 |U_min|`. A pair needs about
/// `100 ε` of kinetic energy along the line of centres to reach it: `e^{−100/T*}` is below
/// `10⁻³⁰` at the paper's `T* = 1.4`.
pub const DEFAULT_CORE_DEPTHS: f64 = 100.0;

/// Default tolerance around the minimum, relative to `|U_min|`.
pub const DEFAULT_MINIMUM_TOLERANCE: f64 = 1e-6;

/// What to do with a level within the tolerance of the potential's minimum.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NearMinimum {
    /// Return [`PotentialError::LevelAtMinimum`].
    #[default]
    Refuse,
    /// Move the level up to `U_min + (U_up − U_min)/4`, where `U_up` is the next level above
    /// (or the core), but at most `0`: a terrace of a quarter spacing below it, three quarters
    /// above, and the level stays on the negative side it came from.
    Shift,
}

/// How a level set is checked and where its hard core is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerraceOptions {
    /// The hard-core level `U_core`; `None` for [`DEFAULT_CORE_DEPTHS`]` · |U_min|`.
    pub core: Option<f64>,
    /// Refuse or shift levels at the minimum.
    pub near_minimum: NearMinimum,
    /// Levels within `tolerance · |U_min|` of `U_min` are "at the minimum".
    pub tolerance: f64,
}

impl Default for TerraceOptions {
    fn default() -> Self {
        Self {
            core: None,
            near_minimum: NearMinimum::Refuse,
            tolerance: DEFAULT_MINIMUM_TOLERANCE,
        }
    }
}

impl TerraceOptions {
    /// These options with the hard core at `core`.
    pub fn with_core(mut self, core: f64) -> Self {
        self.core = Some(core);
        self
    }

    /// These options, shifting levels at the minimum instead of refusing them.
    pub fn shifting(mut self) -> Self {
        self.near_minimum = NearMinimum::Shift;
        self
    }
}

/// A checked, strictly increasing set of levels below a hard core, for a potential with a
/// known minimum.
#[derive(Clone, Debug, PartialEq)]
pub struct LevelSet {
    levels: Vec<f64>,
    core: f64,
    minimum: f64,
    shifted: Vec<usize>,
}

impl LevelSet {
    /// Checks `levels` (ascending) for a potential whose global minimum is `minimum` (module
    /// documentation for what is refused).
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] for a bad minimum, core or tolerance, and the level errors
    /// named in the module documentation.
    pub fn new(
        minimum: f64,
        levels: &[f64],
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        if !(minimum.is_finite() && minimum <= 0.0) {
            return Err(PotentialError::Parameter {
                name: "minimum",
                value: minimum,
                why: "finite and <= 0 (U vanishes for far-apart pairs)",
            });
        }
        let core = match options.core {
            Some(c) => c,
            None if minimum < 0.0 => DEFAULT_CORE_DEPTHS * -minimum,
            None => {
                return Err(PotentialError::Parameter {
                    name: "core",
                    value: f64::NAN,
                    why: "given explicitly for a potential without a well (minimum 0)",
                });
            }
        };
        let core = crate::error::positive("core", core)?;
        if !(options.tolerance.is_finite() && options.tolerance >= 0.0) {
            return Err(PotentialError::Parameter {
                name: "tolerance",
                value: options.tolerance,
                why: "finite and >= 0",
            });
        }
        if levels.len() > MAX_LEVELS {
            return Err(PotentialError::TooManyLevels(levels.len()));
        }
        let tol = options.tolerance * (-minimum);
        let mut out = levels.to_vec();
        for (index, &u) in out.iter().enumerate() {
            if !u.is_finite() {
                return Err(PotentialError::NotFinite("level"));
            }
            if index > 0 {
                let previous = out[index - 1];
                if u < previous {
                    return Err(PotentialError::UnsortedLevels {
                        index,
                        value: u,
                        previous,
                    });
                }
                if too_close(previous, u) {
                    return Err(PotentialError::CoincidentLevels {
                        index: index - 1,
                        a: previous,
                        b: u,
                    });
                }
            }
            if u == 0.0 {
                return Err(PotentialError::LevelAtZero(u));
            }
            if u >= core || too_close(u, core) {
                return Err(PotentialError::LevelAboveCore { level: u, core });
            }
        }
        let mut shifted = Vec::new();
        for index in 0..out.len() {
            let u = out[index];
            if (u - minimum).abs() <= tol {
                match options.near_minimum {
                    NearMinimum::Refuse => {
                        return Err(PotentialError::LevelAtMinimum {
                            level: u,
                            minimum,
                            tolerance: tol,
                        });
                    }
                    NearMinimum::Shift => {
                        let next = out.get(index + 1).copied().unwrap_or(core);
                        let up = if u < 0.0 { next.min(0.0) } else { next };
                        out[index] = minimum + 0.25 * (up - minimum);
                        shifted.push(index);
                    }
                }
            } else if u < minimum {
                return Err(PotentialError::LevelBelowMinimum { level: u, minimum });
            }
        }
        // A shifted level stays strictly between its neighbours and off zero by construction;
        // check the invariants once more rather than rely on the argument.
        for (index, w) in out.windows(2).enumerate() {
            if too_close(w[0], w[1]) || w[1] < w[0] {
                return Err(PotentialError::CoincidentLevels {
                    index,
                    a: w[0],
                    b: w[1],
                });
            }
        }
        if let Some(&u) = out.iter().find(|&&u| u == 0.0) {
            return Err(PotentialError::LevelAtZero(u));
        }
        Ok(Self {
            levels: out,
            core,
            minimum,
            shifted,
        })
    }

    /// The paper's evenly spaced levels `U_k = (k − ½) ΔV` (003 §V), `k` running over the
    /// integers, between the minimum and the core: `U = 0` lies mid-way between the levels
    /// `±ΔV/2`. (003 Fig. 1 writes the same grid as `V_min + (k − ½)ΔV` with `V_min` a
    /// multiple of `ΔV`.) Grid levels more than the tolerance below the minimum are left out (no
    /// pair can cross them); one within the tolerance is refused or shifted.
    ///
    /// # Errors
    /// [`PotentialError::Parameter`] unless `ΔV` is finite and positive;
    /// [`PotentialError::TooManyLevels`]; as [`new`](Self::new).
    pub fn evenly_spaced(
        minimum: f64,
        step: f64,
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        let step = crate::error::positive("step", step)?;
        if !minimum.is_finite() {
            return Err(PotentialError::NotFinite("minimum"));
        }
        let core = options.core.unwrap_or(DEFAULT_CORE_DEPTHS * minimum.abs());
        if !core.is_finite() {
            return Err(PotentialError::NotFinite("core"));
        }
        let floor = minimum - options.tolerance.abs() * minimum.abs();
        // k − ½ ≥ floor/ΔV  and  k − ½ < core/ΔV.
        let k_lo = (floor / step + 0.5).ceil();
        let k_hi = (core / step + 0.5).ceil() - 1.0;
        let count = k_hi - k_lo + 1.0;
        if count > MAX_LEVELS as f64 {
            return Err(PotentialError::TooManyLevels(count as usize));
        }
        let mut levels: Vec<f64> = (0..count.max(0.0) as usize)
            .map(|i| (k_lo + i as f64 - 0.5) * step)
            .collect();
        // The top grid level may round onto the core itself: it is the core.
        while levels
            .last()
            .is_some_and(|&u| too_close(u, core) || u >= core)
        {
            levels.pop();
        }
        Self::new(minimum, &levels, options)
    }

    /// The levels, ascending.
    pub fn levels(&self) -> &[f64] {
        &self.levels
    }

    /// The hard-core level.
    pub fn core(&self) -> f64 {
        self.core
    }

    /// The potential's minimum the set was checked against.
    pub fn minimum(&self) -> f64 {
        self.minimum
    }

    /// Indices of the levels that [`NearMinimum::Shift`] moved.
    pub fn shifted(&self) -> &[usize] {
        &self.shifted
    }

    /// The terrace holding `U = 0`: the number of negative levels.
    pub fn zero_terrace(&self) -> usize {
        self.levels.partition_point(|&u| u < 0.0)
    }
}

/// Whether two levels are within round-off of each other.
fn too_close(a: f64, b: f64) -> bool {
    (b - a).abs() <= 4.0 * f64::EPSILON * a.abs().max(b.abs())
}

/// The step energies of a map.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Steps<'a> {
    /// Every step `ΔV_k` equal (003 §V): `V_k = (k − k₀) ΔV` with `k₀` the zero terrace.
    Uniform(f64),
    /// One step per level, `ΔV_k = V_k − V_{k−1}` (003 Eq. 7), `K` values.
    Increments(&'a [f64]),
    /// One energy per terrace, `K + 1` values; shifted as a whole so that the zero terrace has
    /// `V = 0` (the choice of `V_min`).
    Energies(&'a [f64]),
}

/// The two levels around a terrace: the indicators `f = U − U_k` (003 Eq. 8) a simulator
/// searches for a pair on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    /// The level below (`None` for terrace 0, which extends to the minimum).
    pub below: Option<f64>,
    /// The level above; the hard core for the top terrace.
    pub above: f64,
    /// Whether `above` is the hard core (crossing it is a reflection with `ΔV = +∞`).
    pub above_is_core: bool,
}

/// A terrace map: levels, the hard core, and the potential energy of every terrace (module
/// documentation).
///
/// ```
/// use potential::{LennardJones, PairPotential, TerraceMap, TerraceOptions};
///
/// let lj = LennardJones::new(1.0, 1.0)?;
/// // The paper's map with ΔV = ε/2: levels ±0.25, −0.75, 0.75, 1.25, … up to the core.
/// let map = TerraceMap::evenly_spaced(&lj, 0.5, &TerraceOptions::default())?;
/// assert_eq!(&map.levels()[..3], &[-0.75, -0.25, 0.25]);
/// let far = map.terrace_of(-1e-9)?; // a far-apart pair
/// assert_eq!(map.energy(far)?, 0.0);
/// assert_eq!(map.energy(far - 1)?, -0.5);
/// assert_eq!(map.step_down(far)?, Some(-0.5)); // falling into the well releases 0.5
/// // Levels are crossed out to the reach of −0.25 (003 Eq. 25).
/// assert!((map.reach(&lj)? - lj.reach(-0.25)?).abs() < 1e-15);
/// # Ok::<(), potential::PotentialError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct TerraceMap {
    set: LevelSet,
    energies: Vec<f64>,
    zero: usize,
}

impl TerraceMap {
    /// A map from a checked level set and its step energies.
    ///
    /// # Errors
    /// [`PotentialError::Length`] if `steps` has the wrong length,
    /// [`PotentialError::NotFinite`] for a non-finite step or energy,
    /// [`PotentialError::Parameter`] for a non-positive uniform step.
    pub fn new(set: LevelSet, steps: Steps<'_>) -> Result<Self, PotentialError> {
        let k = set.levels.len();
        let zero = set.zero_terrace();
        let energies: Vec<f64> = match steps {
            Steps::Uniform(dv) => {
                let dv = crate::error::positive("step", dv)?;
                (0..=k).map(|t| (t as f64 - zero as f64) * dv).collect()
            }
            Steps::Increments(dvs) => {
                if dvs.len() != k {
                    return Err(PotentialError::Length {
                        what: "step increments (one per level)",
                        expected: k,
                        got: dvs.len(),
                    });
                }
                if dvs.iter().any(|d| !d.is_finite()) {
                    return Err(PotentialError::NotFinite("step increment"));
                }
                let mut v = vec![0.0; k + 1];
                for t in zero + 1..=k {
                    v[t] = v[t - 1] + dvs[t - 1];
                }
                for t in (0..zero).rev() {
                    v[t] = v[t + 1] - dvs[t];
                }
                v
            }
            Steps::Energies(vs) => {
                if vs.len() != k + 1 {
                    return Err(PotentialError::Length {
                        what: "terrace energies (one per terrace)",
                        expected: k + 1,
                        got: vs.len(),
                    });
                }
                if vs.iter().any(|v| !v.is_finite()) {
                    return Err(PotentialError::NotFinite("terrace energy"));
                }
                let base = vs[zero];
                vs.iter().map(|v| v - base).collect()
            }
        };
        Ok(Self {
            set,
            energies,
            zero,
        })
    }

    /// The paper's map (003 §V): levels `U_k = (k − ½) ΔV`, every step `ΔV`, `V = 0` for far
    /// pairs, the core and near-minimum rule from `options`.
    ///
    /// # Errors
    /// As [`LevelSet::evenly_spaced`].
    pub fn evenly_spaced<P: PairPotential + ?Sized>(
        potential: &P,
        step: f64,
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        let set = LevelSet::evenly_spaced(potential.minimum(), step, options)?;
        Self::new(set, Steps::Uniform(step))
    }

    /// A map with explicit levels (ascending) and step energies.
    ///
    /// # Errors
    /// As [`LevelSet::new`] and [`new`](Self::new).
    pub fn from_levels<P: PairPotential + ?Sized>(
        potential: &P,
        levels: &[f64],
        steps: Steps<'_>,
        options: &TerraceOptions,
    ) -> Result<Self, PotentialError> {
        Self::new(LevelSet::new(potential.minimum(), levels, options)?, steps)
    }

    /// The level set.
    pub fn level_set(&self) -> &LevelSet {
        &self.set
    }

    /// The levels `U_1 < … < U_K`.
    pub fn levels(&self) -> &[f64] {
        &self.set.levels
    }

    /// The hard-core level.
    pub fn core(&self) -> f64 {
        self.set.core
    }

    /// The energy of every terrace, `V_0 … V_K` (the core above is `+∞`).
    pub fn energies(&self) -> &[f64] {
        &self.energies
    }

    /// The number of terraces, `K + 1`.
    pub fn terraces(&self) -> usize {
        self.energies.len()
    }

    /// The terrace holding `U = 0`, where far-apart pairs sit with `V = 0`.
    pub fn zero_terrace(&self) -> usize {
        self.zero
    }

    /// `V_min`: the energy of terrace 0.
    pub fn v_min(&self) -> f64 {
        self.energies[0]
    }

    /// The terrace holding `u` (binary search; a value exactly at a level is on the terrace
    /// above it).
    ///
    /// # Errors
    /// [`PotentialError::NotFinite`] for NaN, [`PotentialError::InsideCore`] for
    /// `u ≥ U_core`.
    #[inline]
    pub fn terrace_of(&self, u: f64) -> Result<usize, PotentialError> {
        if u.is_nan() {
            return Err(PotentialError::NotFinite("U"));
        }
        if u >= self.set.core {
            return Err(PotentialError::InsideCore {
                u,
                core: self.set.core,
            });
        }
        Ok(self.set.levels.partition_point(|&l| l <= u))
    }

    /// `V(U)` (003 Eq. 7): the energy of the terrace holding `u`; `+∞` at or above the core
    /// (and for NaN, which is not below it).
    #[inline]
    pub fn value(&self, u: f64) -> f64 {
        match self.terrace_of(u) {
            Ok(k) => self.energies[k],
            Err(_) => f64::INFINITY,
        }
    }

    /// `V_k`.
    ///
    /// # Errors
    /// [`PotentialError::TerraceIndex`] for `k > K`.
    #[inline]
    pub fn energy(&self, k: usize) -> Result<f64, PotentialError> {
        self.energies.get(k).copied().ok_or(self.bad_index(k))
    }

    /// The levels around terrace `k`.
    ///
    /// # Errors
    /// [`PotentialError::TerraceIndex`] for `k > K`.
    #[inline]
    pub fn bounds(&self, k: usize) -> Result<Bounds, PotentialError> {
        let n = self.set.levels.len();
        if k > n {
            return Err(self.bad_index(k));
        }
        Ok(Bounds {
            below: k.checked_sub(1).map(|i| self.set.levels[i]),
            above: if k < n {
                self.set.levels[k]
            } else {
                self.set.core
            },
            above_is_core: k == n,
        })
    }

    /// `ΔV` of crossing from terrace `k` up to `k + 1`: `V_{k+1} − V_k`, or `+∞` into the core.
    ///
    /// # Errors
    /// [`PotentialError::TerraceIndex`] for `k > K`.
    #[inline]
    pub fn step_up(&self, k: usize) -> Result<f64, PotentialError> {
        match (self.energies.get(k), self.energies.get(k + 1)) {
            (Some(a), Some(b)) => Ok(b - a),
            (Some(_), None) => Ok(f64::INFINITY),
            _ => Err(self.bad_index(k)),
        }
    }

    /// `ΔV` of crossing from terrace `k` down to `k − 1`: `V_{k−1} − V_k`; `None` for terrace 0,
    /// which has no level below it.
    ///
    /// # Errors
    /// [`PotentialError::TerraceIndex`] for `k > K`.
    #[inline]
    pub fn step_down(&self, k: usize) -> Result<Option<f64>, PotentialError> {
        let v = self.energy(k)?;
        Ok(k.checked_sub(1).map(|i| self.energies[i] - v))
    }

    /// The largest reach of any level (the simulator's interaction range): the reach of the
    /// highest negative level and of the lowest positive level (or of the core), whichever is
    /// larger. Reaches grow towards `U = 0` from either side, so no other level can be larger.
    ///
    /// # Errors
    /// As [`PairPotential::reach`].
    pub fn reach<P: PairPotential + ?Sized>(&self, potential: &P) -> Result<f64, PotentialError> {
        let levels = &self.set.levels;
        let below = levels[..self.zero].last().copied();
        let above = levels.get(self.zero).copied().unwrap_or(self.set.core);
        let mut r = potential.reach(above)?;
        if let Some(u) = below {
            r = r.max(potential.reach(u)?);
        }
        Ok(r)
    }

    fn bad_index(&self, index: usize) -> PotentialError {
        PotentialError::TerraceIndex {
            index,
            last: self.energies.len() - 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> TerraceOptions {
        TerraceOptions::default()
    }

    #[test]
    fn evenly_spaced_levels_of_the_paper() {
        let set = LevelSet::evenly_spaced(-1.0, 0.5, &opts()).unwrap();
        assert_eq!(&set.levels()[..4], &[-0.75, -0.25, 0.25, 0.75]);
        assert_eq!(set.core(), 100.0);
        assert_eq!(*set.levels().last().unwrap(), 99.75);
        assert_eq!(set.zero_terrace(), 2);
        // ΔV = 2/3: the grid has a level at −1, the minimum.
        let e = LevelSet::evenly_spaced(-1.0, 2.0 / 3.0, &opts()).unwrap_err();
        assert!(matches!(e, PotentialError::LevelAtMinimum { .. }), "{e}");
        let s = LevelSet::evenly_spaced(-1.0, 2.0 / 3.0, &opts().shifting()).unwrap();
        assert_eq!(s.shifted(), &[0]);
        assert!((s.levels()[0] - (-1.0 + 0.25 * (1.0 - 1.0 / 3.0))).abs() < 1e-15);
    }

    #[test]
    fn terrace_indices_at_and_around_each_level() {
        let map = TerraceMap::new(
            LevelSet::new(-1.0, &[-0.6, -0.2, 0.3], &opts().with_core(2.0)).unwrap(),
            Steps::Uniform(0.4),
        )
        .unwrap();
        for (k, &u) in map.levels().iter().enumerate() {
            assert_eq!(map.terrace_of(u).unwrap(), k + 1, "at level {u}");
            assert_eq!(map.terrace_of(u.next_down()).unwrap(), k, "below {u}");
            assert_eq!(map.terrace_of(u.next_up()).unwrap(), k + 1, "above {u}");
            let b = map.bounds(k + 1).unwrap();
            assert_eq!(b.below, Some(u));
        }
        assert_eq!(map.terrace_of(-5.0).unwrap(), 0);
        assert!(map.terrace_of(2.0).is_err());
        assert!(map.terrace_of(f64::NAN).is_err());
        assert_eq!(map.energies(), &[-0.8, -0.4, 0.0, 0.4]);
        assert_eq!(map.step_up(3).unwrap(), f64::INFINITY);
        assert!(map.bounds(3).unwrap().above_is_core);
        assert_eq!(map.step_down(0).unwrap(), None);
        assert!(map.energy(4).is_err() && map.step_up(4).is_err());
        assert_eq!(map.value(1.9), 0.4);
        assert_eq!(map.value(2.5), f64::INFINITY);
    }

    #[test]
    fn increments_and_energies_put_far_pairs_at_zero() {
        let set = LevelSet::new(-1.0, &[-0.6, -0.2, 0.3], &opts()).unwrap();
        let a = TerraceMap::new(set.clone(), Steps::Increments(&[0.5, 0.1, 0.7])).unwrap();
        assert_eq!(a.energies(), &[-0.6, -0.1, 0.0, 0.7]);
        let b = TerraceMap::new(set.clone(), Steps::Energies(&[1.0, 2.0, 3.0, 4.0])).unwrap();
        assert_eq!(b.energies(), &[-2.0, -1.0, 0.0, 1.0]);
        assert!(TerraceMap::new(set.clone(), Steps::Energies(&[1.0])).is_err());
        assert!(TerraceMap::new(set, Steps::Increments(&[1.0, f64::NAN, 0.0])).is_err());
    }

    #[test]
    fn bad_levels_are_refused_with_their_reason() {
        let o = opts();
        let err = |levels: &[f64]| LevelSet::new(-1.0, levels, &o).unwrap_err();
        assert!(matches!(
            err(&[-0.2, -0.5]),
            PotentialError::UnsortedLevels { .. }
        ));
        assert!(matches!(
            err(&[-0.5, -0.5 + 1e-17]),
            PotentialError::CoincidentLevels { .. }
        ));
        assert!(matches!(err(&[-0.5, 0.0]), PotentialError::LevelAtZero(_)));
        assert!(matches!(
            err(&[-1.5]),
            PotentialError::LevelBelowMinimum { .. }
        ));
        assert!(matches!(
            err(&[200.0]),
            PotentialError::LevelAboveCore { .. }
        ));
        assert!(matches!(err(&[f64::NAN]), PotentialError::NotFinite(_)));
        for near in [-1.0, -1.0 + 1e-9, -1.0 - 1e-9] {
            assert!(matches!(
                err(&[near, -0.5]),
                PotentialError::LevelAtMinimum { .. }
            ));
        }
        // Just outside the tolerance is a legal (narrow) terrace.
        assert!(LevelSet::new(-1.0, &[-1.0 + 2e-6], &o).is_ok());
        assert!(LevelSet::new(1.0, &[0.5], &o).is_err());
        assert!(LevelSet::new(0.0, &[0.5], &o).is_err()); // no well: core must be given
        assert!(LevelSet::new(0.0, &[0.5], &o.with_core(10.0)).is_ok());
    }

    #[test]
    fn shifting_moves_the_level_clear_of_both_neighbours() {
        let s = LevelSet::new(-1.0, &[-1.0 + 1e-9, -0.2], &opts().shifting()).unwrap();
        assert_eq!(s.shifted(), &[0]);
        assert!((s.levels()[0] - (-1.0 + 0.2)).abs() < 1e-15);
        // The only level, with the core far above: a quarter of the way to zero, not to the core
        // (which would put it at U = 0).
        let s = LevelSet::new(-1.0, &[-1.0], &opts().shifting().with_core(3.0)).unwrap();
        assert_eq!(s.levels(), &[-0.75]);
    }
}
