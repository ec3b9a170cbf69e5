//! Semi-flexible molecules (seed 000): point atoms held together by distance
//! constraints that need not fix the whole body — a chain with fixed bond lengths and free bond
//! and torsion angles, say — interacting through stepped radial potentials between the atoms
//! ("sites") of different molecules.
//!
//! **Free motion.** Between events no external force acts, so a molecule's centre of mass moves
//! on a straight line (the loop's [`Body`](crate::engine::body::Body) record) and only its internal
//! motion is non-trivial: the atoms move under the constraint forces alone, whose multipliers
//! depend on positions and velocities (000 §II.A, the `Z` matrix) and have no closed form
//! unless the bonds hold the molecule rigid. The model keeps, per molecule, the atoms'
//! positions and velocities relative to the centre at its last change and propagates them by
//! RATTLE with a fixed step `h` ([`RattleSettings::step`]); positions between steps are the
//! cubic Hermite interpolant of the two neighbouring steps, velocities its derivative
//! ([`rattle`] module). The steps computed are kept until the molecule's next event (those
//! behind the present are dropped once more than [`rattle::TRIM_AT`] are held), so the root
//! searches of all its pairs share them. A RATTLE step that fails (too long for the motion)
//! makes the pair's event due at once, and executing it stops the run with
//! [`CollideError::FreeMotion`]: never a pair left without events. This is the scheme the paper's conclusion
//! proposes for semi-flexible bodies (000 §VI: SHAKE or RATTLE with the root searches of §III).
//!
//! **Event search.** As in the rigid `sites` model: each site pair of two molecules on level `s`
//! of its stepped potential has the indicator `g(t)` of its band of squared distances, here on
//! the numerical trajectory (`d² = |r_ij + q_iα − q_jβ|²`, rate `2 r·u` from the Hermite
//! derivative), searched by `root_search` (adaptive or grid with grazing detection, virtual
//! events at the end of each window). Each search is bracketed by bounding spheres around the
//! centres. The distance of an atom from the centre of mass changes as the molecule flexes;
//! the bound used is rigorous for every configuration the bonds allow:
//!
//! ```text
//! |q_α| = |Σ_k m_k (r_α − r_k)| / M ≤ Σ_k m_k D_αk / M = ρ_α,
//! ```
//!
//! with `D_αk` the shortest path from atom `α` to atom `k` along bonds (a sum of bond lengths,
//! at least the distance by the triangle inequality). For a rigid molecule with every distance
//! bonded it is `Σ_k m_k |r_α − r_k| / M`, a little above `|q_α|`.
//!
//! **Impulses (000 §IV.A).** At an event both molecules' atoms are taken at the event time
//! exactly as the search saw them (so the site distance is at the boundary), with lab
//! velocities `V + u_k`; `collide::ConstraintSolver` applies the impulse on the two atoms and
//! the impulsive constraint forces (the `Z` matrix) to every atom of both molecules, conserving
//! energy exactly for those velocities. The new centre velocity is the atoms' total momentum
//! over `M`, the internal velocities the rest, projected onto the tangent of the bonds (so the
//! bond rates vanish). The positions are kept as interpolated: projecting them onto the bonds
//! would move the event's site pair off its boundary, and the first RATTLE step of the new
//! trajectory restores the bond lengths anyway (SHAKE solves for the lengths at the new step,
//! whatever they were at the old one).
//!
//! **Errors of the method.** RATTLE conserves the bond lengths to the iteration tolerance at its
//! steps and the momenta exactly; between steps the interpolant misses the bond lengths by
//! `O((ωh)⁴)` (`ω` the bonds' angular speed). The kinetic energy of the internal motion, which
//! the exact free motion conserves, is kept by RATTLE at its steps (exactly for a uniformly
//! rotating bond, to `O(h²)` in general), but the interpolant's derivative between steps is
//! biased upwards: for a bond turning by `θ = ωh` per step its speed at mid-step is
//! `(1 + θ²/4)` times the steps' speed. An event samples that speed at a random phase, so
//! without correction the total energy grows by `O((ωh)²)` of the internal kinetic energy at
//! every event (a drift, not a fluctuation: 7 % over 8000 events at `h = 0.01`, 1.4 % at
//! `h = 0.005` for the chains of the tests). [`RattleSettings::rescale`] (the default of the
//! validation) scales the interpolated internal velocities at each event to the internal kinetic
//! energy of the molecule's start — the exactly conserved value — and restores what the tangent
//! projection removes: energy is then conserved to round-off and the step's error shows only
//! in the trajectory (`O(h²)`: a rigid molecule run this way follows the exact rigid motion of
//! the rigid `sites` model to `O(h²)`). Either way the loop's energy bookkeeping stays exact:
//! the model reports the kinetic energy its integration brought in at each event
//! ([`PairModel::take_kinetic_error`]).
//!
//! **Thermostat.** An Andersen collision of a molecule draws its centre velocity (the loop) and
//! its internal velocities: Gaussian atom velocities, the centre's taken off, projected onto the
//! tangent of the bonds (mass-orthogonally), which is the Maxwell–Boltzmann distribution of the
//! constrained internal motion.
//!
//! **Measure.** The constrained dynamics (the paper's) leaves `e^{−βH}` invariant on the
//! constraint surface with the metric factor `√det Z` (000 §II.A): configurations are not
//! uniform on the surface of fixed bond lengths. [`half_log_det_z`] gives the factor,
//! [`PairModel::log_metric`] sums it over molecules, and HMC divides it out when asked for the
//! stiff-bond ensemble instead.
//!
//! **Rigid molecules among them.** A type built by [`FlexibleType::rigid`] (a species without
//! bonds) moves by the exact free motion of its rigid molecule ([`rigid`] module) instead of
//! RATTLE: its atoms' arms and velocities at time `t` come from the motion's pose, so the same
//! site searches run on it. An event between a semi-flexible and a rigid molecule applies the
//! impulse at the rigid one's site (000 §IV.B) and the other's constraint forces (000 §IV.A) in
//! one energy equation (`ConstraintSolver::against_rigid`); two rigid molecules meet by the
//! contact rule (`collide::contact`). A rigid molecule restarts from its new angular velocity;
//! thermostat and HMC draws give it the rotation of the drawn atoms' angular momentum (the
//! mass-weighted projection onto rotations, Maxwell–Boltzmann in `ω`).
//!
//! **Atoms of one molecule.** With [`FlexibleType::interacting_beyond`], atoms more than a
//! given number of bonds apart meet through their site–site potential: the pair of a molecule
//! with itself ([`PairModel::self_pairs`]), searched on the molecule's one RATTLE trajectory,
//! with the impulse of its own constraint forces (`ConstraintSolver::within`, 000 §IV.A). The
//! impulses sum to zero: the centre velocity stays, and the molecular virial gets nothing.

pub mod rattle;
pub mod rigid;

use std::sync::Arc;

use collide::{Bond, CollideError, ConstraintSolver, Contact, Molecule, Velocity, contact};
use glam::{DQuat, DVec3};
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};
use rand_xoshiro::Xoshiro256PlusPlus;
use root_search::SearchError;

use crate::engine::event::{Boundary, Kind};
use crate::engine::hash::mix;
use crate::engine::model::{Executed, Pair, PairClass, PairModel, PairSetupError, Report};
use crate::engine::potential::Potentials;
use crate::engine::saved::{StateReader, push_count};
use crate::models::molecule::{MoleculeError, MoleculeType, SiteBody, check_atoms};
use crate::models::search::{SearchSettings, SearchStats, check_settings};
use crate::models::site_pairs::{Firing, Pending, SiteAtom, SiteDistance, SiteSearch, SiteTable};

pub use rattle::{Constraints, RattleError, Trajectory};
pub use rigid::RigidMotion;

/// Smallest accepted Cholesky pivot of the bonds' `Z` matrix at the reference configuration,
/// relative to its diagonal: below it a bond is (nearly) implied by the others and SHAKE would
/// not converge.
pub const BOND_PIVOT: f64 = 1e-8;

/// Largest relative bond-length error of the positions a molecule is given (they are then
/// projected exactly onto the bonds).
pub const START_TOLERANCE: f64 = 1e-6;

