//! The tempering exponent τ chosen from the recording itself, without ground truth.
//!
//! Eq. 2.10 treats every frame as independent evidence. A robot that stands still, or drives
//! slowly past a landmark triplet, sees the same error many times and the filter counts it
//! every time: on real recordings the map's mean P(ML) is far above its accuracy. Tempering
//! multiplies each frame's log-likelihood by τ ∈ (0, 1], so n correlated frames count as τ·n
//! independent ones ([`crate::PqrmConfig::temper`]). It never changes a maximum-likelihood
//! state — the belief is `softmax(τ · Σ_t ln p(Z_t | q))` — only how sure the map says it is.
//!
//! ## How τ is chosen
//! By how well the map predicts frames it has not seen. The frames are cut into `folds`
//! contiguous blocks in time (contiguous, because the correlation to be measured is between
//! neighbouring frames: a block the robot stood still in is held out whole). For every block
//! and every triplet it saw, the map of the *other* blocks at exponent τ gives the belief
//! `p_τ(q)`, and each held-out frame of the triplet is scored by its predictive probability
//!
//! `ln Σ_q p_τ(q) · ℓ_t(q)`,  `ℓ_t` the frame's own single-frame likelihood (eq. 2.9),
//!
//! the log-probability the map assigns to what the frame saw. A map that is sure of a state
//! held-out frames contradict pays for it; a map that hedges where frames agree pays less.
//! Scores are averaged per (triplet, block) — so often-seen triplets do not dominate — then
//! over all of them, and τ is the grid value with the best mean (the larger τ on a tie).
//! If frames are independent and the sensor model is right, τ = 1 is the Bayes-optimal
//! choice and the criterion finds it up to noise; if every frame is repeated k times, the
//! other blocks' map is k times too sure and τ ≈ 1/k wins. Held-out frames are scored with at
//! least one pseudo-count per state ([`SCORE_FLOOR`]) so that every score is finite.
//!
//! The samples are drawn exactly as the mapper draws them (seed, step = the frame's index),
//! so the evidence of the fit is the evidence of the map. The other blocks' belief is read
//! under the evidence model the map will be read under ([`TemperOptions::evidence`]): with
//! `shared`, a set trained on n frames is `softmax(τ(n) · τ · Σ ln ℓ)`, exactly what the
//! map states, so τ corrects what the model leaves and does not repeat its correction.

use qsr_core::progress::Progress;
use std::collections::{BTreeMap, HashMap};

use qsr_core::Calculus;
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::evidence::EvidenceModel;
use crate::likelihood::{LandmarkSet, StepCounts, log_likelihood, step_counts};
use crate::map::{PqrmConfig, normalise};
use crate::observation::Scan;
use crate::sampler::ScanSamples;

/// Pseudo-counts per state (at least) in a held-out frame's likelihood.
pub const SCORE_FLOOR: f64 = 1.0;

/// Candidate shares ε of held-out frames that say nothing about the state (a misread
/// barcode, a reflection): each frame's likelihood is scored as `(1 − ε)·ℓ_t + ε/Q`, and
/// each τ keeps its best ε. Without it, τ would be bent to hedge against a few outlier frames
/// the map is right to ignore.
pub const OUTLIER_GRID: [f64; 9] = [0.0, 0.005, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3, 0.5];

/// The default grid: τ = 2^(−k/2) for k = 0 … 14 (1 down to 0.0078), a step of √2.
#[must_use]
pub fn default_grid() -> Vec<f64> {
    (0..=14).map(|k| 2f64.powf(-f64::from(k) / 2.0)).collect()
}

/// How the tempering exponent of a map is set. In a config it is written as a user types it:
/// `"auto"` or a number (`temper = 0.3`), checked on reading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "TemperValue", into = "TemperValue")]
pub enum TemperChoice {
    /// A given τ ∈ (0, 1] (1 = the thesis's eq. 2.10).
    Fixed(f64),
    /// Chosen from the recording by held-out prediction ([`fit_temper`]).
    Auto,
}

impl TemperChoice {
    /// Parses `auto` or a number in (0, 1].
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming what was given.
    pub fn parse(text: &str) -> Result<Self> {
        let t = text.trim();
        if t.eq_ignore_ascii_case("auto") {
            return Ok(Self::Auto);
        }
        let v: f64 = t.parse().map_err(|_| {
            PqrmError::InvalidConfig(format!(
                "temper must be `auto` or a number in (0, 1], got `{text}`"
            ))
        })?;
        if !(v.is_finite() && v > 0.0 && v <= 1.0) {
            return Err(PqrmError::InvalidConfig(format!(
                "temper must be in (0, 1], got {v}"
            )));
        }
        Ok(Self::Fixed(v))
    }
}

