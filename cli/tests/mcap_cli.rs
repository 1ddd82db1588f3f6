//! Robot logs in: `qrm map --format mcap` and `qrm convert`, run as a user would. ROS 2 bags
//! from an independent writer (`rosbags`) are in `tests/python/test_ros2_bag.py`.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{ok, qrm};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("qrm-mcap-cli-{name}-{}", std::process::id()));
    std::fs::remove_dir_all(&d).ok();
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn map(format: &str, input: &Path, out: &Path, extra: &[&str]) -> String {
    let mut args = vec![
        "map",
        "--format",
        format,
        "--input",
        s(input),
        "--samples",
        "150",
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    ok(&args, "")
}

#[test]
fn a_sim_log_maps_exactly_as_its_observation_csv() {
    let d = tmp("sim");
    let sim = d.join("sim");
    ok(
        &[
            "sim",
            "--scenario",
            "pqrm-100",
            "--seed",
            "4",
            "--out",
            s(&sim),
        ],
        "",
    );
    map(
        "csv",
        &sim.join("observations.csv"),
        &d.join("a"),
        &["--truth", s(&sim.join("truth.csv"))],
    );
    // Detections are chosen by themselves; the log's surveyed truth comes with them.
    let summary = map("mcap", &sim.join("run.mcap"), &d.join("b"), &[]);
    assert!(
        summary.contains("\"/detections\"") && summary.contains("\"error_rate\""),
        "{summary}"
    );
    let a = std::fs::read(d.join("a/map.json")).unwrap();
    let b = std::fs::read(d.join("b/map.json")).unwrap();
    assert!(a.len() > 1000);
    assert!(
        a == b,
        "the map from run.mcap differs from the map from observations.csv"
    );
    // The lidar scans give a map of their own, with recogniser ids and so no score.
    let scans = map(
        "mcap",
        &sim.join("run.mcap"),
        &d.join("c"),
        &["--topic", "/scan"],
    );
    assert!(
        scans.contains("lidar scans") && !scans.contains("error_rate"),
        "{scans}"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn mrclam_to_mcap_to_map_equals_mrclam_to_map() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/mrclam-dataset7");
    if !data.is_dir() {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    }
    let d = tmp("mrclam");
    let log = d.join("run.mcap");
    let said = ok(
        &[
            "convert",
            "--from",
            "mrclam",
            "--input",
            s(&data),
            "--out",
            s(&log),
        ],
        "",
    );
    assert!(
        said.contains("of 5 robot(s) with surveyed landmarks"),
        "{said}"
    );
    if let Some(exe) = common::mcapcheck() {
        let o = Command::new(exe).arg(&log).output().unwrap();
        assert!(
            o.status.success() && String::from_utf8_lossy(&o.stdout).contains("OK:"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    let direct = map("mrclam", &data, &d.join("direct"), &[]);
    let via = map("mcap", &log, &d.join("via"), &[]);
    let a = std::fs::read(d.join("direct/map.json")).unwrap();
    let b = std::fs::read(d.join("via/map.json")).unwrap();
    assert!(a == b, "MRCLAM → MCAP → map differs from MRCLAM → map");
    let field = |text: &str, key: &str| {
        let v: serde_json::Value = serde_json::from_str(text).unwrap();
        v[key].clone()
    };
    assert_eq!(field(&direct, "error_rate"), field(&via, "error_rate"));
    assert_eq!(field(&via, "topics").as_array().unwrap().len(), 5);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_wrong_topic_a_foreign_schema_and_a_cut_log_are_typed_errors_naming_them() {
    let d = tmp("errors");
    let sim = d.join("sim");
    ok(
        &[
            "sim",
            "--scenario",
            "hallway",
            "--seed",
            "1",
            "--out",
            s(&sim),
        ],
        "",
    );
    let log = sim.join("run.mcap");
    let fail = |input: &Path, extra: &[&str]| {
        let mut args = vec!["map", "--format", "mcap", "--input", s(input), "--out"];
        let out = d.join("never");
        args.push(s(&out));
        args.extend_from_slice(extra);
        let o = qrm(&args, "");
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        assert!(!out.exists(), "a failed read left {}", out.display());
        String::from_utf8(o.stderr).unwrap()
    };
    let e = fail(&log, &["--topic", "/lidar"]);
    assert!(
        e.contains("no topic /lidar; topics present: /scan (foxglove.LaserScan"),
        "{e}"
    );
    let e = fail(&log, &["--topic", "/tf"]);
    assert!(
        e.contains("topic /tf has schema `foxglove.FrameTransform`")
            && e.contains("readable: sensor_msgs/msg/LaserScan"),
        "{e}"
    );
    let e = fail(&log, &["--topic", "/scan", "--topic", "/detections"]);
    assert!(
        e.contains("scans and detections cannot be read together"),
        "{e}"
    );
    // Cut midway: an error naming what was read, or, when asked, the map up to the last chunk.
    let bytes = std::fs::read(&log).unwrap();
    let cut = d.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).unwrap();
    let e = fail(&cut, &[]);
    assert!(
        e.contains("cut.mcap: not a readable MCAP file after") && e.contains("/detections"),
        "{e}"
    );
    let o = qrm(
        &[
            "map",
            "--format",
            "mcap",
            "--input",
            s(&cut),
            "--allow-truncated",
            "--samples",
            "50",
            "--out",
            s(&d.join("partial")),
        ],
        "",
    );
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("read up to its last readable chunk"));
    // Not MCAP at all.
    let e = fail(&sim.join("observations.csv"), &[]);
    assert!(e.contains("not a readable MCAP file"), "{e}");
    // MCAP-only flags on another format.
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            s(&sim.join("observations.csv")),
            "--topic",
            "/x",
            "--out",
            s(&d.join("never")),
        ],
        "",
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("are for --format mcap"));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn convert_writes_whole_or_nothing() {
    let d = tmp("convert");
    let csv = d.join("obs.csv");
    std::fs::write(
        &csv,
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,1,1,2,0,0.01,0,0.01\n0,1,2,3,1,0.01,0,0.01\n",
    )
    .unwrap();
    let out = d.join("run.mcap");
    ok(
        &[
            "convert",
            "--from",
            "csv",
            "--input",
            s(&csv),
            "--out",
            s(&out),
        ],
        "",
    );
    assert!(out.is_file());
    // A bad input leaves no file and no staging directory behind.
    std::fs::write(
        &csv,
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,1,1,NaN,0,0.01,0,0.01\n",
    )
    .unwrap();
    let bad = d.join("bad.mcap");
    let o = qrm(
        &[
            "convert",
            "--from",
            "csv",
            "--input",
            s(&csv),
            "--out",
            s(&bad),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(!bad.exists());
    let left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(left.len(), 2, "{left:?}");
    std::fs::remove_dir_all(&d).ok();
}
