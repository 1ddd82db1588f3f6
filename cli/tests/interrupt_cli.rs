//! Outputs are whole or absent (issue 17): a failing command leaves no output directory, and
//! Ctrl-C stops a long one within a second, says so, and removes what it had started.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::qrm;

fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("qrm-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Regression: `qrm map --truth` wrote `map.json`, then failed scoring (coincident surveyed
/// landmarks) and exited 1 with the map on disk.
#[test]
fn map_failing_at_scoring_leaves_no_output() {
    let d = scratch("map-truth");
    let obs = d.join("obs.csv");
    std::fs::write(
        &obs,
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,0,0,1,0,1\n0,0,2,0,5,1,0,1\n0,0,3,3,2,1,0,1\n",
    )
    .unwrap();
    let truth = d.join("truth.csv");
    std::fs::write(&truth, "landmark,x,y\n1,0,0\n2,0,0\n3,3,2\n").unwrap();
    let out = d.join("out");
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            obs.to_str().unwrap(),
            "--truth",
            truth.to_str().unwrap(),
            "--calculus",
            "left-right",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(
        o.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.exists(), "a failed map left {}", out.display());
    let leftovers: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(leftovers.len(), 2, "only the inputs remain: {leftovers:?}");
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn ctrl_c_stops_a_long_run_within_a_second_and_removes_its_output() {
    let d = scratch("interrupt");
    let out = d.join("study");
    let child = Command::new(env!("CARGO_BIN_EXE_qrm"))
        .args([
            "pqrm",
            "study",
            "--trials",
            "100000",
            "--out",
            out.to_str().unwrap(),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let staging = d.join(format!(".study.partial-{}", child.id()));
    let t0 = Instant::now();
    while !staging.exists() {
        assert!(
            t0.elapsed() < Duration::from_secs(60),
            "the study never started"
        );
        std::thread::sleep(Duration::from_millis(50));
    }
    std::thread::sleep(Duration::from_millis(300));
    let sent = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let took = sent.elapsed();
    assert!(took < Duration::from_secs(1), "took {took:?} to stop");
    assert_eq!(o.status.code(), Some(130));
    assert!(String::from_utf8_lossy(&o.stderr).contains("interrupted"));
    assert!(
        !out.exists() && !staging.exists(),
        "an interrupted run left output behind"
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// Regression (issue 17): `qrm sim --world /dev/zero` read forever until the OOM killer; a
/// device or a directory given as an input file is now refused at once.
#[test]
fn devices_and_directories_are_refused_not_read_forever() {
    let d = scratch("devices");
    let out = d.join("out");
    for args in [
        vec!["sim", "--scenario", "pqrm-100", "--world", "/dev/zero"],
        vec![
            "map",
            "--format",
            "csv",
            "--input",
            "/dev/zero",
            "--calculus",
            "edc",
        ],
        vec![
            "map",
            "--format",
            "g2o",
            "--input",
            "/tmp",
            "--calculus",
            "edc",
        ],
    ] {
        let mut args = args.clone();
        args.extend(["--out", out.to_str().unwrap()]);
        let t0 = Instant::now();
        let o = qrm(&args, "");
        assert_eq!(o.status.code(), Some(1), "{args:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains("not a file"), "{args:?}: {err}");
        assert!(t0.elapsed() < Duration::from_secs(5));
        assert!(!out.exists());
    }
    let _ = std::fs::remove_dir_all(&d);
}
