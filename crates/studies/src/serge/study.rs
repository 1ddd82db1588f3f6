//! The SERGE study of thesis §3.4 as a [`Study`]: per dataset, one shard per fold of the
//! cross-validation and one for the example maps and the dataset's use case.

use qsr_core::cost::{Budget, Cost};
use qsr_core::progress::Progress;
use serde::{Deserialize, Serialize};

use super::cross_validation::{CvRecord, StudyConfig, cross_validate_fold, summarise};
use super::datasets::{Dataset, DatasetName};
use super::examples::{DatasetExamples, examples};
pub use super::output::{DatasetResult, SergeOutput};
use crate::error::{Result, StudyError};
use crate::report::Report;
use crate::shard::check_indices;
use crate::study::Study;

/// The SERGE study: cross-validation over μ and σ (Fig 3.7), example maps (Fig 3.8), the
/// resolution tree (Fig 3.9) and a learned calculus (Fig 3.10).
#[derive(Debug, Clone, Copy, Default)]
pub struct SergeStudy;

/// What one shard did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "part")]
pub enum SergePart {
    /// One fold's SERGE runs.
    Fold {
        /// The fold.
        fold: usize,
        /// Its runs.
        records: Vec<CvRecord>,
    },
    /// The example maps and the use case.
    Examples {
        /// What they produced.
        examples: Box<DatasetExamples>,
    },
}

/// A shard: one part of one dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SergeShard {
    /// The dataset.
    pub dataset: DatasetName,
    /// Its beliefs K.
    pub k: usize,
    /// The part.
    pub part: SergePart,
}

/// Dataset `name` as the study uses it.
///
/// # Errors
/// As [`Dataset::generate_named`].
pub fn dataset(name: DatasetName, config: &StudyConfig) -> Result<Dataset> {
    let data = Dataset::generate_named(name, config.seed)?;
    Ok(if data.observations.is_some() {
        data.with_samples(config.samples)
    } else {
        data
    })
}

/// The most folds of the cross-validation.
pub const MAX_FOLDS: usize = 100;
/// The most grid cells per side.
pub const MAX_GRID: usize = 2_000;
/// The most trials per belief.
pub const MAX_TRIALS_PER_BELIEF: usize = 1_000;
/// The largest μ (states of a learned calculus).
pub const MAX_MU: usize = 10_000;
/// CPU seconds per unit of the work estimate in `check`, measured: `qrm study run serge-cv
/// --quick` (4.0 × 10⁶ units: 3 datasets × 6 × 8 searches × 5 × (2,000 + 60²)) took 2.7 s of
/// CPU.
pub const SECONDS_PER_UNIT: f64 = 6.7e-7;

fn check(config: &StudyConfig) -> Result<()> {
    if config.datasets.is_empty() {
        return Err(StudyError::InvalidParameter(
            "datasets: at least one".into(),
        ));
    }
    let mut seen = config.datasets.clone();
    seen.sort_unstable();
    seen.dedup();
    if seen.len() != config.datasets.len() {
        return Err(StudyError::InvalidParameter(format!(
            "datasets: each at most once ({:?})",
            config.datasets
        )));
    }
    if config.folds < 2 || config.grid < 2 || config.trials_per_belief == 0 || config.samples == 0 {
        return Err(StudyError::InvalidParameter(
            "folds and grid must be at least 2, trials_per_belief and samples at least 1".into(),
        ));
    }
    // Sizes bounded one by one (a grid of 10¹² cells per side is no grid), then their work
    // together (issue 39: folds, grid, samples and trials_per_belief of 10¹² were accepted).
    for (field, v, max) in [
        ("folds", config.folds, MAX_FOLDS),
        ("grid", config.grid, MAX_GRID),
        ("samples", config.samples, pqrm::config::MAX_SAMPLES),
        (
            "trials_per_belief",
            config.trials_per_belief,
            MAX_TRIALS_PER_BELIEF,
        ),
        ("mu_for_sigma", config.mu_for_sigma, MAX_MU),
    ]
    .into_iter()
    .chain(config.mus.iter().flatten().map(|&m| ("mus", m, MAX_MU)))
    {
        if v > max {
            return Err(StudyError::InvalidParameter(format!(
                "{field} = {v}: at most {max}"
            )));
        }
    }
    let searches = config.mus.as_ref().map_or(5, Vec::len) + config.sigmas.len();
    let work = config.datasets.len() as f64
        * (config.folds + 1) as f64
        * searches as f64
        * config.trials_per_belief as f64
        * (config.samples as f64 + (config.grid as f64).powi(2));
    Cost::work(work, SECONDS_PER_UNIT)
        .check(
            &Budget::RUN,
            format!(
                "datasets × (folds + 1) × searches × trials_per_belief × (samples + grid²) = \
                 {} × {} × {searches} × {} × ({} + {}²) = {work:.2e} units",
                config.datasets.len(),
                config.folds + 1,
                config.trials_per_belief,
                config.samples,
                config.grid
            ),
        )
        .map_err(|e| {
            StudyError::InvalidParameter(
                e.hint("fewer folds, trials, samples or a coarser grid")
                    .to_string(),
            )
        })?;
    let sigma_ok = |s: &f64| s.is_finite() && *s >= 0.0;
    if !sigma_ok(&config.sigma_for_mu) {
        return Err(StudyError::InvalidParameter(format!(
            "sigma_for_mu = {}: σ must be finite and ≥ 0",
            config.sigma_for_mu
        )));
    }
    if config.sigmas.is_empty() || !config.sigmas.iter().all(sigma_ok) {
        return Err(StudyError::InvalidParameter(format!(
            "sigmas = {:?}: at least one σ, each finite and ≥ 0",
            config.sigmas
        )));
    }
    // μ = 0 is no resolution (issue 39: `mus = [0]` ran and reported μ = 1).
    if config.mu_for_sigma == 0 {
        return Err(StudyError::InvalidParameter(
            "mu_for_sigma = 0: μ must be at least 1".into(),
        ));
    }
    if let Some(mus) = &config.mus
        && (mus.is_empty() || mus.contains(&0))
    {
        return Err(StudyError::InvalidParameter(format!(
            "mus = {mus:?}: at least one μ, each at least 1"
        )));
    }
    Ok(())
}

