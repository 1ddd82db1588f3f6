//! The thesis's studies as library code (the CLI only formats and plots them):
//! - [`run_monte_carlo`]: the Monte Carlo study of §2.3.1 (set-up in DESIGN §4);
//! - [`run_real`]: mapping a recorded dataset, PQRM beside a per-frame (no filter)
//!   baseline, the analogue of §2.3.2 (Figs 2.14–2.16);
//! - [`noise_check`]: how wrong a range-bearing noise model is, measured against surveyed
//!   inter-landmark distances.
//!
//! Both studies sample the finest calculus (the first one given) once per step and merge its
//! counts into the coarser ones, as the thesis evaluates all six on the same data.

use qsr_core::cost::{Budget, Cost};
use qsr_core::progress::Progress;
use std::collections::BTreeMap;

use qsr_core::{Calculus, MergeMap};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::{LandmarkSet, Orderings, StepCounts, log_likelihood, step_counts};
use crate::loaders::Dataset;
use crate::map::{Pqrm, PqrmConfig, TripletBelief, normalise};
use crate::metrics::{Baselines, GroundTruth, MapMetrics, evaluate, random_baselines};
use crate::observation::{LandmarkId, Observation, Scan};
use crate::sampler::{ScanSamples, mix};

/// The finest calculus and its merges into the others.
struct CalculusFamily {
    calculi: Vec<Calculus>,
    merges: Vec<Option<MergeMap>>,
}

impl CalculusFamily {
    fn new(names: &[String]) -> Result<Self> {
        if names.is_empty() {
            return Err(PqrmError::InvalidConfig("no calculus given".into()));
        }
        let calculi = names
            .iter()
            .map(|n| Calculus::resolve(n))
            .collect::<std::result::Result<Vec<_>, _>>()?;
        let merges = calculi
            .iter()
            .enumerate()
            .map(|(i, c)| {
                if i == 0 {
                    Ok(None)
                } else {
                    calculi[0].merge_map(c).map(Some)
                }
            })
            .collect::<std::result::Result<Vec<_>, _>>()?;
        Ok(Self { calculi, merges })
    }

    fn counts_for(&self, i: usize, fine: &StepCounts) -> StepCounts {
        match &self.merges[i] {
            None => fine.clone(),
            Some(m) => fine.merged(m),
        }
    }
}

/// The most landmarks per simulated world in the Monte Carlo study.
pub const MAX_STUDY_LANDMARKS: usize = 200;

/// CPU seconds per triplet-sample of the work estimate below (every landmark in view at
/// worst), measured: `qrm study run monte-carlo --quick` (1.99 × 10⁸ estimated triplet-samples)
/// took 1.11 s of CPU, simulation, filter and scoring included.
pub const SECONDS_PER_TRIPLET_SAMPLE: f64 = 5.6e-9;

/// What classifying `triplet_samples` takes at [`SECONDS_PER_TRIPLET_SAMPLE`] (the full-scale
/// Monte Carlo study is about 3.8 × 10¹¹: 0.6 core-hours).
pub fn classification_cost(triplet_samples: f64) -> Cost {
    Cost::work(triplet_samples, SECONDS_PER_TRIPLET_SAMPLE)
}

/// Settings of the Monte Carlo study (defaults: DESIGN §4 at full scale).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MonteCarloConfig {
    /// Sensor noise standard deviations σ_R (m).
    pub sigmas: Vec<f64>,
    /// Trials per noise level.
    pub trials: usize,
    /// Samples per landmark per step.
    pub samples: usize,
    /// Landmarks per world (the thesis does not say; DESIGN §4 picks 10).
    pub landmarks: usize,
    /// Side of the square world (m).
    pub world: f64,
    /// Radius of the robot's circular loop about the centre (m).
    pub radius: f64,
    /// Angle between measurements along the loop (degrees).
    pub step_deg: f64,
    /// Sensor range (m).
    pub range: f64,
    /// Calculi, finest first; every other one must be a merge of the first.
    pub calculi: Vec<String>,
    /// Pseudo-count floor of the mapper.
    pub floor: f64,
    /// σ_R values at which confusion matrices and wrongly mapped triplets are recorded
    /// (thesis Figs 2.8, 2.9: 1 m and 50 m); values not in `sigmas` run as extra levels.
    pub detail_sigmas: Vec<f64>,
    /// Seed.
    pub seed: u64,
}

impl Default for MonteCarloConfig {
    fn default() -> Self {
        Self {
            sigmas: (0..=20).map(|i| f64::from(i) * 5.0).collect(),
            trials: 1000,
            samples: 1000,
            landmarks: 10,
            world: 100.0,
            radius: 50.0,
            step_deg: 16.0,
            range: 60.0,
            calculi: qsr_core::POINT_CALCULI
                .iter()
                .map(|s| (*s).to_owned())
                .collect(),
            floor: 1.0,
            detail_sigmas: vec![1.0, 50.0],
            seed: 0,
        }
    }
}

impl MonteCarloConfig {
    /// The quick version used by tests and `--quick`: 5 noise levels, 12 trials, 200 samples.
    #[must_use]
    pub fn quick() -> Self {
        Self {
            sigmas: vec![0.0, 1.0, 10.0, 50.0, 100.0],
            trials: 12,
            samples: 200,
            ..Self::default()
        }
    }

    /// σ_E, the standard deviation of the uniform landmark distribution (world/√12).
    #[must_use]
    pub fn sigma_e(&self) -> f64 {
        self.world / 12f64.sqrt()
    }

