//! The evaluation of reasoning over maps (issue 13 §2, `qrm reason study`):
//! (a) *hidden sets* on a recording with surveyed truth — hide a fraction of the observed
//!     sets, infer them from the rest, score against the truth beside random, the marginal
//!     prior and the map's own (unhidden) belief;
//! (b) *never seen together* in the Monte Carlo world with a short sensor range — coverage and
//!     error of inference on every triplet the robot never saw at once;
//! (c) *consistency check* of the full map — how many most likely entries closure flags and
//!     how many of those are truly wrong (precision) and how many wrong entries it finds
//!     (recall).

use qsr_core::cost::Budget;
use qsr_core::progress::{Progress, phase};
use std::collections::BTreeMap;

use qsr_core::{Calculus, StateId};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::calibration::{CHANCE_DRAWS, Chance, chance_of_predictions};
use crate::error::{PqrmError, Result};
use crate::evidence::EvidenceModel;
use crate::likelihood::LandmarkSet;
use crate::loaders::Dataset;
use crate::map::{Pqrm, PqrmConfig};
use crate::metrics::GroundTruth;
use crate::reason::network::orderings;
use crate::reason::{Composition, Fusion, InferOptions, Inferrer, check, observed_sets};
use crate::study::{MonteCarloConfig, simulate_trial};

/// Settings of the study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReasonStudyConfig {
    /// Calculi to evaluate.
    pub calculi: Vec<String>,
    /// Fraction of the observed sets hidden in (a).
    pub hide_fraction: f64,
    /// Independent hidings in (a).
    pub repeats: usize,
    /// Weight of uniform mixed into each path.
    pub epsilon: f64,
    /// How a composition entry shares a path's probability among its states.
    #[serde(default)]
    pub composition: Composition,
    /// Rounds of chained inference in (b).
    pub rounds: usize,
    /// The mapper's settings.
    pub map: PqrmConfig,
    /// How the maps read a set's frames (`crate::evidence`): the shared-error model, as
    /// `qrm map` reads a recording (issue 35: the study reasons over the maps users get).
    /// With learned composition shares it is the better of the two on every MRCLAM recording
    /// (hidden-set EDC ECE, Datasets 2 / 5 / 7: 0.041 / 0.023 / 0.070 against eq. 2.10's
    /// 0.050 / 0.063 / 0.177; `docs/reasoning.md`). Until 2026-11-29 eq. 2.10: with uniform
    /// shares the softer beliefs spread paths over their entries and the shared model lost.
    #[serde(default = "EvidenceModel::shared_default")]
    pub evidence: EvidenceModel,
    /// The world of (b): the Monte Carlo world with a short range (`landmarks`, `range`,
    /// `step_deg`, `radius`, `world` are used; σ is `sigma_b`).
    pub world: MonteCarloConfig,
    /// Sensor noise of (b) (m).
    pub sigma_b: f64,
    /// Worlds in (b).
    pub worlds_b: usize,
    /// Seed.
    pub seed: u64,
}

impl Default for ReasonStudyConfig {
    fn default() -> Self {
        Self {
            calculi: ["edc", "double-cross", "quadrant", "left-right"]
                .map(str::to_owned)
                .to_vec(),
            hide_fraction: 0.2,
            repeats: 5,
            epsilon: InferOptions::default().epsilon,
            composition: Composition::default(),
            rounds: InferOptions::default().rounds,
            map: PqrmConfig {
                samples: 500,
                ..PqrmConfig::default()
            },
            evidence: EvidenceModel::shared_default(),
            world: MonteCarloConfig {
                landmarks: 30,
                range: 25.0,
                step_deg: 3.0,
                ..MonteCarloConfig::default()
            },
            sigma_b: 1.0,
            worlds_b: 5,
            seed: 0,
        }
    }
}

impl ReasonStudyConfig {
    /// The inference options the study varies from: its ε and composition (each part sets
    /// its own fusion and rounds).
    fn infer_options(&self) -> InferOptions {
        InferOptions {
            epsilon: self.epsilon,
            composition: self.composition,
            rounds: self.rounds,
            ..InferOptions::default()
        }
    }

