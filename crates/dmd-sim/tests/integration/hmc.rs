//! Hybrid Monte Carlo (000 §V) against exact canonical answers, with and without missed
//! events, and its detailed balance.
//!
//! The reference system is two bodies in a periodic box with a square well (hard core σ = 1,
//! well depth ε = 1 out to λ = 1.5, kT = 1): the probability that the pair is on a level is
//! exactly the Boltzmann-weighted volume of its shell, `P(s) = V_s e^{−βU_s} / Z`, with
//! `Z = Σ V_s e^{−βU_s}` (the core's weight is 0). Misses are injected deliberately
//! (`Simulation::set_fault_fraction`: the pair is blind to its events in a random fraction of
//! the segments).

use collide::Particle;
use dmd_sim::hmc::{Acceptance, Chain, Ensemble, HmcSettings, Measure, Outcome};
use dmd_sim::model::{PairModel, Stepped};
use dmd_sim::potential::Potentials;
use dmd_sim::simulation::{LoopSettings, Simulation};
use event_queue::{HeapQueue, LazyQueue, Ticket};
use glam::DVec3;

type Queue = LazyQueue<HeapQueue<Ticket>>;

const L: f64 = 5.2;

fn well() -> Potentials {
    Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY], [1.5, -1.0]])])
}

fn loop_settings(checks: bool) -> LoopSettings {
    LoopSettings {
        rebase_events: 1_000_000,
        seed: 1,
        // Missed events break the loop's invariants on purpose: no debug checks then.
        debug_check_events: u64::from(checks) * 100,
        skin: 0.1,
        start_time: 0.0,
    }
}

fn two_bodies<M: PairModel>(model: M, checks: bool) -> Simulation<M, Queue> {
    Simulation::new(
        DVec3::splat(L),
        &[DVec3::new(1.0, 1.0, 1.0), DVec3::new(3.5, 3.0, 2.0)],
        &[DVec3::new(0.3, -0.2, 0.1), DVec3::new(-0.3, 0.2, -0.1)],
        &[0, 0],
        model,
        loop_settings(checks),
    )
    .unwrap()
}

fn settings(ensemble: Ensemble, acceptance: Acceptance, seed: u64) -> HmcSettings {
    HmcSettings {
        ensemble,
        segment_time: 2.0,
        temperature: 1.0,
        exchanges: 2,
        tolerance: 1e-9,
        acceptance,
        histogram_bins: 40,
        histogram_range: 10.0,
        seed,
        measure: Measure::Dynamics,
    }
}

/// Exact level probabilities `[out of range, in the well]` of the two-body square well.
fn exact_levels() -> [f64; 2] {
    let v = L * L * L;
    let sphere = |r: f64| 4.0 / 3.0 * std::f64::consts::PI * r * r * r;
    let out = v - sphere(1.5);
    let shell = (sphere(1.5) - sphere(1.0)) * 1f64.exp();
    let z = out + shell;
    [out / z, shell / z]
}

/// Level of the chain state from its potential energy (0, −1 or +∞ for an overlap).
fn level_of(u: f64) -> usize {
    if u == 0.0 {
        0
    } else if u == -1.0 {
        1
    } else {
        2
    }
}

struct Sampled {
    fractions: [f64; 3],
    /// Standard errors of the fractions from block averages of the indicator series.
    errors: [f64; 3],
    accepted: u64,
    segments: u64,
    exp_mean: f64,
}

fn sample<M: PairModel>(sim: &mut Simulation<M, Queue>, chain: &mut Chain, n: usize) -> Sampled {
    for _ in 0..200 {
        chain.segment(sim).unwrap();
    }
    chain.recording = true;
    let mut levels = Vec::with_capacity(n);
    for _ in 0..n {
        let seg = chain.segment(sim).unwrap();
        levels.push(level_of(seg.potential));
    }
    let mut fractions = [0.0; 3];
    let mut errors = [0.0; 3];
    for k in 0..3 {
        let x: Vec<f64> = levels
            .iter()
            .map(|&l| f64::from(u8::from(l == k)))
            .collect();
        let b = dmd_sim::hmc::block_average(&x);
        fractions[k] = b.mean;
        errors[k] = b.error;
    }
    let s = chain.summary(2);
    Sampled {
        fractions,
        errors,
        accepted: s.accepted,
        segments: s.segments,
        exp_mean: s.exp_minus_beta_delta_h,
    }
}