    /// Checks the simulated world alone (landmarks, extent, loop, measurement step, range):
    /// what every study simulating this world checks, whatever else it runs.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming the field.
    pub fn validate_world(&self) -> Result<()> {
        let bad = |m: String| Err(PqrmError::InvalidConfig(m));
        if !(3..=MAX_STUDY_LANDMARKS).contains(&self.landmarks) {
            return bad(format!(
                "landmarks must be in 3..={MAX_STUDY_LANDMARKS}, got {}",
                self.landmarks
            ));
        }
        let pos = [self.world, self.radius, self.step_deg, self.range];
        if pos.iter().any(|v| !(v.is_finite() && *v > 0.0)) {
            return bad("world, radius, step and range must be finite and > 0".into());
        }
        // Distances beyond any sensor's (1e308 m squared overflows in the covariances).
        let max = crate::observation::MAX_DISTANCE_M;
        for (field, v) in [
            ("world", self.world),
            ("radius", self.radius),
            ("range", self.range),
        ] {
            if v > max {
                return bad(format!("{field} = {v:?} m: at most {max:e} m"));
            }
        }
        if self.step_deg > 360.0 {
            return bad(format!(
                "step_deg = {}: a measurement every at most 360°",
                self.step_deg
            ));
        }
        Ok(())
    }

    /// Checks every setting, loads the calculi and estimates the work, before anything runs.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming the setting (with the work estimate when it is too
    /// large); calculus errors.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(PqrmError::InvalidConfig(m));
        // Noise levels are distances: bounded as every σ (1e308 squared overflows).
        let level_ok =
            |s: &f64| s.is_finite() && (0.0..=crate::observation::MAX_DISTANCE_M).contains(s);
        if self.sigmas.is_empty() || !self.sigmas.iter().all(level_ok) {
            return bad(format!(
                "sigmas: noise levels must be finite, >= 0 and at most {:e} m: {:?}",
                crate::observation::MAX_DISTANCE_M,
                self.sigmas
            ));
        }
        // The detail levels run as levels too (issue 39: `detail_sigmas = [-1]` ran and
        // reported a verdict "at σ_R = -1 m").
        if !self.detail_sigmas.iter().all(level_ok) {
            return bad(format!(
                "detail_sigmas: noise levels must be finite, >= 0 and at most 1e6 m: {:?}",
                self.detail_sigmas
            ));
        }
        if self.trials == 0 {
            return bad("trials must be >= 1".into());
        }
        crate::map::check_samples(self.samples)?;
        crate::config::check_floor(self.floor)?;
        self.validate_world()?;
        // The calculi load and merge (a spec file that is missing or not a merge of the first
        // fails here, not after the first outputs).
        CalculusFamily::new(&self.calculi)?;
        // The work before it starts: ordered triplet-samples over every level, trial and step
        // (every landmark in view at worst), at the measured cost of one.
        let levels = (self.sigmas.len() + self.detail_sigmas.len()) as f64;
        let steps = (360.0 / self.step_deg).ceil();
        let l = self.landmarks as f64;
        let work =
            levels * self.trials as f64 * steps * l * (l - 1.0) * (l - 2.0) * self.samples as f64;
        classification_cost(work)
            .check(
                &Budget::RUN,
                format!(
                    "levels × trials × steps × ordered triplets × samples = {levels} × {} × \
                     {steps} × {} × {} = {work:.2e} triplet-samples",
                    self.trials,
                    l * (l - 1.0) * (l - 2.0),
                    self.samples
                ),
            )
            .map_err(|e| {
                PqrmError::InvalidConfig(
                    e.hint("fewer trials, samples, landmarks or levels, or a coarser step_deg")
                        .to_string(),
                )
            })?;
        Ok(())
    }
}

/// Mean and standard deviation over trials.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Stat {
    /// Mean.
    pub mean: f64,
    /// Sample standard deviation over trials (divisor n − 1: `qsr_core::stats`).
    pub std: f64,
}

impl Stat {
    fn of(values: &[f64]) -> Self {
        let s = qsr_core::stats::MeanSd::of(values);
        Self {
            mean: s.mean,
            std: s.sd,
        }
    }
}

/// One (calculus, noise level) row of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LevelResult {
    /// Calculus name.
    pub calculus: String,
    /// σ_R (m).
    pub sigma_r: f64,
    /// σ_N = σ_R / σ_E.
    pub sigma_n: f64,
    /// Trials that produced a map.
    pub trials: usize,
    /// Landmark sets per map.
    pub n_sets: Stat,
    /// Mean map entropy (eq. 2.11).
    pub mean_entropy: Stat,
    /// Mean map entropy / ln Q.
    pub normalized_entropy: Stat,
    /// Error rate of the ML state.
    pub error_rate: Stat,
    /// Mean probability of the ML state.
    pub p_ml: Stat,
    /// Mean neighbour distance of the ML state to the truth.
    pub neighbor_distance: Stat,
}

/// A wrongly mapped triplet (thesis Fig 2.8).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WrongTriplet {
    /// σ_R of the trial.
    pub sigma_r: f64,
    /// Normalised position of the third landmark.
    pub x: f64,
    /// Normalised position of the third landmark.
    pub y: f64,
    /// `|AB|` (m).
    pub d_ab: f64,
    /// True state label.
    pub truth: String,
    /// ML state label.
    pub ml: String,
}

