//! [`SurveyAgreement`]: whether the survey a map is scored against agrees with what the robots
//! saw, and [`SurveySplit`]: the map's calibration on the sets where it does and where it
//! does not.
//!
//! A recorded map is judged against surveyed landmark positions. Where every robot sees a
//! landmark pair's distance differently from the survey — a landmark moved after the survey,
//! a slip in the survey, an error every robot's perception makes alike — the map's "error" on
//! the sets with that pair is the survey disagreeing with all of the map's evidence, and no
//! model of the robots' noise can hedge for it without the survey. On MRCLAM Dataset 5, 24
//! of 102 landmark pairs are seen 0.12–0.41 m short of the survey in the median of every
//! frame that saw them, and the map's overconfidence sits on the sets with such a pair
//! (`docs/calibration.md`, "The survey against the robots"). Splitting the score lets a
//! report say which of its misses the survey explains; it changes no verdict.
//!
//! A pair is *off the survey* when the median over the frames that saw both landmarks (at
//! least [`MIN_FRAMES`]) of the distance seen minus the surveyed distance is beyond
//! [`OFF_SURVEY_M`] and beyond [`STANDARD_ERRORS`] standard errors of that median (the frames'
//! spread taken from their median absolute deviation), so that a pair seen a few times by a
//! noisy sensor is not called off by chance. The median, so that the gross outliers a robot
//! makes now and then do not count; distances, so that neither the robots' poses nor the
//! survey's frame are needed.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::calibration::{Calibration, diagram};
use crate::error::Result;
use crate::likelihood::LandmarkSet;
use crate::map::Pqrm;
use crate::metrics::GroundTruth;
use crate::observation::{LandmarkId, Scan};

/// Beyond this median offset (m) a landmark pair can be off the survey: 3–5 % of the distances
/// between MRCLAM's landmark clusters, and about what one robot's frames of a pair spread by
/// (σ 0.11–0.16 m, `scripts/shared_error_anova.py`) — a median beyond it, over many frames,
/// is no frame's noise.
pub const OFF_SURVEY_M: f64 = 0.1;

/// How many standard errors of its median a pair's offset must also exceed.
pub const STANDARD_ERRORS: f64 = 3.0;

/// Frames a pair needs before its median is trusted.
pub const MIN_FRAMES: usize = 5;

/// One landmark pair off the survey.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PairOffset {
    /// The two landmarks, the smaller id first.
    pub pair: [LandmarkId; 2],
    /// Median over frames of the distance seen minus the surveyed one (m).
    pub median: f64,
    /// Frames that saw both.
    pub frames: usize,
}

/// How the survey agrees with a recording's frames.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SurveyAgreement {
    /// Pairs of surveyed landmarks seen together in at least [`MIN_FRAMES`] frames.
    pub pairs_seen: usize,
    /// Those off the survey, by pair.
    pub off: Vec<PairOffset>,
}

impl SurveyAgreement {
    /// Measures the pairs of `scans` against `truth` (see the module docs): `off_m` the
    /// largest median offset that still agrees, `min_frames` the frames a pair needs (the
    /// median must also be [`STANDARD_ERRORS`] standard errors from 0).
    /// Non-finite positions are skipped.
    #[must_use]
    pub fn measure(scans: &[Scan], truth: &GroundTruth, off_m: f64, min_frames: usize) -> Self {
        let mut seen: BTreeMap<[LandmarkId; 2], Thinned> = BTreeMap::new();
        for scan in scans {
            let obs: Vec<_> = scan
                .observations
                .iter()
                .filter_map(|o| truth.positions.get(&o.id).map(|p| (o, p)))
                .collect();
            for (i, (a, pa)) in obs.iter().enumerate() {
                for (b, pb) in &obs[i + 1..] {
                    let d_seen = (a.mean[0] - b.mean[0]).hypot(a.mean[1] - b.mean[1]);
                    let d_true = (pa[0] - pb[0]).hypot(pa[1] - pb[1]);
                    let v = d_seen - d_true;
                    if v.is_finite() {
                        // observations are sorted by id: `a` is the smaller
                        seen.entry([a.id, b.id]).or_default().push(v);
                    }
                }
            }
        }
        let mut out = Self::default();
        for (pair, mut kept) in seen {
            let frames = kept.frames;
            if frames < min_frames.max(1) {
                continue;
            }
            out.pairs_seen += 1;
            let v = &mut kept.values;
            let mid = median(v);
            // the median's standard error: 1.2533·σ/√n for normal frames, σ from the MAD
            let mut dev: Vec<f64> = v.iter().map(|x| (x - mid).abs()).collect();
            let sigma = 1.4826 * median(&mut dev);
            let se = 1.2533 * sigma / (frames as f64).sqrt();
            if mid.abs() > off_m && mid.abs() > STANDARD_ERRORS * se {
                out.off.push(PairOffset {
                    pair,
                    median: mid,
                    frames,
                });
            }
        }
        out
    }

