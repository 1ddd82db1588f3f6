//! The honesty checks of the real-data study: the per-triplet majority vote, the reliability
//! diagram, and the survey check that names landmarks whose truth the measurements contradict.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::loaders::Dataset;
use pqrm::study::{noise_check, run_real};
use pqrm::{GroundTruth, LandmarkId, Observation, PqrmConfig, Scan};
use rand::SeedableRng;
use rand_distr::{Distribution, Normal};

fn obs(id: u32, xy: [f64; 2], sigma: f64) -> Observation {
    Observation::isotropic(LandmarkId(id), xy, sigma).unwrap()
}

fn truth(points: &[[f64; 2]]) -> GroundTruth {
    GroundTruth {
        positions: points
            .iter()
            .enumerate()
            .map(|(i, p)| (LandmarkId(i as u32), *p))
            .collect(),
    }
}

#[test]
fn the_majority_vote_takes_the_state_most_frames_saw_once_per_triplet() {
    // C left of A→B in two frames, right of it in one (an outlier frame), nearly noise-free.
    let left = [[0.0, 0.0], [0.0, 10.0], [-3.0, 5.0]];
    let right = [[0.0, 0.0], [0.0, 10.0], [3.0, 5.0]];
    let scan = |t: f64, p: &[[f64; 2]; 3]| {
        Scan::new(t, 1, (0..3).map(|i| obs(i, p[i as usize], 1e-3)).collect()).unwrap()
    };
    let data = Dataset {
        scans: vec![scan(0.0, &left), scan(1.0, &right), scan(2.0, &left)],
        truth: Some(truth(&left)),
        skipped: 0,
    };
    let config = PqrmConfig {
        samples: 200,
        ..PqrmConfig::default()
    };
    let r = run_real(&data, &["left-right".to_owned()], config, &|| ()).unwrap();
    let r = &r[0];
    // Six ordered triplets, each scored once by the vote and three times per frame.
    assert_eq!(r.majority.n, 6);
    assert_eq!(r.majority.error_rate, 0.0, "two frames of three say left");
    assert!((r.per_frame.error_rate - 1.0 / 3.0).abs() < 1e-12);
    // The truth on the outlier's side: every vote is wrong.
    let data = Dataset {
        truth: Some(truth(&right)),
        ..data
    };
    let r = run_real(&data, &["left-right".to_owned()], config, &|| ()).unwrap();
    assert_eq!(r[0].majority.error_rate, 1.0);
}

/// Twelve landmarks on a ring seen from a few places with noise σ.
fn ring(sigma: f64, frames: usize) -> (Dataset, Vec<[f64; 2]>) {
    let lm: Vec<[f64; 2]> = (0..12)
        .map(|i| {
            let a = f64::from(i) * 0.52;
            [6.0 * a.cos() + 0.2 * f64::from(i), 5.0 * a.sin()]
        })
        .collect();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let n = Normal::new(0.0, sigma).unwrap();
    let scans = (0..frames)
        .map(|t| {
            let o = lm
                .iter()
                .enumerate()
                .map(|(i, p)| {
                    obs(
                        i as u32,
                        [p[0] + n.sample(&mut rng), p[1] + n.sample(&mut rng)],
                        sigma,
                    )
                })
                .collect();
            Scan::new(t as f64, 1, o).unwrap()
        })
        .collect();
    (
        Dataset {
            scans,
            truth: Some(truth(&lm)),
            skipped: 0,
        },
        lm,
    )
}

#[test]
fn a_map_whose_model_matches_its_noise_is_calibrated_and_a_wrong_truth_is_not() {
    let (data, lm) = ring(0.5, 3);
    let config = PqrmConfig {
        samples: 2000,
        ..PqrmConfig::default()
    };
    let r = run_real(&data, &["double-cross".to_owned()], config, &|| ()).unwrap();
    let c = &r[0].calibration;
    let total: usize = c.bins.iter().map(|b| b.n).sum();
    assert_eq!(total, r[0].pqrm.n_scored);
    assert!(
        c.ece < 0.06,
        "a model that matches the noise: ECE {}",
        c.ece
    );
    // Two landmarks swapped in the survey: confident and wrong on their triplets.
    let mut swapped = lm.clone();
    swapped.swap(2, 7);
    let bad = Dataset {
        truth: Some(truth(&swapped)),
        ..data
    };
    let r = run_real(&bad, &["double-cross".to_owned()], config, &|| ()).unwrap();
    assert!(r[0].calibration.ece > 0.15, "ECE {}", r[0].calibration.ece);
}

#[test]
fn the_survey_check_names_swapped_landmarks_and_no_others() {
    let (data, lm) = ring(0.1, 20);
    assert!(noise_check(&data).unwrap().suspects.is_empty());
    let mut swapped = lm.clone();
    swapped.swap(3, 9);
    let bad = Dataset {
        truth: Some(truth(&swapped)),
        ..data
    };
    let check = noise_check(&bad).unwrap();
    let named: Vec<u32> = check.suspects.iter().map(|s| s.landmark).collect();
    let mut sorted = named.clone();
    sorted.sort_unstable();
    assert_eq!(sorted, vec![3, 9], "{:?}", check.suspects);
}