/// Everything the Monte Carlo study measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MonteCarloResult {
    /// The settings.
    pub config: MonteCarloConfig,
    /// One row per calculus and noise level.
    pub levels: Vec<LevelResult>,
    /// Random-guess baselines per calculus.
    pub baselines: BTreeMap<String, Baselines>,
    /// Confusion matrices `[true][ml]` of the finest calculus at each detail σ_R.
    pub confusion: Vec<(f64, Vec<Vec<u64>>)>,
    /// Wrongly mapped triplets of the finest calculus at the detail σ_R values.
    pub wrong: Vec<WrongTriplet>,
}

#[derive(Debug, Clone)]
struct TrialOutcome {
    metrics: Vec<MapMetrics>,
    wrong: Vec<WrongTriplet>,
}

/// Landmarks and the observations of one trial (a world and the robot's loop).
pub(crate) fn simulate_trial(
    config: &MonteCarloConfig,
    sigma: f64,
    level: usize,
    trial: usize,
) -> (GroundTruth, Vec<Scan>) {
    let key = mix(config.seed ^ mix(level as u64) ^ mix(mix(trial as u64)));
    let mut rng = ChaCha8Rng::seed_from_u64(key);
    let mut truth = GroundTruth::default();
    for i in 0..config.landmarks {
        let p = [
            rng.random_range(0.0..config.world),
            rng.random_range(0.0..config.world),
        ];
        truth.positions.insert(LandmarkId(i as u32), p);
    }
    let centre = config.world / 2.0;
    let steps = (360.0 / config.step_deg).ceil() as usize;
    let noise = Normal::new(0.0, sigma.max(0.0))
        .unwrap_or_else(|_| Normal::new(0.0, 0.0).expect("zero noise"));
    let mut scans = Vec::with_capacity(steps);
    for k in 0..steps {
        let th = (k as f64 * config.step_deg).to_radians();
        let (px, py) = (
            centre + config.radius * th.cos(),
            centre + config.radius * th.sin(),
        );
        let heading = th + std::f64::consts::FRAC_PI_2;
        let (s, c) = heading.sin_cos();
        let mut obs = Vec::new();
        for (id, p) in &truth.positions {
            let (dx, dy) = (p[0] - px, p[1] - py);
            if dx.hypot(dy) > config.range {
                continue;
            }
            // Robot frame, then the sensor's noise; the mapper gets the noisy mean and σ² I.
            let (rx, ry) = (c * dx + s * dy, -s * dx + c * dy);
            let z = [rx + noise.sample(&mut rng), ry + noise.sample(&mut rng)];
            if let Ok(o) = Observation::isotropic(*id, z, sigma) {
                obs.push(o);
            }
        }
        if let Ok(scan) = Scan::new(k as f64, 0, obs) {
            scans.push(scan);
        }
    }
    (truth, scans)
}

fn run_trial(
    config: &MonteCarloConfig,
    family: &CalculusFamily,
    sigma: f64,
    level: usize,
    trial: usize,
) -> Result<Option<TrialOutcome>> {
    let (truth, scans) = simulate_trial(config, sigma, level, trial);
    let map_config = PqrmConfig {
        samples: config.samples,
        floor: config.floor,
        orderings: Orderings::All,
        seed: mix(config.seed ^ 0x5a5a ^ mix(level as u64 ^ mix(trial as u64))),
        ..PqrmConfig::default()
    };
    let mut maps = family
        .calculi
        .iter()
        .map(|c| Pqrm::new(c.clone(), map_config))
        .collect::<Result<Vec<_>>>()?;
    for (step, scan) in scans.iter().enumerate() {
        if scan.observations.len() < 3 {
            for m in &mut maps {
                m.apply_counts(&StepCounts::new(m.calculus().n_states()))?;
            }
            continue;
        }
        let samples = ScanSamples::draw(scan, config.samples, map_config.seed, step as u64);
        let fine = step_counts(&family.calculi[0], &samples, Orderings::All)?;
        for (i, m) in maps.iter_mut().enumerate() {
            m.apply_counts(&family.counts_for(i, &fine))?;
        }
    }
    if maps[0].is_empty() {
        return Ok(None);
    }
    let metrics = maps
        .iter()
        .map(|m| evaluate(m, &truth))
        .collect::<Result<Vec<_>>>()?;
    let mut wrong = Vec::new();
    if config.detail_sigmas.contains(&sigma) {
        let fine = &maps[0];
        for (set, b) in fine.iter() {
            let Some(t) = truth.state(fine.calculus(), set)? else {
                continue;
            };
            let ml = b.ml_state();
            if ml != t
                && let Some(([x, y], d_ab)) = truth.normalised(set)
            {
                wrong.push(WrongTriplet {
                    sigma_r: sigma,
                    x,
                    y,
                    d_ab,
                    truth: fine.calculus().label(t).to_owned(),
                    ml: fine.calculus().label(ml).to_owned(),
                });
            }
        }
    }
    Ok(Some(TrialOutcome { metrics, wrong }))
}

/// The outcome of one trial, as shards return it (see [`run_monte_carlo_shard`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialRecord {
    /// Index of the noise level in the (completed) level list.
    pub level: usize,
    /// Trial index within the level.
    pub trial: usize,
    /// Scores of each calculus' map; `None` when the trial produced no map.
    pub metrics: Option<Vec<MapMetrics>>,
    /// Wrongly mapped triplets (detail levels only).
    pub wrong: Vec<WrongTriplet>,
}

