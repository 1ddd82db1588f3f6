//! Inference of relations between landmarks never observed together (see the module docs of
//! [`crate::reason`] for the assumptions).

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::reason::{Algebra, TableScope};
use qsr_core::{Permutation, StateId};
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::LandmarkSet;
use crate::map::Pqrm;
use crate::reason::network::{canonical, landmarks, observed_sets, orderings};

/// How the predictions of several paths are combined.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Fusion {
    /// The mean of the path predictions (linear pool).
    Mixture,
    /// The normalised geometric mean (log-linear pool with weights 1/k).
    Tempered,
    /// The normalised product (independent evidence).
    Product,
    /// The log-linear pool with weights `k^(−α)`, α ∈ [0, 1] fitted on the map itself (between
    /// the product, α = 0, and the tempered product, α = 1): each observed set is predicted
    /// from the others and α minimises the cross-entropy against the map's own belief — no
    /// ground truth is used. With [`Composition::Learned`] the same fit also chooses whether
    /// the pool divides the base rate out of each path and counts it once (see
    /// `fuse_log_linear`): k paths of learned shares each carry the targets' base rate, and a
    /// product counts it k times.
    #[default]
    Fitted,
}

impl Fusion {
    /// All four, in declaration order.
    pub const ALL: [Fusion; 4] = [Self::Mixture, Self::Tempered, Self::Product, Self::Fitted];

    /// The kebab-case name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Mixture => "mixture",
            Self::Tempered => "tempered",
            Self::Product => "product",
            Self::Fitted => "fitted",
        }
    }
}

impl std::str::FromStr for Fusion {
    type Err = PqrmError;

    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|f| f.name() == s)
            .ok_or_else(|| {
                PqrmError::InvalidConfig(format!(
                    "unknown fusion `{s}` (expected mixture, tempered, product or fitted)"
                ))
            })
    }
}

/// How a composition entry `r ∘ s` shares a path's probability among its states.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Composition {
    /// Every state of the entry equally (maximum entropy: the table says which states are
    /// possible, not how often).
    Uniform,
    /// As often as the map's own observed sets say: for each quadruple whose three sets
    /// the map observed, the beliefs of `{x,y:c}`, `{y,c:z}` and `{x,y:z}` add
    /// `p(r)·p(s)·p(t)` to `(r, s, t)`; each entry's weights are those counts with one
    /// pseudo-count spread over the entry's states (so an entry the map never shows stays
    /// uniform). No ground truth is used. On MRCLAM the uniform split left the inference's
    /// low-confidence predictions underconfident (`docs/reasoning.md`).
    #[default]
    Learned,
}

impl Composition {
    /// Both, in declaration order.
    pub const ALL: [Composition; 2] = [Self::Uniform, Self::Learned];

    /// The kebab-case name.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Uniform => "uniform",
            Self::Learned => "learned",
        }
    }
}

impl std::str::FromStr for Composition {
    type Err = PqrmError;

    fn from_str(s: &str) -> Result<Self> {
        Self::ALL
            .into_iter()
            .find(|c| c.name() == s)
            .ok_or_else(|| {
                PqrmError::InvalidConfig(format!(
                    "unknown composition `{s}` (expected uniform or learned)"
                ))
            })
    }
}

/// Settings of an [`Inferrer`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InferOptions {
    /// How paths are combined.
    pub fusion: Fusion,
    /// How a composition entry shares a path's probability among its states.
    #[serde(default)]
    pub composition: Composition,
    /// Weight of the uniform distribution mixed into each path before fusing (0 ≤ ε < 1).
    pub epsilon: f64,
    /// Rounds of [`Inferrer::infer_unseen`]: round 1 uses observed beliefs only, round r
    /// also the sets inferred in rounds 1 … r−1 (longer chains of composition).
    pub rounds: usize,
}

impl Default for InferOptions {
    fn default() -> Self {
        Self {
            fusion: Fusion::default(),
            composition: Composition::default(),
            epsilon: 0.01,
            rounds: 3,
        }
    }
}

