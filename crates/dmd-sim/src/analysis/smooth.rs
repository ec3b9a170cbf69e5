//! Estimators of the continuous model along a trajectory, and the per-sample series the
//! summary's error bars come from.
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
//! [`Samples`] keeps, at every sample, the instantaneous temperature, the stored (terraced)
//! potential energy, the collision-virial pressure of the interval since the previous sample
//! and the two smooth estimates; the summary takes their means and Flyvbjerg–Petersen
//! block-average errors ([`block_average`]).

use glam::{DQuat, DVec3};
use potential::{PairGeometry, PairPotential, RigidGeometry, RigidPairPotential, Smoothed};
use serde::{Deserialize, Serialize};

use crate::analysis::block::{BlockEstimate, block_average};
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
/// zero beyond its own cut-off, as SSD/E is), evaluated at the bodies' attitudes: the view
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

/// What one sample recorded.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SampleRow {
    /// Instantaneous kinetic temperature `2K/dof`.
    pub temperature: f64,
    /// Instantaneous translational temperature `2K_t/dof_t`.
    pub translational_temperature: f64,
    /// The engine's own potential energy (the terraced one in a terraced run).
    pub potential: f64,
    /// The engine's pressure over the interval since the previous sample (collision virial
    /// and mean kinetic energy; NaN for the first sample).
    pub pressure: f64,
    /// `U` of the smooth potential (NaN without an estimator).
    pub potential_smooth: f64,
    /// `(N kT_t + W/3)/V` of the smooth potential (NaN without an estimator).
    pub pressure_smooth: f64,
}

/// The per-sample series of a production run (kept in checkpoints with the observables).
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
pub struct Samples {
    rows: Vec<SampleRow>,
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
        let pressure = match self.last {
            Some((t, w, kint)) if view.elapsed > t => {
                let dt = view.elapsed - t;
                let kt = 2.0 * (view.kinetic_integral - kint) / dt / view.dof;
                (n * kt + (view.virial - w) / (3.0 * dt)) / volume
            }
            _ => f64::NAN,
        };
        self.last = Some((view.elapsed, view.virial, view.kinetic_integral));
        let kt_t =
            2.0 * (view.kinetic - view.rotational_kinetic) / (view.dof - view.rotational_dof);
        let (potential_smooth, pressure_smooth) = match smooth {
            Some(s) => (s.energy, (n * kt_t + s.virial / 3.0) / volume),
            None => (f64::NAN, f64::NAN),
        };
        self.rows.push(SampleRow {
            temperature: 2.0 * view.kinetic / view.dof,
            translational_temperature: kt_t,
            potential: view.potential,
            pressure,
            potential_smooth,
            pressure_smooth,
        });
    }

    /// The rows.
    pub fn rows(&self) -> &[SampleRow] {
        &self.rows
    }

    /// Means and errors over the samples of `n` bodies with `dof` degrees of freedom of which
    /// `rotational_dof` rotational (the smooth ones over the samples that evaluated them,
    /// every `output.smooth_every`-th). A sample's rotational temperature is
    /// `(T dof − T_t (dof − rotational_dof)) / rotational_dof`.
    pub fn summary(&self, n: usize, dof: f64, rotational_dof: f64) -> SampleSummary {
        let col = |f: &dyn Fn(&SampleRow) -> f64| -> Vec<f64> { self.rows.iter().map(f).collect() };
        let smooth_col = |f: &dyn Fn(&SampleRow) -> f64| -> Vec<f64> {
            self.rows
                .iter()
                .filter(|r| !r.potential_smooth.is_nan())
                .map(f)
                .collect()
        };
        let nf = n as f64;
        let smooth = self.rows.iter().any(|r| !r.potential_smooth.is_nan());
        let pressures: Vec<f64> = col(&|r| r.pressure)
            .into_iter()
            .filter(|p| !p.is_nan())
            .collect();
        SampleSummary {
            temperature: block_average(&col(&|r| r.temperature)),
            translational_temperature: block_average(&col(&|r| r.translational_temperature)),
            rotational_temperature: (rotational_dof > 0.0).then(|| {
                let t_dof = dof - rotational_dof;
                block_average(&col(&|r| {
                    (r.temperature * dof - r.translational_temperature * t_dof) / rotational_dof
                }))
            }),
            potential_per_body: block_average(&col(&|r| r.potential / nf)),
            pressure: block_average(&pressures),
            potential_smooth_per_body: smooth
                .then(|| block_average(&smooth_col(&|r| r.potential_smooth / nf))),
            pressure_smooth: smooth.then(|| block_average(&smooth_col(&|r| r.pressure_smooth))),
        }
    }
}
