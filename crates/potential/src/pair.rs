//! The geometry of a pair, what a potential returns, and the [`PairPotential`] trait.
//!
//! A pair of uniaxial rigid bodies is described by the separation of their centres
//! `r_ij = r_i − r_j` and one unit orientation vector per body (`s_i`, `s_j`, the long axis).
//! A rotationally invariant potential is then a function of four scalars (003 §II),
//!
//! ```text
//! r = |r_ij|,   x_i = r_ij·s_i,   x_j = r_ij·s_j,   c = s_i·s_j,
//! ```
//!
//! and its force and torques follow from the four partial derivatives of `U` with respect to
//! them (003 Eqs. 4–5, with one vector per body):
//!
//! ```text
//! F_ij  = −∂U/∂r r̂_ij − ∂U/∂x_i s_i − ∂U/∂x_j s_j            (force on i; F_ji = −F_ij)
//! τ_ij  = −∂U/∂c s_i × s_j − ∂U/∂x_i s_i × r_ij               (torque on i)
//! τ_ji  = −∂U/∂c s_j × s_i − ∂U/∂x_j s_j × r_ij               (torque on j)
//! ```
//!
//! The last line is the second with `i ↔ j` and `r_ji = −r_ij` (so `x_j` keeps its sign:
//! `r_ji·s_j = −x_j` and `∂U/∂(r_ji·s_j) = −∂U/∂x_j`). [`assemble`] does this once for every
//! potential that returns its [`Partials`]. The three vectors satisfy 003 Eq. 6,
//! `r_ij × F_ij + τ_ij + τ_ji = 0`, identically: the `x` terms cancel pairwise and
//! `r_ij × r̂_ij = 0`, so angular momentum is conserved by any potential assembled this way.

use glam::DVec3;

use crate::PotentialError;
use crate::certify::{FreeFlight, TaylorModel};

/// Where two bodies are relative to each other: the separation `r_ij = r_i − r_j` (lab frame;
/// any minimum-image convention is the caller's) and the unit orientation vectors `s_i`, `s_j`
/// of the bodies. Isotropic potentials ignore `s_i` and `s_j`.
///
/// The orientation vectors must be unit vectors (to round-off, as a propagator returns them);
/// the potentials read them as given and do not renormalise.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairGeometry {
    /// `r_ij = r_i − r_j`.
    pub r_ij: DVec3,
    /// Unit orientation vector (long axis) of body `i`.
    pub s_i: DVec3,
    /// Unit orientation vector (long axis) of body `j`.
    pub s_j: DVec3,
}

impl PairGeometry {
    /// A pair with separation `r_ij` and orientations `s_i`, `s_j`.
    #[inline]
    pub const fn new(r_ij: DVec3, s_i: DVec3, s_j: DVec3) -> Self {
        Self { r_ij, s_i, s_j }
    }

    /// A pair of bodies whose orientation does not matter (spheres): both axes are set to
    /// `DVec3::Z`, so an anisotropic potential still sees valid unit vectors.
    #[inline]
    pub const fn spheres(r_ij: DVec3) -> Self {
        Self {
            r_ij,
            s_i: DVec3::Z,
            s_j: DVec3::Z,
        }
    }

    /// The same pair seen from body `j`: `r_ji = −r_ij` and the axes exchanged.
    #[inline]
    pub fn swapped(&self) -> Self {
        Self {
            r_ij: -self.r_ij,
            s_i: self.s_j,
            s_j: self.s_i,
        }
    }

    /// The four rotational invariants `r`, `x_i`, `x_j`, `c`.
    #[inline]
    pub fn invariants(&self) -> Invariants {
        Invariants {
            r: self.r_ij.length(),
            x_i: self.r_ij.dot(self.s_i),
            x_j: self.r_ij.dot(self.s_j),
            c: self.s_i.dot(self.s_j),
        }
    }
}