/// The study's levels: `sigmas` plus any detail σ not among them (Figs 2.8, 2.9 use σ_R = 1 m,
/// which is not on the 5 m grid), sorted.
fn completed(config: &MonteCarloConfig) -> MonteCarloConfig {
    let mut c = config.clone();
    for d in c.detail_sigmas.clone() {
        if !c.sigmas.contains(&d) {
            c.sigmas.push(d);
        }
    }
    c.sigmas.sort_by(f64::total_cmp);
    c.sigmas.dedup();
    c
}

/// Runs trials `start..start + count` of every level: one shard of the study. Trial `t` of
/// level `l` is seeded by `(seed, l, t)` alone, so shards run anywhere (threads, processes,
/// a Ray cluster) and [`aggregate_monte_carlo`] of their records equals one
/// [`run_monte_carlo`].
///
/// # Errors
/// As [`run_monte_carlo`].
pub fn run_monte_carlo_shard(
    config: &MonteCarloConfig,
    start: usize,
    count: usize,
    progress: &dyn Progress,
) -> Result<Vec<TrialRecord>> {
    config.validate()?;
    let config = &completed(config);
    let family = CalculusFamily::new(&config.calculi)?;
    let end = (start + count).min(config.trials);
    let jobs: Vec<(usize, usize)> = (0..config.sigmas.len())
        .flat_map(|l| (start..end).map(move |t| (l, t)))
        .collect();
    progress.add_total(jobs.len());
    jobs.par_iter()
        .map(|&(level, trial)| {
            progress.check()?;
            let r = run_trial(config, &family, config.sigmas[level], level, trial);
            progress.tick();
            r.map(|o| TrialRecord {
                level,
                trial,
                wrong: o.as_ref().map(|o| o.wrong.clone()).unwrap_or_default(),
                metrics: o.map(|o| o.metrics),
            })
        })
        .collect()
}

/// The records sorted by (level, trial), checked to be exactly one per trial of `config`,
/// each made with its `n_calc` calculi.
fn sorted_records<'r>(
    config: &MonteCarloConfig,
    records: &'r [TrialRecord],
    n_calc: usize,
) -> Result<Vec<&'r TrialRecord>> {
    let mut records: Vec<&TrialRecord> = records.iter().collect();
    records.sort_by_key(|r| (r.level, r.trial));
    let expected = config.sigmas.len() * config.trials;
    let in_range = records
        .iter()
        .all(|r| r.level < config.sigmas.len() && r.trial < config.trials);
    let unique = records
        .windows(2)
        .all(|w| (w[0].level, w[0].trial) != (w[1].level, w[1].trial));
    if records.len() != expected || !in_range || !unique {
        return Err(PqrmError::Mismatch(format!(
            "{} trial records for {} levels × {} trials (missing, duplicated or foreign records)",
            records.len(),
            config.sigmas.len(),
            config.trials
        )));
    }
    if records
        .iter()
        .any(|r| r.metrics.as_ref().is_some_and(|m| m.len() != n_calc))
    {
        return Err(PqrmError::Mismatch(
            "trial records were made with other calculi".into(),
        ));
    }
    Ok(records)
}

/// Combines trial records (from one run or many shards, in any order) into the study result.
///
/// # Errors
/// [`PqrmError::Mismatch`] when a record does not belong to the configuration or a trial is
/// missing or duplicated.
pub fn aggregate_monte_carlo(
    config: &MonteCarloConfig,
    records: &[TrialRecord],
) -> Result<MonteCarloResult> {
    config.validate()?;
    let config = &completed(config);
    let family = CalculusFamily::new(&config.calculi)?;
    let records = sorted_records(config, records, family.calculi.len())?;
    let q0 = family.calculi[0].n_states();
    let mut levels = Vec::new();
    let mut confusion = Vec::new();
    let mut wrong = Vec::new();
    let sigma_e = config.sigma_e();
    for (l, &sigma) in config.sigmas.iter().enumerate() {
        let outcomes: Vec<&Vec<MapMetrics>> = records
            .iter()
            .filter(|r| r.level == l)
            .filter_map(|r| r.metrics.as_ref())
            .collect();
        for (ci, calc) in family.calculi.iter().enumerate() {
            let col = |f: &dyn Fn(&MapMetrics) -> f64| {
                Stat::of(&outcomes.iter().map(|o| f(&o[ci])).collect::<Vec<_>>())
            };
            levels.push(LevelResult {
                calculus: calc.name().to_owned(),
                sigma_r: sigma,
                sigma_n: sigma / sigma_e,
                trials: outcomes.len(),
                n_sets: col(&|m| m.n_sets as f64),
                mean_entropy: col(&|m| m.mean_entropy),
                normalized_entropy: col(&|m| m.normalized_entropy),
                error_rate: col(&|m| m.error_rate),
                p_ml: col(&|m| m.p_ml_mean),
                neighbor_distance: col(&|m| m.mean_neighbor_distance),
            });
        }
        if config.detail_sigmas.contains(&sigma) {
            let mut total = vec![vec![0u64; q0]; q0];
            for o in &outcomes {
                for (row, add) in total.iter_mut().zip(&o[0].confusion) {
                    for (a, b) in row.iter_mut().zip(add) {
                        *a += b;
                    }
                }
            }
            for r in records.iter().filter(|r| r.level == l) {
                wrong.extend(r.wrong.iter().cloned());
            }
            confusion.push((sigma, total));
        }
    }
    let baselines = family
        .calculi
        .iter()
        .map(|c| (c.name().to_owned(), random_baselines(c)))
        .collect();
    Ok(MonteCarloResult {
        config: config.clone(),
        levels,
        baselines,
        confusion,
        wrong,
    })
}

