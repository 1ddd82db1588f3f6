//! The 5-fold cross-validation study of thesis §3.4.2 (Fig 3.7).
//!
//! For each fold, beliefs are formed from the other four folds' data points (training) and
//! from the fold's own points (test), on one grid around the training beliefs. SERGE runs on
//! the training beliefs for every setting — μ = 1…K at σ = 2, and σ = 2…16 at μ = 20 — and
//! each map is scored on the test fold: the test-data log likelihood `log ψ3(B_test, L^B,
//! R)` and the error rate (test points outside their belief's region), as §3.4.1 defines.

use qsr_core::progress::Progress;
use rand::SeedableRng;
use rand::seq::SliceRandom;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use serge::{CellMasses, Grid, Serge, SergeParams};

use super::datasets::{Dataset, DatasetName};
use crate::error::{Result, StudyError};

/// What the study runs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyConfig {
    /// The datasets, in the report's order (default: all three).
    #[serde(default = "all_datasets")]
    pub datasets: Vec<DatasetName>,
    /// Grid cells per side.
    pub grid: usize,
    /// Folds.
    pub folds: usize,
    /// μ values of the μ sweep (`None` = 1…K).
    pub mus: Option<Vec<usize>>,
    /// σ of the μ sweep.
    pub sigma_for_mu: f64,
    /// σ values of the σ sweep.
    pub sigmas: Vec<f64>,
    /// μ of the σ sweep (capped at K).
    pub mu_for_sigma: usize,
    /// Trials per belief (T = this × K; the thesis suggests > 100).
    pub trials_per_belief: usize,
    /// Samples per triplet belief (hallway).
    pub samples: usize,
    /// Seed.
    pub seed: u64,
}

fn all_datasets() -> Vec<DatasetName> {
    DatasetName::ALL.to_vec()
}

impl StudyConfig {
    /// The thesis's study: 200 × 200 cells, 5 folds, μ = 1…K, σ = 2, 4, …, 16, T = 100·K,
    /// 10,000 samples per triplet belief.
    #[must_use]
    pub fn full(seed: u64) -> Self {
        Self {
            datasets: all_datasets(),
            grid: 200,
            folds: 5,
            mus: None,
            sigma_for_mu: 2.0,
            sigmas: (1..=8).map(|i| 2.0 * f64::from(i)).collect(),
            mu_for_sigma: 20,
            trials_per_belief: 100,
            samples: 10_000,
            seed,
        }
    }

    /// A quick version for tests: 60 × 60 cells, 5 folds, five μ, three σ, T = 5·K, 2,000
    /// samples.
    #[must_use]
    pub fn quick(seed: u64) -> Self {
        Self {
            grid: 60,
            mus: Some(vec![1, 5, 10, 20, 40]),
            sigmas: vec![2.0, 8.0, 16.0],
            trials_per_belief: 5,
            samples: 2_000,
            ..Self::full(seed)
        }
    }

    /// The μ values for `k` beliefs.
    #[must_use]
    pub fn mus_for(&self, k: usize) -> Vec<usize> {
        match &self.mus {
            None => (1..=k).collect(),
            Some(v) => {
                let mut v: Vec<usize> = v.iter().map(|&m| m.clamp(1, k)).collect();
                v.dedup();
                v
            }
        }
    }

    /// Number of SERGE runs for `k` beliefs.
    #[must_use]
    pub fn n_runs(&self, k: usize) -> usize {
        self.folds * (self.mus_for(k).len() + self.sigmas.len())
    }
}

/// One SERGE run of the study, scored on its test fold.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvRecord {
    /// `"mu"` or `"sigma"`: which sweep.
    pub sweep: String,
    /// μ.
    pub mu: usize,
    /// σ.
    pub sigma: f64,
    /// Fold (0-based).
    pub fold: usize,
    /// |R|.
    pub n_regions: usize,
    /// Training log saliency (log ψ3).
    pub train_log_saliency: f64,
    /// Test-data log likelihood.
    pub test_log_likelihood: f64,
    /// Test points outside their belief's region.
    pub errors: usize,
    /// Test points.
    pub points: usize,
}

impl CvRecord {
    /// errors / points.
    #[must_use]
    pub fn error_rate(&self) -> f64 {
        self.errors as f64 / self.points.max(1) as f64
    }
}

/// Mean and standard deviation over folds of one setting.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvSummary {
    /// Sweep.
    pub sweep: String,
    /// μ.
    pub mu: usize,
    /// σ.
    pub sigma: f64,
    /// Mean |R| and its sd.
    pub n_regions: (f64, f64),
    /// Mean test log likelihood and its sd.
    pub log_likelihood: (f64, f64),
    /// Mean error rate and its sd.
    pub error_rate: (f64, f64),
}

fn mean_sd(v: &[f64]) -> (f64, f64) {
    let s = qsr_core::stats::MeanSd::of(v);
    (s.mean, s.sd)
}

/// Fold of each data point: a seeded shuffle per belief, dealt round-robin.
fn folds_of(dataset: &Dataset, folds: usize, seed: u64) -> Vec<Vec<usize>> {
    dataset
        .points
        .iter()
        .enumerate()
        .map(|(k, pts)| {
            let mut idx: Vec<usize> = (0..pts.len()).collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ (k as u64).wrapping_mul(0x2545_f491));
            idx.shuffle(&mut rng);
            let mut fold = vec![0; pts.len()];
            for (pos, &i) in idx.iter().enumerate() {
                fold[i] = pos % folds;
            }
            fold
        })
        .collect()
}

