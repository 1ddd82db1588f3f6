//! Summary statistics, with one convention for the whole workspace.
//!
//! The spread of trials, folds, worlds or residuals is reported as the **sample standard
//! deviation** (divisor n − 1, Bessel's correction): each set of values is a sample of what
//! the experiment would give if run again, and the sd estimates that population's. One value
//! has sd 0; no value gives mean 0 and sd 0 with `n = 0` (never NaN), so a caller that must
//! tell "no data" from "no spread" reads `n`.
//!
//! Both are computed without overflow for any finite input (the sum is scaled, the squares
//! are taken of deviations divided by the largest one): a surveyed coordinate of 1e154 once
//! made a `z std` infinite (issue 17).
//!
//! ```
//! use qsr_core::stats::MeanSd;
//! let s = MeanSd::of(&[1.0, 2.0, 3.0, 4.0]);
//! assert_eq!(s.mean, 2.5);
//! assert!((s.sd - (5.0f64 / 3.0).sqrt()).abs() < 1e-15); // divisor n − 1 = 3
//! assert_eq!(MeanSd::of(&[]).n, 0);
//! ```

use serde::{Deserialize, Serialize};

/// Mean and sample standard deviation of some values (see the module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct MeanSd {
    /// The arithmetic mean (0 for no value).
    pub mean: f64,
    /// The sample standard deviation, divisor n − 1 (0 for fewer than two values).
    pub sd: f64,
    /// How many values.
    pub n: usize,
}

impl MeanSd {
    /// The mean and sample sd of `values`.
    #[must_use]
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        if n == 0 {
            return Self::default();
        }
        // the mean as Σ x_i/n: each term is finite where the plain sum could overflow
        let nf = n as f64;
        let mean = values.iter().map(|v| v / nf).sum::<f64>();
        if n == 1 {
            return Self { mean, sd: 0.0, n };
        }
        let scale = values.iter().fold(0.0_f64, |m, v| m.max((v - mean).abs()));
        let sd = if scale > 0.0 && scale.is_finite() {
            scale
                * (values
                    .iter()
                    .map(|v| ((v - mean) / scale).powi(2))
                    .sum::<f64>()
                    / (nf - 1.0))
                    .sqrt()
        } else {
            scale
        };
        Self { mean, sd, n }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sd_divides_by_n_minus_one() {
        let s = MeanSd::of(&[2.0, 4.0]);
        assert_eq!((s.mean, s.n), (3.0, 2));
        assert!((s.sd - 2f64.sqrt()).abs() < 1e-15);
        assert_eq!(
            MeanSd::of(&[7.0]),
            MeanSd {
                mean: 7.0,
                sd: 0.0,
                n: 1
            }
        );
        assert_eq!(MeanSd::of(&[]), MeanSd::default());
    }

    #[test]
    fn huge_values_do_not_overflow() {
        let s = MeanSd::of(&[1e308, -1e308, 1e308]);
        assert!(s.mean.is_finite() && s.sd.is_finite(), "{s:?}");
        // deviations ±5e153: squared they would overflow, scaled they do not
        let t = MeanSd::of(&[1e154, 0.0]);
        assert!((t.sd / (5e153 * 2f64.sqrt()) - 1.0).abs() < 1e-12, "{t:?}");
    }
}
