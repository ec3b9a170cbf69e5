//! Rigid asymmetric tops on a full-attitude terraced potential (SSD/E water) through the event
//! loop: conservation of energy, momentum and angular momentum through the impulses of 003
//! Eq. 21 with full inertia tensors, no missed event on a fine verification grid, tops near
//! the separatrix and spinning fast.
//!
//! The potential is used in its own units (kJ/mol, Å, g/mol), so the time unit of these runs
//! is 0.1 ps (`1 kJ/mol = 100 g/mol·Å²/ps²`).

use dmd_sim::model::PairModel;
use dmd_sim::rotor::{Rotor, Top, TopInertia};
use dmd_sim::search::SearchSettings;
use dmd_sim::simulation::{LoopSettings, NoSampler, Simulation, Stop};
use dmd_sim::terraced::{BodySpecies, PairTerraces, Rigid, Terraced};
use event_queue::{BoundedQueue, LazyQueue, Ticket};
use glam::{DQuat, DVec3};
use potential::{
    LevelSet, RigidGeometry, RigidPairPotential, SoftStickyDipole, Steps, TerraceMap,
    TerraceOptions,
};

type Queue = LazyQueue<BoundedQueue<Ticket>>;
type Water = Rigid<SoftStickyDipole>;

/// kT of 298.15 K in kJ/mol.
const KT: f64 = 2.478_957;

fn settings(skin: f64) -> LoopSettings {
    LoopSettings {
        rebase_events: 1_000_000,
        seed: 3,
        debug_check_events: 200,
        skin,
        start_time: 0.0,
    }
}

fn inertia() -> TopInertia {
    TopInertia::new(SoftStickyDipole::INERTIA).unwrap()
}

/// The water model on evenly spaced terraces `step` apart, searched with `search`.
fn water(poses: &[DQuat], omegas: &[DVec3], step: f64, search: SearchSettings) -> Terraced<Water> {
    let ssd = SoftStickyDipole::ssd_e();
    let set = LevelSet::evenly_spaced(ssd.minimum(), step, &TerraceOptions::default()).unwrap();
    let map = TerraceMap::new(set, Steps::Uniform(step)).unwrap();
    let n = poses.len();
    Terraced::new(
        vec![BodySpecies {
            mass: SoftStickyDipole::MASS,
            inertia: inertia(),
        }],
        vec![((0, 0), PairTerraces::new(Rigid(ssd), map).unwrap())],
        &vec![0; n],
        poses,
        omegas,
        0.0,
        search,
        17,
    )
    .unwrap()
}

/// A 2 × 2 × 2 cluster of molecules `spacing` apart in the middle of a 40 Å box, attitudes
/// and angular velocities from `seed` (lab ω scaled by `spin` over thermal).
fn cluster(spacing: f64, spin: f64, seed: u64) -> (Vec<DVec3>, Vec<DVec3>, Vec<DQuat>, Vec<DVec3>) {
    use rand::SeedableRng;
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut r = Vec::new();
    for x in 0..2 {
        for y in 0..2 {
            for z in 0..2 {
                r.push(DVec3::new(x as f64, y as f64, z as f64) * spacing + 18.0);
            }
        }
    }
    let n = r.len();
    let v = dmd_sim::init::maxwell_boltzmann(&vec![SoftStickyDipole::MASS; n], 0.3 * KT, seed);
    let poses = dmd_sim::rods::random_attitudes(n, seed);
    let omegas = poses
        .iter()
        .map(|&q| spin * Top::draw(&inertia(), q, KT, &mut rng))
        .collect();
    (r, v, poses, omegas)
}

/// Total energy, linear momentum and angular momentum (orbital about the origin plus spins).
fn invariants(sim: &Simulation<Terraced<Water>, Queue>) -> Invariants {
    (
        sim.kinetic_energy() + sim.potential_energy(),
        sim.momentum_and_mass().0,
        sim.angular_momentum(),
    )
}

type Invariants = (f64, DVec3, DVec3);

