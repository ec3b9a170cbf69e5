//! Estimators of the continuous model along a trajectory, and the online accumulators of the
//! per-sample quantities the summary's error bars come from.
//!
//! A terraced run samples the terraced potential `V` (003 Eq. 7), whose averages differ from
//! the smooth potential's by the terrace width. At every sample the [`Estimator`] evaluates the
//! smooth potential `U` of the scene's pairs, smoothed to zero between `r_l` and `r_u` exactly
//! as the standard-MD engine does (003 Eq. 26, [`potential::Smoothed`], the window of
//! `[smd] smoothing`), and its molecular virial `W = Σ_{i<j} r_ij·F_ij` over every pair within
//! the cut-off (minimum image), at the sampled configuration: the terraced trajectory's
//! estimate of the continuous model's energy and pressure,
//! `P = (N kT_t + W/3) / V` with `kT_t` the instantaneous translational temperature, the
//! standard-MD engine's own formula, so that the two engines' numbers compare directly.
//!
//! [`Samples`] takes, at every sample, the instantaneous temperature, the stored (terraced)
//! potential energy, the collision-virial pressure of the interval since the previous sample
//! and the two smooth estimates into online blocking accumulators ([`Blocks`]); the summary
//! takes their means and Flyvbjerg–Petersen block-average errors, the numbers
//! [`block_average`](crate::analysis::block::block_average) gives for the stored series, in
//! memory that does not grow with the run.

use glam::{DQuat, DVec3};
use potential::{PairGeometry, PairPotential, RigidGeometry, RigidPairPotential, Smoothed};
use serde::{Deserialize, Serialize};

use crate::analysis::block::{BlockEstimate, Blocks};
use crate::analysis::pairs::{for_each_pair, wrap};
use crate::engine::simulation::View;
use crate::engine::sum::Compensated;

/// `U` and `W = Σ r_ij·F_ij` of the smooth potential at one configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SmoothSums {
    /// Potential energy.
    pub energy: f64,
    /// Molecular virial.
    pub virial: f64,
}

impl SmoothSums {
    /// `U` and `W = r_ij·F_ij` of one pair at `r_ij` from its evaluation; NaN for a pair the
    /// potential has no finite force for.
    #[inline]
    fn of_pair(r_ij: DVec3, eval: Result<potential::PairEval, potential::PotentialError>) -> Self {
        match eval {
            Ok(ev) => SmoothSums {
                energy: ev.energy,
                virial: r_ij.dot(ev.force),
            },
            Err(_) => SmoothSums {
                energy: f64::NAN,
                virial: f64::NAN,
            },
        }
    }
}

/// Something that evaluates the smooth potential of a sampled configuration (object safe, so
/// the observers need not know the potential's type).
pub trait Evaluate: std::fmt::Debug + Send {
    /// `U` and `W` at the configuration of `view` (NaN if a pair cannot be evaluated: an
    /// overlap the smooth potential has no finite force for).
    fn evaluate(&self, view: &View<'_>) -> SmoothSums;

    /// Whether the views it is given must carry the bodies' attitudes.
    fn needs_attitudes(&self) -> bool {
        false
    }
}

/// The smooth (cut and switched) potentials of every species pair.
#[derive(Clone, Debug)]
pub struct Estimator<P> {
    n_species: usize,
    table: Vec<u32>,
    pots: Vec<Smoothed<P>>,
    /// The largest cut-off `r_u`.
    cutoff: f64,
}

impl<P: PairPotential> Estimator<P> {
    /// The potentials `pots` of species pairs `(a, b)` (every unordered pair of the
    /// `n_species` species once).
    ///
    /// # Panics
    /// If a species pair is missing (the scene's checks guarantee every pair).
    pub fn new(n_species: usize, pots: Vec<((usize, usize), Smoothed<P>)>) -> Self {
        let (table, list) = species_table(n_species, pots);
        let cutoff = list.iter().map(|p| p.window().1).fold(0.0, f64::max);
        Estimator {
            n_species,
            table,
            pots: list,
            cutoff,
        }
    }

    /// The largest cut-off `r_u`.
    pub fn cutoff(&self) -> f64 {
        self.cutoff
    }