impl InferOptions {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for ε outside [0, 1) or rounds outside 1..=16.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..1.0).contains(&self.epsilon) {
            return Err(PqrmError::InvalidConfig(format!(
                "epsilon must be in [0, 1), got {}",
                self.epsilon
            )));
        }
        if !(1..=16).contains(&self.rounds) {
            return Err(PqrmError::InvalidConfig(format!(
                "rounds must be in 1..=16, got {}",
                self.rounds
            )));
        }
        Ok(())
    }
}

/// A predicted distribution over the states of one ordered set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Inference {
    /// The set `{a, b : d}`.
    pub set: [u32; 3],
    /// Probabilities in state order (uniform when no path exists).
    pub p: Vec<f64>,
    /// Number of paths combined.
    pub paths: usize,
    /// The fourth landmarks that gave at least one path.
    pub via: Vec<u32>,
    /// The round that inferred it (1: from observed beliefs only; 0: no path, uniform).
    pub round: usize,
}

impl Inference {
    /// The most likely state (lowest id on ties).
    #[must_use]
    pub fn ml_state(&self) -> StateId {
        let mut best = 0;
        for (i, p) in self.p.iter().enumerate() {
            if *p > self.p[best] {
                best = i;
            }
        }
        StateId(best as u16)
    }
}

/// A prediction per ordering of one unordered set.
type Predictions = Vec<(LandmarkSet, Vec<f64>)>;

/// Inference over one map: the tables, the fitted pooling weight, and the sets inferred so
/// far.
#[derive(Debug, Clone)]
pub struct Inferrer<'m> {
    map: &'m Pqrm,
    algebra: Algebra,
    /// `comp[r][s]`: the states of `r ∘ s`, as a list.
    comp: Vec<Vec<Vec<StateId>>>,
    /// `share[r][s][i]`: the share of `comp[r][s][i]` in the entry (sums to 1).
    share: Vec<Vec<Vec<f64>>>,
    /// The base rate every learned path carries (`None`: uniform shares carry none): the
    /// pool divides it out of each path and puts it back once.
    base: Option<Vec<f64>>,
    /// `perm[op][t]`.
    perm: Vec<Vec<Vec<StateId>>>,
    options: InferOptions,
    alpha: f64,
    landmarks: Vec<u32>,
    inferred: BTreeMap<LandmarkSet, Vec<f64>>,
    /// Each ordering of a set [`Inferrer::infer_unseen`] reached, as it was reached (its
    /// paths and round), for [`Inferrer::infer_sets`].
    reached: BTreeMap<LandmarkSet, Inference>,
    /// Whether [`Inferrer::infer_unseen`] ran (a second run would compose through the first).
    rounds_ran: bool,
}

/// The grid α is fitted on.
const ALPHA_GRID: [f64; 11] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0];

/// At most this many observed sets are used to fit α and learn the shares (spread evenly
/// over the map).
const FIT_SETS: usize = 400;

/// The pseudo-count [`Composition::Learned`] spreads evenly over an entry's states. Chosen
/// by leaving one MRCLAM recording out (0.1, 1, 10, 100; hidden-set log loss of the reason
/// study, EDC + double-cross, the other two recordings): folds chose 0.1, 1, 1; 100 was
/// worst on every recording (`docs/reasoning.md`).
const SHARE_PSEUDO_COUNT: f64 = 1.0;

impl<'m> Inferrer<'m> {
    /// Prepares inference over `map` with the calculus's general-position tables (a noisy
    /// sensor puts no probability on boundaries); fits α for [`Fusion::Fitted`].
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for bad options; [`PqrmError::Calculus`] when the calculus
    /// has no ternary tables.
    pub fn new(map: &'m Pqrm, options: InferOptions) -> Result<Self> {
        let algebra = Algebra::of(map.calculus(), TableScope::GeneralPosition)?;
        Self::with_algebra(map, algebra, options)
    }

