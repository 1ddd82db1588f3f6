//! [`Pqrm`]: the probabilistic qualitative relational map and its recursive Bayes filter
//! (thesis eq. 2.10, Algorithm 1).
//!
//! Each landmark set keeps `ln p(R = q | Z_1:t)`. An update adds the step's log-likelihood
//! and renormalises with log-sum-exp, so 10^7 updates never underflow. Sets seen for the
//! first time start from their first observation; sets not seen in a step are unchanged.

use std::io::Write;
use std::path::Path;

use qsr_core::{Calculus, Permutation, StateId};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::evidence::EvidenceModel;
use crate::likelihood::{LandmarkSet, Orderings, StepCounts, log_likelihood, step_counts_into};
use crate::map_file::{self, MapFormat, MapHeader, MapParts, MapSource};
use crate::observation::{LandmarkId, Scan};
use crate::sampler::ScanSamples;
use crate::store::BeliefStore;

pub use crate::config::{MAX_SAMPLES, PqrmConfig, check_samples};
pub use crate::map_file::FORMAT_VERSION;

/// Entropy `−Σ p ln p` in nats (`0 ln 0 = 0`).
#[must_use]
pub fn entropy(p: &[f64]) -> f64 {
    p.iter().filter(|&&v| v > 0.0).map(|&v| -v * v.ln()).sum()
}

/// Entropy in nats of the distribution `p ∝ exp(w)` (`w` need not be normalised), with one
/// `exp` per state and one logarithm: with `m = max w`, `eᵢ = exp(wᵢ − m)` and
/// `ε = Σ eᵢ − 1` (the states but one maximum), `H = ln(1 + ε) − Σ eᵢ (wᵢ − m) / (1 + ε)`.
/// A sharp belief's entropy is then as precise as its small terms (`ε` is summed apart from
/// the 1, so no digit is lost to `1 + ε`), and a map's mean entropy costs half the `exp`
/// and none of the `ln` per state of normalising then `−Σ p ln p` (13 % of mapping 10⁶
/// sets before). `-inf` weights are impossible states (`0 ln 0 = 0`); NaN counts as
/// impossible and `+inf` entries share the probability, as [`normalise`] reads them.
#[must_use]
pub fn entropy_of_log_weights(w: &[f64]) -> f64 {
    let m = w
        .iter()
        .copied()
        .filter(|v| !v.is_nan())
        .fold(f64::NEG_INFINITY, f64::max);
    if !m.is_finite() {
        // every state impossible (uniform, as `normalise` reads it) or `+inf` entries
        // sharing the probability: the entropy of a uniform over them
        let n = if m == f64::INFINITY {
            w.iter().filter(|v| **v == f64::INFINITY).count()
        } else {
            w.len()
        };
        return if n > 1 { (n as f64).ln() } else { 0.0 };
    }
    let (mut eps, mut weighted, mut max_seen) = (0.0f64, 0.0f64, false);
    let mut exp_of = LastExp::new();
    for &v in w {
        let d = v - m;
        if d == 0.0 && !max_seen {
            max_seen = true; // the 1 of the sum, kept apart
            continue;
        }
        // NaN and -inf compare false: impossible; below −746 `exp` is 0
        if d >= UNDERFLOW {
            let e = exp_of.get(d);
            eps += e;
            weighted += e * d;
        }
    }
    (eps.ln_1p() - weighted / (1.0 + eps)).max(0.0)
}

/// `exp` with its last argument remembered. A map's beliefs hold many *equal* log-weights:
/// every state a set's frames never showed gains the same evidence each step (`ln` of the
/// floor's count), so after k steps a settled set has its other states all at one value —
/// each `exp` of it is the same number, computed once. The same function of the same
/// argument: results bit for bit. (libm's `exp` was 16 % of mapping 10⁶ sets in all
/// orderings.)
#[derive(Debug, Clone, Copy)]
struct LastExp {
    arg: f64,
    value: f64,
}

impl LastExp {
    fn new() -> Self {
        Self {
            arg: 0.0,
            value: 1.0,
        }
    }

    #[inline]
    fn get(&mut self, d: f64) -> f64 {
        if d != self.arg {
            self.arg = d;
            self.value = d.exp();
        }
        self.value
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
        entropy_of_log_weights(&self.log_p)
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
///
/// The beliefs live in one flat table (the private `store` module: log-probabilities rounded
/// to `f32` between steps, ≈ 120 bytes per EDC set); every update computes in `f64`.
#[derive(Debug, Clone)]
pub struct Pqrm {
    calculus: Calculus,
    config: PqrmConfig,
    store: BeliefStore,
    steps: u64,
    evidence: EvidenceModel,
    /// Boxed: a map is passed around by value, its scratch need not be.
    buffers: Box<StepBuffers>,
}

/// The tables a step fills, kept from one step to the next: a step over 10⁶ sets then writes
/// into memory the map already holds (the counts alone are 80 MB for EDC) instead of
/// faulting in fresh pages — 7 % of mapping 10⁶ sets (`map_scaling.py`) was the kernel
/// handing out zeroed pages. Not part of the map: a clone starts without them.
#[derive(Default)]
struct StepBuffers {
    counts: StepCounts,
    found: Vec<Option<usize>>,
    slots: Vec<usize>,
    fresh: Vec<bool>,
    seen: Vec<bool>,
}

impl Clone for StepBuffers {
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for StepBuffers {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("StepBuffers")
    }
}

/// Sets whose posteriors are computed together between two writes into the store: enough
/// for both cores, small enough that the block's buffer stays in cache.
const UPDATE_BLOCK: usize = 8192;

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
        let store = BeliefStore::new(calculus.n_states());
        Ok(Self {
            calculus,
            config,
            store,
            steps: 0,
            evidence: EvidenceModel::Independent,
            buffers: Box::default(),
        })
    }

