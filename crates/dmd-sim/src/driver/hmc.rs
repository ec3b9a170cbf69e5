//! Hybrid Monte Carlo with event-driven segments (seed 000 §V): a missed event can never
//! corrupt the sampled ensemble.
//!
//! A [`Chain`] alternates, for segment after segment of fixed simulated time `τ`:
//!
//! 1. **refresh** the momenta: *canonical*, every centre-of-mass velocity (and, through
//!    [`PairModel::draw_rotations`], every angular velocity) drawn from its Gaussian at
//!    temperature `T`; *microcanonical*, centre-of-mass velocities exchanged between random
//!    pairs of bodies of one species (equal masses, so the total kinetic energy and momentum
//!    stay exactly as they were);
//! 2. run the event-driven dynamics for `τ` from that phase-space point `x₀`;
//! 3. evaluate `H = K + U` at the end `x₁`, the potential **from the distances**
//!    ([`Simulation::true_energy`]): a missed hard-core event leaves an overlap (`U = +∞`), a
//!    missed step a pair level that disagrees with its distance (a finite `ΔH`);
//! 4. **accept** `x₁` with probability `min(1, e^{−βΔH})` (canonical; times
//!    `√(det Z(x₀)/det Z(x₁))` for [`Measure::StiffBonds`]), or only if `ΔH = 0` to within
//!    round-off (microcanonical). A rejection puts `x₀` back with every velocity
//!    reversed (the generalised HMC rule that keeps detailed balance when the refresh is only
//!    partial, as the exchange refresh is; for the canonical refresh the reversal is
//!    irrelevant), and rolls back everything the segment did (time, counters, accumulators),
//!    so summary averages are over accepted segments.
//!
//! A new configuration is chosen only at the end of a segment, never because a miss was
//! noticed (the seed warns that doing so breaks detailed balance). The dynamics is time
//! reversible and volume preserving, so with exact event times every segment is accepted
//! (`ΔH` is round-off) and the chain is plain molecular dynamics with momentum refreshes.
//!
//! **Fault injection** (scene key `hmc.fault_fraction`, the loop's `Blindfold`, set with
//! [`Simulation::set_fault_fraction`]) is a validation tool: the
//! sphere engine's event times are analytic and it misses nothing, so to show that HMC
//! repairs misses, misses are made deliberately. In each segment a pseudo-random fraction of
//! the pairs (drawn afresh per segment from the seed) is *blind*: none of its events is
//! predicted, so it flies through its hard core and its steps as a root search that missed
//! them would let it. Within a segment the dynamics is then the exact flow of a modified
//! Hamiltonian (those pairs not interacting): still reversible and volume preserving, so HMC
//! with `ΔH` of the true Hamiltonian samples the true ensemble exactly, while the same
//! segments accepted blindly (`hmc.accept = "always"`, plain dynamics with momentum refreshes)
//! sample a wrong one. A real root search's misses depend on where its grid starts and so are
//! not exactly reversible; that residual bias is what the seed accepts.

use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use serde::{Deserialize, Serialize};

use glam::DVec3;

pub use crate::analysis::block::{BlockEstimate, Blocks, block_average};
use crate::engine::model::PairModel;
use crate::engine::schedule::Scheduler;
use crate::engine::simulation::{NoSampler, SimError, Simulation, Stop};

/// Which ensemble the chain samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Ensemble {
    /// Gaussian momenta at temperature `T`, Metropolis acceptance on `ΔH`.
    Canonical,
    /// Velocities exchanged between pairs of bodies of one species, acceptance only if `ΔH = 0`.
    Microcanonical,
}

/// How segments are accepted.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Acceptance {
    /// Hybrid Monte Carlo (the default).
    Metropolis,
    /// Every segment (plain dynamics with momentum refreshes; a validation comparison).
    Always,
}

/// Which configuration measure a canonical chain samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Measure {
    /// The measure the dynamics leaves invariant (the default): for molecules with distance
    /// constraints it carries the metric factor `√det Z` (000 §II.A), as the constrained
    /// dynamics itself samples.
    #[default]
    Dynamics,
    /// The flat measure on the constraint surface, the limit of infinitely stiff bonds: the
    /// acceptance divides out `√det Z` ([`PairModel::log_metric`]; Fixman's correction).
    StiffBonds,
}