    /// The smooth potential of species `a` and `b`.
    pub fn pair(&self, a: u32, b: u32) -> &Smoothed<P> {
        &self.pots[self.table[a as usize * self.n_species + b as usize] as usize]
    }

    /// `U` and `W` of one pair at `r_ij = r_i − r_j` with axes `s_i`, `s_j` (0 beyond the
    /// cut-off, which the switch of 003 Eq. 26 reaches with zero slope).
    #[inline]
    pub fn pair_sums(&self, a: u32, b: u32, r_ij: DVec3, s_i: DVec3, s_j: DVec3) -> SmoothSums {
        let p = self.pair(a, b);
        let r_u = p.window().1;
        if r_ij.length_squared() >= r_u * r_u {
            return SmoothSums {
                energy: 0.0,
                virial: 0.0,
            };
        }
        SmoothSums::of_pair(r_ij, p.evaluate(&PairGeometry::new(r_ij, s_i, s_j)))
    }
}

impl<P: PairPotential + std::fmt::Debug + Send> Evaluate for Estimator<P> {
    fn evaluate(&self, view: &View<'_>) -> SmoothSums {
        // Bodies without orientation (spheres) have no axes; any unit vector does for them.
        let axis = |i: usize| view.axes.get(i).copied().unwrap_or(DVec3::Z);
        let bodies = view.bodies;
        sum_pairs(view, self.cutoff, |i, j, d| {
            self.pair_sums(bodies[i].species, bodies[j].species, d, axis(i), axis(j))
        })
    }
}

/// The species × species table of `pots` (every unordered pair of the `n_species` species
/// once) and the potentials in table order.
///
/// # Panics
/// If a species pair is missing (the scene's checks guarantee every pair).
fn species_table<T>(n_species: usize, pots: Vec<((usize, usize), T)>) -> (Vec<u32>, Vec<T>) {
    let mut table = vec![u32::MAX; n_species * n_species];
    let mut list = Vec::with_capacity(pots.len());
    for ((a, b), p) in pots {
        table[a * n_species + b] = list.len() as u32;
        table[b * n_species + a] = list.len() as u32;
        list.push(p);
    }
    assert!(
        table.iter().all(|&k| k != u32::MAX),
        "a potential for every species pair"
    );
    (table, list)
}

/// `U` and `W` summed over every pair of `view` within `cutoff` (minimum image), each pair's
/// from `pair(i, j, r_ij)`.
fn sum_pairs(
    view: &View<'_>,
    cutoff: f64,
    pair: impl Fn(usize, usize, DVec3) -> SmoothSums,
) -> SmoothSums {
    let l = view.lengths;
    let n = view.bodies.len();
    let pos: Vec<DVec3> = (0..n).map(|i| wrap(view.position(i), l)).collect();
    let (mut u, mut w) = (Compensated::ZERO, Compensated::ZERO);
    for_each_pair(&pos, l, cutoff, |i, j, d| {
        let s = pair(i, j, d);
        if s.energy != 0.0 || s.virial != 0.0 {
            u.add(s.energy);
            w.add(s.virial);
        }
    });
    SmoothSums {
        energy: u.value(),
        virial: w.value(),
    }
}

/// The smooth potentials of rigid bodies of any shape (`potential::RigidPairPotential`, each
/// zero beyond its own cut-off, as SSD/E and SPC/E are), evaluated at the bodies' attitudes: the view
/// must carry them (`Simulation::sample_attitudes`), else every sum is NaN.
#[derive(Clone, Debug)]
pub struct RigidEstimator<P> {
    n_species: usize,
    table: Vec<u32>,
    pots: Vec<P>,
    cutoff: f64,
}

impl<P: RigidPairPotential> RigidEstimator<P> {
    /// The potentials `pots` of species pairs `(a, b)` (every unordered pair once), each zero
    /// beyond `cutoff`.
    ///
    /// # Panics
    /// If a species pair is missing (the scene's checks guarantee every pair).
    pub fn new(n_species: usize, pots: Vec<((usize, usize), P)>, cutoff: f64) -> Self {
        let (table, pots) = species_table(n_species, pots);
        RigidEstimator {
            n_species,
            table,
            pots,
            cutoff,
        }
    }

