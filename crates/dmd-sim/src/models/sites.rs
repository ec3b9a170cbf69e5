//! Rigid site-based molecules (seed 000): point atoms ("sites") fixed in a rigid body, moving
//! exactly between events, interacting through stepped radial potentials between the sites of
//! different molecules (hard cores, square wells, several steps per pair of site species).
//!
//! **Molecule types** are [`MoleculeType`]s (the shared `molecule` module): atoms in the
//! principal frame of the inertia tensor, spherical rotors, symmetric tops and linear molecules
//! recognised to [`MOMENT_SNAP`].
//!
//! [`Sites`] is the [`PairModel`]. It keeps, indexed like the loop's bodies:
//!
//! - the free motion of every molecule, a [`FreeMotion`] set up at the molecule's last change
//!   with the time of that change (its rotational clock): symmetric and asymmetric tops follow
//!   their exact closed forms (000 §II.B);
//! - the level of every site pair of every pair of molecules that has one off level 0 (changed
//!   only by executed events, never recomputed from a distance at a boundary);
//! - per owner and partner, what the last prediction found: the search state of every site
//!   pair (a virtual event resumes them, 000 §III.B) or the site pair of the pending event.
//!
//! **Event search (000 §III.A).** A site pair `(α, β)` on level `s` of its stepped potential
//! (inner radius `r_in`, outer `r_out`) has its next event when `d² = |r_iα − r_jβ|²` leaves
//! `(r_in², r_out²)`. The indicator watches both boundaries at once,
//!
//! ```text
//! g(t) = (d² − r_in²)(r_out² − d²) / (r_out² − r_in²)      (d² − r_in² on level 0,
//!                                                           r_out² − d² without inner step)
//! ```
//!
//! positive inside, zero at either radius, with `ġ` from `d(d²)/dt = 2 r_αβ·u_αβ`, `u_αβ = v_ij +
//! ω_i × d_iα − ω_j × d_jβ`. Its falling crossing is searched by `root_search`
//! ([`Adaptive`](crate::models::search::SearchMethod::Adaptive) or the uniform
//! [`Grid`](crate::models::search::SearchMethod::Grid) with a grazing threshold in units of `g`,
//! i.e. length²). Each search is bracketed analytically by the bounding spheres: the sites are
//! within `ρ_α = |d_iα|` and `ρ_β` of their centres, so the pair can only be at a radius `R` of the
//! band while the centres are within `R + ρ_α + ρ_β` (`bracket` solves that quadratic without
//! cancellation). A pair of molecules that is not yet within the largest such radius gets a virtual
//! event when it arrives; there every site pair gets its own bracket, and the earliest root over
//! all site pairs is the pair's event. With a finite [`SearchSettings::window`] each site pair's
//! search stops at `now + window`, and the molecule pair's next event is a virtual one at the
//! earliest stopped search, unless a root was found before it; the virtual event resumes exactly
//! the stopped searches (bit for bit, `root_search::Method::resume`).
//!
//! **Impulses.** [`ImpulseRule::ContactPoint`] applies 000 §IV.B through `collide::contact` (the
//! impulse along the line joining the two sites, at their arms from the centres); the
//! [`ImpulseRule::Constrained`] option applies the constrained-Lagrangian rule of 000 §IV.A
//! (`collide::ConstraintSolver`) to the atoms with a rigid framework of `3n − 6` distance
//! constraints (one for a dumbbell), and recovers the centre velocity and angular velocity from
//! the atoms' new velocities. The two are the same physics; [`Sites::set_cross_check`] runs both
//! at every event and records how far apart they land ([`CrossCheck`]). A planar molecule of
//! more than two atoms cannot be held rigid by distance constraints to first order (every
//! atom can move out of the plane), and a collinear one of more than two atoms has dependent
//! constraints: for those the constrained rule is refused at construction.
//!
//! **Checks.** As in the `terraced` model: a search that starts with its site pair off
//! the stored level (beyond round-off) counts `off_terrace` (the trace of a missed event), an
//! executed event whose site distance is not at the boundary counts a `misfit`, and
//! [`SearchSettings::verify_step`] searches every interval again on a fine grid and counts the
//! roots the search missed.

use collide::{CollideError, ConstraintSolver, Contact, Molecule, Velocity, contact};
use glam::{DMat3, DQuat, DVec3};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use rigid_free::FreeMotion;
use root_search::SearchError;

use crate::engine::event::{Boundary, Kind};
use crate::engine::hash::mix;
use crate::engine::model::{Executed, Pair, PairClass, PairModel, PairSetupError, Report};
use crate::engine::potential::Potentials;
use crate::engine::saved::StateReader;
pub use crate::models::molecule::{MOMENT_SNAP, MoleculeError, MoleculeType};
use crate::models::search::{SearchSettings, SearchStats, check_settings};
use crate::models::site_pairs::{SiteAtom, SiteDistance, SiteSearch, SiteTable};

/// Why a molecule type or a site model could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SitesError {
    /// A molecule type is unusable.
    #[error(transparent)]
    Molecule(#[from] MoleculeError),
    /// A site species has no potential with another.
    #[error("site species {0} has no potential table (there are {1} site species)")]
    SiteSpecies(u32, usize),
    /// A body names a molecule type that does not exist.
    #[error("body {body}: molecule type {kind} does not exist")]
    Type {
        /// The body.
        body: usize,
        /// The type it names.
        kind: u32,
    },
    /// A body's orientation or angular velocity is unusable.
    #[error("body {body}: {problem}")]
    Body {
        /// The body.
        body: usize,
        /// What is wrong.
        problem: String,
    },
    /// The constrained-Lagrangian rule cannot hold this molecule rigid.
    #[error("molecule type {0}: {1}")]
    NotConstrainable(usize, &'static str),
    /// A search setting is out of range.
    #[error("bad search setting: {0}")]
    Search(SearchError),
}

/// Which impulse rule executes the events.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImpulseRule {
    /// 000 §IV.B: an impulse at the two sites along the line joining them.
    ContactPoint,
    /// 000 §IV.A: impulses on the atoms plus impulsive constraint forces (`Z` matrix).
    Constrained,
}

