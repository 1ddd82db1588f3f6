//! The layout model (`pqrm::layout`) on simulated recordings whose truth is known: robots
//! driving among cylinders they range at the near surface (an error every frame from a similar
//! viewpoint shares) with a range scale of their own (an error all of one robot's frames
//! share), on top of independent noise. Eq. 2.10 turns the repeated frames into certainty the
//! shared errors do not allow; the layout model, measuring those errors from the frames alone,
//! must be calibrated — and with independent noise only it must be no worse than the filter's
//! reading made for that case (`shared:inf`).
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::BTreeMap;

use pqrm::calibration::EDGES;
use pqrm::layout::Layout;
use pqrm::{
    EvidenceModel, GroundTruth, LandmarkId, Observation, Orderings, Pqrm, PqrmConfig, Scan,
};
use qsr_core::Calculus;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Independent noise per frame and coordinate (m).
const SIGMA: f64 = 0.15;
const LANDMARKS: usize = 12;
const ROBOTS: u32 = 3;
const FRAMES_PER_ROBOT: usize = 40;
/// A robot sees landmarks this close (m).
const RANGE: f64 = 6.0;

/// The shared errors of a scene.
#[derive(Clone, Copy)]
struct Shared {
    /// Largest cylinder radius (m): each landmark's radius is uniform in [0, this], and it is
    /// seen at its near surface.
    extent: f64,
    /// Standard deviation of each robot's range scale (1 = exact).
    scale: f64,
}

const NONE: Shared = Shared {
    extent: 0.0,
    scale: 0.0,
};

/// One scene: landmarks in a 5 m square, robots at random poses seeing those within range.
fn scene(seed: u64, shared: Shared) -> (Vec<Scan>, GroundTruth) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // landmarks along a corridor 8 m long and 1 m wide: most triplets are nearly collinear,
    // near a boundary of every calculus here (as MRCLAM's landmarks along its walls)
    let truth: Vec<[f64; 2]> = (0..LANDMARKS)
        .map(|_| [rng.random_range(0.0..8.0), rng.random_range(-0.5..0.5)])
        .collect();
    let radius: Vec<f64> = truth
        .iter()
        .map(|_| shared.extent * rng.random_range(0.0..1.0))
        .collect();
    let noise = Normal::new(0.0, SIGMA).unwrap();
    let scale_of = Normal::new(1.0, shared.scale.max(f64::MIN_POSITIVE)).unwrap();
    let mut scans = Vec::new();
    for robot in 0..ROBOTS {
        let scale = if shared.scale > 0.0 {
            scale_of.sample(&mut rng)
        } else {
            1.0
        };
        for f in 0..FRAMES_PER_ROBOT {
            let (px, py) = (rng.random_range(0.0..8.0), rng.random_range(-3.0..3.0));
            let yaw: f64 = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            let (c, s) = (yaw.cos(), yaw.sin());
            let mut obs = Vec::new();
            for (i, (p, r)) in truth.iter().zip(&radius).enumerate() {
                let (dx, dy) = (p[0] - px, p[1] - py);
                let d = dx.hypot(dy);
                if !(0.5..RANGE).contains(&d) {
                    continue;
                }
                // the near surface, at the robot's own range scale, in the robot's frame
                let k = scale * (d - r) / d;
                let (wx, wy) = (k * dx, k * dy);
                let xy = [
                    c * wx + s * wy + noise.sample(&mut rng),
                    -s * wx + c * wy + noise.sample(&mut rng),
                ];
                obs.push(Observation::isotropic(LandmarkId(i as u32), xy, SIGMA).unwrap());
            }
            if obs.len() >= 3 {
                let t = f64::from(robot) * 1e3 + f as f64;
                scans.push(Scan::new(t, robot, obs).unwrap());
            }
        }
    }
    let positions = truth
        .iter()
        .enumerate()
        .map(|(i, p)| (LandmarkId(i as u32), *p))
        .collect();
    (scans, GroundTruth { positions })
}

#[derive(Debug)]
struct Scores {
    ece: f64,
    p_ml: f64,
    accuracy: f64,
    log_loss: f64,
    sigma_shared: f64,
}

