//! Reasoning over maps (issue 13 §2): the consistency check finds an injected wrong entry
//! and leaves a clean map alone; inference of hidden sets is far better than chance; chained
//! rounds reach sets one composition cannot; fusion and fitting behave as documented.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::reason::{
    Composition, Fusion, InferOptions, Inferrer, Selection, check, observed_sets, to_network,
};
use pqrm::{GroundTruth, LandmarkId, LandmarkSet, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;
use qsr_core::reason::{Algebra, TableScope, close};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Landmarks at random, scans of every landmark within `range` of stops along a line.
fn world(n: usize, range: f64, seed: u64) -> (GroundTruth, Vec<Scan>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = GroundTruth::default();
    for i in 0..n {
        let p = [rng.random_range(0.0..60.0), rng.random_range(0.0..20.0)];
        truth.positions.insert(LandmarkId(i as u32), p);
    }
    let mut scans = Vec::new();
    for k in 0..40 {
        let x = 60.0 * f64::from(k) / 39.0;
        let obs: Vec<Observation> = truth
            .positions
            .iter()
            .filter(|(_, p)| (p[0] - x).hypot(p[1] - 10.0) <= range)
            .map(|(id, p)| Observation::isotropic(*id, [p[0] - x, p[1] - 10.0], 0.3).unwrap())
            .collect();
        if obs.len() >= 3 {
            scans.push(Scan::new(f64::from(k), 0, obs).unwrap());
        }
    }
    (truth, scans)
}

fn map(calc: &str, scans: &[Scan]) -> Pqrm {
    let mut m = Pqrm::new(
        Calculus::builtin(calc).unwrap(),
        PqrmConfig {
            samples: 300,
            ..PqrmConfig::default()
        },
    )
    .unwrap();
    for s in scans {
        m.update(s).unwrap();
    }
    m
}

#[test]
fn a_clean_map_passes_the_check_and_closes_consistent() {
    let (_, scans) = world(10, 1e3, 1);
    let m = map("double-cross", &scans);
    let result = check(&m).unwrap();
    assert!(result.consistent, "{:?}", result.contradiction);
    assert!(result.flagged.is_empty());
    let alg = Algebra::of(m.calculus(), TableScope::Sound).unwrap();
    let net = to_network(&m, Selection::MostLikely).unwrap();
    assert_eq!(net.n_points(), 10);
    assert!(close(net, &alg).unwrap().is_consistent());
}

#[test]
fn the_check_flags_an_injected_wrong_entry() {
    let (truth, scans) = world(9, 1e3, 2);
    let calc = "double-cross";
    let mut m = map(calc, &scans);
    let c = Calculus::builtin(calc).unwrap();
    // Replace one set's evidence by a single outlier frame: landmark 8 seen at its mirror
    // image across the line through 0 and 1 (a misread barcode, say), with the same noise
    // as the honest frames. The honest sets were seen in many frames.
    let target = LandmarkSet::new(0, 1, 8);
    let t = truth.state(&c, &target).unwrap().unwrap();
    let mut liar = m.clone();
    liar.retain(|s| {
        let mut ids = s.ids();
        ids.sort_unstable();
        ids != [0, 1, 8]
    });
    let mirrored = {
        let p = truth.positions[&LandmarkId(8)];
        let (a, b) = (
            truth.positions[&LandmarkId(0)],
            truth.positions[&LandmarkId(1)],
        );
        // Reflect across the line through landmarks 0 and 1.
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let k = ((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / (dx * dx + dy * dy);
        let foot = [a[0] + k * dx, a[1] + k * dy];
        [2.0 * foot[0] - p[0], 2.0 * foot[1] - p[1]]
    };
    let lie = Scan::new(
        0.0,
        0,
        vec![
            Observation::isotropic(LandmarkId(0), truth.positions[&LandmarkId(0)], 0.3).unwrap(),
            Observation::isotropic(LandmarkId(1), truth.positions[&LandmarkId(1)], 0.3).unwrap(),
            Observation::isotropic(LandmarkId(8), mirrored, 0.3).unwrap(),
        ],
    )
    .unwrap();
    liar.update(&lie).unwrap();
    let wrong = liar.record(&target).unwrap().ml_state();
    assert_ne!(wrong, t, "the injected entry must be wrong");
    m = liar;
    let result = check(&m).unwrap();
    assert!(!result.consistent, "the wrong entry was not refuted");
    assert!(
        result.flagged.iter().any(|f| f.set == [0, 1, 8]),
        "flags {:?} miss the injected set",
        result.flagged
    );
    assert!(result.flagged.len() <= 3, "{:?}", result.flagged);
}

#[test]
fn hidden_sets_are_inferred_far_better_than_chance() {
    let (truth, scans) = world(12, 1e3, 3);
    for calc in ["edc", "double-cross"] {
        let full = map(calc, &scans);
        let c = full.calculus().clone();
        let sets = observed_sets(&full);
        let hidden: Vec<LandmarkSet> = sets.iter().copied().step_by(5).collect();
        let mut visible = full.clone();
        visible.retain(|s| {
            let mut ids = s.ids();
            ids.sort_unstable();
            !hidden.iter().any(|h| h.ids() == ids)
        });
        for fusion in Fusion::ALL {
            let inferrer = Inferrer::new(
                &visible,
                InferOptions {
                    fusion,
                    ..InferOptions::default()
                },
            )
            .unwrap();
            assert!((0.0..=1.0).contains(&inferrer.alpha()));
            let mut wrong = 0;
            for s in &hidden {
                let inf = inferrer.infer(*s).unwrap();
                assert!(inf.paths > 0);
                assert!((inf.p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
                wrong += usize::from(Some(inf.ml_state()) != truth.state(&c, s).unwrap());
            }
            let rate = wrong as f64 / hidden.len() as f64;
            let chance = 1.0 - 1.0 / c.n_states() as f64;
            assert!(
                rate < 0.5 * chance,
                "{calc} {}: error {rate:.3} vs chance {chance:.3}",
                fusion.name()
            );
        }
    }
}

/// Mean −ln p(true state) over every ordering of `hidden`, inferred from `visible`.
fn hidden_log_loss(
    visible: &Pqrm,
    truth: &GroundTruth,
    hidden: &[LandmarkSet],
    composition: Composition,
) -> f64 {
    let c = visible.calculus().clone();
    let inferrer = Inferrer::new(
        visible,
        InferOptions {
            composition,
            ..InferOptions::default()
        },
    )
    .unwrap();
    let mut total = 0.0;
    let mut n = 0;
    for s in hidden {
        for o in pqrm::reason::network::orderings(*s) {
            let inf = inferrer.infer(o).unwrap();
            assert!((inf.p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
            let t = truth.state(&c, &o).unwrap().unwrap();
            total -= inf.p[t.index()].max(1e-300).ln();
            n += 1;
        }
    }
    total / f64::from(n)
}

/// Issue 35: the uniform split of a composition entry among its states made inference from
/// the shared-error model's soft beliefs underconfident; shares learned from the map's own
/// quadruples (no truth) must predict hidden sets better there (measured: 0.344 against
/// 0.424 nats EDC, 0.214 against 0.285 double-cross), and must not cost much where eq. 2.10's
/// sharp beliefs leave little to learn (0.280 against 0.285, 0.154 against 0.150).
#[test]
fn learned_composition_shares_predict_hidden_sets_better_than_uniform_ones() {
    let (truth, scans) = world(14, 1e3, 5);
    let models = [
        (pqrm::EvidenceModel::shared_default(), 0.9),
        (pqrm::EvidenceModel::Independent, 1.1),
    ];
    for calc in ["edc", "double-cross"] {
        for (evidence, bound) in models {
            let full = map(calc, &scans).with_evidence(evidence).unwrap();
            let sets = observed_sets(&full);
            let hidden: Vec<LandmarkSet> = sets.iter().copied().step_by(7).collect();
            let mut visible = full.clone();
            visible.retain(|s| {
                let mut ids = s.ids();
                ids.sort_unstable();
                !hidden.iter().any(|h| h.ids() == ids)
            });
            let uniform = hidden_log_loss(&visible, &truth, &hidden, Composition::Uniform);
            let learned = hidden_log_loss(&visible, &truth, &hidden, Composition::Learned);
            assert!(
                learned < bound * uniform,
                "{calc} under {evidence:?}: learned shares {learned:.3} nats against uniform \
                 {uniform:.3}"
            );
        }
    }
}

#[test]
fn chained_rounds_reach_sets_one_composition_cannot() {
    // A short range along a line: landmarks far apart are never seen together, and some
    // are linked only through chains of overlapping views.
    let (truth, scans) = world(14, 14.0, 4);
    let m = map("double-cross", &scans);
    let once = Inferrer::new(
        &m,
        InferOptions {
            rounds: 1,
            ..InferOptions::default()
        },
    )
    .unwrap()
    .infer_unseen();
    let mut chained = Inferrer::new(&m, InferOptions::default()).unwrap();
    let more = chained.infer_unseen();
    let reached = |v: &[pqrm::reason::Inference]| v.iter().filter(|i| i.round > 0).count();
    assert!(!once.is_empty());
    assert!(
        reached(&more) > reached(&once),
        "rounds reached {} sets, one round {}",
        reached(&more),
        reached(&once)
    );
    assert!(more.iter().any(|i| i.round >= 2));
    // Unreached sets say "unknown": uniform, no paths.
    for i in more.iter().filter(|i| i.round == 0) {
        assert_eq!(i.paths, 0);
        assert!(i.p.iter().all(|p| (p - i.p[0]).abs() < 1e-12));
    }
    // What the rounds infer is better than chance on the reached sets.
    let c = m.calculus();
    let scored: Vec<_> = more.iter().filter(|i| i.round > 0).collect();
    let wrong = scored
        .iter()
        .filter(|i| {
            let s = LandmarkSet::new(i.set[0], i.set[1], i.set[2]);
            Some(i.ml_state()) != truth.state(c, &s).unwrap()
        })
        .count();
    let rate = wrong as f64 / scored.len() as f64;
    assert!(
        rate < 0.6,
        "error {rate:.3} on {} reached sets",
        scored.len()
    );
}

#[test]
fn bad_inference_settings_are_refused() {
    let (_, scans) = world(6, 1e3, 5);
    let m = map("left-right", &scans);
    for bad in [
        InferOptions {
            epsilon: 1.0,
            ..InferOptions::default()
        },
        InferOptions {
            epsilon: f64::NAN,
            ..InferOptions::default()
        },
        InferOptions {
            rounds: 0,
            ..InferOptions::default()
        },
    ] {
        assert!(Inferrer::new(&m, bad).is_err());
    }
    let inf = Inferrer::new(&m, InferOptions::default()).unwrap();
    assert!(inf.infer(LandmarkSet::new(1, 1, 2)).is_err());
}