    /// A small version for tests and `--quick`.
    #[must_use]
    pub fn quick() -> Self {
        let d = Self::default();
        Self {
            calculi: ["edc", "double-cross"].map(str::to_owned).to_vec(),
            repeats: 2,
            map: PqrmConfig {
                samples: 150,
                ..d.map
            },
            world: MonteCarloConfig {
                landmarks: 16,
                ..d.world.clone()
            },
            worlds_b: 2,
            ..d
        }
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] naming the setting.
    pub fn validate(&self) -> Result<()> {
        let bad = |m: String| Err(PqrmError::InvalidConfig(m));
        if !(self.hide_fraction > 0.0 && self.hide_fraction < 1.0) {
            return bad(format!(
                "hide_fraction must be in (0, 1), got {}",
                self.hide_fraction
            ));
        }
        if self.repeats == 0 || self.repeats > 1000 {
            return bad(format!("repeats must be in 1..=1000, got {}", self.repeats));
        }
        InferOptions {
            epsilon: self.epsilon,
            rounds: self.rounds,
            ..InferOptions::default()
        }
        .validate()?;
        if !(self.sigma_b.is_finite()
            && (0.0..=crate::observation::MAX_DISTANCE_M).contains(&self.sigma_b))
        {
            return bad(format!(
                "sigma_b must be finite and >= 0, got {}",
                self.sigma_b
            ));
        }
        if self.worlds_b > 1000 || self.world.landmarks > 200 {
            return bad("worlds_b ≤ 1000 and world.landmarks ≤ 200".into());
        }
        if self.calculi.is_empty() {
            return bad("no calculi".into());
        }
        // Part (b) simulates `world`: its geometry checked as the Monte Carlo study's, and its
        // work estimated the same way (issue 39: `world.step_deg = 1e-12` and `world.world =
        // -1` were accepted, nothing of `world` was checked).
        self.world.validate_world()?;
        let steps = (360.0 / self.world.step_deg).ceil();
        let l = self.world.landmarks as f64;
        let work = self.worlds_b as f64
            * self.calculi.len() as f64
            * steps
            * l
            * (l - 1.0)
            * (l - 2.0)
            * self.map.samples as f64;
        crate::study::classification_cost(work)
            .check(
                &Budget::RUN,
                format!(
                    "part (b): worlds_b × calculi × steps (world.step_deg) × ordered triplets \
                     (world.landmarks) × map.samples = {} × {} × {steps} × {} × {} = \
                     {work:.2e} triplet-samples",
                    self.worlds_b,
                    self.calculi.len(),
                    l * (l - 1.0) * (l - 2.0),
                    self.map.samples
                ),
            )
            .map_err(|e| PqrmError::InvalidConfig(e.to_string()))?;
        self.evidence.validate()?;
        self.map.validate()
    }
}

/// Reliability-diagram bin: predictions whose P(ML) fell in `[lo, hi)`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CalibrationBin {
    /// Lower edge.
    pub lo: f64,
    /// Upper edge.
    pub hi: f64,
    /// Predictions in the bin.
    pub count: usize,
    /// Their mean P(ML).
    pub mean_p: f64,
    /// The fraction whose ML state was right.
    pub accuracy: f64,
}

/// Scores of one predictor over a set of ordered triplets with known truth.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// Ordered triplets scored.
    pub n: usize,
    /// Fraction whose most likely state is wrong.
    pub error_rate: f64,
    /// Fraction whose true state is not among the two most likely.
    pub top2_error: f64,
    /// Mean neighbour distance between the most likely and the true state.
    pub mean_neighbor_distance: f64,
    /// Mean −ln p(true state).
    pub log_loss: f64,
    /// Fraction of predictions more informative than uniform (entropy < ln Q − 0.05).
    pub coverage: f64,
    /// Expected calibration error: Σ_bins (count/n)·|accuracy − mean P(ML)|.
    pub calibration_error: f64,
    /// Ten equal-width bins of P(ML).
    pub bins: Vec<CalibrationBin>,
    /// What calibrated predictions of the same sets would score over the same bins (their
    /// true states drawn from the predictions, one draw per triplet): kept for the inferred
    /// hidden sets of the recording, not computed (`draws` 0) for the baselines and the
    /// simulated worlds.
    #[serde(default)]
    pub chance: Chance,
}

/// The bin edges of [`Score::bins`]: ten equal widths.
const SCORE_EDGES: [f64; 11] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0];

/// Sums over scored predictions. Ties among the most probable states are broken at random
/// in expectation (a uniform prediction scores 1 − 1/Q, not the frequency of state 0).
#[derive(Default, Clone)]
struct Accumulator {
    n: usize,
    wrong: f64,
    top2: f64,
    dist: f64,
    log_loss: f64,
    covered: usize,
    /// Per bin of P(ML): count, sum of P(ML), expected number right.
    bins: [(usize, f64, f64); 10],
    /// Every prediction and its triplet, where [`Score::chance`] is wanted.
    kept: Option<Vec<(Vec<f64>, [u32; 3])>>,
}

impl Accumulator {
    /// An accumulator that keeps its predictions for [`Score::chance`].
    fn keeping() -> Self {
        Self {
            kept: Some(Vec::new()),
            ..Self::default()
        }
    }