/// Runs the Monte Carlo study. `progress` ticks once per finished trial (from worker
/// threads) and is checked before each. Trials run in parallel; the result is identical for
/// any thread count.
///
/// # Errors
/// [`PqrmError::InvalidConfig`]; calculus errors (unknown name, a calculus that is not a
/// merge of the first); [`PqrmError::Cancelled`] when `progress` asks to stop.
pub fn run_monte_carlo(
    config: &MonteCarloConfig,
    progress: &dyn Progress,
) -> Result<MonteCarloResult> {
    let records = run_monte_carlo_shard(config, 0, config.trials, progress)?;
    aggregate_monte_carlo(config, &records)
}

/// Per-frame (no filter) scores: each observation of a set judged on its own.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct FrameMetrics {
    /// (set, frame) observations scored.
    pub n: usize,
    /// Fraction with a wrong ML state.
    pub error_rate: f64,
    /// Mean neighbour distance of the ML state.
    pub mean_neighbor_distance: f64,
    /// Mean entropy of the single-frame distribution.
    pub mean_entropy: f64,
    /// Top-n error rates.
    pub top_n_error: Vec<f64>,
}

/// Frames' votes for each state of one triplet, and the summed single-frame probabilities.
type Votes = (Vec<u32>, Vec<f64>);

/// The per-triplet majority vote's scores.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct VoteMetrics {
    /// Triplets scored.
    pub n: usize,
    /// Fraction whose majority state is wrong.
    pub error_rate: f64,
    /// Mean neighbour distance of the majority state.
    pub mean_neighbor_distance: f64,
}

/// One calculus on a recorded dataset.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RealCalculusResult {
    /// Calculus name.
    pub calculus: String,
    /// The PQRM's scores.
    pub pqrm: MapMetrics,
    /// Entropy of every recorded set (Fig 2.14 histogram data).
    pub entropies: Vec<f64>,
    /// The per-frame baseline's scores (every (triplet, frame) scored once: often-seen
    /// triplets weigh more).
    pub per_frame: FrameMetrics,
    /// The per-triplet majority vote: each triplet's state is the one most frames' ML states
    /// agree on (ties: the larger summed single-frame probability), scored once per triplet,
    /// as the map is — the fair baseline a filter must beat.
    pub majority: VoteMetrics,
    /// The map's reliability diagram.
    pub calibration: crate::calibration::Calibration,
    /// What a calibrated map of the same triplets would score by chance (drawn with the
    /// map's seed).
    #[serde(default)]
    pub chance: crate::calibration::Chance,
    /// The map's log loss against the truth: mean `−ln P(true state)` over scored triplets
    /// (a probability below 1e-300 counts as 1e-300, so the score stays finite).
    #[serde(default)]
    pub log_loss: f64,
    /// The smoothed vote's log loss over the same triplets: each triplet's histogram of
    /// single-frame ML states with one pseudo-count per state. A map whose probabilities lose
    /// to it says less than counting frames, however its bins look.
    #[serde(default)]
    pub vote_log_loss: f64,
    /// Random-guess baselines.
    pub random: Baselines,
    /// The reliability diagram split by whether the survey agrees with the frames on the
    /// set's landmark pairs ([`crate::survey`]).
    #[serde(default)]
    pub survey: crate::survey::SurveySplit,
}

/// Maps a recorded dataset with every calculus and scores PQRM and the per-frame baseline.
///
/// # Errors
/// [`PqrmError::Mismatch`] without ground truth; mapper errors.
pub fn run_real(
    dataset: &Dataset,
    calculi: &[String],
    config: PqrmConfig,
    progress: &dyn Progress,
) -> Result<Vec<RealCalculusResult>> {
    run_real_tempered(
        dataset,
        calculi,
        config,
        &vec![config.temper; calculi.len()],
        crate::EvidenceModel::Independent,
        progress,
    )
}