/// Why a semi-flexible molecule type or model could not be built.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FlexibleError {
    /// A bond is malformed.
    #[error("bond {bond} ({a}, {b}): {problem}")]
    Bond {
        /// The bond's index.
        bond: usize,
        /// One atom.
        a: usize,
        /// The other.
        b: usize,
        /// What is wrong.
        problem: &'static str,
    },
    /// The bonds do not hold every atom to the others.
    #[error("atom {0} is not connected to atom 0 by bonds: the atoms are not one molecule")]
    Disconnected(usize),
    /// The bonds are (nearly) dependent at the reference configuration.
    #[error(
        "bond {0} is (nearly) implied by the others at the reference configuration (a collinear \
         or planar framework with too many bonds): SHAKE cannot hold dependent constraints"
    )]
    DependentBonds(usize),
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
    /// A body's atoms are unusable.
    #[error("body {body}: {problem}")]
    Body {
        /// The body.
        body: usize,
        /// What is wrong.
        problem: String,
    },
    /// A RATTLE setting is out of range.
    #[error("RATTLE {name} = {value}: must be {why}")]
    Rattle {
        /// The setting.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range.
        why: &'static str,
    },
    /// A search setting is out of range.
    #[error("bad search setting: {0}")]
    Search(SearchError),
    /// The search settings are unusable otherwise.
    #[error("bad search settings: {0}")]
    Settings(String),
    /// More atoms than a site-pair table can index.
    #[error("a molecule of {0} atoms: at most 65535 are supported")]
    TooManyAtoms(usize),
    /// The atoms are unusable (too few, a bad mass or position), or a rigid molecule type is.
    #[error(transparent)]
    Molecule(#[from] MoleculeError),
}

/// A semi-flexible molecule type: atoms, site species, bonds and their lengths.
#[derive(Clone, Debug, PartialEq)]
pub struct FlexibleType {
    mass: f64,
    masses: Vec<f64>,
    species: Vec<u32>,
    bonds: Vec<Bond>,
    lengths: Vec<f64>,
    reference: Vec<DVec3>,
    radii: Vec<f64>,
    /// Fewest bonds between each two atoms, `n × n`.
    hops: Vec<u32>,
    /// Atom pairs `a < b` of one molecule that interact (none unless asked for).
    own: Vec<(u16, u16)>,
    /// A rigid molecule (no bonds): moves by its exact free motion.
    rigid: Option<Arc<MoleculeType>>,
}

impl FlexibleType {
    /// The molecule of `atoms` with distance constraints `bonds`, whose lengths are those of the
    /// given positions (the reference configuration, any frame).
    ///
    /// # Errors
    /// [`FlexibleError`] for fewer than two atoms, bad masses or positions, malformed,
    /// duplicated or dependent bonds, and atoms not connected by bonds.
    pub fn new(atoms: &[SiteAtom], bonds: &[Bond]) -> Result<Self, FlexibleError> {
        let n = atoms.len();
        check_atoms(atoms)?;
        if n > usize::from(u16::MAX) {
            return Err(FlexibleError::TooManyAtoms(n));
        }
        let bad = |bond: usize, b: &Bond, problem| FlexibleError::Bond {
            bond,
            a: b.a,
            b: b.b,
            problem,
        };
        let mut lengths = Vec::with_capacity(bonds.len());
        for (k, b) in bonds.iter().enumerate() {
            if b.a >= n || b.b >= n {
                return Err(bad(k, b, "an atom index is out of range"));
            }
            if b.a == b.b {
                return Err(bad(k, b, "an atom cannot be bonded to itself"));
            }
            if bonds[..k]
                .iter()
                .any(|c| (c.a, c.b) == (b.a, b.b) || (c.a, c.b) == (b.b, b.a))
            {
                return Err(bad(k, b, "the bond is given twice"));
            }
            let d = (atoms[b.a].position - atoms[b.b].position).length();
            if d == 0.0 {
                return Err(bad(k, b, "the atoms coincide: the bond has no length"));
            }
            lengths.push(d);
        }
        // Shortest bond paths (Floyd–Warshall), in length and in bonds: connectivity, the
        // bounding radii, and which atoms of one molecule may interact.
        let mut path = vec![f64::INFINITY; n * n];
        let mut hops = vec![u32::MAX; n * n];
        for k in 0..n {
            path[k * n + k] = 0.0;
            hops[k * n + k] = 0;
        }
        for (b, &d) in bonds.iter().zip(&lengths) {
            path[b.a * n + b.b] = d;
            path[b.b * n + b.a] = d;
            hops[b.a * n + b.b] = 1;
            hops[b.b * n + b.a] = 1;
        }
        for m in 0..n {
            for x in 0..n {
                for y in 0..n {
                    let via = path[x * n + m] + path[m * n + y];
                    if via < path[x * n + y] {
                        path[x * n + y] = via;
                    }
                    let via = hops[x * n + m].saturating_add(hops[m * n + y]);
                    if via < hops[x * n + y] {
                        hops[x * n + y] = via;
                    }
                }
            }
        }
        if let Some(k) = (0..n).find(|&k| path[k] == f64::INFINITY) {
            return Err(FlexibleError::Disconnected(k));
        }
        let masses: Vec<f64> = atoms.iter().map(|a| a.mass).collect();
        let mass: f64 = masses.iter().sum();
        let centre = atoms
            .iter()
            .fold(DVec3::ZERO, |c, a| c + a.mass * a.position)
            / mass;
        let reference: Vec<DVec3> = atoms.iter().map(|a| a.position - centre).collect();
        if let Some(k) = dependent_bond(&masses, bonds, &reference) {
            return Err(FlexibleError::DependentBonds(k));
        }
        // 1e-12 above the bound so round-off of the path sums cannot undercut |q_α|.
        let radii = (0..n)
            .map(|x| {
                (0..n).map(|y| masses[y] * path[x * n + y]).sum::<f64>() / mass * (1.0 + 1e-12)
            })
            .collect();
        Ok(FlexibleType {
            mass,
            masses,
            species: atoms.iter().map(|a| a.species).collect(),
            bonds: bonds.to_vec(),
            lengths,
            reference,
            radii,
            hops,
            own: Vec::new(),
            rigid: None,
        })
    }

    /// A rigid molecule of `atoms` among semi-flexible ones: no bonds, the exact free motion of
    /// its [`MoleculeType`] between events ([`rigid`] module), the arms' exact lengths as
    /// bounding radii.
    ///
    /// # Errors
    /// [`FlexibleError::Molecule`] for what [`MoleculeType::new`] refuses, and more atoms than
    /// a site-pair table can index.
    pub fn rigid(atoms: &[SiteAtom]) -> Result<Self, FlexibleError> {
        if atoms.len() > usize::from(u16::MAX) {
            return Err(FlexibleError::TooManyAtoms(atoms.len()));
        }
        let m = MoleculeType::new(atoms)?;
        let centre = m.centre();
        Ok(FlexibleType {
            mass: m.mass(),
            masses: m.masses().to_vec(),
            species: m.site_species().to_vec(),
            bonds: Vec::new(),
            lengths: Vec::new(),
            reference: atoms.iter().map(|a| a.position - centre).collect(),
            radii: m.radii.clone(),
            hops: Vec::new(),
            own: Vec::new(),
            rigid: Some(Arc::new(m)),
        })
    }

    /// The molecule whose atoms more than `bonds` bonds apart (along the shortest bond path)
    /// interact with each other through their site species' potential, as atoms of different
    /// molecules do (`bonds ≥ 1`: bonded atoms never interact, their distance is held).
    pub fn interacting_beyond(mut self, bonds: u32) -> Self {
        if self.rigid.is_some() {
            // The atoms of a rigid molecule keep their distances.
            return self;
        }
        let n = self.masses.len();
        self.own = (0..n)
            .flat_map(|a| (a + 1..n).map(move |b| (a, b)))
            .filter(|&(a, b)| self.hops[a * n + b] > bonds.max(1))
            .map(|(a, b)| (a as u16, b as u16))
            .collect();
        self
    }

    /// The atom pairs `a < b` of one molecule that interact ([`interacting_beyond`](Self::interacting_beyond)).
    pub fn own_pairs(&self) -> &[(u16, u16)] {
        &self.own
    }

    /// Total mass.
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// Atom masses.
    pub fn masses(&self) -> &[f64] {
        &self.masses
    }

    /// Site species of the atoms.
    pub fn site_species(&self) -> &[u32] {
        &self.species
    }

    /// The distance constraints.
    pub fn bonds(&self) -> &[Bond] {
        &self.bonds
    }

    /// The bond lengths.
    pub fn lengths(&self) -> &[f64] {
        &self.lengths
    }

    /// The reference configuration relative to its centre of mass.
    pub fn reference(&self) -> &[DVec3] {
        &self.reference
    }

    /// The bound `ρ_α` on atom `α`'s distance from the centre of mass in any configuration the
    /// bonds allow (module documentation).
    pub fn radii(&self) -> &[f64] {
        &self.radii
    }