    /// Whether any pair of `set` is off the survey.
    #[must_use]
    pub fn disputes(&self, set: &LandmarkSet) -> bool {
        let [a, b, c] = set.0;
        [[a, b], [a, c], [b, c]].iter().any(|&[x, y]| {
            let pair = if x <= y { [x, y] } else { [y, x] };
            self.off.binary_search_by(|p| p.pair.cmp(&pair)).is_ok()
        })
    }
}

/// Most offsets kept per pair: a long recording's pairs keep an evenly thinned subsample
/// (every `stride`-th frame), so memory stays bounded (≤ 32 KiB a pair) where a recording of
/// 10⁵ frames of 20 landmarks would otherwise hold 150 MB; the median of 4,096 values is
/// within about 2 % of σ of the median of all.
const KEEP: usize = 4096;

/// One pair's offsets, thinned to at most [`KEEP`] (deterministic: every `stride`-th frame,
/// the stride doubling each time the subsample fills).
#[derive(Debug, Default)]
struct Thinned {
    values: Vec<f64>,
    /// Frames that saw the pair.
    frames: usize,
    stride: usize,
}

impl Thinned {
    fn push(&mut self, v: f64) {
        let stride = self.stride.max(1);
        if self.frames.is_multiple_of(stride) {
            self.values.push(v);
            if self.values.len() >= KEEP {
                // keep every other one: the frames at multiples of twice the stride
                let mut k = 0;
                self.values.retain(|_| {
                    k += 1;
                    k % 2 == 1
                });
                self.stride = stride * 2;
            }
        }
        self.frames += 1;
    }
}

/// The median of `v` (not empty; reorders it).
pub(crate) fn median(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    let upper = *m;
    if v.len() % 2 == 1 {
        return upper;
    }
    let lower = v[..mid].iter().copied().fold(f64::NEG_INFINITY, f64::max);
    0.5 * (lower + upper)
}

/// A map's calibration on the sets the survey agrees on and on those it disputes.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct SurveySplit {
    /// Pairs seen in enough frames ([`SurveyAgreement::pairs_seen`]).
    pub pairs_seen: usize,
    /// Of them, off the survey.
    pub pairs_off: usize,
    /// Sets with no pair off the survey.
    pub agreed: Calibration,
    /// Sets with one.
    pub disputed: Calibration,
}