    /// As [`Inferrer::new`] with tables computed elsewhere (e.g. a learned calculus's
    /// Algorithm 3 table).
    ///
    /// # Errors
    /// As [`Inferrer::new`]; [`PqrmError::Mismatch`] when the tables have another state count.
    pub fn with_algebra(map: &'m Pqrm, algebra: Algebra, options: InferOptions) -> Result<Self> {
        options.validate()?;
        let q = map.calculus().n_states();
        if algebra.n_states() != q {
            return Err(PqrmError::Mismatch(format!(
                "tables of {} states for a map of {q}",
                algebra.n_states()
            )));
        }
        let id = |i: usize| StateId(i as u16);
        let comp: Vec<Vec<Vec<StateId>>> = (0..q)
            .map(|r| {
                (0..q)
                    .map(|s| algebra.compose(id(r), id(s)).iter().collect())
                    .collect()
            })
            .collect();
        let share = uniform_shares(&comp);
        let perm = Permutation::ALL
            .iter()
            .map(|op| {
                (0..q)
                    .map(|t| algebra.permute(*op, id(t)).iter().collect())
                    .collect()
            })
            .collect();
        let mut me = Self {
            map,
            algebra,
            comp,
            share,
            base: None,
            perm,
            options,
            alpha: 1.0,
            landmarks: landmarks(map).iter().map(|l| l.0).collect(),
            inferred: BTreeMap::new(),
            reached: BTreeMap::new(),
            rounds_ran: false,
        };
        if options.composition == Composition::Learned {
            let (share, base) = me.learn_shares();
            me.share = share;
            me.base = Some(base);
        }
        if options.fusion == Fusion::Fitted {
            let (alpha, keep_base) = me.fit_alpha();
            me.alpha = alpha;
            if !keep_base {
                me.base = None;
            }
        }
        Ok(me)
    }

    /// The fitted α (1 unless the fusion is [`Fusion::Fitted`]).
    #[must_use]
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// Whether the pool divides the base rate out of each path and counts it once: with
    /// [`Composition::Learned`], as the fit chose for [`Fusion::Fitted`], always for the other
    /// log-linear pools; never with uniform shares.
    #[must_use]
    pub fn divides_base_rate(&self) -> bool {
        self.base.is_some()
    }

    /// The options it was made with.
    #[must_use]
    pub fn options(&self) -> &InferOptions {
        &self.options
    }

    /// The tables in use.
    #[must_use]
    pub fn algebra(&self) -> &Algebra {
        &self.algebra
    }

    /// The belief of an ordered set: observed, else inferred in an earlier round.
    fn belief(&self, set: LandmarkSet) -> Option<Vec<f64>> {
        self.map
            .belief(set)
            .or_else(|| self.inferred.get(&set).cloned())
    }

    /// The predictions of every path to `{a,b:d}` and the fourth landmarks that gave them.
    #[must_use]
    pub fn paths(&self, set: LandmarkSet) -> (Vec<Vec<f64>>, Vec<u32>) {
        let [a, b, d] = set.ids();
        let q = self.algebra.n_states();
        // (x, y, z) = op(a, b, d) and the permutation back from (x, y, z) to (a, b, d).
        let mut shapes: Vec<([u32; 3], Option<Permutation>)> = vec![([a, b, d], None)];
        for op in Permutation::ALL {
            let (x, y, z) = op.apply(a, b, d);
            let back = Permutation::ALL
                .into_iter()
                .find(|o| o.apply(x, y, z) == (a, b, d));
            shapes.push(([x, y, z], back));
        }
        let mut paths = Vec::new();
        let mut via = Vec::new();
        for &c in &self.landmarks {
            if c == a || c == b || c == d {
                continue;
            }
            let mut used = false;
            for ([x, y, z], back) in &shapes {
                let (Some(p1), Some(p2)) = (
                    self.belief(LandmarkSet::new(*x, *y, c)),
                    self.belief(LandmarkSet::new(*y, c, *z)),
                ) else {
                    continue;
                };
                let mut pred = vec![0.0; q];
                for (r, pr) in p1.iter().enumerate() {
                    if *pr < 1e-12 {
                        continue;
                    }
                    for (s, ps) in p2.iter().enumerate() {
                        let w = pr * ps;
                        let targets = &self.comp[r][s];
                        if w < 1e-15 || targets.is_empty() {
                            continue;
                        }
                        for (t, share) in targets.iter().zip(&self.share[r][s]) {
                            pred[t.index()] += w * share;
                        }
                    }
                }
                let total: f64 = pred.iter().sum();
                if total <= 0.0 {
                    continue;
                }
                pred.iter_mut().for_each(|v| *v /= total);
                if let Some(op) = back {
                    let table = &self.perm[*op as usize];
                    let mut out = vec![0.0; q];
                    for (t, pt) in pred.iter().enumerate() {
                        let targets = &table[t];
                        for u in targets {
                            out[u.index()] += pt / targets.len() as f64;
                        }
                    }
                    pred = out;
                }
                paths.push(pred);
                used = true;
            }
            if used {
                via.push(c);
            }
        }
        (paths, via)
    }

