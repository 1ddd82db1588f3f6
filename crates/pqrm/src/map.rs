//! [`Pqrm`]: the probabilistic qualitative relational map and its recursive Bayes filter
//! (thesis eq. 2.10, Algorithm 1).
//!
//! Each landmark set keeps `ln p(R = q | Z_1:t)`. An update adds the step's log-likelihood
//! and renormalises with log-sum-exp, so 10^7 updates never underflow. Sets seen for the
//! first time start from their first observation; sets not seen in a step are unchanged.

use std::collections::BTreeMap;
use std::path::Path;

use qsr_core::{Calculus, Permutation, StateId};
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::{LandmarkSet, Orderings, log_likelihood, step_counts};
use crate::metrics::entropy;
use crate::observation::{LandmarkId, Scan};
use crate::sampler::ScanSamples;
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
        if !(self.floor.is_finite() && self.floor >= 0.0) {
            return Err(PqrmError::InvalidConfig(format!(
                "floor must be finite and >= 0, got {}",
                self.floor
            )));
        }
        Ok(())
    }
}

/// The belief over the states of one landmark set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TripletBelief {
    /// `ln p(q)`, normalised.
    pub log_p: Vec<f64>,
    /// Number of steps that observed the set.
    pub updates: u32,
}

impl TripletBelief {
    /// Probabilities.
    #[must_use]
    pub fn probabilities(&self) -> Vec<f64> {
        self.log_p.iter().map(|l| l.exp()).collect()
    }

    /// Entropy in nats.
    #[must_use]
    pub fn entropy(&self) -> f64 {
        entropy(&self.probabilities())
    }

    /// The maximum-likelihood state (lowest id on ties).
    #[must_use]
    pub fn ml_state(&self) -> StateId {
        let mut best = 0;
        for (i, l) in self.log_p.iter().enumerate() {
            if *l > self.log_p[best] {
                best = i;
            }
        }
        StateId(best as u16)
    }

    /// States sorted from most to least likely (ties by id).
    #[must_use]
    pub fn ranked(&self) -> Vec<StateId> {
        let mut idx: Vec<usize> = (0..self.log_p.len()).collect();
        idx.sort_by(|&a, &b| self.log_p[b].total_cmp(&self.log_p[a]).then(a.cmp(&b)));
        idx.into_iter().map(|i| StateId(i as u16)).collect()
    }
}

/// What one update did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UpdateReport {
    /// Sets observed in the step.
    pub observed: usize,
    /// Of those, sets seen for the first time.
    pub new: usize,
    /// Sets whose belief and new evidence contradicted each other completely (possible only
    /// with `floor = 0`); they restart from the new evidence.
    pub conflicts: usize,
}

/// A probabilistic qualitative relational map over one ternary calculus.
#[derive(Debug, Clone)]
pub struct Pqrm {
    calculus: Calculus,
    config: PqrmConfig,
    beliefs: BTreeMap<LandmarkSet, TripletBelief>,
    steps: u64,
}

/// File format version of [`Pqrm::to_json`].
pub const FORMAT_VERSION: u32 = 1;

#[derive(Serialize, Deserialize)]
struct SavedMap {
    format: String,
    version: u32,
    calculus: qsr_core::CalculusSpec,
    config: PqrmConfig,
    steps: u64,
    sets: Vec<SavedSet>,
}

#[derive(Serialize, Deserialize)]
struct SavedSet {
    set: [u32; 3],
    updates: u32,
    log_p: Vec<f64>,
}

impl Pqrm {
    /// An empty map.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`]; [`PqrmError::Calculus`] when the calculus is not ternary.
    pub fn new(calculus: Calculus, config: PqrmConfig) -> Result<Self> {
        config.validate()?;
        if calculus.frame() != qsr_core::FrameKind::Ternary {
            return Err(PqrmError::InvalidConfig(format!(
                "calculus `{}` is {}; the point-landmark mapper needs a ternary calculus",
                calculus.name(),
                calculus.frame().as_str()
            )));
        }
        Ok(Self {
            calculus,
            config,
            beliefs: BTreeMap::new(),
            steps: 0,
        })
    }

