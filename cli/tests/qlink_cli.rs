//! `qrm qlink study`, `qrm qlink field` and `qrm demo` end to end: Table 4.1's CSV in the
//! documented form, Proposition 1 at R' = R, the field experiment's outputs, and the demo's
//! MCAP log passing the Go reference reader.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::Path;
use std::process::Command;

#[test]
fn quick_study_writes_table_4_1() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("qlink-study");
    let _ = std::fs::remove_dir_all(&out);
    common::ok(
        &[
            "qlink",
            "study",
            "--quick",
            "--pairs",
            "60",
            "--seed",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let table = std::fs::read_to_string(out.join("table.csv")).unwrap();
    let mut lines = table.lines();
    assert_eq!(
        lines.next(),
        Some(
            "trial,value,schedule,pairs,no_path,failures,failure_rate,thesis_failure_rate,mean_length,over_prop2_bound"
        )
    );
    let all: Vec<Vec<String>> = lines
        .map(|l| {
            // the schedule holds a comma, quoted
            let (a, rest) = l.split_once(",\"").unwrap();
            let (sched, b) = rest.split_once("\",").unwrap();
            let mut v: Vec<String> = a.split(',').map(str::to_owned).collect();
            v.push(sched.to_owned());
            v.extend(b.split(',').map(str::to_owned));
            v
        })
        .collect();
    // 9 main rows, and the 4 occlusion sizes under 3 further schedules
    assert_eq!(all.len(), 21);
    let rows: Vec<Vec<String>> = all
        .iter()
        .filter(|r| r[2] == "continuous, 1 fallback")
        .map(|r| {
            let mut r = r.clone();
            r.remove(2);
            r
        })
        .collect();
    assert_eq!(rows.len(), 9);
    // issue 18: the occlusion study can fail (sensing only at stops, no fallback circle)
    let sparse: usize = all
        .iter()
        .filter(|r| r[2] == "stops every 30°, 0 fallbacks")
        .map(|r| r[5].parse::<usize>().unwrap())
        .sum();
    assert!(sparse > 0, "{all:?}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        !report.contains("Idealised run"),
        "the default robot is the thesis's"
    );
    let get = |trial: &str, value: &str| {
        rows.iter()
            .find(|r| r[0] == trial && r[1] == value)
            .unwrap()
            .clone()
    };
    // Proposition 1: R' = R without occlusion never fails
    assert_eq!(get("sensor-range", "1")[4], "0");
    // a shorter sensor fails more
    let rate = |r: Vec<String>| r[5].parse::<f64>().unwrap();
    assert!(rate(get("sensor-range", "0.6")) > rate(get("sensor-range", "0.9")));
    for r in &rows {
        assert_eq!(r[2], "60");
    }
    for f in [
        "report.md",
        "records.csv",
        "fig4_6_plan_length_histogram.svg",
        "fig4_7_length_vs_plan_length.png",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let r = common::qrm(
        &[
            "qlink",
            "study",
            "--trial",
            "nope",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("unknown trial"));
}

#[test]
fn the_demo_maps_learns_navigates_and_logs() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("demo");
    let _ = std::fs::remove_dir_all(&out);
    let stdout = common::ok(&["demo", "--out", out.to_str().unwrap()], "");
    assert!(stdout.contains("SERGE learned a calculus"), "{stdout}");
    assert!(stdout.contains("reached"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["success"], true);
    assert!(
        summary["trajectory_length"].as_f64().unwrap() <= summary["prop2_bound"].as_f64().unwrap()
    );
    for f in ["run.mcap", "demo.svg", "demo.png", "learned_calculus.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // the learned calculus is a calculus
    common::ok(
        &[
            "calculus",
            "show",
            out.join("learned_calculus.json").to_str().unwrap(),
        ],
        "",
    );
    if let Some(check) = common::mcapcheck() {
        let r = Command::new(check)
            .arg(out.join("run.mcap"))
            .output()
            .unwrap();
        let text = String::from_utf8_lossy(&r.stdout);
        assert!(
            r.status.success() && text.contains("OK:"),
            "mcapcheck: {text}{}",
            String::from_utf8_lossy(&r.stderr)
        );
    }
}

#[test]
fn quick_field_experiment_writes_its_report() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("qlink-field");
    let _ = std::fs::remove_dir_all(&out);
    common::ok(
        &[
            "qlink",
            "field",
            "--quick",
            "--trials",
            "5",
            "--worlds",
            "2",
            "--seed",
            "1",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let trials = std::fs::read_to_string(out.join("trials.csv")).unwrap();
    assert_eq!(
        trials.lines().count(),
        1 + 2 * 4 * 5,
        "2 worlds × 4 variants × 5 trials"
    );
    assert!(trials.starts_with("world,seed,variant,"));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let variants = summary["variants"].as_array().unwrap();
    assert_eq!(variants.len(), 4);
    for v in variants {
        let rate = v["success_rate"].as_f64().unwrap();
        assert!((0.0..=1.0).contains(&rate), "{v}");
    }
    let worlds = summary["worlds"].as_array().unwrap();
    assert_eq!(worlds.len(), 2);
    assert_eq!(worlds[1]["seed"], 2, "world seeds follow --seed");
    for w in worlds {
        assert!(w["mapping"]["wall_elements"].as_u64().unwrap() > 0);
    }
    let spread = summary["success_rate_over_worlds"].as_array().unwrap();
    assert_eq!(spread.len(), 4);
    assert!(spread.iter().all(|v| v["sd"].as_f64().unwrap() >= 0.0));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("72.2 %") && report.contains("Table 4.2"));
    for f in ["table_4_2.csv", "fig_4_9_thesis.svg", "fig_4_9_thesis.png"] {
        assert!(out.join(f).exists(), "{f}");
    }
    // bad input: zero trials is an error, not an empty report
    let bad = common::qrm(
        &[
            "qlink",
            "field",
            "--trials",
            "0",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!bad.status.success());
    assert!(String::from_utf8_lossy(&bad.stderr).contains("at least 1"));
    let bad = common::qrm(
        &[
            "qlink",
            "field",
            "--worlds",
            "0",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!bad.status.success());
}

/// Regression (issue 17): `qlink study --pairs 0` exited 0 with an empty table. An empty
/// study is an error now, as are non-positive settings, and nothing is written.
#[test]
fn an_empty_study_is_an_error() {
    let out = std::env::temp_dir().join(format!("qrm-qlink-empty-{}", std::process::id()));
    let o = common::qrm(
        &[
            "qlink",
            "study",
            "--quick",
            "--pairs",
            "0",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("pairs must be >= 1"));
    assert!(!out.join("table.csv").exists());
}
