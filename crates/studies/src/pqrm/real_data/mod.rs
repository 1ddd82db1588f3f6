//! The real-data study: thesis §2.3.2 (the New College dataset, Figs 2.14–2.16) redone on a
//! recording whose landmarks are surveyed (UTIAS MRCLAM), so that a map can be scored
//! against a truth that does not come from the same measurements.
//!
//! Beyond the thesis, because a robot developer bringing a recording needs to know: is the
//! map better than voting frame by frame (the per-triplet majority vote), is it honest about
//! its certainty (a reliability diagram), which inverse sensor model and tempering suit the
//! sensor, how τ is chosen without ground truth, and what many robots gain by merging maps.
//!
//! **Shards.** Shard 0 is the main run: τ chosen from the recording, the six maps, the maps
//! at τ = 1 and at the chosen τ, and the robots alone, pooled and merged (they use the main
//! run's τ). Shard `1 + i` maps the recording under sensor variant `i`; after them, one shard
//! per recording in `also`, scored with the main settings ([`recordings`]). Each shard reads
//! the recording itself ([`recording::read`]), so the config's `input` must be readable where the
//! shard runs.

pub mod recording;
pub mod recordings;
mod report;
mod tempering;

use std::path::PathBuf;

use pqrm::loaders::{Dataset, RangeBearingNoise};
use pqrm::robots::{RobotComparison, compare_robots};
use pqrm::sensor::SensorModel;
use pqrm::study::{RealCalculusResult, SensorVariant, run_real_tempered, sensor_sweep};
use pqrm::temper::{TemperChoice, TemperFit, TemperOptions, fit_temper};
use pqrm::{EvidenceModel, PqrmConfig};
use qsr_core::Calculus;
use qsr_core::progress::{Progress, phase};
use serde::{Deserialize, Serialize};

use crate::error::{Result, StudyError};
use crate::report::Report;
use crate::study::Study;
use recording::{Recording, RecordingSummary};

/// Where the recording's range-bearing noise comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum NoiseSource {
    /// Fitted from the recording itself (the spread of distances between landmarks seen
    /// together; `pqrm::calibrate::fit_noise`, no ground truth).
    Fitted,
    /// `sigma_range` and `sigma_bearing` of the config.
    Given,
}

/// One (inverse sensor model, tempering) variant the report compares.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variant {
    /// The inverse sensor model.
    pub sensor: SensorModel,
    /// The tempering exponent τ ∈ (0, 1].
    pub temper: f64,
}

/// What the real-data study runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RealDataConfig {
    /// The MRCLAM recording's directory (landmarks surveyed in `Landmark_Groundtruth.dat`).
    pub input: PathBuf,
    /// Calculi, finest first (the coarser ones are read off the finest one's counts).
    pub calculi: Vec<String>,
    /// Samples per landmark per frame.
    pub samples: usize,
    /// Where the range-bearing noise comes from.
    pub noise: NoiseSource,
    /// Range noise (m): the noise with `noise = "given"`, the noise the recording is first
    /// read with to fit it otherwise.
    pub sigma_range: f64,
    /// Bearing noise (rad), as `sigma_range`.
    pub sigma_bearing: f64,
    /// Drop a detection whose distances to its frame's other landmarks are off those pairs'
    /// medians by more than this many σ of the fitted noise (`None`: keep every detection).
    #[serde(default)]
    pub gate_sigmas: Option<f64>,
    /// Map only the first N frames that see three or more landmarks (`None`: all).
    #[serde(default)]
    pub max_frames: Option<usize>,
    /// The main run's inverse sensor model.
    pub sensor: SensorModel,
    /// The main run's tempering: a number in (0, 1] (1 = the thesis's eq. 2.10) or `"auto"`,
    /// one τ per calculus chosen from the recording. The report compares τ = 1 with the
    /// chosen τ either way.
    pub temper: TemperChoice,
    /// The sensor models and temperings the report compares, one shard each (read as
    /// independent frames, eq. 2.10).
    pub variants: Vec<Variant>,
    /// How the main run's maps read a set's frames (`pqrm::evidence`): `"layout"` (the
    /// default: each recording's layout and the error its frames share beyond it,
    /// `pqrm::layout`), `"shared:N"` (the filter, N chosen by leaving one recording out) or
    /// `"independent"` (eq. 2.10).
    #[serde(default = "layout_evidence")]
    pub evidence: EvidenceModel,
    /// Other recordings scored with the main settings, one row per recording and calculus in
    /// `recordings.csv` (MRCLAM directories).
    #[serde(default)]
    pub also: Vec<PathBuf>,
    /// Seed of the sampler.
    pub seed: u64,
}

