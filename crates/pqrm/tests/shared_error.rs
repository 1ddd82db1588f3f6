//! The shared-error model (`pqrm::evidence`) on simulated recordings whose truth is known:
//! every landmark carries one offset all frames share (a landmark's extent, a mounting) on top
//! of independent noise. Eq. 2.10 turns the repeated frames into certainty the shared offset
//! does not allow; the shared-error model at the offset's size must be calibrated, and with
//! no shared offset eq. 2.10 is calibrated and the model at a large N changes nothing.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::BTreeMap;

use pqrm::calibration::EDGES;
use pqrm::{EvidenceModel, GroundTruth, LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};

/// Independent noise per frame and coordinate (m).
const SIGMA: f64 = 0.3;
const FRAMES: usize = 25;

/// One scene: eight landmarks in a 4 m square, each with a shared offset of standard
/// deviation `shared` (m), seen `FRAMES` times with independent noise `SIGMA`.
fn scene(seed: u64, shared: f64) -> (Vec<Scan>, BTreeMap<LandmarkId, [f64; 2]>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let truth: Vec<[f64; 2]> = (0..8)
        .map(|_| [rng.random_range(0.0..4.0), rng.random_range(0.0..4.0)])
        .collect();
    let offset = Normal::new(0.0, shared.max(f64::MIN_POSITIVE)).unwrap();
    let bias: Vec<[f64; 2]> = truth
        .iter()
        .map(|_| {
            if shared > 0.0 {
                [offset.sample(&mut rng), offset.sample(&mut rng)]
            } else {
                [0.0, 0.0]
            }
        })
        .collect();
    let noise = Normal::new(0.0, SIGMA).unwrap();
    let scans = (0..FRAMES)
        .map(|f| {
            let obs = truth
                .iter()
                .zip(&bias)
                .enumerate()
                .map(|(i, (p, b))| {
                    let xy = [
                        p[0] + b[0] + noise.sample(&mut rng),
                        p[1] + b[1] + noise.sample(&mut rng),
                    ];
                    Observation::isotropic(LandmarkId(i as u32), xy, SIGMA).unwrap()
                })
                .collect();
            Scan::new(f as f64, 0, obs).unwrap()
        })
        .collect();
    let positions = truth
        .iter()
        .enumerate()
        .map(|(i, p)| (LandmarkId(i as u32), *p))
        .collect();
    (scans, positions)
}

struct Scores {
    ece: f64,
    p_ml: f64,
    accuracy: f64,
    log_loss: f64,
}

/// Maps 40 scenes under `evidence` and scores every triplet against the truth.
fn scores(calculus: &str, shared: f64, evidence: EvidenceModel) -> Scores {
    let calc = Calculus::builtin(calculus).unwrap();
    let config = PqrmConfig {
        samples: 200,
        orderings: pqrm::Orderings::Canonical,
        ..PqrmConfig::default()
    };
    let (mut n, mut p_ml, mut hits, mut loss) = (0usize, 0.0, 0usize, 0.0);
    // the reliability diagram pooled over every scene (per-scene bins are mostly noise)
    let k = EDGES.len() - 1;
    let (mut bin_n, mut bin_p, mut bin_hits) = (vec![0usize; k], vec![0.0; k], vec![0usize; k]);
    let scenes = 40;
    for seed in 0..scenes {
        let (scans, positions) = scene(seed, shared);
        let mut map = Pqrm::new(calc.clone(), config)
            .unwrap()
            .with_evidence(evidence)
            .unwrap();
        for s in &scans {
            map.update(s).unwrap();
        }
        let truth = GroundTruth { positions };
        for (set, belief) in map.iter() {
            let t = truth.state(&calc, set).unwrap().unwrap();
            let p = belief.probabilities();
            let ml = belief.ml_state();
            n += 1;
            p_ml += p[ml.index()];
            hits += usize::from(ml == t);
            let bin = EDGES[1..]
                .iter()
                .position(|&hi| p[ml.index()] < hi)
                .unwrap_or(k - 1);
            bin_n[bin] += 1;
            bin_p[bin] += p[ml.index()];
            bin_hits[bin] += usize::from(ml == t);
            loss -= p[t.index()].max(1e-300).ln();
        }
    }
    let nf = n as f64;
    let ece = (0..k)
        .filter(|&b| bin_n[b] > 0)
        .map(|b| (bin_p[b] - bin_hits[b] as f64).abs())
        .sum::<f64>()
        / nf;
    Scores {
        ece,
        p_ml: p_ml / nf,
        accuracy: hits as f64 / nf,
        log_loss: loss / nf,
    }
}