    /// The map read under another evidence model ([`crate::evidence`]): the stored sums of
    /// eq. 2.10 are unchanged, so it can be switched at any time, back and forth.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for a shared-error model out of range.
    pub fn with_evidence(mut self, evidence: EvidenceModel) -> Result<Self> {
        evidence.validate()?;
        // a layout map's rows are beliefs, a filter's are sums: neither reads as the other
        let layout = |m: EvidenceModel| m == EvidenceModel::Layout;
        if !self.is_empty() && layout(evidence) != layout(self.evidence) {
            return Err(PqrmError::InvalidConfig(format!(
                "a map under `{}` cannot be read as `{evidence}`: a layout map's rows are the \
                 layout's beliefs, a filter's are eq. 2.10's sums (map the recording again)",
                self.evidence
            )));
        }
        self.evidence = evidence;
        Ok(self)
    }

    /// `Err` for a layout map ([`EvidenceModel::Layout`]): its beliefs come from the whole
    /// recording at once, so no frame or map can be folded into them.
    fn expect_filter(&self, what: &str) -> Result<()> {
        if self.evidence == EvidenceModel::Layout {
            return Err(PqrmError::InvalidConfig(format!(
                "cannot {what} a layout map: its beliefs come from the layout of a whole \
                 recording (fit the layout again over all the frames: `qrm map --evidence \
                 layout`, `pqrm::layout::Layout::map`)"
            )));
        }
        Ok(())
    }

    /// A layout map ([`EvidenceModel::Layout`]) of the given rows: each set, the frames that
    /// saw it, its belief (normalised, every state possible).
    pub(crate) fn from_beliefs(
        calculus: Calculus,
        config: PqrmConfig,
        steps: u64,
        rows: Vec<crate::layout::SetBelief>,
    ) -> Result<Self> {
        let mut map = Self::new(calculus, config)?.with_evidence(EvidenceModel::Layout)?;
        map.steps = steps;
        map.store.reserve_exact(rows.len());
        for (set, updates, belief) in rows {
            if map.store.slot(&set).is_some() {
                return Err(PqrmError::Mismatch(format!(
                    "set {:?} given twice",
                    set.ids()
                )));
            }
            let row: Vec<f64> = belief.iter().map(|p| p.ln()).collect();
            map.store.push(set, &normalise(row), updates);
        }
        Ok(map)
    }

    /// How the frames of a set combine into its belief (eq. 2.10 unless set).
    #[must_use]
    pub fn evidence(&self) -> EvidenceModel {
        self.evidence
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
        self.store.len()
    }

