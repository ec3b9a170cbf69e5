//! Stepped radial pair potentials: hard cores, square wells and general staircases.
//!
//! A potential is a list of steps `(r_k, ΔU_k)` with `r_0 < r_1 < … < r_{n−1}`: crossing `r_k`
//! inwards changes the pair energy by `ΔU_k` (`+∞` for a hard core, which can only be the
//! innermost step), and the energy beyond `r_{n−1}` is zero, so
//! `U(r) = Σ_{k : r < r_k} ΔU_k`.
//!
//! A pair's **level** `s` is the number of step radii it is inside (0 = out of range). Level `s`
//! lies between the inner boundary `r_{n−s−1}` (none for `s = n`) and the outer boundary
//! `r_{n−s}` (none for `s = 0`). The level of every pair is stored (see
//! [`PairStates`](crate::engine::pair_state::PairStates)) and changed only by the events of that pair:
//! recomputing it from the distance at a boundary would flip on round-off.

/// Relative distance within which a stored level is kept at its boundary (round-off of an
/// event executed at that boundary).
const BOUNDARY_TOLERANCE: f64 = 1e-9;

/// One level of a stepped potential, with what is needed to predict and execute its events.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Level {
    /// Square of the inner boundary radius (`-1` if none: the level reaches `r = 0`).
    pub inner2: f64,
    /// Square of the outer boundary radius (`+∞` if none: level 0).
    pub outer2: f64,
    /// Energy change of crossing the inner boundary inwards (`+∞` for a hard core).
    pub dv_in: f64,
    /// Energy change of crossing the outer boundary outwards.
    pub dv_out: f64,
    /// Pair energy on this level.
    pub energy: f64,
}

/// A stepped radial pair potential, ready for the event loop.
#[derive(Clone, Debug, PartialEq)]
pub struct StepPotential {
    radii: Vec<f64>,
    steps: Vec<f64>,
    levels: Vec<Level>,
}

impl StepPotential {
    /// The level of a pair at distance `d` whose stored level is `stored`: the stored level if the
    /// distance is on it or within round-off of its boundary, else the level of the distance.
    pub fn true_level(&self, stored: usize, d: f64) -> usize {
        let expected = self.level_at(d);
        if expected == stored {
            return stored;
        }
        let n = self.radii().len();
        if stored <= n && expected.abs_diff(stored) == 1 {
            let at = self.radii()[n - stored.max(expected)];
            if (d - at).abs() <= BOUNDARY_TOLERANCE * at {
                return stored;
            }
        }
        expected
    }

    /// Builds the levels from `(radius, energy step)` pairs, radii strictly increasing (the
    /// scene checks that; this constructor trusts it).
    pub fn new(steps: &[[f64; 2]]) -> Self {
        let radii: Vec<f64> = steps.iter().map(|s| s[0]).collect();
        let dus: Vec<f64> = steps.iter().map(|s| s[1]).collect();
        let n = radii.len();
        let levels = (0..=n)
            .map(|s| {
                let energy = dus[n - s..].iter().sum::<f64>();
                let (inner2, dv_in) = if s < n {
                    let k = n - s - 1;
                    (radii[k] * radii[k], dus[k])
                } else {
                    (-1.0, f64::NAN)
                };
                let (outer2, dv_out) = if s > 0 {
                    let k = n - s;
                    (radii[k] * radii[k], -dus[k])
                } else {
                    (f64::INFINITY, f64::NAN)
                };
                Level {
                    inner2,
                    outer2,
                    dv_in,
                    dv_out,
                    energy,
                }
            })
            .collect();
        StepPotential {
            radii,
            steps: dus,
            levels,
        }
    }

    /// The levels, indexed by level number.
    #[inline]
    pub fn levels(&self) -> &[Level] {
        &self.levels
    }

    /// The outermost radius: pairs farther apart never interact.
    pub fn reach(&self) -> f64 {
        *self
            .radii
            .last()
            .expect("a potential has at least one step")
    }

    /// The hard-core diameter, if the innermost step is infinite.
    pub fn core(&self) -> Option<f64> {
        (self.steps[0] == f64::INFINITY).then_some(self.radii[0])
    }

    /// Whether this is a bare hard core (one infinite step).
    pub fn is_hard_sphere(&self) -> bool {
        self.steps.len() == 1 && self.core().is_some()
    }

    /// The level a pair at distance `r` is on (number of radii strictly greater than `r`).
    pub fn level_at(&self, r: f64) -> usize {
        self.radii.iter().filter(|&&x| r < x).count()
    }