    /// Internal degrees of freedom: `3n − 3 − (bonds)` (the bonds are independent), or the
    /// rotations of a rigid molecule (2 for a linear one, else 3).
    pub fn internal_dof(&self) -> f64 {
        match &self.rigid {
            Some(m) => m.rotational_dof(),
            None => (3 * self.masses.len() - 3 - self.bonds.len()) as f64,
        }
    }

    /// The centre of mass of positions `q` of this molecule's atoms.
    pub fn centre_of(&self, q: &[DVec3]) -> DVec3 {
        self.masses
            .iter()
            .zip(q)
            .fold(DVec3::ZERO, |s, (&m, &x)| s + m * x)
            / self.mass
    }
}

/// The bonds' metric matrix `Z_αβ = Σ_k (1/m_k) ∇_kσ_α·∇_kσ_β` (000 §II.A) at atom positions
/// `q`, row-major, for the constraint functions `σ_α` whose gradient at bond `α`'s first atom
/// is the bond vector `r_α` divided by `norm(r_α)` (the second atom's is its negative).
fn bond_metric(
    masses: &[f64],
    bonds: &[Bond],
    q: &[DVec3],
    norm: impl Fn(DVec3) -> f64,
) -> Vec<f64> {
    let nb = bonds.len();
    let r: Vec<DVec3> = bonds.iter().map(|b| q[b.a] - q[b.b]).collect();
    let n: Vec<f64> = r.iter().map(|&x| norm(x)).collect();
    let mut z = vec![0.0; nb * nb];
    for (x, bx) in bonds.iter().enumerate() {
        for (y, by) in bonds.iter().enumerate() {
            // Only the atoms the two bonds share contribute.
            let mut s = 0.0;
            for (atom, sx) in [(bx.a, 1.0), (bx.b, -1.0)] {
                for (other, sy) in [(by.a, 1.0), (by.b, -1.0)] {
                    if atom == other {
                        s += sx * sy / masses[atom];
                    }
                }
            }
            z[x * nb + y] = s * r[x].dot(r[y]) / (n[x] * n[y]);
        }
    }
    z
}

/// Cholesky factorisation of the symmetric `nb × nb` matrix `z` in place (lower triangle).
/// The first row whose pivot is below `floor` times its diagonal (or not a number) is the
/// error.
fn cholesky(z: &mut [f64], nb: usize, floor: f64) -> Result<(), usize> {
    for k in 0..nb {
        let diag = z[k * nb + k];
        let mut p = diag;
        for m in 0..k {
            p -= z[k * nb + m] * z[k * nb + m];
        }
        if p.is_nan() || p <= floor * diag {
            return Err(k);
        }
        let p = p.sqrt();
        z[k * nb + k] = p;
        for r in k + 1..nb {
            let mut s = z[r * nb + k];
            for m in 0..k {
                s -= z[r * nb + m] * z[k * nb + m];
            }
            z[r * nb + k] = s / p;
        }
    }
    Ok(())
}

/// The first bond whose Cholesky pivot of `Z` is below [`BOND_PIVOT`] of its diagonal, if
/// any (gradients `r_α` unnormalised: the test is relative, so their scale does not matter).
fn dependent_bond(masses: &[f64], bonds: &[Bond], q: &[DVec3]) -> Option<usize> {
    let mut z = bond_metric(masses, bonds, q, |_| 1.0);
    cholesky(&mut z, bonds.len(), BOND_PIVOT).err()
}

/// `½ ln det Z` of one molecule at atom positions `q`, for unit constraint gradients
/// (`σ_α = |r_α| − b_α`): the density of the measure that the constrained dynamics leaves
/// invariant on the bond surface, relative to the flat one `Π_α δ(|r_α| − b_α) d³q` of the
/// stiff-spring limit (000 §II.A; Fixman). `+∞` never occurs for bonds that passed
/// [`FlexibleType::new`]; a configuration where they become dependent gives `−∞`.
pub fn half_log_det_z(masses: &[f64], bonds: &[Bond], q: &[DVec3]) -> f64 {
    let nb = bonds.len();
    let mut z = bond_metric(masses, bonds, q, DVec3::length);
    match cholesky(&mut z, nb, 0.0) {
        // det Z = Π L_kk², so ½ ln det Z = Σ ln L_kk.
        Ok(()) => (0..nb).map(|k| z[k * nb + k].ln()).sum(),
        Err(_) => f64::NEG_INFINITY,
    }
}

/// The RATTLE propagation of the internal motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RattleSettings {
    /// The step `h`.
    pub step: f64,
    /// Relative tolerance of the SHAKE and velocity iterations (bond lengths, bond rates).
    pub tolerance: f64,
    /// At each event, scale a molecule's interpolated internal velocities to the internal
    /// kinetic energy of its start (which the exact free motion conserves), and after the
    /// impulse restore what the tangent projection removed: the total energy is then
    /// conserved to round-off and the RATTLE error shows in the trajectory only. Off: the
    /// energy takes the step's `O(h²)` error at every event (module documentation).
    pub rescale: bool,
}

impl RattleSettings {
    fn check(&self) -> Result<(), FlexibleError> {
        if !(self.step.is_finite() && self.step > 0.0) {
            return Err(FlexibleError::Rattle {
                name: "step",
                value: self.step,
                why: "positive and finite",
            });
        }
        if !(self.tolerance >= 1e-15 && self.tolerance <= 1e-4) {
            return Err(FlexibleError::Rattle {
                name: "tolerance",
                value: self.tolerance,
                why: "in [1e-15, 1e-4]",
            });
        }
        Ok(())
    }
}

/// What the RATTLE side of a run did: the size of the corrections at events.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct FlexStats {
    /// RATTLE steps computed.
    pub steps: u64,
    /// Molecule starts set (events, thermostat collisions).
    pub restarts: u64,
    /// Largest relative bond-length error of an interpolated state at an event (the start of
    /// the molecule's next trajectory; its first RATTLE step restores the bonds).
    pub interpolated_bond_error: f64,
    /// Largest relative change of a molecule's internal kinetic energy by the velocity
    /// projection after an impulse.
    pub projection_energy: f64,
    /// Trajectories whose RATTLE step failed (their pairs got no events; the run is broken).
    pub failures: u64,
}

impl FlexStats {
    /// Adds the figures to a model's report (prefix `rattle.`).
    pub fn report_into(&self, report: &mut Report) {
        report.count("rattle.steps", self.steps);
        report.count("rattle.restarts", self.restarts);
        report.real(
            "rattle.interpolated_bond_error",
            self.interpolated_bond_error,
        );
        report.real("rattle.projection_energy", self.projection_energy);
        report.count("rattle.failures", self.failures);
    }

    /// The figures of a model's report (`None` for a model without RATTLE).
    pub fn from_report(report: &Report) -> Option<FlexStats> {
        Some(FlexStats {
            steps: report.get_count("rattle.steps")?,
            restarts: report.get_count("rattle.restarts")?,
            interpolated_bond_error: report.get_real("rattle.interpolated_bond_error")?,
            projection_energy: report.get_real("rattle.projection_energy")?,
            failures: report.get_count("rattle.failures")?,
        })
    }
}

/// Semi-flexible molecules with stepped site–site potentials (module documentation).
#[derive(Debug)]
pub struct Flexible {
    types: Vec<FlexibleType>,
    constraints: Vec<Constraints>,
    /// Site pairs, their levels and searches, and the molecules' types.
    table: SiteTable,
    motions: Vec<Motion>,
    rattle: RattleSettings,
    solver: ConstraintSolver,
    flex: FlexStats,
    /// Kinetic energy the integration brought in at events, not yet taken by the loop.
    kinetic_error: f64,
}

/// Mutable references to two different elements.
fn two<T>(v: &mut [T], i: usize, j: usize) -> (&mut T, &mut T) {
    debug_assert_ne!(i, j);
    if i < j {
        let (a, b) = v.split_at_mut(j);
        (&mut a[i], &mut b[0])
    } else {
        let (a, b) = v.split_at_mut(i);
        (&mut b[0], &mut a[j])
    }
}

/// The internal kinetic energy `½ Σ m u²`.
fn kinetic(masses: &[f64], u: &[DVec3]) -> f64 {
    masses
        .iter()
        .zip(u)
        .map(|(m, x)| 0.5 * m * x.length_squared())
        .sum()
}