/// (dataset, part) of shard `index`: parts `0..folds` are folds, part `folds` the examples.
fn locate(config: &StudyConfig, index: usize) -> Result<(DatasetName, usize)> {
    let per = config.folds + 1;
    config
        .datasets
        .get(index / per)
        .map(|&d| (d, index % per))
        .ok_or_else(|| {
            StudyError::InvalidParameter(format!(
                "shard {index} of a study of {} shards",
                per * config.datasets.len()
            ))
        })
}

/// Runs shard `index`.
///
/// # Errors
/// As [`cross_validate_fold`] and [`examples`]; an index beyond the shards.
pub fn run_shard(
    config: &StudyConfig,
    index: usize,
    progress: &dyn Progress,
) -> Result<SergeShard> {
    check(config)?;
    let (name, part) = locate(config, index)?;
    let data = dataset(name, config)?;
    let part = if part < config.folds {
        SergePart::Fold {
            fold: part,
            records: cross_validate_fold(&data, config, part, progress)?,
        }
    } else {
        progress.add_total(1);
        progress.check()?;
        let examples = examples(&data, name, config)?;
        progress.tick();
        SergePart::Examples {
            examples: Box::new(examples),
        }
    };
    Ok(SergeShard {
        dataset: name,
        k: data.len(),
        part,
    })
}

/// Merges shards given in any order (each exactly once).
///
/// # Errors
/// [`StudyError::InvalidParameter`] for a missing, duplicated or foreign shard.
pub fn aggregate(config: &StudyConfig, shards: Vec<(usize, SergeShard)>) -> Result<SergeOutput> {
    let per = config.folds + 1;
    check_indices(per * config.datasets.len(), shards.iter().map(|(i, _)| *i))?;
    let mut shards = shards;
    shards.sort_by_key(|(i, _)| *i);
    let mut datasets = Vec::new();
    for (d, chunk) in shards.chunks(per).enumerate() {
        let name = config.datasets[d];
        let mut records = Vec::new();
        let mut found = None;
        let mut k = 0;
        for (i, shard) in chunk {
            let part = i % per;
            let fits = shard.dataset == name
                && match &shard.part {
                    SergePart::Fold { fold, .. } => *fold == part,
                    SergePart::Examples { .. } => part == config.folds,
                };
            if !fits {
                return Err(StudyError::InvalidParameter(format!(
                    "shard {i} is not part {part} of dataset `{}`",
                    name.as_str()
                )));
            }
            k = shard.k;
            match &shard.part {
                SergePart::Fold { records: r, .. } => records.extend(r.iter().cloned()),
                SergePart::Examples { examples } => found = Some((**examples).clone()),
            }
        }
        let examples = found.ok_or_else(|| {
            StudyError::InvalidParameter(format!("no examples of `{}`", name.as_str()))
        })?;
        datasets.push(DatasetResult {
            dataset: name,
            k,
            summary: summarise(&records),
            records,
            examples,
        });
    }
    Ok(SergeOutput { datasets })
}

impl Study for SergeStudy {
    const NAME: &'static str = "serge-cv";
    const ABOUT: &'static str = "§3.4: SERGE cross-validation over μ and σ, example maps, resolution tree, learned calculus (Figs 3.7-3.10)";
    type Config = StudyConfig;
    type Output = SergeOutput;
    type Shard = SergeShard;

    fn quick(seed: u64) -> StudyConfig {
        StudyConfig::quick(seed)
    }
    fn full(seed: u64) -> StudyConfig {
        StudyConfig::full(seed)
    }
    fn check(config: &StudyConfig) -> Result<()> {
        check(config)
    }
    /// Per dataset: one shard per fold, and one for the example maps and the use case.
    fn shards(config: &StudyConfig) -> Result<usize> {
        check(config)?;
        Ok((config.folds + 1) * config.datasets.len())
    }
    /// A fold's SERGE runs (one per μ and σ searched); the example maps are one unit.
    fn shard_units(config: &StudyConfig, index: usize) -> Result<usize> {
        check(config)?;
        let (name, part) = locate(config, index)?;
        if part < config.folds {
            let k = dataset(name, config)?.len();
            Ok(config.mus_for(k).len() + config.sigmas.len())
        } else {
            Ok(1)
        }
    }
    fn run_shard(
        config: &StudyConfig,
        index: usize,
        progress: &dyn Progress,
    ) -> Result<SergeShard> {
        run_shard(config, index, progress)
    }
    fn aggregate(config: &StudyConfig, shards: Vec<(usize, SergeShard)>) -> Result<SergeOutput> {
        aggregate(config, shards)
    }
    fn report(config: &StudyConfig, output: &SergeOutput) -> Report {
        super::report::report(config, output)
    }
}