    /// Whether no set has been recorded.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.store.len() == 0
    }

    /// Bytes the beliefs take in memory (tables and index, by capacity).
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        self.store.heap_bytes()
    }

    /// Frees the tables kept from one step to the next for the next one (about
    /// `4·Q + 38` bytes per set of a step: as much again as the beliefs of a map whose
    /// steps see every set). Call it when a map is done growing; the next step allocates
    /// them again.
    pub fn release_step_buffers(&mut self) {
        *self.buffers = StepBuffers::default();
    }

    /// The belief of one set, if recorded (as recorded: see [`Pqrm::belief`] for the
    /// orderings a canonical map derives).
    #[must_use]
    pub fn get(&self, set: &LandmarkSet) -> Option<TripletBelief> {
        self.store.slot(set).map(|slot| self.belief_at(slot))
    }

    fn belief_at(&self, slot: usize) -> TripletBelief {
        let updates = self.store.updates(slot);
        // the row is eq. 2.10's sum; the evidence model reads it with its exponent
        let tau = self.evidence.exponent(updates);
        let mut log_p: Vec<f64> = self
            .store
            .row(slot)
            .iter()
            .map(|&v| tau * f64::from(v))
            .collect();
        // stored as f32, normalised to f32's precision: renormalised in f64 so that a
        // belief handed out sums to one as closely as an f64 can
        normalise_in_place(&mut log_p);
        TripletBelief { log_p, updates }
    }

    /// Recorded sets and their beliefs, in set order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (&LandmarkSet, TripletBelief)> + '_ {
        self.store
            .sorted_slots()
            .into_iter()
            .map(|slot| (self.store.set(slot), self.belief_at(slot)))
    }

    /// One time step: sample every observed landmark once, compute `p(R | Z_t)` for every
    /// set of three observed landmarks, and fold it into the map.
    ///
    /// # Errors
    /// [`PqrmError::CoincidentLandmarks`] (nothing is changed then).
    pub fn update(&mut self, scan: &Scan) -> Result<UpdateReport> {
        self.expect_filter("add frames to")?;
        let samples = ScanSamples::draw_with(
            scan,
            self.config.samples,
            self.config.seed,
            self.steps,
            self.config.sensor,
        );
        let mut counts = std::mem::take(&mut self.buffers.counts);
        let report = step_counts_into(&self.calculus, &samples, self.config.orderings, &mut counts)
            .and_then(|()| self.apply_counts(&counts));
        self.buffers.counts = counts;
        report
    }

    /// Folds precomputed histograms (one step's evidence) into the map and advances the step
    /// counter: how a study maps several calculi from one sampling of the finest one.
    ///
    /// Sets are found (or given a slot) in order, then their posteriors are computed in
    /// parallel blocks and written back: the result does not depend on the thread count. A
    /// set listed twice in one step is folded in twice, in order.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when the histograms have the wrong number of states.
    pub fn apply_counts(&mut self, counts: &StepCounts) -> Result<UpdateReport> {
        self.expect_filter("add frames to")?;
        let mut buffers = std::mem::take(&mut self.buffers);
        let report = self.fold_counts(counts, &mut buffers);
        self.buffers = buffers;
        report
    }

    /// [`Pqrm::apply_counts`] with the step's index tables in `buffers`.
    fn fold_counts(
        &mut self,
        counts: &StepCounts,
        buffers: &mut StepBuffers,
    ) -> Result<UpdateReport> {
        let q = self.calculus.n_states();
        if counts.n_states() != q && !counts.is_empty() {
            return Err(PqrmError::Mismatch(format!(
                "{} counts per set for a {q}-state calculus",
                counts.n_states()
            )));
        }
        let evidence = Evidence::new(self.config.floor, self.config.temper, counts);
        let mut report = UpdateReport {
            observed: counts.len(),
            ..UpdateReport::default()
        };
        let repeated = self.slots_for(counts, buffers);
        let (slots, fresh) = (&buffers.slots, &buffers.fresh);
        report.new = fresh.iter().filter(|f| **f).count();
        if repeated {
            // a set twice in one step: its second update needs the first one's result
            for (i, (&slot, &new)) in slots.iter().zip(fresh).enumerate() {
                let mut ll = vec![0.0; q];
                evidence.fill(counts.counts(i), &mut ll);
                let mut post = vec![0.0; q];
                let prior = (!new || self.store.updates(slot) > 0).then(|| self.store.row(slot));
                report.conflicts += usize::from(posterior(prior, &ll, &mut post));
                let updates = self.store.updates(slot) + 1;
                self.store.set_row(slot, &post, updates);
            }
            self.steps += 1;
            return Ok(report);
        }
        let mut buffer = vec![0.0f32; UPDATE_BLOCK.min(counts.len()) * q];
        for start in (0..counts.len()).step_by(UPDATE_BLOCK) {
            let len = UPDATE_BLOCK.min(counts.len() - start);
            let store = &self.store;
            let (slots, fresh) = (&slots[start..start + len], &fresh[start..start + len]);
            let conflicts: usize = buffer[..len * q]
                .par_chunks_mut(q.max(1))
                .with_min_len(256)
                .enumerate()
                .map_init(
                    || (vec![0.0; q], vec![0.0; q]),
                    |(ll, post), (t, out)| {
                        evidence.fill(counts.counts(start + t), ll);
                        let prior = (!fresh[t]).then(|| store.row(slots[t]));
                        usize::from(posterior_stored(prior, ll, post, out))
                    },
                )
                .sum();
            report.conflicts += conflicts;
            for (t, &slot) in slots.iter().enumerate() {
                let updates = self.store.updates(slot) + 1;
                self.store
                    .set_stored_row(slot, &buffer[t * q..(t + 1) * q], updates);
            }
        }
        self.steps += 1;
        Ok(report)
    }

    /// Each set's slot in the store and whether it is new (into `buffers.slots` and
    /// `buffers.fresh`); true when a set is listed twice. Slots are looked up in parallel
    /// (read-only), then new sets get a slot in order (serial: the index is one hash table);
    /// a new set's prior is ignored.
    fn slots_for(&mut self, counts: &StepCounts, buffers: &mut StepBuffers) -> bool {
        let q = self.calculus.n_states();
        let store = &self.store;
        let StepBuffers {
            found,
            slots,
            fresh,
            seen,
            ..
        } = buffers;
        counts
            .sets()
            .par_iter()
            .with_min_len(4096)
            .map(|s| store.slot(s))
            .collect_into_vec(found);
        let new_sets = found.iter().filter(|f| f.is_none()).count();
        self.store.reserve_exact(new_sets);
        slots.clear();
        fresh.clear();
        seen.clear();
        seen.resize(self.store.len() + new_sets, false);
        let mut repeated = false;
        let uniform = vec![0.0; q];
        for (&set, &found) in counts.sets().iter().zip(found.iter()) {
            let (slot, new) = match found {
                Some(slot) => (slot, false),
                // a set listed twice in one step is new only the first time
                None => self.store.slot_or_push(set, &uniform, 0),
            };
            repeated |= std::mem::replace(&mut seen[slot], true);
            slots.push(slot);
            fresh.push(new);
        }
        repeated
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
        if let Some(b) = self.get(&set) {
            return Some(b.probabilities());
        }
        if self.config.orderings != Orderings::Canonical {
            return None;
        }
        let [a, b, c] = set.0;
        let mut sorted = [a, b, c];
        sorted.sort();
        let stored = self.get(&LandmarkSet(sorted))?;
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
    pub fn retain(&mut self, keep: impl FnMut(&LandmarkSet) -> bool) {
        self.store.retain(keep);
    }

    /// Predicts `{a,b:d}` from the other beliefs of the map by composition (see
    /// [`crate::reason`]), with the default options.
    ///
    /// # Errors
    /// As [`crate::reason::infer`].
    pub fn infer(&self, set: LandmarkSet) -> Result<crate::reason::Inference> {
        crate::reason::infer(self, set)
    }

    /// The stored belief record of a set (as recorded, no derivation).
    #[must_use]
    pub fn record(&self, set: &LandmarkSet) -> Option<TripletBelief> {
        self.get(set)
    }

    /// Mean entropy over recorded sets (eq. 2.11); `None` for an empty map.
    ///
    /// The entropies are summed exactly, in fixed point (units of 2⁻⁸⁰ nats, far below an
    /// `f64`'s resolution of the mean), so the sum depends neither on the order of the sets —
    /// a mapped map's insertion order or a loaded one's set order — nor on the threads that
    /// add it: no sort of the sets is needed (it was a third of this function's time at 10⁶
    /// sets), and the sets are read in parallel.
    #[must_use]
    pub fn mean_entropy(&self) -> Option<f64> {
        if self.is_empty() {
            return None;
        }
        const UNIT: f64 = (1u128 << 80) as f64;
        let q = self.calculus.n_states();
        let total: u128 = (0..self.store.len())
            .into_par_iter()
            .with_min_len(4096)
            .map_init(
                || vec![0.0; q],
                |w, slot| {
                    // the belief `belief_at` hands out, without normalising it first
                    let tau = self.evidence.exponent(self.store.updates(slot));
                    for (w, &v) in w.iter_mut().zip(self.store.row(slot)) {
                        *w = tau * f64::from(v);
                    }
                    // at most ln Q·2⁸⁰ < 2⁸⁴ a set (Q ≤ 2¹⁶): 2⁴⁴ sets before u128 fills
                    (entropy_of_log_weights(w) * UNIT) as u128
                },
            )
            .sum();
        Some(total as f64 / UNIT / self.store.len() as f64)
    }

    /// Combines another map of the same calculus into this one: sets in both get the
    /// product of the two beliefs (both started from their own first observation, so the
    /// product is the posterior of all observations under the filter's uniform prior), sets
    /// in one map are copied.
    ///
    /// The merged map reads its beliefs under *this* map's evidence model
    /// ([`Pqrm::evidence`]); `other`'s is not consulted. Both store eq. 2.10's sums, so the
    /// merged rows are the same whichever model either map was read under, and
    /// [`Pqrm::with_evidence`] switches the reading afterwards.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when the calculi differ.
    pub fn merge(&mut self, other: &Pqrm) -> Result<()> {
        self.expect_filter("merge into")?;
        other.expect_filter("merge")?;
        if self.calculus.spec() != other.calculus.spec() {
            return Err(PqrmError::Mismatch(format!(
                "cannot merge a `{}` map into a `{}` map",
                other.calculus.name(),
                self.calculus.name()
            )));
        }
        for slot in other.store.sorted_slots() {
            let set = *other.store.set(slot);
            let theirs = other.store.row(slot);
            let their_updates = other.store.updates(slot);
            match self.store.slot(&set) {
                None => {
                    let row: Vec<f64> = theirs.iter().map(|&v| f64::from(v)).collect();
                    self.store.push(set, &row, their_updates);
                }
                Some(mine) => {
                    let post: Vec<f64> = self
                        .store
                        .row(mine)
                        .iter()
                        .zip(theirs)
                        .map(|(x, y)| f64::from(*x) + f64::from(*y))
                        .collect();
                    let updates = self.store.updates(mine) + their_updates;
                    if post.iter().any(|v| *v > f64::NEG_INFINITY) {
                        self.store.set_row(mine, &normalise(post), updates);
                    } else {
                        let kept: Vec<f32> = self.store.row(mine).to_vec();
                        self.store.set_stored_row(mine, &kept, updates);
                    }
                }
            }
        }
        self.steps += other.steps;
        Ok(())
    }

    /// The map as the file writers read it: header and rows in set order, in place.
    fn source(&self) -> MapSource<'_> {
        MapSource {
            header: MapHeader {
                calculus: self.calculus.spec().clone(),
                config: self.config,
                steps: self.steps,
                evidence: self.evidence,
            },
            n_states: self.calculus.n_states(),
            rows: self
                .store
                .sorted_slots()
                .into_iter()
                .map(|s| {
                    (
                        self.store.set(s).ids(),
                        self.store.updates(s),
                        self.store.row(s),
                    )
                })
                .collect(),
        }
    }

    /// A map from a file's contents, checked: every row a normalised log-distribution over
    /// the calculus's states, every set of three distinct ids, no set twice.
    ///
    /// # Errors
    /// [`PqrmError::Format`] naming the first bad set; calculus errors for a bad spec.
    pub(crate) fn from_parts(parts: MapParts) -> Result<Self> {
        let calculus = Calculus::from_spec(parts.header.calculus)?;
        let mut map =
            Self::new(calculus, parts.header.config)?.with_evidence(parts.header.evidence)?;
        map.steps = parts.header.steps;
        let q = map.calculus.n_states();
        let n = parts.sets.len();
        if parts.updates.len() != n || parts.log_p.len() != n * q {
            return Err(PqrmError::Format(format!(
                "{n} sets but {} update counts and {} log-probabilities ({q} states each)",
                parts.updates.len(),
                parts.log_p.len()
            )));
        }
        // the check is per row and independent: in parallel, the first bad row reported
        let bad = parts
            .log_p
            .par_chunks(q.max(1))
            .position_first(|row| !is_log_distribution(row));
        if let Some(i) = bad {
            return Err(PqrmError::Format(format!(
                "set {:?}: not a normalised log-distribution over {q} states",
                parts.sets[i]
            )));
        }
        map.store.reserve_exact(n);
        for (i, ids) in parts.sets.iter().enumerate() {
            // A set relates three landmarks: one with a repeated id has no state in any
            // calculus, and every later stage (networks, reasoning, merging) assumes three.
            if ids[0] == ids[1] || ids[0] == ids[2] || ids[1] == ids[2] {
                return Err(PqrmError::Format(format!(
                    "set {ids:?} repeats a landmark id (a set relates three distinct landmarks)"
                )));
            }
            let set = LandmarkSet(ids.map(LandmarkId));
            if map.store.slot(&set).is_some() {
                return Err(PqrmError::Format(format!("set {ids:?} is recorded twice")));
            }
            let row: Vec<f64> = parts.log_p[i * q..(i + 1) * q]
                .iter()
                .map(|&v| f64::from(v))
                .collect();
            // stored as saved (f32 in, f32 kept): a save/load round trip is exact
            map.store.push(set, &row, parts.updates[i]);
        }
        Ok(map)
    }

    /// The map as versioned JSON (calculus spec included, so a learned calculus travels
    /// with its map). For large maps prefer [`Pqrm::to_binary`] (a tenth of the size, read
    /// ten times faster).
    ///
    /// # Errors
    /// [`PqrmError::Format`] if serialisation fails.
    pub fn to_json(&self) -> Result<String> {
        let mut out = Vec::new();
        map_file::write_json(&self.source(), &mut out)?;
        String::from_utf8(out).map_err(|e| PqrmError::Format(e.to_string()))
    }

    /// Reads a map written by [`Pqrm::to_json`].
    ///
    /// # Errors
    /// [`PqrmError::Format`] for malformed JSON, another format or version, or beliefs that
    /// do not fit the calculus; calculus errors for a bad embedded spec.
    pub fn from_json(text: &str) -> Result<Self> {
        Self::from_parts(map_file::read_json(text)?)
    }

    /// The map in the binary format of [`crate::map_file`] (header, little-endian tables,
    /// CRC-32).
    ///
    /// # Errors
    /// [`PqrmError::Format`] if the header cannot be serialised.
    pub fn to_binary(&self) -> Result<Vec<u8>> {
        let mut out = Vec::new();
        map_file::write_binary(&self.source(), &mut out)?;
        Ok(out)
    }

    /// Reads a map written by [`Pqrm::to_binary`].
    ///
    /// # Errors
    /// [`PqrmError::Format`] naming the field for a wrong magic, version, size, checksum or
    /// belief.
    pub fn from_binary(bytes: &[u8]) -> Result<Self> {
        Self::from_parts(map_file::decode_binary(bytes)?)
    }

    /// Saves to a file in the format its extension names ([`MapFormat::from_path`]:
    /// `.pqrm` binary, anything else JSON), written to a temporary file and renamed: never
    /// half-written.
    ///
    /// # Errors
    /// [`PqrmError::Io`].
    pub fn save(&self, path: &Path) -> Result<()> {
        self.save_as(path, MapFormat::from_path(path))
    }

    /// Saves in the given format (see [`Pqrm::save`]).
    ///
    /// # Errors
    /// [`PqrmError::Io`].
    pub fn save_as(&self, path: &Path, format: MapFormat) -> Result<()> {
        let io = |source| PqrmError::Io {
            path: path.to_path_buf(),
            source,
        };
        let mut name = path.file_name().unwrap_or_default().to_os_string();
        name.push(".tmp");
        let tmp = path.with_file_name(name);
        let file = std::fs::File::create(&tmp).map_err(io)?;
        let mut w = std::io::BufWriter::new(file);
        let source = self.source();
        let written = match format {
            MapFormat::Json => map_file::write_json(&source, &mut w),
            MapFormat::Binary => map_file::write_binary(&source, &mut w),
        }
        .and_then(|()| w.flush().map_err(io));
        if let Err(e) = written {
            let _ = std::fs::remove_file(&tmp);
            return Err(e);
        }
        std::fs::rename(&tmp, path).map_err(io)
    }

    /// Loads a saved map, JSON or binary (told apart by the binary format's magic bytes).
    ///
    /// # Errors
    /// [`PqrmError::Io`], then as [`Pqrm::from_json`] or [`Pqrm::from_binary`], with the
    /// file named.
    pub fn load(path: &Path) -> Result<Self> {
        let io = |source| PqrmError::Io {
            path: path.to_path_buf(),
            source,
        };
        let bytes = read_capped(path).map_err(io)?;
        let parsed = if map_file::is_binary(&bytes) {
            Self::from_binary(&bytes)
        } else {
            let text = String::from_utf8(bytes).map_err(|e| {
                io(std::io::Error::new(
                    std::io::ErrorKind::InvalidData,
                    format!("not UTF-8 JSON nor a binary map: {e}"),
                ))
            })?;
            Self::from_json(&text)
        };
        // Name the file in format errors (the I/O error above names it already).
        parsed.map_err(|e| match e {
            PqrmError::Format(m) => PqrmError::Format(format!("{}: {m}", path.display())),
            other => other,
        })
    }
}