impl RealDataConfig {
    /// Where the study looks for the recording unless told: the repository's copy.
    pub const DEFAULT_INPUT: &'static str = "../shared/data/mrclam-dataset7";
    /// The gate of the full study: 3σ.
    pub const GATE_SIGMAS: f64 = 3.0;

    /// The thesis's scale: every frame, 1,000 samples per landmark.
    #[must_use]
    pub fn full(seed: u64) -> Self {
        Self {
            input: PathBuf::from(Self::DEFAULT_INPUT),
            calculi: qsr_core::POINT_CALCULI
                .iter()
                .map(|s| (*s).to_owned())
                .collect(),
            samples: 1000,
            noise: NoiseSource::Fitted,
            sigma_range: RangeBearingNoise::MRCLAM.sigma_range,
            sigma_bearing: RangeBearingNoise::MRCLAM.sigma_bearing,
            gate_sigmas: Some(Self::GATE_SIGMAS),
            max_frames: None,
            sensor: SensorModel::Gaussian,
            temper: TemperChoice::Fixed(1.0),
            variants: standard_variants(),
            evidence: EvidenceModel::Layout,
            also: Vec::new(),
            seed,
        }
    }

    /// A first look in a second: the first 120 frames, 80 samples.
    #[must_use]
    pub fn quick(seed: u64) -> Self {
        Self {
            samples: 80,
            max_frames: Some(120),
            ..Self::full(seed)
        }
    }

    /// Takes a user's noise request (`--noise`, `--sigma-range`, `--sigma-bearing`): `auto`
    /// fits, `fixed` uses the given σs (MRCLAM's where one is missing); without a mode a given
    /// σ means fixed and none means fitted.
    ///
    /// # Errors
    /// [`StudyError::InvalidParameter`] for `auto` beside given σs.
    pub fn request_noise(&mut self, request: &crate::recording::NoiseRequest) -> Result<()> {
        use crate::recording::NoiseMode;
        let given = request.sigma_range.is_some() || request.sigma_bearing.is_some();
        self.noise = match request.mode {
            Some(NoiseMode::Auto) if given => {
                return Err(StudyError::InvalidParameter(
                    "--noise auto fits σ_r and σ_b; drop --sigma-range/--sigma-bearing or say \
                     --noise fixed"
                        .into(),
                ));
            }
            Some(NoiseMode::Fixed) => NoiseSource::Given,
            None if given => NoiseSource::Given,
            Some(NoiseMode::Auto) | None => NoiseSource::Fitted,
        };
        if let Some(s) = request.sigma_range {
            self.sigma_range = s;
        }
        if let Some(s) = request.sigma_bearing {
            self.sigma_bearing = s;
        }
        Ok(())
    }

    /// The mapper's settings of the main run (τ set per calculus later).
    pub(crate) fn pqrm_config(&self) -> PqrmConfig {
        PqrmConfig {
            samples: self.samples,
            seed: self.seed,
            sensor: self.sensor,
            ..PqrmConfig::default()
        }
    }
}

/// The variants every report compares ([`pqrm::study::standard_variants`]).
#[must_use]
pub fn standard_variants() -> Vec<Variant> {
    pqrm::study::standard_variants()
        .into_iter()
        .map(|(sensor, temper)| Variant { sensor, temper })
        .collect()
}

/// τ chosen from the recording beside the maps at τ = 1 and at the chosen τ.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Tempering {
    /// Per calculus: the held-out log score of every τ tried, and the one chosen.
    pub fits: Vec<TemperFit>,
    /// The maps at the chosen τ.
    pub chosen: Vec<RealCalculusResult>,
    /// The maps at τ = 1.
    pub untempered: Vec<RealCalculusResult>,
}

