//! Beliefs `B_k = p(X_k | Z_k)` (thesis eq. 3.1): where one object (or one landmark of a
//! triplet, in a normalised frame) probably is.
//!
//! Two forms, as the thesis uses both: a Gaussian (the well-separated and lab data of §3.4.1,
//! fitted to the measurements) and a weighted-equally sample set (the hallway triplets,
//! 10,000 transformed samples each, which are far from Gaussian). A [`BeliefSet`] is the
//! validated, non-empty input of SERGE; its JSON form is
//! `{"beliefs": [{"mean": [x, y], "cov": [[a, b], [b, c]]}, {"samples": [[x, y], ...]}]}`.

use serde::{Deserialize, Serialize};

use crate::error::{Result, SergeError};

/// One belief.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged, deny_unknown_fields)]
pub enum Belief {
    /// A bivariate normal.
    Gaussian {
        /// Mean `[x, y]`.
        mean: [f64; 2],
        /// Covariance `[[a, b], [b, c]]` (symmetric positive definite).
        cov: [[f64; 2]; 2],
    },
    /// Equally weighted samples `[x, y]`.
    Samples {
        /// The samples.
        samples: Vec<[f64; 2]>,
    },
}

impl Belief {
    /// A Gaussian belief.
    #[must_use]
    pub fn gaussian(mean: [f64; 2], cov: [[f64; 2]; 2]) -> Self {
        Self::Gaussian { mean, cov }
    }

    /// A sample belief.
    #[must_use]
    pub fn samples(samples: Vec<[f64; 2]>) -> Self {
        Self::Samples { samples }
    }

    /// The maximum-likelihood Gaussian of some points (mean and covariance of the points,
    /// §3.4.1), with `floor` added to the variances so two or three collinear points still
    /// give a proper belief.
    ///
    /// # Errors
    /// [`SergeError::Empty`] with no points; [`SergeError::NonFinite`].
    pub fn fit_gaussian(points: &[[f64; 2]], floor: f64) -> Result<Self> {
        if points.is_empty() {
            return Err(SergeError::Empty(
                "cannot fit a Gaussian to no points".into(),
            ));
        }
        if points.iter().flatten().any(|v| !v.is_finite()) || !floor.is_finite() {
            return Err(SergeError::NonFinite("a point to fit is not finite".into()));
        }
        let n = points.len() as f64;
        let mx = points.iter().map(|p| p[0]).sum::<f64>() / n;
        let my = points.iter().map(|p| p[1]).sum::<f64>() / n;
        let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
        for p in points {
            let (dx, dy) = (p[0] - mx, p[1] - my);
            a += dx * dx;
            b += dx * dy;
            c += dy * dy;
        }
        Ok(Self::gaussian(
            [mx, my],
            [[a / n + floor, b / n], [b / n, c / n + floor]],
        ))
    }

    /// The mean of the belief.
    #[must_use]
    pub fn mean(&self) -> [f64; 2] {
        match self {
            Self::Gaussian { mean, .. } => *mean,
            Self::Samples { samples } => {
                let n = samples.len().max(1) as f64;
                [
                    samples.iter().map(|p| p[0]).sum::<f64>() / n,
                    samples.iter().map(|p| p[1]).sum::<f64>() / n,
                ]
            }
        }
    }

    /// An axis-aligned box `[x0, x1, y0, y1]` holding the bulk of the belief: mean ± 4 sd for
    /// a Gaussian, the 0.5 % and 99.5 % quantiles of the samples per axis.
    #[must_use]
    pub fn extent(&self) -> [f64; 4] {
        match self {
            Self::Gaussian { mean, cov } => {
                let (sx, sy) = (cov[0][0].sqrt(), cov[1][1].sqrt());
                [
                    mean[0] - 4.0 * sx,
                    mean[0] + 4.0 * sx,
                    mean[1] - 4.0 * sy,
                    mean[1] + 4.0 * sy,
                ]
            }
            Self::Samples { samples } => {
                let q = |axis: usize| {
                    let mut v: Vec<f64> = samples.iter().map(|p| p[axis]).collect();
                    v.sort_by(f64::total_cmp);
                    let lo = v[((v.len() - 1) as f64 * 0.005).round() as usize];
                    let hi = v[((v.len() - 1) as f64 * 0.995).round() as usize];
                    (lo, hi)
                };
                let ((x0, x1), (y0, y1)) = (q(0), q(1));
                [x0, x1, y0, y1]
            }
        }
    }

