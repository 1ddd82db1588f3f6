//! Map quality (thesis §2.3.1–2.3.2): entropy (eq. 2.11), error rate of the
//! maximum-likelihood state, neighbour distance to the truth, P(ML), confusion matrix and
//! top-n error rate, with the random-guess baseline of each.

use std::collections::BTreeMap;

use qsr_core::{Calculus, Point2, StateId};
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::LandmarkSet;
use crate::map::Pqrm;
use crate::observation::LandmarkId;

pub use crate::map::entropy;

/// Surveyed landmark positions: the reference every map is scored against.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct GroundTruth {
    /// Position of each landmark (any fixed frame).
    pub positions: BTreeMap<LandmarkId, [f64; 2]>,
}

impl GroundTruth {
    /// The true state of an ordered set; `None` if a landmark has no surveyed position.
    ///
    /// # Errors
    /// [`PqrmError::CoincidentLandmarks`] when two surveyed positions coincide.
    pub fn state(&self, calculus: &Calculus, set: &LandmarkSet) -> Result<Option<StateId>> {
        let p = |id: &LandmarkId| self.positions.get(id).map(|v| Point2::new(v[0], v[1]));
        let (Some(a), Some(b), Some(c)) = (p(&set.0[0]), p(&set.0[1]), p(&set.0[2])) else {
            return Ok(None);
        };
        calculus
            .classify_triplet(a, b, c)
            .map(Some)
            .map_err(|e| match e {
                qsr_core::QsrError::DegenerateFrame { .. } => PqrmError::CoincidentLandmarks {
                    set: set.ids(),
                    reason: e.to_string(),
                },
                other => PqrmError::Calculus(other),
            })
    }

    /// The normalised position of C in the frame of (A, B) and `|AB|`: where a triplet sits
    /// in the calculus's picture (thesis Fig 2.8).
    #[must_use]
    pub fn normalised(&self, set: &LandmarkSet) -> Option<([f64; 2], f64)> {
        let p = |id: &LandmarkId| self.positions.get(id).map(|v| Point2::new(v[0], v[1]));
        let (a, b, c) = (p(&set.0[0])?, p(&set.0[1])?, p(&set.0[2])?);
        let f = qsr_core::TernaryFrame::new(a, b).ok()?;
        let q = f.to_normalised(&c);
        Some(([q.x, q.y], f.scale()))
    }
}

/// Scores of one map against the truth.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MapMetrics {
    /// Sets in the map.
    pub n_sets: usize,
    /// Sets with a true state (all landmarks surveyed).
    pub n_scored: usize,
    /// Mean entropy over all sets (nats).
    pub mean_entropy: f64,
    /// Mean entropy divided by ln Q.
    pub normalized_entropy: f64,
    /// Fraction of scored sets whose ML state is wrong.
    pub error_rate: f64,
    /// Mean neighbour distance between ML and true state.
    pub mean_neighbor_distance: f64,
    /// Mean probability of the ML state.
    pub p_ml_mean: f64,
    /// `top_n_error[n-1]`: fraction whose true state is not among the n most likely.
    pub top_n_error: Vec<f64>,
    /// `confusion[true][ml]` counts.
    pub confusion: Vec<Vec<u64>>,
    /// Sets at each neighbour distance 0, 1, ...
    pub neighbor_histogram: Vec<u64>,
}

/// Scores every recorded set of `map` that `truth` covers.
///
/// # Errors
/// [`PqrmError::Mismatch`] for an empty map; truth errors.
pub fn evaluate(map: &Pqrm, truth: &GroundTruth) -> Result<MapMetrics> {
    if map.is_empty() {
        return Err(PqrmError::Mismatch(
            "the map has no landmark sets to score".into(),
        ));
    }
    let calculus = map.calculus();
    let q = calculus.n_states();
    let neighbours = calculus.neighbours();
    let diameter = neighbours.diameter().unwrap_or(0) as usize;
    let mut m = MapMetrics {
        n_sets: map.len(),
        top_n_error: vec![0.0; q],
        confusion: vec![vec![0; q]; q],
        neighbor_histogram: vec![0; diameter + 1],
        ..MapMetrics::default()
    };
    let (mut wrong, mut dist, mut pml, mut ent) = (0usize, 0u64, 0.0, 0.0);
    let mut rank_hits = vec![0usize; q];
    for (set, belief) in map.iter() {
        let p = belief.probabilities();
        ent += belief.entropy();
        let Some(t) = truth.state(calculus, set)? else {
            continue;
        };
        m.n_scored += 1;
        let ml = belief.ml_state();
        pml += p[ml.index()];
        m.confusion[t.index()][ml.index()] += 1;
        if ml != t {
            wrong += 1;
        }
        let d = neighbours.distance(ml, t).unwrap_or(diameter as u32);
        dist += u64::from(d);
        m.neighbor_histogram[(d as usize).min(diameter)] += 1;
        let rank = belief
            .ranked()
            .iter()
            .position(|s| *s == t)
            .unwrap_or(q - 1);
        rank_hits[rank] += 1;
    }
    m.mean_entropy = ent / map.len() as f64;
    m.normalized_entropy = if q > 1 {
        m.mean_entropy / (q as f64).ln()
    } else {
        0.0
    };
    if m.n_scored > 0 {
        let n = m.n_scored as f64;
        m.error_rate = wrong as f64 / n;
        m.mean_neighbor_distance = dist as f64 / n;
        m.p_ml_mean = pml / n;
        let mut covered = 0;
        for (err, hits) in m.top_n_error.iter_mut().zip(&rank_hits) {
            covered += hits;
            *err = 1.0 - covered as f64 / n;
        }
    }
    Ok(m)
}

/// What guessing a state uniformly at random scores, for the same calculus.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Baselines {
    /// `(Q − 1)/Q`.
    pub error_rate: f64,
    /// Mean neighbour distance between a uniform guess and a uniform true state.
    pub mean_neighbor_distance: f64,
    /// `1/Q`: the probability a uniform belief gives its ML state.
    pub p_ml: f64,
    /// `1 − n/Q` for n = 1..Q.
    pub top_n_error: Vec<f64>,
    /// `ln Q`: the entropy of a uniform belief.
    pub entropy: f64,
}

/// Random-guess baselines; the neighbour distance is the exact expectation over uniform
/// guess and truth (the thesis estimates it by drawing 1000 guesses per true state).
#[must_use]
pub fn random_baselines(calculus: &Calculus) -> Baselines {
    let q = calculus.n_states();
    let g = calculus.neighbours();
    let total: u64 = g
        .distance_matrix()
        .iter()
        .flatten()
        .map(|d| u64::from(d.unwrap_or(0)))
        .sum();
    Baselines {
        error_rate: (q as f64 - 1.0) / q as f64,
        mean_neighbor_distance: total as f64 / (q * q) as f64,
        p_ml: 1.0 / q as f64,
        top_n_error: (1..=q).map(|n| 1.0 - n as f64 / q as f64).collect(),
        entropy: (q as f64).ln(),
    }
}