/// Reads a whole file, refusing one above [`qsr_core::text_file::MAX_INPUT_BYTES`] before
/// reading it.
fn read_capped(path: &Path) -> std::io::Result<Vec<u8>> {
    let len = std::fs::metadata(path)?.len();
    if len > qsr_core::text_file::MAX_INPUT_BYTES {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "{len} bytes is over the {} byte limit for a map",
                qsr_core::text_file::MAX_INPUT_BYTES
            ),
        ));
    }
    std::fs::read(path)
}

/// Whether a stored row is a normalised log-distribution (what every loaded row must be).
fn is_log_distribution(row: &[f32]) -> bool {
    let total: f64 = row.iter().map(|&v| f64::from(v).exp()).sum();
    row.iter().all(|v| !v.is_nan() && f64::from(*v) <= 1e-6) && (total - 1.0).abs() <= 1e-5
}

/// One step's log-likelihoods per set: `ln((count + α) / (s + αQ))`, tempered. Every set of
/// a step has the same sample count `s`, so the logarithms come from a table of `s + 1`
/// values computed once per step (the same expression as [`log_likelihood`], so the same
/// bits); a set with another total is computed directly.
struct Evidence {
    floor: f64,
    temper: f64,
    /// The total the table is for, and `ln((c + α)/total)` for `c = 0..=total`.
    table: Option<(u64, Vec<f64>)>,
}