/// The simulation of `model` from positions `r` and velocities `v` in a 40 Å box.
fn in_box(model: Terraced<Water>, r: &[DVec3], v: &[DVec3]) -> Simulation<Terraced<Water>, Queue> {
    Simulation::new(
        DVec3::splat(40.0),
        r,
        v,
        &vec![0; r.len()],
        model,
        settings(0.5),
    )
    .unwrap()
}

/// Runs `model` for `events` from positions `r` and velocities `v` in a 40 Å box: the
/// simulation and its invariants before and after.
fn run_in_box(
    model: Terraced<Water>,
    r: &[DVec3],
    v: &[DVec3],
    events: u64,
) -> (Simulation<Terraced<Water>, Queue>, Invariants, Invariants) {
    let mut sim = in_box(model, r, v);
    let before = invariants(&sim);
    sim.run(Stop::Events(events), &mut NoSampler, &mut |_| {})
        .unwrap();
    let after = invariants(&sim);
    (sim, before, after)
}

fn run_cluster(spin: f64, seed: u64, verify: bool) -> Simulation<Terraced<Water>, Queue> {
    let (r, v, poses, omegas) = cluster(3.0, spin, seed);
    let n = r.len();
    let mut search = SearchSettings::paper(0.02 / spin.max(1.0));
    if verify {
        search.verify_step = Some(2e-4 / spin.max(1.0));
    }
    let model = water(&poses, &omegas, 0.5 * KT, search);
    let (sim, (e0, p0, l0), (e1, p1, l1)) = run_in_box(model, &r, &v, 6_000);
    let c = sim.counters();
    let st = sim.model().search_stats();
    assert!(c.pair_events() > 3000, "{c:?}");
    assert!(c.step_in > 100 && c.step_out > 100, "{c:?}");
    // Every event at its level, every search from its own terrace.
    assert_eq!(
        (st.misfits, st.off_terrace, st.failures),
        (0, 0, 0),
        "{st:?}"
    );
    let scale_e: f64 = sim.kinetic_energy();
    assert!((e1 - e0).abs() < 1e-12 * scale_e, "E {e0} -> {e1}");
    let scale_p: f64 =
        sim.bodies().iter().map(|b| b.v.length()).sum::<f64>() * SoftStickyDipole::MASS;
    assert!((p1 - p0).length() < 1e-13 * scale_p, "p {p0} -> {p1}");
    let scale_l: f64 = sim
        .positions()
        .iter()
        .zip(sim.bodies())
        .map(|(p, b)| p.length() * b.v.length() * SoftStickyDipole::MASS)
        .sum();
    assert!(
        (l1 - l0).length() < 1e-13 * scale_l,
        "L {l0} -> {l1} (scale {scale_l})"
    );
    // The tops took part: their angular velocities changed.
    let moved = (0..n as u32)
        .filter(|&i| (sim.model().omega(i) - omegas[i as usize]).length() > 1e-3)
        .count();
    assert!(moved > n / 2, "{moved}");
    sim
}

/// A bound cluster of water molecules far from the walls: energy, momentum and angular momentum
/// (orbital and spin) through thousands of terrace crossings and reflections.
#[test]
fn a_free_water_cluster_conserves_energy_momentum_and_angular_momentum() {
    let sim = run_cluster(1.0, 5, false);
    sim.check().unwrap();
}

/// The same, spinning ten times faster than thermal, every searched stretch searched again on
/// a grid a hundred times finer: no crossing stepped over.
#[test]
fn fast_spinning_tops_miss_no_event_on_the_verification_grid() {
    let sim = run_cluster(10.0, 7, true);
    let st = sim.model().search_stats();
    assert!(st.verified > 10_000, "{st:?}");
    assert_eq!(st.verify_misses, 0, "{st:?}");
}