/// How one molecule's atoms move between its events.
#[derive(Clone, Debug)]
enum Motion {
    /// A semi-flexible molecule: RATTLE steps and their interpolant.
    Rattle(Trajectory),
    /// A rigid molecule: its exact free motion (boxed: a free motion is several times the
    /// size of a trajectory's record).
    Rigid(Box<RigidMotion>),
}

impl Motion {
    /// Drops RATTLE steps behind `now`.
    fn trim(&mut self, now: f64) {
        if let Motion::Rattle(t) = self {
            t.trim(now);
        }
    }

    /// RATTLE steps computed so far.
    fn computed_steps(&self) -> usize {
        match self {
            Motion::Rattle(t) => t.computed_steps(),
            Motion::Rigid(_) => 0,
        }
    }

    /// A RATTLE step failed.
    fn failed(&self) -> bool {
        matches!(self, Motion::Rattle(t) if t.failure().is_some())
    }

    /// Arm and velocity of atom `a` about the centre at `t`.
    #[inline]
    fn atom_at(
        &mut self,
        c: &Constraints,
        t: f64,
        a: usize,
    ) -> Result<(DVec3, DVec3), RattleError> {
        match self {
            Motion::Rattle(tr) => tr.atom_at(c, t, a),
            Motion::Rigid(m) => Ok(m.atom_at(t, a)),
        }
    }

    /// Arms and velocities of every atom at `t`, keeping computed RATTLE steps.
    fn state_at(
        &mut self,
        c: &Constraints,
        t: f64,
    ) -> Result<(Vec<DVec3>, Vec<DVec3>), RattleError> {
        match self {
            Motion::Rattle(tr) => tr.state_at(c, t),
            Motion::Rigid(m) => Ok(m.state_at(t)),
        }
    }

    /// Arms and velocities of every atom at `t`, read-only.
    fn peek(&self, c: &Constraints, t: f64) -> Result<(Vec<DVec3>, Vec<DVec3>), RattleError> {
        match self {
            Motion::Rattle(tr) => tr.peek(c, t),
            Motion::Rigid(m) => Ok(m.state_at(t)),
        }
    }

    /// Arms and velocities at the last change.
    fn initial(&self) -> (&[DVec3], &[DVec3]) {
        match self {
            Motion::Rattle(t) => t.initial(),
            Motion::Rigid(m) => m.initial(),
        }
    }

    /// Moves the time origin to `t0`.
    fn rebase(&mut self, t0: f64) {
        match self {
            // The steps stay: only their time origin moves (re-anchoring would change the
            // trajectory by the interpolation error, not by round-off).
            Motion::Rattle(t) => t.shift_time(t0),
            Motion::Rigid(m) => m.rebase(t0),
        }
    }

    fn write_numbers(&self, x: &mut Vec<f64>) {
        match self {
            Motion::Rattle(t) => t.write_numbers(x),
            Motion::Rigid(m) => m.write_numbers(x),
        }
    }
}