/// [`TemperChoice`] as written in a config.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(untagged)]
enum TemperValue {
    Number(f64),
    Text(String),
}

impl TryFrom<TemperValue> for TemperChoice {
    type Error = PqrmError;
    fn try_from(v: TemperValue) -> Result<Self> {
        match v {
            TemperValue::Number(t) => Self::parse(&t.to_string()),
            TemperValue::Text(s) => Self::parse(&s),
        }
    }
}

impl From<TemperChoice> for TemperValue {
    fn from(c: TemperChoice) -> Self {
        match c {
            TemperChoice::Fixed(t) => Self::Number(t),
            TemperChoice::Auto => Self::Text("auto".to_owned()),
        }
    }
}

/// Checks one exponent per calculus, each in (0, 1].
///
/// # Errors
/// [`PqrmError::InvalidConfig`] for a wrong count or an exponent out of range.
pub fn check_count(tempers: &[f64], calculi: usize) -> Result<()> {
    if tempers.len() != calculi {
        return Err(PqrmError::InvalidConfig(format!(
            "{} tempering exponents for {calculi} calculi",
            tempers.len()
        )));
    }
    if let Some(t) = tempers
        .iter()
        .find(|t| !(t.is_finite() && **t > 0.0 && **t <= 1.0))
    {
        return Err(PqrmError::InvalidConfig(format!(
            "temper must be in (0, 1], got {t}"
        )));
    }
    Ok(())
}

/// Settings of [`fit_temper`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TemperOptions {
    /// Contiguous blocks of frames, each held out once (≥ 2).
    pub folds: usize,
    /// Candidate exponents, each in (0, 1].
    pub grid: Vec<f64>,
    /// The evidence model the map will be read under ([`crate::evidence`]): the other
    /// blocks' belief is scored as that map would state it — `softmax(τ(n) · τ · Σ ln ℓ)`,
    /// `n` the frames trained on — so the chosen τ is a correction *on top of* the model.
    /// Fitting under eq. 2.10 for a map read under `shared` corrected twice (issue 35).
    #[serde(default)]
    pub evidence: EvidenceModel,
}

impl Default for TemperOptions {
    fn default() -> Self {
        Self {
            folds: 5,
            grid: default_grid(),
            evidence: EvidenceModel::Independent,
        }
    }
}

impl TemperOptions {
    /// Sets the number of blocks.
    #[must_use]
    pub fn folds(mut self, folds: usize) -> Self {
        self.folds = folds;
        self
    }

    /// Sets the candidate exponents.
    #[must_use]
    pub fn grid(mut self, grid: Vec<f64>) -> Self {
        self.grid = grid;
        self
    }

    /// Sets the evidence model the fitted map is read under.
    #[must_use]
    pub fn evidence(mut self, evidence: EvidenceModel) -> Self {
        self.evidence = evidence;
        self
    }

    fn validate(&self) -> Result<()> {
        if self.folds < 2 {
            return Err(PqrmError::InvalidConfig(format!(
                "choosing τ needs at least 2 folds, got {}",
                self.folds
            )));
        }
        if self.grid.is_empty() {
            return Err(PqrmError::InvalidConfig("empty τ grid".into()));
        }
        self.evidence.validate()?;
        if let Some(v) = self
            .grid
            .iter()
            .find(|v| !(v.is_finite() && **v > 0.0 && **v <= 1.0))
        {
            return Err(PqrmError::InvalidConfig(format!(
                "every τ of the grid must be in (0, 1], got {v}"
            )));
        }
        Ok(())
    }
}

/// One candidate exponent and its held-out score.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TemperScore {
    /// τ.
    pub temper: f64,
    /// The share of held-out frames explained as outliers under this τ (the best of
    /// [`OUTLIER_GRID`]).
    pub outlier_rate: f64,
    /// Mean held-out log predictive probability (nats; higher is better).
    pub log_score: f64,
}