/// Tops started on (or next to) the separatrix of the free asymmetric top: angular velocity
/// about the intermediate axis with a tiny perturbation, and exactly on it. The exact
/// propagator (hyperbolic case) carries them through the run with every invariant kept.
#[test]
fn tops_near_the_separatrix_conserve_the_invariants() {
    let (r, v, poses, _) = cluster(3.0, 1.0, 9);
    // Body y has the smallest moment, z the intermediate one (0.6145 < 1.1550 < 1.7696).
    let omegas: Vec<DVec3> = poses
        .iter()
        .enumerate()
        .map(|(i, &q)| {
            let eps = if i % 2 == 0 { 0.0 } else { 1e-9 };
            q * DVec3::new(eps, eps, 20.0)
        })
        .collect();
    let model = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.005));
    let (sim, (e0, p0, l0), (e1, p1, l1)) = run_in_box(model, &r, &v, 3_000);
    let k = sim.kinetic_energy();
    assert!((e1 - e0).abs() < 1e-12 * k, "E {e0} -> {e1}");
    assert!((p1 - p0).length() < 1e-9, "p {p0} -> {p1}");
    assert!(
        (l1 - l0).length() < 1e-9 * l0.length().max(1.0),
        "L {l0} -> {l1}"
    );
    let st = sim.model().search_stats();
    assert_eq!(
        (st.misfits, st.off_terrace, st.failures),
        (0, 0, 0),
        "{st:?}"
    );
    sim.check().unwrap();
}

/// Saved and restored, a top's rotation is the same bit for bit; the model's rotational
/// degrees of freedom are three per body.
#[test]
fn the_tops_state_round_trips_and_counts_three_rotations_per_body() {
    let (_, _, poses, omegas) = cluster(3.0, 1.0, 11);
    let mut a = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.02));
    assert_eq!(a.rotational_dof(), 3.0 * poses.len() as f64);
    let saved = a.extra_state();
    let b = {
        let mut b = water(&poses, &omegas, 0.5 * KT, SearchSettings::paper(0.02));
        a.scale_rotations(0.3, 1.7);
        b.set_extra_state(&saved).unwrap();
        b
    };
    a.set_extra_state(&saved).unwrap();
    for i in 0..poses.len() as u32 {
        assert_eq!(a.attitude(i, 0.123), b.attitude(i, 0.123));
        assert_eq!(a.omega(i), b.omega(i));
    }
    assert!(a.set_extra_state(&saved[1..]).is_err());
}

// ----- the event loop against an independent integration of the same terraced dynamics -----

/// A top of the reference integration: centre and velocity (lab), attitude (body → lab) and
/// angular velocity in the body frame.
#[derive(Clone, Copy, Debug)]
struct RefTop {
    r: DVec3,
    v: DVec3,
    q: DQuat,
    w: DVec3,
}

/// What an event did to its pair's terrace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Turn {
    /// Crossed to the terrace above (`U` rising).
    Up,
    /// Crossed to the terrace below.
    Down,
    /// Bounced off the step, the terrace kept.
    Reflected,
}

/// `q ⊗ (0, w)`, the Hamilton product with a pure quaternion.
fn times_pure(q: DQuat, w: DVec3) -> DQuat {
    q * DQuat::from_xyzw(w.x, w.y, w.z, 0.0)
}

/// Torque-free motion over `dt`: the centre on a straight line, attitude and body-frame angular
/// velocity by one classical RK4 step of `q̇ = ½ q ⊗ (0, ω)` and Euler's equations
/// `I ω̇ = (Iω) × ω`, the quaternion renormalised.
fn rk4(moments: DVec3, top: &RefTop, dt: f64) -> RefTop {
    let rate = |q: DQuat, w: DVec3| (times_pure(q, w) * 0.5, (moments * w).cross(w) / moments);
    let (q0, w0) = (top.q, top.w);
    let (q1, w1) = rate(q0, w0);
    let (q2, w2) = rate(q0 + q1 * (0.5 * dt), w0 + w1 * (0.5 * dt));
    let (q3, w3) = rate(q0 + q2 * (0.5 * dt), w0 + w2 * (0.5 * dt));
    let (q4, w4) = rate(q0 + q3 * dt, w0 + w3 * dt);
    RefTop {
        r: top.r + top.v * dt,
        v: top.v,
        q: (q0 + (q1 + q2 * 2.0 + q3 * 2.0 + q4) * (dt / 6.0)).normalize(),
        w: w0 + (w1 + w2 * 2.0 + w3 * 2.0 + w4) * (dt / 6.0),
    }
}

