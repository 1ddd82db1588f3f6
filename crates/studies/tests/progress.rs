//! Long Q-Link work reports through `qsr_core::progress` and stops when asked (issue 19:
//! Ctrl-C in Python's `qlink_study` surfaced only when the call returned).

use qsr_core::progress::{Progress, Watch};
use studies::qlink::table_4_1::{StudyConfig, run_study};

fn small() -> StudyConfig {
    StudyConfig {
        trial: studies::qlink::table_4_1::Trials::SensorRange,
        pairs: Some(30),
        samples: 40,
        ..StudyConfig::quick(3)
    }
}

#[test]
fn a_watch_counts_every_navigation_and_changes_no_result() {
    let config = small();
    let (plain, _) = run_study(&config, &|| {}).unwrap();
    let recorder = Recorder::default();
    let (watched, _) = run_study(&config, &recorder).unwrap();
    assert_eq!(plain, watched);
    // the map, a distance field per goal landmark, then the navigations
    let landmarks = 200;
    assert_eq!(recorder.totals(), vec![(0, 1 + landmarks + watched.len())]);
    assert_eq!(recorder.watch.done(), recorder.watch.total());
}

/// A progress that records each announcement with the ticks done when it came.
#[derive(Default)]
struct Recorder {
    watch: Watch,
    announced: std::sync::Mutex<Vec<(usize, usize)>>,
}

impl Recorder {
    fn totals(&self) -> Vec<(usize, usize)> {
        self.announced
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }
}

impl Progress for Recorder {
    fn tick(&self) {
        self.watch.tick();
    }
    fn add_total(&self, units: usize) {
        self.announced
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .push((self.watch.done(), units));
        self.watch.add_total(units);
    }
    fn cancelled(&self) -> bool {
        self.watch.cancelled()
    }
}

/// The quick config of `study`, made smaller where a quick run takes more than a few seconds
/// (the same small settings as the Python tests'); `None` without the recording it reads.
fn small_config(study: &dyn studies::AnyStudy) -> Option<serde_json::Value> {
    let mut c = study.config(false, study.default_seed());
    let recording = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data/mrclam-dataset7");
    match study.name() {
        "table-4-1" => {
            c["trial"] = "sensor-range".into();
            c["pairs"] = 30.into();
            c["schedule_pairs"] = 30.into();
            c["samples"] = 30.into();
            c["range_factors"] = serde_json::json!([1.0, 0.7]);
        }
        "reason" | "real-data" => {
            if !recording.is_dir() {
                return None;
            }
            c["input"] = recording.to_string_lossy().into_owned().into();
            c["max_frames"] = 80.into();
            if study.name() == "reason" {
                c["study"]["calculi"] = serde_json::json!(["double-cross"]);
            }
        }
        _ => {}
    }
    Some(c)
}

/// Every study announces its whole total once, before its first tick, and ticks exactly that
/// many units — a whole run and a shard alike (issue 40: a tqdm bar's total grew twentyfold
/// during `qrm.studies.run`, and real-data's ended at 2,520 of 2,760).
#[test]
fn every_study_announces_its_total_once_before_it_starts_and_meets_it() {
    let mut ran = Vec::new();
    for study in studies::STUDIES {
        let Some(config) = small_config(*study) else {
            continue;
        };
        let name = study.name();
        let whole = Recorder::default();
        study
            .run(&config, &whole)
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        let totals = whole.totals();
        assert_eq!(totals.len(), 1, "{name}: announced {totals:?}");
        assert_eq!(
            totals[0].0, 0,
            "{name}: announced after {} ticks",
            totals[0].0
        );
        assert_eq!(whole.watch.done(), totals[0].1, "{name}: ticks ≠ total");
        assert!(totals[0].1 > 0, "{name}");
        // the last shard alone: its own total, met
        let last = study.shards(&config).unwrap() - 1;
        let shard = Recorder::default();
        study.run_shard(&config, last, &shard).unwrap();
        let totals = shard.totals();
        assert_eq!(totals.len(), 1, "{name} shard {last}: announced {totals:?}");
        assert_eq!(totals[0].0, 0, "{name} shard {last}");
        assert_eq!(shard.watch.done(), totals[0].1, "{name} shard {last}");
        ran.push(name);
    }
    assert!(ran.len() >= 5, "{ran:?}");
}

#[test]
fn a_stopped_watch_cancels_the_study_before_it_navigates() {
    let watch = Watch::new();
    watch.stop();
    let err = run_study(&small(), &watch).unwrap_err();
    assert!(err.is_cancelled(), "{err:?}");
    assert_eq!(watch.done(), 0);
}

/// A stop that arrives while the navigations run: the study returns `Cancelled` without
/// running the rest.
#[test]
fn a_stop_during_the_navigations_ends_them_early() {
    struct StopAfter {
        watch: Watch,
        after: usize,
    }
    impl Progress for StopAfter {
        fn tick(&self) {
            self.watch.tick();
            if self.watch.done() >= self.after {
                self.watch.stop();
            }
        }
        fn add_total(&self, units: usize) {
            self.watch.add_total(units);
        }
        fn cancelled(&self) -> bool {
            self.watch.cancelled()
        }
    }
    let p = StopAfter {
        watch: Watch::new(),
        after: 3,
    };
    let err = run_study(&small(), &p).unwrap_err();
    assert!(err.is_cancelled(), "{err:?}");
    // workers already inside a navigation finish it; none starts after the stop
    let threads = rayon::current_num_threads();
    assert!(p.watch.done() < 3 + threads, "{} done", p.watch.done());
    assert!(p.watch.done() < p.watch.total());
}