/// How far the two impulse rules landed apart over the events checked
/// ([`Sites::set_cross_check`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct CrossCheck {
    /// Events executed by both rules.
    pub events: u64,
    /// Largest `|ΔS| / |S|` of the impulse.
    pub impulse: f64,
    /// Largest difference of a new centre velocity or site velocity from the rotation
    /// (`|Δv| + |Δω| ρ`), relative to the largest site speed of the pair before the event.
    pub velocity: f64,
    /// Events at which the two rules disagreed on crossing or reflecting.
    pub outcome_mismatches: u64,
}

/// One molecule's free motion since its last change at time `t`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rotation {
    motion: FreeMotion,
    t: f64,
}

impl Rotation {
    #[inline(always)]
    fn pose(&self, now: f64) -> (DMat3, DVec3) {
        let p = self.motion.pose(now - self.t);
        (p.orientation, p.omega_lab())
    }
}

/// Rigid site-based molecules with stepped site–site potentials (module documentation).
#[derive(Debug)]
pub struct Sites {
    types: Vec<MoleculeType>,
    /// Site pairs, their levels and searches, and the molecules' types.
    table: SiteTable,
    rotations: Vec<Rotation>,
    rule: ImpulseRule,
    cross: Option<CrossCheck>,
    solver: ConstraintSolver,
}

impl Sites {
    /// Counters of this model's root searches so far.
    pub fn search_stats(&self) -> SearchStats {
        self.table.stats
    }

