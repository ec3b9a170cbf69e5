//! Means with standard errors of correlated series by blocking (Flyvbjerg and Petersen).

use serde::{Deserialize, Serialize};

/// Mean with a standard error from block averages.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BlockEstimate {
    /// Mean.
    pub mean: f64,
    /// Standard error of the mean (see [`block_average`]).
    pub error: f64,
    /// Blocks at the level the error was taken from.
    pub blocks: u64,
    /// Samples.
    pub samples: u64,
}

/// Mean and standard error of a correlated series by blocking (Flyvbjerg & Petersen, J. Chem.
/// Phys. 91, 461, 1989): the series is halved into blocks of 1, 2, 4, … samples; the naive error
/// of the block means grows with the block length until the blocks are longer than the
/// correlation time, then stays flat. The largest error over the levels with at least 16
/// blocks is returned (conservative; its own relative uncertainty is about `1/√(2·blocks)`).
pub fn block_average(x: &[f64]) -> BlockEstimate {
    let n = x.len();
    let mean = if n > 0 {
        x.iter().sum::<f64>() / n as f64
    } else {
        f64::NAN
    };
    let mut best = (f64::NAN, 0u64);
    let mut level: Vec<f64> = x.to_vec();
    while level.len() >= 16 {
        let m = level.len() as f64;
        let mu = level.iter().sum::<f64>() / m;
        let var = level.iter().map(|v| (v - mu) * (v - mu)).sum::<f64>() / (m - 1.0);
        let err = (var / m).sqrt();
        if best.0.is_nan() || err > best.0 {
            best = (err, level.len() as u64);
        }
        level = level.chunks_exact(2).map(|c| 0.5 * (c[0] + c[1])).collect();
    }
    BlockEstimate {
        mean,
        error: best.0,
        blocks: best.1,
        samples: n as u64,
    }
}