/// Splits `map`'s reliability diagram by `agreement` (sets with a true state only).
///
/// # Errors
/// Truth errors (coincident surveyed landmarks).
pub fn split(map: &Pqrm, truth: &GroundTruth, agreement: &SurveyAgreement) -> Result<SurveySplit> {
    let (mut agreed, mut disputed) = (Vec::new(), Vec::new());
    for (set, belief) in map.iter() {
        let Some(t) = truth.state(map.calculus(), set)? else {
            continue;
        };
        let ml = belief.ml_state();
        let scored = (belief.probabilities()[ml.index()], ml == t);
        if agreement.disputes(set) {
            disputed.push(scored);
        } else {
            agreed.push(scored);
        }
    }
    Ok(SurveySplit {
        pairs_seen: agreement.pairs_seen,
        pairs_off: agreement.off.len(),
        agreed: diagram(agreed),
        disputed: diagram(disputed),
    })
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // tests: a panic is the failure report
    use super::*;
    use crate::observation::Observation;

    fn scan(t: f64, points: &[(u32, [f64; 2])]) -> Scan {
        let obs = points
            .iter()
            .map(|&(id, p)| Observation::isotropic(LandmarkId(id), p, 0.05).unwrap())
            .collect();
        Scan::new(t, 0, obs).unwrap()
    }

    /// A landmark that stood 0.3 m from its surveyed place: every pair with it is off the
    /// survey, by its median (one wild frame does not move it), and no other pair is; a pair
    /// seen too rarely is not judged; a set is disputed exactly when it holds such a pair.
    #[test]
    fn a_landmark_away_from_its_survey_puts_its_pairs_off_and_no_other() {
        let surveyed = [[0.0, 0.0], [4.0, 0.0], [0.0, 3.0], [4.0, 3.0]];
        let mut actual = surveyed;
        actual[3] = [4.3, 3.3]; // landmark 3 stood 0.3 m off in x and in y
        let truth = GroundTruth {
            positions: (0..4)
                .map(|i| (LandmarkId(i), surveyed[i as usize]))
                .collect(),
        };
        // the robot at (1, 1): frames see the actual layout shifted (no rotation needed:
        // distances only), with ±1 cm of alternating noise per id
        let mut scans: Vec<Scan> = (0..9)
            .map(|k| {
                let e = if k % 2 == 0 { 0.01 } else { -0.01 };
                let pts: Vec<(u32, [f64; 2])> = (0..4)
                    .map(|i| {
                        let p = actual[i as usize];
                        (i, [p[0] - 1.0 + e * f64::from(i), p[1] - 1.0])
                    })
                    .collect();
                scan(f64::from(k), &pts)
            })
            .collect();
        // one wild frame: landmark 0 seen 5 m off
        scans.push(scan(
            10.0,
            &[(0, [4.0, -1.0]), (1, [3.0, -1.0]), (2, [-1.0, 2.0])],
        ));
        // landmark 9 (surveyed nowhere) is ignored
        scans.push(scan(11.0, &[(0, [0.0, 0.0]), (9, [1.0, 1.0])]));
        let a = SurveyAgreement::measure(&scans, &truth, OFF_SURVEY_M, MIN_FRAMES);
        assert_eq!(a.pairs_seen, 6);
        let off: Vec<[u32; 2]> = a.off.iter().map(|p| [p.pair[0].0, p.pair[1].0]).collect();
        assert_eq!(off, vec![[0, 3], [1, 3], [2, 3]], "{a:?}");
        // the medians are the offsets of the distances
        let want = [
            4.3f64.hypot(3.3) - 5.0,
            0.3f64.hypot(3.3) - 3.0,
            4.3f64.hypot(0.3) - 4.0,
        ];
        for (p, w) in a.off.iter().zip(want) {
            assert!((p.median - w).abs() < 0.05, "{p:?}: want {w}");
            assert_eq!(p.frames, 9);
        }
        let set = |x: u32, y: u32, z: u32| LandmarkSet::new(x, y, z);
        assert!(a.disputes(&set(3, 0, 1)));
        assert!(a.disputes(&set(1, 2, 3)));
        assert!(!a.disputes(&set(0, 1, 2)));
        assert!(!a.disputes(&set(2, 1, 0)));
        // a stricter frame count judges nothing
        let none = SurveyAgreement::measure(&scans, &truth, OFF_SURVEY_M, 100);
        assert_eq!((none.pairs_seen, none.off.len()), (0, 0));
    }

    /// Five frames whose distances scatter by ±0.5 m: a median 0.12 m off is within three of
    /// its standard errors, so the pair is not off; the same median from tight frames is.
    #[test]
    fn a_pair_whose_frames_scatter_is_not_called_off_by_its_median_alone() {
        let truth = GroundTruth {
            positions: [(LandmarkId(1), [0.0, 0.0]), (LandmarkId(2), [3.0, 0.0])].into(),
        };
        let frames = |offsets: &[f64]| -> Vec<Scan> {
            offsets
                .iter()
                .enumerate()
                .map(|(k, e)| scan(k as f64, &[(1, [0.0, 0.0]), (2, [3.0 + e, 0.0])]))
                .collect()
        };
        let loose = frames(&[0.5, -0.4, 0.3, -0.35, 0.12]);
        let a = SurveyAgreement::measure(&loose, &truth, OFF_SURVEY_M, MIN_FRAMES);
        assert_eq!((a.pairs_seen, a.off.len()), (1, 0), "{a:?}");
        let tight = frames(&[0.13, 0.11, 0.12, 0.125, 0.12]);
        let a = SurveyAgreement::measure(&tight, &truth, OFF_SURVEY_M, MIN_FRAMES);
        assert_eq!(a.off.len(), 1, "{a:?}");
        assert!((a.off[0].median - 0.12).abs() < 1e-9);
    }

    /// A long recording's pair keeps at most `KEEP` offsets, exactly the frames at multiples
    /// of its stride (evenly spread over the recording), and counts every frame.
    #[test]
    fn a_long_pair_keeps_an_even_subsample_and_counts_every_frame() {
        for n in [1, KEEP - 1, KEEP, KEEP + 1, 3 * KEEP + 5, 10_000] {
            let mut t = Thinned::default();
            (0..n).for_each(|k| t.push(k as f64));
            assert_eq!(t.frames, n);
            assert!(
                t.values.len() <= KEEP && t.values.len() >= n.min(KEEP / 2),
                "{n}"
            );
            let stride = t.stride.max(1);
            let want: Vec<f64> = (0..n).step_by(stride).map(|k| k as f64).collect();
            assert_eq!(t.values, want, "{n}");
        }
        // through `measure`: 10,001 frames whose offsets cycle about 0.2 m
        let truth = GroundTruth {
            positions: [(LandmarkId(1), [0.0, 0.0]), (LandmarkId(2), [3.0, 0.0])].into(),
        };
        let scans: Vec<Scan> = (0..10_001)
            .map(|k| {
                let e = 0.2 + 0.01 * f64::from(k % 7 - 3);
                scan(f64::from(k), &[(1, [0.0, 0.0]), (2, [3.0 + e, 0.0])])
            })
            .collect();
        let a = SurveyAgreement::measure(&scans, &truth, OFF_SURVEY_M, MIN_FRAMES);
        assert_eq!(a.off.len(), 1);
        assert_eq!(a.off[0].frames, 10_001);
        assert!((a.off[0].median - 0.2).abs() < 1e-9, "{}", a.off[0].median);
    }

    #[test]
    fn the_median_of_odd_and_even_counts() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [4.0, 1.0, 3.0, 2.0]), 2.5);
        assert_eq!(median(&mut [-1.0]), -1.0);
    }
}
