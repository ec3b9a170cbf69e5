//! Pair potentials of rigid bodies of any shape: the geometry is the separation and each body's
//! whole attitude, not one axis per body.
//!
//! [`PairPotential`] describes uniaxial bodies by one unit vector each (003 §II). A water
//! molecule, or any body without an axis of continuous symmetry, needs its full attitude: a unit
//! quaternion `q` taking body coordinates to lab coordinates, so that the body's axes in the lab
//! are `e_x = q·x̂`, `e_y = q·ŷ`, `e_z = q·ẑ`. A [`RigidGeometry`] holds `r_ij = r_i − r_j` and
//! both quaternions; a [`RigidPairPotential`] returns the same [`PairEval`] as the uniaxial
//! trait: energy, force on `i`, torque on `i` and on `j`, all in the lab frame.
//!
//! **Force and torques (003 Eqs. 4–5 generalised).** `U` is a function of `r_ij` and the six
//! lab vectors `e_a^k` (`a ∈ {i, j}`, `k ∈ {x, y, z}`). The force on `i` is `F_ij = −∂U/∂r_ij`
//! at fixed attitudes, and `j` receives `−F_ij`. Turning body `a` by a small angle `δφ` about a
//! lab axis `n` moves every axis by `δe = δφ n × e`, so `δU = δφ n·Σ_k e_a^k × ∂U/∂e_a^k` and
//! the torque `τ_a = −∂U/∂φ` is
//!
//! ```text
//! τ_a = −Σ_k e_a^k × ∂U/∂e_a^k.
//! ```
//!
//! For a uniaxial potential only `e_z` enters and this is 003 Eq. 5. A rotationally invariant
//! `U` is unchanged when `r_ij` and all axes turn together, so `r_ij × F_ij + τ_ij + τ_ji = 0`
//! (003 Eq. 6) holds for every potential of this kind; the tests check it to round-off.
//!
//! **Rate along free motion.** With `v_ij = v_i − v_j` and lab angular velocities `ω_i`, `ω_j`,
//! `ė_a^k = ω_a × e_a^k` and [`PairEval::rate`] gives `U̇ = −F_ij·v_ij − τ_ij·ω_i − τ_ji·ω_j`
//! (003 Eq. 12) unchanged: the rate needs nothing but the three vectors.
//!
//! **Uniaxial potentials are rigid ones.** [`Uniaxial`] wraps any [`PairPotential`] and reads
//! each body's axis as `s = q·ẑ`; its results are those of the wrapped potential bit for bit,
//! and the fast uniaxial path stays available to code that has only axes.

use glam::{DQuat, DVec3};

use crate::certify::{RigidFlight, TaylorModel};
use crate::{PairEval, PairGeometry, PairPotential, PotentialError};

/// Where two rigid bodies are relative to each other: the separation `r_ij = r_i − r_j` (lab
/// frame; any minimum-image convention is the caller's) and each body's attitude, a unit
/// quaternion taking body coordinates to lab coordinates.
///
/// The quaternions must be normalised (to round-off, as a propagator returns them); the
/// potentials read them as given.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidGeometry {
    /// `r_ij = r_i − r_j`.
    pub r_ij: DVec3,
    /// Attitude of body `i` (body → lab).
    pub q_i: DQuat,
    /// Attitude of body `j` (body → lab).
    pub q_j: DQuat,
}

impl RigidGeometry {
    /// A pair with separation `r_ij` and attitudes `q_i`, `q_j`.
    #[inline]
    pub const fn new(r_ij: DVec3, q_i: DQuat, q_j: DQuat) -> Self {
        Self { r_ij, q_i, q_j }
    }

    /// The same pair seen from body `j`: `r_ji = −r_ij` and the attitudes exchanged.
    #[inline]
    pub fn swapped(&self) -> Self {
        Self {
            r_ij: -self.r_ij,
            q_i: self.q_j,
            q_j: self.q_i,
        }
    }

    /// The pair turned as a whole by the rotation `rot` (lab frame): `r_ij → rot·r_ij`,
    /// `q → rot·q`. A rotationally invariant potential has the same energy for both, and its
    /// force and torques turn with `rot`.
    #[inline]
    pub fn rotated(&self, rot: DQuat) -> Self {
        Self {
            r_ij: rot * self.r_ij,
            q_i: rot * self.q_i,
            q_j: rot * self.q_j,
        }
    }

    /// The uniaxial view of this pair: each body's axis is its body `ẑ` in the lab, `q·ẑ`.
    #[inline]
    pub fn axes(&self) -> PairGeometry {
        PairGeometry::new(self.r_ij, self.q_i * DVec3::Z, self.q_j * DVec3::Z)
    }

