//! [`PqrmConfig`]: the mapper's settings and their checks, apart from the map so that the map
//! file's header can name them without depending on the map.

use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::Orderings;
use crate::sensor::SensorModel;

/// Mapper settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PqrmConfig {
    /// Samples per landmark per step (`s` of §2.3; the thesis uses 1000).
    pub samples: usize,
    /// Pseudo-counts per state added to every step's histogram (see [`crate::likelihood`]).
    pub floor: f64,
    /// Which orderings of each triplet are recorded.
    pub orderings: Orderings,
    /// Seed of the sampler.
    pub seed: u64,
    /// The inverse sensor model the detections are sampled from (maps saved before it
    /// existed are Gaussian).
    #[serde(default)]
    pub sensor: SensorModel,
    /// Tempering exponent τ ∈ (0, 1]: each step's log-likelihood is multiplied by τ, so n
    /// correlated frames count as τ·n independent ones (1 = the thesis's eq. 2.10).
    #[serde(default = "one")]
    pub temper: f64,
}

fn one() -> f64 {
    1.0
}

impl Default for PqrmConfig {
    fn default() -> Self {
        Self {
            samples: 1000,
            floor: 1.0,
            orderings: Orderings::All,
            seed: 0,
            sensor: SensorModel::Gaussian,
            temper: 1.0,
        }
    }
}

/// The most samples per landmark per step a mapper accepts: 16 MB of samples per landmark
/// in view, a thousand times the thesis's 1000. More is refused up front rather than left to
/// fail an allocation (or overflow a size) mid-run.
pub const MAX_SAMPLES: usize = 1_000_000;

/// Checks a samples-per-landmark count against `1..=MAX_SAMPLES`.
///
/// # Errors
/// [`PqrmError::InvalidConfig`] with the memory the count would take.
pub fn check_samples(samples: usize) -> Result<()> {
    if samples == 0 {
        return Err(PqrmError::InvalidConfig("samples must be >= 1".into()));
    }
    if samples > MAX_SAMPLES {
        let gib = samples as f64 * 16.0 / f64::from(1u32 << 30);
        return Err(PqrmError::InvalidConfig(format!(
            "samples = {samples} would take {gib:.3e} GiB per landmark in view (16 bytes a \
             sample); at most {MAX_SAMPLES} are accepted (the thesis uses 1000)"
        )));
    }
    Ok(())
}

impl PqrmConfig {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for samples outside `1..=MAX_SAMPLES` or a
    /// negative/non-finite floor.
    pub fn validate(&self) -> Result<()> {
        check_samples(self.samples)?;
        self.sensor.validate()?;
        if !(self.temper.is_finite() && self.temper > 0.0 && self.temper <= 1.0) {
            return Err(PqrmError::InvalidConfig(format!(
                "temper must be in (0, 1], got {}",
                self.temper
            )));
        }
        check_floor(self.floor)
    }
}

/// The largest floor (pseudo-counts per state): far above any sample count a map uses, and
/// small enough that `floor × states` stays finite (a floor of 1e308 made every likelihood
/// `inf / inf`, NaN).
pub const MAX_FLOOR: f64 = 1e6;

/// Checks a floor: finite, `0..=MAX_FLOOR`.
///
/// # Errors
/// [`PqrmError::InvalidConfig`] naming the field and its value.
pub fn check_floor(floor: f64) -> Result<()> {
    if floor.is_finite() && (0.0..=MAX_FLOOR).contains(&floor) {
        Ok(())
    } else {
        Err(PqrmError::InvalidConfig(format!(
            "floor = {floor:?}: must be finite, >= 0 and at most {MAX_FLOOR:e} pseudo-counts"
        )))
    }
}