/// Tolerance: 4.5 standard errors (block-averaged, so segment correlations are included) plus
/// the estimate's own uncertainty; a fixed seed makes the test deterministic, the margin makes
/// it robust to changes of seed.
fn assert_matches(s: &Sampled, what: &str) {
    let exact = exact_levels();
    #[allow(clippy::needless_range_loop)]
    for k in 0..2 {
        let err = s.errors[k].max(1e-4);
        assert!(
            (s.fractions[k] - exact[k]).abs() < 4.5 * err,
            "{what}: level {k} sampled {:.4} ± {:.4}, exact {:.4}",
            s.fractions[k],
            s.errors[k],
            exact[k]
        );
    }
    assert_eq!(s.fractions[2], 0.0, "{what}: a chain state overlaps");
}

#[test]
fn exact_dynamics_accepts_every_segment_and_samples_the_canonical_levels() {
    let model = Stepped::new(well(), vec![Particle::new(1.0).unwrap()], 2);
    let mut sim = two_bodies(model, true);
    let mut chain = Chain::new(
        settings(Ensemble::Canonical, Acceptance::Metropolis, 11),
        false,
    );
    let s = sample(&mut sim, &mut chain, 6000);
    assert_eq!(s.accepted, s.segments, "no event is missed: all accepted");
    assert!((s.exp_mean - 1.0).abs() < 1e-12, "{}", s.exp_mean);
    assert_matches(&s, "exact dynamics");
}

#[test]
fn missed_events_are_repaired_by_hmc_but_bias_plain_dynamics() {
    // The pair is blind in 30 % of the segments: it flies through its core and its well edge.
    let faulty = |seed| {
        let mut sim = two_bodies(
            Stepped::new(well(), vec![Particle::new(1.0).unwrap()], 2),
            false,
        );
        sim.set_fault_fraction(0.3, seed);
        sim
    };
    let mut sim = faulty(5);
    let mut chain = Chain::new(
        settings(Ensemble::Canonical, Acceptance::Metropolis, 12),
        false,
    );
    let hmc = sample(&mut sim, &mut chain, 6000);
    assert!(
        hmc.accepted < hmc.segments,
        "misses must cause rejections ({} of {})",
        hmc.accepted,
        hmc.segments
    );
    let stats = &chain.stats;
    assert!(stats.rejected_overlap > 0 && stats.rejected_energy > 0);
    // For reversible, volume-preserving segments (the blind dynamics is one) ⟨e^{−βΔH}⟩ is the
    // probability that the segment run backwards from an allowed state starts in one:
    // 1 − the rate of segments ending in an overlap. Its scatter here is that of a mean of
    // 6000 values of e^{−βΔH} ≤ e¹ (≈ 0.01), hence 0.05.
    let overlap_rate = stats.rejected_overlap as f64 / stats.segments as f64;
    assert!(
        (hmc.exp_mean + overlap_rate - 1.0).abs() < 0.05,
        "{} + {overlap_rate}",
        hmc.exp_mean
    );
    assert_matches(&hmc, "HMC with misses");

    // The same faulty segments accepted blindly: the well is under-populated and the core
    // entered; the deviation is many standard errors.
    let mut sim = faulty(5);
    let mut plain = Chain::new(settings(Ensemble::Canonical, Acceptance::Always, 12), false);
    let p = sample(&mut sim, &mut plain, 6000);
    let exact = exact_levels();
    let z = (p.fractions[1] - exact[1]).abs() / p.errors[1];
    assert!(
        z > 8.0,
        "plain dynamics with misses: well {:.4} ± {:.4} vs exact {:.4}",
        p.fractions[1],
        p.errors[1],
        exact[1]
    );
    assert!(
        p.fractions[2] > 0.0,
        "plain dynamics never left a core overlapping"
    );
}