/// The exponent chosen for one calculus, and the evidence for it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TemperFit {
    /// Calculus name.
    pub calculus: String,
    /// The chosen τ.
    pub chosen: f64,
    /// Blocks of frames.
    pub folds: usize,
    /// (triplet, block) pairs scored: triplets seen both in a block and outside it.
    pub units: usize,
    /// Every candidate, in grid order.
    pub scores: Vec<TemperScore>,
}

impl TemperFit {
    /// The score of τ = 1 (the untempered filter), if the grid has it.
    #[must_use]
    pub fn untempered_score(&self) -> Option<f64> {
        self.scores
            .iter()
            .find(|s| s.temper == 1.0)
            .map(|s| s.log_score)
    }

    /// The chosen τ's score.
    #[must_use]
    pub fn chosen_score(&self) -> f64 {
        self.scores
            .iter()
            .find(|s| s.temper == self.chosen)
            .map_or(f64::NAN, |s| s.log_score)
    }
}

/// Per calculus and triplet: summed log-likelihoods of each block (`folds × states`) and the
/// frames each block has.
struct BlockSums {
    sums: Vec<f64>,
    frames: Vec<u32>,
}

/// The block of frame `i` of `n`.
fn block_of(i: usize, n: usize, folds: usize) -> usize {
    // i < n, so the product stays below folds · n; u128 keeps it exact for any n
    ((i as u128 * folds as u128) / n as u128) as usize
}

/// Chooses τ for each calculus from `scans` (see the module docs). `config` gives the
/// samples, seed, sensor model, floor and orderings of the map to be made; its own `temper`
/// is ignored.
///
/// # Errors
/// [`PqrmError::InvalidConfig`] for bad options or a config the mapper refuses;
/// [`PqrmError::Mismatch`] when fewer frames than folds have three or more landmarks, or no
/// triplet is seen both inside and outside a block (nothing to predict);
/// [`PqrmError::CoincidentLandmarks`] as the mapper.
pub fn fit_temper(
    calculi: &[Calculus],
    scans: &[Scan],
    config: PqrmConfig,
    options: &TemperOptions,
    progress: &dyn Progress,
) -> Result<Vec<TemperFit>> {
    options.validate()?;
    PqrmConfig {
        temper: 1.0,
        ..config
    }
    .validate()?;
    if calculi.is_empty() {
        return Err(PqrmError::InvalidConfig("no calculus given".into()));
    }
    let usable = scans.iter().filter(|s| s.observations.len() >= 3).count();
    if usable < options.folds {
        return Err(PqrmError::Mismatch(format!(
            "choosing τ by {} held-out blocks needs at least {} frames with three or more \
             landmarks, the recording has {usable}",
            options.folds, options.folds
        )));
    }
    let k = options.folds;
    let blocks = block_sums(calculi, scans, config, k, progress)?;
    let (totals, units) = held_out_scores(calculi, scans, config, options, &blocks, progress)?;
    calculi
        .iter()
        .enumerate()
        .map(|(ci, calc)| choose(calc, k, options, &totals[ci], units[ci]))
        .collect()
}

/// Each calculus's evidence from frame `step`: its counts per landmark set.
fn frame_counts(
    calculi: &[Calculus],
    config: PqrmConfig,
    step: usize,
    scan: &Scan,
) -> Result<Vec<StepCounts>> {
    let samples = ScanSamples::draw_with(
        scan,
        config.samples,
        config.seed,
        step as u64,
        config.sensor,
    );
    calculi
        .iter()
        .map(|c| step_counts(c, &samples, config.orderings))
        .collect()
}

/// Pass 1: every block's summed evidence per calculus and triplet.
fn block_sums(
    calculi: &[Calculus],
    scans: &[Scan],
    config: PqrmConfig,
    k: usize,
    progress: &dyn Progress,
) -> Result<Vec<HashMap<LandmarkSet, BlockSums>>> {
    let n = scans.len();
    let mut blocks: Vec<HashMap<LandmarkSet, BlockSums>> =
        calculi.iter().map(|_| HashMap::new()).collect();
    for (i, scan) in scans.iter().enumerate() {
        progress.check()?;
        progress.tick();
        if scan.observations.len() < 3 {
            continue;
        }
        let b = block_of(i, n, k);
        for (ci, counts) in frame_counts(calculi, config, i, scan)?
            .into_iter()
            .enumerate()
        {
            let q = calculi[ci].n_states();
            for (set, c) in &counts {
                let e = blocks[ci].entry(set).or_insert_with(|| BlockSums {
                    sums: vec![0.0; k * q],
                    frames: vec![0; k],
                });
                for (s, l) in e.sums[b * q..(b + 1) * q]
                    .iter_mut()
                    .zip(log_likelihood(c, config.floor))
                {
                    *s += l;
                }
                e.frames[b] += 1;
            }
        }
    }
    Ok(blocks)
}