    /// Whether the separation and both quaternions are finite.
    #[inline]
    pub fn is_finite(&self) -> bool {
        self.r_ij.is_finite() && self.q_i.is_finite() && self.q_j.is_finite()
    }
}

/// A smooth, rotationally and translationally invariant pair potential of rigid bodies of any
/// shape (the module documentation gives the force and torque formulas).
///
/// The conventions are those of [`PairPotential`]: `energy` is `+∞` (never NaN for finite
/// input) where the bodies overlap so much that the potential is infinite or overflows;
/// `evaluate` then returns [`PotentialError::Overlap`], and [`PotentialError::NotFinite`] for a
/// non-finite geometry; the potential decays to zero at large distance. Implementations should
/// be `#[inline]` and must not allocate.
pub trait RigidPairPotential {
    /// `U_ij` for this geometry; `+∞` for overlapping bodies. By default the energy of
    /// [`evaluate`](Self::evaluate), bit for bit (`+∞` where it reports an overlap, NaN for a
    /// non-finite geometry); a potential with a cheaper energy alone overrides it.
    #[inline]
    fn energy(&self, g: &RigidGeometry) -> f64 {
        match self.evaluate(g) {
            Ok(e) => e.energy,
            Err(PotentialError::Overlap { .. }) => f64::INFINITY,
            Err(_) => f64::NAN,
        }
    }

    /// Energy, force on `i` and torques on `i` and `j` (lab frame). [`PairEval::rate`] turns
    /// them into `U̇` along free motion.
    ///
    /// # Errors
    /// [`PotentialError::Overlap`] where the energy is infinite or it or a derivative
    /// overflows; [`PotentialError::NotFinite`] for a non-finite geometry.
    fn evaluate(&self, g: &RigidGeometry) -> Result<PairEval, PotentialError>;

    /// A lower bound on `U` over all distances and attitudes: exact where the implementation
    /// says so, otherwise the minimum of a rigorous bound (a level set checked against it may
    /// contain levels no pair reaches, never refuse one a pair can reach).
    fn minimum(&self) -> f64;

    /// A length of the order of the largest contact distance.
    fn length_scale(&self) -> f64;

    /// An upper bound on the reach of a level `u_k`: the largest centre distance at which `U`
    /// can be at or below `u_k` (for `u_k < 0`) or at or above it (for `u_k > 0`) for any
    /// attitudes (as [`PairPotential::reach`]). Beyond it the pair cannot cross the level.
    ///
    /// # Errors
    /// [`PotentialError::LevelAtZero`] for `u_k = 0`, [`PotentialError::NotFinite`] for a
    /// non-finite level, and what the implementation's search may return.
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError>;

    /// Certified event prediction for bodies of any shape ([`certify`](crate::certify)): a
    /// model of `U` itself over the window `[0, h]` of `flight`, `U(τ) ∈ U + U̇τ ± Kτ²/2` with
    /// `K` ([`TaylorModel::spread`]) bounding `|Ü|` on the whole window (`ddx` and `third`
    /// zero). `None` (the default): no certificate, engines rely on their root searches.
    ///
    /// The contract, property-tested for the potentials that implement it: for every
    /// `τ ∈ [0, h]` of the exact free motion that `flight` bounds,
    /// `|U(τ) − U − U̇τ| ≤ Kτ²/2`.
    fn taylor_model(&self, flight: &RigidFlight, h: f64) -> Option<TaylorModel> {
        let _ = (flight, h);
        None
    }

    /// Whether [`taylor_model`](Self::taylor_model) offers models at all: engines skip setting
    /// up a [`RigidFlight`] (the two attitudes and spins at the window's start) where it does
    /// not. `false` by default.
    fn certifies(&self) -> bool {
        false
    }

    /// Whether engines use the models by default (a search horizon above zero) or only when a
    /// scene asks for them: [`certifies`](Self::certifies) unless the implementation measured
    /// its models to cost more than the root search they replace.
    fn certifies_by_default(&self) -> bool {
        self.certifies()
    }
}

/// [`RigidPairPotential::reach`] from monotone envelopes of `U` (the site-based potentials):
/// a level below the rigorous `minimum` is reached nowhere (0); an attractive level `u_k < 0`
/// reaches as far as `outermost_attract(−u_k)`, the outermost distance where the attractive
/// envelope is still at least `−u_k`; a repulsive level as far as `outermost_repel(u_k)`.
///
/// # Errors
/// [`PotentialError::LevelAtZero`] for `u_k = 0`, [`PotentialError::NotFinite`] for a
/// non-finite level.
pub(crate) fn reach_from_envelopes(
    u_k: f64,
    minimum: f64,
    outermost_attract: impl FnOnce(f64) -> f64,
    outermost_repel: impl FnOnce(f64) -> f64,
) -> Result<f64, PotentialError> {
    if !u_k.is_finite() {
        return Err(PotentialError::NotFinite("level"));
    }
    if u_k == 0.0 {
        return Err(PotentialError::LevelAtZero(u_k));
    }
    Ok(if u_k < 0.0 {
        if u_k < minimum {
            0.0
        } else {
            outermost_attract(-u_k)
        }
    } else {
        outermost_repel(u_k)
    })
}