/// Settings of a chain.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HmcSettings {
    /// Ensemble.
    pub ensemble: Ensemble,
    /// Segment length `τ` in simulated time.
    pub segment_time: f64,
    /// Temperature of the canonical refresh and of `β`; for the microcanonical chain only the
    /// energy unit of the `ΔH` histogram.
    pub temperature: f64,
    /// Velocity exchanges per segment (microcanonical).
    pub exchanges: u64,
    /// Relative tolerance on `ΔH` (of `K + |U|`) within which it counts as round-off.
    pub tolerance: f64,
    /// Acceptance rule.
    pub acceptance: Acceptance,
    /// Bins of the `ΔH` histogram over `±range · T`.
    pub histogram_bins: usize,
    /// Half width of the `ΔH` histogram in units of `T`.
    pub histogram_range: f64,
    /// Seed of the chain's generator.
    pub seed: u64,
    /// The configuration measure sampled (canonical chains).
    #[serde(default)]
    pub measure: Measure,
}

/// Why a segment ended as it did.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Outcome {
    /// Accepted.
    Accepted,
    /// Rejected: hard cores overlap at the end (`ΔH = +∞`, a missed hard-core event).
    Overlap,
    /// Rejected on the energy: the Metropolis test (canonical) or `ΔH ≠ 0` (microcanonical).
    Energy,
    /// Rejected: `ΔH` is not a number (a non-finite state).
    NonFinite,
}

impl Outcome {
    /// The name used in `hmc.csv` and the summary.
    pub fn name(self) -> &'static str {
        match self {
            Outcome::Accepted => "accepted",
            Outcome::Overlap => "overlap",
            Outcome::Energy => "energy",
            Outcome::NonFinite => "non_finite",
        }
    }
}

/// What one segment did.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// Segment number (from 0, equilibration segments included).
    pub index: u64,
    /// Accepted or why not.
    pub outcome: Outcome,
    /// `H(x₁) − H(x₀)`.
    pub delta_h: f64,
    /// Kinetic energy of the chain state after the decision.
    pub kinetic: f64,
    /// Potential energy (from the distances) of the chain state after the decision.
    pub potential: f64,
    /// Events the segment executed.
    pub events: u64,
    /// Pairs whose stored level disagreed with their distance at the end (missed steps).
    pub mismatched: u64,
    /// Pairs overlapping at the end (missed hard-core events).
    pub overlaps: u64,
}

/// Counts and series of a chain (production segments only).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct HmcStats {
    /// Segments run.
    pub segments: u64,
    /// Segments accepted.
    pub accepted: u64,
    /// Rejected for an overlap.
    pub rejected_overlap: u64,
    /// Rejected on the energy.
    pub rejected_energy: u64,
    /// Rejected for a non-finite `ΔH`.
    pub rejected_non_finite: u64,
    /// Segments that ended with a missed event (mismatched level or overlap), accepted or not.
    pub segments_with_misses: u64,
    /// Events executed in rejected segments (rolled back; not in the summary's `events`).
    pub events_rejected: u64,
    /// `Σ ΔH` over finite `ΔH`, and how many.
    pub delta_h_sum: f64,
    /// Number of finite `ΔH`.
    pub delta_h_finite: u64,
    /// Largest `|ΔH|` among finite ones.
    pub delta_h_max_abs: f64,
    /// `Σ e^{−βΔH}` (an infinite `ΔH` adds 0); see [`HmcSummary::exp_minus_beta_delta_h`].
    pub exp_sum: f64,
    /// `ΔH` histogram counts over `±range · T`.
    pub histogram: Vec<u64>,
    /// `ΔH` below the histogram, above it (finite), `+∞`, and within round-off of 0.
    pub histogram_outside: (u64, u64, u64, u64),
    /// Potential energy of the chain state after each segment (the finite ones), accumulated
    /// online for its mean and block-average error: memory grows as the logarithm of the
    /// segments.
    pub potential: Blocks,
    /// Kinetic energy of the chain state after each segment (the finite ones), likewise.
    pub kinetic: Blocks,
    /// Segments whose chain state has a non-finite potential energy (overlapping bodies).
    pub overlapping_states: u64,
}

