//! The free motion of one body state: the propagator chosen once from the moments and the state,
//! and the pose it gives at any time.

use crate::asymmetric::{AsymmetricTop, Invariants};
use crate::attitude::{check_rotation, check_vector};
use crate::axes::AxisOrder;
use crate::separatrix::SeparatrixTop;
use crate::symmetric::SymmetricTop;
use crate::uniform::UniformRotation;
use crate::{BodyKind, FreeError, Moments};
use glam::{DMat3, DQuat, DVec3};

/// Which exact solution a state follows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MotionKind {
    /// Zero angular velocity (`L = 0`).
    Rest,
    /// Spherical rotor: uniform rotation.
    Spherical,
    /// Asymmetric top spinning exactly about a principal axis: uniform rotation.
    SteadySpin,
    /// Linear rotor (rod): uniform rotation perpendicular to the axis, spin left out.
    LinearRotor,
    /// Symmetric top: trigonometric.
    Symmetric,
    /// Asymmetric top: Jacobi elliptic functions and a theta series.
    Asymmetric,
    /// Asymmetric top exactly on the separatrix (`m_c = 0`): hyperbolic functions.
    Separatrix,
}

/// The propagator of one state, one variant per exact solution (static dispatch).
///
/// The asymmetric variant is larger than the others (its AGM table); it is kept inline on
/// purpose: a simulator stores one value per body, and a box would add an allocation per event
/// and a pointer chase per evaluation.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Case {
    /// No rotation.
    Rest,
    /// Constant angular velocity (sphere, steady spin, linear rotor).
    Uniform(UniformRotation),
    /// Symmetric top.
    Symmetric(SymmetricTop),
    /// Asymmetric top.
    Asymmetric(AsymmetricTop),
    /// Asymmetric top on the separatrix.
    Separatrix(SeparatrixTop),
}

/// Attitude and angular velocity of a body at one time, with the lab-frame quantities a
/// collision search asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose {
    /// `R = Aᵀ`: rotates body-fixed vectors into the lab (columns are the body axes in the lab).
    pub orientation: DMat3,
    /// Angular velocity in the body (principal-axis) frame.
    pub omega: DVec3,
}

impl Pose {
    /// The attitude `A` (body = A · lab).
    #[inline]
    pub fn attitude(&self) -> DMat3 {
        self.orientation.transpose()
    }

    /// The orientation as a unit quaternion (scalar part ≥ 0).
    pub fn quat(&self) -> DQuat {
        crate::quat_from_attitude(self.attitude())
    }

    /// Angular velocity in the lab frame.
    #[inline]
    pub fn omega_lab(&self) -> DVec3 {
        self.orientation * self.omega
    }

    /// Lab components of a body-fixed vector (a point relative to the centre of mass, or an axis).
    #[inline]
    pub fn lab_vector(&self, body: DVec3) -> DVec3 {
        self.orientation * body
    }

    /// Rate of change of the lab components of a body-fixed vector: `ω_lab × (R body)`.
    #[inline]
    pub fn lab_velocity(&self, body: DVec3) -> DVec3 {
        self.omega_lab().cross(self.lab_vector(body))
    }
}

/// The exact torque-free motion of one rigid-body state.
///
/// Built once per state (after every event that changes the body), it evaluates the pose at any
/// time measured from that state, as often as a root search needs. Negative times run the motion
/// backwards.
///
/// ```
/// use glam::{DMat3, DVec3};
/// use rigid_free::{FreeMotion, Moments, MotionKind};
/// let moments = Moments::new([1.0, 2.0, 3.0])?;
/// let motion = FreeMotion::new(&moments, DMat3::IDENTITY, DVec3::new(1.0, 0.5, 2.0))?;
/// assert_eq!(motion.kind(), MotionKind::Asymmetric);
/// let pose = motion.pose(10.0);
/// // The lab angular momentum is conserved.
/// let l_lab = |p: &rigid_free::Pose| p.orientation * (DVec3::new(1.0, 2.0, 3.0) * p.omega);
/// assert!((l_lab(&pose) - l_lab(&motion.pose(0.0))).length() < 1e-13);
/// # Ok::<(), rigid_free::FreeError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FreeMotion {
    moments: Moments,
    orientation0: DMat3,
    omega0: DVec3,
    kind: MotionKind,
    case: Case,
}

impl FreeMotion {
    /// Chooses and sets up the propagator for `moments`, the attitude `A(0)` (body = A·lab) and
    /// the body-frame angular velocity `ω(0)`.
    ///
    /// For a linear rotor the component of `ω` along the rod is its decoupled spin and is
    /// dropped.
    ///
    /// # Errors
    /// [`FreeError::NonFiniteVector`] for a NaN or infinite `ω`, [`FreeError::NotARotation`] for
    /// an attitude that is not a proper rotation to 1e-9.
    pub fn new(moments: &Moments, attitude: DMat3, omega: DVec3) -> Result<Self, FreeError> {
        let r0 = check_rotation(attitude)?.transpose();
        let mut omega = check_vector(omega, "angular velocity")?;
        let i = moments.get();
        if let BodyKind::Linear { axis } = moments.kind() {
            omega[axis] = 0.0;
        }
        let (kind, case) = if omega == DVec3::ZERO {
            (MotionKind::Rest, Case::Rest)
        } else {
            match moments.kind() {
                BodyKind::Spherical => (
                    MotionKind::Spherical,
                    Case::Uniform(UniformRotation::new(r0, omega)),
                ),
                BodyKind::Linear { .. } => (
                    MotionKind::LinearRotor,
                    Case::Uniform(UniformRotation::new(r0, omega)),
                ),
                BodyKind::Symmetric { axis } => (
                    MotionKind::Symmetric,
                    Case::Symmetric(SymmetricTop::new(axis, i, r0, omega)),
                ),
                BodyKind::Asymmetric => Self::asymmetric(i, r0, omega),
            }
        };
        Ok(Self {
            moments: *moments,
            orientation0: r0,
            omega0: omega,
            kind,
            case,
        })
    }