    /// Combines path predictions with `fusion` (α for the fitted one is this inferrer's).
    #[must_use]
    pub fn fuse(&self, paths: &[Vec<f64>], fusion: Fusion) -> Vec<f64> {
        let q = self.algebra.n_states();
        let k = paths.len().max(1) as f64;
        let weight = match fusion {
            Fusion::Mixture => return fuse_mixture(paths, q, self.options.epsilon),
            Fusion::Product => 1.0,
            Fusion::Tempered => 1.0 / k,
            Fusion::Fitted => k.powf(-self.alpha),
        };
        fuse_log_linear(paths, q, self.options.epsilon, weight, self.base.as_deref())
    }

    /// Predicts `{a,b:d}` from the beliefs (observed, and inferred by earlier calls of
    /// [`Inferrer::infer_unseen`]).
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for a set with a repeated landmark.
    pub fn infer(&self, set: LandmarkSet) -> Result<Inference> {
        let [a, b, d] = set.ids();
        if a == b || b == d || a == d {
            return Err(PqrmError::InvalidConfig(format!(
                "set {:?} repeats a landmark",
                set.ids()
            )));
        }
        let (paths, via) = self.paths(set);
        Ok(Inference {
            set: set.ids(),
            p: self.fuse(&paths, self.options.fusion),
            paths: paths.len(),
            round: usize::from(!paths.is_empty()),
            via,
        })
    }

    /// Infers every unordered set of the map's landmarks that was never observed, in rounds
    /// ([`InferOptions::rounds`]); returns one inference per set (its increasing-id
    /// ordering), in id order. Sets still without a path after the last round are uniform
    /// (`round` 0). Round r sees only what rounds before it inferred, so the result does not
    /// depend on the order of the sets.
    pub fn infer_unseen(&mut self) -> Vec<Inference> {
        self.rounds_ran = true;
        let seen: BTreeSet<LandmarkSet> = observed_sets(self.map).into_iter().collect();
        let ids = self.landmarks.clone();
        let mut unseen = Vec::new();
        for (i, a) in ids.iter().enumerate() {
            for (j, b) in ids.iter().enumerate().skip(i + 1) {
                for d in ids.iter().skip(j + 1) {
                    let s = LandmarkSet::new(*a, *b, *d);
                    if !seen.contains(&s) {
                        unseen.push(s);
                    }
                }
            }
        }
        let mut result: BTreeMap<LandmarkSet, Inference> = BTreeMap::new();
        for round in 1..=self.options.rounds {
            // (the set, each ordering's fused prediction, the set's inference)
            let mut new: Vec<(LandmarkSet, Predictions, Inference)> = Vec::new();
            for s in unseen.iter().filter(|s| !result.contains_key(s)) {
                let per_ordering: Vec<(LandmarkSet, Vec<Vec<f64>>, Vec<u32>)> = orderings(*s)
                    .into_iter()
                    .map(|o| {
                        let (p, v) = self.paths(o);
                        (o, p, v)
                    })
                    .collect();
                if per_ordering.iter().all(|(_, p, _)| p.is_empty()) {
                    continue;
                }
                let fused: Vec<(LandmarkSet, Vec<f64>)> = per_ordering
                    .iter()
                    .map(|(o, p, _)| (*o, self.fuse(p, self.options.fusion)))
                    .collect();
                for ((o, paths, via), (_, p)) in per_ordering.iter().zip(&fused) {
                    let reached = Inference {
                        set: o.ids(),
                        p: p.clone(),
                        paths: paths.len(),
                        via: via.clone(),
                        round,
                    };
                    self.reached.insert(*o, reached);
                }
                let (_, p0, v0) = &per_ordering[0];
                let inf = Inference {
                    set: s.ids(),
                    p: fused[0].1.clone(),
                    paths: p0.len(),
                    via: v0.clone(),
                    round,
                };
                new.push((*s, fused, inf));
            }
            if new.is_empty() {
                break;
            }
            for (s, fused, inf) in new {
                for (o, p) in fused {
                    self.inferred.insert(o, p);
                }
                result.insert(s, inf);
            }
        }
        let q = self.algebra.n_states();
        unseen
            .into_iter()
            .map(|s| {
                result.remove(&s).unwrap_or_else(|| Inference {
                    set: s.ids(),
                    p: vec![1.0 / q as f64; q],
                    paths: 0,
                    via: Vec::new(),
                    round: 0,
                })
            })
            .collect()
    }