/// A hybrid Monte Carlo chain: its settings, generator, segment count and statistics.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Chain {
    /// Settings.
    pub settings: HmcSettings,
    rng: Xoshiro256PlusPlus,
    next_index: u64,
    /// Statistics of the production segments.
    pub stats: HmcStats,
    /// Whether segments are recorded in `stats` (production) or only run (equilibration).
    pub recording: bool,
    /// Every production segment, when asked for (`hmc.series`).
    pub series: Option<Vec<Segment>>,
}

impl Chain {
    /// Checks a chain read from a checkpoint against the scene's `settings` and `hmc.series`
    /// (`keep_series`): the same settings, a histogram of their bins, and counts and series
    /// that agree with each other.
    ///
    /// # Errors
    /// What does not fit.
    pub fn check_fits(&self, settings: &HmcSettings, keep_series: bool) -> Result<(), String> {
        if self.settings != *settings {
            return Err("its HMC settings are not the scene's [hmc]".into());
        }
        let s = &self.stats;
        if s.histogram.len() != settings.histogram_bins {
            return Err(format!(
                "its ΔH histogram has {} bins, the scene {}",
                s.histogram.len(),
                settings.histogram_bins
            ));
        }
        if self.series.is_some() != keep_series {
            return Err("its series of segments does not match hmc.series".into());
        }
        let decided = [
            s.accepted,
            s.rejected_overlap,
            s.rejected_energy,
            s.rejected_non_finite,
        ]
        .into_iter()
        .try_fold(0u64, u64::checked_add);
        let segments = usize::try_from(s.segments).ok();
        if decided != Some(s.segments)
            || s.delta_h_finite > s.segments
            || s.segments_with_misses > s.segments
            || s.potential.len().checked_add(s.overlapping_states) != Some(s.segments)
            || s.kinetic.len() > s.segments
            || self
                .series
                .as_ref()
                .is_some_and(|v| segments != Some(v.len()))
            || s.segments > self.next_index
        {
            return Err("its HMC counts do not agree with each other".into());
        }
        if !(s.delta_h_sum.is_finite()
            && s.delta_h_max_abs.is_finite()
            && s.delta_h_max_abs >= 0.0
            && s.exp_sum >= 0.0
            && s.potential.check().is_ok()
            && s.kinetic.check().is_ok())
        {
            return Err("its HMC sums are not valid numbers".into());
        }
        Ok(())
    }

    /// A chain with its generator seeded from `settings.seed`.
    pub fn new(settings: HmcSettings, keep_series: bool) -> Self {
        let rng = Xoshiro256PlusPlus::seed_from_u64(settings.seed ^ 0x4843_4d43_0000_0009);
        let bins = settings.histogram_bins;
        Chain {
            settings,
            rng,
            next_index: 0,
            stats: HmcStats {
                histogram: vec![0; bins],
                ..HmcStats::default()
            },
            recording: false,
            series: keep_series.then(Vec::new),
        }
    }

    /// Segments run so far (equilibration included).
    pub fn segments_run(&self) -> u64 {
        self.next_index
    }

