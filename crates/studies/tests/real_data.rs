//! The real-data study (thesis §2.3.2 on MRCLAM) as a study: configs checked by field, the
//! main run and the sensor variants as shards merged in any order into the local run.

use std::path::{Path, PathBuf};

use studies::Study;
use studies::pqrm::real_data::{NoiseSource, RealData, RealDataConfig, RealDataShard, Variant};

fn mrclam() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/mrclam-dataset7");
    d.is_dir().then_some(d)
}

fn err(config: &RealDataConfig) -> String {
    RealData::check(config)
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default()
}

#[test]
fn a_config_is_refused_by_the_field_that_does_not_fit() {
    let good = RealDataConfig::quick(0);
    assert!(RealData::check(&good).is_ok());
    assert!(RealData::check(&RealDataConfig::full(0)).is_ok());
    let e = err(&RealDataConfig {
        sigma_range: f64::NAN,
        ..good.clone()
    });
    assert!(e.contains("sigma_range = NaN"), "{e}");
    let e = err(&RealDataConfig {
        sigma_bearing: -0.1,
        ..good.clone()
    });
    assert!(e.contains("sigma_bearing = -0.1"), "{e}");
    let e = err(&RealDataConfig {
        gate_sigmas: Some(0.0),
        ..good.clone()
    });
    assert!(e.contains("gate_sigmas = 0"), "{e}");
    let e = err(&RealDataConfig {
        max_frames: Some(0),
        ..good.clone()
    });
    assert!(e.contains("max_frames = 0"), "{e}");
    let e = err(&RealDataConfig {
        calculi: vec!["edc".into(), "cardinal-directions-9".into()],
        ..good.clone()
    });
    assert!(e.contains("cardinal-directions-9"), "{e}");
    let mut bad_variant = good.clone();
    bad_variant.variants.push(Variant {
        temper: 1.5,
        ..bad_variant.variants[0]
    });
    let e = err(&bad_variant);
    assert!(e.contains("variants[6]") && e.contains("(0, 1]"), "{e}");
    let e = err(&RealDataConfig { samples: 0, ..good });
    assert!(e.contains("samples"), "{e}");
}

#[test]
fn a_missing_recording_is_named_before_any_work() {
    let config = RealDataConfig {
        input: PathBuf::from("/nonexistent/mrclam"),
        ..RealDataConfig::quick(0)
    };
    let e = RealData::run(&config, &|| {}).unwrap_err().to_string();
    assert!(
        e.contains("input = /nonexistent/mrclam") && e.contains("no such directory"),
        "{e}"
    );
}

/// The main run and every variant as shards, merged in reverse order: exactly the local run;
/// a missing variant or the main run given as a variant is refused.
#[test]
fn the_main_run_and_the_variants_merge_in_any_order_into_the_run() {
    let Some(input) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let config = RealDataConfig {
        input,
        samples: 40,
        max_frames: Some(60),
        variants: studies::pqrm::real_data::standard_variants()[..2].to_vec(),
        // the filter, so that the first variant (Gaussian, τ = 1) makes the main run's maps
        // (the default layout map is no variant of the filter)
        evidence: pqrm::EvidenceModel::shared_default(),
        ..RealDataConfig::quick(4)
    };
    assert_eq!(RealData::shards(&config).unwrap(), 3);
    let local = RealData::run(&config, &|| {}).unwrap();
    assert_eq!(local.main.recording.frames, 60);
    assert_eq!(local.main.results.len(), 6);
    assert_eq!(
        local.sensor_models.len(),
        2 * 6,
        "two variants × six calculi"
    );
    let shards: Vec<(usize, RealDataShard)> = (0..3)
        .rev()
        .map(|i| (i, RealData::run_shard(&config, i, &|| {}).unwrap()))
        .collect();
    let merged = RealData::aggregate(&config, shards.clone()).unwrap();
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&local).unwrap()
    );
    // the first variant is the main run's model (Gaussian, τ = 1): the same maps
    assert_eq!(local.sensor_models[0].calculus, "edc");
    assert_eq!(
        local.sensor_models[0].error_rate,
        local.main.results[0].pqrm.error_rate
    );
    let without_main: Vec<_> = shards.iter().filter(|s| s.0 != 0).cloned().collect();
    let e = RealData::aggregate(&config, without_main).unwrap_err();
    assert!(e.to_string().contains("missing [0]"), "{e}");
    let swapped: Vec<_> = shards.iter().cloned().map(|(i, s)| (2 - i, s)).collect();
    assert!(RealData::aggregate(&config, swapped).is_err());
    assert!(RealData::run_shard(&config, 3, &|| {}).is_err());
    let given = RealDataConfig {
        noise: NoiseSource::Given,
        gate_sigmas: None,
        variants: Vec::new(),
        ..config
    };
    let run = RealData::run(&given, &|| {}).unwrap();
    assert!(run.main.recording.noise_fit.is_none() && run.main.recording.gated.is_none());
    assert_eq!(run.main.recording.noise.sigma_range, given.sigma_range);
    let report = RealData::report(&given, &run);
    let md = report.to_markdown();
    assert!(md.contains("given in the config") && !md.contains("Gross outliers gated"));
    assert!(report.tables.iter().any(|t| t.name == "real"));
    assert!(report.attachments.iter().any(|a| a.name == "real.json"));
}
