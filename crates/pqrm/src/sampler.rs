//! Sampling the Gaussian inverse sensor model (thesis eq. 2.9).
//!
//! Each observed landmark is sampled `s` times **once per time step**, and the same samples
//! are reused for every landmark set that contains it. That is what makes the mapper fast
//! (m·s normal draws instead of m³·3s) and what makes the estimates of one step consistent
//! with each other: the six orderings of a triplet see the same sampled configurations.
//!
//! Every landmark's generator is seeded from `(seed, step, landmark id)` alone, so the samples
//! do not depend on which other landmarks were seen, on their order, or on the thread count.
//!
//! The generator is xoshiro256++ ([`Xoshiro256PlusPlus`]), not a ChaCha stream: Monte Carlo
//! sampling needs statistical quality, not unpredictability, and ChaCha8's block function was
//! half of the draws' time and a fifth of a PQRM step's (10 landmarks × 1,000 samples:
//! 0.077 → 0.035 ms on one thread, `cargo run --release -p pqrm --example step_timing`;
//! the samples of a given seed changed on 2026-11-29). Samples drawn elsewhere — a particle
//! filter's, or a recorded stream — go in through [`ScanSamples::from_columns`].

use rand::SeedableRng;
use rand::rngs::Xoshiro256PlusPlus;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

use crate::error::{PqrmError, Result};
use crate::observation::{LandmarkId, Scan};
use crate::sensor::SensorModel;

/// SplitMix64 finaliser: decorrelates the seeds of neighbouring (step, id) pairs.
#[must_use]
pub fn mix(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of one landmark at one step.
#[must_use]
pub fn landmark_rng(seed: u64, step: u64, id: LandmarkId) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(mix(seed ^ mix(step ^ mix(u64::from(id.0)))))
}

/// `s` samples of every landmark of one scan, as columns.
#[derive(Debug, Clone)]
pub struct ScanSamples {
    ids: Vec<LandmarkId>,
    xs: Vec<Vec<f64>>,
    ys: Vec<Vec<f64>>,
}

impl ScanSamples {
    /// Draws `samples` points from each observation's Gaussian (landmarks in parallel: each
    /// has its own generator, so the samples do not depend on the thread count).
    #[must_use]
    pub fn draw(scan: &Scan, samples: usize, seed: u64, step: u64) -> Self {
        Self::draw_with(scan, samples, seed, step, SensorModel::Gaussian)
    }

    /// As [`ScanSamples::draw`] under another inverse sensor model (the Gaussian's samples
    /// are the same bit for bit).
    #[must_use]
    pub fn draw_with(
        scan: &Scan,
        samples: usize,
        seed: u64,
        step: u64,
        model: SensorModel,
    ) -> Self {
        let (xs, ys): (Vec<Vec<f64>>, Vec<Vec<f64>>) = scan
            .observations
            .par_iter()
            .map(|o| {
                let mut rng = landmark_rng(seed, step, o.id);
                let [l11, l21, l22] = o.cholesky();
                let mut x = Vec::with_capacity(samples);
                let mut y = Vec::with_capacity(samples);
                if model != SensorModel::Gaussian {
                    for _ in 0..samples {
                        let p = model.sample(&mut rng, o.mean, [l11, l21, l22]);
                        x.push(p[0]);
                        y.push(p[1]);
                    }
                    return (x, y);
                }
                for _ in 0..samples {
                    let z1: f64 = StandardNormal.sample(&mut rng);
                    let z2: f64 = StandardNormal.sample(&mut rng);
                    x.push(o.mean[0] + l11 * z1);
                    y.push(o.mean[1] + l21 * z1 + l22 * z2);
                }
                (x, y)
            })
            .unzip();
        Self {
            ids: scan.observations.iter().map(|o| o.id).collect(),
            xs,
            ys,
        }
    }

