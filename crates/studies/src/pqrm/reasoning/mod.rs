//! Reasoning over maps (new; the thesis builds compose tables and calls compose-based
//! reasoning "one of the most useful capabilities of QSRs", §3.3.2, but measures none): on a
//! recording with surveyed landmarks, (a) sets hidden from the map and inferred from the rest
//! by composition, (b) in simulation, triplets never seen together inferred by chained
//! composition, (c) the map's most likely states checked by algebraic closure. The run is
//! `pqrm::reason_study`; this module makes it a study — one shard per calculus, the
//! recording read alike by every shard — and [`report`] judges it.

use std::path::PathBuf;

use pqrm::loaders::Dataset;
use pqrm::reason_study::{ReasonCalculusResult, ReasonStudyConfig, run_reason_study};
use qsr_core::progress::Progress;
use serde::{Deserialize, Serialize};

use crate::error::{Result, StudyError};
use crate::recording::{NoiseRequest, RecordingFormat};
use crate::report::Report;
use crate::study::Study;

pub mod report;

/// What the reasoning study runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReasonConfig {
    /// The recording; it needs surveyed landmarks (MRCLAM's own, or `truth`).
    pub input: PathBuf,
    /// Its form.
    pub format: RecordingFormat,
    /// Surveyed landmarks (CSV `landmark,x,y`) for a recording without them.
    #[serde(default)]
    pub truth: Option<PathBuf>,
    /// Use only the first N frames with three or more landmarks (`None`: all).
    #[serde(default)]
    pub max_frames: Option<usize>,
    /// The range-bearing noise (MRCLAM): fitted from the recording unless given, as `qrm
    /// map` reads it (issue 35: the study reasons over the maps users get).
    #[serde(default)]
    pub noise: NoiseRequest,
    /// Drop gross outliers frame by frame; `None`: where the noise is fitted, as `qrm map`
    /// does ([`crate::mapping::gate`]).
    #[serde(default)]
    pub gate: Option<bool>,
    /// The study's settings: calculi, hidings, inference, the simulated world of (b).
    pub study: ReasonStudyConfig,
}

impl ReasonConfig {
    fn with(study: ReasonStudyConfig, seed: u64) -> Self {
        let mut study = study;
        study.seed = seed;
        study.map.seed = seed;
        Self {
            input: PathBuf::from(crate::pqrm::real_data::RealDataConfig::DEFAULT_INPUT),
            format: RecordingFormat::Mrclam,
            truth: None,
            max_frames: None,
            noise: NoiseRequest::default(),
            gate: None,
            study,
        }
    }
}

/// What one calculus's shard produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReasonShard {
    /// Frames of the recording mapped (every shard reads the same).
    pub frames: usize,
    /// The calculus's results.
    pub result: ReasonCalculusResult,
}

/// What the study produced.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReasonOutput {
    /// Frames of the recording mapped.
    pub frames: usize,
    /// One result per calculus, in the config's order.
    pub results: Vec<ReasonCalculusResult>,
}

/// The reasoning study.
#[derive(Debug, Clone, Copy)]
pub struct ReasonStudy;

/// The recording as every shard maps it — read as `qrm map` reads it (the noise fitted
/// where it can be, gross outliers gated where it was), then frames of three landmarks or
/// more, the first `max_frames` of them, with surveyed truth.
///
/// # Errors
/// The loaders' (file, line, field); the noise fit's when asked for; [`StudyError::InvalidParameter`]
/// without truth or without a frame of three landmarks.
pub fn read_recording(config: &ReasonConfig) -> Result<Dataset> {
    // A fit that cannot be made (a short recording) keeps MRCLAM's noise, silently here:
    // every shard reads alike, and the report states the noise it ran with.
    let noise = config
        .noise
        .resolve(config.format, &config.input, &|_| ())?;
    let mut data = crate::recording::read(config.format, &config.input, noise.noise)?;
    crate::mapping::gate(&mut data, config.gate, noise.fit.as_ref())?;
    if let Some(t) = &config.truth {
        data.truth = Some(pqrm::loaders::read_truth_csv(t)?);
    }
    if data.truth.is_none() {
        return Err(StudyError::InvalidParameter(format!(
            "{} has no surveyed truth: give `truth` (a CSV `landmark,x,y`; --truth FILE)",
            config.input.display()
        )));
    }
    data.scans.retain(|s| s.observations.len() >= 3);
    if let Some(n) = config.max_frames {
        data.scans.truncate(n);
    }
    if data.scans.is_empty() {
        return Err(StudyError::InvalidParameter(format!(
            "{}: no frame sees three landmarks",
            config.input.display()
        )));
    }
    Ok(data)
}

