//! Forces, torques, energy and virial over a neighbour list, with the potential's own
//! `evaluate` (003 Eqs. 4–6; the same code the event-driven engine calls).
//!
//! Each pair is evaluated once (a half list) and its force added to `i` and subtracted from
//! `j`: Newton's third law holds exactly, so the total force vanishes up to the round-off of
//! the sums. The loop is generic over the potential (static dispatch, inlined) and over
//! whether torques are wanted at all: spheres, or bodies whose potential does not depend on
//! orientation, take the loop without axes and torque accumulation.

use glam::DVec3;
use potential::{PairGeometry, PairPotential, PotentialError, Smoothed};

use crate::neighbour::{NeighbourList, unpack};

/// Sums over the pairs of one force evaluation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct PairSums {
    /// `Σ U_ij`.
    pub(crate) energy: f64,
    /// `Σ r_ij · F_ij` (the molecular virial; 3PV = 3NkT + W).
    pub(crate) virial: f64,
    /// Pairs closer than the cut-off (evaluated).
    pub(crate) pairs: u64,
}

/// The pair whose evaluation failed.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct PairFailure {
    pub(crate) i: usize,
    pub(crate) j: usize,
    pub(crate) error: PotentialError,
}

/// Fills `force` (and `torque` when `TORQUES`) and returns the sums. `axis` is read only when
/// `TORQUES`; `cutoff2` is `r_u²` of the smoothing.
pub(crate) fn evaluate<P: PairPotential, const TORQUES: bool>(
    pot: &Smoothed<P>,
    cutoff2: f64,
    list: &NeighbourList,
    pos: &[DVec3],
    axis: &[DVec3],
    force: &mut [DVec3],
    torque: &mut [DVec3],
) -> Result<PairSums, PairFailure> {
    force.fill(DVec3::ZERO);
    if TORQUES {
        torque.fill(DVec3::ZERO);
    }
    let mut sums = PairSums::default();
    let shifts = &list.shifts;
    let inner2 = pot.window().0 * pot.window().0;
    for i in 0..pos.len() {
        let (a, b) = (list.start[i] as usize, list.start[i + 1] as usize);
        let p = pos[i];
        let s_i = if TORQUES { axis[i] } else { DVec3::Z };
        let mut f_i = DVec3::ZERO;
        let mut t_i = DVec3::ZERO;
        for &e in &list.entries[a..b] {
            let (j, c) = unpack(e);
            let r_ij = p - pos[j] + shifts[c];
            let r2 = r_ij.length_squared();
            // Pairs in the skin but beyond r_u contribute exactly zero (003 Eq. 26).
            if r2 >= cutoff2 {
                continue;
            }
            let g = if TORQUES {
                PairGeometry::new(r_ij, s_i, axis[j])
            } else {
                PairGeometry::spheres(r_ij)
            };
            // Inside r_l the smoothed potential is the inner one unchanged (003 Eq. 26 with
            // g = 1): call it directly and skip the switch's square root and branches.
            let ev = if r2 <= inner2 {
                pot.inner().evaluate(&g)
            } else {
                pot.evaluate(&g)
            };
            let ev = match ev {
                Ok(ev) => ev,
                Err(error) => return Err(PairFailure { i, j, error }),
            };
            f_i += ev.force;
            force[j] -= ev.force;
            if TORQUES {
                t_i += ev.torque_i;
                torque[j] += ev.torque_j;
            }
            sums.energy += ev.energy;
            sums.virial += r_ij.dot(ev.force);
            sums.pairs += 1;
        }
        force[i] += f_i;
        if TORQUES {
            torque[i] += t_i;
        }
    }
    Ok(sums)
}