/// One (triplet, held-out block) unit being scored: the belief of the other blocks under each
/// τ, the summed log scores for each (τ, ε), and the frames scored.
type Unit = (Vec<Vec<f64>>, Vec<f64>, u32);

/// A triplet's belief trained on every block but `b`, under each τ of the grid: a new unit.
fn trained_unit(e: &BlockSums, b: usize, q: usize, k: usize, options: &TemperOptions) -> Unit {
    // the map of the other blocks reads its sum with the evidence model's exponent for the
    // frames it holds
    let trained: u32 = (0..k).filter(|&bb| bb != b).map(|bb| e.frames[bb]).sum();
    let model = options.evidence.exponent(trained);
    let train: Vec<f64> = (0..q)
        .map(|s| {
            (0..k)
                .filter(|&bb| bb != b)
                .map(|bb| e.sums[bb * q + s])
                .sum()
        })
        .collect();
    let beliefs = options
        .grid
        .iter()
        .map(|tau| {
            normalise(train.iter().map(|v| model * (tau * v)).collect())
                .into_iter()
                .map(f64::exp)
                .collect()
        })
        .collect();
    (
        beliefs,
        vec![0.0; options.grid.len() * OUTLIER_GRID.len()],
        0,
    )
}

/// Adds one held-out frame's log predictive probability under each (τ, ε) to `unit`.
fn score_into(unit: &mut Unit, seen: &[f64]) {
    let uniform = 1.0 / seen.len() as f64;
    for (s, p) in unit.1.chunks_mut(OUTLIER_GRID.len()).zip(&unit.0) {
        let pred: f64 = p.iter().zip(seen).map(|(a, l)| a * l).sum();
        for (s, eps) in s.iter_mut().zip(OUTLIER_GRID) {
            // Σ_q p(q)·((1 − ε)·ℓ(q) + ε/Q) = (1 − ε)·Σ p ℓ + ε/Q
            let mixed = (1.0 - eps) * pred + eps * uniform;
            *s += mixed.max(f64::MIN_POSITIVE).ln();
        }
    }
    unit.2 += 1;
}

/// Pass 2: each held-out frame scored against the other blocks' map, for every τ; per
/// calculus, the scores summed over units (each unit's mean over its frames) and the units.
fn held_out_scores(
    calculi: &[Calculus],
    scans: &[Scan],
    config: PqrmConfig,
    options: &TemperOptions,
    blocks: &[HashMap<LandmarkSet, BlockSums>],
    progress: &dyn Progress,
) -> Result<(Vec<Vec<f64>>, Vec<usize>)> {
    let (n, k) = (scans.len(), options.folds);
    let g = options.grid.len() * OUTLIER_GRID.len();
    let score_floor = config.floor.max(SCORE_FLOOR);
    let mut totals = vec![vec![0.0; g]; calculi.len()];
    let mut units = vec![0usize; calculi.len()];
    // per calculus, the current block's units (ordered maps: the scores are summed in one
    // order whatever the thread count)
    let mut current: Vec<BTreeMap<LandmarkSet, Unit>> =
        calculi.iter().map(|_| BTreeMap::new()).collect();
    let mut flush = |current: &mut Vec<BTreeMap<LandmarkSet, Unit>>| {
        for (ci, m) in current.iter_mut().enumerate() {
            for (_, (_, sums, frames)) in std::mem::take(m) {
                units[ci] += 1;
                for (t, s) in totals[ci].iter_mut().zip(&sums) {
                    *t += s / f64::from(frames);
                }
            }
        }
    };
    let mut block = 0;
    for (i, scan) in scans.iter().enumerate() {
        progress.check()?;
        progress.tick();
        let b = block_of(i, n, k);
        if b != block {
            flush(&mut current);
            block = b;
        }
        if scan.observations.len() < 3 {
            continue;
        }
        for (ci, counts) in frame_counts(calculi, config, i, scan)?
            .into_iter()
            .enumerate()
        {
            let q = calculi[ci].n_states();
            for (set, c) in &counts {
                let Some(e) = blocks[ci].get(&set) else {
                    continue;
                };
                if e.frames.iter().sum::<u32>() == e.frames[b] {
                    continue; // seen in this block only: nothing trained to predict it
                }
                let unit = current[ci]
                    .entry(set)
                    .or_insert_with(|| trained_unit(e, b, q, k, options));
                let seen: Vec<f64> = log_likelihood(c, score_floor)
                    .into_iter()
                    .map(f64::exp)
                    .collect();
                score_into(unit, &seen);
            }
        }
    }
    flush(&mut current);
    Ok((totals, units))
}

