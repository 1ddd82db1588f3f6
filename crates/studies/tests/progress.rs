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
    let watch = Watch::new();
    let (watched, _) = run_study(&config, &watch).unwrap();
    assert_eq!(plain, watched);
    assert_eq!(watch.done(), watched.len());
    assert_eq!(watch.total(), watched.len());
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