    fn add(&mut self, calc: &Calculus, p: &[f64], truth: StateId, set: LandmarkSet) {
        if let Some(kept) = &mut self.kept {
            kept.push((p.to_vec(), set.ids()));
        }
        let q = p.len();
        let pm = p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let tol = 1e-12 * pm.abs().max(1e-300);
        let tied: Vec<usize> = (0..q).filter(|i| (p[*i] - pm).abs() <= tol).collect();
        let hit = if tied.contains(&truth.index()) {
            1.0 / tied.len() as f64
        } else {
            0.0
        };
        // Top 2: states strictly above the second-best value are in; those equal to it share
        // the remaining slots.
        let mut sorted = p.to_vec();
        sorted.sort_by(|a, b| b.total_cmp(a));
        let second = sorted[1.min(q - 1)];
        let tol2 = 1e-12 * second.abs().max(1e-300);
        let above = p.iter().filter(|v| **v > second + tol2).count();
        let equal = p.iter().filter(|v| (**v - second).abs() <= tol2).count();
        let pt = p[truth.index()];
        let in_top2 = if pt > second + tol2 {
            1.0
        } else if (pt - second).abs() <= tol2 {
            (2usize.saturating_sub(above)) as f64 / equal.max(1) as f64
        } else {
            0.0
        };
        self.n += 1;
        self.wrong += 1.0 - hit;
        self.top2 += 1.0 - in_top2.min(1.0);
        self.dist += tied
            .iter()
            .map(|i| {
                f64::from(
                    calc.neighbours()
                        .distance(StateId(*i as u16), truth)
                        .unwrap_or(0),
                )
            })
            .sum::<f64>()
            / tied.len() as f64;
        self.log_loss -= pt.max(1e-12).ln();
        let h: f64 = p.iter().filter(|v| **v > 0.0).map(|v| -v * v.ln()).sum();
        self.covered += usize::from(h < (q as f64).ln() - 0.05);
        // the bins `chance_of_predictions` scores its draws in
        let bin = crate::calibration::bin_of(&SCORE_EDGES, pm);
        self.bins[bin].0 += 1;
        self.bins[bin].1 += pm;
        self.bins[bin].2 += hit;
    }

    /// The scores; [`Score::chance`] drawn from a generator seeded with `seed`.
    fn score(&self, seed: u64) -> Score {
        let n = self.n.max(1) as f64;
        let bins: Vec<CalibrationBin> = self
            .bins
            .iter()
            .enumerate()
            .map(|(i, (count, psum, right))| CalibrationBin {
                lo: i as f64 / 10.0,
                hi: (i + 1) as f64 / 10.0,
                count: *count,
                mean_p: if *count > 0 {
                    psum / *count as f64
                } else {
                    0.0
                },
                accuracy: if *count > 0 {
                    *right / *count as f64
                } else {
                    0.0
                },
            })
            .collect();
        Score {
            n: self.n,
            error_rate: self.wrong / n,
            top2_error: self.top2 / n,
            mean_neighbor_distance: self.dist / n,
            log_loss: self.log_loss / n,
            coverage: self.covered as f64 / n,
            calibration_error: bins
                .iter()
                .map(|b| b.count as f64 / n * (b.accuracy - b.mean_p).abs())
                .sum(),
            bins,
            chance: self.kept.as_ref().map_or_else(Chance::default, |kept| {
                chance_of_predictions(&SCORE_EDGES, kept, CHANCE_DRAWS, seed)
            }),
        }
    }
}

/// Named predictors of one part of the study: inference with each fusion, and baselines.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Predictors {
    /// Inference, by fusion name.
    pub inferred: BTreeMap<String, Score>,
    /// Uniform over the states.
    pub random: Score,
    /// The frequency of most likely states over the visible map's entries.
    pub prior: Score,
    /// (a) only: the map's own belief of the hidden set before hiding (what observing gives).
    pub observed: Option<Score>,
}

/// The consistency check of one full map against the truth.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CheckScore {
    /// Observed unordered sets.
    pub sets: usize,
    /// Sets whose canonical ML state is wrong.
    pub wrong: usize,
    /// Whether the ML states survived closure as they are.
    pub consistent: bool,
    /// Sets flagged.
    pub flagged: usize,
    /// Flagged sets that are truly wrong.
    pub flagged_wrong: usize,
    /// flagged_wrong / flagged (`None` when nothing is flagged).
    pub precision: Option<f64>,
    /// flagged_wrong / wrong (`None` when nothing is wrong).
    pub recall: Option<f64>,
    /// The error rate of random flags at the same count: wrong / sets.
    pub base_rate: f64,
}

/// One landmark of the reference-pair picture: where it sits in the frame of the pair (from
/// the surveyed truth) and how much probability the map gives its true state.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PicturePoint {
    /// The landmark `c` of `{a,b:c}`.
    pub landmark: u32,
    /// Normalised position (A at the origin, B at (0, 1)).
    pub xy: [f64; 2],
    /// Whether the set was observed (else hidden and inferred).
    pub observed: bool,
    /// Probability of the true state: the belief if observed, the inference if hidden.
    pub p_true: f64,
}

/// Every landmark relative to one reference pair, observed beside inferred (first hiding).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferencePairPicture {
    /// `(a, b)`.
    pub pair: [u32; 2],
    /// One point per other landmark with truth.
    pub points: Vec<PicturePoint>,
}

/// One calculus's results.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct ReasonCalculusResult {
    /// Calculus name.
    pub calculus: String,
    /// Number of states.
    pub states: usize,
    /// Whether some general-position compose entry excludes a state (else inference can only
    /// return uniform).
    pub informative_compose: bool,
    /// (a) hidden sets on the recording.
    pub hidden: Predictors,
    /// (b) triplets never seen together in the simulated world.
    pub unseen: Predictors,
    /// (b) restricted to the triplets chained inference reached (round ≥ 1).
    pub unseen_reached: Predictors,
    /// (b): unordered sets never seen together, over all worlds.
    pub unseen_sets: usize,
    /// (b): of those, how many each round of chained inference reached (index 0: none).
    pub unseen_rounds: Vec<usize>,
    /// (c) the consistency check.
    pub check: CheckScore,
    /// The reference pair with the most hidden sets, observed vs inferred (first hiding).
    pub picture: Option<ReferencePairPicture>,
}

