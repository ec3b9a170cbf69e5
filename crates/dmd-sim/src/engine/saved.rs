//! A model's state beyond the loop's body records as a flat list of numbers
//! (`PairModel::extra_state`, the model contract's): checkpoints and
//! HMC rollbacks carry it verbatim. [`push_count`] writes an integer exactly (two 32-bit halves);
//! [`StateReader`] reads the list back and names what does not fit, so a checkpoint of another
//! scene is refused with a reason instead of restoring nonsense.

use glam::{DMat3, DVec3};

/// Appends `c` as two exact 32-bit halves (an `f64` holds integers only to 2⁵³).
pub fn push_count(out: &mut Vec<f64>, c: u64) {
    out.push((c >> 32) as f64);
    out.push((c & 0xffff_ffff) as f64);
}

/// Reads a model's saved numbers front to back.
#[derive(Debug)]
pub struct StateReader<'a> {
    x: &'a [f64],
    at: usize,
}

impl<'a> StateReader<'a> {
    /// A reader at the start of `x`.
    pub fn new(x: &'a [f64]) -> Self {
        StateReader { x, at: 0 }
    }

    /// The next `n` numbers, every one finite.
    ///
    /// # Errors
    /// Too few numbers left, or one not finite; the message names `what`.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [f64], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.x.len());
        let Some(end) = end else {
            return Err(format!(
                "the saved state ends before {what} ({} numbers, {n} more wanted at {})",
                self.x.len(),
                self.at
            ));
        };
        let s = &self.x[self.at..end];
        if let Some(k) = s.iter().position(|v| !v.is_finite()) {
            return Err(format!("{what} has a non-finite number ({})", s[k]));
        }
        self.at = end;
        Ok(s)
    }

    /// One finite number.
    ///
    /// # Errors
    /// As [`take`](Self::take).
    pub fn real(&mut self, what: &str) -> Result<f64, String> {
        Ok(self.take(1, what)?[0])
    }

    /// A vector of three numbers.
    ///
    /// # Errors
    /// As [`take`](Self::take).
    pub fn vec3(&mut self, what: &str) -> Result<DVec3, String> {
        Ok(DVec3::from_slice(self.take(3, what)?))
    }

    /// A matrix of nine numbers, column-major.
    ///
    /// # Errors
    /// As [`take`](Self::take).
    pub fn mat3(&mut self, what: &str) -> Result<DMat3, String> {
        Ok(DMat3::from_cols_slice(self.take(9, what)?))
    }

    /// An integer written as one number, below `limit`.
    ///
    /// # Errors
    /// As [`take`](Self::take), or not an integer in `[0, limit)`.
    pub fn index(&mut self, what: &str, limit: u64) -> Result<u64, String> {
        let v = self.real(what)?;
        if v >= 0.0 && v.fract() == 0.0 && v < limit as f64 {
            Ok(v as u64)
        } else {
            Err(format!("{what} is {v}, not an integer below {limit}"))
        }
    }

    /// An integer written by [`push_count`].
    ///
    /// # Errors
    /// As [`take`](Self::take), or the halves are not 32-bit integers.
    pub fn count(&mut self, what: &str) -> Result<u64, String> {
        let h = self.take(2, what)?;
        let ok = |v: f64| (0.0..4_294_967_296.0).contains(&v) && v.fract() == 0.0;
        if ok(h[0]) && ok(h[1]) {
            Ok((h[0] as u64) << 32 | h[1] as u64)
        } else {
            Err(format!("{what} is not a count"))
        }
    }

    /// Checks that every number was read.
    ///
    /// # Errors
    /// Numbers are left over (the state is of another model or scene).
    pub fn finish(self) -> Result<(), String> {
        if self.at == self.x.len() {
            Ok(())
        } else {
            Err(format!(
                "the saved state has {} numbers, the model reads {}",
                self.x.len(),
                self.at
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_and_misfits_are_named() {
        let mut x = vec![1.5, 2.0];
        push_count(&mut x, u64::MAX - 3);
        x.extend_from_slice(&[0.0, 1.0, 2.0]);
        let mut r = StateReader::new(&x);
        assert_eq!(r.real("a").unwrap(), 1.5);
        assert_eq!(r.index("b", 3).unwrap(), 2);
        assert_eq!(r.count("c").unwrap(), u64::MAX - 3);
        assert_eq!(r.vec3("d").unwrap(), DVec3::new(0.0, 1.0, 2.0));
        r.finish().unwrap();

        let mut r = StateReader::new(&x);
        assert!(r.index("the first", 10).unwrap_err().contains("the first"));
        let mut r = StateReader::new(&x);
        r.real("a").unwrap();
        assert!(r.index("b", 2).unwrap_err().contains("below 2"));
        let mut r = StateReader::new(&x[..3]);
        r.take(2, "a").unwrap();
        assert!(r.count("c").unwrap_err().contains("ends before c"));
        let r = StateReader::new(&x);
        assert!(r.finish().unwrap_err().contains("7 numbers"));
        let nan = [f64::NAN];
        assert!(
            StateReader::new(&nan)
                .real("t")
                .unwrap_err()
                .contains("non-finite")
        );
    }
}