    /// Infers the ordered `sets` as a run over the whole map does, so asking for one set and
    /// reading it from the run over every unseen set give the same answer: a set the map
    /// observed is predicted from the observed beliefs ([`Inferrer::infer`] before any
    /// round), a set never observed is what [`Inferrer::infer_unseen`]'s rounds reached for
    /// that ordering (uniform, round 0, when no round reached it).
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for a landmark the map does not have or a set that
    /// repeats one.
    pub fn infer_sets(&mut self, sets: &[LandmarkSet]) -> Result<Vec<Inference>> {
        for s in sets {
            if let Some(id) = s.ids().iter().find(|id| !self.landmarks.contains(id)) {
                return Err(PqrmError::InvalidConfig(format!(
                    "landmark {id} is not in the map (its landmarks: {:?})",
                    self.landmarks
                )));
            }
        }
        let seen: BTreeSet<LandmarkSet> = observed_sets(self.map).into_iter().collect();
        // Observed sets first, from observed beliefs alone; every set is checked here.
        let direct: Vec<Inference> = sets.iter().map(|s| self.infer(*s)).collect::<Result<_>>()?;
        if sets.iter().any(|s| !seen.contains(&canonical(*s))) && !self.rounds_ran {
            self.infer_unseen();
        }
        let q = self.algebra.n_states();
        Ok(sets
            .iter()
            .zip(direct)
            .map(|(s, d)| {
                if seen.contains(&canonical(*s)) {
                    return d;
                }
                self.reached.get(s).cloned().unwrap_or_else(|| Inference {
                    set: s.ids(),
                    p: vec![1.0 / q as f64; q],
                    paths: 0,
                    via: Vec::new(),
                    round: 0,
                })
            })
            .collect())
    }

    /// The inferred belief of an ordered set after [`Inferrer::infer_unseen`].
    #[must_use]
    pub fn inferred(&self, set: LandmarkSet) -> Option<&[f64]> {
        self.inferred.get(&set).map(Vec::as_slice)
    }

    /// The observed sets the shares and α are fitted on: at most [`FIT_SETS`], spread
    /// evenly over the map.
    fn fit_sets(&self) -> Vec<LandmarkSet> {
        let sets = observed_sets(self.map);
        let stride = sets.len().div_ceil(FIT_SETS).max(1);
        sets.into_iter().step_by(stride).collect()
    }

