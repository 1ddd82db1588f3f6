//! Issue 40: a common 2D lidar gave an empty map. Eight poles (radius 0.25 m) passed by a robot
//! driving 20 m, scanned by a 360° lidar of 360, 720 and 1,440 beams (σ 2 cm, 2 % dropouts,
//! 20 m range): the extractor and recogniser must give one id per pole at every resolution.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::{BTreeMap, BTreeSet};

use rand::SeedableRng;
use sim2d::{
    ExtractorConfig, Hit, LidarConfig, LidarDetector, PointLandmark, Pose, World, WorldSpec,
};

/// Eight poles (radius 0.25 m) 2–5 m either side of the robot's straight drive, at least
/// 1.5 m apart, drawn with `seed`.
fn poles(seed: u64) -> World {
    use rand::RngExt;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut at: Vec<[f64; 2]> = Vec::new();
    while at.len() < 8 {
        let side = if rng.random_bool(0.5) { 1.0 } else { -1.0 };
        let p = [
            rng.random_range(1.0..19.0),
            side * rng.random_range(2.0..5.0),
        ];
        if at.iter().all(|q| (p[0] - q[0]).hypot(p[1] - q[1]) >= 1.5) {
            at.push(p);
        }
    }
    World::new(WorldSpec {
        bounds: [-5.0, 25.0, -10.0, 10.0],
        landmarks: at
            .iter()
            .enumerate()
            .map(|(i, &pos)| PointLandmark {
                id: i as u32,
                pos,
                radius: 0.25,
            })
            .collect(),
        walls: Vec::new(),
        clutter: Vec::new(),
    })
    .unwrap()
}

/// (ids per pole, ids that are no pole, scans with ≥ 3 poles detected, mean centre error) for
/// `beams` beams.
fn run(seed: u64, beams: usize, extractor: ExtractorConfig) -> (Vec<usize>, usize, usize, f64) {
    let world = poles(seed);
    let lidar = LidarConfig {
        fov: std::f64::consts::TAU,
        rays: beams,
        max_range: 20.0,
        range_sigma: 0.02,
        dropout: 0.02,
        ..LidarConfig::default()
    };
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed ^ 0x5ca7);
    // As `qrm map --format mcap` reads scans (qrm-log): mapping needs three candidates.
    let mut detector = LidarDetector {
        extractor,
        recognizer: sim2d::TriangleRecognizer::new(0.3).tracking(),
        ..LidarDetector::new(0.3, 0.1)
    }
    .with_min_candidates(sim2d::MAPPING_MIN_CANDIDATES);
    let mut ids_of: BTreeMap<usize, BTreeSet<u32>> = BTreeMap::new();
    let mut false_ids = BTreeSet::new();
    let mut useful = 0;
    let (mut err, mut n_err) = (0.0, 0usize);
    let spec = world.spec().clone();
    for k in 0..200 {
        let pose = Pose {
            x: -2.0 + 0.12 * k as f64,
            y: 0.0,
            theta: 0.0,
        };
        let scan = world.lidar(&pose, &lidar, &mut rng).unwrap();
        let found = detector.detect(&scan);
        let poles_seen = found
            .iter()
            .filter(|(_, h)| matches!(h, Some(Hit::Landmark(_))))
            .count();
        useful += usize::from(poles_seen >= 3);
        for (d, hit) in found {
            match hit {
                Some(Hit::Landmark(i)) => {
                    ids_of.entry(i).or_default().insert(d.id);
                    let t = pose.to_local(spec.landmarks[i].pos);
                    err += (d.xy[0] - t[0]).hypot(d.xy[1] - t[1]);
                    n_err += 1;
                }
                _ => {
                    false_ids.insert(d.id);
                }
            }
        }
    }
    let per_pole = (0..8)
        .map(|i| ids_of.get(&i).map_or(0, BTreeSet::len))
        .collect();
    (per_pole, false_ids.len(), useful, err / n_err.max(1) as f64)
}

#[test]
fn one_id_per_pole_from_360_to_1440_beams() {
    let mut split = 0;
    for seed in 1..=6 {
        for beams in [360, 720, 1440] {
            let (per_pole, false_ids, useful, err) = run(seed, beams, ExtractorConfig::default());
            eprintln!(
                "seed {seed}, {beams} beams: ids per pole {per_pole:?}, false ids {false_ids}, \
                 scans with ≥ 3 poles {useful}, centre error {err:.3} m"
            );
            // One id per pole; at 1° a pole far away covers two or three returns and shows
            // up in scans many frames apart, and one of six worlds still splits its
            // far poles' ids in two (measured; see issue 40's note).
            let most = if beams == 360 { 2 } else { 1 };
            assert!(
                per_pole.iter().all(|&n| (1..=most).contains(&n)) && false_ids == 0,
                "seed {seed}, {beams} beams: ids per pole {per_pole:?}, {false_ids} false ids"
            );
            if beams == 360 {
                split += per_pole.iter().filter(|&&n| n > 1).count();
            }
            assert!(
                useful >= 100,
                "seed {seed}, {beams} beams: {useful} scans with ≥ 3 poles"
            );
            assert!(
                err < 0.1,
                "seed {seed}, {beams} beams: centre error {err:.3} m"
            );
        }
    }
    assert!(split <= 3, "{split} of 48 poles split at 360 beams");
}

/// The fixed rule of a 0.25° scanner (10..=50 returns) on a 1° scanner: a pole at 5 m gives
/// about six returns, so nothing was a landmark (the regression this file pins).
#[test]
fn the_point_counts_scale_with_the_scans_resolution() {
    let c = ExtractorConfig::default();
    assert_eq!(c.points_for(0.25f64.to_radians()), (10, 50));
    assert_eq!(c.points_for(0.5f64.to_radians()), (5, 25));
    assert_eq!(c.points_for(1f64.to_radians()), (3, 13));
    assert_eq!(c.points_for(0.1f64.to_radians()), (25, 125));
    let fixed = ExtractorConfig {
        points_resolution: 0.0,
        ..c
    };
    assert_eq!(fixed.points_for(1f64.to_radians()), (10, 50));
}