/// Accumulators for every fusion and the baselines; the fusions' keep their predictions
/// when `keep` ([`Score::chance`]).
fn new_accs(keep: bool) -> Accumulators {
    (
        Fusion::ALL
            .iter()
            .map(|f| {
                let acc = if keep {
                    Accumulator::keeping()
                } else {
                    Accumulator::default()
                };
                (f.name().to_owned(), acc)
            })
            .collect(),
        Accumulator::default(),
        Accumulator::default(),
        Accumulator::default(),
    )
}

fn predictors(
    fusions: &BTreeMap<String, Accumulator>,
    random: &Accumulator,
    prior: &Accumulator,
    observed: Option<&Accumulator>,
    seed: u64,
) -> Predictors {
    Predictors {
        inferred: fusions
            .iter()
            .map(|(k, a)| (k.clone(), a.score(seed)))
            .collect(),
        random: random.score(seed),
        prior: prior.score(seed),
        observed: observed.map(|a| a.score(seed)),
    }
}

/// The distribution of most likely states over every recorded ordering of a map.
fn ml_prior(map: &Pqrm) -> Vec<f64> {
    let q = map.calculus().n_states();
    let mut counts = vec![1.0; q]; // Laplace: no state gets probability 0
    for set in observed_sets(map) {
        for o in orderings(set) {
            if let Some(p) = map.belief(o) {
                let ml = (0..q).fold(0, |b, i| if p[i] > p[b] { i } else { b });
                counts[ml] += 1.0;
            }
        }
    }
    let total: f64 = counts.iter().sum();
    counts.iter().map(|c| c / total).collect()
}

fn build_map(
    calc: &Calculus,
    scans: &[crate::observation::Scan],
    config: PqrmConfig,
    evidence: EvidenceModel,
    progress: &dyn Progress,
) -> Result<Pqrm> {
    if evidence == EvidenceModel::Layout {
        // a layout map is read from the whole recording at once
        for _ in scans {
            progress.check()?;
            progress.tick();
        }
        let layout = crate::layout::Layout::fit(scans, progress)?;
        return layout.map(calc.clone(), scans, config, &|| {});
    }
    let mut map = Pqrm::new(calc.clone(), config)?.with_evidence(evidence)?;
    for scan in scans {
        progress.check()?;
        progress.tick();
        if scan.observations.len() >= 3 {
            map.update(scan)?;
        }
    }
    Ok(map)
}

type Accumulators = (
    BTreeMap<String, Accumulator>,
    Accumulator,
    Accumulator,
    Accumulator,
);

/// Scores every fusion and the baselines on `targets` (ordered sets with truth), each
/// inferred in one round from the visible map's observed beliefs.
fn score_hidden(
    visible: &Pqrm,
    full: &Pqrm,
    truth: &GroundTruth,
    targets: &[LandmarkSet],
    base: InferOptions,
    accs: &mut Accumulators,
    progress: &dyn Progress,
) -> Result<()> {
    let calc = visible.calculus();
    let q = calc.n_states();
    let inferrer = Inferrer::new(
        visible,
        InferOptions {
            fusion: Fusion::Fitted,
            rounds: 1,
            ..base
        },
    )?;
    let prior = ml_prior(visible);
    let uniform = vec![1.0 / q as f64; q];
    for set in targets {
        progress.check()?;
        let Some(t) = truth.state(calc, set)? else {
            continue;
        };
        let (ps, _) = inferrer.paths(*set);
        for f in Fusion::ALL {
            let p = inferrer.fuse(&ps, f);
            if let Some(acc) = accs.0.get_mut(f.name()) {
                acc.add(calc, &p, t, *set);
            }
        }
        accs.1.add(calc, &uniform, t, *set);
        accs.2.add(calc, &prior, t, *set);
        if let Some(p) = full.belief(*set) {
            accs.3.add(calc, &p, t, *set);
        }
    }
    Ok(())
}

/// Scores chained inference of every never-observed set of `map` (each fusion its own
/// rounds) and the baselines; returns how many sets each round inferred (fitted fusion).
fn score_unseen(
    map: &Pqrm,
    truth: &GroundTruth,
    base: InferOptions,
    accs: &mut Accumulators,
    reached: &mut Accumulators,
    progress: &dyn Progress,
) -> Result<Vec<usize>> {
    let calc = map.calculus();
    let q = calc.n_states();
    let prior = ml_prior(map);
    let uniform = vec![1.0 / q as f64; q];
    let mut per_round = vec![0; base.rounds + 1];
    for f in Fusion::ALL {
        progress.check()?;
        let mut inferrer = Inferrer::new(map, InferOptions { fusion: f, ..base })?;
        let inferences = inferrer.infer_unseen();
        for inf in &inferences {
            progress.check()?;
            let set = LandmarkSet::new(inf.set[0], inf.set[1], inf.set[2]);
            if f == Fusion::Fitted {
                per_round[inf.round] += 1;
            }
            for o in orderings(set) {
                let Some(t) = truth.state(calc, &o)? else {
                    continue;
                };
                let p = inferrer
                    .inferred(o)
                    .map_or_else(|| uniform.clone(), <[f64]>::to_vec);
                if let Some(acc) = accs.0.get_mut(f.name()) {
                    acc.add(calc, &p, t, o);
                }
                if inf.round > 0
                    && let Some(acc) = reached.0.get_mut(f.name())
                {
                    acc.add(calc, &p, t, o);
                }
                if f == Fusion::Fitted {
                    accs.1.add(calc, &uniform, t, o);
                    accs.2.add(calc, &prior, t, o);
                    if inf.round > 0 {
                        reached.1.add(calc, &uniform, t, o);
                        reached.2.add(calc, &prior, t, o);
                    }
                }
            }
        }
    }
    Ok(per_round)
}