impl Evidence {
    fn new(floor: f64, temper: f64, counts: &StepCounts) -> Self {
        let q = counts.n_states();
        let table = (!counts.is_empty())
            .then(|| counts.counts(0).iter().map(|&c| u64::from(c)).sum::<u64>())
            .filter(|&total| total as usize <= counts.len() * q)
            .map(|total| {
                // `log_likelihood`'s entry for a bin of `c` out of `total`, term for term: its
                // sum of the counts is exact (integers below 2^53), so one logarithm per
                // count replaces a whole histogram's (the profile's top after the kernel)
                let floor = if floor.is_finite() && floor > 0.0 {
                    floor
                } else {
                    0.0
                };
                let sum = total as f64 + floor * q.max(1) as f64;
                let values = (0..=total)
                    .map(|c| {
                        if sum <= 0.0 {
                            -(q.max(1) as f64).ln()
                        } else {
                            ((c as f64 + floor) / sum).ln()
                        }
                    })
                    .collect();
                (total, values)
            });
        Self {
            floor,
            temper,
            table,
        }
    }

    fn fill(&self, counts: &[u32], out: &mut [f64]) {
        let total: u64 = counts.iter().map(|&c| u64::from(c)).sum();
        match &self.table {
            Some((t, values)) if *t == total => {
                for (o, &c) in out.iter_mut().zip(counts) {
                    *o = values[c as usize];
                }
            }
            _ => out.copy_from_slice(&log_likelihood(counts, self.floor)),
        }
        if self.temper != 1.0 {
            out.iter_mut().for_each(|v| *v *= self.temper);
        }
    }
}