    /// Pair energy at distance `r` (`+∞` inside a hard core).
    pub fn energy_at(&self, r: f64) -> f64 {
        self.levels[self.level_at(r)].energy
    }

    /// The step radii.
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// The energy steps.
    pub fn steps(&self) -> &[f64] {
        &self.steps
    }
}

/// A pair table for [`Potentials::from_tables`]: the two species and the `[radius, step]`s.
pub type PairTable = ((usize, usize), Vec<[f64; 2]>);

/// All pair potentials of a scene: a symmetric species × species table.
#[derive(Clone, Debug, PartialEq)]
pub struct Potentials {
    n_species: usize,
    /// `table[a * n + b]` indexes `potentials`.
    table: Vec<u32>,
    potentials: Vec<StepPotential>,
}

impl Potentials {
    /// From explicit tables: `tables[k] = ((a, b), steps)` for species `a`, `b` in
    /// `0..n_species`. Every unordered pair must appear exactly once, with radii strictly
    /// increasing (what a scene's check guarantees).
    ///
    /// # Panics
    /// If a pair is missing or given twice.
    pub fn from_tables(n_species: usize, tables: &[PairTable]) -> Self {
        let n = n_species;
        let mut table = vec![u32::MAX; n * n];
        let mut potentials = Vec::new();
        for ((a, b), steps) in tables {
            assert_eq!(table[a * n + b], u32::MAX, "pair ({a}, {b}) given twice");
            let k = potentials.len() as u32;
            potentials.push(StepPotential::new(steps));
            table[a * n + b] = k;
            table[b * n + a] = k;
        }
        assert!(
            table.iter().all(|&k| k != u32::MAX),
            "a pair of species has no table"
        );
        Potentials {
            n_species: n,
            table,
            potentials,
        }
    }

    /// The potential between species `a` and `b`.
    #[inline]
    pub fn get(&self, a: u32, b: u32) -> &StepPotential {
        &self.potentials[self.table[a as usize * self.n_species + b as usize] as usize]
    }

    /// The index of the potential between species `a` and `b`.
    #[inline]
    pub fn index(&self, a: u32, b: u32) -> usize {
        self.table[a as usize * self.n_species + b as usize] as usize
    }

    /// The distinct potentials.
    pub fn all(&self) -> &[StepPotential] {
        &self.potentials
    }

    /// Number of species.
    pub fn n_species(&self) -> usize {
        self.n_species
    }

    /// The largest reach of any potential: the smallest allowed cell side.
    pub fn reach(&self) -> f64 {
        self.potentials
            .iter()
            .map(StepPotential::reach)
            .fold(0.0, f64::max)
    }

    /// Whether every potential is a bare hard core (the hard-sphere fast path applies).
    pub fn all_hard_spheres(&self) -> bool {
        self.potentials.iter().all(StepPotential::is_hard_sphere)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_well_levels() {
        let p = StepPotential::new(&[[1.0, f64::INFINITY], [1.5, -1.0]]);
        let l = p.levels();
        assert_eq!(l.len(), 3);
        // Level 0: outside the well.
        assert_eq!(l[0].outer2, f64::INFINITY);
        assert_eq!(l[0].inner2, 2.25);
        assert_eq!(l[0].dv_in, -1.0);
        assert_eq!(l[0].energy, 0.0);
        // Level 1: inside the well, bounded by the core.
        assert_eq!(l[1].outer2, 2.25);
        assert_eq!(l[1].dv_out, 1.0);
        assert_eq!(l[1].inner2, 1.0);
        assert_eq!(l[1].dv_in, f64::INFINITY);
        assert_eq!(l[1].energy, -1.0);
        assert_eq!(p.level_at(1.2), 1);
        assert_eq!(p.level_at(1.5), 0);
        assert_eq!(p.energy_at(1.49), -1.0);
        assert_eq!(p.core(), Some(1.0));
        assert!(!p.is_hard_sphere());
        assert_eq!(p.reach(), 1.5);
    }

    #[test]
    fn soft_staircase_has_a_reachable_centre() {
        let p = StepPotential::new(&[[0.5, 3.0], [1.0, 1.0], [2.0, -0.5]]);
        let l = p.levels();
        assert_eq!(l.len(), 4);
        assert_eq!(l[3].inner2, -1.0);
        assert_eq!(l[3].energy, 3.5);
        assert_eq!(l[2].energy, 0.5);
        assert_eq!(l[1].energy, -0.5);
        assert_eq!(p.energy_at(0.1), 3.5);
        assert!(p.core().is_none());
        assert!(StepPotential::new(&[[1.0, f64::INFINITY]]).is_hard_sphere());
    }
}