impl Flexible {
    /// Molecules of `types` interacting through the site–site `potentials`; body `i` is of type
    /// `body_type[i]` with atom positions `positions[i]` and velocities `velocities[i]` at time
    /// `t0` (any origin: the centre of mass and its velocity are taken off, they are the loop's
    /// body record); internal motion by RATTLE with `rattle`, searches with `settings`, jitter
    /// drawn from `seed`. Positions must satisfy the bonds to [`START_TOLERANCE`] and are then
    /// projected onto them exactly; velocities are projected onto the constraints' tangent.
    ///
    /// # Errors
    /// [`FlexibleError`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        types: Vec<FlexibleType>,
        potentials: Potentials,
        body_type: &[u32],
        positions: &[Vec<DVec3>],
        velocities: &[Vec<DVec3>],
        t0: f64,
        rattle: RattleSettings,
        settings: SearchSettings,
        seed: u64,
    ) -> Result<Self, FlexibleError> {
        rattle.check()?;
        check_settings(&settings).map_err(FlexibleError::Search)?;
        let ns = potentials.n_species();
        for t in &types {
            if let Some(&s) = t.species.iter().find(|&&s| s as usize >= ns) {
                return Err(FlexibleError::SiteSpecies(s, ns));
            }
        }
        let constraints: Vec<Constraints> = types
            .iter()
            .map(|t| Constraints::new(&t.masses, &t.bonds, &t.lengths, rattle.tolerance))
            .collect();
        if positions.len() != body_type.len() || velocities.len() != body_type.len() {
            return Err(FlexibleError::Body {
                body: positions.len().min(velocities.len()),
                problem: format!(
                    "{} bodies, but {} position and {} velocity sets",
                    body_type.len(),
                    positions.len(),
                    velocities.len()
                ),
            });
        }
        let mut motions = Vec::with_capacity(body_type.len());
        for (i, &ty) in body_type.iter().enumerate() {
            let Some(t) = types.get(ty as usize) else {
                return Err(FlexibleError::Type { body: i, kind: ty });
            };
            let c = &constraints[ty as usize];
            let body = |problem: String| FlexibleError::Body { body: i, problem };
            let (q, u) = (&positions[i], &velocities[i]);
            if q.len() != t.masses.len() || u.len() != t.masses.len() {
                return Err(body(format!(
                    "{} positions and {} velocities for {} atoms",
                    q.len(),
                    u.len(),
                    t.masses.len()
                )));
            }
            if !q.iter().chain(u).all(|x| x.is_finite()) {
                return Err(body("a position or velocity is not finite".into()));
            }
            let centre = t.centre_of(q);
            let vc = t.centre_of(u);
            let mut q: Vec<DVec3> = q.iter().map(|&x| x - centre).collect();
            let mut u: Vec<DVec3> = u.iter().map(|&x| x - vc).collect();
            if let Some(m) = &t.rigid {
                let motion = RigidMotion::fitted(Arc::clone(m), t0, &q, &u, START_TOLERANCE)
                    .map_err(body)?;
                motions.push(Motion::Rigid(Box::new(motion)));
                continue;
            }
            let off = c.violation(&q);
            if off > START_TOLERANCE {
                return Err(body(format!(
                    "the atoms miss their bond lengths by {off:e} (relative): more than {}",
                    START_TOLERANCE
                )));
            }
            c.project_positions(&mut q)
                .and_then(|()| c.project_velocities(&q, &mut u))
                .map_err(|e| body(e.to_string()))?;
            motions.push(Motion::Rattle(Trajectory::new(t0, rattle.step, &q, &u)));
        }
        let own: Vec<Vec<(u16, u16)>> = types.iter().map(|t| t.own.clone()).collect();
        let species: Vec<&[u32]> = types.iter().map(|t| &t.species[..]).collect();
        let table = SiteTable::new(
            types.iter().map(|t| (&t.species[..], &t.radii[..])),
            potentials,
            body_type,
            settings,
            mix(seed ^ 0xf1e8_0000_0000_0013),
        )
        .with_own_pairs(&own, &species);
        Ok(Flexible {
            types,
            constraints,
            table,
            motions,
            rattle,
            solver: ConstraintSolver::new(),
            flex: FlexStats::default(),
            kinetic_error: 0.0,
        })
    }

    /// The molecule types.
    pub fn types(&self) -> &[FlexibleType] {
        &self.types
    }

    /// The RATTLE settings.
    pub fn rattle(&self) -> RattleSettings {
        self.rattle
    }

    /// Counters of this model's root searches so far.
    pub fn search_stats(&self) -> SearchStats {
        self.table.stats
    }

    /// What the RATTLE side did so far.
    pub fn flex_stats(&self) -> FlexStats {
        let mut f = self.flex;
        f.failures = self.motions.iter().filter(|m| m.failed()).count() as u64 + self.flex.failures;
        f
    }

    /// Atom positions relative to the centre and internal velocities of molecule `i` at `now`
    /// (read-only: steps beyond the cache are computed and dropped).
    ///
    /// # Errors
    /// The RATTLE step that failed.
    pub fn internal_state(
        &self,
        i: u32,
        now: f64,
    ) -> Result<(Vec<DVec3>, Vec<DVec3>), RattleError> {
        let ty = self.table.type_of(i);
        self.motions[i as usize].peek(&self.constraints[ty], now)
    }

    /// Largest relative bond-length error over all molecules at their last change (where the
    /// state is projected) and at `now` (interpolated).
    pub fn bond_error(&self, now: f64) -> f64 {
        let mut worst: f64 = 0.0;
        for (i, t) in self.motions.iter().enumerate() {
            let c = &self.constraints[self.table.type_of(i as u32)];
            worst = worst.max(c.violation(t.initial().0));
            match self.internal_state(i as u32, now) {
                Ok((q, _)) => worst = worst.max(c.violation(&q)),
                Err(_) => return f64::INFINITY,
            }
        }
        worst
    }

    /// The stored level of site `a` of `i` with site `b` of `j`.
    pub fn site_level(&self, i: u32, j: u32, a: usize, b: usize) -> u16 {
        self.table.site_level(i, j, a, b)
    }

    /// Runs every site pair of `pair` whose search is due (on the molecules' motions), then
    /// picks the pair's next event ([`SiteTable::choose`]); a failed RATTLE step makes it due
    /// at once.
    fn search(
        table: &mut SiteTable,
        (motions, constraints, flex): (&mut [Motion], &[Constraints], &mut FlexStats),
        pair: &Pair,
        mut sites: Vec<SiteSearch>,
        fresh: bool,
    ) -> Option<(f64, Kind)> {
        let Pair {
            i, j, now, dr, dv, ..
        } = *pair;
        let (ti, tj) = (table.type_of(i), table.type_of(j));
        // Steps behind the present are not needed again.
        motions[i as usize].trim(now);
        motions[j as usize].trim(now);
        let before: usize =
            motions[i as usize].computed_steps() + motions[j as usize].computed_steps();
        if i == j {
            let mut geo = OwnGeometry {
                motion: &mut motions[i as usize],
                c: &constraints[ti],
            };
            table.search_due(&mut geo, (i, j), now, &mut sites, fresh);
        } else {
            let (motion_i, motion_j) = two(motions, i as usize, j as usize);
            let mut geo = FlexGeometry {
                motion_i,
                motion_j,
                ci: &constraints[ti],
                cj: &constraints[tj],
                dr,
                dv,
                now,
            };
            table.search_due(&mut geo, (i, j), now, &mut sites, fresh);
        }
        let after: usize =
            motions[i as usize].computed_steps() + motions[j as usize].computed_steps();
        flex.steps += after.saturating_sub(before) as u64;
        if motions[i as usize].failed() || motions[j as usize].failed() {
            table.save(i, j, now, Pending::Broken);
            return Some((0.0, Kind::Pair(Boundary::Inner)));
        }
        table.choose(i, j, now, sites)
    }

    /// The event of two atoms of molecule `i` (`fired`): the impulse along their separation
    /// with the impulsive constraint forces of the molecule's own bonds (000 §IV.A). The
    /// impulses sum to zero, so the centre velocity (`vi`, and `vj`, the same body's) stays.
    fn execute_within(
        &mut self,
        i: u32,
        now: f64,
        fired: &Firing,
        vi: &mut DVec3,
        vj: &mut DVec3,
    ) -> Result<Executed, CollideError> {
        let t = self.table.type_of(i);
        let (q, mut u) = self.motions[i as usize]
            .state_at(&self.constraints[t], now)
            .map_err(|_| BROKEN)?;
        self.rescale(i as usize, &mut u);
        let (a, b) = (fired.a, fired.b);
        let n = q[a] - q[b];
        let judged = self.table.judge(fired, n, n.dot(u[a] - u[b]));
        if !judged.right_way {
            return Ok(Executed {
                class: PairClass::Skipped,
                delta_u: 0.0,
                virial: 0.0,
                overlap: judged.overlap,
            });
        }
        let before = self.internal_kinetic(i as usize);
        let ty = &self.types[t];
        let imp = self.solver.within(
            Molecule {
                masses: &ty.masses,
                positions: &q,
                velocities: &mut u,
                bonds: &ty.bonds,
            },
            a,
            b,
            judged.step,
        )?;
        // The centre of the internal velocities moves by round-off only: it stays at zero.
        let drift = ty.centre_of(&u);
        let u: Vec<DVec3> = u.iter().map(|&x| x - drift).collect();
        self.restart(i, now, q, u, self.rattle.rescale)
            .map_err(|_| BROKEN)?;
        *vj = *vi;
        self.kinetic_error += self.internal_kinetic(i as usize) - before + imp.delta_v;
        Ok(Executed {
            class: self.table.settle(i, i, fired, imp.outcome, judged.step),
            delta_u: imp.delta_v,
            // The molecular virial counts forces between molecules only.
            virial: 0.0,
            overlap: judged.overlap,
        })
    }

    /// A rigid molecule as an impulse rule sees it at `now`, with its lab angular velocity
    /// (`None` for a semi-flexible one).
    fn rigid_at(&self, i: u32, now: f64) -> Result<Option<(SiteBody, DVec3)>, CollideError> {
        match &self.motions[i as usize] {
            Motion::Rigid(m) => m.body_at(now).map(Some),
            Motion::Rattle(_) => Ok(None),
        }
    }

    /// Restarts molecule `i` at `now` after an impulse and returns its new centre velocity:
    /// a rigid molecule from the rule's new velocity `rigid`, a semi-flexible one from its
    /// atoms' new lab velocities `vel` at arms `q` (the centre's part taken off, the rest
    /// projected onto the bonds' tangent).
    fn after_impulse(
        &mut self,
        i: u32,
        now: f64,
        q: Vec<DVec3>,
        vel: &[DVec3],
        rigid: Option<Velocity>,
    ) -> Result<DVec3, CollideError> {
        if let (Motion::Rigid(m), Some(v)) = (&self.motions[i as usize], rigid) {
            let next = m
                .restarted(now, v.angular)
                .map_err(|_| CollideError::NotFinite("angular velocity after the impulse"))?;
            self.motions[i as usize] = Motion::Rigid(Box::new(next));
            self.flex.restarts += 1;
            return Ok(v.linear);
        }
        let t = &self.types[self.table.type_of(i)];
        let centre = t.centre_of(vel);
        let internal: Vec<DVec3> = vel.iter().map(|&x| x - centre).collect();
        let keep = self.rattle.rescale;
        self.restart(i, now, q, internal, keep)
            .map_err(|_| BROKEN)?;
        Ok(centre)
    }

    /// A rigid molecule `i` restarts at `now` with its angular velocity times `factor`
    /// (exactly: nothing projected); `false` for a semi-flexible one.
    fn respin(&mut self, i: u32, now: f64, factor: f64) -> bool {
        let Motion::Rigid(m) = &self.motions[i as usize] else {
            return false;
        };
        match m.restarted(now, factor * m.pose(now).1) {
            Ok(next) => {
                self.motions[i as usize] = Motion::Rigid(Box::new(next));
                self.flex.restarts += 1;
            }
            Err(_) => self.flex.failures += 1,
        }
        true
    }

    /// Starts molecule `i` afresh at `now` from internal positions `q` (kept as they are: the
    /// event's site pair stays at its boundary) and velocities `u` (projected onto the tangent
    /// of the bonds there; with `keep`, scaled back to their kinetic energy before the
    /// projection). Returns the kinetic energy the projection removed.
    fn restart(
        &mut self,
        i: u32,
        now: f64,
        q: Vec<DVec3>,
        mut u: Vec<DVec3>,
        keep: bool,
    ) -> Result<f64, RattleError> {
        let ty = self.table.type_of(i);
        if let Motion::Rigid(m) = &self.motions[i as usize] {
            // The rotation of the atoms' angular momentum: the mass-weighted projection of `u`
            // onto the rigid motions (the orientation is the motion's own at `now`).
            let (o, _) = m.pose(now);
            let w = m.omega_of_atoms(o, &q, &u);
            let k0 = kinetic(&self.types[ty].masses, &u);
            let next = m.restarted(now, w).map_err(|_| RattleError::NotFinite)?;
            self.motions[i as usize] = Motion::Rigid(Box::new(next));
            self.flex.restarts += 1;
            return Ok(k0 - self.internal_kinetic(i as usize));
        }
        let c = &self.constraints[ty];
        let t = &self.types[ty];
        self.flex.interpolated_bond_error = self.flex.interpolated_bond_error.max(c.violation(&q));
        let k0 = kinetic(&t.masses, &u);
        c.project_velocities(&q, &mut u)?;
        let k1 = kinetic(&t.masses, &u);
        if k0 > 0.0 {
            self.flex.projection_energy = self.flex.projection_energy.max((k0 - k1).abs() / k0);
        }
        if keep && k1 > 0.0 {
            let f = (k0 / k1).sqrt();
            for x in &mut u {
                *x *= f;
            }
        }
        self.flex.restarts += 1;
        if let Motion::Rattle(t) = &mut self.motions[i as usize] {
            t.reset(now, &q, &u);
        }
        Ok(k0 - k1)
    }

    /// With [`RattleSettings::rescale`], scales molecule `i`'s interpolated internal velocities
    /// `u` to the kinetic energy of its start, which the exact free motion conserves.
    fn rescale(&self, i: usize, u: &mut [DVec3]) {
        // A rigid molecule's free motion conserves its kinetic energy exactly.
        if !self.rattle.rescale || matches!(self.motions[i], Motion::Rigid(_)) {
            return;
        }
        let t = &self.types[self.table.type_of(i as u32)];
        let (k, target) = (kinetic(&t.masses, u), self.internal_kinetic(i));
        if k > 0.0 {
            let f = (target / k).sqrt();
            for x in u {
                *x *= f;
            }
        }
    }

    /// Internal kinetic energy of molecule `i` at its last change.
    fn internal_kinetic(&self, i: usize) -> f64 {
        let t = &self.types[self.table.type_of(i as u32)];
        kinetic(&t.masses, self.motions[i].initial().1)
    }

    /// Draws molecule `i`'s internal velocities afresh at `kt` at `now` (Gaussian atom
    /// velocities, centre velocity taken off, projected onto the constraints' tangent: the
    /// Maxwell–Boltzmann distribution of the constrained internal motion). Returns the change
    /// of the internal kinetic energy.
    fn draw_internal(
        &mut self,
        i: u32,
        now: f64,
        kt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> Result<f64, RattleError> {
        let ty = self.table.type_of(i);
        let before = self.internal_kinetic(i as usize);
        let (q, _) = self.motions[i as usize].state_at(&self.constraints[ty], now)?;
        let u = draw_velocities(&self.types[ty], kt, rng);
        self.restart(i, now, q, u, false)?;
        Ok(self.internal_kinetic(i as usize) - before)
    }
}

