//! A recording in any form qrm reads — observation CSV, the MRCLAM folder, g2o landmark
//! edges, a ROS 2 bag or Foxglove/qrm MCAP log — for the studies that map a user's data and
//! for the front ends that read one.

use std::path::Path;

use pqrm::loaders::{Dataset, RangeBearingNoise, read_csv, read_g2o, read_mrclam};
use serde::{Deserialize, Serialize};

use crate::error::{Result, StudyError};

/// The form of a recording.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RecordingFormat {
    /// `t,robot,landmark,x,y,cxx,cxy,cyy` rows.
    Csv,
    /// The UTIAS MRCLAM dataset's folder (range-bearing, surveyed landmarks).
    Mrclam,
    /// g2o landmark edges.
    G2o,
    /// A ROS 2 bag or a Foxglove/qrm MCAP log.
    Mcap,
}

impl RecordingFormat {
    /// Every form, in the order the command line lists them.
    pub const ALL: [Self; 4] = [Self::Csv, Self::Mrclam, Self::G2o, Self::Mcap];

    /// Its name (`csv`, `mrclam`, `g2o`, `mcap`), as in configs and on the command line.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Csv => "csv",
            Self::Mrclam => "mrclam",
            Self::G2o => "g2o",
            Self::Mcap => "mcap",
        }
    }
}

impl std::fmt::Display for RecordingFormat {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Reads the recording at `path`; `noise` gives MRCLAM's range-bearing detections their
/// covariances (the other forms carry their own).
///
/// # Errors
/// [`StudyError::Pqrm`] for a negative, huge or non-finite noise; the loaders' errors
/// ([`StudyError::Pqrm`], [`StudyError::Log`]) naming the file, line and field.
pub fn read(format: RecordingFormat, path: &Path, noise: RangeBearingNoise) -> Result<Dataset> {
    noise.validate()?;
    Ok(match format {
        RecordingFormat::Csv => read_csv(path)?,
        RecordingFormat::Mrclam => read_mrclam(path, noise)?,
        RecordingFormat::G2o => read_g2o(path)?,
        RecordingFormat::Mcap => {
            qrm_log::read_mcap(path, &qrm_log::ReadOptions::default())?.dataset
        }
    })
}

/// A recording's frames as the landmark sightings a calculus is learned from
/// ([`serge::selection`]).
#[must_use]
pub fn sightings(scans: &[pqrm::Scan]) -> Vec<Vec<serge::selection::Sighting>> {
    scans
        .iter()
        .map(|s| {
            s.observations
                .iter()
                .map(|o| serge::selection::Sighting {
                    id: o.id.0,
                    xy: o.mean,
                    cov: o.cov,
                })
                .collect()
        })
        .collect()
}

/// Where a range-bearing recording's noise comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseMode {
    /// Fitted from the recording itself ([`pqrm::calibrate::fit_noise`]).
    Auto,
    /// The given standard deviations, else MRCLAM's.
    Fixed,
}

/// The range-bearing noise a user asks for: a mode, standard deviations, or neither. Without
/// a mode a given σ means fixed (explicit values win) and otherwise MRCLAM is fitted; the
/// other forms carry their own covariances and take the fixed noise.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct NoiseRequest {
    /// `auto` or `fixed`; `None`: as said above.
    pub mode: Option<NoiseMode>,
    /// Range noise (m).
    pub sigma_range: Option<f64>,
    /// Bearing noise (rad).
    pub sigma_bearing: Option<f64>,
}

/// The noise a recording is read with, and how it was chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ResolvedNoise {
    /// What the loader uses.
    pub noise: RangeBearingNoise,
    /// The fit, when the noise was fitted.
    pub fit: Option<pqrm::calibrate::NoiseFit>,
}

impl NoiseRequest {
    /// Checks the σs given, whatever the recording's form: a σ for a recording that carries
    /// its own covariances goes unused, but 1e308 is still a wrong flag (issue 39).
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] naming `sigma_range` or `sigma_bearing`.
    pub fn validate(&self) -> Result<()> {
        self.fixed().validate()?;
        Ok(())
    }

    /// The σs given, MRCLAM's where one is missing (unchecked).
    fn fixed(&self) -> RangeBearingNoise {
        RangeBearingNoise {
            sigma_range: self
                .sigma_range
                .unwrap_or(RangeBearingNoise::MRCLAM.sigma_range),
            sigma_bearing: self
                .sigma_bearing
                .unwrap_or(RangeBearingNoise::MRCLAM.sigma_bearing),
        }
    }

    /// The noise to read `input` (of form `format`) with. A fit nobody asked for that fails (a
    /// recording too short) keeps the fixed noise, and `warn` is told why; `mode: auto` asked
    /// for it, so there it is an error.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] for `auto` on a form that is not range-bearing or
    /// beside given σs; the loader's errors; the fit's when `auto` was asked for.
    pub fn resolve(
        &self,
        format: RecordingFormat,
        input: &Path,
        warn: &dyn Fn(String),
    ) -> Result<ResolvedNoise> {
        self.validate()?;
        let fixed = self.fixed();
        let given = self.sigma_range.is_some() || self.sigma_bearing.is_some();
        let fixed_only = ResolvedNoise {
            noise: fixed,
            fit: None,
        };
        let mode = self
            .mode
            .unwrap_or(if given || format != RecordingFormat::Mrclam {
                NoiseMode::Fixed
            } else {
                NoiseMode::Auto
            });
        if mode == NoiseMode::Fixed {
            return Ok(fixed_only);
        }
        if format != RecordingFormat::Mrclam {
            return Err(StudyError::InvalidParameter(
                "--noise auto fits a range-bearing sensor: --format mrclam (the other formats \
                 carry their own covariances; `qrm pqrm calibrate` reports a fit for any)"
                    .into(),
            ));
        }
        if given {
            return Err(StudyError::InvalidParameter(
                "--noise auto fits σ_r and σ_b; drop --sigma-range/--sigma-bearing or say \
                 --noise fixed"
                    .into(),
            ));
        }
        match pqrm::calibrate::fit_noise(&read(format, input, fixed)?) {
            Ok(fit) => Ok(ResolvedNoise {
                noise: RangeBearingNoise {
                    sigma_range: fit.sigma_range,
                    sigma_bearing: fit.sigma_bearing,
                },
                fit: Some(fit),
            }),
            Err(e) if self.mode.is_none() => {
                warn(format!(
                    "{}: the noise cannot be fitted ({e}); using σ_r = {} m, σ_b = {} rad",
                    input.display(),
                    fixed.sigma_range,
                    fixed.sigma_bearing
                ));
                Ok(fixed_only)
            }
            Err(e) => Err(StudyError::InvalidParameter(format!(
                "fitting the noise (--noise auto): {e}"
            ))),
        }
    }
}