    /// `U` and `W` of one pair at `r_ij = r_i − r_j` and attitudes `q_i`, `q_j` (NaN where the
    /// potential has no finite force).
    #[inline]
    pub fn pair_sums(&self, a: u32, b: u32, r_ij: DVec3, q_i: DQuat, q_j: DQuat) -> SmoothSums {
        let p = &self.pots[self.table[a as usize * self.n_species + b as usize] as usize];
        SmoothSums::of_pair(r_ij, p.evaluate(&RigidGeometry::new(r_ij, q_i, q_j)))
    }
}

impl<P: RigidPairPotential + std::fmt::Debug + Send> Evaluate for RigidEstimator<P> {
    fn needs_attitudes(&self) -> bool {
        true
    }

    fn evaluate(&self, view: &View<'_>) -> SmoothSums {
        if view.attitudes.len() != view.bodies.len() {
            return SmoothSums {
                energy: f64::NAN,
                virial: f64::NAN,
            };
        }
        let (bodies, q) = (view.bodies, &view.attitudes);
        sum_pairs(view, self.cutoff, |i, j, d| {
            self.pair_sums(bodies[i].species, bodies[j].species, d, q[i], q[j])
        })
    }
}

/// The per-sample quantities of a production run, each in its online blocking accumulator
/// ([`Blocks`]): memory is `O(log samples)` whatever the run's length, and checkpoints keep the
/// accumulators, so a resumed run continues them exactly.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Samples {
    /// Samples taken (the smooth potential is evaluated at every `smooth_every`-th).
    count: u64,
    /// Instantaneous kinetic temperature `2K/dof`.
    temperature: Blocks,
    /// Instantaneous translational temperature `2K_t/dof_t`.
    translational_temperature: Blocks,
    /// Instantaneous rotational temperature `(T dof − T_t dof_t)/dof_r` (bodies that rotate).
    rotational_temperature: Blocks,
    /// The engine's own potential energy per body (the terraced one in a terraced run).
    potential_per_body: Blocks,
    /// The engine's pressure over each interval between samples (collision virial and mean
    /// kinetic energy; none for the first sample).
    pressure: Blocks,
    /// `U/N` of the smooth potential, at the samples that evaluated it to a number.
    potential_smooth_per_body: Blocks,
    /// `(N kT_t + W/3)/V` of the smooth potential, at the same samples.
    pressure_smooth: Blocks,
    /// Elapsed time, virial and `∫K dt` at the previous sample.
    last: Option<(f64, f64, f64)>,
}

/// Means and block-average errors of a run's samples.
#[derive(Clone, Copy, Debug)]
pub struct SampleSummary {
    /// Kinetic temperature.
    pub temperature: BlockEstimate,
    /// Translational temperature.
    pub translational_temperature: BlockEstimate,
    /// Rotational temperature (bodies with rotational degrees of freedom).
    pub rotational_temperature: Option<BlockEstimate>,
    /// Potential energy per body (the engine's own).
    pub potential_per_body: BlockEstimate,
    /// Pressure per sampling interval (the engine's own).
    pub pressure: BlockEstimate,
    /// Smooth potential energy per body (with an estimator).
    pub potential_smooth_per_body: Option<BlockEstimate>,
    /// Smooth pressure (with an estimator).
    pub pressure_smooth: Option<BlockEstimate>,
}

impl SampleSummary {
    /// The summary keys of the errors whose blocking found no plateau: the run is shorter than
    /// a few correlation times of that quantity, and its error is a lower bound.
    pub fn without_plateau(&self) -> Vec<&'static str> {
        [
            (Some(&self.temperature), "temperature_error"),
            (
                Some(&self.translational_temperature),
                "translational_temperature_error",
            ),
            (
                self.rotational_temperature.as_ref(),
                "rotational_temperature_error",
            ),
            (
                Some(&self.potential_per_body),
                "potential_energy_per_body_error",
            ),
            (Some(&self.pressure), "pressure_error"),
            (
                self.potential_smooth_per_body.as_ref(),
                "potential_energy_per_body_smooth_error",
            ),
            (self.pressure_smooth.as_ref(), "pressure_smooth_error"),
        ]
        .into_iter()
        .filter(|(b, _)| b.is_some_and(|b| !b.converged))
        .map(|(_, key)| key)
        .collect()
    }
}