/// The τ of one calculus: each τ's score is its best over the outlier rates (a profile
/// likelihood); the best score wins, the larger τ on a tie.
fn choose(
    calc: &Calculus,
    k: usize,
    options: &TemperOptions,
    totals: &[f64],
    units: usize,
) -> Result<TemperFit> {
    if units == 0 {
        return Err(PqrmError::Mismatch(format!(
            "{}: no triplet is seen both inside and outside one of the {k} blocks of \
             frames; nothing to choose τ by",
            calc.name()
        )));
    }
    let scores: Vec<TemperScore> = options
        .grid
        .iter()
        .zip(totals.chunks(OUTLIER_GRID.len()))
        .map(|(&temper, t)| {
            let (e, best) = t
                .iter()
                .enumerate()
                .fold(
                    (0, f64::NEG_INFINITY),
                    |b, (e, v)| {
                        if *v > b.1 { (e, *v) } else { b }
                    },
                );
            TemperScore {
                temper,
                outlier_rate: OUTLIER_GRID[e],
                log_score: best / units as f64,
            }
        })
        .collect();
    let best = scores
        .iter()
        .fold(None::<TemperScore>, |best, s| match best {
            Some(b)
                if b.log_score > s.log_score
                    || (b.log_score == s.log_score && b.temper >= s.temper) =>
            {
                Some(b)
            }
            _ => Some(*s),
        });
    Ok(TemperFit {
        calculus: calc.name().to_owned(),
        chosen: best.map_or(1.0, |b| b.temper),
        folds: k,
        units,
        scores,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_contiguous_and_cover_every_fold() {
        let n = 17;
        let b: Vec<usize> = (0..n).map(|i| block_of(i, n, 5)).collect();
        assert!(b.windows(2).all(|w| w[0] <= w[1]));
        assert_eq!(b[0], 0);
        assert_eq!(b[n - 1], 4);
        for f in 0..5 {
            assert!(b.contains(&f));
        }
    }

    #[test]
    fn a_config_writes_temper_as_auto_or_a_number_and_checks_it_on_reading() {
        let j = |c: TemperChoice| serde_json::to_string(&c).unwrap_or_default();
        assert_eq!(j(TemperChoice::Auto), "\"auto\"");
        assert_eq!(j(TemperChoice::Fixed(0.3)), "0.3");
        let r = |s: &str| serde_json::from_str::<TemperChoice>(s);
        assert_eq!(r("0.3").ok(), Some(TemperChoice::Fixed(0.3)));
        assert_eq!(r("1").ok(), Some(TemperChoice::Fixed(1.0)));
        assert_eq!(r("\"AUTO\"").ok(), Some(TemperChoice::Auto));
        let e = r("1.5").err().map(|e| e.to_string()).unwrap_or_default();
        assert!(e.contains("(0, 1]"), "{e}");
        assert!(r("\"often\"").is_err());
    }

    #[test]
    fn parse_accepts_auto_and_the_unit_interval_only() {
        assert_eq!(TemperChoice::parse("auto").ok(), Some(TemperChoice::Auto));
        assert_eq!(
            TemperChoice::parse(" 0.5").ok(),
            Some(TemperChoice::Fixed(0.5))
        );
        for bad in ["0", "-0.1", "1.5", "nan", "inf", "", "half"] {
            assert!(TemperChoice::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn the_grid_runs_from_one_down_by_root_two() {
        let g = default_grid();
        assert_eq!(g[0], 1.0);
        assert!(
            g.windows(2)
                .all(|w| (w[0] / w[1] - 2f64.sqrt()).abs() < 1e-12)
        );
        assert!(TemperOptions::default().validate().is_ok());
        assert!(TemperOptions::default().folds(1).validate().is_err());
        assert!(
            TemperOptions::default()
                .grid(vec![0.5, 1.2])
                .validate()
                .is_err()
        );
        assert!(TemperOptions::default().grid(vec![]).validate().is_err());
    }
}
