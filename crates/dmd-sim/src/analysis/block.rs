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
    /// Whether the blocked errors reached their plateau ([`plateau`]); if not, the series is
    /// too short for its correlation time and `error` is a lower bound.
    #[serde(default = "yes")]
    pub converged: bool,
}

fn yes() -> bool {
    true
}

/// Whether blocked errors (`(error, blocks)` per level, block length doubling, levels with at
/// least 16 blocks) have reached their plateau: the last level's error exceeds neither of the
/// two before it by more than twice its own relative uncertainty `1/√(2(blocks − 1))`. While
/// the blocks are shorter than the correlation time each doubling raises the error by up to
/// √2, two by up to 2 (against 37 % allowed with 16 blocks), so a curve still rising at its end
/// fails. Fewer than three levels cannot show a plateau.
pub fn plateau(levels: &[(f64, u64)]) -> bool {
    let [.., (two_before, _), (before, _), (last, blocks)] = levels else {
        return false;
    };
    let allowed = 1.0 + 2.0 / (2.0 * (*blocks as f64 - 1.0)).sqrt();
    *last <= *before * allowed && *last <= *two_before * allowed
}

/// Mean and standard error of a correlated series by blocking (Flyvbjerg & Petersen, J. Chem.
/// Phys. 91, 461, 1989): the series is halved into blocks of 1, 2, 4, … samples; the naive error
/// of the block means grows with the block length until the blocks are longer than the
/// correlation time, then stays flat. The largest error over the levels with at least 16
/// blocks is returned (conservative; its own relative uncertainty is about `1/√(2·blocks)`),
/// with whether the curve reached its plateau ([`plateau`]).
pub fn block_average(x: &[f64]) -> BlockEstimate {
    let n = x.len();
    let mean = if n > 0 {
        x.iter().sum::<f64>() / n as f64
    } else {
        f64::NAN
    };
    let mut levels = Vec::new();
    let mut level: Vec<f64> = x.to_vec();
    while level.len() >= 16 {
        let m = level.len() as f64;
        let mu = level.iter().sum::<f64>() / m;
        let var = level.iter().map(|v| (v - mu) * (v - mu)).sum::<f64>() / (m - 1.0);
        levels.push(((var / m).sqrt(), level.len() as u64));
        level = level.chunks_exact(2).map(|c| 0.5 * (c[0] + c[1])).collect();
    }
    estimate_of(mean, &levels, n as u64)
}

/// The largest error over the levels, and whether they reached their plateau.
fn estimate_of(mean: f64, levels: &[(f64, u64)], samples: u64) -> BlockEstimate {
    let mut best = (f64::NAN, 0u64);
    for &(err, blocks) in levels {
        if best.0.is_nan() || err > best.0 {
            best = (err, blocks);
        }
    }
    BlockEstimate {
        mean,
        error: best.0,
        blocks: best.1,
        samples,
        converged: plateau(levels),
    }
}

/// One blocking level of [`Blocks`]: Welford's running mean and sum of squared deviations of
/// the block means, and the first half of the block being formed.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
struct Level {
    count: u64,
    mean: f64,
    m2: f64,
    pending: Option<f64>,
}

/// [`block_average`] of a series that arrives one value at a time, in `O(log n)` memory: each
/// level keeps the running mean and spread of its block means and hands every completed pair
/// on to the next level. The levels hold exactly the blocks of [`block_average`] (a trailing
/// odd value waits), so the estimate is the same up to round-off.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Blocks {
    levels: Vec<Level>,
}

impl Blocks {
    /// Adds the next value of the series.
    pub fn push(&mut self, x: f64) {
        let mut x = x;
        let mut k = 0;
        loop {
            if k == self.levels.len() {
                self.levels.push(Level::default());
            }
            let l = &mut self.levels[k];
            l.count += 1;
            let d = x - l.mean;
            l.mean += d / l.count as f64;
            l.m2 += d * (x - l.mean);
            match l.pending.take() {
                None => {
                    l.pending = Some(x);
                    return;
                }
                Some(first) => {
                    x = 0.5 * (first + x);
                    k += 1;
                }
            }
        }
    }

    /// Values pushed.
    pub fn len(&self) -> u64 {
        self.levels.first().map_or(0, |l| l.count)
    }

    /// Whether nothing was pushed.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes it takes: one level per doubling of the values pushed, `O(log n)`.
    pub fn bytes(&self) -> usize {
        std::mem::size_of::<Self>() + self.levels.capacity() * std::mem::size_of::<Level>()
    }