    /// Runs one segment on `sim`, which must be at a chain state: at a re-basing of the time
    /// origin ([`Simulation::at_origin`]) with its pair levels matching its distances (a fresh
    /// simulation, or one left by the previous segment).
    ///
    /// # Errors
    /// [`SimError`] from the dynamics.
    pub fn segment<M: PairModel, S: Scheduler>(
        &mut self,
        sim: &mut Simulation<M, S>,
    ) -> Result<Segment, SimError> {
        let index = self.next_index;
        self.next_index += 1;
        sim.begin_segment(index);
        let settings = &self.settings;
        let rng = &mut self.rng;
        match settings.ensemble {
            Ensemble::Canonical => {
                sim.set_refreshed_momenta(true);
                let t = settings.temperature;
                sim.refresh_momenta(|bodies, now, masses, model| {
                    for b in bodies.iter_mut() {
                        let s = (t / masses[b.species as usize]).sqrt();
                        b.v = DVec3::new(
                            StandardNormal.sample(rng),
                            StandardNormal.sample(rng),
                            StandardNormal.sample(rng),
                        ) * s;
                    }
                    model.draw_rotations(now, t, rng);
                });
            }
            Ensemble::Microcanonical => {
                let exchanges = settings.exchanges;
                sim.refresh_momenta(|bodies, _, _, _| {
                    exchange(bodies, exchanges, rng);
                });
            }
        }
        let start = sim.save_state();
        let h0 = sim.true_energy();
        let stiff = settings.measure == Measure::StiffBonds;
        let g0 = if stiff {
            sim.model().log_metric(sim.now())
        } else {
            0.0
        };
        let events0 = sim.counters().events;
        sim.run(
            Stop::Time(settings.segment_time),
            &mut NoSampler,
            &mut |_| {},
        )?;
        sim.move_origin_here();
        let h1 = sim.true_energy();
        let g1 = if stiff {
            sim.model().log_metric(sim.now())
        } else {
            0.0
        };
        let events = sim.counters().events - events0;
        let dh = h1.total() - h0.total();
        let beta = 1.0 / settings.temperature;
        let scale = (h0.kinetic + h0.potential.abs()).max(f64::MIN_POSITIVE);
        let round_off = dh.abs() <= settings.tolerance * scale;
        let u: f64 = self.rng.random();
        let outcome = if dh.is_nan() || (g0 - g1).is_nan() {
            Outcome::NonFinite
        } else if settings.acceptance == Acceptance::Always {
            Outcome::Accepted
        } else if h1.overlaps > 0 {
            Outcome::Overlap
        } else {
            let accept = match settings.ensemble {
                Ensemble::Canonical => {
                    // The target's density ratio: e^{−βΔH}, times √(det Z₀/det Z₁) for the
                    // stiff-bond measure (the dynamics preserves the one with √det Z).
                    let log_ratio = -beta * dh + (g0 - g1);
                    log_ratio >= 0.0 || u < log_ratio.exp()
                }
                Ensemble::Microcanonical => round_off,
            };
            if accept {
                Outcome::Accepted
            } else {
                Outcome::Energy
            }
        };
        let (kinetic, potential) = if outcome == Outcome::Accepted {
            sim.repair_levels();
            (h1.kinetic, h1.potential)
        } else {
            sim.restore_state(&start, false)
                .expect("a state saved by this simulation fits it");
            sim.reverse_momenta();
            (h0.kinetic, h0.potential)
        };
        let seg = Segment {
            index,
            outcome,
            delta_h: dh,
            kinetic,
            potential,
            events,
            mismatched: h1.mismatched,
            overlaps: h1.overlaps,
        };
        if self.recording {
            self.record(&seg, beta, round_off);
        }
        Ok(seg)
    }

    fn record(&mut self, seg: &Segment, beta: f64, round_off: bool) {
        let s = &mut self.stats;
        s.segments += 1;
        match seg.outcome {
            Outcome::Accepted => s.accepted += 1,
            Outcome::Overlap => s.rejected_overlap += 1,
            Outcome::Energy => s.rejected_energy += 1,
            Outcome::NonFinite => s.rejected_non_finite += 1,
        }
        if seg.outcome != Outcome::Accepted {
            s.events_rejected += seg.events;
        }
        if seg.mismatched > 0 || seg.overlaps > 0 {
            s.segments_with_misses += 1;
        }
        let dh = seg.delta_h;
        if dh.is_finite() {
            s.delta_h_sum += dh;
            s.delta_h_finite += 1;
            s.delta_h_max_abs = s.delta_h_max_abs.max(dh.abs());
        }
        if !dh.is_nan() {
            s.exp_sum += (-beta * dh).exp();
        }
        let range = self.settings.histogram_range;
        let x = dh * beta;
        if dh == f64::INFINITY {
            s.histogram_outside.2 += 1;
        } else if x < -range {
            s.histogram_outside.0 += 1;
        } else if x >= range {
            s.histogram_outside.1 += 1;
        } else if x.is_finite() {
            let bins = s.histogram.len();
            let k = (((x + range) / (2.0 * range)) * bins as f64) as usize;
            s.histogram[k.min(bins - 1)] += 1;
        }
        if round_off {
            s.histogram_outside.3 += 1;
        }
        if seg.potential.is_finite() {
            s.potential.push(seg.potential);
        } else {
            s.overlapping_states += 1;
        }
        if seg.kinetic.is_finite() {
            s.kinetic.push(seg.kinetic);
        }
        if let Some(series) = &mut self.series {
            series.push(*seg);
        }
    }

