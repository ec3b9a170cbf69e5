//! Hard spherocylinders: uniaxial rigid bodies made of a segment of length `L` and every point
//! within `D/2` of it (a cylinder with hemispherical caps), colliding elastically, with no
//! potential but the hard core.
//!
//! **Free motion.** Each body's centre moves on the loop's straight line; its axis turns as the
//! exact linear rotor of the terraced rods (a [`LinearRotor`] behind the shared [`Rotor`] trait,
//! anchored at the body's last change, no spin about the axis).
//!
//! **Event times.** Two bodies touch when the distance `d(t)` between their axis segments
//! (closest points of two segments, [`closest_points`], exact for parallel segments) falls to
//! `D_ij = (D_i + D_j)/2`. Along the free motion a point at arm `s` on segment `i` moves at
//! `v_i + ω_i × s u_i`, so `d` is Lipschitz with the constant
//! `B = |v_i − v_j| + h_i |ω_i| + h_j |ω_j|` (`h = L/2`), and `d(t) − D_ij ≥ g − B τ` a time `τ`
//! after a sample of gap `g`. Sharper, as the bodies are convex: the gap is at least their
//! separation along the fixed normal `n` of the sample's closest points, which closes no faster
//! than `B_n = −n·(v_i − v_j) + h_i |n × ω_i| + h_j |n × ω_j| ≤ B` (a pair with `B_n ≤ 0` never
//! meets again). The prediction is conservative advancement: from the start of the window in
//! which the centres are within the reach `h_i + h_j + D_ij`, step `τ ← τ + (g + ε)/B_n`, which
//! can overshoot a contact by at most an overlap `ε` (a relative
//! [`SLACK`] of `D_ij`: grazes shallower than that are round-off), until a sample lies inside
//! the core; the crossing in that last step is then refined by the Illinois false position to
//! round-off. A prediction that takes [`MAX_STEPS`] samples (a long near-graze) ends in a virtual
//! event at its last sample, from which the next call continues; nothing is saved, since both
//! bodies are unchanged when a virtual event comes due. Predictions from the same state are the
//! same numbers, so a run continued from a checkpoint is bit-identical.
//!
//! **Impulses.** At contact the impulse acts along the unit normal `n` between the closest
//! points, at arms `s_i u_i` and `s_j u_j` from the centres: `collide::contact` with
//! `collide::LinearBody` views of the two bodies (the terrace rule of 003 Eq. 21 with `F = n`),
//! `ΔV = +∞`. The torques `s u × n` are perpendicular to the axes, so a body never gains spin
//! about its axis, and both lines of action lie on the line through the closest points, so
//! energy, momentum and angular momentum are conserved to round-off.

use collide::{CollideError, Contact, LinearBody, Velocity, contact};
use glam::DVec3;
use rigid_free::LinearRotor;

use crate::engine::event::{Boundary, Kind};
use crate::engine::model::{
    Executed, OVERLAP_TOLERANCE, Pair, PairClass, PairModel, PairSetupError, Report,
};
use crate::engine::saved::{StateReader, push_count};
use crate::models::rotor::{Anchored, Rotations, Rotor};
use crate::models::search::bracket;

/// Samples of one prediction before it ends in a virtual event.
pub const MAX_STEPS: u32 = 256;

/// The overlap, relative to the contact distance, that one step of the advancement may reach
/// before the crossing is refined (and the depth below which a graze counts as round-off).
pub const SLACK: f64 = 1e-10;

/// One species: the shape, mass and moment of inertia of its bodies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Spherocylinder {
    /// Length `L` of the axis segment (length, ≥ 0; 0 is a hard sphere).
    pub length: f64,
    /// Diameter `D` of the hard shell (length, > 0).
    pub diameter: f64,
    /// Mass.
    pub mass: f64,
    /// Moment of inertia about an axis through the centre perpendicular to the body's own.
    pub inertia: f64,
}