/// Runs (a) and (c) on `dataset` (which needs surveyed truth) and (b) in simulation.
/// `progress` is called once per unit of work (see [`ReasonStudyConfig::work_units`]).
///
/// # Errors
/// [`PqrmError::Mismatch`] without ground truth; invalid settings; mapper errors.
pub fn run_reason_study(
    dataset: &Dataset,
    config: &ReasonStudyConfig,
    progress: &dyn Progress,
) -> Result<Vec<ReasonCalculusResult>> {
    config.validate()?;
    let truth = dataset
        .truth
        .as_ref()
        .ok_or_else(|| PqrmError::Mismatch("the reasoning study needs surveyed truth".into()))?;
    let mut out = Vec::new();
    for name in &config.calculi {
        let calc = Calculus::resolve(name)?;
        // (a) and (c): the full map of the recording.
        let full = build_map(&calc, &dataset.scans, config.map, config.evidence, progress)?;
        let sets: Vec<LandmarkSet> = observed_sets(&full)
            .into_iter()
            .filter(|s| truth.state(&calc, s).ok().flatten().is_some())
            .collect();
        let (hidden, picture) = hide_and_infer(&full, &sets, truth, config, progress)?;
        let check_score = check_score(&calc, &full, &sets, truth)?;
        progress.tick();
        let (unseen, unseen_reached, unseen_sets, unseen_rounds) =
            infer_unseen_in_simulation(&calc, config, progress)?;
        let generic =
            qsr_core::reason::Algebra::of(&calc, qsr_core::reason::TableScope::GeneralPosition)?;
        let informative_compose = calc.states().any(|r| {
            calc.states()
                .any(|s| generic.compose(r, s).len() < calc.n_states())
        });
        out.push(ReasonCalculusResult {
            calculus: calc.name().to_owned(),
            states: calc.n_states(),
            informative_compose,
            hidden,
            unseen,
            unseen_reached,
            unseen_sets,
            unseen_rounds,
            check: check_score,
            picture,
        });
    }
    Ok(out)
}

/// (a) Hiding: in each repeat a share of the observed sets is hidden and inferred from the
/// rest, scored against the truth; the first repeat's reference pair is pictured.
fn hide_and_infer(
    full: &Pqrm,
    sets: &[LandmarkSet],
    truth: &GroundTruth,
    config: &ReasonStudyConfig,
    progress: &dyn Progress,
) -> Result<(Predictors, Option<ReferencePairPicture>)> {
    let mut accs = new_accs(true);
    let mut picture = None;
    for repeat in 0..config.repeats {
        let mut rng = ChaCha8Rng::seed_from_u64(
            config.seed ^ (repeat as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15),
        );
        let hidden: Vec<LandmarkSet> = sets
            .iter()
            .copied()
            .filter(|_| rng.random::<f64>() < config.hide_fraction)
            .collect();
        let mut visible = full.clone();
        let hidden_set: std::collections::BTreeSet<[u32; 3]> =
            hidden.iter().map(LandmarkSet::ids).collect();
        visible.retain(|s| {
            let mut ids = s.ids();
            ids.sort_unstable();
            !hidden_set.contains(&ids)
        });
        let targets: Vec<LandmarkSet> = hidden.iter().flat_map(|s| orderings(*s)).collect();
        score_hidden(
            &visible,
            full,
            truth,
            &targets,
            config.infer_options(),
            &mut accs,
            progress,
        )?;
        if repeat == 0 {
            picture = reference_pair_picture(&visible, truth, &hidden, config.infer_options())?;
        }
        progress.tick();
    }
    Ok((
        predictors(&accs.0, &accs.1, &accs.2, Some(&accs.3), config.seed),
        picture,
    ))
}

/// (c) The consistency check of the full map, scored: how many of the entries it flags are
/// wrong (precision) and how many wrong entries it flags (recall).
fn check_score(
    calc: &Calculus,
    full: &Pqrm,
    sets: &[LandmarkSet],
    truth: &GroundTruth,
) -> Result<CheckScore> {
    let checked = check(full)?;
    let wrong_sets: std::collections::BTreeSet<[u32; 3]> = sets
        .iter()
        .filter(|s| {
            let p = full.belief(**s).unwrap_or_default();
            let ml = (0..p.len()).fold(0, |b, i| if p[i] > p[b] { i } else { b });
            truth.state(calc, s).ok().flatten() != Some(StateId(ml as u16))
        })
        .map(LandmarkSet::ids)
        .collect();
    let flagged_wrong = checked
        .flagged
        .iter()
        .filter(|f| wrong_sets.contains(&f.set))
        .count();
    Ok(CheckScore {
        sets: sets.len(),
        wrong: wrong_sets.len(),
        consistent: checked.consistent,
        flagged: checked.flagged.len(),
        flagged_wrong,
        precision: (!checked.flagged.is_empty())
            .then(|| flagged_wrong as f64 / checked.flagged.len() as f64),
        recall: (!wrong_sets.is_empty()).then(|| flagged_wrong as f64 / wrong_sets.len() as f64),
        base_rate: wrong_sets.len() as f64 / sets.len().max(1) as f64,
    })
}