/// The scalars a rotationally invariant pair potential of uniaxial bodies depends on.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Invariants {
    /// `r = |r_ij|`.
    pub r: f64,
    /// `x_i = r_ij·s_i`.
    pub x_i: f64,
    /// `x_j = r_ij·s_j`.
    pub x_j: f64,
    /// `c = s_i·s_j`.
    pub c: f64,
}

/// The energy and its partial derivatives with respect to the [`Invariants`] (each taken with
/// the other three held fixed). [`assemble`] turns them into a force and two torques.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Partials {
    /// `U`.
    pub energy: f64,
    /// `∂U/∂r`.
    pub d_r: f64,
    /// `∂U/∂x_i`.
    pub d_xi: f64,
    /// `∂U/∂x_j`.
    pub d_xj: f64,
    /// `∂U/∂c`.
    pub d_c: f64,
}

/// Energy, force and both torques of a pair (003 Eqs. 4–5). The same field names as
/// `collide::PairForce`, whose impulse rule takes the three vectors.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PairEval {
    /// `U_ij`.
    pub energy: f64,
    /// `F_ij`: force on body `i` (body `j` receives `−F_ij`).
    pub force: DVec3,
    /// `τ_ij`: torque on body `i` about its centre.
    pub torque_i: DVec3,
    /// `τ_ji`: torque on body `j` about its centre.
    pub torque_j: DVec3,
}

impl PairEval {
    /// `dU/dt` along free motion (003 Eq. 12): `U̇ = −F_ij·v_ij − τ_ij·ω_i − τ_ji·ω_j`, with
    /// `v_ij = v_i − v_j` and lab-frame angular velocities. This is `ḟ` of the indicator
    /// `f = U − U_k` that the root search follows.
    #[inline]
    pub fn rate(&self, v_ij: DVec3, omega_i: DVec3, omega_j: DVec3) -> f64 {
        -(self.force.dot(v_ij) + self.torque_i.dot(omega_i) + self.torque_j.dot(omega_j))
    }

    /// How far the torques are from balancing the force's moment (003 Eq. 6):
    /// `|r_ij × F_ij + τ_ij + τ_ji|` relative to `|r_ij||F_ij| + |τ_ij| + |τ_ji|` (zero if all
    /// vanish). Round-off level for every potential of this crate.
    pub fn torque_imbalance(&self, r_ij: DVec3) -> f64 {
        let sum = r_ij.cross(self.force) + self.torque_i + self.torque_j;
        let scale =
            r_ij.length() * self.force.length() + self.torque_i.length() + self.torque_j.length();
        if scale == 0.0 {
            0.0
        } else {
            sum.length() / scale
        }
    }

    /// Whether the energy and every component are finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.energy.is_finite()
            && self.force.is_finite()
            && self.torque_i.is_finite()
            && self.torque_j.is_finite()
    }
}

/// Force and torques from the partial derivatives (003 Eqs. 4–5; see the module text).
///
/// `inv` must be `g.invariants()` (potentials compute it once and pass it on).
///
/// # Errors
/// [`PotentialError::Overlap`] if the energy, the force or a torque is not finite (the
/// potential overflowed, or the centres coincide).
#[inline]
pub fn assemble(
    g: &PairGeometry,
    inv: &Invariants,
    p: &Partials,
) -> Result<PairEval, PotentialError> {
    let r_hat = g.r_ij / inv.r;
    let force = -(p.d_r * r_hat + p.d_xi * g.s_i + p.d_xj * g.s_j);
    let sij = g.s_i.cross(g.s_j);
    let torque_i = -(p.d_xi * g.s_i.cross(g.r_ij)) - p.d_c * sij;
    let torque_j = -(p.d_xj * g.s_j.cross(g.r_ij)) + p.d_c * sij;
    let out = PairEval {
        energy: p.energy,
        force,
        torque_i,
        torque_j,
    };
    if out.is_finite() {
        Ok(out)
    } else {
        Err(overlap(
            g,
            inv.r,
            "the energy or its derivatives overflow binary64",
        ))
    }
}