/// The closest points of segments `c_i + s u_i` (`|s| ≤ h_i`) and `c_j + t u_j` (`|t| ≤ h_j`)
/// with unit axes and `r = c_i − c_j`: `(s, t, w)` with `w = r + s u_i − t u_j`, whose length is
/// the segments' distance. For parallel axes (`1 − (u_i·u_j)² ≤ 1e-12`) any pair of closest
/// points is one: `s = 0`, then `t`, then `s` clamped again, which is exact there.
#[inline]
pub fn closest_points(r: DVec3, ui: DVec3, hi: f64, uj: DVec3, hj: f64) -> (f64, f64, DVec3) {
    let b = ui.dot(uj);
    let c = ui.dot(r);
    let f = uj.dot(r);
    let denom = 1.0 - b * b;
    // For a given t the best s is b t − c; for a given s the best t is b s + f.
    let mut s = if denom > 1e-12 {
        ((b * f - c) / denom).clamp(-hi, hi)
    } else {
        0.0
    };
    let mut t = b * s + f;
    if t < -hj || t > hj {
        t = t.clamp(-hj, hj);
        s = (b * t - c).clamp(-hi, hi);
    }
    (s, t, r + s * ui - t * uj)
}

/// Counters of the model's predictions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct Stats {
    /// Predictions (and continuations after virtual events).
    predictions: u64,
    /// Samples of the segment distance taken by the advancement.
    samples: u64,
    /// Samples taken by the refinement of crossings.
    refinements: u64,
    /// Predictions that ended in a virtual event.
    virtuals: u64,
}

impl Stats {
    const NUMBERS: usize = 4;

    fn counts(&self) -> [u64; Self::NUMBERS] {
        [
            self.predictions,
            self.samples,
            self.refinements,
            self.virtuals,
        ]
    }
}

/// Hard spherocylinders (module documentation).
#[derive(Clone, Debug)]
pub struct Spherocylinders {
    species: Vec<Spherocylinder>,
    rot: Rotations<LinearRotor>,
    reach: f64,
    stats: Stats,
}

/// What the advancement watches of one pair at a time `τ` after `now`.
struct Flight {
    dr: DVec3,
    dv: DVec3,
    ri: LinearRotor,
    rj: LinearRotor,
    /// `now` minus each rotor's anchor.
    ti: f64,
    tj: f64,
    hi: f64,
    hj: f64,
    core: f64,
}

impl Flight {
    /// The gap `d − D_ij` at `τ` after `now`.
    #[inline(always)]
    fn gap(&self, tau: f64) -> f64 {
        self.sample(tau).0
    }

    /// The gap at `τ` and the fastest rate at which it can close from then on: the rate of the
    /// bodies' separation along the fixed normal `n` of the closest points at `τ`,
    /// `−n·Δv + h_i |n × ω_i| + h_j |n × ω_j|` (`NaN` without a normal). Two convex bodies are
    /// at least as far apart as their separation along any fixed direction, `n·Δr(τ') −
    /// h_i |n·u_i(τ')| − h_j |n·u_j(τ')| − D_ij`, which equals the gap at `τ` and falls no faster
    /// than that rate: `n·u` changes at `u·(n × ω)`, and the centres' part is linear.
    #[inline(always)]
    fn sample(&self, tau: f64) -> (f64, f64) {
        let r = self.dr + self.dv * tau;
        let (_, _, w) = closest_points(
            r,
            self.ri.pose(self.ti + tau),
            self.hi,
            self.rj.pose(self.tj + tau),
            self.hj,
        );
        let d = w.length();
        let n = w / d;
        let closing = -n.dot(self.dv)
            + self.hi * n.cross(Rotor::omega(&self.ri)).length()
            + self.hj * n.cross(Rotor::omega(&self.rj)).length();
        (d - self.core, closing)
    }

    /// The Lipschitz constant of the segments' distance along the flight.
    fn bound(&self) -> f64 {
        self.dv.length()
            + self.hi * Rotor::omega(&self.ri).length()
            + self.hj * Rotor::omega(&self.rj).length()
    }

    /// The rate of change of the distance at `τ` along the normal of the closest points
    /// (negative: approaching).
    fn rate(&self, tau: f64) -> f64 {
        let (ui, uj) = (self.ri.pose(self.ti + tau), self.rj.pose(self.tj + tau));
        let (s, t, w) = closest_points(self.dr + self.dv * tau, ui, self.hi, uj, self.hj);
        let (wi, wj) = (Rotor::omega(&self.ri), Rotor::omega(&self.rj));
        let u = self.dv + wi.cross(s * ui) - wj.cross(t * uj);
        w.dot(u)
    }
}

