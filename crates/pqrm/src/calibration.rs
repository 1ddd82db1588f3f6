//! Is a map honest about its uncertainty? A reliability diagram: scored triplets binned by the
//! probability of their most likely state, P(ML), each bin's accuracy beside its mean P(ML).
//! A calibrated map has accuracy ≈ P(ML) in every bin; an overconfident one has accuracy below.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::map::Pqrm;
use crate::metrics::GroundTruth;

/// Bin edges of P(ML): coarse where maps rarely are, fine near 1 where most triplets sit.
pub const EDGES: [f64; 9] = [0.0, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99, 0.999, 1.0];

/// One bin of a reliability diagram.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationBin {
    /// Lower edge (inclusive).
    pub lo: f64,
    /// Upper edge (exclusive; the last bin includes 1).
    pub hi: f64,
    /// Scored triplets in the bin.
    pub n: usize,
    /// Their mean P(ML).
    pub mean_p_ml: f64,
    /// The fraction whose ML state is the true one.
    pub accuracy: f64,
}

/// A map's reliability diagram.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Non-empty bins, in order.
    pub bins: Vec<CalibrationBin>,
    /// Expected calibration error: the triplet-weighted mean of |accuracy − mean P(ML)|.
    pub ece: f64,
    /// The largest |accuracy − mean P(ML)| over bins with at least [`MIN_BIN`] triplets.
    pub max_gap: f64,
}

/// Bins with fewer triplets are shown but not judged (their accuracy is noise).
pub const MIN_BIN: usize = 30;

/// A map is calibrated when its ECE is at most this …
pub const CALIBRATED_ECE: f64 = 0.05;
/// … and every bin of at least [`MIN_BIN`] triplets is within this of its accuracy.
pub const CALIBRATED_GAP: f64 = 0.10;

impl Calibration {
    /// ECE ≤ [`CALIBRATED_ECE`] and every judged bin within [`CALIBRATED_GAP`]: what a
    /// robot betting on P(ML) needs (an honest average and no badly-off band of beliefs).
    #[must_use]
    pub fn is_calibrated(&self) -> bool {
        is_calibrated(self.ece, self.max_gap)
    }
}

/// The test of [`Calibration::is_calibrated`] on its two figures.
#[must_use]
pub fn is_calibrated(ece: f64, max_gap: f64) -> bool {
    ece <= CALIBRATED_ECE && max_gap <= CALIBRATED_GAP
}

/// The reliability diagram of `map` against `truth` (triplets with a true state).
///
/// # Errors
/// Truth errors (coincident surveyed landmarks).
pub fn calibration(map: &Pqrm, truth: &GroundTruth) -> Result<Calibration> {
    let mut scored = Vec::new();
    for (set, belief) in map.iter() {
        let Some(t) = truth.state(map.calculus(), set)? else {
            continue;
        };
        let ml = belief.ml_state();
        scored.push((belief.probabilities()[ml.index()], ml == t));
    }
    Ok(diagram(scored))
}

/// The reliability diagram of scored beliefs: each one's P(ML) and whether its ML state is
/// the true one.
pub(crate) fn diagram(scored: impl IntoIterator<Item = (f64, bool)>) -> Calibration {
    diagram_with(&EDGES, scored)
}

/// [`diagram`] over the bins between `edges` (increasing, from 0 to 1).
fn diagram_with(edges: &[f64], scored: impl IntoIterator<Item = (f64, bool)>) -> Calibration {
    let k = edges.len().saturating_sub(1).max(1);
    let (mut n, mut conf, mut hits) = (vec![0usize; k], vec![0.0; k], vec![0usize; k]);
    for (p, hit) in scored {
        let bin = bin_of(edges, p);
        n[bin] += 1;
        conf[bin] += p;
        hits[bin] += usize::from(hit);
    }
    let total: usize = n.iter().sum();
    let mut out = Calibration::default();
    for b in 0..k {
        if n[b] == 0 {
            continue;
        }
        let bin = CalibrationBin {
            lo: edges[b],
            hi: edges[b + 1],
            n: n[b],
            mean_p_ml: conf[b] / n[b] as f64,
            accuracy: hits[b] as f64 / n[b] as f64,
        };
        let gap = (bin.accuracy - bin.mean_p_ml).abs();
        out.ece += gap * n[b] as f64 / total as f64;
        if n[b] >= MIN_BIN {
            out.max_gap = out.max_gap.max(gap);
        }
        out.bins.push(bin);
    }
    out
}