/// Maps `scenes` scenes with the filter under `evidence` (or the layout) and scores every
/// set against the truth, the reliability diagram pooled over the scenes.
fn scores(calculus: &str, shared: Shared, evidence: EvidenceModel) -> Scores {
    let calc = Calculus::builtin(calculus).unwrap();
    let config = PqrmConfig {
        samples: 200,
        orderings: Orderings::Canonical,
        ..PqrmConfig::default()
    };
    let k = EDGES.len() - 1;
    let (mut bin_n, mut bin_p, mut bin_hits) = (vec![0usize; k], vec![0.0; k], vec![0usize; k]);
    let (mut n, mut p_ml, mut hits, mut loss, mut sigma) = (0usize, 0.0, 0usize, 0.0, 0.0);
    let scenes = 12;
    for seed in 0..scenes {
        let (scans, truth) = scene(seed, shared);
        let layout = Layout::fit(&scans, &|| {}).unwrap();
        sigma += layout.shared_error().sigma_shared / scenes as f64;
        let map = if evidence == EvidenceModel::Layout {
            layout.map(calc.clone(), &scans, config, &|| {}).unwrap()
        } else {
            let mut map = Pqrm::new(calc.clone(), config)
                .unwrap()
                .with_evidence(evidence)
                .unwrap();
            for s in &scans {
                map.update(s).unwrap();
            }
            map
        };
        for (set, belief) in map.iter() {
            let t = truth.state(&calc, set).unwrap().unwrap();
            let p = belief.probabilities();
            let ml = belief.ml_state();
            let q = p[ml.index()];
            let bin = EDGES[1..].iter().position(|&hi| q < hi).unwrap_or(k - 1);
            n += 1;
            p_ml += q;
            hits += usize::from(ml == t);
            bin_n[bin] += 1;
            bin_p[bin] += q;
            bin_hits[bin] += usize::from(ml == t);
            loss -= p[t.index()].max(1e-300).ln();
        }
    }
    let nf = n as f64;
    Scores {
        ece: (0..k)
            .map(|b| (bin_p[b] - bin_hits[b] as f64).abs())
            .sum::<f64>()
            / nf,
        p_ml: p_ml / nf,
        accuracy: hits as f64 / nf,
        log_loss: loss / nf,
        sigma_shared: sigma,
    }
}

const SHARED: Shared = Shared {
    extent: 0.5,
    scale: 0.08,
};

/// Cylinders up to 0.5 m in radius ranged at their surface and robots whose range scales err
/// by 8 %. Eq. 2.10 is sure where it is often wrong; today's filter reading (`shared:4`)
/// hedges by a constant that is too much here; the layout model, measuring the shared error
/// from the frames alone, is calibrated and has the lowest log loss of the three. Fails if
/// the shared error is not measured (the draws then spread by the frames' standard error alone:
/// overconfident) or is taken as the frames' whole spread (underconfident).
#[test]
fn shared_errors_make_eq_2_10_overconfident_and_the_layout_honest() {
    for calculus in ["left-right", "double-cross", "edc"] {
        let plain = scores(calculus, SHARED, EvidenceModel::Independent);
        let today = scores(calculus, SHARED, EvidenceModel::shared_default());
        let layout = scores(calculus, SHARED, EvidenceModel::Layout);
        eprintln!("{calculus}: eq. 2.10 {plain:?}\n  shared:4 {today:?}\n  layout {layout:?}");
        assert!(
            plain.p_ml > plain.accuracy + 0.01,
            "{calculus}: eq. 2.10 {plain:?}"
        );
        if calculus != "left-right" {
            // two states and 98 % right leave eq. 2.10 little room to miss by
            assert!(plain.ece > 0.05, "{calculus}: eq. 2.10 {plain:?}");
        }
        assert!(layout.ece < 0.03, "{calculus}: layout {layout:?}");
        assert!(
            (layout.p_ml - layout.accuracy).abs() < 0.03,
            "{calculus}: {layout:?}"
        );
        assert!(
            layout.log_loss < 0.75 * today.log_loss,
            "{calculus}: {layout:?} vs {today:?}"
        );
        assert!(layout.log_loss < 0.25 * plain.log_loss, "{calculus}");
    }
}