/// As [`run_real`], each calculus's map tempered by its own exponent (`tempers`, one per
/// calculus in order, e.g. chosen by [`crate::temper::fit_temper`]) and read under
/// `evidence` ([`crate::evidence`]); `config.temper` is ignored. Tempering changes no maximum-likelihood state, so only the confidence scores
/// (entropy, P(ML), calibration) depend on it.
///
/// # Errors
/// As [`run_real`]; [`PqrmError::InvalidConfig`] for a wrong count or an exponent outside
/// (0, 1].
pub fn run_real_tempered(
    dataset: &Dataset,
    calculi: &[String],
    config: PqrmConfig,
    tempers: &[f64],
    evidence: crate::EvidenceModel,
    progress: &dyn Progress,
) -> Result<Vec<RealCalculusResult>> {
    crate::temper::check_count(tempers, calculi.len())?;
    let truth = dataset
        .truth
        .as_ref()
        .ok_or_else(|| PqrmError::Mismatch("the real-data study needs ground truth".into()))?;
    let family = CalculusFamily::new(calculi)?;
    let mut maps = family
        .calculi
        .iter()
        .zip(tempers)
        .map(|(c, &temper)| {
            Pqrm::new(c.clone(), PqrmConfig { temper, ..config })?.with_evidence(evidence)
        })
        .collect::<Result<Vec<_>>>()?;
    let n = family.calculi.len();
    // a layout map is read from the whole recording at once, after the votes are counted
    let layout = if evidence == crate::EvidenceModel::Layout {
        Some(crate::layout::Layout::fit(&dataset.scans, progress)?)
    } else {
        None
    };
    // Per calculus and triplet: how many frames voted for each state, and the summed
    // single-frame probability (the tie-breaker).
    let mut votes: Vec<BTreeMap<LandmarkSet, Votes>> = vec![BTreeMap::new(); n];
    let mut frames: Vec<FrameTally> = family
        .calculi
        .iter()
        .map(|c| FrameTally {
            ranks: vec![0; c.n_states()],
            ..FrameTally::default()
        })
        .collect();
    for (step, scan) in dataset.scans.iter().enumerate() {
        progress.check()?;
        progress.tick();
        if scan.observations.len() < 3 {
            continue;
        }
        let samples = ScanSamples::draw_with(
            scan,
            config.samples,
            config.seed,
            step as u64,
            config.sensor,
        );
        let fine = step_counts(&family.calculi[0], &samples, config.orderings)?;
        for i in 0..n {
            let counts = family.counts_for(i, &fine);
            let calc = &family.calculi[i];
            for (set, c) in &counts {
                let Some(t) = truth.state(calc, &set)? else {
                    continue;
                };
                let b = TripletBelief {
                    log_p: normalise(log_likelihood(c, config.floor)),
                    updates: 1,
                };
                let v = votes[i]
                    .entry(set)
                    .or_insert_with(|| (vec![0; calc.n_states()], vec![0.0; calc.n_states()]));
                v.0[b.ml_state().index()] += 1;
                for (m, p) in v.1.iter_mut().zip(b.probabilities()) {
                    *m += p;
                }
                frames[i].add(calc, &b, t);
            }
            if layout.is_none() {
                maps[i].apply_counts(&counts)?;
            }
        }
    }
    if let Some(layout) = &layout {
        for (map, calc) in maps.iter_mut().zip(&family.calculi) {
            *map = layout.map(calc.clone(), &dataset.scans, config, &|| {})?;
        }
    }
    let agreement = crate::survey::SurveyAgreement::measure(
        &dataset.scans,
        truth,
        crate::survey::OFF_SURVEY_M,
        crate::survey::MIN_FRAMES,
    );
    maps.iter()
        .zip(&votes)
        .zip(&frames)
        .map(|((map, votes), frames)| real_result(map, truth, votes, frames, &agreement))
        .collect()
}

/// The per-frame baseline of one calculus: each frame's single-observation belief scored
/// against the truth.
#[derive(Debug, Clone, Default)]
struct FrameTally {
    /// Scored (frame, triplet) pairs.
    n: usize,
    /// Of them, with the wrong ML state.
    wrong: usize,
    /// Summed neighbour distance of the ML state to the true one.
    dist: u64,
    /// Summed entropy.
    entropy: f64,
    /// How often the true state had each rank.
    ranks: Vec<usize>,
}

impl FrameTally {
    fn add(&mut self, calc: &Calculus, b: &TripletBelief, truth: qsr_core::StateId) {
        let ml = b.ml_state();
        self.n += 1;
        self.wrong += usize::from(ml != truth);
        self.dist += u64::from(calc.neighbours().distance(ml, truth).unwrap_or(0));
        self.entropy += b.entropy();
        let rank = b.ranked().iter().position(|s| *s == truth).unwrap_or(0);
        self.ranks[rank] += 1;
    }

    fn metrics(&self) -> FrameMetrics {
        let nf = self.n.max(1) as f64;
        let mut covered = 0;
        let top_n_error = self
            .ranks
            .iter()
            .map(|r| {
                covered += r;
                1.0 - covered as f64 / nf
            })
            .collect();
        FrameMetrics {
            n: self.n,
            error_rate: self.wrong as f64 / nf,
            mean_neighbor_distance: self.dist as f64 / nf,
            mean_entropy: self.entropy / nf,
            top_n_error,
        }
    }
}

/// One calculus's result: the map scored, the majority vote over frames, the per-frame
/// baseline, calibration and random baselines.
fn real_result(
    map: &Pqrm,
    truth: &crate::metrics::GroundTruth,
    votes: &BTreeMap<LandmarkSet, Votes>,
    frames: &FrameTally,
    agreement: &crate::survey::SurveyAgreement,
) -> Result<RealCalculusResult> {
    let calc = map.calculus();
    let (mut vn, mut vwrong, mut vdist) = (0usize, 0usize, 0u64);
    let (mut scored, mut loss, mut vote_loss) = (0usize, 0.0, 0.0);
    for (set, (count, mass)) in votes {
        let Some(t) = truth.state(calc, set)? else {
            continue;
        };
        if let Some(p) = map.belief(*set) {
            let total: u32 = count.iter().sum();
            scored += 1;
            loss -= p[t.index()].max(1e-300).ln();
            vote_loss -= ((f64::from(count[t.index()]) + 1.0)
                / (f64::from(total) + count.len() as f64))
                .ln();
        }
        let best = (0..count.len())
            .max_by(|&a, &b| count[a].cmp(&count[b]).then(mass[a].total_cmp(&mass[b])))
            .unwrap_or(0);
        let s = qsr_core::StateId(u16::try_from(best).unwrap_or(u16::MAX));
        vn += 1;
        vwrong += usize::from(s != t);
        vdist += u64::from(calc.neighbours().distance(s, t).unwrap_or(0));
    }
    let vnf = vn.max(1) as f64;
    let snf = scored.max(1) as f64;
    Ok(RealCalculusResult {
        log_loss: loss / snf,
        vote_log_loss: vote_loss / snf,
        calculus: calc.name().to_owned(),
        majority: VoteMetrics {
            n: vn,
            error_rate: vwrong as f64 / vnf,
            mean_neighbor_distance: vdist as f64 / vnf,
        },
        calibration: crate::calibration::calibration(map, truth)?,
        chance: crate::calibration::chance(
            map,
            truth,
            crate::calibration::CHANCE_DRAWS,
            map.config().seed,
        )?,
        pqrm: evaluate(map, truth)?,
        entropies: map.iter().map(|(_, b)| b.entropy()).collect(),
        per_frame: frames.metrics(),
        random: random_baselines(calc),
        survey: crate::survey::split(map, truth, agreement)?,
    })
}

