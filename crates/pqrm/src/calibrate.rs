//! Sensor noise from the data, without ground truth.
//!
//! The distance between two landmarks seen in the same frame does not depend on the robot's
//! pose, so its spread across frames measures the sensor. For a range-bearing sensor with
//! noise σ_r, σ_b, a measured distance `d = |p_i − p_j|` has variance (to first order)
//!
//! `var d = σ_r² · a + σ_b² · b`,  `a = Σ_k (u·e_r,k)²`,  `b = Σ_k r_k² (u·e_θ,k)²`,
//!
//! over the two landmarks k (range `r_k`, radial and tangential unit vectors `e_r,k`, `e_θ,k`,
//! `u` the unit vector between them). Each pair's residuals about its median distance over the
//! frames that saw it give one equation per frame; σ_r² and σ_b² are fitted by iteratively
//! reweighted least squares on the inliers (|z| ≤ 3), and the outlier rate is the share of
//! residuals beyond 3σ in excess of the Gaussian's 0.27 %.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::loaders::Dataset;

/// Pairs seen in fewer frames carry no usable spread.
pub const MIN_FRAMES_PER_PAIR: usize = 5;

/// The fitted noise of a range-bearing sensor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseFit {
    /// Range standard deviation (m).
    pub sigma_range: f64,
    /// Bearing standard deviation (rad).
    pub sigma_bearing: f64,
    /// Share of detections beyond 3σ in excess of a Gaussian's (gross outliers).
    pub outlier_rate: f64,
    /// Landmark pairs used (seen together in at least [`MIN_FRAMES_PER_PAIR`] frames).
    pub pairs: usize,
    /// Residuals used.
    pub residuals: usize,
    /// The longest range observed (m): the field of view an outlier can land in.
    pub max_range: f64,
}

/// One residual: a pair's distance in one frame minus its median, and the σ the fit predicts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    /// Measured minus median distance (m), corrected for the median's own noise.
    pub residual: f64,
    /// Predicted standard deviation under the fit (m).
    pub sigma: f64,
}

struct Row {
    e: f64,
    a: f64,
    b: f64,
}

fn rows(dataset: &Dataset) -> (Vec<Row>, usize, f64) {
    // Per unordered pair: (distance, a, b) in every frame that saw both.
    let mut per_pair: BTreeMap<(u32, u32), Vec<[f64; 3]>> = BTreeMap::new();
    let mut max_range = 0.0_f64;
    for scan in &dataset.scans {
        for (i, p) in scan.observations.iter().enumerate() {
            max_range = max_range.max(p.mean[0].hypot(p.mean[1]));
            for q in &scan.observations[i + 1..] {
                let d = [p.mean[0] - q.mean[0], p.mean[1] - q.mean[1]];
                let dist = d[0].hypot(d[1]);
                if dist <= 0.0 || !dist.is_finite() {
                    continue;
                }
                let u = [d[0] / dist, d[1] / dist];
                let (mut a, mut b) = (0.0, 0.0);
                for m in [p.mean, q.mean] {
                    let r = m[0].hypot(m[1]);
                    if r <= 0.0 {
                        continue;
                    }
                    let er = [m[0] / r, m[1] / r];
                    let radial = u[0] * er[0] + u[1] * er[1];
                    let tangential = -u[0] * er[1] + u[1] * er[0];
                    a += radial * radial;
                    b += r * r * tangential * tangential;
                }
                per_pair
                    .entry((p.id.0, q.id.0))
                    .or_default()
                    .push([dist, a, b]);
            }
        }
    }
    let mut out = Vec::new();
    let mut pairs = 0;
    for obs in per_pair.values() {
        let n = obs.len();
        if n < MIN_FRAMES_PER_PAIR {
            continue;
        }
        pairs += 1;
        let mut ds: Vec<f64> = obs.iter().map(|o| o[0]).collect();
        ds.sort_by(f64::total_cmp);
        let median = ds[n / 2];
        // A residual about the sample median has about (1 − 1/n)… of the variance; inflate
        // it back (the exact factor for the mean is n/(n−1); close enough for the median).
        let c = (n as f64 / (n as f64 - 1.0)).sqrt();
        out.extend(obs.iter().map(|&[d, a, b]| Row {
            e: (d - median) * c,
            a,
            b,
        }));
    }
    (out, pairs, max_range)
}

/// Weighted least squares of `e² ≈ x·a + y·b` with weights `w`, x, y ≥ 0.
fn solve(rows: &[&Row], w: &[f64]) -> (f64, f64) {
    let (mut saa, mut sab, mut sbb, mut sae, mut sbe) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (r, w) in rows.iter().zip(w) {
        let e2 = r.e * r.e;
        saa += w * r.a * r.a;
        sab += w * r.a * r.b;
        sbb += w * r.b * r.b;
        sae += w * r.a * e2;
        sbe += w * r.b * e2;
    }
    let det = saa * sbb - sab * sab;
    let (x, y) = if det.abs() > 1e-300 {
        ((sae * sbb - sbe * sab) / det, (saa * sbe - sab * sae) / det)
    } else {
        (0.0, 0.0)
    };
    match (x >= 0.0, y >= 0.0) {
        (true, true) => (x, y),
        // One component negative: fit the other alone.
        (false, _) if sbb > 0.0 => (0.0, (sbe / sbb).max(0.0)),
        (_, false) if saa > 0.0 => ((sae / saa).max(0.0), 0.0),
        _ => (0.0, 0.0),
    }
}

