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
    let k = EDGES.len() - 1;
    let (mut n, mut conf, mut hits) = (vec![0usize; k], vec![0.0; k], vec![0usize; k]);
    for (set, belief) in map.iter() {
        let Some(t) = truth.state(map.calculus(), set)? else {
            continue;
        };
        let ml = belief.ml_state();
        let p = belief.probabilities()[ml.index()];
        let bin = EDGES[1..].iter().position(|&hi| p < hi).unwrap_or(k - 1);
        n[bin] += 1;
        conf[bin] += p;
        hits[bin] += usize::from(ml == t);
    }
    let total: usize = n.iter().sum();
    let mut out = Calibration::default();
    for b in 0..k {
        if n[b] == 0 {
            continue;
        }
        let bin = CalibrationBin {
            lo: EDGES[b],
            hi: EDGES[b + 1],
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
    Ok(out)
}