    /// Samples drawn elsewhere: landmark `ids[i]` has the points `(xs[i][u], ys[i][u])`.
    /// Every landmark has the same number of samples (the kernel pairs sample `u` of each
    /// landmark of a set), ids are strictly increasing (as a [`Scan`]'s are), and every
    /// coordinate is finite.
    ///
    /// # Errors
    /// [`PqrmError::InvalidConfig`] for columns of different lengths, none at all, or unsorted
    /// or repeated ids, [`PqrmError::NonFinite`] for a NaN or infinite coordinate (naming landmark and
    /// sample).
    ///
    /// ```
    /// use pqrm::{LandmarkId, ScanSamples};
    /// let ids = vec![LandmarkId(1), LandmarkId(4)];
    /// let s = ScanSamples::from_columns(ids, vec![vec![0.0, 0.1], vec![3.0, 2.9]],
    ///                                   vec![vec![0.0, 0.0], vec![1.0, 1.1]]).unwrap();
    /// assert_eq!(s.samples(), 2);
    /// assert!(ScanSamples::from_columns(vec![LandmarkId(1)], vec![vec![f64::NAN]],
    ///                                   vec![vec![0.0]]).is_err());
    /// ```
    pub fn from_columns(
        ids: Vec<LandmarkId>,
        xs: Vec<Vec<f64>>,
        ys: Vec<Vec<f64>>,
    ) -> Result<Self> {
        if xs.len() != ids.len() || ys.len() != ids.len() {
            return Err(PqrmError::InvalidConfig(format!(
                "samples: {} ids but {} x columns and {} y columns",
                ids.len(),
                xs.len(),
                ys.len()
            )));
        }
        if let Some(w) = ids.windows(2).find(|w| w[0] >= w[1]) {
            return Err(PqrmError::InvalidConfig(format!(
                "samples: landmark ids must be strictly increasing, {} comes before {}",
                w[0], w[1]
            )));
        }
        let s = xs.first().map_or(0, Vec::len);
        if s == 0 && !ids.is_empty() {
            return Err(PqrmError::InvalidConfig(
                "samples: every landmark needs at least one sample, the first has none".into(),
            ));
        }
        for ((id, x), y) in ids.iter().zip(&xs).zip(&ys) {
            if x.len() != s || y.len() != s {
                return Err(PqrmError::InvalidConfig(format!(
                    "samples: landmark {id} has {} x and {} y samples, the first landmark {s}",
                    x.len(),
                    y.len()
                )));
            }
            if let Some(u) = x
                .iter()
                .zip(y)
                .position(|(a, b)| !(a.is_finite() && b.is_finite()))
            {
                return Err(PqrmError::NonFinite(format!(
                    "landmark {id}, sample {u}: ({}, {})",
                    x[u], y[u]
                )));
            }
        }
        Ok(Self { ids, xs, ys })
    }

    /// Landmarks in the scan, sorted.
    #[must_use]
    pub fn ids(&self) -> &[LandmarkId] {
        &self.ids
    }

    /// Samples `(xs, ys)` of the i-th landmark.
    #[must_use]
    pub fn columns(&self, i: usize) -> (&[f64], &[f64]) {
        (&self.xs[i], &self.ys[i])
    }

    /// Samples per landmark.
    #[must_use]
    pub fn samples(&self) -> usize {
        self.xs.first().map_or(0, Vec::len)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)] // tests: a panic is the failure report
    use super::*;

    /// Samples from elsewhere: every malformed input is a typed error naming what is wrong,
    /// and well-formed columns come back as given.
    #[test]
    fn columns_from_elsewhere_are_checked() {
        let ids = |v: &[u32]| v.iter().map(|&i| LandmarkId(i)).collect::<Vec<_>>();
        let col = |n: usize| vec![vec![0.5; n], vec![1.5; n]];
        let s = ScanSamples::from_columns(ids(&[2, 7]), col(3), col(3)).unwrap();
        assert_eq!((s.ids(), s.samples()), (&ids(&[2, 7])[..], 3));
        assert_eq!(s.columns(1), (&[1.5; 3][..], &[1.5; 3][..]));
        let err = |i: &[u32], xs: Vec<Vec<f64>>, ys: Vec<Vec<f64>>| {
            ScanSamples::from_columns(ids(i), xs, ys)
                .unwrap_err()
                .to_string()
        };
        assert!(err(&[7, 2], col(3), col(3)).contains("strictly increasing"));
        assert!(err(&[2, 2], col(3), col(3)).contains("strictly increasing"));
        assert!(err(&[2], col(3), col(3)).contains("1 ids but 2 x columns"));
        assert!(err(&[2, 7], col(0), col(0)).contains("at least one sample"));
        assert!(err(&[2, 7], col(3), vec![vec![0.0; 3], vec![0.0; 2]]).contains("landmark 7"));
        let mut bad = col(3);
        bad[1][2] = f64::NAN;
        let e = err(&[2, 7], bad, col(3));
        assert!(e.contains("landmark 7, sample 2"), "{e}");
        assert!(
            ScanSamples::from_columns(Vec::new(), Vec::new(), Vec::new())
                .unwrap()
                .ids()
                .is_empty()
        );
    }
}