/// What shard 0 produces: everything but the sensor variants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MainRun {
    /// The recording as mapped.
    pub recording: RecordingSummary,
    /// The main run, one result per calculus.
    pub results: Vec<RealCalculusResult>,
    /// τ chosen from the data and its effect (`None`: it could not be chosen).
    pub tempering: Option<Tempering>,
    /// Why τ could not be chosen (with `tempering` `None` and a fixed τ).
    pub tempering_failed: Option<String>,
    /// Each robot alone, pooled, merged (empty for a one-robot recording).
    pub robots: Vec<RobotComparison>,
}

/// One shard's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "part")]
pub enum RealDataShard {
    /// Shard 0.
    Main(Box<MainRun>),
    /// Shard `1 + i`: variant `i`, one row per calculus.
    Variant {
        /// The rows.
        rows: Vec<SensorVariant>,
    },
    /// Shard `1 + variants + j`: recording `also[j]`, one row per calculus.
    Recording {
        /// The rows.
        rows: Vec<recordings::RecordingRow>,
    },
}

/// A run: the main run and the sensor variants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RealDataOutput {
    /// Shard 0.
    #[serde(flatten)]
    pub main: MainRun,
    /// Every variant's rows, in the config's order.
    pub sensor_models: Vec<SensorVariant>,
    /// Each recording of `also`, in order: one row per calculus.
    #[serde(default)]
    pub recordings: Vec<Vec<recordings::RecordingRow>>,
}

/// The study of thesis §2.3.2 on a surveyed recording.
#[derive(Debug, Clone, Copy, Default)]
pub struct RealData;

fn check_index(c: &RealDataConfig, index: usize) -> Result<()> {
    let n = RealData::shards(c)?;
    if index >= n {
        return Err(StudyError::InvalidParameter(format!(
            "shard {index} of a study with {n} shards"
        )));
    }
    Ok(())
}

impl Study for RealData {
    const NAME: &'static str = "real-data";
    const ABOUT: &'static str =
        "§2.3.2: PQRM on a real recording with surveyed landmarks (MRCLAM; Figs 2.14-2.16)";
    type Config = RealDataConfig;
    type Output = RealDataOutput;
    type Shard = RealDataShard;