/// Gaussian atom velocities at `kt` with the centre velocity taken off (not yet projected).
fn draw_velocities(t: &FlexibleType, kt: f64, rng: &mut Xoshiro256PlusPlus) -> Vec<DVec3> {
    let mut u: Vec<DVec3> = t
        .masses
        .iter()
        .map(|&m| {
            let g: [f64; 3] = std::array::from_fn(|_| StandardNormal.sample(rng));
            DVec3::from(g) * (kt / m).sqrt()
        })
        .collect();
    let vc = t.centre_of(&u);
    for x in &mut u {
        *x -= vc;
    }
    u
}

/// Random starts for bodies of `body_type`: each molecule's reference configuration turned by
/// a rotation uniform on SO(3), and internal velocities from the Maxwell–Boltzmann distribution
/// at `kt` on the constraints' tangent (projected by the model). Positions are relative to the
/// centre of mass.
pub fn random_internal(
    types: &[FlexibleType],
    body_type: &[u32],
    kt: f64,
    seed: u64,
) -> (Vec<Vec<DVec3>>, Vec<Vec<DVec3>>) {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
    let mut qs = Vec::with_capacity(body_type.len());
    let mut us = Vec::with_capacity(body_type.len());
    for &ty in body_type {
        let t = &types[ty as usize];
        let rot = loop {
            let c: [f64; 4] = std::array::from_fn(|_| StandardNormal.sample(&mut rng));
            let q = DQuat::from_xyzw(c[0], c[1], c[2], c[3]);
            if q.length_squared() > 1e-6 {
                break q.normalize();
            }
        };
        qs.push(t.reference.iter().map(|&x| rot * x).collect());
        us.push(draw_velocities(t, kt, &mut rng));
    }
    (qs, us)
}

/// The two molecules of a pair and their relative centre motion: what the indicators need.
struct FlexGeometry<'a> {
    motion_i: &'a mut Motion,
    motion_j: &'a mut Motion,
    ci: &'a Constraints,
    cj: &'a Constraints,
    dr: DVec3,
    dv: DVec3,
    now: f64,
}

impl SiteDistance for FlexGeometry<'_> {
    /// On the molecules' motions (NaN if a RATTLE step failed).
    #[inline]
    fn distance2(&mut self, a: usize, b: usize, t: f64) -> (f64, f64) {
        match (
            self.motion_i.atom_at(self.ci, t, a),
            self.motion_j.atom_at(self.cj, t, b),
        ) {
            (Ok((qa, ua)), Ok((qb, ub))) => {
                let r = self.dr + self.dv * (t - self.now) + qa - qb;
                let u = self.dv + ua - ub;
                (r.length_squared(), 2.0 * r.dot(u))
            }
            _ => (f64::NAN, f64::NAN),
        }
    }
}

/// Where two atoms of one molecule are, on its RATTLE trajectory.
struct OwnGeometry<'a> {
    motion: &'a mut Motion,
    c: &'a Constraints,
}

impl SiteDistance for OwnGeometry<'_> {
    /// On the RATTLE trajectory (NaN if a step failed).
    #[inline]
    fn distance2(&mut self, a: usize, b: usize, t: f64) -> (f64, f64) {
        match (
            self.motion.atom_at(self.c, t, a),
            self.motion.atom_at(self.c, t, b),
        ) {
            (Ok((qa, ua)), Ok((qb, ub))) => {
                let (r, u) = (qa - qb, ua - ub);
                (r.length_squared(), 2.0 * r.dot(u))
            }
            _ => (f64::NAN, f64::NAN),
        }
    }
}

/// The error an impulse reports for a molecule whose RATTLE trajectory broke.
const BROKEN: CollideError = CollideError::FreeMotion(
    "a RATTLE step of a semi-flexible molecule failed (a bond turned by about a right angle \
     within one step, or SHAKE did not converge): the step h is too long for its internal motion",
);

impl PairModel for Flexible {
    fn reach(&self) -> f64 {
        self.table.reach()
    }

    fn n_species(&self) -> usize {
        self.types.len()
    }

    fn mass(&self, s: u32) -> f64 {
        self.types[s as usize].mass
    }

    const SELF_PAIRS: bool = true;

    #[inline]
    fn self_pairs(&self, s: u32) -> bool {
        self.table.has_own_pairs(s as usize)
    }

    fn setup_pair(&mut self, pair: &Pair) -> Result<(), PairSetupError> {
        let Pair { i, j, dr, .. } = *pair;
        self.table.setup(
            i,
            j,
            dr,
            self.motions[i as usize].initial().0,
            self.motions[j as usize].initial().0,
        )
    }

    fn predict(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let motion = (&mut self.motions[..], &self.constraints[..], &mut self.flex);
        self.table.predict(pair, |table, sites, fresh| {
            Self::search(table, motion, pair, sites, fresh)
        })
    }

