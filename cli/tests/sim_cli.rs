//! `qrm sim` end to end: every scenario runs, its MCAP log passes the Go reference reader
//! (`shared/tools/mcapcheck`), and `qrm sim` → `qrm map` is a pipeline. The Python `mcap`
//! package reads the same logs in `tests/python/test_mcap.py`.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::Path;
use std::process::Command;

fn qrm(args: &[&str]) -> String {
    common::ok(args, "")
}

#[test]
fn every_scenario_writes_a_valid_log_and_a_mappable_csv() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sim-cli");
    let check = common::mcapcheck();
    for sc in ["hallway", "pqrm-100", "qlink-200", "field"] {
        let out = root.join(sc);
        let mut args = vec![
            "sim",
            "--scenario",
            sc,
            "--seed",
            "3",
            "--out",
            out.to_str().unwrap(),
        ];
        if sc == "qlink-200" {
            args.push("--no-lidar");
        }
        qrm(&args);
        for f in [
            "run.mcap",
            "observations.csv",
            "truth.csv",
            "world.toml",
            "scenario.svg",
            "scenario.png",
        ] {
            assert!(out.join(f).exists(), "{sc}: {f}");
        }
        if let Some(exe) = &check {
            let o = Command::new(exe)
                .arg(out.join("run.mcap"))
                .output()
                .unwrap();
            let text = String::from_utf8_lossy(&o.stdout);
            assert!(
                o.status.success() && text.contains("OK:"),
                "{sc}: {text}{}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
    // The pipeline: simulated observations into the mapper, scored against the world.
    let hall = root.join("hallway");
    let map = root.join("hallway-map");
    qrm(&[
        "map",
        "--format",
        "csv",
        "--input",
        hall.join("observations.csv").to_str().unwrap(),
        "--truth",
        hall.join("truth.csv").to_str().unwrap(),
        "--calculus",
        "double-cross",
        "--samples",
        "200",
        "--out",
        map.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(map.join("summary.json")).unwrap()).unwrap();
    assert!(s["n_sets"].as_u64().unwrap() > 1000);
    assert!(s["error_rate"].as_f64().unwrap() < 0.2, "{s}");
}

#[test]
fn lidar_only_mapping_is_a_pipeline_too() {
    // The §4.4.2 set-up: landmarks from the lidar alone, recognised without ids.
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sim-lidar");
    let (sim, map) = (root.join("sim"), root.join("map"));
    qrm(&[
        "sim",
        "--scenario",
        "field",
        "--detector",
        "lidar",
        "--seed",
        "2",
        "--out",
        sim.to_str().unwrap(),
    ]);
    qrm(&[
        "map",
        "--format",
        "csv",
        "--input",
        sim.join("observations.csv").to_str().unwrap(),
        "--truth",
        sim.join("truth.csv").to_str().unwrap(),
        "--calculus",
        "left-right",
        "--samples",
        "100",
        "--out",
        map.to_str().unwrap(),
    ]);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(map.join("summary.json")).unwrap()).unwrap();
    assert!(s["n_scored"].as_u64().unwrap() > 100, "{s}");
    // Mostly right: well below left-right's chance (0.5). Measured on this seed: 0.243, and
    // 0.252 once landmarks up close were no longer dropped for having more than 50 returns
    // (issue 40; seven more detections of real trees); seed 3 gives 0.308. The lidar-only
    // pipeline's errors are issue 36's (about half the ids are false landmarks).
    assert!(
        s["error_rate"].as_f64().unwrap() < 0.3,
        "lidar-only maps mostly right: {s}"
    );
    // half the ids are false landmarks: the frames agree on no one layout, so the default
    // (`--evidence auto`) maps with the filter and says why (a layout map of them: error 0.46)
    let why = s["evidence_choice"].as_str().unwrap();
    assert!(
        why.contains("the filter") && why.contains("disagree"),
        "{why}"
    );
    assert_eq!(s["evidence"], "shared:4");
}

#[test]
fn seeds_make_runs_byte_identical_and_bad_input_fails() {
    let root = Path::new(env!("CARGO_TARGET_TMPDIR")).join("sim-seeds");
    let run = |dir: &str, seed: &str| {
        let out = root.join(dir);
        qrm(&[
            "sim",
            "--scenario",
            "field",
            "--seed",
            seed,
            "--out",
            out.to_str().unwrap(),
        ]);
        std::fs::read(out.join("observations.csv")).unwrap()
    };
    assert_eq!(run("a", "7"), run("b", "7"));
    assert_ne!(run("a", "7"), run("c", "8"));
    let bad = root.join("bad.toml");
    std::fs::write(
        &bad,
        "bounds = [0, 10, 0, 10]\n[[landmark]]\nid = 1\npos = [5, 5]\nradius = -2.0\n",
    )
    .unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_qrm"))
        .args([
            "sim",
            "--scenario",
            "hallway",
            "--world",
            bad.to_str().unwrap(),
            "--out",
            root.join("x").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("radius"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = Command::new(env!("CARGO_BIN_EXE_qrm"))
        .args(["sim", "--scenario", "moon", "--out", "x"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("invalid value 'moon'") && err.contains("pqrm-100, qlink-200, hallway, field"),
        "{err}"
    );
}