/// How well a dataset's covariances describe its errors, from the pairs of landmarks seen in
/// one frame: the measured distance between the two against the surveyed one, in units of
/// the standard deviation the covariances predict.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NoiseCheck {
    /// Pairs compared.
    pub pairs: usize,
    /// Standard deviation of the normalised residuals (1 if the model is right).
    pub z_std: f64,
    /// Median |z| (0.674 for a correct Gaussian model).
    pub z_median_abs: f64,
    /// Fraction with |z| > 3 (0.0027 for a correct Gaussian model).
    pub outlier_fraction: f64,
    /// Median absolute distance error (m).
    pub median_abs_error: f64,
    /// Landmarks whose measured distances disagree with the survey far more than the others'
    /// (a swapped, moved or misidentified landmark), worst first.
    pub suspects: Vec<SuspectLandmark>,
}

/// A landmark whose surveyed position the measurements contradict.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SuspectLandmark {
    /// The landmark.
    pub landmark: u32,
    /// Pairs it was measured in.
    pub pairs: usize,
    /// Median |z| of those pairs (the dataset's median is `z_median_abs`).
    pub median_abs_z: f64,
}

/// A landmark is suspect when its pairs' median |z| is beyond both this and
/// [`SUSPECT_RATIO`] times the dataset's median, over at least [`SUSPECT_MIN_PAIRS`] pairs.
pub const SUSPECT_Z: f64 = 3.0;
/// See [`SUSPECT_Z`].
pub const SUSPECT_RATIO: f64 = 3.0;
/// See [`SUSPECT_Z`].
pub const SUSPECT_MIN_PAIRS: usize = 10;

/// Compares observed pair distances with the truth (see [`NoiseCheck`]).
///
/// # Errors
/// [`PqrmError::Mismatch`] without ground truth or without any pair.
pub fn noise_check(dataset: &Dataset) -> Result<NoiseCheck> {
    let truth = dataset
        .truth
        .as_ref()
        .ok_or_else(|| PqrmError::Mismatch("the noise check needs ground truth".into()))?;
    let mut z = Vec::new();
    let mut abs_err = Vec::new();
    let mut per_landmark: std::collections::BTreeMap<u32, Vec<f64>> =
        std::collections::BTreeMap::new();
    for scan in &dataset.scans {
        for (i, a) in scan.observations.iter().enumerate() {
            for b in &scan.observations[i + 1..] {
                let (Some(ta), Some(tb)) = (truth.positions.get(&a.id), truth.positions.get(&b.id))
                else {
                    continue;
                };
                let d = [a.mean[0] - b.mean[0], a.mean[1] - b.mean[1]];
                let dm = d[0].hypot(d[1]);
                if dm == 0.0 {
                    continue;
                }
                let u = [d[0] / dm, d[1] / dm];
                let var: f64 = (0..2)
                    .flat_map(|r| (0..2).map(move |c| (r, c)))
                    .map(|(r, c)| u[r] * u[c] * (a.cov[r][c] + b.cov[r][c]))
                    .sum();
                let dt = (ta[0] - tb[0]).hypot(ta[1] - tb[1]);
                abs_err.push((dm - dt).abs());
                if var > 0.0 {
                    let zi = (dm - dt) / var.sqrt();
                    z.push(zi);
                    per_landmark.entry(a.id.0).or_default().push(zi.abs());
                    per_landmark.entry(b.id.0).or_default().push(zi.abs());
                }
            }
        }
    }
    if z.is_empty() {
        return Err(PqrmError::Mismatch(
            "no landmark pair seen in one frame".into(),
        ));
    }
    // scaled inside so that squares cannot overflow (a surveyed coordinate of 1e154 gave
    // `z std inf`, issue 17)
    let std = qsr_core::stats::MeanSd::of(&z).sd;
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let z_median_abs = median(z.iter().map(|v| v.abs()).collect());
    let mut suspects: Vec<SuspectLandmark> = per_landmark
        .into_iter()
        .filter(|(_, v)| v.len() >= SUSPECT_MIN_PAIRS)
        .map(|(landmark, v)| SuspectLandmark {
            landmark,
            pairs: v.len(),
            median_abs_z: median(v),
        })
        .filter(|s| s.median_abs_z > SUSPECT_Z.max(SUSPECT_RATIO * z_median_abs))
        .collect();
    suspects.sort_by(|a, b| b.median_abs_z.total_cmp(&a.median_abs_z));
    Ok(NoiseCheck {
        pairs: z.len(),
        z_std: std,
        z_median_abs,
        suspects,
        outlier_fraction: z.iter().filter(|v| v.abs() > 3.0).count() as f64 / z.len() as f64,
        median_abs_error: median(abs_err),
    })
}