impl Samples {
    /// Records the sample `view`, with the smooth sums of the estimator if there is one.
    pub fn sample(&mut self, view: &View<'_>, smooth: Option<SmoothSums>) {
        let n = view.bodies.len() as f64;
        let l = view.lengths;
        let volume = l.x * l.y * l.z;
        if let Some((t, w, kint)) = self.last
            && view.elapsed > t
        {
            let dt = view.elapsed - t;
            let kt = 2.0 * (view.kinetic_integral - kint) / dt / view.dof;
            self.pressure
                .push((n * kt + (view.virial - w) / (3.0 * dt)) / volume);
        }
        self.last = Some((view.elapsed, view.virial, view.kinetic_integral));
        self.count += 1;
        let t_dof = view.dof - view.rotational_dof;
        let kt = 2.0 * view.kinetic / view.dof;
        let kt_t = 2.0 * (view.kinetic - view.rotational_kinetic) / t_dof;
        self.temperature.push(kt);
        self.translational_temperature.push(kt_t);
        if view.rotational_dof > 0.0 {
            self.rotational_temperature
                .push((kt * view.dof - kt_t * t_dof) / view.rotational_dof);
        }
        self.potential_per_body.push(view.potential / n);
        // A configuration the smooth potential has no finite force for is left out of both.
        if let Some(s) = smooth.filter(|s| !s.energy.is_nan()) {
            self.potential_smooth_per_body.push(s.energy / n);
            self.pressure_smooth
                .push((n * kt_t + s.virial / 3.0) / volume);
        }
    }

    /// Samples taken.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Bytes the accumulators take (they grow as `log2` of the samples).
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.each().iter().map(|b| b.bytes()).sum::<usize>()
    }

    fn each(&self) -> [&Blocks; 7] {
        [
            &self.temperature,
            &self.translational_temperature,
            &self.rotational_temperature,
            &self.potential_per_body,
            &self.pressure,
            &self.potential_smooth_per_body,
            &self.pressure_smooth,
        ]
    }

    /// Whether a state read from a checkpoint is one that sampling can produce: every
    /// accumulator consistent ([`Blocks::check`]), one temperature per sample, a pressure per
    /// interval, smooth values at most once per sample.
    ///
    /// # Errors
    /// What does not fit.
    pub fn check(&self) -> Result<(), String> {
        if let Some(e) = self.each().iter().find_map(|b| b.check().err()) {
            return Err(e);
        }
        let n = self.count;
        let ok = self.temperature.len() == n
            && self.translational_temperature.len() == n
            && self.potential_per_body.len() == n
            && (self.rotational_temperature.is_empty() || self.rotational_temperature.len() == n)
            && self.pressure.len() <= n.saturating_sub(1)
            && self.potential_smooth_per_body.len() == self.pressure_smooth.len()
            && self.potential_smooth_per_body.len() <= n
            && (n == 0) == self.last.is_none()
            && self
                .last
                .is_none_or(|(t, w, k)| t.is_finite() && w.is_finite() && k.is_finite());
        if ok {
            Ok(())
        } else {
            Err(format!(
                "its per-sample accumulators do not fit its {n} samples"
            ))
        }
    }

    /// Means and errors over the samples (the smooth ones over the samples that evaluated
    /// them, every `output.smooth_every`-th); rotational temperature for bodies that rotate.
    pub fn summary(&self) -> SampleSummary {
        let smooth = !self.potential_smooth_per_body.is_empty();
        SampleSummary {
            temperature: self.temperature.estimate(),
            translational_temperature: self.translational_temperature.estimate(),
            rotational_temperature: (!self.rotational_temperature.is_empty())
                .then(|| self.rotational_temperature.estimate()),
            potential_per_body: self.potential_per_body.estimate(),
            pressure: self.pressure.estimate(),
            potential_smooth_per_body: smooth.then(|| self.potential_smooth_per_body.estimate()),
            pressure_smooth: smooth.then(|| self.pressure_smooth.estimate()),
        }
    }
}