    fn validate(&self, index: usize) -> Result<()> {
        match self {
            Self::Gaussian { mean, cov } => {
                if mean
                    .iter()
                    .chain(cov.iter().flatten())
                    .any(|v| !v.is_finite())
                {
                    return Err(SergeError::NonFinite(format!(
                        "belief {index}: mean {mean:?} / covariance {cov:?}"
                    )));
                }
                let bad = |reason| SergeError::DegenerateCovariance {
                    index,
                    cov: *cov,
                    reason,
                };
                // Scale-free: divide by the largest entry, so no product overflows (inf − inf
                // = NaN would pass every `<` test).
                let m = cov.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
                if m == 0.0 {
                    return Err(bad("a variance is not positive"));
                }
                let [[a, b], [b2, d]] = cov.map(|row| row.map(|v| v / m));
                let scale = a.abs().max(d.abs()).max(f64::MIN_POSITIVE);
                if (b - b2).abs() > 1e-9 * scale.max(b.abs()) {
                    return Err(bad("not symmetric"));
                }
                if a <= 0.0 || d <= 0.0 {
                    return Err(bad("a variance is not positive"));
                }
                let det = a * d - b * b2;
                // Issue 39: an indefinite matrix (det < 0: |cov_xy| above √(cov_xx·cov_yy)) was
                // called a line; only det ≈ 0 is one.
                if det < -1e-12 * a * d {
                    return Err(bad(
                        "not positive semi-definite: |cov_xy| exceeds √(cov_xx · cov_yy), no \
                         Gaussian has this covariance",
                    ));
                }
                if det <= 1e-12 * a * d {
                    return Err(bad("singular: the belief is a line, not an area"));
                }
                Ok(())
            }
            Self::Samples { samples } => {
                if samples.is_empty() {
                    return Err(SergeError::Empty(format!("belief {index} has no samples")));
                }
                if samples.iter().flatten().any(|v| !v.is_finite()) {
                    return Err(SergeError::NonFinite(format!(
                        "belief {index} has a non-finite sample"
                    )));
                }
                Ok(())
            }
        }
    }
}

/// A validated, non-empty list of beliefs (index = belief id `k`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BeliefSet {
    beliefs: Vec<Belief>,
}

impl BeliefSet {
    /// Validates beliefs.
    ///
    /// # Errors
    /// [`SergeError::Empty`], [`SergeError::NonFinite`], [`SergeError::DegenerateCovariance`].
    pub fn new(beliefs: Vec<Belief>) -> Result<Self> {
        if beliefs.is_empty() {
            return Err(SergeError::Empty("the belief set is empty".into()));
        }
        for (i, b) in beliefs.iter().enumerate() {
            b.validate(i)?;
        }
        Ok(Self { beliefs })
    }

    /// Parses the JSON input form `{"beliefs": [...]}`.
    ///
    /// # Errors
    /// [`SergeError::Parse`] for malformed JSON, then the errors of [`BeliefSet::new`].
    pub fn from_json_str(text: &str, context: &str) -> Result<Self> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Doc {
            beliefs: Vec<Belief>,
        }
        let doc: Doc = serde_json::from_str(text).map_err(|e| SergeError::Parse {
            context: context.to_owned(),
            reason: format!(
                "{e} (expected {{\"beliefs\": [{{\"mean\": [x, y], \"cov\": [[a, b], [b, c]]}} \
                 or {{\"samples\": [[x, y], ...]}}, ...]}})"
            ),
        })?;
        Self::new(doc.beliefs)
    }

    /// The JSON input form.
    #[must_use]
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({ "beliefs": self.beliefs })
    }

    /// Number of beliefs `K`.
    #[must_use]
    pub fn len(&self) -> usize {
        self.beliefs.len()
    }

    /// Always false (a set is never empty).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.beliefs.is_empty()
    }

    /// The beliefs.
    #[must_use]
    pub fn as_slice(&self) -> &[Belief] {
        &self.beliefs
    }

    /// Union of the beliefs' extents.
    #[must_use]
    pub fn extent(&self) -> [f64; 4] {
        self.beliefs.iter().map(Belief::extent).fold(
            [
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
            ],
            |a, e| {
                [
                    a[0].min(e[0]),
                    a[1].max(e[1]),
                    a[2].min(e[2]),
                    a[3].max(e[3]),
                ]
            },
        )
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)] // tests: a panic is the failure report
mod tests {
    use super::*;

    fn refusal(cov: [[f64; 2]; 2]) -> String {
        BeliefSet::new(vec![Belief::Gaussian {
            mean: [0.0, 0.0],
            cov,
        }])
        .unwrap_err()
        .to_string()
    }

    /// Issue 39: an indefinite covariance was called "singular: the belief is a line".
    #[test]
    fn regression_an_indefinite_covariance_is_not_called_a_line() {
        let e = refusal([[1.0, 2.0], [2.0, 1.0]]);
        assert!(
            e.contains("not positive semi-definite") && !e.contains("line"),
            "{e}"
        );
        let e = refusal([[1.0, 1.0], [1.0, 1.0]]);
        assert!(e.contains("line"), "{e}");
        assert!(
            BeliefSet::new(vec![Belief::Gaussian {
                mean: [0.0, 0.0],
                cov: [[1.0, 0.5], [0.5, 1.0]],
            }])
            .is_ok()
        );
    }
}