    /// Molecules of `types` interacting through the site–site `potentials` (over the site
    /// species); body `i` is of type `body_type[i]`, with orientation `orientations[i]` (body
    /// → lab) and lab angular velocity `omegas[i]` at time `t0`; searches with `settings`, the
    /// jitter drawn from `seed`; events executed by `rule`.
    ///
    /// # Errors
    /// [`SitesError`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        types: Vec<MoleculeType>,
        potentials: Potentials,
        body_type: &[u32],
        orientations: &[DQuat],
        omegas: &[DVec3],
        t0: f64,
        settings: SearchSettings,
        rule: ImpulseRule,
        seed: u64,
    ) -> Result<Self, SitesError> {
        let ns = potentials.n_species();
        for t in &types {
            if let Some(&s) = t.species.iter().find(|&&s| s as usize >= ns) {
                return Err(SitesError::SiteSpecies(s, ns));
            }
        }
        if rule == ImpulseRule::Constrained {
            for (k, t) in types.iter().enumerate() {
                if let Err(e) = &t.bonds {
                    return Err(SitesError::NotConstrainable(k, e));
                }
            }
        }
        let mut rotations = Vec::with_capacity(body_type.len());
        for (i, &ty) in body_type.iter().enumerate() {
            let Some(t) = types.get(ty as usize) else {
                return Err(SitesError::Type { body: i, kind: ty });
            };
            let (q, w) = (orientations[i], omegas[i]);
            if !(q.is_finite() && w.is_finite()) || q.length_squared() == 0.0 {
                return Err(SitesError::Body {
                    body: i,
                    problem: "orientation or angular velocity is not finite".into(),
                });
            }
            let q = q.normalize();
            let wb = DMat3::from_quat(q).transpose() * w;
            let motion =
                FreeMotion::from_quat(&t.moments, q, wb).map_err(|e| SitesError::Body {
                    body: i,
                    problem: e.to_string(),
                })?;
            rotations.push(Rotation { motion, t: t0 });
        }
        check_settings(&settings).map_err(SitesError::Search)?;
        let table = SiteTable::new(
            types.iter().map(|t| (&t.species[..], &t.radii[..])),
            potentials,
            body_type,
            settings,
            mix(seed ^ 0x5173_e500_0000_0011),
        );
        Ok(Sites {
            types,
            table,
            rotations,
            rule,
            cross: None,
            solver: ConstraintSolver::new(),
        })
    }

    /// Runs both impulse rules at every event from now on, executing with the chosen one, and
    /// records how far apart they land ([`Sites::cross_check`]).
    ///
    /// # Errors
    /// A molecule type the constrained rule cannot hold rigid.
    pub fn set_cross_check(&mut self, on: bool) -> Result<(), SitesError> {
        if on {
            for (k, t) in self.types.iter().enumerate() {
                if let Err(e) = &t.bonds {
                    return Err(SitesError::NotConstrainable(k, e));
                }
            }
            self.cross = Some(self.cross.unwrap_or_default());
        } else {
            self.cross = None;
        }
        Ok(())
    }

    /// The cross-check record, if it is on.
    pub fn cross_check(&self) -> Option<CrossCheck> {
        self.cross
    }

    /// The molecule types.
    pub fn types(&self) -> &[MoleculeType] {
        &self.types
    }

    /// The site–site potentials.
    pub fn potentials(&self) -> &Potentials {
        self.table.potentials()
    }

    /// The search settings.
    pub fn settings(&self) -> &SearchSettings {
        self.table.settings()
    }

    /// Lab orientation (body → lab) and lab angular velocity of molecule `i` at `now`.
    pub fn pose(&self, i: u32, now: f64) -> (DMat3, DVec3) {
        self.rotations[i as usize].pose(now)
    }

    /// Lab positions of molecule `i`'s sites relative to its centre at `now`.
    pub fn site_arms(&self, i: u32, now: f64) -> Vec<DVec3> {
        let (r, _) = self.pose(i, now);
        self.types[self.table.type_of(i)]
            .sites
            .iter()
            .map(|&d| r * d)
            .collect()
    }

    /// The stored level of site `a` of `i` with site `b` of `j`.
    pub fn site_level(&self, i: u32, j: u32, a: usize, b: usize) -> u16 {
        self.table.site_level(i, j, a, b)
    }

    /// Number of molecule pairs with a site pair off level 0.
    pub fn stored_pairs(&self) -> usize {
        self.table.stored_pairs()
    }

    /// Runs every site pair of `pair` whose search is due (on the molecules' free motion), then
    /// picks the pair's next event ([`SiteTable::choose`]).
    fn search(
        table: &mut SiteTable,
        (types, rotations): (&[MoleculeType], &[Rotation]),
        pair: &Pair,
        mut sites: Vec<SiteSearch>,
        fresh: bool,
    ) -> Option<(f64, Kind)> {
        let Pair {
            i, j, now, dr, dv, ..
        } = *pair;
        let mut geo = RigidGeometry {
            ri: rotations[i as usize],
            rj: rotations[j as usize],
            sites_i: &types[table.type_of(i)].sites,
            sites_j: &types[table.type_of(j)].sites,
            dr,
            dv,
            now,
            cache: PoseCache::default(),
        };
        table.search_due(&mut geo, (i, j), now, &mut sites, fresh);
        table.choose(i, j, now, sites)
    }

    /// The lab velocities of sites after the rule: the rule's new velocities of both bodies.
    #[allow(clippy::too_many_arguments)]
    fn constrained(
        &mut self,
        i: u32,
        j: u32,
        a: usize,
        b: usize,
        dr: DVec3,
        (oi, oj): (DMat3, DMat3),
        vel_i: Velocity,
        vel_j: Velocity,
        step: f64,
    ) -> Result<(collide::Impulse, Velocity, Velocity), CollideError> {
        let ti = &self.types[self.table.type_of(i)];
        let tj = &self.types[self.table.type_of(j)];
        let arms_i: Vec<DVec3> = ti.sites.iter().map(|&d| oi * d).collect();
        let arms_j: Vec<DVec3> = tj.sites.iter().map(|&d| oj * d).collect();
        let pos_i: Vec<DVec3> = arms_i.iter().map(|&d| dr + d).collect();
        let pos_j = arms_j.clone();
        let mut vi: Vec<DVec3> = arms_i
            .iter()
            .map(|&d| vel_i.linear + vel_i.angular.cross(d))
            .collect();
        let mut vj: Vec<DVec3> = arms_j
            .iter()
            .map(|&d| vel_j.linear + vel_j.angular.cross(d))
            .collect();
        let bonds_i = ti.bonds.as_deref().map_err(|_| {
            CollideError::NoImpulse("the constrained rule needs a rigid framework of bonds")
        })?;
        let bonds_j = tj.bonds.as_deref().map_err(|_| {
            CollideError::NoImpulse("the constrained rule needs a rigid framework of bonds")
        })?;
        let imp = self.solver.between(
            Molecule {
                masses: &ti.masses,
                positions: &pos_i,
                velocities: &mut vi,
                bonds: bonds_i,
            },
            a,
            Molecule {
                masses: &tj.masses,
                positions: &pos_j,
                velocities: &mut vj,
                bonds: bonds_j,
            },
            b,
            step,
        )?;
        // Centre velocity and angular momentum of the atoms' new velocities.
        let rigid = |t: &MoleculeType, o: DMat3, arms: &[DVec3], v: &[DVec3]| -> Velocity {
            let p = t
                .masses
                .iter()
                .zip(v)
                .fold(DVec3::ZERO, |s, (&m, &u)| s + m * u);
            let vc = p / t.mass;
            let l = t
                .masses
                .iter()
                .zip(arms.iter().zip(v))
                .fold(DVec3::ZERO, |s, (&m, (&d, &u))| s + m * d.cross(u - vc));
            Velocity::new(vc, o * t.omega_from_momentum(o, l))
        };
        Ok((
            imp,
            rigid(ti, oi, &arms_i, &vi),
            rigid(tj, oj, &arms_j, &vj),
        ))
    }
}

/// Poses of the two molecules at the last few sample times: the site pairs of one molecule
/// pair share their samples on a grid (and their first sample always).
#[derive(Default)]
struct PoseCache {
    entries: [(f64, DMat3, DVec3, DMat3, DVec3); 8],
    next: usize,
    len: usize,
}

impl PoseCache {
    #[inline]
    fn get(&mut self, t: f64, ri: &Rotation, rj: &Rotation) -> (DMat3, DVec3, DMat3, DVec3) {
        for e in &self.entries[..self.len] {
            if e.0 == t {
                return (e.1, e.2, e.3, e.4);
            }
        }
        let (oi, wi) = ri.pose(t);
        let (oj, wj) = rj.pose(t);
        self.entries[self.next] = (t, oi, wi, oj, wj);
        self.next = (self.next + 1) % self.entries.len();
        self.len = (self.len + 1).min(self.entries.len());
        (oi, wi, oj, wj)
    }
}