    /// The calculus.
    #[must_use]
    pub fn calculus(&self) -> &Calculus {
        &self.calculus
    }

    /// The settings.
    #[must_use]
    pub fn config(&self) -> &PqrmConfig {
        &self.config
    }

    /// Steps processed so far.
    #[must_use]
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Number of recorded landmark sets.
    #[must_use]
    pub fn len(&self) -> usize {
        self.beliefs.len()
    }

    /// Whether no set has been recorded.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.beliefs.is_empty()
    }

    /// The belief of one set, if recorded.
    #[must_use]
    pub fn get(&self, set: &LandmarkSet) -> Option<&TripletBelief> {
        self.beliefs.get(set)
    }

    /// Recorded sets and their beliefs, in set order.
    pub fn iter(&self) -> impl Iterator<Item = (&LandmarkSet, &TripletBelief)> {
        self.beliefs.iter()
    }

    /// One time step: sample every observed landmark once, compute `p(R | Z_t)` for every
    /// set of three observed landmarks, and fold it into the map.
    ///
    /// # Errors
    /// [`PqrmError::CoincidentLandmarks`] (nothing is changed then).
    pub fn update(&mut self, scan: &Scan) -> Result<UpdateReport> {
        let samples = ScanSamples::draw_with(
            scan,
            self.config.samples,
            self.config.seed,
            self.steps,
            self.config.sensor,
        );
        let counts = step_counts(&self.calculus, &samples, self.config.orderings)?;
        let report = self.apply_counts(&counts)?;
        Ok(report)
    }

    /// Folds precomputed histograms (one step's evidence) into the map and advances the step
    /// counter: how a study maps several calculi from one sampling of the finest one.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when a histogram has the wrong number of states.
    pub fn apply_counts(&mut self, counts: &[(LandmarkSet, Vec<u32>)]) -> Result<UpdateReport> {
        let q = self.calculus.n_states();
        if let Some((set, c)) = counts.iter().find(|(_, c)| c.len() != q) {
            return Err(PqrmError::Mismatch(format!(
                "set {:?}: {} counts for a {q}-state calculus",
                set.ids(),
                c.len()
            )));
        }
        let mut report = UpdateReport::default();
        for (set, c) in counts {
            let mut ll = log_likelihood(c, self.config.floor);
            if self.config.temper != 1.0 {
                for v in &mut ll {
                    *v *= self.config.temper;
                }
            }
            report.observed += 1;
            match self.beliefs.get_mut(set) {
                None => {
                    report.new += 1;
                    self.beliefs.insert(
                        *set,
                        TripletBelief {
                            log_p: normalise(ll),
                            updates: 1,
                        },
                    );
                }
                Some(b) => {
                    let post: Vec<f64> = b.log_p.iter().zip(&ll).map(|(a, l)| a + l).collect();
                    b.log_p = if post.iter().all(|v| *v == f64::NEG_INFINITY) {
                        report.conflicts += 1;
                        normalise(ll)
                    } else {
                        normalise(post)
                    };
                    b.updates += 1;
                }
            }
        }
        self.steps += 1;
        Ok(report)
    }

    /// The belief of an ordered set `{a, b : c}` as probabilities in state order.
    ///
    /// With [`Orderings::Canonical`] the other orderings are derived from the recorded one
    /// through the calculus's general-position permutation tables: the probability of each
    /// recorded state is spread evenly over the states its permutation can take (exact when
    /// the permutation is one-to-one, as the inverse is for every built-in).
    ///
    /// `None` when the set was never observed.
    #[must_use]
    pub fn belief(&self, set: LandmarkSet) -> Option<Vec<f64>> {
        if let Some(b) = self.beliefs.get(&set) {
            return Some(b.probabilities());
        }
        if self.config.orderings != Orderings::Canonical {
            return None;
        }
        let [a, b, c] = set.0;
        let mut sorted = [a, b, c];
        sorted.sort();
        let stored = self.beliefs.get(&LandmarkSet(sorted))?;
        // The permutation that maps the stored (sorted) order onto the asked order.
        let op = Permutation::ALL.into_iter().find(|op| {
            let (p, q, r) = op.apply(sorted[0], sorted[1], sorted[2]);
            [p, q, r] == [a, b, c]
        })?;
        let table = self.calculus.permutation_with(op, false).ok()?;
        let mut out = vec![0.0; self.calculus.n_states()];
        for (r, p) in stored.probabilities().into_iter().enumerate() {
            let targets = table.get(StateId(r as u16));
            for t in targets {
                out[t.index()] += p / targets.len() as f64;
            }
        }
        Some(out)
    }

    /// Keeps only the recorded sets for which `keep` is true (e.g. to hide sets from a map
    /// and test inference on them).
    pub fn retain(&mut self, mut keep: impl FnMut(&LandmarkSet) -> bool) {
        self.beliefs.retain(|s, _| keep(s));
    }

    /// Predicts `{a,b:d}` from the other beliefs of the map by composition (see
    /// [`crate::reason`]), with the default options.
    ///
    /// # Errors
    /// As [`crate::reason::infer_with`].
    pub fn infer(&self, set: LandmarkSet) -> Result<crate::reason::Inference> {
        crate::reason::infer(self, set)
    }

    /// The stored belief record of a set (as recorded, no derivation).
    #[must_use]
    pub fn record(&self, set: &LandmarkSet) -> Option<&TripletBelief> {
        self.beliefs.get(set)
    }

    /// Mean entropy over recorded sets (eq. 2.11); `None` for an empty map.
    #[must_use]
    pub fn mean_entropy(&self) -> Option<f64> {
        if self.beliefs.is_empty() {
            return None;
        }
        Some(
            self.beliefs
                .values()
                .map(TripletBelief::entropy)
                .sum::<f64>()
                / self.beliefs.len() as f64,
        )
    }

    /// Combines another map of the same calculus into this one: sets in both get the
    /// product of the two beliefs (both started from their own first observation, so the
    /// product is the posterior of all observations under the filter's uniform prior), sets
    /// in one map are copied.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when the calculi differ.
    pub fn merge(&mut self, other: &Pqrm) -> Result<()> {
        if self.calculus.spec() != other.calculus.spec() {
            return Err(PqrmError::Mismatch(format!(
                "cannot merge a `{}` map into a `{}` map",
                other.calculus.name(),
                self.calculus.name()
            )));
        }
        for (set, b) in &other.beliefs {
            match self.beliefs.get_mut(set) {
                None => {
                    self.beliefs.insert(*set, b.clone());
                }
                Some(mine) => {
                    let post: Vec<f64> = mine
                        .log_p
                        .iter()
                        .zip(&b.log_p)
                        .map(|(x, y)| x + y)
                        .collect();
                    if post.iter().any(|v| *v > f64::NEG_INFINITY) {
                        mine.log_p = normalise(post);
                    }
                    mine.updates += b.updates;
                }
            }
        }
        self.steps += other.steps;
        Ok(())
    }

    /// The map as versioned JSON (calculus spec included, so a learned calculus travels
    /// with its map).
    ///
    /// # Errors
    /// [`PqrmError::Format`] if serialisation fails.
    pub fn to_json(&self) -> Result<String> {
        let saved = SavedMap {
            format: "qrm-pqrm".into(),
            version: FORMAT_VERSION,
            calculus: self.calculus.spec().clone(),
            config: self.config,
            steps: self.steps,
            sets: self
                .beliefs
                .iter()
                .map(|(s, b)| SavedSet {
                    set: s.ids(),
                    updates: b.updates,
                    log_p: b.log_p.iter().map(|l| l.max(-1e300)).collect(),
                })
                .collect(),
        };
        serde_json::to_string(&saved).map_err(|e| PqrmError::Format(e.to_string()))
    }

    /// Reads a map written by [`Pqrm::to_json`].
    ///
    /// # Errors
    /// [`PqrmError::Format`] for malformed JSON, another format or version, or beliefs that
    /// do not fit the calculus; calculus errors for a bad embedded spec.
    pub fn from_json(text: &str) -> Result<Self> {
        let saved: SavedMap =
            serde_json::from_str(text).map_err(|e| PqrmError::Format(e.to_string()))?;
        if saved.format != "qrm-pqrm" || saved.version != FORMAT_VERSION {
            return Err(PqrmError::Format(format!(
                "expected qrm-pqrm version {FORMAT_VERSION}, found {} version {}",
                saved.format, saved.version
            )));
        }
        let calculus = Calculus::from_spec(saved.calculus)?;
        let mut map = Self::new(calculus, saved.config)?;
        map.steps = saved.steps;
        let q = map.calculus.n_states();
        for s in saved.sets {
            let total: f64 = s.log_p.iter().map(|v| v.exp()).sum();
            if s.log_p.len() != q
                || s.log_p.iter().any(|v| v.is_nan() || *v > 1e-9)
                || (total - 1.0).abs() > 1e-6
            {
                return Err(PqrmError::Format(format!(
                    "set {:?}: not a normalised log-distribution over {q} states",
                    s.set
                )));
            }
            let set = LandmarkSet(s.set.map(LandmarkId));
            // Stored as saved (already normalised): a save/load round trip is exact.
            map.beliefs.insert(
                set,
                TripletBelief {
                    log_p: s.log_p,
                    updates: s.updates,
                },
            );
        }
        Ok(map)
    }

    /// Saves to a file (written to a temporary file and renamed: never half-written).
    ///
    /// # Errors
    /// [`PqrmError::Io`].
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = self.to_json()?;
        let tmp = path.with_extension("json.tmp");
        let io = |source| PqrmError::Io {
            path: path.to_path_buf(),
            source,
        };
        std::fs::write(&tmp, text).map_err(io)?;
        std::fs::rename(&tmp, path).map_err(io)
    }

    /// Loads a saved map.
    ///
    /// # Errors
    /// [`PqrmError::Io`], then as [`Pqrm::from_json`].
    pub fn load(path: &Path) -> Result<Self> {
        let text = qsr_core::text_file::read_text(path, qsr_core::text_file::MAX_INPUT_BYTES)
            .map_err(|source| PqrmError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        // Name the file in format errors (the I/O error above names it already).
        Self::from_json(&text).map_err(|e| match e {
            PqrmError::Format(m) => PqrmError::Format(format!("{}: {m}", path.display())),
            other => other,
        })
    }
}

/// Log-sum-exp normalisation (`-inf` entries stay `-inf`). Never returns NaN: entries of
/// `+inf` share all the probability (they dominate every finite one), NaN entries count as
/// impossible (`-inf`), and a vector with no possible entry becomes uniform.
#[must_use]
pub fn normalise(mut log_p: Vec<f64>) -> Vec<f64> {
    let n = log_p.len();
    log_p
        .iter_mut()
        .filter(|v| v.is_nan())
        .for_each(|v| *v = f64::NEG_INFINITY);
    let infinite = log_p.iter().filter(|v| **v == f64::INFINITY).count();
    if infinite > 0 {
        let share = -(infinite as f64).ln();
        log_p.iter_mut().for_each(|v| {
            *v = if *v == f64::INFINITY {
                share
            } else {
                f64::NEG_INFINITY
            };
        });
        return log_p;
    }
    let max = log_p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        let u = -(n as f64).ln();
        log_p.iter_mut().for_each(|v| *v = u);
        return log_p;
    }
    let z = max + log_p.iter().map(|v| (v - max).exp()).sum::<f64>().ln();
    log_p.iter_mut().for_each(|v| *v -= z);
    log_p
}