    fn quick(seed: u64) -> RealDataConfig {
        RealDataConfig::quick(seed)
    }
    fn full(seed: u64) -> RealDataConfig {
        RealDataConfig::full(seed)
    }
    fn check(c: &RealDataConfig) -> Result<()> {
        let bad = |what: String| Err(StudyError::InvalidParameter(what));
        if c.calculi.is_empty() {
            return bad("calculi: none given".into());
        }
        for name in &c.calculi {
            Calculus::resolve(name)?;
        }
        RangeBearingNoise {
            sigma_range: c.sigma_range,
            sigma_bearing: c.sigma_bearing,
        }
        .validate()?;
        if let Some(z) = c.gate_sigmas
            && !(z.is_finite() && z > 0.0)
        {
            return bad(format!("gate_sigmas = {z}: must be a positive number of σ"));
        }
        if c.max_frames == Some(0) {
            return bad("max_frames = 0: no frame to map".into());
        }
        c.pqrm_config().validate()?;
        c.evidence.validate()?;
        for (i, v) in c.variants.iter().enumerate() {
            PqrmConfig {
                sensor: v.sensor,
                temper: v.temper,
                ..c.pqrm_config()
            }
            .validate()
            .map_err(|e| StudyError::InvalidParameter(format!("variants[{i}]: {e}")))?;
        }
        Ok(())
    }
    /// The main run, one shard per sensor variant, one per other recording.
    fn shards(c: &RealDataConfig) -> Result<usize> {
        Ok(1 + c.variants.len() + c.also.len())
    }
    /// The main run's phases (fitting τ, the maps, the robots, τ = 1 and the chosen τ); a
    /// variant maps every frame once.
    fn shard_units(c: &RealDataConfig, index: usize) -> Result<usize> {
        check_index(c, index)?;
        if let Some(input) = index.checked_sub(1 + c.variants.len()).map(|j| &c.also[j]) {
            let other = recording::read(&RealDataConfig {
                input: input.clone(),
                ..c.clone()
            })?;
            return Ok(recordings::units(c, other.data.scans.len()));
        }
        let recording = recording::read(c)?;
        Ok(if index == 0 {
            main_units(c, &recording.data).iter().sum()
        } else {
            recording.data.scans.len()
        })
    }
    fn run_shard(
        c: &RealDataConfig,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<RealDataShard> {
        check_index(c, index)?;
        if let Some(input) = index.checked_sub(1 + c.variants.len()).map(|j| &c.also[j]) {
            let rows = recordings::score_recording(c, input, progress)?;
            return Ok(RealDataShard::Recording { rows });
        }
        let recording = recording::read(c)?;
        if index == 0 {
            return Ok(RealDataShard::Main(Box::new(main_run(
                c, recording, progress,
            )?)));
        }
        let v = c.variants[index - 1];
        let rows = phase(progress, recording.data.scans.len(), |p| {
            sensor_sweep(
                &recording.data,
                &c.calculi,
                c.pqrm_config(),
                &[(v.sensor, v.temper)],
                p,
            )
        })?;
        Ok(RealDataShard::Variant { rows })
    }
    fn aggregate(
        c: &RealDataConfig,
        shards: Vec<(usize, RealDataShard)>,
    ) -> Result<RealDataOutput> {
        let n = Self::shards(c)?;
        crate::shard::check_indices(n, shards.iter().map(|s| s.0))?;
        let mut shards = shards;
        shards.sort_by_key(|s| s.0);
        let mut main = None;
        let mut sensor_models = Vec::new();
        let mut others = Vec::new();
        let first_recording = 1 + c.variants.len();
        for (i, s) in shards {
            match (i, s) {
                (0, RealDataShard::Main(m)) => main = Some(*m),
                (i, RealDataShard::Variant { rows }) if i > 0 && i < first_recording => {
                    sensor_models.extend(rows);
                }
                (i, RealDataShard::Recording { rows }) if i >= first_recording => {
                    others.push(rows);
                }
                (i, _) => {
                    return Err(StudyError::InvalidParameter(format!(
                        "shard {i} holds another part (shard 0 is the main run, then the variants, then the other recordings)"
                    )));
                }
            }
        }
        let main = main.ok_or_else(|| StudyError::InvalidParameter("no main run".into()))?;
        Ok(RealDataOutput {
            main,
            sensor_models,
            recordings: others,
        })
    }
    fn report(c: &RealDataConfig, output: &RealDataOutput) -> Report {
        report::report(c, output)
    }
}

fn layout_evidence() -> EvidenceModel {
    EvidenceModel::Layout
}

/// Units of the main run's phases over `data`: fitting τ (two passes), the main maps, the
/// robots compared (when there are two or more), τ = 1 and the chosen τ.
fn main_units(c: &RealDataConfig, data: &Dataset) -> [usize; 4] {
    let frames = data.scans.len();
    let robots = data
        .scans
        .iter()
        .map(|s| s.robot)
        .collect::<std::collections::BTreeSet<_>>()
        .len();
    let compared = if robots >= 2 {
        2 * frames * c.calculi.len()
    } else {
        0
    };
    [2 * frames, frames, compared, 2 * frames]
}

/// Shard 0: τ from the data, the main maps, τ = 1 beside the chosen τ, the robots.
fn main_run(c: &RealDataConfig, rec: Recording, progress: &dyn Progress) -> Result<MainRun> {
    let data = &rec.data;
    let [fit_units, main_units, robot_units, temper_units] = main_units(c, data);
    let config = c.pqrm_config();
    let calcs = c
        .calculi
        .iter()
        .map(|n| Calculus::resolve(n))
        .collect::<std::result::Result<Vec<_>, _>>()?;
    // τ chosen from the data is always measured (the report compares it with τ = 1); the
    // main run uses it only with `temper = "auto"`.
    let layout = c.evidence == pqrm::EvidenceModel::Layout;
    if layout && c.temper != TemperChoice::Fixed(1.0) {
        return Err(StudyError::InvalidParameter(
            "temper: a layout map (evidence = \"layout\") has no frames to temper; leave τ at 1"
                .into(),
        ));
    }
    let fitted_or_not = phase(progress, fit_units, |p| {
        if layout {
            // τ tempers the filter's frames; a layout map has none (reported as not fitted)
            return Err(pqrm::PqrmError::InvalidConfig(
                "the layout model reads no frame's evidence to temper".into(),
            ));
        }
        // fitted under the model the main run reads its maps with (the τ is on top of it)
        fit_temper(
            &calcs,
            &data.scans,
            config,
            &TemperOptions::default().evidence(c.evidence),
            p,
        )
    });
    let (fits, tempering_failed) = match fitted_or_not {
        Ok(f) => (Some(f), None),
        Err(e) if c.temper == TemperChoice::Auto || matches!(e, pqrm::PqrmError::Cancelled(_)) => {
            return Err(e.into());
        }
        Err(e) => (None, Some(e.to_string())),
    };
    let fitted: Option<Vec<f64>> = fits.as_ref().map(|f| f.iter().map(|f| f.chosen).collect());
    let tempers = match (c.temper, &fitted) {
        (TemperChoice::Fixed(t), _) => vec![t; c.calculi.len()],
        (TemperChoice::Auto, Some(f)) => f.clone(),
        (TemperChoice::Auto, None) => {
            return Err(StudyError::InvalidParameter("no τ was chosen".into()));
        }
    };
    let results = phase(progress, main_units, |p| {
        run_real_tempered(data, &c.calculi, config, &tempers, c.evidence, p)
    })?;
    let robots = phase(progress, robot_units, |p| {
        // the comparison merges robots' maps, which only the filter's can be: under the
        // layout model it compares the filter's, read under the shared-error model
        let evidence = if layout {
            pqrm::EvidenceModel::shared_default()
        } else {
            c.evidence
        };
        if robot_units > 0 {
            compare_robots(data, &calcs, (config, evidence), &tempers, p)
        } else {
            Ok(Vec::new())
        }
    })?;
    let tempering = phase(progress, temper_units, |p| -> Result<Option<Tempering>> {
        let (Some(fits), Some(fitted)) = (fits, fitted) else {
            return Ok(None);
        };
        let at = |ts: &[f64]| -> Result<Vec<RealCalculusResult>> {
            if ts == tempers.as_slice() {
                Ok(results.clone())
            } else {
                Ok(run_real_tempered(
                    data, &c.calculi, config, ts, c.evidence, p,
                )?)
            }
        };
        let untempered = at(&vec![1.0; c.calculi.len()])?;
        let chosen = at(&fitted)?;
        Ok(Some(Tempering {
            fits,
            chosen,
            untempered,
        }))
    })?;
    Ok(MainRun {
        recording: rec.summary,
        results,
        tempering,
        tempering_failed,
        robots,
    })
}

#[cfg(test)]
mod tests {
    use super::{NoiseSource, RealDataConfig};
    use crate::recording::{NoiseMode, NoiseRequest};

    fn asked(mode: Option<NoiseMode>, sigma_range: Option<f64>) -> Option<RealDataConfig> {
        let mut config = RealDataConfig::quick(0);
        let request = NoiseRequest {
            mode,
            sigma_range,
            sigma_bearing: None,
        };
        config.request_noise(&request).ok().map(|()| config)
    }

    #[test]
    fn a_given_sigma_means_fixed_noise_and_auto_beside_it_is_refused() {
        let fitted = asked(None, None).unwrap();
        assert_eq!(fitted.noise, NoiseSource::Fitted);
        let given = asked(None, Some(0.3)).unwrap();
        assert_eq!((given.noise, given.sigma_range), (NoiseSource::Given, 0.3));
        let default_bearing = RealDataConfig::quick(0).sigma_bearing;
        assert_eq!(given.sigma_bearing, default_bearing);
        let fixed = asked(Some(NoiseMode::Fixed), None).unwrap();
        assert_eq!(fixed.noise, NoiseSource::Given);
        assert_eq!(
            asked(Some(NoiseMode::Auto), None).unwrap().noise,
            NoiseSource::Fitted
        );
        assert!(asked(Some(NoiseMode::Auto), Some(0.3)).is_none());
    }
}