/// One query of `qrm pqrm prob`: three points and their covariances `[sxx, sxy, syy]`, as
/// the JSON line `{"points": [[x, y] x3], "cov": [[sxx, sxy, syy] x3]}`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ObservationQuery {
    /// The three means.
    pub points: [[f64; 2]; 3],
    /// Their covariances, upper triangle.
    pub cov: [[f64; 3]; 3],
}

impl ObservationQuery {
    /// Parses one JSON line; `origin` and `line` name it in errors.
    ///
    /// # Errors
    /// [`PqrmError::Parse`] naming the origin, the line and what is malformed.
    pub fn from_json(text: &str, origin: &std::path::Path, line: usize) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| PqrmError::Parse {
            path: origin.to_path_buf(),
            line,
            reason: format!("expected {{\"points\": [[x,y]x3], \"cov\": [[sxx,sxy,syy]x3]}}: {e}"),
        })
    }

    /// The covariances as 2×2 matrices.
    #[must_use]
    pub fn covariances(&self) -> [[[f64; 2]; 2]; 3] {
        self.cov.map(|[a, b, c]| [[a, b], [b, c]])
    }

    /// `p(R | Z)` of this query ([`single_observation`]).
    ///
    /// # Errors
    /// As [`single_observation`].
    pub fn probabilities(
        &self,
        calculus: &Calculus,
        samples: usize,
        floor: f64,
        seed: u64,
    ) -> Result<Vec<f64>> {
        single_observation(
            calculus,
            self.points,
            self.covariances(),
            samples,
            floor,
            seed,
        )
    }
}

/// `p(R | Z)` of a single observation of three points given in one frame (world or robot),
/// each with its own covariance: the quantity of eq. 2.9 without the filter. `floor = 0`
/// gives plain sample frequencies.
///
/// # Errors
/// Observation errors for bad means/covariances, [`PqrmError::CoincidentLandmarks`].
pub fn single_observation(
    calculus: &Calculus,
    points: [[f64; 2]; 3],
    covs: [[[f64; 2]; 2]; 3],
    samples: usize,
    floor: f64,
    seed: u64,
) -> Result<Vec<f64>> {
    crate::map::check_samples(samples)?;
    if !(floor.is_finite() && floor >= 0.0) {
        return Err(PqrmError::InvalidConfig(format!(
            "floor must be finite and >= 0, got {floor}"
        )));
    }
    let obs = (0..3)
        .map(|i| Observation::new(LandmarkId(i as u32), points[i], covs[i]))
        .collect::<Result<Vec<_>>>()?;
    let scan = Scan::new(0.0, 0, obs)?;
    let s = ScanSamples::draw(&scan, samples, seed, 0);
    let counts = crate::likelihood::set_counts(calculus, &s, [0, 1, 2], &mut Vec::new())?;
    Ok(log_likelihood(&counts, floor)
        .into_iter()
        .map(f64::exp)
        .collect())
}

/// One (sensor model, tempering) variant of the real-data study, for one calculus.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorVariant {
    /// The inverse sensor model.
    pub sensor: crate::sensor::SensorModel,
    /// The tempering exponent.
    pub temper: f64,
    /// Calculus name.
    pub calculus: String,
    /// PQRM's error rate.
    pub error_rate: f64,
    /// The per-triplet majority vote's error rate (the same for every variant of a sensor
    /// model: single frames are not tempered).
    pub majority_error_rate: f64,
    /// Mean P(ML).
    pub p_ml_mean: f64,
    /// Expected calibration error.
    pub ece: f64,
    /// Largest calibration gap over well-filled bins.
    pub max_gap: f64,
}

/// The variants every real-data report compares: the thesis's Gaussian, tempered, and the
/// heavy-tailed models (Student-t with ν = 4; 5 % outliers within 30 m, MRCLAM's range).
#[must_use]
pub fn standard_variants() -> Vec<(crate::sensor::SensorModel, f64)> {
    use crate::sensor::SensorModel::{Gaussian, Outliers, StudentT};
    vec![
        (Gaussian, 1.0),
        (Gaussian, 0.3),
        (Gaussian, 0.1),
        (StudentT { nu: 4.0 }, 1.0),
        (StudentT { nu: 4.0 }, 0.3),
        (
            Outliers {
                rate: 0.05,
                spread: 30.0,
            },
            1.0,
        ),
    ]
}

/// Runs the real-data study once per (sensor model, tempering) variant: how the model and
/// the tempering change error and calibration.
///
/// # Errors
/// As [`run_real`]; [`PqrmError::InvalidConfig`] for a bad variant.
pub fn sensor_sweep(
    dataset: &Dataset,
    calculi: &[String],
    base: PqrmConfig,
    variants: &[(crate::sensor::SensorModel, f64)],
    progress: &dyn Progress,
) -> Result<Vec<SensorVariant>> {
    let mut out = Vec::new();
    for &(sensor, temper) in variants {
        let config = PqrmConfig {
            sensor,
            temper,
            ..base
        };
        config.validate()?;
        for r in run_real(dataset, calculi, config, progress)? {
            out.push(SensorVariant {
                sensor,
                temper,
                calculus: r.calculus,
                error_rate: r.pqrm.error_rate,
                majority_error_rate: r.majority.error_rate,
                p_ml_mean: r.pqrm.p_ml_mean,
                ece: r.calibration.ece,
                max_gap: r.calibration.max_gap,
            });
        }
    }
    Ok(out)
}