/// Checks that `dataset` can be cross-validated with `config`.
///
/// # Errors
/// [`StudyError::InvalidParameter`] for fewer than 2 folds or a belief with fewer points
/// than folds.
pub fn check(dataset: &Dataset, config: &StudyConfig) -> Result<()> {
    if config.folds < 2 {
        return Err(StudyError::InvalidParameter("at least 2 folds".into()));
    }
    if let Some(k) = dataset.points.iter().position(|p| p.len() < config.folds) {
        return Err(StudyError::InvalidParameter(format!(
            "belief {k} has {} data points, fewer than {} folds",
            dataset.points[k].len(),
            config.folds
        )));
    }
    Ok(())
}

/// Runs the cross-validation study; `progress` ticks after every SERGE run and is checked
/// before each (a cancelled study returns [`StudyError::Cancelled`]).
///
/// # Errors
/// As [`check`] and [`cross_validate_fold`].
pub fn cross_validate(
    dataset: &Dataset,
    config: &StudyConfig,
    progress: &dyn Progress,
) -> Result<Vec<CvRecord>> {
    check(dataset, config)?;
    let mut records = Vec::new();
    for fold in 0..config.folds {
        records.extend(cross_validate_fold(dataset, config, fold, progress)?);
    }
    Ok(records)
}

/// The SERGE runs of one fold: every setting trained on the other folds and scored on this
/// one. Depends on the dataset, the config and `fold` alone (a shard of the study).
///
/// # Errors
/// As [`check`]; [`StudyError::InvalidParameter`] for a fold beyond the config's; SERGE's
/// errors; [`StudyError::Cancelled`].
pub fn cross_validate_fold(
    dataset: &Dataset,
    config: &StudyConfig,
    fold: usize,
    progress: &dyn Progress,
) -> Result<Vec<CvRecord>> {
    check(dataset, config)?;
    if fold >= config.folds {
        return Err(StudyError::InvalidParameter(format!(
            "fold {fold} of {} folds",
            config.folds
        )));
    }
    let k = dataset.len();
    let fold_of = folds_of(dataset, config.folds, config.seed);
    let mut records = Vec::new();
    let fseed = config.seed ^ (fold as u64 + 1).wrapping_mul(0x9e37);
    let train = dataset.beliefs(|k, i| fold_of[k][i] != fold, fseed)?;
    let test = dataset.beliefs(|k, i| fold_of[k][i] == fold, fseed ^ 0x7e57)?;
    let test_points: Vec<Vec<[f64; 2]>> = dataset
        .points
        .iter()
        .enumerate()
        .map(|(k, pts)| {
            pts.iter()
                .enumerate()
                .filter(|&(i, _)| fold_of[k][i] == fold)
                .map(|(_, p)| *p)
                .collect()
        })
        .collect();
    let grid = Grid::around(&train, config.grid, config.grid)?;
    let train_m = CellMasses::compute(&train, grid)?;
    let test_m = CellMasses::compute(&test, grid)?;
    let serge = Serge::new(&train_m)?;
    let settings: Vec<(&str, usize, f64)> = config
        .mus_for(k)
        .into_iter()
        .map(|mu| ("mu", mu, config.sigma_for_mu))
        .chain(
            config
                .sigmas
                .iter()
                .map(|&s| ("sigma", config.mu_for_sigma.min(k), s)),
        )
        .collect();
    progress.add_total(settings.len());
    for (sweep, mu, sigma) in settings {
        progress.check()?;
        let params = SergeParams::new(mu, sigma)
            .trials(config.trials_per_belief * k)
            .seed(fseed);
        let map = serge.run(&params)?;
        let (errors, points) = map.errors(&test_points)?;
        records.push(CvRecord {
            sweep: sweep.into(),
            mu,
            sigma,
            fold,
            n_regions: map.n_regions,
            train_log_saliency: map.log_saliency,
            test_log_likelihood: map.log_likelihood(&test_m)?,
            errors,
            points,
        });
        progress.tick();
    }
    Ok(records)
}

/// Mean ± sd over folds per setting, in sweep order.
#[must_use]
pub fn summarise(records: &[CvRecord]) -> Vec<CvSummary> {
    let mut keys: Vec<(String, usize, u64)> = Vec::new();
    for r in records {
        let key = (r.sweep.clone(), r.mu, r.sigma.to_bits());
        if !keys.contains(&key) {
            keys.push(key);
        }
    }
    keys.into_iter()
        .map(|(sweep, mu, sbits)| {
            let sel: Vec<&CvRecord> = records
                .iter()
                .filter(|r| r.sweep == sweep && r.mu == mu && r.sigma.to_bits() == sbits)
                .collect();
            let f = |g: &dyn Fn(&CvRecord) -> f64| {
                mean_sd(&sel.iter().map(|r| g(r)).collect::<Vec<_>>())
            };
            CvSummary {
                sweep: sweep.clone(),
                mu,
                sigma: f64::from_bits(sbits),
                n_regions: f(&|r| r.n_regions as f64),
                log_likelihood: f(&|r| r.test_log_likelihood),
                error_rate: f(&|r| r.error_rate()),
            }
        })
        .collect()
}