/// The bin of a P(ML) between `edges` (the last bin includes 1). Shared by every reliability
/// diagram qrm draws, so a score and what chance gives it bin each prediction alike.
pub(crate) fn bin_of(edges: &[f64], p: f64) -> usize {
    let k = edges.len().saturating_sub(1).max(1);
    edges
        .get(1..)
        .and_then(|upper| upper.iter().position(|&hi| p < hi))
        .unwrap_or(k - 1)
}

/// What a *calibrated* map of the same triplets would score: the spread of ECE and of the
/// largest bin gap when each triplet's true state is drawn from the map's own belief
/// (consistency resampling, Bröcker & Smith 2007).
///
/// Why: the verdict's thresholds (ECE ≤ [`CALIBRATED_ECE`], bins of ≥ [`MIN_BIN`] within
/// [`CALIBRATED_GAP`]) are fixed, but what chance alone does to the two scores depends on how
/// many triplets were scored and where their beliefs sit. On MRCLAM's recordings (91–411
/// unordered triplets, each scored in six orderings) a bin of 30 ordered sets holds about five
/// triplets, and a map whose every belief is exactly right fails the bar on one recording up
/// to a third of the time (it passes 63–100 % of the draws, measured on each recording).
/// The band says whether a miss is beyond what chance does.
///
/// The six orderings of one triplet share one geometry, so they share one draw: one uniform
/// number per unordered triplet, each ordering's state taken where its own cumulative belief
/// passes it (their states move together, as the true ones do).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Chance {
    /// Draws taken (0: not computed).
    pub draws: usize,
    /// The median and the 95th percentile of a calibrated map's ECE.
    pub ece: [f64; 2],
    /// The median and the 95th percentile of its largest gap over bins of ≥ [`MIN_BIN`].
    pub max_gap: [f64; 2],
    /// The share of draws in which the calibrated map passes [`is_calibrated`].
    pub pass_rate: f64,
}

impl Chance {
    /// Whether `ece` is beyond what a calibrated map of these triplets shows in 95 % of
    /// draws (false when not computed).
    #[must_use]
    pub fn ece_beyond(&self, ece: f64) -> bool {
        self.draws > 0 && ece > self.ece[1]
    }
}

/// Draws [`chance`] takes in the studies: the 95th percentiles to about ±0.003.
pub const CHANCE_DRAWS: usize = 1000;

/// [`Chance`] for `map` against `truth`: `draws` draws from a generator seeded with `seed`
/// (the same on any machine and thread count).
///
/// # Errors
/// Truth errors (coincident surveyed landmarks).
pub fn chance(map: &Pqrm, truth: &GroundTruth, draws: usize, seed: u64) -> Result<Chance> {
    let mut scored = Vec::new();
    for (set, belief) in map.iter() {
        if truth.state(map.calculus(), set)?.is_none() {
            continue;
        }
        scored.push((belief.probabilities(), belief.ml_state().index(), set.ids()));
    }
    Ok(chance_with(&EDGES, scored, draws, seed))
}

/// [`Chance`] of any predictions scored in a reliability diagram over the bins between
/// `edges`: each prediction's probabilities over the states and the triplet it is of
/// (predictions of one unordered triplet — its orderings, or the triplet predicted again in
/// another trial — share one draw, as their true states are one geometry's). The ML state is
/// the first most probable one. The reasoning study's inferred beliefs are judged with it
/// (`crate::reason_study`, ten equal bins).
#[must_use]
pub fn chance_of_predictions(
    edges: &[f64],
    predictions: &[(Vec<f64>, [u32; 3])],
    draws: usize,
    seed: u64,
) -> Chance {
    let scored = predictions.iter().map(|(p, triplet)| {
        let ml = (0..p.len()).fold(0, |b, i| if p[i] > p[b] { i } else { b });
        (p.clone(), ml, *triplet)
    });
    chance_with(edges, scored, draws, seed)
}

/// [`Chance`] of predictions given as (probabilities, ML state, triplet): each one's
/// cumulative belief and group (its unordered triplet) for [`chance_of`].
fn chance_with(
    edges: &[f64],
    predictions: impl IntoIterator<Item = (Vec<f64>, usize, [u32; 3])>,
    draws: usize,
    seed: u64,
) -> Chance {
    let mut groups: std::collections::BTreeMap<[u32; 3], usize> = std::collections::BTreeMap::new();
    let scored: Vec<(Vec<f64>, usize, f64, usize)> = predictions
        .into_iter()
        .map(|(p, ml, mut key)| {
            key.sort_unstable();
            let next = groups.len();
            let group = *groups.entry(key).or_insert(next);
            let cumulative: Vec<f64> = p
                .iter()
                .scan(0.0, |acc, v| {
                    *acc += v;
                    Some(*acc)
                })
                .collect();
            (cumulative, ml, p.get(ml).copied().unwrap_or(0.0), group)
        })
        .collect();
    chance_of(edges, &scored, groups.len(), draws, seed)
}

