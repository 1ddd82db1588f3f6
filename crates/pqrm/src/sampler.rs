//! Sampling the Gaussian inverse sensor model (thesis eq. 2.9).
//!
//! Each observed landmark is sampled `s` times **once per time step**, and the same samples
//! are reused for every landmark set that contains it. That is what makes the mapper fast
//! (m·s normal draws instead of m³·3s) and what makes the estimates of one step consistent
//! with each other: the six orderings of a triplet see the same sampled configurations.
//!
//! Every landmark's generator is seeded from `(seed, step, landmark id)` alone, so the samples
//! do not depend on which other landmarks were seen, on their order, or on the thread count.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;

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
pub fn landmark_rng(seed: u64, step: u64, id: LandmarkId) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(mix(seed ^ mix(step ^ mix(u64::from(id.0)))))
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