    /// Whether a state read back (from a checkpoint) is one that pushing values gives: each
    /// level holds half the values of the one below (rounded down) and a pending value exactly
    /// when its count is odd, with finite means and non-negative spreads.
    ///
    /// # Errors
    /// What does not fit.
    pub fn check(&self) -> Result<(), String> {
        for (k, l) in self.levels.iter().enumerate() {
            let below = if k == 0 {
                None
            } else {
                Some(self.levels[k - 1].count / 2)
            };
            // A level with a pair done has handed it on: the top one holds its first value only.
            let top = k + 1 == self.levels.len();
            let ok = below.is_none_or(|c| c == l.count)
                && (!top || l.count == 1)
                && l.pending.is_some() == (l.count % 2 == 1)
                && l.pending.is_none_or(f64::is_finite)
                && l.mean.is_finite()
                && l.m2.is_finite()
                && l.m2 >= 0.0;
            if !ok {
                return Err(format!(
                    "its blocking level {k} ({} values) is not one that sampling gives",
                    l.count
                ));
            }
        }
        Ok(())
    }

    /// Mean of every value pushed and its standard error by the rule of [`block_average`]
    /// (the largest over the levels with at least 16 blocks; NaN with fewer than 16 values).
    pub fn estimate(&self) -> BlockEstimate {
        let levels: Vec<(f64, u64)> = self
            .levels
            .iter()
            .filter(|l| l.count >= 16)
            .map(|l| {
                let m = l.count as f64;
                ((l.m2 / (m - 1.0) / m).sqrt(), l.count)
            })
            .collect();
        let mean = self.levels.first().map_or(f64::NAN, |l| l.mean);
        estimate_of(mean, &levels, self.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, StandardNormal};

    /// `n` values of the AR(1) process `x_t = φ x_{t−1} + ε_t` (unit-variance noise), started
    /// in its stationary distribution.
    fn ar1(phi: f64, n: usize, seed: u64) -> Vec<f64> {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(seed);
        let x0: f64 = StandardNormal.sample(&mut rng);
        let mut x = x0 / (1.0 - phi * phi).sqrt();
        (0..n)
            .map(|_| {
                let e: f64 = StandardNormal.sample(&mut rng);
                x = phi * x + e;
                x
            })
            .collect()
    }

    /// For AR(1) the variance of the mean of `n` values tends to
    /// `σ² (1 + φ)/(1 − φ) / n` with `σ² = 1/(1 − φ²)`: the blocked error of one long series
    /// must find it, within the blocking's own uncertainty (the largest of the levels' errors
    /// is taken, each uncertain by `1/√(2·blocks)`, so one series may come out a third high).
    #[test]
    fn blocked_errors_of_an_ar1_series_match_the_analytic_value() {
        let n = 1 << 18;
        for (phi, seed) in [(0.0, 1), (0.5, 2), (0.9, 3), (0.97, 4)] {
            let x = ar1(phi, n, seed);
            let exact = (1.0 / (1.0 - phi * phi) * (1.0 + phi) / (1.0 - phi) / n as f64).sqrt();
            let b = block_average(&x);
            let ratio = b.error / exact;
            assert!(
                (0.75..1.45).contains(&ratio),
                "φ = {phi}: blocked {} against analytic {exact} ({ratio})",
                b.error
            );
            // The naive error (no blocking) misses the correlation by √((1 + φ)/(1 − φ)).
            if phi >= 0.9 {
                let naive = (x.iter().map(|v| (v - b.mean).powi(2)).sum::<f64>()
                    / (n as f64 - 1.0)
                    / n as f64)
                    .sqrt();
                assert!(naive < 0.4 * exact, "φ = {phi}: naive {naive}");
            }
        }
    }

    /// Averaged over many independent series the blocked error is the analytic one within
    /// 15 % (taking the largest level's error makes it a few per cent high on average), and
    /// so is the scatter of the means.
    #[test]
    fn blocked_errors_are_calibrated_over_many_series() {
        let (phi, n, runs) = (0.8, 1 << 14, 200);
        let exact = (1.0 / (1.0 - phi * phi) * (1.0 + phi) / (1.0 - phi) / n as f64).sqrt();
        let mut means = Vec::new();
        let mut errors = Vec::new();
        for seed in 0..runs {
            let b = block_average(&ar1(phi, n, 100 + seed));
            means.push(b.mean);
            errors.push(b.error);
        }
        let m = means.iter().sum::<f64>() / runs as f64;
        let scatter =
            (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (runs as f64 - 1.0)).sqrt();
        let mean_error = errors.iter().sum::<f64>() / runs as f64;
        assert!(
            (mean_error / exact - 1.0).abs() < 0.15,
            "{mean_error} vs {exact}"
        );
        assert!((scatter / exact - 1.0).abs() < 0.2, "{scatter} vs {exact}");
    }

    /// Long series of short correlation reach the plateau; series shorter than a few
    /// correlation times do not, and say so.
    #[test]
    fn the_plateau_is_found_when_the_series_is_long_enough_and_only_then() {
        let converged = |phi: f64, n: usize| {
            (0..40)
                .filter(|&seed| block_average(&ar1(phi, n, 500 + seed)).converged)
                .count()
        };
        // τ ≈ 10 samples, 2^16 samples: nearly always a plateau.
        assert!(converged(0.9, 1 << 16) >= 34, "{}", converged(0.9, 1 << 16));
        // τ ≈ 2000 samples, 2^12 samples (two correlation times): almost never.
        assert!(
            converged(0.9995, 1 << 12) <= 6,
            "{}",
            converged(0.9995, 1 << 12)
        );
        assert!(!plateau(&[(1.0, 64), (1.0, 32)]));
        assert!(plateau(&[(1.0, 64), (1.0, 32), (1.0, 16)]));
        assert!(!plateau(&[(1.0, 64), (1.0, 32), (1.41, 16)]));
        assert!(!plateau(&[(1.0, 64), (1.3, 32), (1.41, 16)]));
    }

    /// The online accumulator gives the stored series' estimate for any series: the same
    /// levels, blocks, samples and plateau verdict, and mean and error equal up to round-off
    /// (Welford's running sums against two passes).
    mod online {
        use super::super::*;
        use proptest::prelude::*;

        proptest! {
            #![proptest_config(ProptestConfig::with_cases(200))]
            #[test]
            fn online_estimate_is_the_stored_series_estimate(
                n in 0usize..5000,
                phi in 0.0f64..0.999,
                offset in -1e6f64..1e6,
                scale in 1e-6f64..1e6,
                seed in any::<u64>(),
            ) {
                let x: Vec<f64> = super::ar1(phi, n, seed)
                    .into_iter()
                    .map(|v| offset + scale * v)
                    .collect();
                let mut b = Blocks::default();
                for &v in &x {
                    b.push(v);
                }
                prop_assert!(b.check().is_ok());
                let (a, o) = (block_average(&x), b.estimate());
                prop_assert_eq!((a.blocks, a.samples), (o.blocks, o.samples));
                prop_assert_eq!(a.converged, o.converged);
                if n > 0 {
                    let tol = 1e-12 * (offset.abs() + scale);
                    prop_assert!((a.mean - o.mean).abs() <= tol, "{} {}", a.mean, o.mean);
                }
                if n >= 16 {
                    // Round-off of the spreads is relative to the mean's size over the error's.
                    let tol = 1e-9 * a.error + 1e-13 * (offset.abs() + scale);
                    prop_assert!((a.error - o.error).abs() <= tol, "{} {}", a.error, o.error);
                } else {
                    prop_assert!(a.error.is_nan() && o.error.is_nan());
                }
            }
        }
    }

    /// A million values take 20 levels of a few dozen bytes: memory grows as `log2 n`, not
    /// with `n` (the stored series would take 8 MB).
    #[test]
    fn online_blocks_stay_small_after_a_million_values() {
        let mut b = Blocks::default();
        let x = ar1(0.9, 1000, 77);
        for &v in &x {
            b.push(v);
        }
        let (levels_1e3, bytes_1e3) = (b.levels.len(), b.bytes());
        for k in 1000..1_000_000 {
            b.push(x[k % 1000]);
        }
        assert_eq!(b.len(), 1_000_000);
        assert_eq!(levels_1e3, 10);
        assert_eq!(b.levels.len(), 20);
        assert!(
            b.bytes() <= 2 * bytes_1e3 + 1024,
            "{} {}",
            b.bytes(),
            bytes_1e3
        );
        assert!(b.bytes() < 2048, "{} bytes", b.bytes());
        assert!(b.check().is_ok());
        // The checkpoint's form of it is as small.
        assert!(postcard::to_allocvec(&b).unwrap().len() < 1024);
    }

    /// A state that pushing cannot give is refused (a forged checkpoint).
    #[test]
    fn inconsistent_blocks_are_refused() {
        let mut b = Blocks::default();
        for v in ar1(0.5, 100, 3) {
            b.push(v);
        }
        let mut bad = b.clone();
        bad.levels[2].count += 1;
        assert!(bad.check().is_err());
        let mut bad = b.clone();
        bad.levels[0].m2 = -1.0;
        assert!(bad.check().is_err());
        let mut bad = b.clone();
        bad.levels[1].pending = Some(f64::NAN);
        assert!(bad.check().is_err());
        let mut bad = b.clone();
        bad.levels.push(Level::default());
        assert!(bad.check().is_err());
    }

    #[test]
    fn online_blocks_agree_with_block_average() {
        for n in [0, 1, 15, 16, 17, 100, 1000, 4097] {
            let x = ar1(0.7, n, 9 + n as u64);
            let mut b = Blocks::default();
            for &v in &x {
                b.push(v);
            }
            let (a, o) = (block_average(&x), b.estimate());
            assert_eq!(
                (a.blocks, a.samples, a.converged),
                (o.blocks, o.samples, o.converged),
                "n = {n}"
            );
            if n == 0 {
                assert!(o.mean.is_nan() && o.error.is_nan());
                continue;
            }
            assert!((a.mean - o.mean).abs() < 1e-12, "n = {n}");
            if n < 16 {
                assert!(a.error.is_nan() && o.error.is_nan(), "n = {n}");
            } else {
                assert!(
                    (a.error - o.error).abs() < 1e-10 * a.error,
                    "n = {n}: {} {}",
                    a.error,
                    o.error
                );
            }
        }
    }
}