    /// [`Composition::Learned`]'s shares: for each fitted set `(x,y,z)` (every ordering) and
    /// fourth landmark `c` with `{x,y:c}` and `{y,c:z}` observed, `p(r)·p(s)·p(t)` added to
    /// `(r, s, t)` for each state `t` of `r ∘ s`, then one pseudo-count per entry spread
    /// evenly over its states. The target is the set's own belief, so no ground truth.
    /// Also returns the base rate of the targets (the counts summed over entries, one
    /// pseudo-count spread over the states, smoothed with ε as a path is): what a path of
    /// learned shares predicts when its two beliefs say nothing, so that a pool of k paths
    /// counts it once and not k times.
    fn learn_shares(&self) -> (Vec<Vec<Vec<f64>>>, Vec<f64>) {
        let q = self.algebra.n_states();
        let mut counts: Vec<Vec<Vec<f64>>> = self
            .comp
            .iter()
            .map(|row| row.iter().map(|ts| vec![0.0; ts.len()]).collect())
            .collect();
        for set in self.fit_sets() {
            let [a, b, d] = set.ids();
            for o in orderings(set) {
                let [x, y, z] = o.ids();
                let Some(target) = self.map.belief(o) else {
                    continue;
                };
                for &c in &self.landmarks {
                    if c == a || c == b || c == d {
                        continue;
                    }
                    let (Some(p1), Some(p2)) = (
                        self.map.belief(LandmarkSet::new(x, y, c)),
                        self.map.belief(LandmarkSet::new(y, c, z)),
                    ) else {
                        continue;
                    };
                    for (r, pr) in p1.iter().enumerate().filter(|(_, p)| **p >= 1e-12) {
                        for (s, ps) in p2.iter().enumerate() {
                            let w = pr * ps;
                            if w < 1e-15 {
                                continue;
                            }
                            for (t, n) in self.comp[r][s].iter().zip(&mut counts[r][s]) {
                                *n += w * target[t.index()];
                            }
                        }
                    }
                }
            }
        }
        debug_assert_eq!(counts.len(), q);
        let mut base = vec![SHARE_PSEUDO_COUNT / q as f64; q];
        for (r, row) in counts.iter().enumerate() {
            for (s, entry) in row.iter().enumerate() {
                for (t, n) in self.comp[r][s].iter().zip(entry) {
                    base[t.index()] += n;
                }
            }
        }
        let total: f64 = base.iter().sum();
        let eps = self.options.epsilon;
        base.iter_mut()
            .for_each(|b| *b = (1.0 - eps) * *b / total + eps / q as f64);
        for entry in counts.iter_mut().flatten() {
            let k = entry.len() as f64;
            let total: f64 = entry.iter().sum::<f64>() + SHARE_PSEUDO_COUNT;
            entry
                .iter_mut()
                .for_each(|n| *n = (*n + SHARE_PSEUDO_COUNT / k) / total);
        }
        (counts, base)
    }

    /// α minimising the mean cross-entropy between each observed set's belief and its
    /// prediction from the other sets (leave-one-out: a set's own paths never use it).
    fn fit_alpha(&self) -> (f64, bool) {
        let q = self.algebra.n_states();
        let samples: Vec<(Vec<Vec<f64>>, Vec<f64>)> = self
            .fit_sets()
            .iter()
            .filter_map(|s| {
                let target = self.map.belief(canonical(*s))?;
                let (paths, _) = self.paths(canonical(*s));
                (paths.len() > 1).then_some((paths, target))
            })
            .collect();
        if samples.is_empty() {
            return (1.0, self.base.is_some());
        }
        let loss = |alpha: f64, base: Option<&[f64]>| -> f64 {
            samples
                .iter()
                .map(|(paths, target)| {
                    let w = (paths.len() as f64).powf(-alpha);
                    let p = fuse_log_linear(paths, q, self.options.epsilon, w, base);
                    target
                        .iter()
                        .zip(&p)
                        .map(|(t, v)| -t * v.max(1e-300).ln())
                        .sum::<f64>()
                })
                .sum::<f64>()
        };
        let bases: Vec<Option<&[f64]>> = match self.base.as_deref() {
            Some(b) => vec![None, Some(b)],
            None => vec![None],
        };
        ALPHA_GRID
            .into_iter()
            .flat_map(|a| bases.iter().map(move |b| (a, *b)))
            .map(|(a, b)| (loss(a, b), a, b.is_some()))
            .min_by(|x, y| x.0.total_cmp(&y.0))
            .map_or((1.0, false), |(_, a, b)| (a, b))
    }
}

