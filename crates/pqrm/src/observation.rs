//! Landmark observations: what a robot's perception hands the mapper at one time step.
//!
//! Positions are in the robot's frame at that step (the mapper never needs a global pose:
//! every qualitative state is invariant to the frame, thesis §2.2.1). Each observation carries
//! the Gaussian inverse sensor model of eq. 2.9: a mean and a 2×2 covariance.

use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result, finite};

/// A landmark's identity (data association is given, thesis §2.2.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(transparent)]
pub struct LandmarkId(pub u32);

impl std::fmt::Display for LandmarkId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}", self.0)
    }
}

/// One landmark seen at one time step: mean position (m, robot frame) and covariance (m²).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Observation {
    /// Which landmark.
    pub id: LandmarkId,
    /// Mean position `[x, y]`.
    pub mean: [f64; 2],
    /// Covariance `[[xx, xy], [yx, yy]]`.
    pub cov: [[f64; 2]; 2],
}

/// The largest distance (m) qrm takes as a noise σ or an outlier spread: a thousand kilometres,
/// beyond any range sensor. Larger values overflow when squared into a covariance (1e308) or
/// leave samples unable to tell landmarks metres apart (2⁶⁴ m), and then a later stage blames
/// the recording or "coinciding landmarks" instead of the flag.
pub const MAX_DISTANCE_M: f64 = 1e6;

/// Relative tolerance for the symmetry and semi-definiteness checks of a covariance.
const COV_TOL: f64 = 1e-9;

impl Observation {
    /// A validated observation.
    ///
    /// # Errors
    /// [`PqrmError::NonFinite`]; [`PqrmError::BadCovariance`] when the covariance is not
    /// symmetric (relative tolerance 1e-9) or not positive semi-definite (a negative variance
    /// or determinant beyond rounding).
    pub fn new(id: LandmarkId, mean: [f64; 2], cov: [[f64; 2]; 2]) -> Result<Self> {
        finite(|| format!("landmark {id}: mean {mean:?}"), &mean)?;
        finite(
            || format!("landmark {id}: covariance {cov:?}"),
            &[cov[0][0], cov[0][1], cov[1][0], cov[1][1]],
        )?;
        let bad = |reason| PqrmError::BadCovariance {
            id: id.0,
            cov,
            reason,
        };
        // Scale-free: divide by the largest entry first, so no product below overflows (a
        // determinant of 1e200·1e200 − 1e250² is inf − inf = NaN, and NaN < tol is false).
        let m = cov.iter().flatten().fold(0.0f64, |acc, v| acc.max(v.abs()));
        if m == 0.0 {
            return Ok(Self { id, mean, cov });
        }
        let [[a, b], [b2, d]] = cov.map(|row| row.map(|v| v / m));
        let scale = a.abs() + d.abs() + f64::MIN_POSITIVE;
        if (b - b2).abs() > COV_TOL * scale.max(b.abs()) {
            return Err(bad("not symmetric"));
        }
        if a < 0.0 || d < 0.0 {
            return Err(bad("negative variance"));
        }
        let det = a * d - b * b;
        if det < -COV_TOL * scale * scale {
            return Err(bad("negative determinant"));
        }
        Ok(Self { id, mean, cov })
    }

    /// An isotropic observation: `cov = sigma² I`.
    ///
    /// # Errors
    /// As [`Observation::new`]; a negative `sigma` is an error.
    pub fn isotropic(id: LandmarkId, mean: [f64; 2], sigma: f64) -> Result<Self> {
        if sigma < 0.0 {
            return Err(PqrmError::InvalidConfig(format!(
                "landmark {id}: sigma {sigma} < 0"
            )));
        }
        Self::new(id, mean, [[sigma * sigma, 0.0], [0.0, sigma * sigma]])
    }

    /// From a range-bearing measurement with independent Gaussian noise on range (m) and
    /// bearing (rad): the mean is `(r cos b, r sin b)` and the covariance is the linearised
    /// `J diag(σr², σb²) Jᵀ` with `J = [[cos b, −r sin b], [sin b, r cos b]]`.
    ///
    /// # Errors
    /// As [`Observation::new`]; negative range or standard deviations are errors.
    pub fn from_range_bearing(
        id: LandmarkId,
        range: f64,
        bearing: f64,
        sigma_range: f64,
        sigma_bearing: f64,
    ) -> Result<Self> {
        finite(
            || {
                format!(
                    "landmark {id}: range-bearing ({range}, {bearing}, {sigma_range}, {sigma_bearing})"
                )
            },
            &[range, bearing, sigma_range, sigma_bearing],
        )?;
        if range < 0.0 || sigma_range < 0.0 || sigma_bearing < 0.0 {
            return Err(PqrmError::InvalidConfig(format!(
                "landmark {id}: range {range} and standard deviations ({sigma_range}, {sigma_bearing}) must be >= 0"
            )));
        }
        let (s, c) = bearing.sin_cos();
        let (vr, vb) = (
            sigma_range * sigma_range,
            sigma_bearing * sigma_bearing * range * range,
        );
        let cov = [
            [c * c * vr + s * s * vb, s * c * (vr - vb)],
            [s * c * (vr - vb), s * s * vr + c * c * vb],
        ];
        Self::new(id, [range * c, range * s], cov)
    }

    /// Lower Cholesky factor `[l11, l21, l22]` of the covariance (semi-definite allowed).
    #[must_use]
    pub fn cholesky(&self) -> [f64; 3] {
        let l11 = self.cov[0][0].max(0.0).sqrt();
        let l21 = if l11 > 0.0 { self.cov[0][1] / l11 } else { 0.0 };
        let l22 = (self.cov[1][1] - l21 * l21).max(0.0).sqrt();
        [l11, l21, l22]
    }
}

/// Everything one robot saw at one time step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Scan {
    /// Time stamp (s).
    pub t: f64,
    /// Which robot (0 for single-robot data).
    pub robot: u32,
    /// Observations, sorted by landmark id, each id once.
    pub observations: Vec<Observation>,
}

impl Scan {
    /// A validated scan: observations are sorted by id; a repeated id is an error.
    ///
    /// # Errors
    /// [`PqrmError::NonFinite`] for a non-finite time, [`PqrmError::DuplicateLandmark`].
    pub fn new(t: f64, robot: u32, mut observations: Vec<Observation>) -> Result<Self> {
        finite(|| format!("scan time {t}"), &[t])?;
        observations.sort_by_key(|o| o.id);
        if let Some(w) = observations.windows(2).find(|w| w[0].id == w[1].id) {
            return Err(PqrmError::DuplicateLandmark(w[0].id.0));
        }
        Ok(Self {
            t,
            robot,
            observations,
        })
    }
}