/// (b) Sets never observed, inferred in simulated worlds: the predictors over every unseen
/// set and over those a round reached, the unseen sets and how many each round reached.
fn infer_unseen_in_simulation(
    calc: &Calculus,
    config: &ReasonStudyConfig,
    progress: &dyn Progress,
) -> Result<(Predictors, Predictors, usize, Vec<usize>)> {
    let mut accs_b = new_accs(false);
    let mut reached_b = new_accs(false);
    let mut unseen_sets = 0;
    let mut unseen_rounds = vec![0; config.rounds + 1];
    for w in 0..config.worlds_b {
        let world = MonteCarloConfig {
            seed: config.seed ^ 0x5eed_0b0b,
            ..config.world.clone()
        };
        let (wtruth, scans) = simulate_trial(&world, config.sigma_b, 0, w);
        // a simulated world's map is part of its one unit
        let map = phase(progress, 0, |p| {
            build_map(
                calc,
                &scans,
                PqrmConfig {
                    seed: config.map.seed ^ w as u64,
                    ..config.map
                },
                config.evidence,
                p,
            )
        })?;
        let per_round = score_unseen(
            &map,
            &wtruth,
            config.infer_options(),
            &mut accs_b,
            &mut reached_b,
            progress,
        )?;
        unseen_sets += per_round.iter().sum::<usize>();
        for (total, n) in unseen_rounds.iter_mut().zip(per_round) {
            *total += n;
        }
        progress.tick();
    }
    Ok((
        predictors(&accs_b.0, &accs_b.1, &accs_b.2, None, config.seed),
        predictors(&reached_b.0, &reached_b.1, &reached_b.2, None, config.seed),
        unseen_sets,
        unseen_rounds,
    ))
}

/// The ordered pair with the most hidden sets, every other landmark placed in its frame.
fn reference_pair_picture(
    visible: &Pqrm,
    truth: &GroundTruth,
    hidden: &[LandmarkSet],
    base: InferOptions,
) -> Result<Option<ReferencePairPicture>> {
    let mut count: BTreeMap<[u32; 2], usize> = BTreeMap::new();
    for s in hidden {
        let [a, b, c] = s.ids();
        for pair in [[a, b], [a, c], [b, c]] {
            *count.entry(pair).or_default() += 1;
        }
    }
    let Some((&[a, b], _)) = count.iter().max_by(|x, y| x.1.cmp(y.1).then(y.0.cmp(x.0))) else {
        return Ok(None);
    };
    let calc = visible.calculus();
    let inferrer = Inferrer::new(visible, InferOptions { rounds: 1, ..base })?;
    let mut points = Vec::new();
    for c in truth.positions.keys().map(|l| l.0) {
        if c == a || c == b {
            continue;
        }
        let set = LandmarkSet::new(a, b, c);
        let (Some(t), Some((xy, _))) = (truth.state(calc, &set)?, truth.normalised(&set)) else {
            continue;
        };
        let mut ids = [a, b, c];
        ids.sort_unstable();
        let is_hidden = hidden.iter().any(|h| h.ids() == ids);
        let (observed, p) = match visible.belief(set) {
            Some(p) if !is_hidden => (true, p),
            _ if is_hidden => (false, inferrer.infer(set)?.p),
            _ => continue, // never observed at all: not part of the hiding experiment
        };
        points.push(PicturePoint {
            landmark: c,
            xy,
            observed,
            p_true: p[t.index()],
        });
    }
    Ok(Some(ReferencePairPicture {
        pair: [a, b],
        points,
    }))
}

impl ReasonStudyConfig {
    /// Units of work [`run_reason_study`] reports through `progress` over a recording of
    /// `frames` frames: per calculus, each frame mapped, each hiding repeat, the check, each
    /// simulated world.
    #[must_use]
    pub fn work_units(&self, frames: usize) -> u64 {
        (self.calculi.len() * (frames + 1 + self.repeats + self.worlds_b)) as u64
    }
}

/// One statement of the report, judged from the measurements.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Claim {
    /// What is claimed.
    pub what: String,
    /// The measurement it rests on.
    pub ours: String,
    /// Whether the measurement supports it.
    pub holds: bool,
}

