//! The Monte Carlo study as a `Study`: shards merge into exactly the local run, and the
//! report counts the trials it ran.
#![allow(clippy::unwrap_used, missing_docs)]

use studies::Study;
use studies::pqrm::monte_carlo::{MonteCarlo, trial_ranges};

fn small() -> pqrm::study::MonteCarloConfig {
    pqrm::study::MonteCarloConfig {
        sigmas: vec![0.0, 20.0],
        detail_sigmas: vec![1.0],
        trials: 5,
        samples: 40,
        calculi: vec!["edc".into(), "left-right".into()],
        ..MonteCarlo::quick(7)
    }
}

#[test]
fn shards_in_any_order_give_the_local_run() {
    let c = small();
    let n = MonteCarlo::shards(&c).unwrap();
    assert_eq!(n, trial_ranges(&c).len());
    let local = MonteCarlo::run(&c, &|| {}).unwrap();
    let shards: Vec<_> = (0..n)
        .rev()
        .map(|i| (i, MonteCarlo::run_shard(&c, i, &|| {}).unwrap()))
        .collect();
    let merged = MonteCarlo::aggregate(&c, shards.clone()).unwrap();
    assert_eq!(
        serde_json::to_string(&merged).unwrap(),
        serde_json::to_string(&local).unwrap()
    );
    let e = MonteCarlo::aggregate(&c, shards[1..].to_vec())
        .unwrap_err()
        .to_string();
    assert!(e.contains("missing"), "{e}");
}

#[test]
fn the_set_up_counts_the_detail_level_it_added() {
    // issue 14: the full run printed "21000 trials" after running 22,000 (σ_R = 1 m, a
    // detail level, runs as a level of its own)
    let c = small();
    let r = MonteCarlo::run(&c, &|| {}).unwrap();
    let report = MonteCarlo::report(&c, &r);
    assert!(
        report
            .setup
            .contains("5 trials per level: 15 trials in all"),
        "{}",
        report.setup
    );
    let levels = report.table("levels").unwrap();
    assert_eq!(levels.rows.len(), 3 * 2, "three levels × two calculi");
    // every claim has a computed verdict and says what we measured
    assert!(report.claims.iter().all(|c| !c.ours.is_empty()));
    assert!(report.claim("Fig 2.11b").is_some());
}
