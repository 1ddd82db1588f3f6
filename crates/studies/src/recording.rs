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
/// [`StudyError::InvalidParameter`] for a negative or non-finite noise; the loaders' errors
/// ([`StudyError::Pqrm`], [`StudyError::Log`]) naming the file, line and field.
pub fn read(format: RecordingFormat, path: &Path, noise: RangeBearingNoise) -> Result<Dataset> {
    let ok = |s: f64| s.is_finite() && s >= 0.0;
    if !(ok(noise.sigma_range) && ok(noise.sigma_bearing)) {
        return Err(StudyError::InvalidParameter(format!(
            "noise standard deviations must be finite and >= 0, not {} m and {} rad",
            noise.sigma_range, noise.sigma_bearing
        )));
    }
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
