//! Heavy-tailed inverse sensor models and tempering in the mapper.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::likelihood::StepCounts;
use pqrm::sensor::SensorModel;
use pqrm::{LandmarkId, LandmarkSet, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;

fn scan(t: f64, c: [f64; 2], sigma: f64) -> Scan {
    let o = |id, xy| Observation::isotropic(LandmarkId(id), xy, sigma).unwrap();
    Scan::new(t, 0, vec![o(0, [0.0, 0.0]), o(1, [0.0, 10.0]), o(2, c)]).unwrap()
}

fn belief(map: &Pqrm) -> Vec<f64> {
    let set = LandmarkSet::new(0, 1, 2);
    map.get(&set).unwrap().log_p.clone()
}

#[test]
fn tempering_by_a_half_makes_two_equal_frames_count_as_one() {
    let lr = Calculus::builtin("left-right").unwrap();
    let counts = StepCounts::from_vecs(&[(LandmarkSet::new(0, 1, 2), vec![700, 300])]).unwrap();
    let mut half = Pqrm::new(
        lr.clone(),
        PqrmConfig {
            temper: 0.5,
            ..PqrmConfig::default()
        },
    )
    .unwrap();
    half.apply_counts(&counts).unwrap();
    half.apply_counts(&counts).unwrap();
    let mut once = Pqrm::new(lr, PqrmConfig::default()).unwrap();
    once.apply_counts(&counts).unwrap();
    for (a, b) in belief(&half).iter().zip(belief(&once)) {
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn one_outlier_frame_moves_a_heavy_tailed_map_less_than_a_gaussian_one() {
    // Nine frames put C left of A→B by 3σ; one frame (a misread) puts it far right.
    let lr = Calculus::builtin("left-right").unwrap();
    let run = |sensor| {
        let mut m = Pqrm::new(
            lr.clone(),
            PqrmConfig {
                sensor,
                samples: 4000,
                ..PqrmConfig::default()
            },
        )
        .unwrap();
        for t in 0..9 {
            m.update(&scan(f64::from(t), [-0.3, 5.0], 0.1)).unwrap();
        }
        let before = belief(&m)[1];
        m.update(&scan(9.0, [2.0, 5.0], 0.1)).unwrap();
        belief(&m)[1] - before // how far the outlier moved log P(right)
    };
    let g = run(SensorModel::Gaussian);
    let t = run(SensorModel::StudentT { nu: 3.0 });
    let o = run(SensorModel::Outliers {
        rate: 0.1,
        spread: 30.0,
    });
    assert!(g > 5.0, "the Gaussian is moved by many nats: {g}");
    // The mixture bounds a frame's influence whatever the outlier's distance; a t(3) tail
    // at 20σ still puts almost every sample on the far side, so it helps only a little.
    assert!(o < g / 3.0, "gaussian {g}, outliers {o}");
    assert!(t < g, "gaussian {g}, student-t {t}");
}

#[test]
fn bad_settings_are_refused_and_old_maps_load_as_gaussian_untempered() {
    let lr = Calculus::builtin("left-right").unwrap();
    for temper in [0.0, 1.5, f64::NAN, -1.0] {
        let c = PqrmConfig {
            temper,
            ..PqrmConfig::default()
        };
        assert!(c.validate().is_err(), "temper {temper}");
    }
    let c = PqrmConfig {
        sensor: SensorModel::StudentT { nu: -2.0 },
        ..PqrmConfig::default()
    };
    assert!(Pqrm::new(lr.clone(), c).is_err());
    // A map saved before the sensor model existed.
    let mut m = Pqrm::new(lr, PqrmConfig::default()).unwrap();
    m.update(&scan(0.0, [-1.0, 5.0], 0.1)).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&m.to_json().unwrap()).unwrap();
    let cfg = v["config"].as_object_mut().unwrap();
    assert!(cfg.remove("sensor").is_some() && cfg.remove("temper").is_some());
    let old = Pqrm::from_json(&v.to_string()).unwrap();
    assert_eq!(old.config().sensor, SensorModel::Gaussian);
    assert_eq!(old.config().temper, 1.0);
}