/// The claims the study tests for one calculus, with `fusion` as the inference reported.
#[must_use]
pub fn claims(r: &ReasonCalculusResult, fusion: Fusion) -> Vec<Claim> {
    let mut out = Vec::new();
    let f = fusion.name();
    if let Some(inf) = r.hidden.inferred.get(f) {
        out.push(Claim {
            what: format!(
                "{}: inferred hidden sets beat the marginal prior",
                r.calculus
            ),
            ours: format!(
                "error {:.3} vs {:.3}, log loss {:.3} vs {:.3}",
                inf.error_rate, r.hidden.prior.error_rate, inf.log_loss, r.hidden.prior.log_loss
            ),
            holds: inf.n > 0
                && inf.error_rate < r.hidden.prior.error_rate
                && inf.log_loss < r.hidden.prior.log_loss,
        });
        out.push(Claim {
            what: format!(
                "{}: inference of hidden sets is calibrated (ECE ≤ 0.05)",
                r.calculus
            ),
            ours: if inf.chance.draws > 0 {
                format!(
                    "ECE {:.3} over {} predictions; calibrated predictions of the same sets: \
                     ECE {:.3} (median), {:.3} (95th percentile) — {}",
                    inf.calibration_error,
                    inf.n,
                    inf.chance.ece[0],
                    inf.chance.ece[1],
                    if inf.chance.ece_beyond(inf.calibration_error) {
                        "beyond chance"
                    } else {
                        "within chance"
                    }
                )
            } else {
                format!(
                    "ECE {:.3} over {} predictions",
                    inf.calibration_error, inf.n
                )
            },
            holds: inf.n > 0 && inf.calibration_error <= 0.05,
        });
    }
    if let Some(inf) = r.unseen_reached.inferred.get(f) {
        let reached: usize = r.unseen_rounds.iter().skip(1).sum();
        out.push(Claim {
            what: format!(
                "{}: triplets never seen together that chained composition reaches are \
                 predicted better than by the prior",
                r.calculus
            ),
            ours: format!(
                "{reached} of {} sets reached; on them error {:.3} vs prior {:.3}, log loss \
                 {:.3} vs {:.3}",
                r.unseen_sets,
                inf.error_rate,
                r.unseen_reached.prior.error_rate,
                inf.log_loss,
                r.unseen_reached.prior.log_loss
            ),
            holds: inf.n > 0
                && inf.error_rate < r.unseen_reached.prior.error_rate
                && inf.log_loss < r.unseen_reached.prior.log_loss,
        });
    }
    let c = &r.check;
    out.push(Claim {
        what: format!(
            "{}: an entry the check flags is a wrong map entry more often than a random \
             entry is (precision above the base rate)",
            r.calculus
        ),
        ours: match c.precision {
            Some(p) => format!(
                "precision {p:.3} ({} of {} flags) vs base rate {:.3}",
                c.flagged_wrong, c.flagged, c.base_rate
            ),
            None => format!(
                "nothing flagged (the most likely states pass closure; {} of {} wrong)",
                c.wrong, c.sets
            ),
        },
        holds: c.precision.is_some_and(|p| p > c.base_rate),
    });
    if !r.informative_compose {
        for claim in &mut out {
            claim.ours.push_str(
                " — this calculus's general-position compose table is universal: the algebra \
                 alone carries no information (what `learned` composition shares add is the \
                 map's own statistics of its quadruples)",
            );
        }
    }
    out
}

