//! The noise fit from pairwise distances recovers a simulated sensor's noise and outlier rate
//! without ground truth.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::calibrate::{fit_noise, residuals};
use pqrm::loaders::Dataset;
use pqrm::{LandmarkId, Observation, Scan};
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};

/// Ten landmarks seen from 300 random poses by a range-bearing sensor.
fn recording(sigma_r: f64, sigma_b: f64, outliers: f64, seed: u64) -> Dataset {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let lm: Vec<[f64; 2]> = (0..10)
        .map(|_| [rng.random_range(-8.0..8.0), rng.random_range(-8.0..8.0)])
        .collect();
    let nr = Normal::new(0.0, sigma_r).unwrap();
    let nb = Normal::new(0.0, sigma_b).unwrap();
    let scans = (0..300)
        .map(|t| {
            let (px, py, th) = (
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(-3.1..3.1),
            );
            let obs = lm
                .iter()
                .enumerate()
                .map(|(i, l)| {
                    let (dx, dy) = (l[0] - px, l[1] - py);
                    let r = dx.hypot(dy) + nr.sample(&mut rng);
                    let b = dy.atan2(dx) - th + nb.sample(&mut rng);
                    let mut xy = [r * b.cos(), r * b.sin()];
                    if rng.random::<f64>() < outliers {
                        let (rr, a) = (
                            20.0 * rng.random::<f64>().sqrt(),
                            std::f64::consts::TAU * rng.random::<f64>(),
                        );
                        xy = [rr * a.cos(), rr * a.sin()];
                    }
                    Observation::isotropic(LandmarkId(i as u32), xy, 0.1).unwrap()
                })
                .collect();
            Scan::new(f64::from(t), 1, obs).unwrap()
        })
        .collect();
    Dataset {
        scans,
        truth: None,
        skipped: 0,
    }
}

#[test]
fn the_fit_recovers_range_and_bearing_noise_and_the_outlier_rate() {
    // The last case's bearing noise moves points by ~4 cm against 20 cm of range noise: it is
    // identified less well (tolerance 30 %).
    for (sr, sb, out, seed, tol_b) in [
        (0.1, 0.02, 0.0, 1, 0.15),
        (0.05, 0.01, 0.03, 2, 0.15),
        (0.2, 0.005, 0.05, 3, 0.3),
    ] {
        let f = fit_noise(&recording(sr, sb, out, seed)).unwrap();
        assert!(
            (f.sigma_range / sr - 1.0).abs() < 0.15,
            "σ_r {} for {sr}",
            f.sigma_range
        );
        assert!(
            (f.sigma_bearing / sb - 1.0).abs() < tol_b,
            "σ_b {} for {sb}",
            f.sigma_bearing
        );
        // An outlier spoils every pair it is in for that frame: the residual rate is up to
        // twice the detection rate; the fit reports the residual share.
        assert!(
            f.outlier_rate <= 2.0 * out + 0.01,
            "outliers {} for {out}",
            f.outlier_rate
        );
        assert!(
            f.outlier_rate >= out * 0.8,
            "outliers {} for {out}",
            f.outlier_rate
        );
        assert_eq!(f.pairs, 45);
    }
}

#[test]
fn residuals_under_the_fit_are_standard_normal_inside_three_sigma() {
    let data = recording(0.1, 0.02, 0.0, 9);
    let f = fit_noise(&data).unwrap();
    let z: Vec<f64> = residuals(&data, &f)
        .iter()
        .map(|r| r.residual / r.sigma)
        .collect();
    let var = z.iter().map(|v| v * v).sum::<f64>() / z.len() as f64;
    assert!((var - 1.0).abs() < 0.1, "var {var}");
}

#[test]
fn too_little_data_is_a_typed_error() {
    let mut d = recording(0.1, 0.02, 0.0, 4);
    d.scans.truncate(3);
    assert!(fit_noise(&d).is_err());
}

#[test]
fn gating_removes_the_outliers_and_keeps_the_honest_detections() {
    use pqrm::calibrate::gate_outliers;
    let clean = recording(0.05, 0.01, 0.0, 5);
    let f = fit_noise(&clean).unwrap();
    let (_, g) = gate_outliers(&clean, &f, 3.0);
    assert!(
        (g.detections as f64) < 0.01 * g.of as f64,
        "gated {} of {} honest detections",
        g.detections,
        g.of
    );
    let dirty = recording(0.05, 0.01, 0.05, 5);
    let f = fit_noise(&dirty).unwrap();
    let (_, g) = gate_outliers(&dirty, &f, 3.0);
    let share = g.detections as f64 / g.of as f64;
    assert!(
        (0.035..0.07).contains(&share),
        "gated {share} with 5 % outliers"
    );
}
