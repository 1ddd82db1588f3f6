//! The recording a real-data study maps: read with the noise the config asks for (given, or
//! fitted from the recording itself), gross outliers gated, the frames kept, the noise model
//! checked against the surveyed landmarks. Every shard reads it the same way, so a shard on
//! another machine maps exactly the frames a local run maps.

use std::path::Path;

use pqrm::calibrate::{Gated, NoiseFit, fit_noise, gate_outliers};
use pqrm::loaders::{Dataset, RangeBearingNoise, read_mrclam};
use pqrm::study::{NoiseCheck, noise_check};
use serde::{Deserialize, Serialize};

use super::{NoiseSource, RealDataConfig};
use crate::error::{Result, StudyError};

/// A frame needs three landmarks to say anything about a triplet.
const MIN_LANDMARKS_PER_FRAME: usize = 3;

/// The recording as mapped, and what was done to it on the way.
#[derive(Debug, Clone)]
pub struct Recording {
    /// The frames mapped (three or more landmarks each), with the surveyed truth.
    pub data: Dataset,
    /// What the report says about it.
    pub summary: RecordingSummary,
}

/// What a report says about the recording: its name, the noise it was read with, the
/// outliers gated, the check of the noise model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RecordingSummary {
    /// The recording's directory name (`mrclam-dataset7`).
    pub title: String,
    /// Frames mapped.
    pub frames: usize,
    /// The range-bearing noise the detections' covariances come from.
    pub noise: RangeBearingNoise,
    /// The fit it came from (`None`: given in the config).
    pub noise_fit: Option<NoiseFit>,
    /// The gross outliers gated (`None`: gating off).
    pub gated: Option<Gated>,
    /// Measurements the loader skipped on purpose (robot-to-robot sightings, unknown
    /// barcodes).
    pub skipped_measurements: usize,
    /// How well the noise model describes the measured inter-landmark distances.
    pub noise_check: NoiseCheck,
}

/// Reads the recording of `config` as every shard maps it.
///
/// # Errors
/// [`StudyError::Pqrm`] for a recording that cannot be read (naming the file and line) or
/// whose noise cannot be fitted; [`StudyError::InvalidParameter`] for an input that is not a
/// directory, or when no frame sees three landmarks.
pub fn read(config: &RealDataConfig) -> Result<Recording> {
    if !config.input.is_dir() {
        return Err(StudyError::InvalidParameter(format!(
            "input = {}: no such directory (the MRCLAM recording's folder: `input` in the config, `--input DIR` of `qrm pqrm real`)",
            config.input.display()
        )));
    }
    let given = RangeBearingNoise {
        sigma_range: config.sigma_range,
        sigma_bearing: config.sigma_bearing,
    };
    let (noise, noise_fit) = match config.noise {
        NoiseSource::Given => (given, None),
        NoiseSource::Fitted => {
            let fit = fit_noise(&read_mrclam(&config.input, given)?)?;
            let fitted = RangeBearingNoise {
                sigma_range: fit.sigma_range,
                sigma_bearing: fit.sigma_bearing,
            };
            (fitted, Some(fit))
        }
    };
    let mut data = read_mrclam(&config.input, noise)?;
    let gated = match config.gate_sigmas {
        Some(z_max) => {
            let fit = match &noise_fit {
                Some(f) => *f,
                None => fit_noise(&data)?,
            };
            let (kept, g) = gate_outliers(&data, &fit, z_max);
            data.scans = kept.scans;
            Some(g)
        }
        None => None,
    };
    data.scans
        .retain(|s| s.observations.len() >= MIN_LANDMARKS_PER_FRAME);
    if let Some(n) = config.max_frames {
        data.scans.truncate(n);
    }
    if data.scans.is_empty() {
        return Err(StudyError::InvalidParameter(format!(
            "{}: no frame sees {MIN_LANDMARKS_PER_FRAME} or more landmarks",
            config.input.display()
        )));
    }
    let check = noise_check(&data)?;
    Ok(Recording {
        summary: RecordingSummary {
            title: title(&config.input),
            frames: data.scans.len(),
            noise,
            noise_fit,
            gated,
            skipped_measurements: data.skipped,
            noise_check: check,
        },
        data,
    })
}

/// The name a report gives a recording: its directory's name.
fn title(input: &Path) -> String {
    input.file_name().map_or_else(
        || input.display().to_string(),
        |n| n.to_string_lossy().into_owned(),
    )
}