    /// [`FreeMotion::new`] with the orientation given as a quaternion (body → lab).
    ///
    /// # Errors
    /// As [`FreeMotion::new`]; a zero or non-finite quaternion is [`FreeError::NotARotation`] or
    /// [`FreeError::NonFiniteVector`].
    pub fn from_quat(moments: &Moments, q: DQuat, omega: DVec3) -> Result<Self, FreeError> {
        if !q.is_finite() {
            return Err(FreeError::NonFiniteVector {
                what: "orientation quaternion",
            });
        }
        if q.length_squared() == 0.0 {
            return Err(FreeError::NotARotation { deviation: 1.0 });
        }
        Self::new(moments, crate::attitude_from_quat(q), omega)
    }

    /// Orders the axes (intermediate moment on axis 2, the axis `L` circles on axis 3, from the
    /// sign of `Δ2 = L² − 2E I_mid`) and dispatches the degenerate states.
    fn asymmetric(i: [f64; 3], r0: DMat3, omega: DVec3) -> (MotionKind, Case) {
        let nonzero = (0..3).filter(|&k| omega[k] != 0.0).count();
        if nonzero == 1 {
            return (
                MotionKind::SteadySpin,
                Case::Uniform(UniformRotation::new(r0, omega)),
            );
        }
        let iv = DVec3::from(i);
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| i[a].total_cmp(&i[b]));
        let [lo, mid, hi] = idx;
        let d2 = Invariants::delta_mid(iv, omega, lo, mid, hi);
        let order = AxisOrder::new(if d2 >= 0.0 {
            [lo, mid, hi]
        } else {
            [hi, mid, lo]
        });
        let io = order.ordered(iv).abs();
        let wo = order.ordered(omega);
        // Δ2 is invariant under the signed permutation (its two terms are swapped, if anything).
        let inv = Invariants::new(io, wo, d2);
        if inv.delta[2] == 0.0 || inv.delta[0] == 0.0 {
            // ω1 = ω2 = 0 (or ω2 = ω3 = 0) up to underflow of the squares: steady spin.
            return (
                MotionKind::SteadySpin,
                Case::Uniform(UniformRotation::new(r0, omega)),
            );
        }
        if inv.delta[1] == 0.0 {
            return (
                MotionKind::Separatrix,
                Case::Separatrix(SeparatrixTop::new(order, io, wo, &inv, r0)),
            );
        }
        (
            MotionKind::Asymmetric,
            Case::Asymmetric(AsymmetricTop::new(order, io, wo, &inv, r0)),
        )
    }

    /// Which exact solution this state follows.
    #[inline]
    pub fn kind(&self) -> MotionKind {
        self.kind
    }

    /// The propagator itself, for callers that want to match on it.
    #[inline]
    pub fn case(&self) -> &Case {
        &self.case
    }

    /// The moments of inertia.
    #[inline]
    pub fn moments(&self) -> &Moments {
        &self.moments
    }

    /// The pose at time `t` after the state this motion was built from. At `t = 0` it is that
    /// state, bit for bit.
    #[inline]
    pub fn pose(&self, t: f64) -> Pose {
        if t == 0.0 {
            return self.initial_pose();
        }
        let (orientation, omega) = match &self.case {
            Case::Rest => (self.orientation0, DVec3::ZERO),
            Case::Uniform(u) => (u.orientation(t), u.omega()),
            Case::Symmetric(s) => s.orientation_omega(t),
            Case::Asymmetric(a) => a.orientation_omega(t),
            Case::Separatrix(s) => s.orientation_omega(t),
        };
        Pose { orientation, omega }
    }

    /// The body-frame angular velocity at time `t` (cheaper than [`FreeMotion::pose`]).
    #[inline]
    pub fn omega(&self, t: f64) -> DVec3 {
        if t == 0.0 {
            return self.omega0;
        }
        match &self.case {
            Case::Rest => DVec3::ZERO,
            Case::Uniform(u) => u.omega(),
            Case::Symmetric(s) => s.omega(t),
            Case::Asymmetric(a) => a.omega(t),
            Case::Separatrix(s) => s.omega(t),
        }
    }

    /// `dω/dt` in the body frame from Euler's equations `I ω̇ = (I ω) × ω`, for the body-frame
    /// `omega` of a pose of this motion. The lab angular velocity changes at `R ω̇` (the term
    /// `ω × ω` vanishes).
    #[inline]
    pub fn omega_dot(&self, omega: DVec3) -> DVec3 {
        match self.kind {
            MotionKind::Rest
            | MotionKind::Spherical
            | MotionKind::SteadySpin
            | MotionKind::LinearRotor => DVec3::ZERO,
            _ => {
                let i = DVec3::from(self.moments.get());
                (i * omega).cross(omega) / i
            }
        }
    }

    /// The propagator `P(t) = A(t) A(0)ᵀ`.
    pub fn propagator(&self, t: f64) -> DMat3 {
        self.pose(t).attitude() * self.orientation0
    }

    /// The state this motion was built from (for a linear rotor without the dropped spin).
    pub fn initial_pose(&self) -> Pose {
        Pose {
            orientation: self.orientation0,
            omega: self.omega0,
        }
    }
}