/// The study's settings for shard `index`'s calculus alone.
fn one_calculus(config: &ReasonConfig, index: usize) -> Result<ReasonStudyConfig> {
    ReasonStudy::check(config)?;
    let calculus = config.study.calculi.get(index).ok_or_else(|| {
        StudyError::InvalidParameter(format!(
            "shard {index} of a study of {} calculi",
            config.study.calculi.len()
        ))
    })?;
    Ok(ReasonStudyConfig {
        calculi: vec![calculus.clone()],
        ..config.study.clone()
    })
}

impl Study for ReasonStudy {
    const NAME: &'static str = "reason";
    const ABOUT: &'static str = "new (§3.3.2 measures none): inference of hidden and never-seen triplets by composition, consistency checks, on MRCLAM";
    type Config = ReasonConfig;
    type Output = ReasonOutput;
    type Shard = ReasonShard;

    fn quick(seed: u64) -> ReasonConfig {
        ReasonConfig::with(ReasonStudyConfig::quick(), seed)
    }
    fn full(seed: u64) -> ReasonConfig {
        ReasonConfig::with(ReasonStudyConfig::default(), seed)
    }
    fn check(config: &ReasonConfig) -> Result<()> {
        config.study.validate()?;
        config.noise.validate()?;
        if config.max_frames == Some(0) {
            return Err(StudyError::InvalidParameter(
                "max_frames must be >= 1 (or left out: all frames)".into(),
            ));
        }
        Ok(())
    }
    /// One shard per calculus: its results depend on the recording and the seeds alone.
    fn shards(config: &ReasonConfig) -> Result<usize> {
        Self::check(config)?;
        Ok(config.study.calculi.len())
    }
    /// Each frame of the recording mapped, each hiding repeat, the check, each simulated
    /// world ([`ReasonStudyConfig::work_units`] of the one calculus).
    fn shard_units(config: &ReasonConfig, index: usize) -> Result<usize> {
        let one = one_calculus(config, index)?;
        let frames = read_recording(config)?.scans.len();
        Ok(usize::try_from(one.work_units(frames)).unwrap_or(usize::MAX))
    }
    fn run_shard(
        config: &ReasonConfig,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<ReasonShard> {
        let one = one_calculus(config, index)?;
        let calculus = one.calculi[0].clone();
        let data = read_recording(config)?;
        let mut results = run_reason_study(&data, &one, progress)?;
        let result = results.pop().ok_or_else(|| {
            StudyError::InvalidParameter(format!("no result for calculus `{calculus}`"))
        })?;
        Ok(ReasonShard {
            frames: data.scans.len(),
            result,
        })
    }
    fn aggregate(config: &ReasonConfig, shards: Vec<(usize, ReasonShard)>) -> Result<ReasonOutput> {
        let n = Self::shards(config)?;
        crate::shard::check_indices(n, shards.iter().map(|(i, _)| *i))?;
        let mut shards = shards;
        shards.sort_by_key(|(i, _)| *i);
        let frames = shards.first().map_or(0, |(_, s)| s.frames);
        let mut results = Vec::with_capacity(n);
        for (i, s) in shards {
            // a result names its calculus as the calculus names itself (a spec file's name)
            let named = &config.study.calculi[i];
            let same_calculus = *named == s.result.calculus
                || qsr_core::Calculus::resolve(named).is_ok_and(|c| c.name() == s.result.calculus);
            if s.frames != frames || !same_calculus {
                return Err(StudyError::InvalidParameter(format!(
                    "shard {i} mapped {} frames with `{}`, not this config's {frames} with `{named}`",
                    s.frames, s.result.calculus
                )));
            }
            results.push(s.result);
        }
        Ok(ReasonOutput { frames, results })
    }
    fn report(config: &ReasonConfig, output: &ReasonOutput) -> Report {
        report::report(config, output)
    }
}