/// Illinois false position on `[a, b]` with `g(a) > 0 ≥ g(b)`: a time at which `g ≤ 0` within
/// round-off of the crossing (the bracket shrinks to adjacent floats or `g` vanishes), and the
/// number of samples.
fn refine(g: impl Fn(f64) -> f64, mut a: f64, mut ga: f64, mut b: f64, mut gb: f64) -> (f64, u64) {
    let mut samples = 0;
    let mut side = 0i8;
    for _ in 0..200 {
        if gb == 0.0 {
            break;
        }
        let mut x = (a * gb - b * ga) / (gb - ga);
        if !(x > a && x < b) {
            x = 0.5 * (a + b);
            if !(x > a && x < b) {
                break;
            }
        }
        let gx = g(x);
        samples += 1;
        if gx > 0.0 {
            a = x;
            ga = gx;
            if side == 1 {
                gb *= 0.5;
            }
            side = 1;
        } else {
            b = x;
            gb = gx;
            if side == -1 {
                ga *= 0.5;
            }
            side = -1;
        }
    }
    (b, samples)
}

impl Spherocylinders {
    /// Bodies of `species`; body `i` is of species `body_species[i]` with axis `axes[i]` and
    /// lab angular velocity `omegas[i]` (its part along the axis dropped) at time 0.
    ///
    /// # Errors
    /// A description naming the species or body whose numbers are unusable.
    pub fn new(
        species: Vec<Spherocylinder>,
        body_species: &[u32],
        axes: &[DVec3],
        omegas: &[DVec3],
    ) -> Result<Self, String> {
        for (k, s) in species.iter().enumerate() {
            let ok = |x: f64| x.is_finite() && x > 0.0;
            if !(s.length.is_finite() && s.length >= 0.0) {
                return Err(format!("species {k}: length {} is not ≥ 0", s.length));
            }
            for (what, x) in [
                ("diameter", s.diameter),
                ("mass", s.mass),
                ("inertia", s.inertia),
            ] {
                if !ok(x) {
                    return Err(format!("species {k}: {what} {x} is not positive"));
                }
            }
        }
        if body_species.len() != axes.len() || axes.len() != omegas.len() {
            return Err("one species, axis and angular velocity per body".to_owned());
        }
        let rods = axes
            .iter()
            .zip(omegas)
            .zip(body_species)
            .enumerate()
            .map(|(i, ((&a, &w), &s))| {
                let sp = species
                    .get(s as usize)
                    .ok_or_else(|| format!("body {i}: species {s} does not exist"))?;
                LinearRotor::start(&sp.inertia, a, w)
                    .map(|rotor| Anchored { rotor, t: 0.0 })
                    .map_err(|e| format!("body {i}: {e}"))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut reach = 0.0f64;
        for a in &species {
            for b in &species {
                reach = reach.max(0.5 * (a.length + b.length) + 0.5 * (a.diameter + b.diameter));
            }
        }
        let inertia = species.iter().map(|s| s.inertia).collect();
        Ok(Spherocylinders {
            species,
            rot: Rotations::new(rods, body_species, inertia),
            reach,
            stats: Stats::default(),
        })
    }

    /// The unit axis of body `i` at `now`.
    pub fn axis_at(&self, i: u32, now: f64) -> DVec3 {
        self.rot.bodies[i as usize].pose(now)
    }

    /// The contact distance and half-lengths of species `si`, `sj`.
    #[inline(always)]
    fn shape(&self, si: u32, sj: u32) -> (f64, f64, f64) {
        let (a, b) = (self.species[si as usize], self.species[sj as usize]);
        (
            0.5 * (a.diameter + b.diameter),
            0.5 * a.length,
            0.5 * b.length,
        )
    }

    /// The segments' distance of pair `(i, j)` at `now` and separation `dr`, and the contact
    /// distance.
    pub fn distance(&self, i: u32, j: u32, si: u32, sj: u32, now: f64, dr: DVec3) -> (f64, f64) {
        let (core, hi, hj) = self.shape(si, sj);
        let (_, _, w) = closest_points(dr, self.axis_at(i, now), hi, self.axis_at(j, now), hj);
        (w.length(), core)
    }

    fn flight(&self, pair: &Pair) -> Flight {
        let (core, hi, hj) = self.shape(pair.si, pair.sj);
        let (ri, rj) = (
            self.rot.bodies[pair.i as usize],
            self.rot.bodies[pair.j as usize],
        );
        Flight {
            dr: pair.dr,
            dv: pair.dv,
            ri: ri.rotor,
            rj: rj.rotor,
            ti: pair.now - ri.t,
            tj: pair.now - rj.t,
            hi,
            hj,
            core,
        }
    }

    /// The next contact of a pair within `horizon` from now (module documentation).
    fn advance(&mut self, pair: &Pair, horizon: f64) -> Option<(f64, Kind)> {
        self.stats.predictions += 1;
        let fl = self.flight(pair);
        let reach = fl.hi + fl.hj + fl.core;
        let (enter, exit) = bracket(pair.dr, pair.dv, reach * reach)?;
        let end = exit.min(horizon);
        let b = fl.bound();
        // Written so that a NaN bound or window counts as nothing to find.
        let (in_time, moving) = (enter <= end, b > 0.0);
        if !in_time || !moving {
            // Out of reach before the horizon, or nothing moves (the gap stays as it is).
            return None;
        }
        let slack = SLACK * fl.core;
        let mut tau = enter;
        let mut last: Option<(f64, f64)> = None;
        for _ in 0..MAX_STEPS {
            let (g, closing) = fl.sample(tau);
            self.stats.samples += 1;
            if g.is_nan() {
                return None;
            }
            if g > 0.0 && closing <= 0.0 {
                // Separated along a fixed direction that they can only widen: never again.
                return None;
            }
            if g <= 0.0 {
                match last {
                    Some((a, ga)) => {
                        let (t, n) = refine(|x| fl.gap(x), a, ga, tau, g);
                        self.stats.refinements += n;
                        return Some((t, Kind::Pair(Boundary::Inner)));
                    }
                    // In contact at the first sample (the round-off of the collision just
                    // executed, or a pair started touching): an event now if approaching.
                    None if fl.rate(tau) < 0.0 => {
                        return Some((tau, Kind::Pair(Boundary::Inner)));
                    }
                    None => {}
                }
            } else {
                last = Some((tau, g));
            }
            if tau >= end {
                return None;
            }
            // The separating-plane rate where the gap has a normal, else the global bound (a
            // NaN rate fails the comparison and takes the bound).
            let rate = if g > 0.0 && closing < b { closing } else { b };
            tau = (tau + (g.max(0.0) + slack) / rate).min(end);
        }
        self.stats.virtuals += 1;
        Some((tau, Kind::Virtual))
    }
}

impl PairModel for Spherocylinders {
    fn reach(&self) -> f64 {
        self.reach
    }

    fn n_species(&self) -> usize {
        self.species.len()
    }

    fn mass(&self, s: u32) -> f64 {
        self.species[s as usize].mass
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let (d, core) = self.distance(pair.i, pair.j, pair.si, pair.sj, pair.now, pair.dr);
        if d * d < core * core * (1.0 - OVERLAP_TOLERANCE) {
            return Err(PairSetupError::Overlap { distance: d, core });
        }
        Ok(())
    }

    #[inline]
    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        self.advance(pair, f64::INFINITY)
    }

    const PRUNES: bool = true;

    #[inline]
    fn predict_before(&mut self, pair: &Pair, horizon: f64) -> Option<(f64, Kind)> {
        self.advance(pair, horizon)
    }

    fn resume(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        self.advance(pair, f64::INFINITY)
    }

    fn execute(
        &mut self,
        pair: &Pair,
        boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, CollideError> {
        let Pair {
            i,
            j,
            si,
            sj,
            now,
            dr,
            ..
        } = *pair;
        debug_assert_eq!(boundary, Boundary::Inner);
        let (core, hi, hj) = self.shape(si, sj);
        let (ri, rj) = (self.rot.bodies[i as usize], self.rot.bodies[j as usize]);
        let (ui, uj) = (ri.pose(now), rj.pose(now));
        let (wi, wj) = (Rotor::omega(&ri.rotor), Rotor::omega(&rj.rotor));
        let (s, t, w) = closest_points(dr, ui, hi, uj, hj);
        let d = w.length();
        let overlap = d * d < core * core * (1.0 - OVERLAP_TOLERANCE);
        let skipped = Executed {
            class: PairClass::Skipped,
            delta_u: 0.0,
            virial: 0.0,
            overlap,
        };
        let Some(n) = w.try_normalize() else {
            // The axes cross: no normal (a broken invariant upstream).
            return Ok(skipped);
        };
        let (arm_i, arm_j) = (s * ui, t * uj);
        let rate = n.dot(*vi + wi.cross(arm_i) - *vj - wj.cross(arm_j));
        if rate >= 0.0 {
            return Ok(skipped);
        }
        let (a, b) = (self.species[si as usize], self.species[sj as usize]);
        let out = contact(
            &LinearBody::new(a.mass, a.inertia, ui)?,
            &LinearBody::new(b.mass, b.inertia, uj)?,
            Velocity::new(*vi, wi),
            Velocity::new(*vj, wj),
            &Contact::new(n, arm_i, arm_j),
            f64::INFINITY,
        )?;
        let unusable = |_| CollideError::NotFinite("angular velocity after the impulse");
        self.rot
            .restart(i, ui, out.i.angular, now)
            .map_err(unusable)?;
        self.rot
            .restart(j, uj, out.j.angular, now)
            .map_err(unusable)?;
        *vi = out.i.linear;
        *vj = out.j.linear;
        Ok(Executed {
            class: PairClass::Core,
            delta_u: 0.0,
            virial: out.impulse.s * dr.dot(n),
            overlap,
        })
    }

    fn pair_energy(&self, _i: u32, _j: u32, _si: u32, _sj: u32) -> f64 {
        0.0
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair {
            i, j, si, sj, dr, ..
        } = *pair;
        let (d, core) = self.distance(i, j, si, sj, pair.now, dr);
        let (_, hi, hj) = self.shape(si, sj);
        if dr.length() < hi + hj + core && !listed {
            return Err(format!(
                "pair ({i}, {j}) can touch at centre distance {} but is not listed",
                dr.length()
            ));
        }
        if d < core * (1.0 - 1e-9) {
            return Err(format!(
                "spherocylinders {i} and {j} overlap: axis distance {d} < {core}"
            ));
        }
        Ok(())
    }

    #[inline]
    fn level(&self, _i: u32, _j: u32) -> u16 {
        0
    }

    fn set_level(&mut self, _i: u32, _j: u32, level: u16) {
        debug_assert_eq!(level, 0, "hard bodies have no levels but 0");
    }

    fn storable_level(&self, _si: u32, _sj: u32, _level: u16) -> bool {
        false
    }

    /// No levels; `+∞` for an overlap beyond round-off.
    fn configured_level(&self, pair: &Pair, _stored: u16) -> (u16, f64) {
        let (d, core) = self.distance(pair.i, pair.j, pair.si, pair.sj, pair.now, pair.dr);
        if d * d < core * core * (1.0 - OVERLAP_TOLERANCE) {
            (0, f64::INFINITY)
        } else {
            (0, 0.0)
        }
    }

    crate::models::rotor::rotation_hooks!(rot);

    fn report(&self) -> Report {
        let mut r = Report::default();
        r.count("spherocylinders.predictions", self.stats.predictions);
        r.count("spherocylinders.samples", self.stats.samples);
        r.count("spherocylinders.refinement_samples", self.stats.refinements);
        r.count("spherocylinders.virtual_events", self.stats.virtuals);
        r
    }

    fn extra_state(&self) -> Vec<f64> {
        let mut x = Vec::with_capacity(self.rot.numbers() + 2 * Stats::NUMBERS);
        self.rot.write(&mut x);
        for c in self.stats.counts() {
            push_count(&mut x, c);
        }
        x
    }

    fn set_extra_state(&mut self, state: &[f64]) -> Result<(), String> {
        let mut r = StateReader::new(state);
        let rotations = r.take(self.rot.numbers(), "the bodies' rotations")?;
        let mut c = [0u64; Stats::NUMBERS];
        for x in &mut c {
            *x = r.count("a counter")?;
        }
        r.finish()?;
        self.rot.read(rotations)?;
        self.stats = Stats {
            predictions: c[0],
            samples: c[1],
            refinements: c[2],
            virtuals: c[3],
        };
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::simulation::{LoopSettings, NoSampler, Simulation, Stop};
    use event_queue::{HeapQueue, LazyQueue, Ticket};
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    const ROD: Spherocylinder = Spherocylinder {
        length: 3.0,
        diameter: 1.0,
        mass: 1.3,
        inertia: 0.9,
    };

    fn unit(v: [f64; 3]) -> Option<DVec3> {
        DVec3::from(v).try_normalize()
    }

    /// The distance of two segments by brute force: 401 points on `i` against the exact
    /// distance of each to segment `j`.
    fn brute(r: DVec3, ui: DVec3, hi: f64, uj: DVec3, hj: f64) -> f64 {
        (0..=400)
            .map(|k| {
                let p = r + ui * (hi * (k as f64 / 200.0 - 1.0));
                let t = uj.dot(p).clamp(-hj, hj);
                (p - t * uj).length()
            })
            .fold(f64::INFINITY, f64::min)
    }

    /// The contact separation along `e` of two bodies with axes `ui`, `uj` (bisection on the
    /// monotone-enough distance: 0 at coinciding centres, ≥ D beyond `L + D`).
    fn touching(ui: DVec3, hi: f64, uj: DVec3, hj: f64, e: DVec3) -> DVec3 {
        let d = |x: f64| closest_points(e * x, ui, hi, uj, hj).2.length() - ROD.diameter;
        // The first crossing from outside inwards: walk in from beyond the reach.
        let mut b = hi + hj + ROD.diameter + 1.0;
        let mut x = b;
        while x > 0.0 && d(x) > 0.0 {
            b = x;
            x -= 0.01;
        }
        let mut a = x.max(0.0);
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if d(m) > 0.0 { b = m } else { a = m }
        }
        e * b
    }

    proptest! {
        /// The closest points are those of a fine brute-force scan (to its resolution), the
        /// distance is never below the true one, and parallel segments are exact.
        #[test]
        fn closest_points_match_a_brute_force_scan(
            r in prop::array::uniform3(-4.0f64..4.0),
            a in prop::array::uniform3(-1.0f64..1.0),
            b in prop::array::uniform3(-1.0f64..1.0),
            hi in 0.0f64..2.0,
            hj in 0.0f64..2.0,
            parallel in any::<bool>(),
        ) {
            let (Some(ui), Some(uj)) = (unit(a), unit(b)) else { return Ok(()) };
            let uj = if parallel { ui } else { uj };
            let r = DVec3::from(r);
            let (s, t, w) = closest_points(r, ui, hi, uj, hj);
            prop_assert!(s.abs() <= hi && t.abs() <= hj);
            prop_assert!((w - (r + s * ui - t * uj)).length() < 1e-12);
            let d = w.length();
            let reference = brute(r, ui, hi, uj, hj);
            // The scan's spacing is hi/200; it can only overestimate.
            prop_assert!(d <= reference + 1e-12, "{d} > {reference}");
            prop_assert!(reference - d <= hi / 200.0 + 1e-12, "{d} < {reference}");
        }

        /// The impulse at the contact point conserves energy, momentum and angular momentum
        /// (about any origin: the bodies' centres at `dr` and 0) to round-off and reverses the
        /// normal velocity of the contact points.
        #[test]
        fn collisions_conserve_energy_momentum_and_angular_momentum(
            a in prop::array::uniform3(-1.0f64..1.0),
            b in prop::array::uniform3(-1.0f64..1.0),
            e in prop::array::uniform3(-1.0f64..1.0),
            v in prop::array::uniform3(-2.0f64..2.0),
            w in prop::array::uniform3(-2.0f64..2.0),
            wj in prop::array::uniform3(-2.0f64..2.0),
            mass_j in 0.3f64..3.0,
            inertia_j in 0.1f64..3.0,
        ) {
            let (Some(ui), Some(uj), Some(e)) = (unit(a), unit(b), unit(e)) else { return Ok(()) };
            let other = Spherocylinder { mass: mass_j, inertia: inertia_j, length: 2.0, ..ROD };
            let dr = touching(ui, 0.5 * ROD.length, uj, 0.5 * other.length, e);
            let mut m = Spherocylinders::new(
                vec![ROD, other],
                &[0, 1],
                &[ui, uj],
                &[DVec3::from(w), DVec3::from(wj)],
            ).unwrap();
            let (d, core) = m.distance(0, 1, 0, 1, 0.0, dr);
            prop_assert!((d - core).abs() < 1e-12, "{d} {core}");
            let (mut vi, mut vj) = (DVec3::from(v), DVec3::ZERO);
            let kinetic = |m: &Spherocylinders, vi: DVec3, vj: DVec3| {
                0.5 * ROD.mass * vi.length_squared()
                    + 0.5 * mass_j * vj.length_squared()
                    + m.rotational_kinetic()
            };
            let angular = |m: &Spherocylinders, vi: DVec3, vj: DVec3| {
                // Body j sits at the origin: its orbital part is 0 × p_j.
                let _ = vj;
                dr.cross(ROD.mass * vi) + m.spin(0, 0) + m.spin(1, 1)
            };
            let (k0, p0, l0) = (
                kinetic(&m, vi, vj),
                ROD.mass * vi + mass_j * vj,
                angular(&m, vi, vj),
            );
            let pair = Pair { i: 0, j: 1, si: 0, sj: 1, now: 0.0, dr, dv: vi - vj };
            let out = m.execute(&pair, Boundary::Inner, &mut vi, &mut vj).unwrap();
            if out.class == PairClass::Skipped {
                // Separating: nothing changed.
                prop_assert_eq!(vi, DVec3::from(v));
                return Ok(());
            }
            prop_assert_eq!(out.class, PairClass::Core);
            let (k1, p1, l1) = (
                kinetic(&m, vi, vj),
                ROD.mass * vi + mass_j * vj,
                angular(&m, vi, vj),
            );
            let scale = 1.0 + k0;
            prop_assert!((k1 - k0).abs() < 1e-13 * scale, "K {k0} → {k1}");
            prop_assert!((p1 - p0).length() < 1e-13 * scale, "p {p0} → {p1}");
            prop_assert!((l1 - l0).length() < 1e-12 * scale, "L {l0} → {l1}");
            prop_assert!(out.virial > 0.0);
        }
    }

    proptest! {
        /// Prediction never misses a contact: along random free flights (translation and
        /// rotation), the predicted time (through virtual events) is the first time a fine scan
        /// of the gap finds it closed, and the gap there is zero to round-off.
        #[test]
        fn predictions_find_the_first_contact_of_a_fine_scan(
            a in prop::array::uniform3(-1.0f64..1.0),
            b in prop::array::uniform3(-1.0f64..1.0),
            r in prop::array::uniform3(-4.0f64..4.0),
            v in prop::array::uniform3(-1.5f64..1.5),
            w in prop::array::uniform3(-2.0f64..2.0),
            wj in prop::array::uniform3(-2.0f64..2.0),
        ) {
            let (Some(ui), Some(uj)) = (unit(a), unit(b)) else { return Ok(()) };
            let (dr0, dv) = (DVec3::from(r), DVec3::from(v));
            let mut m = Spherocylinders::new(
                vec![ROD],
                &[0, 0],
                &[ui, uj],
                &[DVec3::from(w), DVec3::from(wj)],
            ).unwrap();
            let gap = |m: &Spherocylinders, t: f64| {
                let (d, core) = m.distance(0, 1, 0, 0, t, dr0 + dv * t);
                d - core
            };
            prop_assume!(gap(&m, 0.0) > 1e-3);
            let horizon = 6.0;
            let mut now = 0.0;
            let predicted = loop {
                let pair = Pair { i: 0, j: 1, si: 0, sj: 0, now, dr: dr0 + dv * now, dv };
                match m.predict(&pair) {
                    Some((dt, Kind::Virtual)) => now += dt,
                    Some((dt, _)) => break Some(now + dt),
                    None => break None,
                }
                prop_assert!(now < 1e3, "virtual events do not advance");
            };
            let step = 1e-4;
            let first = (0..=(horizon / step) as usize)
                .map(|k| k as f64 * step)
                .find(|&t| gap(&m, t) < 0.0);
            match (predicted, first) {
                (Some(t), _) if t <= horizon => {
                    prop_assert!(gap(&m, t).abs() < 1e-9, "gap {} at {t}", gap(&m, t));
                    // Nothing closed before it on the scan.
                    prop_assert!(first.is_none_or(|f| f >= t - step), "{first:?} before {t}");
                }
                (_, Some(f)) => prop_assert!(false, "missed the contact at {f}: {predicted:?}"),
                _ => {}
            }
        }
    }

    /// A small box of rods from a lattice with room for any orientation, run through many
    /// collisions: energy and momentum conserved, every pair apart by at least its contact
    /// distance at the end (and at every debug check on the way), no anomaly.
    #[test]
    fn a_gas_of_rods_conserves_energy_and_never_overlaps() {
        let rod = Spherocylinder { length: 2.0, ..ROD };
        let spacing = 3.05;
        let k = 4;
        let l = DVec3::splat(spacing * k as f64);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(16);
        let mut gauss = || {
            DVec3::new(
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
                StandardNormal.sample(&mut rng),
            )
        };
        let n = k * k * k;
        let positions: Vec<DVec3> = (0..n)
            .map(|m| {
                DVec3::new((m % k) as f64, ((m / k) % k) as f64, (m / (k * k)) as f64) * spacing
            })
            .collect();
        let axes: Vec<DVec3> = (0..n).map(|_| gauss().normalize()).collect();
        let omegas: Vec<DVec3> = (0..n).map(|_| gauss()).collect();
        let mut velocities: Vec<DVec3> = (0..n).map(|_| gauss()).collect();
        let mean = velocities.iter().sum::<DVec3>() / n as f64;
        for v in &mut velocities {
            *v -= mean;
        }
        let species = vec![0u32; n];
        let model = Spherocylinders::new(vec![rod], &species, &axes, &omegas).unwrap();
        let settings = LoopSettings {
            rebase_events: 3_000,
            seed: 1,
            debug_check_events: 2_000,
            skin: 0.3,
            start_time: 0.0,
        };
        let mut sim: Simulation<_, LazyQueue<HeapQueue<Ticket>>> =
            Simulation::new(l, &positions, &velocities, &species, model, settings).unwrap();
        // Translational and rotational: a hard gas has no other energy.
        let energy = |sim: &Simulation<Spherocylinders, _>| sim.kinetic_energy();
        let e0 = energy(&sim);
        sim.run(Stop::Events(20_000), &mut NoSampler, &mut |_| {})
            .unwrap();
        let c = sim.counters();
        assert!(c.core > 1_500, "{c:?}");
        assert_eq!(sim.anomalies().total(), 0, "{:?}", sim.anomalies());
        let e1 = energy(&sim);
        assert!((e1 - e0).abs() < 1e-11 * e0, "{e0} → {e1}");
        let (p, _) = sim.momentum_and_mass();
        assert!(p.length() < 1e-11 * e0, "{p}");
        sim.check().unwrap();
        let now = sim.now();
        let bodies = sim.bodies();
        let mut closest = f64::INFINITY;
        for i in 0..n {
            for j in 0..i {
                let d = bodies[i].position_at(now) - bodies[j].position_at(now);
                let dr = d - l * (d / l).round();
                let (dist, core) = sim.model().distance(i as u32, j as u32, 0, 0, now, dr);
                closest = closest.min(dist / core);
            }
        }
        assert!(
            closest >= 1.0 - 1e-9,
            "closest pair at {closest} of contact"
        );
    }

    /// Two rods turning towards each other about parallel axes with no translation: the
    /// prediction finds the contact that the rotation alone brings, at the time the geometry
    /// gives (two crossed rods turning into one plane).
    #[test]
    fn a_contact_brought_by_rotation_alone_is_found_at_its_time() {
        // Rod i along x at the origin, rod j at height 1.5 above it along y; i turns about y,
        // tilting its +x half up towards j's axis.
        let rate = 0.7;
        let ui = DVec3::X;
        let uj = DVec3::Y;
        let dr = DVec3::new(0.0, 0.0, -1.5);
        let mut m = Spherocylinders::new(
            vec![ROD],
            &[0, 0],
            &[ui, uj],
            &[DVec3::new(0.0, -rate, 0.0), DVec3::ZERO],
        )
        .unwrap();
        let pair = Pair {
            i: 0,
            j: 1,
            si: 0,
            sj: 0,
            now: 0.0,
            dr,
            dv: DVec3::ZERO,
        };
        let (t, kind) = m.predict(&pair).unwrap();
        assert_eq!(kind, Kind::Pair(Boundary::Inner));
        // Tilted by θ, the point of i at arm s is (s cos θ, 0, s sin θ); its distance from
        // j's axis (x = 0, z = 1.5) is least at s = 1.5 sin θ (inside i's half-length), where
        // it is 1.5 cos θ: contact at 1.5 cos θ = D.
        let theta = (ROD.diameter / 1.5).acos();
        assert!((t - theta / rate).abs() < 1e-12, "{t} vs {}", theta / rate);
        let (d, core) = m.distance(0, 1, 0, 0, t, dr);
        assert!((d - core).abs() < 1e-12 && d >= core * (1.0 - SLACK), "{d}");
    }
}