    /// The summary of the production segments for `n` bodies.
    pub fn summary(&self, n: usize) -> HmcSummary {
        let s = &self.stats;
        let n = n as f64;
        let per_body = |x: &Blocks| {
            let b = x.estimate();
            BlockEstimate {
                mean: b.mean / n,
                error: b.error / n,
                ..b
            }
        };
        let range = self.settings.histogram_range * self.settings.temperature;
        HmcSummary {
            ensemble: match self.settings.ensemble {
                Ensemble::Canonical => "canonical",
                Ensemble::Microcanonical => "microcanonical",
            }
            .to_owned(),
            acceptance: match self.settings.acceptance {
                Acceptance::Metropolis => "metropolis",
                Acceptance::Always => "always",
            }
            .to_owned(),
            measure: match self.settings.measure {
                Measure::Dynamics => "dynamics",
                Measure::StiffBonds => "stiff-bonds",
            }
            .to_owned(),
            segment_time: self.settings.segment_time,
            temperature: self.settings.temperature,
            segments: s.segments,
            accepted: s.accepted,
            acceptance_rate: if s.segments > 0 {
                s.accepted as f64 / s.segments as f64
            } else {
                f64::NAN
            },
            rejected_by_cause: [
                ("overlap", s.rejected_overlap),
                ("energy", s.rejected_energy),
                ("non_finite", s.rejected_non_finite),
            ]
            .into_iter()
            .map(|(k, v)| (k.to_owned(), v))
            .collect(),
            segments_with_misses: s.segments_with_misses,
            events_rejected: s.events_rejected,
            delta_h_mean: if s.delta_h_finite > 0 {
                s.delta_h_sum / s.delta_h_finite as f64
            } else {
                f64::NAN
            },
            delta_h_max_abs: s.delta_h_max_abs,
            exp_minus_beta_delta_h: if s.segments > 0 {
                s.exp_sum / s.segments as f64
            } else {
                f64::NAN
            },
            delta_h_histogram: Histogram {
                low: -range,
                high: range,
                counts: s.histogram.clone(),
                below: s.histogram_outside.0,
                above: s.histogram_outside.1,
                infinite: s.histogram_outside.2,
                within_round_off: s.histogram_outside.3,
            },
            potential_energy_per_body: per_body(&s.potential),
            kinetic_energy_per_body: per_body(&s.kinetic),
            overlapping_states: s.overlapping_states,
        }
    }
}

/// Exchanges centre-of-mass velocities between `count` random pairs of bodies of one species
/// (equal masses: kinetic energy and momentum unchanged). Angular velocities are not exchanged:
/// a rod's `ω` is perpendicular to its own axis, and another rod's, along a different axis,
/// would not be (its component along the axis would be dropped and the energy would change);
/// the rotations are refreshed by the dynamics of the segments alone.
fn exchange(bodies: &mut [crate::engine::body::Body], count: u64, rng: &mut Xoshiro256PlusPlus) {
    let n_species = bodies.iter().map(|b| b.species).max().map_or(0, |s| s + 1) as usize;
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); n_species];
    for (i, b) in bodies.iter().enumerate() {
        members[b.species as usize].push(i as u32);
    }
    let n = bodies.len() as u32;
    for _ in 0..count {
        let i = rng.random_range(0..n);
        let m = &members[bodies[i as usize].species as usize];
        if m.len() < 2 {
            continue;
        }
        let k = rng.random_range(0..m.len() - 1);
        let j = if m[k] == i { m[m.len() - 1] } else { m[k] };
        let (a, b) = (i as usize, j as usize);
        let v = bodies[a].v;
        bodies[a].v = bodies[b].v;
        bodies[b].v = v;
    }
}

