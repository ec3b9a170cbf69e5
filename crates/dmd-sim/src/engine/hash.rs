//! A keyed hash for randomness that must be a function of its inputs alone (the same on resume
//! and on every machine): the root searches' step jitter per pair and time, and the pairs HMC's
//! fault injection hides per segment.

/// SplitMix64's finaliser: a well-mixed 64-bit hash.
#[inline]
pub(crate) fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}