/// The filter's step for one set (eq. 2.10) into `out`: the normalised sum of the prior and
/// the evidence, or the evidence alone for a new set — or when the two contradict each other
/// completely (possible only with `floor = 0`), which is reported as a conflict.
fn posterior(prior: Option<&[f32]>, ll: &[f64], out: &mut [f64]) -> bool {
    let mut conflict = false;
    match prior {
        None => out.copy_from_slice(ll),
        Some(prior) => {
            for ((o, p), l) in out.iter_mut().zip(prior).zip(ll) {
                *o = f64::from(*p) + l;
            }
            if out.iter().all(|v| *v == f64::NEG_INFINITY) {
                conflict = true;
                out.copy_from_slice(ll);
            }
        }
    }
    normalise_in_place(out);
    conflict
}

/// [`posterior`] rounded into stored precision (`out`, [`crate::store`]'s `f32`), the same
/// values bit for bit in three passes instead of eight: the sum of prior and evidence with
/// its maximum, the exponentials, the normalised values rounded as they are written. A
/// vector that needs [`normalise_in_place`]'s special cases (a NaN or `+inf` entry, no
/// possible state, a conflict) takes the general path. (The passes were a third of the
/// filter's time, the filter a fifth of a 10-landmark step's.)
fn posterior_stored(prior: Option<&[f32]>, ll: &[f64], sums: &mut [f64], out: &mut [f32]) -> bool {
    match prior {
        None => sums.copy_from_slice(ll),
        Some(prior) => {
            for ((s, &p), &l) in sums.iter_mut().zip(prior).zip(ll) {
                *s = f64::from(p) + l;
            }
        }
    }
    let (max, special) = max_or_special(sums);
    if special || max == f64::NEG_INFINITY {
        let conflict = posterior(prior, ll, sums);
        for (o, v) in out.iter_mut().zip(sums.iter()) {
            *o = crate::store::to_stored(*v);
        }
        return conflict;
    }
    let z = log_sum_exp(sums, max);
    for (o, v) in out.iter_mut().zip(sums.iter()) {
        *o = crate::store::to_stored(v - z);
    }
    false
}

/// The largest of `values` and whether one is NaN or `+inf` (then the largest means
/// nothing). Four running maxima by comparison, not `f64::max`: its NaN rule made one chain of
/// four dependent operations per value, half of the filter's time
/// (`examples/step_timing.rs`: the filter 0.060 → 0.043 ms a step); NaN is caught by the flag
/// instead.
#[inline]
fn max_or_special(values: &[f64]) -> (f64, bool) {
    let mut max = [f64::NEG_INFINITY; 4];
    let mut special = false;
    let mut quads = values.chunks_exact(4);
    for quad in &mut quads {
        for (m, &v) in max.iter_mut().zip(quad) {
            *m = if v > *m { v } else { *m };
            special |= v.is_nan() | (v == f64::INFINITY);
        }
    }
    for &v in quads.remainder() {
        max[0] = if v > max[0] { v } else { max[0] };
        special |= v.is_nan() | (v == f64::INFINITY);
    }
    let [a, b, c, d] = max;
    let (ab, cd) = (if a > b { a } else { b }, if c > d { c } else { d });
    (if ab > cd { ab } else { cd }, special)
}