/// The terraced dynamics integrated with a fixed step and none of the engine's propagators,
/// searches or impulse code: RK4 between events, terrace changes read from the smooth pair
/// energy after every step and located by bisection, the impulse of 003 Eq. 21 solved here.
struct Reference {
    ssd: SoftStickyDipole,
    map: TerraceMap,
    mass: f64,
    moments: DVec3,
    step: f64,
    /// Bisections stop at this width (time).
    tol: f64,
    t: f64,
    tops: Vec<RefTop>,
    /// `(i, j, terrace)` of every pair, the terrace changed only by events.
    pairs: Vec<(usize, usize, usize)>,
}

impl Reference {
    fn new(ssd: SoftStickyDipole, map: TerraceMap, step: f64, tol: f64, tops: Vec<RefTop>) -> Self {
        let mut r = Reference {
            ssd,
            map,
            mass: SoftStickyDipole::MASS,
            // The moments the engine's tops have (water's rounded published moments made
            // exactly planar), so that both integrate the same bodies.
            moments: inertia().principal(),
            step,
            tol,
            t: 0.0,
            tops,
            pairs: Vec::new(),
        };
        for i in 0..r.tops.len() {
            for j in i + 1..r.tops.len() {
                let k = r.terrace(&r.tops, i, j);
                r.pairs.push((i, j, k));
            }
        }
        r
    }

    fn advanced(&self, dt: f64) -> Vec<RefTop> {
        self.tops
            .iter()
            .map(|top| rk4(self.moments, top, dt))
            .collect()
    }

    fn geometry(tops: &[RefTop], i: usize, j: usize) -> RigidGeometry {
        RigidGeometry::new(tops[i].r - tops[j].r, tops[i].q, tops[j].q)
    }

    fn terrace(&self, tops: &[RefTop], i: usize, j: usize) -> usize {
        let u = self.ssd.energy(&Self::geometry(tops, i, j));
        self.map.terrace_of(u).unwrap()
    }

    /// `U̇ = −F·(v_i − v_j) − τ_i·ω_i − τ_j·ω_j` (`F` the force on `i`, lab frame).
    fn rate(&self, tops: &[RefTop], i: usize, j: usize) -> f64 {
        let e = self.ssd.evaluate(&Self::geometry(tops, i, j)).unwrap();
        let (a, b) = (&tops[i], &tops[j]);
        -(e.force.dot(a.v - b.v) + e.torque_i.dot(a.q * a.w) + e.torque_j.dot(b.q * b.w))
    }

