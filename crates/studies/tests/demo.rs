//! The demo as a study: one shard that merges into exactly the local run, a report whose
//! files say what its output holds, and settings refused before any work.

use qsr_core::progress::Progress;
use studies::Study;
use studies::demo::{Demo, DemoConfig};

fn attachment<'a>(report: &'a studies::Report, name: &str) -> &'a studies::Attachment {
    report
        .attachments
        .iter()
        .find(|a| a.name == name)
        .unwrap_or_else(|| panic!("no attachment {name}"))
}

#[test]
fn the_demo_is_one_shard_that_merges_into_the_local_run() {
    let config = DemoConfig::new(1);
    assert_eq!(Demo::shards(&config).unwrap(), 1);
    let local = Demo::run(&config, &|| {}).unwrap();
    // through the registry, as Python and a Ray driver run it: the shard as JSON
    let any = studies::find("demo").unwrap();
    let json_config = serde_json::to_value(&config).unwrap();
    let shard = any.run_shard(&json_config, 0, &|| {}).unwrap();
    let ran = any
        .aggregate(&json_config, vec![(0, shard.clone())])
        .unwrap();
    assert_eq!(ran.output, serde_json::to_value(&local).unwrap());
    assert_eq!(ran.report, Demo::report(&config, &local));
    // a missing, repeated, out-of-range or foreign shard is refused
    let e = any.aggregate(&json_config, vec![]).unwrap_err().to_string();
    assert!(e.contains("missing [0]"), "{e}");
    let twice = vec![(0, shard.clone()), (0, shard.clone())];
    let e = any.aggregate(&json_config, twice).unwrap_err().to_string();
    assert!(e.contains("more than once [0]"), "{e}");
    assert!(Demo::run_shard(&config, 1, &|| {}).is_err());
    let other = serde_json::to_value(DemoConfig::new(2)).unwrap();
    let e = any
        .aggregate(&other, vec![(0, shard)])
        .unwrap_err()
        .to_string();
    assert!(e.contains("not this config's"), "{e}");
}

#[test]
fn the_report_files_say_what_the_output_holds() {
    let config = DemoConfig::new(1);
    let out = Demo::run(&config, &|| {}).unwrap();
    let report = Demo::report(&config, &out);
    let summary: serde_json::Value =
        serde_json::from_str(&attachment(&report, "summary.json").text).unwrap();
    let nav = &out.run.outcome;
    assert_eq!(summary["success"], nav.success);
    assert_eq!(summary["goal"], out.run.goal);
    assert_eq!(summary["plan_len"], nav.plan_len);
    assert_eq!(summary["frames"], out.frames);
    assert!(summary.get("seconds").is_none(), "no timings in an output");
    // seed 1 crosses the site on the robot that errs (issue 36): the longest plan that
    // succeeds, found on the first try
    assert_eq!(summary["robot"]["detection"]["sigma"], 0.7, "{summary}");
    assert!(summary["robot"]["motion"]["heading_sigma"].as_f64() > Some(0.0));
    assert!(nav.success && nav.plan_len >= 3, "{summary}");
    assert_eq!(nav.plan.len(), nav.plan_len + 1);
    // the log is MCAP, carried as bytes, and as base64 through JSON
    let log = attachment(&report, "run.mcap");
    let bytes = log.data.as_deref().unwrap();
    assert!(bytes.starts_with(b"\x89MCAP0\r\n") && bytes.ends_with(b"\x89MCAP0\r\n"));
    let back: studies::Attachment =
        serde_json::from_str(&serde_json::to_string(log).unwrap()).unwrap();
    assert_eq!(&back, log);
    let learned = attachment(&report, "learned_calculus.json");
    let calculus = qsr_core::Calculus::from_json_str(&learned.text).unwrap();
    assert_eq!(
        Some(calculus.n_states()),
        out.learned.as_ref().map(|l| l.states)
    );
    // one row per transition; the picture's plan is the first plan's elements
    assert_eq!(
        report.table("transitions").map(|t| t.rows.len()),
        Some(nav.transitions.len())
    );
    assert_eq!(out.picture.plan.len(), nav.plan.len());
    assert!(report.setup.lines().count() == 3, "{}", report.setup);
}

#[test]
fn a_base64_field_that_is_not_base64_is_refused() {
    let e = serde_json::from_str::<studies::Attachment>(
        r#"{"name": "run.mcap", "text": "", "data": "not*base64"}"#,
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("not base64"), "{e}");
}

#[test]
fn settings_without_a_run_are_refused_naming_what() {
    for r in [f64::NAN, 0.0, -3.0, f64::INFINITY] {
        let c = DemoConfig {
            nav_range: r,
            ..DemoConfig::new(1)
        };
        let e = Demo::check(&c).unwrap_err().to_string();
        assert!(e.contains("nav_range"), "{e}");
        assert!(Demo::shards(&c).is_err());
    }
    let c = DemoConfig {
        goal: Some(99_999),
        ..DemoConfig::new(1)
    };
    let e = Demo::run(&c, &|| {}).unwrap_err().to_string();
    assert!(e.contains("no pose") && e.contains("landmark 99999"), "{e}");
}

#[test]
fn a_cancelled_demo_stops_with_cancelled() {
    struct Stop;
    impl Progress for Stop {
        fn tick(&self) {}
        fn cancelled(&self) -> bool {
            true
        }
    }
    let e = Demo::run(&DemoConfig::new(1), &Stop).unwrap_err();
    assert!(e.is_cancelled(), "{e}");
}

/// Regression (issue 40): the demo tried at most 24 runs, so seed 9 showed a failed run
/// though its 30th pair reaches its goal. Every pair with a plan is tried now, in batches
/// whose choice — the first success in the rule's order — does not depend on the threads.
/// (Seed 19 since the site's ground became pitched, issue 36: its first success is its 27th
/// pair, as seed 9's was its 30th.)
#[test]
fn regression_the_demo_tries_every_pair_before_it_shows_a_failure() {
    // the robot of the bug: exact
    let config = DemoConfig {
        exact_robot: true,
        ..DemoConfig::new(19)
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| Demo::run(&config, &|| {}).unwrap());
    let run = &one.run;
    assert!(
        run.outcome.success,
        "seed 19: {} tried of {}",
        run.tried, run.candidates
    );
    assert!(
        run.tried > 24 && run.tried <= run.candidates,
        "{} tried",
        run.tried
    );
    let many = Demo::run(&config, &|| {}).unwrap();
    assert_eq!((many.run.goal, many.run.tried), (run.goal, run.tried));
    assert_eq!(many.run.outcome, run.outcome);
}