/// A histogram with its outliers.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Histogram {
    /// Lower edge.
    pub low: f64,
    /// Upper edge.
    pub high: f64,
    /// Counts of equal bins between the edges.
    pub counts: Vec<u64>,
    /// Below `low`.
    pub below: u64,
    /// At or above `high` (finite).
    pub above: u64,
    /// `+∞` (hard cores overlapping at the end).
    pub infinite: u64,
    /// Within round-off of zero (also counted in their bin).
    pub within_round_off: u64,
}

/// The `hmc` section of `summary.json`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HmcSummary {
    /// `canonical` or `microcanonical`.
    pub ensemble: String,
    /// `metropolis` or `always`.
    pub acceptance: String,
    /// `dynamics` or `stiff-bonds`: the configuration measure sampled.
    #[serde(default = "dynamics")]
    pub measure: String,
    /// `τ`.
    pub segment_time: f64,
    /// `T` (canonical refresh and `β`).
    pub temperature: f64,
    /// Production segments.
    pub segments: u64,
    /// Accepted ones.
    pub accepted: u64,
    /// `accepted / segments`.
    pub acceptance_rate: f64,
    /// `overlap`, `energy`, `non_finite`.
    pub rejected_by_cause: std::collections::BTreeMap<String, u64>,
    /// Segments that ended with a missed event, accepted or not.
    pub segments_with_misses: u64,
    /// Events executed in rejected segments.
    pub events_rejected: u64,
    /// Mean of the finite `ΔH`.
    pub delta_h_mean: f64,
    /// Largest finite `|ΔH|`.
    pub delta_h_max_abs: f64,
    /// `⟨e^{−βΔH}⟩` over the segments (an infinite `ΔH` counts 0). For reversible,
    /// volume-preserving segments started from the ensemble it equals the probability that a
    /// segment run backwards from an allowed state also starts in one: 1 when no segment can
    /// end in an overlap, else `1 −` the fraction of segments that end in one (the same
    /// fraction forwards and backwards). `⟨e^{−βΔH}⟩ + overlap rate = 1` is the check.
    pub exp_minus_beta_delta_h: f64,
    /// `ΔH` histogram.
    pub delta_h_histogram: Histogram,
    /// Potential energy per body of the chain states, block averaged.
    pub potential_energy_per_body: BlockEstimate,
    /// Kinetic energy per body of the chain states, block averaged.
    pub kinetic_energy_per_body: BlockEstimate,
    /// Chain states with overlapping hard cores (only when every segment is accepted).
    pub overlapping_states: u64,
}

fn dynamics() -> String {
    "dynamics".to_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocking_error_of_independent_and_correlated_series() {
        // Independent uniforms: the error is σ/√n = √(1/12)/√n within the estimate's scatter.
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(3);
        let x: Vec<f64> = (0..1 << 14).map(|_| rng.random::<f64>()).collect();
        let b = block_average(&x);
        let exact = (1.0f64 / 12.0 / x.len() as f64).sqrt();
        assert!(
            (b.error / exact - 1.0).abs() < 0.25,
            "{} vs {exact}",
            b.error
        );
        // Each value repeated 8 times: the naive error is √8 too small, blocking finds it.
        let y: Vec<f64> = x[..1 << 11]
            .iter()
            .flat_map(|&v| std::iter::repeat_n(v, 8))
            .collect();
        let b = block_average(&y);
        let exact = (1.0f64 / 12.0 / 2048.0).sqrt();
        assert!(
            (b.error / exact - 1.0).abs() < 0.3,
            "{} vs {exact}",
            b.error
        );
    }
}