    /// The first time in the step `(0, dt]` (which ends in `end`) at which pair `(i, j)` is off
    /// terrace `k`, to within `tol` from above; `None` if it stays on it.
    fn leaves(&self, (i, j, k): (usize, usize, usize), dt: f64, end: &[RefTop]) -> Option<f64> {
        let off = |tau: f64| self.terrace(&self.advanced(tau), i, j) != k;
        let mut hi = dt;
        if self.terrace(end, i, j) == k {
            // On the terrace at both ends, the pair can only have left and come back if `U`
            // turned inside the step: bisect `U̇` for the turn and look there.
            let r0 = self.rate(&self.tops, i, j);
            if r0 * self.rate(end, i, j) >= 0.0 {
                return None;
            }
            let mut lo = 0.0;
            while hi - lo > self.tol {
                let mid = 0.5 * (lo + hi);
                if self.rate(&self.advanced(mid), i, j) * r0 > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            if !off(hi) {
                return None;
            }
        }
        // Bisection, each trial integrated afresh from the step's start.
        let mut lo = 0.0;
        while hi - lo > self.tol {
            let mid = 0.5 * (lo + hi);
            if off(mid) {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Some(hi)
    }

    /// Runs to `t_end`: every event's time, what it did and the state just after it.
    fn run(&mut self, t_end: f64) -> Vec<(f64, Turn, Vec<RefTop>)> {
        let mut events = Vec::new();
        while self.t < t_end {
            let dt = self.step.min(t_end - self.t);
            let end = self.advanced(dt);
            let first = (0..self.pairs.len())
                .filter_map(|p| self.leaves(self.pairs[p], dt, &end).map(|t| (t, p)))
                .min_by(|a, b| a.0.total_cmp(&b.0));
            match first {
                None => {
                    self.tops = end;
                    self.t += dt;
                }
                Some((t, p)) => {
                    // The impulse acts at the first state found off the terrace, within `tol`
                    // past the level; the next step starts there.
                    self.tops = self.advanced(t);
                    self.t += t;
                    let turn = self.impulse(p);
                    events.push((self.t, turn, self.tops.clone()));
                    // A wrong impulse can leave a pair off its terrace, "crossing" at every
                    // bisection: fail rather than creep on.
                    assert!(events.len() < 1000, "runaway events at {}", self.t);
                }
            }
        }
        events
    }

    /// The impulse of 003 Eq. 21 on pair `p`, which has just left its terrace: along the
    /// generalised force `G = (F, −F, τ_i, τ_j)` in the mass metric `M` (masses and world
    /// inertias, `I_w⁻¹ = q I⁻¹ q⁻¹`), `Δu = λ M⁻¹ G`, which changes the kinetic energy by
    /// `λ G·u + ½ λ² G·M⁻¹G`. That change is `−ΔV`, the step of the terrace map, if a real root
    /// exists (the one that vanishes with `ΔV`: the pair goes on); else it is 0 with `λ ≠ 0`,
    /// `G·u` reversed: a reflection, the pair stays on its terrace.
    fn impulse(&mut self, p: usize) -> Turn {
        let (i, j, k) = self.pairs[p];
        let next = self.terrace(&self.tops, i, j);
        assert_eq!(next.abs_diff(k), 1, "two levels crossed in one bisection");
        let dv = self.map.energies()[next] - self.map.energies()[k];
        let e = self
            .ssd
            .evaluate(&Self::geometry(&self.tops, i, j))
            .unwrap();
        let (a, b) = (self.tops[i], self.tops[j]);
        // The torques in each body's frame, where the inertia is diagonal.
        let (ti, tj) = (a.q.inverse() * e.torque_i, b.q.inverse() * e.torque_j);
        let gu = e.force.dot(a.v - b.v) + ti.dot(a.w) + tj.dot(b.w);
        let gmg = 2.0 * e.force.length_squared() / self.mass
            + (ti * ti / self.moments).element_sum()
            + (tj * tj / self.moments).element_sum();
        // ½ G·M⁻¹G λ² + G·u λ + ΔV = 0.
        let disc = gu * gu - 2.0 * gmg * dv;
        let (lambda, turn) = if disc > 0.0 {
            self.pairs[p].2 = next;
            let turn = if next > k { Turn::Up } else { Turn::Down };
            ((-gu + disc.sqrt().copysign(gu)) / gmg, turn)
        } else {
            (-2.0 * gu / gmg, Turn::Reflected)
        };
        self.tops[i].v += lambda * e.force / self.mass;
        self.tops[j].v -= lambda * e.force / self.mass;
        self.tops[i].w += lambda * ti / self.moments;
        self.tops[j].w += lambda * tj / self.moments;
        turn
    }

    /// Kinetic energy plus the terrace energies of the pairs.
    fn energy(&self) -> f64 {
        let kinetic = |t: &RefTop| {
            0.5 * self.mass * t.v.length_squared() + 0.5 * (self.moments * t.w * t.w).element_sum()
        };
        let terraces = self.pairs.iter().map(|&(_, _, k)| self.map.energies()[k]);
        self.tops.iter().map(kinetic).sum::<f64>() + terraces.sum::<f64>()
    }
}

/// The engine's state of every body now, as the reference holds it: centres relative to
/// `centre`, `w` in the body frame from the spin angular momentum and the attitude.
fn engine_state(sim: &Simulation<Terraced<Water>, Queue>, centre: DVec3) -> Vec<RefTop> {
    let moments = inertia().principal();
    let r = sim.positions();
    (0..r.len())
        .map(|i| {
            let q = sim.model().attitude(i as u32, sim.now()).unwrap();
            RefTop {
                r: r[i] - centre,
                v: sim.bodies()[i].v,
                q,
                w: (q.inverse() * sim.model().spin(i as u32, 0)) / moments,
            }
        })
        .collect()
}

/// The largest differences of two states: centres, velocities, attitudes (up to the
/// quaternion's sign) and lab angular velocities.
fn state_difference(a: &[RefTop], b: &[RefTop]) -> [f64; 4] {
    let mut d = [0.0f64; 4];
    for (x, y) in a.iter().zip(b) {
        let dq = (x.q - y.q).length().min((x.q + y.q).length());
        let dw = (x.q * x.w - y.q * y.w).length();
        let here = [(x.r - y.r).length(), (x.v - y.v).length(), dq, dw];
        for (d, e) in d.iter_mut().zip(here) {
            *d = d.max(e);
        }
    }
    d
}

/// Four numbers in scientific notation.
fn sci(d: [f64; 4]) -> String {
    format!("{:.1e} {:.1e} {:.1e} {:.1e}", d[0], d[1], d[2], d[3])
}

/// Three SSD/E molecules in a chain of hydrogen bonds, tilted a little off the bonds and moving
/// slowly, stay bound and cross the kT/2 terraces of their wells back and forth; every pair has
/// events, and some bounce off steps they cannot climb. The event loop (exact torque-free tops,
/// root searches, `collide::terrace`) and a fixed-step integration of the same terraced
/// dynamics written here execute the same events, of the same kinds, in the same order and at
/// the same times, with the same states after every event and at the end.
///
/// The differences are the reference's: its RK4 error falls as h⁴ down to h = 2.5·10⁻⁴ (about
/// 2·10⁻¹² in event times), where the bisection's width, amplified from event to event, takes
/// over. The bounds below leave a margin of at least 50 over that; the trajectory of one velocity
/// component changed by 10⁻⁶ of itself, or of an impulse with the wrong inertia or step, misses
/// them by orders of magnitude.
#[test]
fn water_molecules_follow_a_tight_integration_of_the_terraced_dynamics() {
    let ssd = SoftStickyDipole::ssd_e();
    let step = 0.5 * KT;
    let set = LevelSet::evenly_spaced(ssd.minimum(), step, &TerraceOptions::default()).unwrap();
    let map = TerraceMap::new(set, Steps::Uniform(step)).unwrap();
    let bond = SoftStickyDipole::hydrogen_bond(2.8);
    let tilts = [
        DVec3::new(0.05, -0.03, 0.02),
        DVec3::new(-0.02, 0.04, 0.03),
        DVec3::new(0.03, 0.02, -0.04),
    ];
    let velocities = [
        DVec3::new(0.12, -0.05, 0.08),
        DVec3::new(-0.12, 0.05, -0.08),
        DVec3::new(0.02, 0.1, -0.06),
    ];
    let spins = [
        DVec3::new(0.6, -0.9, 0.4),
        DVec3::new(-0.5, 0.7, 0.8),
        DVec3::new(0.3, 0.5, -0.7),
    ];
    // Each molecule the acceptor of the one before, centred on the origin for the reference
    // (positions near 0 keep its many small steps free of round-off) and on `centre` in a
    // 40 Å box for the engine.
    let mut start = Vec::new();
    let (mut r, mut q) = (DVec3::ZERO, DQuat::IDENTITY);
    for k in 0..3 {
        start.push(RefTop {
            r,
            v: velocities[k],
            q: DQuat::from_scaled_axis(tilts[k]) * q,
            w: spins[k],
        });
        r -= q * bond.r_ij;
        q *= bond.q_j;
    }
    let mean = start.iter().map(|t| t.r).sum::<DVec3>() / 3.0;
    for t in &mut start {
        t.r -= mean;
    }
    let centre = DVec3::splat(20.0);
    let t_end = 1.3; // 130 fs

    let mut reference = Reference::new(ssd, map, 2.5e-4, 1e-14 * t_end, start.clone());
    let e0 = reference.energy();
    let events = reference.run(t_end);
    let crossings = events.iter().filter(|e| e.1 != Turn::Reflected).count();
    let reflections = events.len() - crossings;
    assert!(
        crossings > 60 && reflections > 10,
        "{crossings}, {reflections}"
    );
    // A check of the reference itself: kinetic plus terrace energy is kept through its impulses.
    assert!((reference.energy() - e0).abs() < 1e-12 * e0.abs());

    let poses: Vec<DQuat> = start.iter().map(|t| t.q).collect();
    let omegas: Vec<DVec3> = start.iter().map(|t| t.q * t.w).collect();
    let model = water(&poses, &omegas, step, SearchSettings::paper(0.02));
    let r: Vec<DVec3> = start.iter().map(|t| centre + t.r).collect();
    let v: Vec<DVec3> = start.iter().map(|t| t.v).collect();
    let mut sim = in_box(model, &r, &v);
    // One event at a time (virtual events and list updates included), each pair event held
    // against the reference's next one.
    let mut seen = 0;
    let mut worst_time = 0.0f64;
    let mut worst_state = [0.0f64; 4];
    while seen < events.len() && sim.time() < t_end {
        let c0 = sim.counters();
        sim.run(Stop::Events(1), &mut NoSampler, &mut |_| {})
            .unwrap();
        let c = sim.counters();
        let turn = if c.step_in > c0.step_in {
            Turn::Up
        } else if c.step_out > c0.step_out {
            Turn::Down
        } else if c.step_reflect > c0.step_reflect {
            Turn::Reflected
        } else {
            continue;
        };
        let (t, turn_ref, state) = &events[seen];
        assert_eq!(
            turn,
            *turn_ref,
            "event {seen} at {} (reference {t})",
            sim.time()
        );
        worst_time = worst_time.max((sim.time() - t).abs());
        let d = state_difference(&engine_state(&sim, centre), state);
        for (w, d) in worst_state.iter_mut().zip(d) {
            *w = w.max(d);
        }
        seen += 1;
    }
    // Then on to the end of the stretch, with no further pair event.
    assert!(sim.time() < t_end, "{seen} of {} events", events.len());
    sim.run(Stop::Time(t_end - sim.time()), &mut NoSampler, &mut |_| {})
        .unwrap();
    let c = sim.counters();
    assert_eq!(
        (c.pair_events(), c.step_reflect, c.core),
        (events.len() as u64, reflections as u64, 0)
    );
    assert_eq!(sim.anomalies().total(), 0);
    let at_end = state_difference(&engine_state(&sim, centre), &reference.tops);
    // Scales: the largest speed and angular velocity met.
    let tops = || events.iter().flat_map(|e| e.2.iter());
    let v_scale = tops().map(|t| t.v.length()).fold(0.0, f64::max);
    let w_scale = tops().map(|t| t.w.length()).fold(0.0, f64::max);
    let relative = |d: [f64; 4]| [d[0], d[1] / v_scale, d[2], d[3] / w_scale];
    let (worst_state, at_end) = (relative(worst_state), relative(at_end));
    eprintln!(
        "{} events ({crossings} crossings, {reflections} reflections) in {t_end}: event times to \
         {worst_time:.1e}; |dr| (Å), |dv|, |dq|, |dω| (relative) after events {}, at the end {}",
        events.len(),
        sci(worst_state),
        sci(at_end)
    );
    assert!(worst_time < 1e-10, "{worst_time:e}");
    for d in [worst_state, at_end] {
        assert!(d.iter().all(|&x| x < 1e-9), "{}", sci(d));
    }
}