/// The error for a geometry without finite force: [`PotentialError::NotFinite`] if the input
/// itself is not finite (NaN in, error out), [`PotentialError::Overlap`] otherwise. Only on
/// the error path, so the checks cost nothing in the common case.
#[cold]
pub(crate) fn overlap(g: &PairGeometry, r: f64, what: &'static str) -> PotentialError {
    if g.r_ij.is_finite() && g.s_i.is_finite() && g.s_j.is_finite() {
        PotentialError::Overlap { r, what }
    } else {
        PotentialError::NotFinite("pair geometry (r_ij, s_i or s_j)")
    }
}

/// A smooth, rotationally and translationally invariant pair potential of uniaxial bodies.
///
/// The extension point for users' own potentials. It is object safe (`&dyn PairPotential`
/// works, for set-up code and tests), but the engines are generic over it, so hot paths get
/// static dispatch; implementations should be `#[inline]` and must not allocate.
///
/// Conventions every implementation keeps:
/// - `energy` is `+∞` where the bodies overlap so much that the potential is infinite (centres
///   coinciding, an effective distance `≤ 0`), never NaN for finite input;
/// - `evaluate` returns the same energy with force and torques consistent with it (003 Eqs.
///   4–5; [`assemble`] does the vector algebra), or [`PotentialError::Overlap`] where the
///   energy is infinite or it or a derivative overflows binary64 (only deep inside the core);
/// - the potential decays to zero at large distance, so far-apart pairs carry no energy;
/// - a NaN or infinity in the geometry is the caller's bug: `energy` passes the NaN on and
///   `evaluate` returns [`PotentialError::NotFinite`].
pub trait PairPotential {
    /// `U_ij` for this geometry; `+∞` for overlapping bodies.
    fn energy(&self, g: &PairGeometry) -> f64;

    /// Energy, force on `i` and torques on `i` and `j`.
    ///
    /// # Errors
    /// [`PotentialError::Overlap`] where the energy is infinite or it or a derivative
    /// overflows; [`PotentialError::NotFinite`] for a non-finite geometry.
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError>;

    /// The global minimum of `U` over all distances and orientations (a negative number for a
    /// potential with a well).
    fn minimum(&self) -> f64;

    /// A length of the order of the largest contact distance. Numerical searches (the
    /// [`reach`](Self::reach)) scan distances from `1e-3` to `1e3` times it.
    fn length_scale(&self) -> f64;

    /// Whether `U` depends on the orientations at all. `false` lets numerical searches skip
    /// the orientations and engines skip the torques.
    fn depends_on_orientation(&self) -> bool {
        true
    }

    /// The reach of a level `u_k`: the largest centre distance at which `U` can be at or below
    /// `u_k` (for `u_k < 0`) or at or above it (for `u_k > 0`) for any orientations. Beyond it
    /// the pair cannot cross the level, so it sets the simulator's cell size and the analytic
    /// bracketing times of the root search (003 §V.A). Zero if no configuration reaches the
    /// level (a level below the minimum).
    ///
    /// The default searches numerically ([`reach::numerical`](crate::reach::numerical));
    /// potentials with a closed form override it.
    ///
    /// # Errors
    /// [`PotentialError::LevelAtZero`] for `u_k = 0`, [`PotentialError::NotFinite`] for a
    /// non-finite level, [`PotentialError::UnboundedReach`] if the level is still reached at
    /// the end of the numerical search range.
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        crate::reach::numerical(self, u_k)
    }

    /// Certified event prediction (the [`certify`](crate::certify) module): a Taylor model of
    /// an effective coordinate `x` of which `U` is a function alone, over the window `[0, h]` of
    /// `flight`, with `third` bounding `|x⃛|` on the whole window. `None` (the default): the
    /// potential offers no certificate and engines rely on their root searches alone.
    fn taylor_model(&self, flight: &FreeFlight, h: f64) -> Option<TaylorModel> {
        let _ = (flight, h);
        None
    }

    /// The open intervals of the effective coordinate `x` of
    /// [`taylor_model`](Self::taylor_model) on which `lo < U < hi` (`lo = −∞` for the lowest
    /// terrace), disjoint and in increasing order: the band of a terrace in `x`. Engines
    /// compute them once per terrace and find the one holding the pair with
    /// [`certify::interval_containing`](crate::certify::interval_containing). The default, for
    /// potentials without a model, is none.
    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        let _ = (lo, hi);
        Vec::new()
    }
}

