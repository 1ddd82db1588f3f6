//! The map: persistence, merging, derived orderings, determinism, the studies in quick mode,
//! MRCLAM end to end, and the embedding example.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::likelihood::{LandmarkSet, Orderings, StepCounts};
use pqrm::study::{MonteCarloConfig, noise_check, run_monte_carlo, run_real};
use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;

#[path = "../examples/perception_loop.rs"]
#[allow(dead_code)]
mod perception_loop;

fn scans(n: usize) -> Vec<Scan> {
    let pts = [[0.0, 0.0], [0.0, 4.0], [1.5, 2.2], [-2.0, 1.0], [3.0, 5.0]];
    (0..n)
        .map(|k| {
            let obs = pts
                .iter()
                .enumerate()
                .filter(|(i, _)| (i + k) % 5 != 0 || n < 3)
                .map(|(i, p)| Observation::isotropic(LandmarkId(i as u32), *p, 0.8).unwrap())
                .collect();
            Scan::new(k as f64, 0, obs).unwrap()
        })
        .collect()
}

fn build(calc: &str, scans: &[Scan], orderings: Orderings) -> Pqrm {
    let mut m = Pqrm::new(
        Calculus::builtin(calc).unwrap(),
        PqrmConfig {
            samples: 400,
            orderings,
            seed: 3,
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
fn a_saved_map_loads_back_identically() {
    let m = build("edc", &scans(6), Orderings::All);
    let dir = std::env::temp_dir().join(format!("pqrm-save-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("map.json");
    m.save(&path).unwrap();
    let back = Pqrm::load(&path).unwrap();
    assert_eq!(back.len(), m.len());
    let (x, y) = (back.to_json().unwrap(), m.to_json().unwrap());
    let at = x.bytes().zip(y.bytes()).position(|(a, b)| a != b);
    assert!(
        at.is_none() && x.len() == y.len(),
        "round trip changed the map at byte {at:?}: …{}…",
        at.map_or(String::new(), |i| x
            [i.saturating_sub(80)..(i + 40).min(x.len())]
            .to_owned())
    );
    // A malformed file is a typed error, and nothing half-written stays behind on save.
    std::fs::write(
        dir.join("bad.json"),
        "{\"format\":\"qrm-pqrm\",\"version\":99}",
    )
    .unwrap();
    assert!(Pqrm::load(&dir.join("bad.json")).is_err());
    assert!(!dir.join("map.json.tmp").exists());
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn merging_two_maps_equals_one_map_of_all_the_evidence() {
    let calc = Calculus::builtin("double-cross").unwrap();
    let cfg = PqrmConfig::default();
    let set = LandmarkSet::new(1, 2, 3);
    let other = LandmarkSet::new(2, 1, 3);
    let ev = [
        StepCounts::from_vecs(&[(set, vec![50, 20, 10, 5, 3, 2])]).unwrap(),
        StepCounts::from_vecs(&[
            (set, vec![30, 40, 10, 5, 3, 2]),
            (other, vec![1, 2, 3, 4, 5, 75]),
        ])
        .unwrap(),
    ];
    let mut a = Pqrm::new(calc.clone(), cfg).unwrap();
    a.apply_counts(&ev[0]).unwrap();
    let mut b = Pqrm::new(calc.clone(), cfg).unwrap();
    b.apply_counts(&ev[1]).unwrap();
    let mut all = Pqrm::new(calc.clone(), cfg).unwrap();
    all.apply_counts(&ev[0]).unwrap();
    all.apply_counts(&ev[1]).unwrap();
    a.merge(&b).unwrap();
    for s in [set, other] {
        let (x, y) = (a.record(&s).unwrap(), all.record(&s).unwrap());
        // equal up to the f32 rounding of the stored log-probabilities
        for (u, v) in x.log_p.iter().zip(&y.log_p) {
            assert!((u - v).abs() < 1e-6 * u.abs().max(1.0), "{u} vs {v}");
        }
    }
    let edc = Pqrm::new(Calculus::builtin("edc").unwrap(), cfg).unwrap();
    assert!(
        a.merge(&edc).is_err(),
        "maps of different calculi do not merge"
    );
}

#[test]
fn canonical_maps_derive_the_other_orderings() {
    let sc = scans(5);
    let all = build("edc", &sc, Orderings::All);
    let canon = build("edc", &sc, Orderings::Canonical);
    assert_eq!(canon.len() * 6, all.len());
    // The inverse is one-to-one in general position and both maps saw the same samples:
    // the derived {B, A : C} equals the recorded one.
    let asked = LandmarkSet::new(2, 1, 3);
    let derived = canon.belief(asked).unwrap();
    let recorded = all.belief(asked).unwrap();
    // (to the f32 rounding of stored log-probabilities: probabilities within 1e-6)
    for (d, r) in derived.iter().zip(&recorded) {
        assert!((d - r).abs() < 1e-6, "{derived:?} vs {recorded:?}");
    }
    // Other permutations spread probability over their sets: still a distribution.
    let d = canon.belief(LandmarkSet::new(3, 1, 2)).unwrap();
    assert!((d.iter().sum::<f64>() - 1.0).abs() < 1e-6);
    assert!(canon.belief(LandmarkSet::new(1, 2, 9)).is_none());
}

#[test]
fn results_do_not_depend_on_the_thread_count() {
    let sc = scans(8);
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| build("edc", &sc, Orderings::All).to_json().unwrap())
    };
    assert_eq!(run(1), run(2));
    let study = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| {
                serde_json::to_string(
                    &run_monte_carlo(
                        &MonteCarloConfig {
                            trials: 3,
                            sigmas: vec![0.0, 20.0],
                            ..MonteCarloConfig::quick()
                        },
                        &|| {},
                    )
                    .unwrap(),
                )
                .unwrap()
            })
    };
    assert_eq!(study(1), study(2));
}

#[test]
fn the_quick_monte_carlo_study_behaves_as_the_thesis_says() {
    let r = run_monte_carlo(&MonteCarloConfig::quick(), &|| {}).unwrap();
    let row = |calc: &str, sigma: f64| {
        r.levels
            .iter()
            .find(|l| l.calculus == calc && l.sigma_r == sigma)
            .unwrap()
    };
    for calc in qsr_core::POINT_CALCULI {
        let base = &r.baselines[calc];
        // Noise-free maps are right; every level beats a random guess (Fig 2.11a).
        assert_eq!(row(calc, 0.0).error_rate.mean, 0.0, "{calc}");
        for sigma in [1.0, 10.0, 50.0, 100.0] {
            assert!(
                row(calc, sigma).error_rate.mean < base.error_rate,
                "{calc} at {sigma}"
            );
        }
        // More noise, more entropy.
        assert!(row(calc, 100.0).mean_entropy.mean > row(calc, 1.0).mean_entropy.mean);
    }
    // EDC: mean neighbour distance < 1 for σ_N < 1 (σ_R = 10 m is σ_N = 0.35), entropy well
    // below ln 20 even at σ_N = 3.5 (Figs 2.6, 2.7).
    assert!(row("edc", 10.0).neighbor_distance.mean < 1.0);
    assert!(row("edc", 100.0).mean_entropy.mean < 20f64.ln() - 0.5);
    assert!(!r.confusion.is_empty() && !r.wrong.is_empty());
}

#[test]
fn mrclam_end_to_end_quick_subset() {
    let Some(shared) = qrm_shared() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found beside the checkout");
        return;
    };
    let mut data =
        pqrm::loaders::read_mrclam(&shared, pqrm::loaders::RangeBearingNoise::MRCLAM).unwrap();
    assert!(data.skipped > 0, "robot-to-robot sightings are skipped");
    assert_eq!(data.truth.as_ref().unwrap().positions.len(), 15);
    data.scans.retain(|s| s.observations.len() >= 3);
    assert!(
        data.scans.len() > 500,
        "about a thousand frames see three landmarks or more"
    );
    data.scans.truncate(150);
    let calculi: Vec<String> = ["edc", "double-cross", "left-right"]
        .iter()
        .map(|s| (*s).to_owned())
        .collect();
    let cfg = PqrmConfig {
        samples: 200,
        ..PqrmConfig::default()
    };
    let results = run_real(&data, &calculi, cfg, &|| {}).unwrap();
    for r in &results {
        assert!(r.pqrm.n_scored > 50, "{}", r.calculus);
        assert!(
            r.pqrm.error_rate < r.random.error_rate,
            "{}: PQRM beats a random guess",
            r.calculus
        );
        // Filtering many frames is at least as good as judging each frame alone.
        assert!(
            r.pqrm.error_rate <= r.per_frame.error_rate + 0.05,
            "{}: {} vs {}",
            r.calculus,
            r.pqrm.error_rate,
            r.per_frame.error_rate
        );
    }
    let check = noise_check(&data).unwrap();
    assert!(check.pairs > 100 && check.z_std > 0.0);
}

fn qrm_shared() -> Option<std::path::PathBuf> {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/mrclam-dataset7");
    dir.is_dir().then_some(dir)
}

#[test]
fn the_embedding_example_runs() {
    let p = perception_loop::run();
    assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    // Landmark 3 at (5, 2) is right of 1→2 ((2,8) → (9,9)), below A: EDC 20 (right, y < 0).
    let edc = Calculus::builtin("edc").unwrap();
    let truth = edc
        .classify_triplet(
            qsr_core::Point2::new(2.0, 8.0),
            qsr_core::Point2::new(9.0, 9.0),
            qsr_core::Point2::new(5.0, 2.0),
        )
        .unwrap();
    let best = p
        .iter()
        .enumerate()
        .fold(0, |b, (i, v)| if *v > p[b] { i } else { b });
    assert_eq!(best, truth.index());
}

#[test]
fn loaders_read_g2o_landmark_lines_and_reject_bad_ones() {
    let dir = std::env::temp_dir().join(format!("pqrm-g2o-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let good = dir.join("vp.txt");
    std::fs::write(
        &good,
        "ODOMETRY 0 1 0.1 0 0 1 0 0 1 0 1\nLANDMARK 1 4 3.0 1.0 0.1 0.0 0.1\nLANDMARK 1 7 2.0 -1.0 0.1 0.0 0.1\nLANDMARK 2 4 2.9 1.1 0.1 0.0 0.1\n",
    )
    .unwrap();
    let d = pqrm::loaders::read_g2o(&good).unwrap();
    assert_eq!(d.scans.len(), 2);
    assert_eq!(d.scans[0].observations.len(), 2);
    assert_eq!(d.skipped, 1, "the ODOMETRY line");
    let bad = dir.join("bad.txt");
    std::fs::write(&bad, "LANDMARK 1 4 3.0 1.0 0.1 0.0\n").unwrap();
    let e = pqrm::loaders::read_g2o(&bad).unwrap_err().to_string();
    assert!(e.contains("bad.txt:1"), "{e}");
    std::fs::write(&bad, "LANDMARK 1 4 3.0 1.0 0.1 5.0 0.1\n").unwrap();
    let e = pqrm::loaders::read_g2o(&bad).unwrap_err().to_string();
    assert!(e.contains("semi-definite"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Regression (issue 17): ids went through saturating `as u32` casts (`-6.7` and `NaN` became
/// landmark 0, `1e10` became 4294967295: landmarks silently merged), any text file read as an
/// empty g2o dataset, and a header-only CSV as an empty one. Each is now an error naming the
/// file, the line and the field.
#[test]
fn loaders_refuse_ids_that_are_not_integers_and_files_without_observations() {
    let dir = std::env::temp_dir().join(format!("pqrm-ids-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let f = dir.join("x.g2o");
    for (id, needle) in [
        ("-6.7", "landmark"),
        ("NaN", "landmark"),
        ("1e10", "landmark"),
    ] {
        std::fs::write(&f, format!("LANDMARK 1 {id} 3.0 1.0 0.1 0.0 0.1\n")).unwrap();
        let e = pqrm::loaders::read_g2o(&f).unwrap_err().to_string();
        assert!(e.contains("x.g2o:1") && e.contains(needle), "{id}: {e}");
    }
    std::fs::write(&f, "# a README, not a g2o file\nhello world\n").unwrap();
    let e = pqrm::loaders::read_g2o(&f).unwrap_err().to_string();
    assert!(e.contains("no `LANDMARK"), "{e}");
    let csv = dir.join("obs.csv");
    std::fs::write(&csv, "t,robot,landmark,x,y,cxx,cxy,cyy\n").unwrap();
    let e = pqrm::loaders::read_csv(&csv).unwrap_err().to_string();
    assert!(e.contains("no observations"), "{e}");
    // A landmark twice in one scan names the file and both lines (it named neither).
    std::fs::write(
        &csv,
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,5,1,1,0.1,0,0.1\n0,0,5,1.1,1,0.1,0,0.1\n",
    )
    .unwrap();
    let e = pqrm::loaders::read_csv(&csv).unwrap_err().to_string();
    assert!(
        e.contains("obs.csv:3") && e.contains("first on line 2"),
        "{e}"
    );
    let truth = dir.join("truth.csv");
    std::fs::write(&truth, "landmark,x,y\n1e10,0,0\n").unwrap();
    let e = pqrm::loaders::read_truth_csv(&truth)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("truth.csv:2") && e.contains("landmark must be an integer"),
        "{e}"
    );
    // MRCLAM: a barcode that is not an integer.
    let m = dir.join("mrclam");
    std::fs::create_dir_all(&m).unwrap();
    std::fs::write(m.join("Landmark_Groundtruth.dat"), "6 1.0 2.0 0 0\n").unwrap();
    std::fs::write(m.join("Barcodes.dat"), "6 72\n").unwrap();
    std::fs::write(m.join("Robot1_Measurement.dat"), "0.0 72.5 1.0 0.1\n").unwrap();
    let e = pqrm::loaders::read_mrclam(&m, pqrm::loaders::RangeBearingNoise::MRCLAM)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("Robot1_Measurement.dat:1") && e.contains("barcode"),
        "{e}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn study_shards_merge_into_the_single_run() {
    use pqrm::study::{aggregate_monte_carlo, run_monte_carlo_shard};
    let cfg = MonteCarloConfig {
        trials: 5,
        sigmas: vec![0.0, 30.0],
        samples: 60,
        ..MonteCarloConfig::quick()
    };
    let whole = run_monte_carlo(&cfg, &|| {}).unwrap();
    let mut records = run_monte_carlo_shard(&cfg, 3, 2, &|| {}).unwrap();
    records.extend(run_monte_carlo_shard(&cfg, 0, 3, &|| {}).unwrap());
    let merged = aggregate_monte_carlo(&cfg, &records).unwrap();
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&whole).unwrap()
    );
    // The detail level σ = 1 m runs although it is not in `sigmas`.
    assert!(whole.levels.iter().any(|l| l.sigma_r == 1.0));
    // Missing or duplicated shards are refused.
    assert!(aggregate_monte_carlo(&cfg, &records[1..]).is_err());
    let mut dup = records.clone();
    dup.push(records[0].clone());
    assert!(aggregate_monte_carlo(&cfg, &dup).is_err());
}

/// Regression (issue 17, found by the `truth_csv` corpus): a landmark surveyed twice kept the
/// last position silently; now an error naming both lines.
#[test]
fn a_landmark_surveyed_twice_is_refused_with_both_lines() {
    let e = pqrm::loaders::parse_truth_csv(
        "landmark,x,y\n1,0,0\n2,1,1\n1,2,3\n",
        std::path::Path::new("t.csv"),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("t.csv:4") && e.contains("lines 2 and 4"), "{e}");
}

/// Regression (issue 17, found by the `mrclam` fuzz target): NaN in a recording was passed on
/// as a measurement; every loader now refuses non-finite numbers naming file, line and field.
#[test]
fn non_finite_numbers_are_refused_with_their_field() {
    let e = pqrm::loaders::parse_csv(
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,inf,1,1,0,1\n",
        std::path::Path::new("o.csv"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("o.csv:2") && e.contains("x: `inf` is not a finite number"),
        "{e}"
    );
    let long = "9".repeat(2 << 20);
    let e = pqrm::loaders::parse_g2o(
        &format!("LANDMARK 0 1 {long}x 2 1 0 1\n"),
        std::path::Path::new("g.g2o"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.len() < 300,
        "a 2 MB field is not echoed whole: {} bytes",
        e.len()
    );
}

/// Issue 39: a saved map whose set repeats an id loaded (JSON, or binary with a valid CRC),
/// then `qrm reason check` panicked and `qrm pqrm merge` copied the set on.
#[test]
fn regression_a_saved_map_whose_set_repeats_an_id_is_refused_by_both_loaders() {
    let m = build("left-right", &scans(3), Orderings::All);
    let json = m.to_json().unwrap();
    let first = m.iter().next().unwrap().0.ids();
    let [a, b, c] = first;
    let bad = json.replacen(
        &format!("\"set\":[{a},{b},{c}]"),
        &format!("\"set\":[{a},{a},{c}]"),
        1,
    );
    assert_ne!(
        bad, json,
        "the test could not find the first set in the JSON"
    );
    let err = Pqrm::from_json(&bad).unwrap_err().to_string();
    assert!(err.contains("repeats a landmark id"), "{err}");

    // The binary file: the first set's second id made the first's, checksum made valid again.
    let mut bytes = m.to_binary().unwrap();
    let header_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let sets_at = 32 + header_len;
    let first_id: [u8; 4] = bytes[sets_at..sets_at + 4].try_into().unwrap();
    bytes[sets_at + 4..sets_at + 8].copy_from_slice(&first_id);
    let body = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
    let err = Pqrm::from_binary(&bytes).unwrap_err().to_string();
    assert!(err.contains("repeats a landmark id"), "{err}");
}