    fn resume(&mut self, pair: &Pair) -> Option<(f64, Kind)> {
        let motion = (&mut self.motions[..], &self.constraints[..], &mut self.flex);
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
        let fired = match self.table.fire(i, j, now) {
            Ok(Some(fired)) => fired,
            Ok(None) => return Ok(skipped(false)),
            Err(()) => return Err(BROKEN),
        };
        let (a, b) = (fired.a, fired.b);
        if i == j {
            return self.execute_within(i, now, &fired, vi, vj);
        }
        let (ti, tj) = (self.table.type_of(i), self.table.type_of(j));
        // The atoms exactly as the search saw them.
        let (qi, mut ui) = self.motions[i as usize]
            .state_at(&self.constraints[ti], now)
            .map_err(|_| BROKEN)?;
        let (qj, mut uj) = self.motions[j as usize]
            .state_at(&self.constraints[tj], now)
            .map_err(|_| BROKEN)?;
        self.rescale(i as usize, &mut ui);
        self.rescale(j as usize, &mut uj);
        let n = dr + qi[a] - qj[b];
        let judged = self
            .table
            .judge(&fired, n, n.dot((*vi + ui[a]) - (*vj + uj[b])));
        let step = judged.step;
        if !judged.right_way {
            return Ok(skipped(judged.overlap));
        }
        // Lab positions relative to j's centre, lab velocities.
        let pos_i: Vec<DVec3> = qi.iter().map(|&x| dr + x).collect();
        let mut vel_i: Vec<DVec3> = ui.iter().map(|&x| *vi + x).collect();
        let mut vel_j: Vec<DVec3> = uj.iter().map(|&x| *vj + x).collect();
        let (rigid_i, rigid_j) = (self.rigid_at(i, now)?, self.rigid_at(j, now)?);
        let (type_i, type_j) = (&self.types[ti], &self.types[tj]);
        let mol_i = Molecule {
            masses: &type_i.masses,
            positions: &pos_i,
            velocities: &mut vel_i,
            bonds: &type_i.bonds,
        };
        let mol_j = Molecule {
            masses: &type_j.masses,
            positions: &qj,
            velocities: &mut vel_j,
            bonds: &type_j.bonds,
        };
        // The impulse on i is `S n` in every pairing: constrained atoms (000 §IV.A), a rigid
        // molecule (000 §IV.B), or one of each.
        let (imp, after_i, after_j) = match (rigid_i, rigid_j) {
            (None, None) => (self.solver.between(mol_i, a, mol_j, b, step)?, None, None),
            (None, Some((body, w))) => {
                let v = Velocity::new(*vj, w);
                let (imp, after) = self
                    .solver
                    .against_rigid(mol_i, a, &body, v, qj[b], qj[b], step)?;
                (imp, None, Some(after))
            }
            (Some((body, w)), None) => {
                let v = Velocity::new(*vi, w);
                let (imp, after) = self
                    .solver
                    .against_rigid(mol_j, b, &body, v, pos_i[a], qi[a], step)?;
                (imp, Some(after), None)
            }
            (Some((bi, wi)), Some((bj, wj))) => {
                let (vel_i, vel_j) = (Velocity::new(*vi, wi), Velocity::new(*vj, wj));
                let out = contact(&bi, &bj, vel_i, vel_j, &Contact::new(n, qi[a], qj[b]), step)?;
                (out.impulse, Some(out.i), Some(out.j))
            }
        };
        // Kinetic energy as the loop counts it (centres, internal motion at the starts).
        let counted = |this: &Self, vi: DVec3, vj: DVec3| {
            0.5 * this.types[ti].mass * vi.length_squared()
                + 0.5 * this.types[tj].mass * vj.length_squared()
                + this.internal_kinetic(i as usize)
                + this.internal_kinetic(j as usize)
        };
        let before = counted(self, *vi, *vj);
        let new_vi = self.after_impulse(i, now, qi, &vel_i, after_i)?;
        let new_vj = self.after_impulse(j, now, qj, &vel_j, after_j)?;
        *vi = new_vi;
        *vj = new_vj;
        // What the loop does not see: the change beyond −ΔU (the RATTLE step's energy error
        // between the starts and now, and the projection).
        self.kinetic_error += counted(self, new_vi, new_vj) - before + imp.delta_v;
        Ok(Executed {
            class: self.table.settle(i, j, &fired, imp.outcome, step),
            delta_u: imp.delta_v,
            virial: imp.s * dr.dot(n),
            overlap: judged.overlap,
        })
    }

    // Levels are kept per site pair in the model's own map (as `sites`): the loop's per-pair
    // level is always 0.
    fn level(&self, _i: u32, _j: u32) -> u16 {
        0
    }

    fn set_level(&mut self, _i: u32, _j: u32, level: u16) {
        debug_assert_eq!(
            level, 0,
            "semi-flexible molecules keep their levels per site pair"
        );
    }

    fn storable_level(&self, _si: u32, _sj: u32, _level: u16) -> bool {
        false
    }

    fn configured_level(&self, pair: &Pair, _stored: u16) -> (u16, f64) {
        let Pair { i, j, now, dr, .. } = *pair;
        let (Ok((qi, _)), Ok((qj, _))) = (self.internal_state(i, now), self.internal_state(j, now))
        else {
            return (0, f64::INFINITY);
        };
        (0, self.table.configured_energy(i, j, dr, &qi, &qj))
    }

    fn extra_state(&self) -> Vec<f64> {
        let mut x = Vec::new();
        for m in &self.motions {
            m.write_numbers(&mut x);
        }
        self.table.write_numbers(&mut x);
        let f = &self.flex;
        push_count(&mut x, f.steps);
        push_count(&mut x, f.restarts);
        push_count(&mut x, f.failures);
        x.extend_from_slice(&[
            f.interpolated_bond_error,
            f.projection_energy,
            self.kinetic_error,
        ]);
        x
    }

    fn set_extra_state(&mut self, state: &[f64]) -> Result<(), String> {
        let mut r = StateReader::new(state);
        let mut motions = Vec::with_capacity(self.motions.len());
        for (i, &ty) in self.table.body_type.iter().enumerate() {
            let t = &self.types[ty as usize];
            let motion = match &t.rigid {
                Some(m) => RigidMotion::read_numbers(&mut r, Arc::clone(m))
                    .map(|m| Motion::Rigid(Box::new(m))),
                None => Trajectory::read_numbers(&mut r, self.rattle.step, t.masses.len())
                    .map(Motion::Rattle),
            };
            motions.push(motion.map_err(|e| format!("molecule {i}: {e}"))?);
        }
        let table = self.table.read_numbers(&mut r)?;
        let flex = FlexStats {
            steps: r.count("rattle.steps")?,
            restarts: r.count("rattle.restarts")?,
            failures: r.count("rattle.failures")?,
            interpolated_bond_error: r.real("rattle.interpolated_bond_error")?,
            projection_energy: r.real("rattle.projection_energy")?,
        };
        let kinetic_error = r.real("the kinetic energy error")?;
        r.finish()?;
        self.motions = motions;
        self.table.commit(table);
        self.flex = flex;
        self.kinetic_error = kinetic_error;
        Ok(())
    }

    fn pair_energy(&self, i: u32, j: u32, _si: u32, _sj: u32) -> f64 {
        self.table.pair_energy(i, j)
    }

    fn check_pair(&self, pair: &Pair, listed: bool) -> Result<(), String> {
        let Pair { i, j, now, dr, .. } = *pair;
        let (qi, _) = self
            .internal_state(i, now)
            .map_err(|e| format!("molecule {i}: {e}"))?;
        let (qj, _) = self
            .internal_state(j, now)
            .map_err(|e| format!("molecule {j}: {e}"))?;
        self.table.check((i, j), dr, &qi, &qj, listed)
    }

    #[inline]
    fn forget(&mut self, i: u32) {
        self.table.forget(i);
    }

    fn rebase(&mut self, t0: f64) {
        for m in &mut self.motions {
            m.rebase(t0);
        }
    }

    fn rotational_kinetic(&self) -> f64 {
        let mut k = crate::engine::sum::Compensated::ZERO;
        for i in 0..self.motions.len() {
            k.add(self.internal_kinetic(i));
        }
        k.value()
    }

    fn rotational_dof(&self) -> f64 {
        self.table
            .body_type
            .iter()
            .map(|&t| self.types[t as usize].internal_dof())
            .sum()
    }

    fn thermalize(
        &mut self,
        i: u32,
        _s: u32,
        now: f64,
        kt: f64,
        rng: &mut Xoshiro256PlusPlus,
    ) -> f64 {
        match self.draw_internal(i, now, kt, rng) {
            Ok(dk) => dk,
            Err(_) => {
                self.flex.failures += 1;
                0.0
            }
        }
    }

    /// The atoms on the RATTLE trajectory (`None` if its step failed: the loop reports the
    /// failure itself).
    fn atoms(&self, i: u32, now: f64) -> Option<(Vec<DVec3>, Vec<DVec3>)> {
        self.internal_state(i, now).ok()
    }

    fn spin(&self, i: u32, s: u32) -> DVec3 {
        let (q, u) = self.motions[i as usize].initial();
        self.types[s as usize]
            .masses
            .iter()
            .zip(q.iter().zip(u))
            .fold(DVec3::ZERO, |l, (&m, (&x, &v))| l + m * x.cross(v))
    }

    fn report(&self) -> Report {
        let mut r = Report::default();
        self.table.stats.report_into(&mut r);
        self.flex_stats().report_into(&mut r);
        r
    }

    fn log_metric(&self, now: f64) -> f64 {
        (0..self.motions.len())
            .map(|i| match self.internal_state(i as u32, now) {
                Ok((q, _)) => {
                    let ty = &self.types[self.table.type_of(i as u32)];
                    half_log_det_z(&ty.masses, &ty.bonds, &q)
                }
                Err(_) => f64::NAN,
            })
            .sum()
    }

    fn bond_error_at(&self, now: f64) -> Option<f64> {
        Some(self.bond_error(now))
    }

    fn take_kinetic_error(&mut self) -> f64 {
        std::mem::take(&mut self.kinetic_error)
    }

    fn draw_rotations(&mut self, now: f64, temperature: f64, rng: &mut Xoshiro256PlusPlus) {
        for i in 0..self.motions.len() as u32 {
            if self.draw_internal(i, now, temperature, rng).is_err() {
                self.flex.failures += 1;
            }
        }
    }