impl<P: RigidPairPotential + ?Sized> RigidPairPotential for &P {
    #[inline]
    fn energy(&self, g: &RigidGeometry) -> f64 {
        (**self).energy(g)
    }
    #[inline]
    fn evaluate(&self, g: &RigidGeometry) -> Result<PairEval, PotentialError> {
        (**self).evaluate(g)
    }
    fn minimum(&self) -> f64 {
        (**self).minimum()
    }
    fn length_scale(&self) -> f64 {
        (**self).length_scale()
    }
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        (**self).reach(u_k)
    }
    #[inline]
    fn taylor_model(&self, flight: &RigidFlight, h: f64) -> Option<TaylorModel> {
        (**self).taylor_model(flight, h)
    }
    #[inline]
    fn certifies(&self) -> bool {
        (**self).certifies()
    }
    fn certifies_by_default(&self) -> bool {
        (**self).certifies_by_default()
    }
}

/// Any uniaxial [`PairPotential`] as a [`RigidPairPotential`]: each body's axis is `q·ẑ`.
///
/// Energy, force and torques are those of the wrapped potential for the axes
/// [`RigidGeometry::axes`], bit for bit; `minimum`, `length_scale` and `reach` are forwarded
/// (so the reach is the wrapped potential's, exact or numerical). The torques have no component
/// along the axes, as for the uniaxial potential.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Uniaxial<P>(pub P);

impl<P: PairPotential> RigidPairPotential for Uniaxial<P> {
    #[inline]
    fn energy(&self, g: &RigidGeometry) -> f64 {
        self.0.energy(&g.axes())
    }
    #[inline]
    fn evaluate(&self, g: &RigidGeometry) -> Result<PairEval, PotentialError> {
        if !g.is_finite() {
            return Err(PotentialError::NotFinite(
                "rigid pair geometry (r_ij, q_i or q_j)",
            ));
        }
        self.0.evaluate(&g.axes())
    }
    fn minimum(&self) -> f64 {
        self.0.minimum()
    }
    fn length_scale(&self) -> f64 {
        self.0.length_scale()
    }
    fn reach(&self, u_k: f64) -> Result<f64, PotentialError> {
        self.0.reach(u_k)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{GayBerne, LjRod};

    #[test]
    fn the_adapter_agrees_with_the_uniaxial_potential_bit_for_bit() {
        let q_i = DQuat::from_euler(glam::EulerRot::ZYX, 0.3, -1.1, 2.0);
        let q_j = DQuat::from_euler(glam::EulerRot::ZYX, -2.4, 0.7, 0.2);
        let g = RigidGeometry::new(DVec3::new(3.1, -1.4, 2.2), q_i, q_j);
        let rod = LjRod::paper();
        let gb = GayBerne::default();
        let a = g.axes();
        assert_eq!(Uniaxial(rod).evaluate(&g), rod.evaluate(&a));
        assert_eq!(Uniaxial(rod).energy(&g), rod.energy(&a));
        assert_eq!(Uniaxial(gb).evaluate(&g), gb.evaluate(&a));
        assert_eq!(Uniaxial(rod).minimum(), rod.minimum());
        assert_eq!(Uniaxial(rod).reach(-0.5), rod.reach(-0.5));
        // The axes are the quaternions' body ẑ.
        assert!((a.s_i - q_i * DVec3::Z).length() < 1e-16);
        assert!((a.s_i.length() - 1.0).abs() < 1e-15);
    }

    #[test]
    fn non_finite_geometry_is_refused() {
        let g = RigidGeometry::new(
            DVec3::new(f64::NAN, 0.0, 0.0),
            DQuat::IDENTITY,
            DQuat::IDENTITY,
        );
        assert!(matches!(
            Uniaxial(LjRod::paper()).evaluate(&g),
            Err(PotentialError::NotFinite(_))
        ));
    }

    #[test]
    fn swapped_and_rotated_pairs() {
        let g = RigidGeometry::new(DVec3::X, DQuat::from_rotation_y(0.4), DQuat::IDENTITY);
        let s = g.swapped();
        assert_eq!(s.r_ij, -DVec3::X);
        assert_eq!((s.q_i, s.q_j), (g.q_j, g.q_i));
        let rot = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let t = g.rotated(rot);
        assert!((t.r_ij - DVec3::Y).length() < 1e-15);
        assert!((t.axes().s_i - rot * g.axes().s_i).length() < 1e-15);
    }
}