impl<P: PairPotential + ?Sized> PairPotential for &P {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        (**self).energy(g)
    }
    #[inline]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        (**self).evaluate(g)
    }
    fn minimum(&self) -> f64 {
        (**self).minimum()
    }
    fn length_scale(&self) -> f64 {
        (**self).length_scale()
    }
    fn depends_on_orientation(&self) -> bool {
        (**self).depends_on_orientation()
    }
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        (**self).reach(u_k)
    }
    #[inline]
    fn taylor_model(&self, flight: &FreeFlight, h: f64) -> Option<TaylorModel> {
        (**self).taylor_model(flight, h)
    }
    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        (**self).coordinate_intervals(lo, hi)
    }
}

impl<P: PairPotential + ?Sized> PairPotential for Box<P> {
    #[inline]
    fn energy(&self, g: &PairGeometry) -> f64 {
        (**self).energy(g)
    }
    #[inline]
    fn evaluate(&self, g: &PairGeometry) -> Result<PairEval, PotentialError> {
        (**self).evaluate(g)
    }
    fn minimum(&self) -> f64 {
        (**self).minimum()
    }
    fn length_scale(&self) -> f64 {
        (**self).length_scale()
    }
    fn depends_on_orientation(&self) -> bool {
        (**self).depends_on_orientation()
    }
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        (**self).reach(u_k)
    }
    #[inline]
    fn taylor_model(&self, flight: &FreeFlight, h: f64) -> Option<TaylorModel> {
        (**self).taylor_model(flight, h)
    }
    fn coordinate_intervals(&self, lo: f64, hi: f64) -> Vec<(f64, f64)> {
        (**self).coordinate_intervals(lo, hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn assembled_torques_balance_the_moment_of_the_force() {
        let g = PairGeometry::new(
            DVec3::new(1.3, -0.4, 0.7),
            DVec3::new(0.6, 0.0, 0.8),
            DVec3::new(0.0, 1.0, 0.0),
        );
        let p = Partials {
            energy: -0.3,
            d_r: 1.7,
            d_xi: -0.9,
            d_xj: 0.4,
            d_c: 2.2,
        };
        let e = assemble(&g, &g.invariants(), &p).unwrap();
        assert!(e.torque_imbalance(g.r_ij) < 1e-15);
        // The torque about the axis of each body vanishes only for the c and x_i terms' own
        // body: τ_ij has no component along s_i.
        assert!(e.torque_i.dot(g.s_i).abs() < 1e-15);
        assert!(e.torque_j.dot(g.s_j).abs() < 1e-15);
    }

    #[test]
    fn swapped_pair_exchanges_the_roles() {
        let g = PairGeometry::new(DVec3::X, DVec3::Y, DVec3::Z);
        let s = g.swapped();
        assert_eq!(s.r_ij, -DVec3::X);
        assert_eq!((s.s_i, s.s_j), (DVec3::Z, DVec3::Y));
        let (a, b) = (g.invariants(), s.invariants());
        assert_eq!((a.r, a.c), (b.r, b.c));
        assert_eq!((a.x_i, a.x_j), (-b.x_j, -b.x_i));
    }

    #[test]
    fn overflow_is_an_overlap_error_not_nan() {
        let g = PairGeometry::spheres(DVec3::X);
        let p = Partials {
            energy: f64::INFINITY,
            d_r: f64::NEG_INFINITY,
            ..Partials::default()
        };
        assert!(matches!(
            assemble(&g, &g.invariants(), &p),
            Err(PotentialError::Overlap { .. })
        ));
    }
}