    fn reverse_rotations(&mut self) {
        // Called at a re-basing: the present is time 0. Each molecule restarts there with its
        // internal velocities reversed.
        for i in 0..self.motions.len() as u32 {
            if self.respin(i, 0.0, -1.0) {
                continue;
            }
            let ty = self.table.type_of(i);
            let state = self.motions[i as usize].state_at(&self.constraints[ty], 0.0);
            let done = state.and_then(|(q, mut u)| {
                self.rescale(i as usize, &mut u);
                let keep = self.rattle.rescale;
                self.restart(i, 0.0, q, u.into_iter().map(|x| -x).collect(), keep)
            });
            if done.is_err() {
                self.flex.failures += 1;
            }
        }
    }

    fn scale_rotations(&mut self, now: f64, factor: f64) {
        // Each molecule restarts at `now` from its interpolated state with its internal
        // velocities scaled (brought first to the kinetic energy of its start when `rescale`
        // is on, as at events, so that the scaled energy is factor² times the tracked one).
        for i in 0..self.motions.len() as u32 {
            if self.respin(i, now, factor) {
                continue;
            }
            let ty = self.table.type_of(i);
            let state = self.motions[i as usize].state_at(&self.constraints[ty], now);
            let done = state.and_then(|(q, mut u)| {
                self.rescale(i as usize, &mut u);
                let keep = self.rattle.rescale;
                self.restart(i, now, q, u.into_iter().map(|x| factor * x).collect(), keep)
            });
            if done.is_err() {
                self.flex.failures += 1;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::models::site_pairs::atom;

    /// A bent trimer of masses `m1, m2, m3` and bonds `b1, b2` at bend angle `theta`.
    fn trimer(theta: f64, m: [f64; 3], b: [f64; 2]) -> [SiteAtom; 3] {
        [
            atom(b[0], 0.0, 0.0, m[0]),
            atom(0.0, 0.0, 0.0, m[1]),
            atom(b[1] * theta.cos(), b[1] * theta.sin(), 0.0, m[2]),
        ]
    }

    #[test]
    fn the_metric_of_a_trimer_is_fixmans() {
        // Unit gradients: Z = [[1/m1 + 1/m2, −cos θ/m2], [−cos θ/m2, 1/m2 + 1/m3]], whatever
        // the bond lengths, the orientation and the position.
        let bonds = [Bond::new(0, 1), Bond::new(1, 2)];
        let m = [10.0, 1.0, 3.0];
        let turn = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, -0.5).normalize(), 0.7);
        for theta in [0.05, 0.6, 1.5, 2.2, 3.1] {
            let q: Vec<DVec3> = trimer(theta, m, [0.8, 1.7])
                .iter()
                .map(|a| turn * a.position + DVec3::new(3.0, -1.0, 2.0))
                .collect();
            let det = (1.0 / m[0] + 1.0 / m[1]) * (1.0 / m[1] + 1.0 / m[2])
                - (theta.cos() / m[1]).powi(2);
            let got = half_log_det_z(&m, &bonds, &q);
            assert!(
                (got - 0.5 * det.ln()).abs() < 1e-12,
                "θ = {theta}: {got} vs {det}"
            );
        }
        // Collinear and all bonded: dependent, the measure vanishes (to round-off).
        let line = trimer(std::f64::consts::PI, [1.0; 3], [1.0, 1.0]).map(|a| a.position);
        let all = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)];
        assert!(half_log_det_z(&[1.0; 3], &all, &line) < -10.0);
    }

    #[test]
    fn bad_molecules_are_refused_with_reasons() {
        let two = [atom(0.0, 0.0, 0.0, 1.0), atom(1.0, 0.0, 0.0, 1.0)];
        assert!(matches!(
            FlexibleType::new(&two[..1], &[]),
            Err(FlexibleError::Molecule(MoleculeError::TooFewAtoms(1)))
        ));
        assert!(matches!(
            FlexibleType::new(&two, &[Bond::new(0, 2)]),
            Err(FlexibleError::Bond { bond: 0, .. })
        ));
        assert!(matches!(
            FlexibleType::new(&two, &[Bond::new(0, 1), Bond::new(1, 0)]),
            Err(FlexibleError::Bond { bond: 1, .. })
        ));
        assert!(matches!(
            FlexibleType::new(&two, &[]),
            Err(FlexibleError::Disconnected(1))
        ));
        let mut heavy = two;
        heavy[1].mass = -1.0;
        assert!(matches!(
            FlexibleType::new(&heavy, &[Bond::new(0, 1)]),
            Err(FlexibleError::Molecule(MoleculeError::Mass { atom: 1, .. }))
        ));
        // Three collinear atoms with all three distances bonded: dependent.
        let line = [
            atom(0.0, 0.0, 0.0, 1.0),
            atom(1.0, 0.0, 0.0, 1.0),
            atom(2.0, 0.0, 0.0, 1.0),
        ];
        let all = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(0, 2)];
        assert!(matches!(
            FlexibleType::new(&line, &all),
            Err(FlexibleError::DependentBonds(2))
        ));
        // A triangle with all three bonds is fine: 3 internal degrees of freedom (rotation).
        let tri = [
            atom(0.0, 0.0, 0.0, 1.0),
            atom(1.0, 0.0, 0.0, 2.0),
            atom(0.3, 0.8, 0.0, 1.0),
        ];
        let t = FlexibleType::new(&tri, &all).unwrap();
        assert_eq!(t.internal_dof(), 3.0);
        // The bounds hold the atoms: every radius at least the atom's distance.
        for (r, q) in t.radii().iter().zip(t.reference()) {
            assert!(*r >= q.length());
        }
    }

    #[test]
    fn the_bound_holds_a_flexing_chain() {
        // A 4-chain: the bound of the end atom holds for the stretched and a folded shape.
        let bonds = [Bond::new(0, 1), Bond::new(1, 2), Bond::new(2, 3)];
        let straight: Vec<SiteAtom> = (0..4).map(|k| atom(k as f64, 0.0, 0.0, 1.0)).collect();
        let folded = [
            atom(0.0, 1.0, 0.0, 1.0),
            atom(0.0, 0.0, 0.0, 1.0),
            atom(1.0, 0.0, 0.0, 1.0),
            atom(1.0, 1.0, 0.0, 1.0),
        ];
        let a = FlexibleType::new(&straight, &bonds).unwrap();
        let b = FlexibleType::new(&folded, &bonds).unwrap();
        // Same bond graph and lengths: the same bounds.
        for (ra, rb) in a.radii().iter().zip(b.radii()) {
            assert!((ra - rb).abs() < 1e-12);
        }
        // The straight chain's end atom is at 1.5 from the centre; the bound is (0+1+2+3)/4.
        assert!((a.radii()[0] - 1.5).abs() < 1e-9);
        for (r, q) in b.radii().iter().zip(b.reference()) {
            assert!(*r >= q.length());
        }
    }

    #[test]
    fn bad_settings_and_starts_are_refused() {
        let tri = [
            atom(0.0, 0.0, 0.0, 1.0),
            atom(1.0, 0.0, 0.0, 2.0),
            atom(0.3, 0.8, 0.0, 1.0),
        ];
        let t = FlexibleType::new(&tri, &[Bond::new(0, 1), Bond::new(1, 2)]).unwrap();
        let pot = Potentials::from_tables(1, &[((0, 0), vec![[1.0, f64::INFINITY]])]);
        let q = vec![t.reference().to_vec()];
        let u = vec![vec![DVec3::X, DVec3::Y, DVec3::Z]];
        let rattle = RattleSettings {
            step: 0.01,
            tolerance: 1e-12,
            rescale: false,
        };
        let s = SearchSettings::paper(0.01);
        let mk = |r: RattleSettings, q: &[Vec<DVec3>]| {
            Flexible::new(vec![t.clone()], pot.clone(), &[0], q, &u, 0.0, r, s, 1)
        };
        assert!(mk(rattle, &q).is_ok());
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let r = RattleSettings {
                step: bad,
                ..rattle
            };
            assert!(matches!(mk(r, &q), Err(FlexibleError::Rattle { .. })));
        }
        let r = RattleSettings {
            tolerance: 0.1,
            ..rattle
        };
        assert!(matches!(mk(r, &q), Err(FlexibleError::Rattle { .. })));
        // A start that misses its bond lengths.
        let mut off = q.clone();
        off[0][2] += DVec3::new(0.1, 0.0, 0.0);
        assert!(matches!(mk(rattle, &off), Err(FlexibleError::Body { .. })));
        // The velocities are projected: bond rates vanish, centre velocity is off.
        let m = mk(rattle, &q).unwrap();
        let (q0, u0) = m.motions[0].initial();
        assert!(m.constraints[0].rate_violation(q0, u0) < 1e-11);
        assert!(t.centre_of(u0).length() < 1e-15);
    }
}