/// Log-sum-exp normalisation (`-inf` entries stay `-inf`). Never returns NaN: entries of
/// `+inf` share all the probability (they dominate every finite one), NaN entries count as
/// impossible (`-inf`), and a vector with no possible entry becomes uniform.
#[must_use]
pub fn normalise(mut log_p: Vec<f64>) -> Vec<f64> {
    normalise_in_place(&mut log_p);
    log_p
}

/// Below this, `exp` underflows to 0 (its smallest subnormal result is at about −745.13).
const UNDERFLOW: f64 = -746.0;

/// [`normalise`] without allocating.
pub fn normalise_in_place(log_p: &mut [f64]) {
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
        return;
    }
    let max = log_p.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        let u = -(n as f64).ln();
        log_p.iter_mut().for_each(|v| *v = u);
        return;
    }
    let z = log_sum_exp(log_p, max);
    log_p.iter_mut().for_each(|v| *v -= z);
}

/// `ln Σ exp(v)` of values without NaN or `+inf` whose largest is `max` (finite).
fn log_sum_exp(values: &[f64], max: f64) -> f64 {
    // below −745 `exp` is 0 in IEEE arithmetic anyway: skipping it keeps libm off its
    // underflow path (errno, and the SVID wrapper in manylinux builds), which a sharp belief
    // takes for most of its states at every step
    let mut exp_of = LastExp::new();
    max + values
        .iter()
        .map(|v| {
            let d = v - max;
            if d < UNDERFLOW { 0.0 } else { exp_of.get(d) }
        })
        .sum::<f64>()
        .ln()
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // tests: a panic is the failure report
    use super::*;

    /// The four-lane maximum is `f64::max`'s wherever no entry is NaN or `+inf`, for every
    /// length (the lanes and the remainder), and flags those entries wherever they are.
    #[test]
    fn the_lane_maximum_is_the_maximum_and_flags_nan_and_infinity() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(31);
        for _ in 0..20_000 {
            let len = rng.random_range(0..=11);
            let v: Vec<f64> = (0..len)
                .map(|_| match rng.random_range(0..8) {
                    0 => f64::NEG_INFINITY,
                    1 => f64::NAN,
                    2 => f64::INFINITY,
                    3 => -0.0,
                    _ => rng.random_range(-50.0..5.0),
                })
                .collect();
            let (max, special) = max_or_special(&v);
            let expect = v.iter().any(|x| x.is_nan() || *x == f64::INFINITY);
            assert_eq!(special, expect, "{v:?}");
            if !expect {
                let want = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                assert_eq!(max, want, "{v:?}");
            }
        }
    }

    /// The fused filter step stores what `posterior` then rounding stored, bit for bit, and
    /// reports the same conflicts: ordinary vectors, runs of equal values, entries far below
    /// the rest, and the special cases (NaN, `+inf`, all `-inf`, a prior that contradicts the
    /// evidence), with and without a prior.
    #[test]
    fn the_fused_filter_step_stores_what_the_plain_one_did() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(29);
        let special = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -800.0,
            0.0,
            -0.0,
        ];
        for case in 0..20_000 {
            let q = 1 + case % 23;
            let draw = |rng: &mut rand_chacha::ChaCha8Rng| -> f64 {
                match rng.random_range(0..10) {
                    0 => special[rng.random_range(0..special.len())],
                    1 => -3.5,
                    _ => rng.random_range(-900.0..5.0),
                }
            };
            let ll: Vec<f64> = (0..q).map(|_| draw(&mut rng)).collect();
            let prior: Vec<f32> = (0..q).map(|_| draw(&mut rng) as f32).collect();
            for prior in [None, Some(prior.as_slice())] {
                let mut plain = vec![0.0; q];
                let conflict = posterior(prior, &ll, &mut plain);
                let (mut sums, mut fused) = (vec![0.0; q], vec![0.0f32; q]);
                let fused_conflict = posterior_stored(prior, &ll, &mut sums, &mut fused);
                assert_eq!(conflict, fused_conflict, "case {case}");
                let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
                let stored: Vec<f32> = plain.iter().map(|&v| crate::store::to_stored(v)).collect();
                assert_eq!(
                    bits(&stored),
                    bits(&fused),
                    "case {case}: {prior:?} + {ll:?}"
                );
            }
        }
    }

    /// Remembering the last `exp` changes no bit: `normalise` and the entropy of vectors
    /// with runs of equal log-weights (as a map's settled sets have), interleaved with other
    /// values, zeros of both signs and values at the underflow edge, equal those computed
    /// with one `exp` per entry.
    #[test]
    fn equal_log_weights_share_one_exp_bit_for_bit() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let plain_normalise = |mut v: Vec<f64>| {
            let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let z = max
                + v.iter()
                    .map(|x| {
                        let d = x - max;
                        if d < UNDERFLOW { 0.0 } else { d.exp() }
                    })
                    .sum::<f64>()
                    .ln();
            v.iter_mut().for_each(|x| *x -= z);
            v
        };
        let plain_entropy = |w: &[f64]| {
            let m = w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let (mut eps, mut weighted, mut max_seen) = (0.0f64, 0.0f64, false);
            for &v in w {
                let d = v - m;
                if d == 0.0 && !max_seen {
                    max_seen = true;
                    continue;
                }
                if d >= UNDERFLOW {
                    let e = d.exp();
                    eps += e;
                    weighted += e * d;
                }
            }
            (eps.ln_1p() - weighted / (1.0 + eps)).max(0.0)
        };
        let mut cached = 0;
        for case in 0..3000 {
            let q = 2 + case % 20;
            let levels: Vec<f64> = (0..3)
                .map(|_| -rng.random_range(0.0..60.0))
                .chain([0.0, -0.0, UNDERFLOW, UNDERFLOW + 1e-9])
                .collect();
            let w: Vec<f64> = (0..q)
                .map(|_| levels[rng.random_range(0..levels.len())] + 3.0)
                .collect();
            cached += usize::from(w.windows(2).any(|p| p[0] == p[1]));
            let got = normalise(w.clone());
            let want = plain_normalise(w.clone());
            assert!(
                got.iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "{w:?}: {got:?} vs {want:?}"
            );
            assert_eq!(
                entropy_of_log_weights(&w).to_bits(),
                plain_entropy(&w).to_bits(),
                "{w:?}"
            );
        }
        assert!(cached > 1000, "runs of equal weights exercised: {cached}");
    }

    /// The entropy from log-weights is `−Σ p ln p` of the normalised belief, and keeps
    /// the digits of a sharp one (where `p_ML = 1 − ε` leaves `−p ln p` of the ML state
    /// at the mercy of rounding `1 − ε`).
    #[test]
    fn entropy_from_log_weights_is_the_beliefs_entropy() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let mut next = move || rng.random_range(0.0..1.0);
        for _ in 0..2000 {
            let q = 2 + (next() * 20.0) as usize;
            let shift = next() * 100.0 - 50.0;
            let spread = next() * 12.0;
            let w: Vec<f64> = (0..q).map(|_| shift - spread * next()).collect();
            let p: Vec<f64> = normalise(w.clone()).iter().map(|l| l.exp()).collect();
            let (got, want) = (entropy_of_log_weights(&w), entropy(&p));
            assert!(
                (got - want).abs() <= 1e-12 * (1.0 + want),
                "{w:?}: {got} vs {want}"
            );
        }
        // sharp: two states 40 nats apart, H = ln(1 + e) + 40 e / (1 + e), e = exp(−40)
        let e = (-40f64).exp();
        let exact = e.ln_1p() + 40.0 * e / (1.0 + e);
        let got = entropy_of_log_weights(&[3.0, -37.0]);
        assert!((got - exact).abs() <= 1e-14 * exact, "{got} vs {exact}");
        // impossible states, a tie, every state impossible, NaN, +inf
        let ln2 = 2f64.ln();
        assert!((entropy_of_log_weights(&[0.0, f64::NEG_INFINITY, 0.0]) - ln2).abs() < 1e-15);
        assert!((entropy_of_log_weights(&[f64::NEG_INFINITY; 4]) - 4f64.ln()).abs() < 1e-15);
        assert!((entropy_of_log_weights(&[f64::NAN, 1.0, 1.0]) - ln2).abs() < 1e-15);
        let inf = entropy_of_log_weights(&[f64::INFINITY, 0.0, f64::INFINITY]);
        assert!((inf - ln2).abs() < 1e-15);
        assert_eq!(entropy_of_log_weights(&[-1e300]), 0.0);
        assert_eq!(entropy_of_log_weights(&[]), 0.0);
    }

    /// Regression (issue 37): the evidence table computed a whole histogram's logarithms per
    /// possible count; its one-logarithm form must give `log_likelihood`'s values bit for bit.
    #[test]
    fn the_evidence_table_is_log_likelihood_bit_for_bit() {
        for q in [1usize, 2, 7, 20] {
            for floor in [0.0, 0.25, 1.0, 3.0, -1.0, f64::NAN] {
                for total in [0u32, 1, 9, 50] {
                    let mut counts = StepCounts::new(q);
                    let mut first = vec![0u32; q];
                    first[0] = total;
                    // enough sets that the table is built (at most one entry per count)
                    for id in 0..=total {
                        counts.push(LandmarkSet::new(1, 2, 3 + id), &first).unwrap();
                    }
                    let evidence = Evidence::new(floor, 1.0, &counts);
                    assert!(evidence.table.is_some(), "the table path is tested");
                    let mut out = vec![0.0; q];
                    // every split of the total between two states, and the total in one
                    for c in 0..=total {
                        let mut h = vec![0u32; q];
                        h[0] = c;
                        if q > 1 {
                            h[q - 1] = total - c;
                        }
                        evidence.fill(&h, &mut out);
                        let want = log_likelihood(&h, floor);
                        let same = out
                            .iter()
                            .zip(&want)
                            .all(|(a, b)| a.to_bits() == b.to_bits());
                        assert!(same, "q {q}, floor {floor}, {h:?}: {out:?} vs {want:?}");
                    }
                }
            }
        }
    }

    /// Regression (issue 37): skipping `exp` where it underflows changes no bit of the
    /// normalised belief.
    #[test]
    fn normalising_without_underflowing_exp_changes_no_bit() {
        let plain = |v: &[f64]| -> Vec<f64> {
            let max = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let z = max + v.iter().map(|x| (x - max).exp()).sum::<f64>().ln();
            v.iter().map(|x| x - z).collect()
        };
        let cases: [&[f64]; 4] = [
            &[0.0, -745.0, -745.2, -746.0, -746.1, -1e4, f64::NEG_INFINITY],
            &[-3.0, -2.0, -1000.0, -0.5],
            &[-800.0, -1.0, -1.0, -2000.0],
            &[5.0, -740.9, -745.13, -5000.0],
        ];
        for v in cases {
            let mut got = v.to_vec();
            normalise_in_place(&mut got);
            let want = plain(v);
            let same = got
                .iter()
                .zip(&want)
                .all(|(a, b)| a.to_bits() == b.to_bits());
            assert!(same, "{v:?}: {got:?} vs {want:?}");
        }
    }
}