/// The two molecules of a pair and their relative centre motion: what the site pairs'
/// indicators need.
struct RigidGeometry<'a> {
    ri: Rotation,
    rj: Rotation,
    /// The sites of each in its body frame.
    sites_i: &'a [DVec3],
    sites_j: &'a [DVec3],
    dr: DVec3,
    dv: DVec3,
    now: f64,
    cache: PoseCache,
}

impl SiteDistance for RigidGeometry<'_> {
    #[inline]
    fn distance2(&mut self, a: usize, b: usize, t: f64) -> (f64, f64) {
        let (oi, wi, oj, wj) = self.cache.get(t, &self.ri, &self.rj);
        let (di, dj) = (oi * self.sites_i[a], oj * self.sites_j[b]);
        let r = self.dr + self.dv * (t - self.now) + di - dj;
        let u = self.dv + wi.cross(di) - wj.cross(dj);
        (r.length_squared(), 2.0 * r.dot(u))
    }
}

impl PairModel for Sites {
    fn reach(&self) -> f64 {
        self.table.reach()
    }

    fn n_species(&self) -> usize {
        self.types.len()
    }

    fn mass(&self, s: u32) -> f64 {
        self.types[s as usize].mass
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let Pair { i, j, dr, .. } = *pair;
        // Both molecules at i's clock (a new pair: both moved freely since then).
        let t = self.rotations[i as usize].t;
        let (arms_i, arms_j) = (self.site_arms(i, t), self.site_arms(j, t));
        self.table.setup(i, j, dr, &arms_i, &arms_j)
    }

    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let motion = (&self.types[..], &self.rotations[..]);
        self.table.predict(pair, |table, sites, fresh| {
            Self::search(table, motion, pair, sites, fresh)
        })
    }

    fn resume(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let motion = (&self.types[..], &self.rotations[..]);
        self.table.resume(pair, |table, sites, fresh| {
            Self::search(table, motion, pair, sites, fresh)
        })
    }

    fn execute(
        &mut self,
        pair: &Pair,
        _boundary: Boundary,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, CollideError> {
        let Pair { i, j, now, dr, .. } = *pair;
        let skipped = |overlap| Executed {
            class: PairClass::Skipped,
            delta_u: 0.0,
            virial: 0.0,
            overlap,
        };
        let Ok(Some(fired)) = self.table.fire(i, j, now) else {
            return Ok(skipped(false));
        };
        let (a, b) = (fired.a, fired.b);
        let (ti, tj) = (self.table.type_of(i), self.table.type_of(j));
        let (oi, wi) = self.pose(i, now);
        let (oj, wj) = self.pose(j, now);
        let (di, dj) = (oi * self.types[ti].sites[a], oj * self.types[tj].sites[b]);
        let n = dr + di - dj;
        let u = (*vi + wi.cross(di)) - (*vj + wj.cross(dj));
        let judged = self.table.judge(&fired, n, n.dot(u));
        let step = judged.step;
        if !judged.right_way {
            return Ok(skipped(judged.overlap));
        }
        let vel_i = Velocity::new(*vi, wi);
        let vel_j = Velocity::new(*vj, wj);
        let contact_rule =
            |this: &Self| -> Result<(collide::Impulse, Velocity, Velocity), CollideError> {
                let bi = this.types[ti].body(oi)?;
                let bj = this.types[tj].body(oj)?;
                let out = contact(&bi, &bj, vel_i, vel_j, &Contact::new(n, di, dj), step)?;
                Ok((out.impulse, out.i, out.j))
            };
        let (imp, new_i, new_j) = match self.rule {
            ImpulseRule::ContactPoint => contact_rule(self)?,
            ImpulseRule::Constrained => {
                self.constrained(i, j, a, b, dr, (oi, oj), vel_i, vel_j, step)?
            }
        };
        if let Some(mut cc) = self.cross {
            let other = match self.rule {
                ImpulseRule::ContactPoint => {
                    self.constrained(i, j, a, b, dr, (oi, oj), vel_i, vel_j, step)?
                }
                ImpulseRule::Constrained => contact_rule(self)?,
            };
            let rho = self.types[ti].radius.max(self.types[tj].radius);
            let speed = [vel_i, vel_j]
                .iter()
                .map(|v| v.linear.length() + v.angular.length() * rho)
                .fold(0.0, f64::max)
                .max(f64::MIN_POSITIVE);
            let dev = |x: Velocity, y: Velocity| {
                (x.linear - y.linear).length() + (x.angular - y.angular).length() * rho
            };
            cc.events += 1;
            cc.impulse = cc
                .impulse
                .max((imp.s - other.0.s).abs() / imp.s.abs().max(f64::MIN_POSITIVE));
            cc.velocity = cc
                .velocity
                .max(dev(new_i, other.1).max(dev(new_j, other.2)) / speed);
            if imp.outcome != other.0.outcome {
                cc.outcome_mismatches += 1;
            }
            self.cross = Some(cc);
        }
        *vi = new_i.linear;
        *vj = new_j.linear;
        for (m, o, v) in [(i, oi, new_i.angular), (j, oj, new_j.angular)] {
            let t = &self.types[self.table.type_of(m)];
            let q = DQuat::from_mat3(&o).normalize();
            let wb = DMat3::from_quat(q).transpose() * v;
            let motion = FreeMotion::from_quat(&t.moments, q, wb)
                .map_err(|_| CollideError::NotFinite("angular velocity after the impulse"))?;
            self.rotations[m as usize] = Rotation { motion, t: now };
        }
        Ok(Executed {
            class: self.table.settle(i, j, &fired, imp.outcome, step),
            delta_u: imp.delta_v,
            virial: imp.s * dr.dot(n),
            overlap: judged.overlap,
        })
    }

    // Site molecules store a level per *site* pair in their own map, not one level per
    // molecule pair: the loop's per-pair level is always 0 for them. HMC's ΔH reads the energy
    // judged from the site distances below; checkpoints and HMC's rollback carry the site
    // levels in the model's own saved state (`extra_state`).
    fn level(&self, _i: u32, _j: u32) -> u16 {
        0
    }

    fn set_level(&mut self, _i: u32, _j: u32, level: u16) {
        debug_assert_eq!(level, 0, "site molecules keep their levels per site pair");
    }

    fn storable_level(&self, _si: u32, _sj: u32, _level: u16) -> bool {
        false
    }

    fn configured_level(&self, pair: &Pair, _stored: u16) -> (u16, f64) {
        let Pair { i, j, now, dr, .. } = *pair;
        let (arms_i, arms_j) = (self.site_arms(i, now), self.site_arms(j, now));
        (0, self.table.configured_energy(i, j, dr, &arms_i, &arms_j))
    }

    fn extra_state(&self) -> Vec<f64> {
        // Each molecule's free motion as the state it was built from (exactly: rebuilding it
        // from these numbers gives the same motion bit for bit), then the site-pair levels and
        // the search counters.
        let mut x = Vec::with_capacity(13 * self.rotations.len() + 1 + 24);
        for r in &self.rotations {
            let p = r.motion.initial_pose();
            x.extend_from_slice(&p.orientation.to_cols_array());
            x.extend_from_slice(&p.omega.to_array());
            x.push(r.t);
        }
        self.table.write_numbers(&mut x);
        x
    }

    fn set_extra_state(&mut self, state: &[f64]) -> Result<(), String> {
        let mut r = StateReader::new(state);
        let mut rotations = Vec::with_capacity(self.rotations.len());
        for (i, &ty) in self.table.body_type.iter().enumerate() {
            let orientation = r.mat3("a molecule's orientation")?;
            let omega = r.vec3("a molecule's angular velocity")?;
            let t = r.real("a molecule's clock")?;
            let motion = FreeMotion::new(
                &self.types[ty as usize].moments,
                orientation.transpose(),
                omega,
            )
            .map_err(|e| format!("molecule {i} cannot be restored: {e}"))?;
            rotations.push(Rotation { motion, t });
        }
        let table = self.table.read_numbers(&mut r)?;
        r.finish()?;
        self.rotations = rotations;
        self.table.commit(table);
        Ok(())
    }

    fn pair_energy(&self, i: u32, j: u32, _si: u32, _sj: u32) -> f64 {
        self.table.pair_energy(i, j)
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair { i, j, now, dr, .. } = *pair;
        let (arms_i, arms_j) = (self.site_arms(i, now), self.site_arms(j, now));
        self.table.check((i, j), dr, &arms_i, &arms_j, listed)
    }

    #[inline]
    fn forget(&mut self, i: u32) {
        self.table.forget(i);
    }

    fn rebase(&mut self, t0: f64) {
        for (r, &ty) in self.rotations.iter_mut().zip(&self.table.body_type) {
            let p = r.motion.pose(t0 - r.t);
            let q = DQuat::from_mat3(&p.orientation).normalize();
            match FreeMotion::from_quat(&self.types[ty as usize].moments, q, p.omega) {
                Ok(motion) => *r = Rotation { motion, t: 0.0 },
                // Not finite (a broken invariant, reported elsewhere): keep the old anchor.
                Err(_) => r.t -= t0,
            }
        }
    }

    fn rotational_kinetic(&self) -> f64 {
        let mut k = crate::engine::sum::Compensated::ZERO;
        for (r, &ty) in self.rotations.iter().zip(&self.table.body_type) {
            let w = r.motion.omega(0.0);
            k.add(0.5 * (self.types[ty as usize].principal * w * w).element_sum());
        }
        k.value()
    }

    fn rotational_dof(&self) -> f64 {
        self.table
            .body_type
            .iter()
            .map(|&t| self.types[t as usize].rotational_dof())
            .sum()
    }

    fn thermalize(
        &mut self,
        i: u32,
        s: u32,
        now: f64,
        kt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> f64 {
        let t = &self.types[s as usize];
        let r = self.rotations[i as usize];
        let p = r.motion.pose(now - r.t);
        let w = draw_body_omega(t, kt, rng);
        let q = DQuat::from_mat3(&p.orientation).normalize();
        let Ok(motion) = FreeMotion::from_quat(&t.moments, q, w) else {
            return 0.0;
        };
        let before = 0.5 * (t.principal * p.omega * p.omega).element_sum();
        let w0 = motion.omega(0.0);
        let after = 0.5 * (t.principal * w0 * w0).element_sum();
        self.rotations[i as usize] = Rotation { motion, t: now };
        after - before
    }

    fn spin(&self, i: u32, s: u32) -> DVec3 {
        let p = self.rotations[i as usize].motion.initial_pose();
        p.orientation * (self.types[s as usize].principal * p.omega)
    }

    fn omega(&self, i: u32) -> DVec3 {
        self.rotations[i as usize].motion.initial_pose().omega_lab()
    }

    fn axis(&self, i: u32, now: f64) -> Option<DVec3> {
        Some(self.pose(i, now).0.x_axis)
    }

    /// The body frame is the principal frame of [`MoleculeType::sites`] (axis 1 of the
    /// smallest moment, the axis of a linear molecule); the attitude is the free motion's
    /// orientation.
    fn attitude(&self, i: u32, now: f64) -> Option<DQuat> {
        Some(DQuat::from_mat3(&self.pose(i, now).0).normalize())
    }

    fn report(&self) -> Report {
        let mut r = Report::default();
        self.table.stats.report_into(&mut r);
        r
    }

    fn draw_rotations(&mut self, now: f64, temperature: f64, rng: &mut Xoshiro256PlusPlus) {
        // HMC's momentum refresh: each molecule restarts at `now` from its present attitude
        // with a body-frame angular velocity drawn from equipartition.
        for (r, &ty) in self.rotations.iter_mut().zip(&self.table.body_type) {
            let t = &self.types[ty as usize];
            let p = r.motion.pose(now - r.t);
            let q = DQuat::from_mat3(&p.orientation).normalize();
            let w = draw_body_omega(t, temperature, rng);
            if let Ok(motion) = FreeMotion::from_quat(&t.moments, q, w) {
                *r = Rotation { motion, t: now };
            }
        }
    }

    fn reverse_rotations(&mut self) {
        // HMC reverses at a re-basing (present time 0), where every molecule is anchored: the
        // reversed motion starts from the same attitude with −ω and retraces the old one.
        for (r, &ty) in self.rotations.iter_mut().zip(&self.table.body_type) {
            let moments = &self.types[ty as usize].moments;
            let p = r.motion.pose(-r.t);
            let reversed = if r.t == 0.0 {
                let p0 = r.motion.initial_pose();
                FreeMotion::new(moments, p0.orientation.transpose(), -p0.omega)
            } else {
                FreeMotion::from_quat(
                    moments,
                    DQuat::from_mat3(&p.orientation).normalize(),
                    -p.omega,
                )
            };
            if let Ok(motion) = reversed {
                *r = Rotation { motion, t: 0.0 };
            }
        }
    }

    fn scale_rotations(&mut self, now: f64, factor: f64) {
        // Each molecule restarts at `now` from its present attitude with its body-frame
        // angular velocity scaled, as a thermostat collision restarts it with a fresh one.
        for (r, &ty) in self.rotations.iter_mut().zip(&self.table.body_type) {
            let p = r.motion.pose(now - r.t);
            let q = DQuat::from_mat3(&p.orientation).normalize();
            if let Ok(motion) =
                FreeMotion::from_quat(&self.types[ty as usize].moments, q, factor * p.omega)
            {
                *r = Rotation { motion, t: now };
            }
        }
    }
}

/// A body-frame angular velocity drawn from equipartition at `kt`: each principal component
/// Gaussian with variance `kT / I_k` (none about a linear molecule's axis).
pub fn draw_body_omega(t: &MoleculeType, kt: f64, rng: &mut Xoshiro256PlusPlus) -> DVec3 {
    let mut w = DVec3::ZERO;
    for k in 0..3 {
        let g: f64 = StandardNormal.sample(rng);
        if t.principal[k] > 0.0 {
            w[k] = g * (kt / t.principal[k]).sqrt();
        }
    }
    w
}

/// Orientations uniform on SO(3) and lab angular velocities from equipartition at `kt` for
/// bodies of `body_type`, drawn from `seed`.
pub fn random_orientations(
    types: &[MoleculeType],
    body_type: &[u32],
    kt: f64,
    seed: u64,
) -> (Vec<DQuat>, Vec<DVec3>) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut qs = Vec::with_capacity(body_type.len());
    let mut ws = Vec::with_capacity(body_type.len());
    for &ty in body_type {
        // A normalised 4-D Gaussian is uniform on the unit quaternions.
        let q = loop {
            let c: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(&mut rng));
            let q = DQuat::from_xyzw(c[0], c[1], c[2], c[3]);
            if q.length_squared() > 1e-6 {
                break q.normalize();
            }
        };
        let w = draw_body_omega(&types[ty as usize], kt, &mut rng);
        qs.push(q);
        ws.push(DMat3::from_quat(q) * w);
    }
    (qs, ws)
}