/// With a shared offset as large as the independent noise (N = σ²/σ_b² = 1), eq. 2.10 is
/// sure where it is often wrong; the shared-error model at N = 1 is calibrated and has the
/// lower log loss. Fails if the exponent is not applied, or applied the wrong way round.
#[test]
fn a_shared_offset_makes_eq_2_10_overconfident_and_the_model_at_its_size_honest() {
    for calculus in ["left-right", "double-cross"] {
        let plain = scores(calculus, SIGMA, EvidenceModel::Independent);
        let model = scores(calculus, SIGMA, EvidenceModel::Shared { frames: 1.0 });
        eprintln!(
            "{calculus}: eq. 2.10 P(ML) {:.3} acc {:.3} ECE {:.3} loss {:.3}; shared:1 P(ML) {:.3} ECE {:.3} loss {:.3}",
            plain.p_ml,
            plain.accuracy,
            plain.ece,
            plain.log_loss,
            model.p_ml,
            model.ece,
            model.log_loss
        );
        assert!(
            plain.p_ml - plain.accuracy > 0.05 && plain.ece > 0.05,
            "{calculus}: eq. 2.10 should be overconfident"
        );
        assert!(model.ece < 0.05, "{calculus}: shared:1 ECE {}", model.ece);
        assert!(
            (model.p_ml - model.accuracy).abs() < 0.05,
            "{calculus}: shared:1 P(ML) {} vs accuracy {}",
            model.p_ml,
            model.accuracy
        );
        assert!(model.log_loss < 0.8 * plain.log_loss, "{calculus}");
        // the most likely states are eq. 2.10's
        assert!((model.accuracy - plain.accuracy).abs() < 1e-12);
    }
}

/// Independent noise only: the frames still share the true geometry, so eq. 2.10 — which
/// multiplies them as independent given the state — is overconfident too (log-odds growing
/// like n where the posterior's grow like √n); the model with no shared offset (N = ∞,
/// τ(n) = 1/√n) is calibrated, a negligible offset (N = 10⁴) scores as N = ∞, and the
/// default N is no worse than eq. 2.10 in log loss.
#[test]
fn with_independent_noise_the_geometry_alone_is_shared_and_the_model_is_calibrated() {
    let plain = scores("double-cross", 0.0, EvidenceModel::Independent);
    let root = scores(
        "double-cross",
        0.0,
        EvidenceModel::Shared {
            frames: f64::INFINITY,
        },
    );
    let near = scores("double-cross", 0.0, EvidenceModel::Shared { frames: 1e4 });
    let default = scores("double-cross", 0.0, EvidenceModel::shared_default());
    eprintln!(
        "independent noise: eq. 2.10 P(ML) {:.3} acc {:.3} ECE {:.3} loss {:.3}; shared:inf P(ML) {:.3} ECE {:.3} loss {:.3}; \
         default P(ML) {:.3} ECE {:.3} loss {:.3}",
        plain.p_ml,
        plain.accuracy,
        plain.ece,
        plain.log_loss,
        root.p_ml,
        root.ece,
        root.log_loss,
        default.p_ml,
        default.ece,
        default.log_loss
    );
    assert!(plain.ece > 0.05 && plain.p_ml > plain.accuracy + 0.05);
    assert!(root.ece < 0.03, "shared:inf ECE {}", root.ece);
    assert!(root.log_loss < 0.5 * plain.log_loss);
    assert!((near.ece - root.ece).abs() < 0.01 && (near.log_loss - root.log_loss).abs() < 0.01);
    assert!(default.log_loss < plain.log_loss);
}

/// A saved map keeps its evidence model and a reader reads it the same way; switching the
/// model back returns eq. 2.10's beliefs exactly (the rows store the plain sums).
#[test]
fn the_evidence_model_survives_saving_and_switching_it_is_lossless() {
    let (scans, _) = scene(3, SIGMA);
    let calc = Calculus::builtin("double-cross").unwrap();
    let config = PqrmConfig {
        samples: 100,
        ..PqrmConfig::default()
    };
    let mut plain = Pqrm::new(calc.clone(), config).unwrap();
    for s in &scans {
        plain.update(s).unwrap();
    }
    let shared = EvidenceModel::Shared { frames: 2.0 };
    let model = plain.clone().with_evidence(shared).unwrap();
    let back = Pqrm::from_json(&model.to_json().unwrap()).unwrap();
    assert_eq!(back.evidence(), shared);
    let binary = Pqrm::from_binary(&model.to_binary().unwrap()).unwrap();
    assert_eq!(binary.evidence(), shared);
    let again = back.with_evidence(EvidenceModel::Independent).unwrap();
    let mut softer = 0;
    for ((set, p), (_, m)) in plain.iter().zip(model.iter()) {
        let q = again.get(set).unwrap();
        for (a, b) in p.log_p.iter().zip(&q.log_p) {
            assert!((a - b).abs() < 1e-6 || (*a < -80.0 && *b < -80.0));
        }
        assert_eq!(p.ml_state(), m.ml_state());
        softer += usize::from(m.entropy() > p.entropy() + 1e-9);
    }
    assert!(softer > 0, "the shared model must soften some belief");
    assert!(
        Pqrm::new(calc, config)
            .unwrap()
            .with_evidence(EvidenceModel::Shared { frames: -1.0 })
            .is_err()
    );
}