#[test]
fn transitions_balance_in_a_tiny_system() {
    // Detailed balance: in a reversible stationary chain the number of transitions a → b
    // equals that of b → a up to counting noise, for every pair of states. With three pair
    // levels (a repulsive shoulder outside an attractive well) this is not automatic: a
    // stationary but irreversible chain would carry a net flux round 0 → 1 → 2 → 0. Misses are
    // injected so that rejections take part. The difference of two counts of a nearly
    // Poisson process has standard deviation √(sum); 5 of them are allowed.
    let pots = Potentials::from_tables(
        1,
        &[((0, 0), vec![[1.0, f64::INFINITY], [1.3, -1.0], [1.6, 0.5]])],
    );
    let model = Stepped::new(pots, vec![Particle::new(1.0).unwrap()], 2);
    let mut sim: Simulation<_, Queue> = Simulation::new(
        DVec3::splat(5.5),
        &[DVec3::new(1.0, 1.0, 1.0), DVec3::new(3.5, 3.0, 2.0)],
        &[DVec3::new(0.3, -0.2, 0.1), DVec3::new(-0.3, 0.2, -0.1)],
        &[0, 0],
        model,
        loop_settings(false),
    )
    .unwrap();
    sim.set_fault_fraction(0.3, 9);
    let mut set = settings(Ensemble::Canonical, Acceptance::Metropolis, 13);
    set.segment_time = 0.5;
    let mut chain = Chain::new(set, false);
    let state = |u: f64| match u {
        0.0 => 0,
        0.5 => 1,
        -0.5 => 2,
        _ => 3,
    };
    let mut flux = [[0u64; 4]; 4];
    let mut prev = state(sim.true_energy().potential);
    let mut rejected = 0;
    for _ in 0..60000 {
        let seg = chain.segment(&mut sim).unwrap();
        rejected += u64::from(seg.outcome != Outcome::Accepted);
        let s = state(seg.potential);
        flux[prev][s] += 1;
        prev = s;
    }
    assert!(rejected > 100, "{rejected} rejections");
    for a in 0..3 {
        assert_eq!(flux[a][3] + flux[3][a], 0, "a chain state overlaps");
        for b in a + 1..3 {
            let (ab, ba) = (flux[a][b] as f64, flux[b][a] as f64);
            assert!(
                ab.min(ba) > 100.0,
                "too few transitions {a} <-> {b}: {flux:?}"
            );
            assert!(
                (ab - ba).abs() < 5.0 * (ab + ba).sqrt(),
                "transitions {a} -> {b}: {ab}, {b} -> {a}: {ba}"
            );
        }
    }
}

#[test]
fn microcanonical_chain_keeps_the_energy_and_rejects_every_missed_step() {
    // Four bodies (two exchange pairs); the energy shell is kept exactly.
    let pos = [
        DVec3::new(1.0, 1.0, 1.0),
        DVec3::new(3.5, 3.0, 2.0),
        DVec3::new(1.0, 3.6, 4.0),
        DVec3::new(4.0, 1.2, 3.4),
    ];
    let vel = [
        DVec3::new(0.9, -0.2, 0.1),
        DVec3::new(-0.3, 0.7, -0.1),
        DVec3::new(0.2, 0.4, -0.8),
        DVec3::new(-0.8, -0.9, 0.8),
    ];
    for (fault, seed) in [(0.0, 21), (0.2, 22)] {
        let model = Stepped::new(well(), vec![Particle::new(1.0).unwrap()], 4);
        let mut sim: Simulation<_, Queue> = Simulation::new(
            DVec3::splat(L),
            &pos,
            &vel,
            &[0; 4],
            model,
            loop_settings(fault == 0.0),
        )
        .unwrap();
        sim.set_fault_fraction(fault, seed);
        let e0 = sim.true_energy().total();
        let (p0, _) = sim.momentum_and_mass();
        let mut chain = Chain::new(
            settings(Ensemble::Microcanonical, Acceptance::Metropolis, seed),
            false,
        );
        chain.recording = true;
        for _ in 0..1500 {
            let seg = chain.segment(&mut sim).unwrap();
            if seg.outcome == Outcome::Accepted {
                // Misses may be accepted only when they cancel exactly (a pair left the well
                // while another entered it unseen): ΔH = 0 is the rule.
                assert!(seg.overlaps == 0 && seg.delta_h.abs() < 1e-11, "{seg:?}");
            }
            let e = sim.true_energy().total();
            assert!((e - e0).abs() < 1e-11, "energy {e} left the shell {e0}");
        }
        let (p1, _) = sim.momentum_and_mass();
        // Reversals on rejection flip the momentum; it is conserved up to sign.
        assert!((p1 - p0).length() < 1e-12 || (p1 + p0).length() < 1e-12);
        let s = &chain.stats;
        if fault == 0.0 {
            assert_eq!(s.accepted, s.segments);
        } else {
            assert!(s.rejected_energy + s.rejected_overlap > 0);
            assert!(s.accepted > 0);
        }
    }
}