/// The shipped molecules (reduced units: lengths in the diameter `σ` of the largest site).
pub mod molecules {
    use super::*;

    /// A hard dumbbell: two sites of diameter 1 (site species 0), unit masses, at separation
    /// `elongation` (`L* = L/σ`), with the hard-core table for [`Potentials::from_tables`].
    ///
    /// # Errors
    /// A non-positive or non-finite elongation.
    pub fn dumbbell(elongation: f64) -> Result<(MoleculeType, Potentials), SitesError> {
        let t = MoleculeType::new(&[
            SiteAtom {
                position: DVec3::new(0.0, 0.0, -0.5 * elongation),
                mass: 1.0,
                species: 0,
            },
            SiteAtom {
                position: DVec3::new(0.0, 0.0, 0.5 * elongation),
                mass: 1.0,
                species: 0,
            },
        ])?;
        Ok((
            t,
            Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]),
        ))
    }

    /// A methane-like molecule: a carbon-like site (species 0, mass 12) at the centre of a
    /// regular tetrahedron of four hydrogen-like sites (species 1, mass 1) at 0.32 (C–H 1.09 Å
    /// over σ_C = 3.4 Å). Hard cores with square wells: C–C core 1, well to 1.5, depth 1;
    /// C–H core 0.75, well to 1.1, depth 0.25; H–H core 0.55, well to 0.8, depth 0.1. A
    /// spherical rotor with tetrahedral sites (the companion application's methane, in spirit;
    /// not its parameters).
    pub fn methane_like() -> (MoleculeType, Potentials) {
        let s = 0.32 / 3f64.sqrt();
        let h = |x: f64, y: f64, z: f64| SiteAtom {
            position: DVec3::new(x, y, z) * s,
            mass: 1.0,
            species: 1,
        };
        let atoms = [
            SiteAtom {
                position: DVec3::ZERO,
                mass: 12.0,
                species: 0,
            },
            h(1.0, 1.0, 1.0),
            h(1.0, -1.0, -1.0),
            h(-1.0, 1.0, -1.0),
            h(-1.0, -1.0, 1.0),
        ];
        (
            MoleculeType::new(&atoms).expect("a valid molecule"),
            Potentials::from_tables(
                2,
                &[
                    ((0, 0), vec![[1.0, f64::INFINITY], [1.5, -1.0]]),
                    ((0, 1), vec![[0.75, f64::INFINITY], [1.1, -0.25]]),
                    ((1, 1), vec![[0.55, f64::INFINITY], [0.8, -0.1]]),
                ],
            ),
        )
    }

    /// A benzene-like planar ring: six carbon-like sites (species 0, mass 12) on a hexagon of
    /// radius 0.41 (1.40 Å over σ_C = 3.4 Å) and six hydrogen-like sites (species 1, mass 1)
    /// radially outside at 0.73. Hard cores with square wells as [`methane_like`] but C–C core
    /// 0.95. A symmetric top (planar: `I₃ = I₁ + I₂`).
    pub fn benzene_like() -> (MoleculeType, Potentials) {
        let mut atoms = Vec::with_capacity(12);
        for k in 0..6 {
            let a = std::f64::consts::FRAC_PI_3 * f64::from(k);
            let u = DVec3::new(a.cos(), a.sin(), 0.0);
            atoms.push(SiteAtom {
                position: 0.41 * u,
                mass: 12.0,
                species: 0,
            });
            atoms.push(SiteAtom {
                position: 0.73 * u,
                mass: 1.0,
                species: 1,
            });
        }
        (
            MoleculeType::new(&atoms).expect("a valid molecule"),
            Potentials::from_tables(
                2,
                &[
                    ((0, 0), vec![[0.95, f64::INFINITY], [1.4, -1.0]]),
                    ((0, 1), vec![[0.75, f64::INFINITY], [1.1, -0.25]]),
                    ((1, 1), vec![[0.55, f64::INFINITY], [0.8, -0.1]]),
                ],
            ),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shipped_molecules_have_their_symmetry() {
        let (m, _) = molecules::methane_like();
        assert_eq!(m.moments.kind(), rigid_free::BodyKind::Spherical);
        assert!(m.bonds().is_ok());
        let (b, _) = molecules::benzene_like();
        assert_eq!(
            b.moments.kind(),
            rigid_free::BodyKind::Symmetric { axis: 2 }
        );
        assert!(b.bonds().is_err());
        let (d, p) = molecules::dumbbell(0.6).unwrap();
        assert!(d.is_linear() && (d.radius() - 0.3).abs() < 1e-15);
        assert_eq!(p.get(0, 0).core(), Some(1.0));
        assert!(molecules::dumbbell(0.0).is_err());
    }
}

#[cfg(test)]
mod pair_tests {
    use super::*;
    use crate::engine::pair_state::SiteLevels;
    use crate::models::site_pairs::atom;

    /// Two dumbbells approaching, one tilted and spinning or not: the predicted event (after
    /// the virtual event at the bounding spheres' contact) is the first time two sites touch.
    #[test]
    fn two_dumbbells_meet_at_site_contact() {
        let t = MoleculeType::new(&[atom(0.0, 0.0, -0.3, 1.0), atom(0.0, 0.0, 0.3, 1.0)]).unwrap();
        let pot = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]);
        for w in [DVec3::ZERO, DVec3::new(0.0, 2.0, 0.0)] {
            let mut m = Sites::new(
                vec![t.clone()],
                pot.clone(),
                &[0, 0],
                &[DQuat::IDENTITY, DQuat::from_rotation_y(0.3)],
                &[DVec3::ZERO, w],
                0.0,
                SearchSettings::paper(0.02),
                ImpulseRule::ContactPoint,
                1,
            )
            .unwrap();
            let dr = DVec3::new(3.0, 0.0, 0.0);
            let dv = DVec3::new(-1.0, 0.0, 0.0);
            let mut now = 0.0;
            let mut out = m.predict(&Pair {
                i: 0,
                j: 1,
                si: 0,
                sj: 0,
                now,
                dr,
                dv,
            });
            let mut virtuals = 0;
            while let Some((dt, Kind::Virtual)) = out {
                now += dt;
                virtuals += 1;
                out = m.resume(&Pair {
                    i: 0,
                    j: 1,
                    si: 0,
                    sj: 0,
                    now,
                    dr: dr + dv * now,
                    dv,
                });
                assert!(virtuals < 100);
            }
            // The bounding spheres (reach 1 + 0.3 + 0.3) meet at t = 1.4: nothing before.
            assert!(now >= 1.4 - 1e-9 && virtuals >= 1, "{now}");
            let (dt, kind) = out.unwrap();
            assert_eq!(kind, Kind::Pair(Boundary::Inner));
            let t = now + dt;
            let c = dr + dv * t;
            let (a0, a1) = (m.site_arms(0, t), m.site_arms(1, t));
            let dmin = a0
                .iter()
                .flat_map(|a| a1.iter().map(move |b| (c + *a - *b).length()))
                .fold(f64::INFINITY, f64::min);
            assert!((dmin - 1.0).abs() < 1e-9, "{w}: closest sites {dmin}");
            // And no site pair was closer than contact before (sampled).
            for q in 0..200 {
                let s = t * f64::from(q) / 200.0;
                let c = dr + dv * s;
                let (a0, a1) = (m.site_arms(0, s), m.site_arms(1, s));
                for a in &a0 {
                    for b in &a1 {
                        assert!((c + *a - *b).length() > 1.0 - 1e-9);
                    }
                }
            }
        }
    }

    /// The exact free motion of an asymmetric molecule keeps its lab angular momentum.
    #[test]
    fn free_flight_conserves_lab_angular_momentum() {
        let t = MoleculeType::new(&[
            atom(0.0, 0.0, 0.0, 3.0),
            atom(0.6, 0.2, 0.0, 1.0),
            atom(-0.3, 0.5, 0.25, 2.0),
        ])
        .unwrap();
        let pot = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]);
        let m = Sites::new(
            vec![t.clone()],
            pot,
            &[0],
            &[DQuat::from_rotation_y(0.3)],
            &[DVec3::new(0.3, -1.0, 2.0)],
            0.0,
            SearchSettings::paper(0.02),
            ImpulseRule::ContactPoint,
            1,
        )
        .unwrap();
        assert_eq!(
            m.rotations[0].motion.kind(),
            rigid_free::MotionKind::Asymmetric
        );
        let l = |time: f64| {
            let (o, w) = m.pose(0, time);
            o * (t.moments() * (o.transpose() * w))
        };
        for time in [0.1, 1.0, 3.0, 30.0] {
            assert!((l(time) - l(0.0)).length() < 1e-12, "{time}");
        }
    }

    /// Two asymmetric tops with a stored site-pair level, for the saved-state tests.
    fn tops() -> Sites {
        let t = MoleculeType::new(&[
            atom(0.0, 0.0, 0.0, 3.0),
            atom(0.6, 0.2, 0.0, 1.0),
            atom(-0.3, 0.5, 0.25, 2.0),
        ])
        .unwrap();
        let pot = Potentials::from_tables(
            1,
            &[((0, 0), vec![[0.5, f64::INFINITY], [1.0, -1.0], [1.4, -0.5]])],
        );
        let mut m = Sites::new(
            vec![t],
            pot,
            &[0, 0],
            &[DQuat::from_rotation_y(0.3), DQuat::from_rotation_x(-1.1)],
            &[DVec3::new(0.3, -1.0, 2.0), DVec3::new(-0.7, 0.2, 0.4)],
            0.0,
            SearchSettings::paper(0.02),
            ImpulseRule::ContactPoint,
            1,
        )
        .unwrap();
        let mut levels = SiteLevels::default();
        levels.set(0, 1, 2, 1, (3, 3), 2);
        let stats = SearchStats {
            searches: 7,
            ..SearchStats::default()
        };
        m.table.commit((levels, stats));
        m
    }

    /// HMC's rejection: reversed at a re-basing, each molecule retraces its free motion.
    #[test]
    fn reversed_rotations_retrace_the_free_motion() {
        let mut m = tops();
        let start: Vec<_> = (0..2).map(|i| m.pose(i, 0.0)).collect();
        let t = 2.7;
        m.rebase(t);
        m.reverse_rotations();
        for (i, (o0, w0)) in start.iter().enumerate() {
            let (o, w) = m.pose(i as u32, t);
            assert!(
                (o - *o0).abs_diff_eq(DMat3::ZERO, 1e-12),
                "{i}: {o} vs {o0}"
            );
            assert!((w + *w0).length() < 1e-12, "{i}: {w} vs {w0}");
        }
    }

    /// The saved state restores the free motions bit for bit, the site levels and counters;
    /// a state of another scene is refused with a reason.
    #[test]
    fn saved_state_restores_bit_for_bit_and_refuses_misfits() {
        let mut m = tops();
        m.rebase(1.3);
        let saved = m.extra_state();
        let poses: Vec<_> = (0..2).map(|i| m.pose(i, 0.9)).collect();
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(5);
        m.draw_rotations(0.0, 2.0, &mut rng);
        m.table
            .commit((SiteLevels::default(), SearchStats::default()));
        assert_ne!(m.pose(0, 0.9), poses[0]);
        m.set_extra_state(&saved).unwrap();
        for (i, p) in poses.iter().enumerate() {
            let (o, w) = m.pose(i as u32, 0.9);
            assert_eq!(
                o.to_cols_array().map(f64::to_bits),
                p.0.to_cols_array().map(f64::to_bits)
            );
            assert_eq!(
                w.to_array().map(f64::to_bits),
                p.1.to_array().map(f64::to_bits)
            );
        }
        assert_eq!(m.site_level(0, 1, 2, 1), 2);
        assert_eq!(m.search_stats().searches, 7);
        assert_eq!(m.extra_state(), saved);
        // Too short, too long, a level beyond the table, a pair beyond the molecules.
        assert!(m.set_extra_state(&saved[..saved.len() - 1]).is_err());
        let mut long = saved.clone();
        long.push(0.0);
        assert!(m.set_extra_state(&long).unwrap_err().contains("numbers"));
        let at = 2 * 13;
        assert_eq!(saved[at], 1.0, "one stored pair");
        let mut bad = saved.clone();
        bad[at + 4 + 2 * 3 + 1] = 99.0;
        assert!(
            m.set_extra_state(&bad).unwrap_err().contains("level"),
            "{bad:?}"
        );
        let mut bad = saved.clone();
        bad[at + 2] = 2.0;
        assert!(m.set_extra_state(&bad).unwrap_err().contains("molecule"));
        let mut bad = saved;
        bad[0] = f64::NAN;
        assert!(m.set_extra_state(&bad).unwrap_err().contains("non-finite"));
    }
}