/// The fusion with the lowest mean log loss on the hidden sets over all calculi (the
/// measurement behind [`Fusion::default`]).
#[must_use]
pub fn best_fusion(results: &[ReasonCalculusResult]) -> Option<Fusion> {
    Fusion::ALL.into_iter().min_by(|a, b| {
        let loss = |f: Fusion| {
            let v: Vec<f64> = results
                .iter()
                .filter_map(|r| r.hidden.inferred.get(f.name()).map(|s| s.log_loss))
                .collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        loss(*a).total_cmp(&loss(*b))
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn set(k: u32) -> LandmarkSet {
        LandmarkSet::new(3 * k, 3 * k + 1, 3 * k + 2)
    }

    /// Inferred predictions kept for the chance band: honest ones (P(ML) 0.7, right 70 % of
    /// the time) score an ECE within it, overconfident ones (P(ML) 0.95, right 70 %) beyond
    /// it, and the claim's text says which; the baselines keep nothing.
    #[test]
    fn the_hidden_sets_ece_is_judged_against_what_chance_gives() {
        use rand::{RngExt, SeedableRng};
        let calc = Calculus::builtin("double-cross").unwrap();
        let q = calc.n_states();
        let belief = |p_ml: f64| {
            let mut p = vec![(1.0 - p_ml) / (q - 1) as f64; q];
            p[0] = p_ml;
            p
        };
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let (mut honest, mut bold) = (Accumulator::keeping(), Accumulator::keeping());
        for k in 0..600 {
            let truth = StateId(if rng.random::<f64>() < 0.7 { 0 } else { 1 });
            honest.add(&calc, &belief(0.7), truth, set(k));
            bold.add(&calc, &belief(0.95), truth, set(k));
        }
        let (honest, bold) = (honest.score(9), bold.score(9));
        assert_eq!(honest.chance.draws, CHANCE_DRAWS);
        assert!(
            !honest.chance.ece_beyond(honest.calibration_error),
            "{honest:?}"
        );
        assert!(
            bold.chance.ece_beyond(bold.calibration_error),
            "{:?}",
            bold.chance
        );
        assert!(
            bold.chance.ece[1] < 0.05,
            "600 triplets leave little to chance"
        );
        assert_eq!(Accumulator::default().score(9).chance.draws, 0);
        let mut r = ReasonCalculusResult {
            calculus: "x".into(),
            ..ReasonCalculusResult::default()
        };
        r.hidden.inferred.insert("fitted".into(), bold);
        let c = claims(&r, Fusion::Fitted);
        let calibrated = c.iter().find(|c| c.what.contains("calibrated")).unwrap();
        assert!(!calibrated.holds);
        assert!(
            calibrated.ours.contains("beyond chance"),
            "{}",
            calibrated.ours
        );
    }

    #[test]
    fn a_uniform_prediction_scores_as_chance_not_as_state_zero() {
        let calc = Calculus::builtin("double-cross").unwrap();
        let q = calc.n_states();
        let mut acc = Accumulator::default();
        // Truth is always state 0: an argmax with lowest-id ties would score 0 % error.
        for _ in 0..10 {
            acc.add(&calc, &vec![1.0 / q as f64; q], StateId(0), set(0));
        }
        let s = acc.score(0);
        assert!(
            (s.error_rate - (1.0 - 1.0 / q as f64)).abs() < 1e-12,
            "{}",
            s.error_rate
        );
        assert!(
            (s.top2_error - (1.0 - 2.0 / q as f64)).abs() < 1e-12,
            "{}",
            s.top2_error
        );
        assert!((s.log_loss - (q as f64).ln()).abs() < 1e-12);
        assert!(s.coverage.abs() < 1e-12);
        // A confident right prediction and a confident wrong one.
        let mut acc = Accumulator::default();
        let mut p = vec![0.0; q];
        p[2] = 1.0;
        acc.add(&calc, &p, StateId(2), set(0));
        acc.add(&calc, &p, StateId(3), set(1));
        let s = acc.score(0);
        assert!((s.error_rate - 0.5).abs() < 1e-12);
        assert_eq!(s.bins[9].count, 2);
        assert!((s.bins[9].accuracy - 0.5).abs() < 1e-12);
        assert!((s.calibration_error - 0.5).abs() < 1e-12);
    }

    /// Regression: the score binned P(ML) by `⌊10·p⌋`, the chance band by comparing with the
    /// edges; 0.8999999999999999 times 10 rounds to 9, so the two put it in different bins.
    #[test]
    fn a_prediction_just_below_an_edge_is_binned_as_the_chance_band_bins_it() {
        let calc = Calculus::builtin("left-right").unwrap();
        let p_ml = 0.899_999_999_999_999_9_f64;
        assert!(
            p_ml < 0.9 && (p_ml * 10.0) as usize == 9,
            "the edge case itself"
        );
        let mut acc = Accumulator::default();
        let mut p = vec![0.0; calc.n_states()];
        p[0] = p_ml;
        p[1] = 1.0 - p_ml;
        acc.add(&calc, &p, StateId(0), set(0));
        let s = acc.score(0);
        assert_eq!(s.bins[8].count, 1);
        assert_eq!(s.bins[9].count, 0);
        assert_eq!(crate::calibration::bin_of(&SCORE_EDGES, p_ml), 8);
    }

    #[test]
    fn claims_are_judged_from_the_numbers() {
        let score = |err: f64, loss: f64| Score {
            n: 10,
            error_rate: err,
            log_loss: loss,
            ..Score::default()
        };
        let mut r = ReasonCalculusResult {
            calculus: "x".into(),
            informative_compose: true,
            ..ReasonCalculusResult::default()
        };
        r.hidden.inferred.insert("fitted".into(), score(0.2, 0.5));
        r.hidden.prior = score(0.8, 1.5);
        r.check = CheckScore {
            sets: 10,
            wrong: 2,
            flagged: 0,
            precision: None,
            base_rate: 0.2,
            ..CheckScore::default()
        };
        let c = claims(&r, Fusion::Fitted);
        assert!(c[0].holds, "{c:?}");
        let check = c.last().unwrap();
        assert!(!check.holds, "nothing flagged is not a precise check");
        assert!(check.ours.contains("nothing flagged"));
        // Worse than the prior in log loss: the claim fails.
        r.hidden.inferred.insert("fitted".into(), score(0.2, 2.0));
        assert!(!claims(&r, Fusion::Fitted)[0].holds);
        r.informative_compose = false;
        assert!(
            claims(&r, Fusion::Fitted)[0]
                .ours
                .contains("no information")
        );
    }
}

#[cfg(test)]
mod layout_tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    /// The study can reason over layout maps (`evidence = "layout"`): a map of the same sets
    /// as the filter's, read from the recording's layout instead of refused frame by frame.
    #[test]
    fn the_study_maps_a_recording_by_its_layout_when_asked() {
        let config = ReasonStudyConfig::quick();
        let (_, scans) = simulate_trial(&config.world, 0.3, 0, 0);
        let calc = Calculus::builtin("double-cross").unwrap();
        let layout = build_map(&calc, &scans, config.map, EvidenceModel::Layout, &|| {}).unwrap();
        let filter = build_map(&calc, &scans, config.map, config.evidence, &|| {}).unwrap();
        assert_eq!(layout.evidence(), EvidenceModel::Layout);
        let sets = |m: &Pqrm| m.iter().map(|(s, _)| *s).collect::<Vec<_>>();
        assert_eq!(sets(&layout), sets(&filter));
        assert!(!layout.is_empty());
    }
}
