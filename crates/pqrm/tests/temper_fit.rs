//! The tempering exponent chosen from the data (`pqrm::temper::fit_temper`): it must see
//! correlated frames for what they are and make the map honest, with no ground truth.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::BTreeMap;

use pqrm::calibration::calibration;
use pqrm::temper::{TemperOptions, fit_temper};
use pqrm::{GroundTruth, LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

const SIGMA: f64 = 0.4;

/// Ten landmarks in a 10 m square, and `distinct` frames of noisy detections of all of them,
/// each frame repeated `repeat` times in a row (a robot standing still sees the same error).
fn recording(seed: u64, distinct: usize, repeat: usize) -> (Vec<Scan>, GroundTruth) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth: Vec<[f64; 2]> = (0..10)
        .map(|_| [rng.random_range(0.0..10.0), rng.random_range(0.0..10.0)])
        .collect();
    let noise = Normal::new(0.0, SIGMA).unwrap();
    let mut scans = Vec::new();
    for f in 0..distinct {
        let obs: Vec<Observation> = truth
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let xy = [p[0] + noise.sample(&mut rng), p[1] + noise.sample(&mut rng)];
                Observation::isotropic(LandmarkId(i as u32), xy, SIGMA).unwrap()
            })
            .collect();
        for r in 0..repeat {
            scans.push(Scan::new((f * repeat + r) as f64, 0, obs.clone()).unwrap());
        }
    }
    let positions: BTreeMap<LandmarkId, [f64; 2]> = truth
        .iter()
        .enumerate()
        .map(|(i, p)| (LandmarkId(i as u32), *p))
        .collect();
    (scans, GroundTruth { positions })
}

fn config() -> PqrmConfig {
    PqrmConfig {
        samples: 300,
        orderings: pqrm::Orderings::Canonical,
        ..PqrmConfig::default()
    }
}

fn chosen(calculus: &Calculus, scans: &[Scan]) -> f64 {
    let fits = fit_temper(
        std::slice::from_ref(calculus),
        scans,
        config(),
        &TemperOptions::default(),
        &|| {},
    )
    .unwrap();
    fits[0].chosen
}

fn map(calculus: &Calculus, scans: &[Scan], temper: f64) -> Pqrm {
    let mut m = Pqrm::new(calculus.clone(), PqrmConfig { temper, ..config() }).unwrap();
    for s in scans {
        m.update(s).unwrap();
    }
    m
}

#[test]
fn frames_repeated_five_times_get_a_tau_about_five_times_smaller() {
    // The same twenty frames, once each and each five times in a row: the other blocks' map
    // of the repeated recording is five times too sure, so τ must fall by about five (the
    // grid's step is √2: 4 or 5.7). Held-out blocks that were not contiguous would leak
    // copies of the held-out frames into the map and push τ up instead.
    let lr = Calculus::builtin("left-right").unwrap();
    for seed in [1, 2] {
        let (independent, _) = recording(seed, 20, 1);
        let (repeated, _) = recording(seed, 20, 5);
        let t_ind = chosen(&lr, &independent);
        let t_rep = chosen(&lr, &repeated);
        let ratio = t_ind / t_rep;
        assert!(
            (2.8..=8.0).contains(&ratio),
            "seed {seed}: τ {t_rep} for repeated frames vs {t_ind} for the same frames once"
        );
    }
}

#[test]
fn the_chosen_tau_is_as_well_calibrated_as_the_best_tau_in_hindsight() {
    // Measured with the ground truth the fit never sees: over frames seen once (few and
    // many) and repeated, the chosen τ's expected calibration error is within 0.03 of the
    // best grid τ's. (Measured: chosen 0.18 / 0.044 / 0.044 / 0.022, best 0.125 / 0.044 /
    // 0.031 / 0.022; τ = 1 is 0.04–0.06 worse in ECE.) Even independent frames want τ < 1:
    // eq. 2.10 multiplies single-frame posteriors as if the geometry were drawn anew each
    // frame, so a near-collinear triplet's log-odds grow like n instead of √n.
    let edc = Calculus::builtin("edc").unwrap();
    for (distinct, repeat) in [(20, 1), (100, 1), (20, 5), (20, 8)] {
        let (scans, truth) = recording(3, distinct, repeat);
        let tau = chosen(&edc, &scans);
        let ece = |t| calibration(&map(&edc, &scans, t), &truth).unwrap().ece;
        let best = pqrm::temper::default_grid()
            .into_iter()
            .map(ece)
            .fold(f64::INFINITY, f64::min);
        let (at_tau, at_one) = (ece(tau), ece(1.0));
        assert!(
            at_tau <= best + 0.03,
            "{distinct} frames × {repeat}: ECE {at_tau} at the chosen τ = {tau}, best {best}"
        );
        assert!(
            at_tau < at_one,
            "{distinct} frames × {repeat}: ECE {at_tau} at τ = {tau}, {at_one} untempered"
        );
    }
}

#[test]
fn the_chosen_tau_makes_a_map_of_correlated_frames_better_calibrated() {
    let edc = Calculus::builtin("edc").unwrap();
    let (scans, truth) = recording(3, 20, 8);
    let tau = chosen(&edc, &scans);
    assert!(tau < 1.0, "eight copies of every frame, yet τ = {tau}");
    let raw = map(&edc, &scans, 1.0);
    let tempered = map(&edc, &scans, tau);
    let (c_raw, c_tau) = (
        calibration(&raw, &truth).unwrap(),
        calibration(&tempered, &truth).unwrap(),
    );
    assert!(
        c_tau.ece < c_raw.ece,
        "ECE {} at τ = {tau} vs {} untempered",
        c_tau.ece,
        c_raw.ece
    );
    // tempering never changes a maximum-likelihood state, only the confidence in it
    for ((s1, b1), (s2, b2)) in raw.iter().zip(tempered.iter()) {
        assert_eq!(s1, s2);
        assert_eq!(b1.ml_state(), b2.ml_state());
    }
}

#[test]
fn the_fit_is_deterministic_and_independent_of_the_thread_count() {
    let lr = Calculus::builtin("left-right").unwrap();
    let (scans, _) = recording(4, 30, 2);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                fit_temper(
                    std::slice::from_ref(&lr),
                    &scans,
                    config(),
                    &TemperOptions::default(),
                    &|| {},
                )
                .unwrap()
            })
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(one, two);
    assert_eq!(one, run(2));
}

#[test]
fn too_few_frames_or_nothing_to_predict_is_a_typed_error() {
    let lr = Calculus::builtin("left-right").unwrap();
    let (scans, _) = recording(5, 3, 1);
    let err = fit_temper(
        std::slice::from_ref(&lr),
        &scans,
        config(),
        &TemperOptions::default(),
        &|| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("at least 5 frames"), "{err}");
    // five frames, each of a different landmark triple: no triplet outside its own block
    let o = |id: u32, x: f64, y: f64| Observation::isotropic(LandmarkId(id), [x, y], 0.1).unwrap();
    let disjoint: Vec<Scan> = (0..5u32)
        .map(|f| {
            let b = 3 * f;
            Scan::new(
                f64::from(f),
                0,
                vec![o(b, 0.0, 0.0), o(b + 1, 5.0, 0.0), o(b + 2, 2.0, 3.0)],
            )
            .unwrap()
        })
        .collect();
    let err = fit_temper(
        std::slice::from_ref(&lr),
        &disjoint,
        config(),
        &TemperOptions::default(),
        &|| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("nothing to choose"), "{err}");
    assert!(
        fit_temper(&[], &scans, config(), &TemperOptions::default(), &|| {}).is_err(),
        "no calculus"
    );
}