/// Independent noise only: the frames share nothing but the geometry. The layout measures a
/// shared error far below the one above, stays calibrated, and is no worse in log loss than
/// the filter's reading for exactly this case (`shared:inf`).
#[test]
fn with_independent_noise_the_layout_measures_little_shared_error_and_loses_nothing() {
    let calculus = "double-cross";
    let root = scores(
        calculus,
        NONE,
        EvidenceModel::Shared {
            frames: f64::INFINITY,
        },
    );
    let layout = scores(calculus, NONE, EvidenceModel::Layout);
    let shared = scores(calculus, SHARED, EvidenceModel::Layout);
    eprintln!(
        "independent noise: shared:inf {root:?}\n  layout {layout:?}\n  with shared errors {shared:?}"
    );
    assert!(layout.ece < 0.05, "layout ECE {}", layout.ece);
    assert!(
        layout.log_loss <= 1.05 * root.log_loss,
        "{layout:?} vs {root:?}"
    );
    assert!(
        layout.sigma_shared < 0.5 * shared.sigma_shared,
        "{} vs {}",
        layout.sigma_shared,
        shared.sigma_shared
    );
}

/// The layout's map has the filter's sets and frame counts, in both orderings.
#[test]
fn a_layout_map_has_the_sets_and_frame_counts_of_the_filter() {
    let (scans, _) = scene(7, SHARED);
    let calc = Calculus::builtin("left-right").unwrap();
    let layout = Layout::fit(&scans, &|| {}).unwrap();
    for orderings in [Orderings::All, Orderings::Canonical] {
        let config = PqrmConfig {
            samples: 50,
            orderings,
            ..PqrmConfig::default()
        };
        let mut filter = Pqrm::new(calc.clone(), config).unwrap();
        for s in &scans {
            filter.update(s).unwrap();
        }
        let map = layout.map(calc.clone(), &scans, config, &|| {}).unwrap();
        let of = |m: &Pqrm| -> BTreeMap<[u32; 3], u32> {
            m.iter().map(|(s, b)| (s.ids(), b.updates)).collect()
        };
        assert_eq!(of(&map), of(&filter), "{orderings:?}");
        assert_eq!(map.steps(), filter.steps());
        assert_eq!(map.evidence(), EvidenceModel::Layout);
    }
}

/// A layout map is read from a whole recording: adding frames, merging and reading its rows
/// as a filter's are refused with a reason; saved and loaded it reads the same.
#[test]
fn a_layout_map_refuses_frames_and_merges_and_survives_a_round_trip() {
    let (scans, _) = scene(3, SHARED);
    let calc = Calculus::builtin("double-cross").unwrap();
    let config = PqrmConfig::default();
    let mut map = Layout::fit(&scans, &|| {})
        .unwrap()
        .map(calc.clone(), &scans, config, &|| {})
        .unwrap();
    let err = map.update(&scans[0]).unwrap_err().to_string();
    assert!(err.contains("layout map"), "{err}");
    let mut filter = Pqrm::new(calc, config).unwrap();
    filter.update(&scans[0]).unwrap();
    assert!(map.merge(&filter).is_err());
    assert!(filter.merge(&map).is_err());
    let err = map
        .clone()
        .with_evidence(EvidenceModel::shared_default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("layout"), "{err}");
    assert!(filter.with_evidence(EvidenceModel::Layout).is_err());
    let back = Pqrm::from_json(&map.to_json().unwrap()).unwrap();
    assert_eq!(back.evidence(), EvidenceModel::Layout);
    let back_bin = Pqrm::from_binary(&map.to_binary().unwrap()).unwrap();
    for (set, b) in map.iter() {
        for m in [&back, &back_bin] {
            let r = m.get(set).unwrap();
            assert_eq!(r.updates, b.updates);
            for (x, y) in r.probabilities().iter().zip(b.probabilities()) {
                assert!((x - y).abs() < 1e-6, "{set:?}");
            }
        }
    }
}

/// The beliefs do not depend on the thread count.
#[test]
fn layout_beliefs_do_not_depend_on_the_thread_count() {
    let (scans, _) = scene(11, SHARED);
    let calc = Calculus::builtin("edc").unwrap();
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                let layout = Layout::fit(&scans, &|| {}).unwrap();
                layout
                    .map(calc.clone(), &scans, PqrmConfig::default(), &|| {})
                    .unwrap()
                    .to_json()
                    .unwrap()
            })
    };
    assert_eq!(run(1), run(2));
}