/// Fits range and bearing noise and the outlier rate from the spread of pairwise distances.
///
/// # Errors
/// [`PqrmError::Mismatch`] when no landmark pair is seen together in enough frames.
pub fn fit_noise(dataset: &Dataset) -> Result<NoiseFit> {
    let (rows, pairs, max_range) = rows(dataset);
    if rows.len() < 20 {
        return Err(PqrmError::Mismatch(format!(
            "the noise fit needs landmark pairs seen together in {MIN_FRAMES_PER_PAIR} or more frames; \
             this recording has {} usable residuals",
            rows.len()
        )));
    }
    let all: Vec<&Row> = rows.iter().collect();
    let (mut x, mut y) = solve(&all, &vec![1.0; all.len()]);
    // 3σ-truncated Gaussian: the variance of the inliers is 0.9733 of the whole.
    const TRUNCATED_VARIANCE: f64 = 0.973_35;
    for _ in 0..30 {
        let var = |r: &Row| (x * r.a + y * r.b).max(1e-300);
        let inliers: Vec<&Row> = rows.iter().filter(|r| r.e * r.e <= 9.0 * var(r)).collect();
        if inliers.len() < 10 {
            break;
        }
        let w: Vec<f64> = inliers.iter().map(|r| 1.0 / var(r).powi(2)).collect();
        let (nx, ny) = solve(&inliers, &w);
        let (nx, ny) = (nx / TRUNCATED_VARIANCE, ny / TRUNCATED_VARIANCE);
        let done = (nx - x).abs() <= 1e-9 * x.max(1e-30) && (ny - y).abs() <= 1e-9 * y.max(1e-30);
        (x, y) = (nx, ny);
        if done {
            break;
        }
    }
    let beyond = rows
        .iter()
        .filter(|r| r.e * r.e > 9.0 * (x * r.a + y * r.b))
        .count() as f64
        / rows.len() as f64;
    Ok(NoiseFit {
        sigma_range: x.sqrt(),
        sigma_bearing: y.sqrt(),
        outlier_rate: (beyond - 0.0027).max(0.0),
        pairs,
        residuals: rows.len(),
        max_range,
    })
}

/// Every residual with the σ the fit predicts for it (for a plot of residuals against the
/// model).
#[must_use]
pub fn residuals(dataset: &Dataset, fit: &NoiseFit) -> Vec<Residual> {
    let (rows, _, _) = rows(dataset);
    rows.iter()
        .map(|r| Residual {
            residual: r.e,
            sigma: (fit.sigma_range.powi(2) * r.a + fit.sigma_bearing.powi(2) * r.b).sqrt(),
        })
        .collect()
}

/// What [`gate_outliers`] removed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Gated {
    /// Detections removed.
    pub detections: usize,
    /// Detections looked at.
    pub of: usize,
}

/// Removes gross outliers frame by frame: a detection whose distances to the other landmarks
/// of its frame disagree with those pairs' medians over the whole recording (median |z| over
/// its pairs > `z_max` under `fit`) is dropped. A frame needs three or more other landmarks
/// with known pairs to judge one, so small frames are kept whole.
#[must_use]
pub fn gate_outliers(dataset: &Dataset, fit: &NoiseFit, z_max: f64) -> (Dataset, Gated) {
    let mut medians: BTreeMap<(u32, u32), Vec<f64>> = BTreeMap::new();
    for scan in &dataset.scans {
        for (i, p) in scan.observations.iter().enumerate() {
            for q in &scan.observations[i + 1..] {
                let d = (p.mean[0] - q.mean[0]).hypot(p.mean[1] - q.mean[1]);
                medians.entry((p.id.0, q.id.0)).or_default().push(d);
            }
        }
    }
    let medians: BTreeMap<(u32, u32), f64> = medians
        .into_iter()
        .filter(|(_, v)| v.len() >= MIN_FRAMES_PER_PAIR)
        .map(|(k, mut v)| {
            v.sort_by(f64::total_cmp);
            (k, v[v.len() / 2])
        })
        .collect();
    let mut gated = Gated::default();
    let mut out = dataset.clone();
    for scan in &mut out.scans {
        let obs = &scan.observations;
        gated.of += obs.len();
        let keep: Vec<bool> = obs
            .iter()
            .map(|p| {
                let mut z: Vec<f64> = obs
                    .iter()
                    .filter(|q| q.id != p.id)
                    .filter_map(|q| {
                        let key = if p.id < q.id {
                            (p.id.0, q.id.0)
                        } else {
                            (q.id.0, p.id.0)
                        };
                        let m = medians.get(&key)?;
                        let d = [p.mean[0] - q.mean[0], p.mean[1] - q.mean[1]];
                        let dist = d[0].hypot(d[1]);
                        let u = [d[0] / dist, d[1] / dist];
                        let (mut a, mut b) = (0.0, 0.0);
                        for m in [p.mean, q.mean] {
                            let r = m[0].hypot(m[1]);
                            if r > 0.0 {
                                let (rad, tan) = (
                                    (u[0] * m[0] + u[1] * m[1]) / r,
                                    (-u[0] * m[1] + u[1] * m[0]) / r,
                                );
                                a += rad * rad;
                                b += r * r * tan * tan;
                            }
                        }
                        let s =
                            (fit.sigma_range.powi(2) * a + fit.sigma_bearing.powi(2) * b).sqrt();
                        (s > 0.0 && dist.is_finite()).then(|| (dist - m).abs() / s)
                    })
                    .collect();
                if z.len() < 3 {
                    return true;
                }
                z.sort_by(f64::total_cmp);
                z[z.len() / 2] <= z_max
            })
            .collect();
        let before = scan.observations.len();
        let mut k = keep.iter();
        scan.observations.retain(|_| *k.next().unwrap_or(&true));
        gated.detections += before - scan.observations.len();
    }
    out.scans.retain(|s| !s.observations.is_empty());
    (out, gated)
}