/// [`chance`] of scored beliefs: each one's cumulative belief, ML state, P(ML) and group (its
/// unordered triplet, `< n_groups`).
fn chance_of(
    edges: &[f64],
    scored: &[(Vec<f64>, usize, f64, usize)],
    n_groups: usize,
    draws: usize,
    seed: u64,
) -> Chance {
    use rand::{RngExt, SeedableRng};
    if scored.is_empty() || draws == 0 {
        return Chance::default();
    }
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut u = vec![0.0f64; n_groups];
    let (mut eces, mut gaps, mut passes) =
        (Vec::with_capacity(draws), Vec::with_capacity(draws), 0);
    for _ in 0..draws {
        u.iter_mut().for_each(|v| *v = rng.random::<f64>());
        let d = diagram_with(
            edges,
            scored.iter().map(|(cumulative, ml, p, group)| {
                // the drawn state: the first whose cumulative belief passes u (the last one if
                // rounding leaves the total below u)
                let at = u[*group] * cumulative.last().copied().unwrap_or(1.0);
                let state = cumulative
                    .iter()
                    .position(|c| *c > at)
                    .unwrap_or(cumulative.len().saturating_sub(1));
                (*p, state == *ml)
            }),
        );
        passes += usize::from(d.is_calibrated());
        eces.push(d.ece);
        gaps.push(d.max_gap);
    }
    let quantiles = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        let at = |q: f64| v[((v.len() - 1) as f64 * q).round() as usize];
        [at(0.5), at(0.95)]
    };
    Chance {
        draws,
        ece: quantiles(&mut eces),
        max_gap: quantiles(&mut gaps),
        pass_rate: passes as f64 / draws as f64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `n` beliefs over four states with P(ML) = `p` (the rest spread evenly), in groups of
    /// `per_group`.
    fn beliefs(n: usize, p: f64, per_group: usize) -> Vec<(Vec<f64>, usize, f64, usize)> {
        let rest = (1.0 - p) / 3.0;
        (0..n)
            .map(|i| (vec![p, p + rest, p + 2.0 * rest, 1.0], 0, p, i / per_group))
            .collect()
    }

    #[test]
    fn certain_beliefs_are_calibrated_in_every_draw() {
        let c = chance_of(&EDGES, &beliefs(300, 1.0, 1), 300, 200, 1);
        assert_eq!((c.ece, c.max_gap, c.pass_rate), ([0.0; 2], [0.0; 2], 1.0));
    }

    #[test]
    fn many_independent_triplets_leave_little_to_chance() {
        // 3,000 triplets at P(ML) = 0.75: the drawn accuracy is 0.75 ± 0.008
        let c = chance_of(&EDGES, &beliefs(3000, 0.75, 1), 3000, 400, 2);
        assert!(c.ece[0] < 0.01 && c.ece[1] < 0.02, "{c:?}");
        assert!(c.ece[1] > c.ece[0] && c.pass_rate > 0.99, "{c:?}");
    }

    #[test]
    fn orderings_of_one_triplet_share_a_draw_and_widen_the_band() {
        // 180 ordered sets: as 180 triplets, or as 30 triplets in six orderings each
        let alone = chance_of(&EDGES, &beliefs(180, 0.75, 1), 180, 1000, 3);
        let six = chance_of(&EDGES, &beliefs(180, 0.75, 6), 30, 1000, 3);
        // one bin of 180 at p = 0.75: |accuracy − 0.75| has sd √(0.75·0.25/k), k the triplets
        let sd = |k: f64| (0.75f64 * 0.25 / k).sqrt();
        assert!((alone.ece[1] - 1.96 * sd(180.0)).abs() < 0.015, "{alone:?}");
        assert!((six.ece[1] - 1.96 * sd(30.0)).abs() < 0.03, "{six:?}");
        // P(|Z| > 0.05 / sd): 0.12 alone, 0.53 in sixes
        assert!(
            alone.pass_rate > 0.8 && six.pass_rate < 0.6,
            "{alone:?} {six:?}"
        );
    }

    #[test]
    fn the_same_seed_draws_the_same_band() {
        let b = beliefs(500, 0.8, 3);
        assert_eq!(
            chance_of(&EDGES, &b, 167, 300, 9),
            chance_of(&EDGES, &b, 167, 300, 9)
        );
        assert_ne!(
            chance_of(&EDGES, &b, 167, 300, 9),
            chance_of(&EDGES, &b, 167, 300, 10)
        );
    }
}