/// Every state of each composition entry an equal share.
fn uniform_shares(comp: &[Vec<Vec<StateId>>]) -> Vec<Vec<Vec<f64>>> {
    comp.iter()
        .map(|row| {
            row.iter()
                .map(|ts| vec![1.0 / ts.len().max(1) as f64; ts.len()])
                .collect()
        })
        .collect()
}

fn fuse_mixture(paths: &[Vec<f64>], q: usize, eps: f64) -> Vec<f64> {
    let uniform = 1.0 / q as f64;
    if paths.is_empty() {
        return vec![uniform; q];
    }
    let k = paths.len() as f64;
    (0..q)
        .map(|t| {
            paths
                .iter()
                .map(|p| (1.0 - eps) * p[t] + eps * uniform)
                .sum::<f64>()
                / k
        })
        .collect()
}

/// `p ∝ Π_i p_i^weight`, each path smoothed with ε first; uniform without paths or when
/// nothing survives. With a `base` rate every path carries (learned shares), each path is
/// read relative to it and it is put back once: `p ∝ b · Π_i (p_i / b)^weight`.
fn fuse_log_linear(
    paths: &[Vec<f64>],
    q: usize,
    eps: f64,
    weight: f64,
    base: Option<&[f64]>,
) -> Vec<f64> {
    let uniform = 1.0 / q as f64;
    if paths.is_empty() {
        return vec![uniform; q];
    }
    let k = paths.len() as f64;
    let logs: Vec<f64> = (0..q)
        .map(|t| {
            let pooled = paths
                .iter()
                .map(|p| ((1.0 - eps) * p[t] + eps * uniform).ln())
                .sum::<f64>()
                * weight;
            match base {
                Some(b) => pooled + (1.0 - k * weight) * b[t].ln(),
                None => pooled,
            }
        })
        .collect();
    let max = logs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut out: Vec<f64> = logs.iter().map(|l| (l - max).exp()).collect();
    let total: f64 = out.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        // ε = 0 with paths that exclude each other: nothing is left; say "unknown".
        return vec![uniform; q];
    }
    out.iter_mut().for_each(|v| *v /= total);
    out
}

/// Predicts `{a,b:d}` from the map's observed beliefs with the default options.
///
/// # Errors
/// As [`Inferrer::new`] and [`Inferrer::infer`].
pub fn infer(map: &Pqrm, set: LandmarkSet) -> Result<Inference> {
    Inferrer::new(map, InferOptions::default())?.infer(set)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A pool of k paths that each say only the base rate says the base rate, whatever the
    /// pool's weight; without the correction the product counts it k times.
    #[test]
    fn a_base_rate_every_path_carries_is_counted_once() {
        let base = [0.6, 0.3, 0.1];
        let paths = vec![base.to_vec(); 4];
        for weight in [1.0, 0.5, 0.25] {
            let p = fuse_log_linear(&paths, 3, 0.0, weight, Some(&base));
            for (a, b) in p.iter().zip(base) {
                assert!((a - b).abs() < 1e-12, "weight {weight}: {p:?}");
            }
        }
        let p = fuse_log_linear(&paths, 3, 0.0, 1.0, None);
        assert!(p[0] > 0.9, "the product of four copies sharpens: {p:?}");
        // one informative path among base-rate ones decides alone, at weight 1
        let mut mixed = vec![base.to_vec(); 3];
        mixed.push(vec![0.2, 0.3, 0.5]);
        let p = fuse_log_linear(&mixed, 3, 0.0, 1.0, Some(&base));
        for (a, b) in p.iter().zip([0.2, 0.3, 0.5]) {
            assert!((a - b).abs() < 1e-12, "{p:?}");
        }
    }
}
