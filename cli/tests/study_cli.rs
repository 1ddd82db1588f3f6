//! `qrm study`: one runner for every study — list, config, run — and the old subcommands as
//! its aliases, byte for byte.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::Path;

fn dir(name: &str) -> std::path::PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    d
}

#[test]
fn the_alias_and_the_runner_write_the_same_files() {
    let (a, b, c) = (dir("alias"), dir("runner"), dir("from-file"));
    common::ok(
        &[
            "qlink",
            "study",
            "--quick",
            "--trial",
            "sensor-range",
            "--pairs",
            "30",
            "--seed",
            "2",
            "--out",
            a.to_str().unwrap(),
        ],
        "",
    );
    let printed = common::ok(
        &[
            "study",
            "run",
            "table-4-1",
            "--quick",
            "--set",
            "trial=sensor-range",
            "--set",
            "pairs=30",
            "--set",
            "schedule_pairs=30",
            "--seed",
            "2",
            "--out",
            b.to_str().unwrap(),
        ],
        "",
    );
    // the report's claims are printed with their computed verdicts
    assert!(
        printed.contains("] Failure rate as R' shrinks: thesis rises"),
        "{printed}"
    );
    for f in [
        "table.csv",
        "records.csv",
        "fig4_7_length_vs_plan_length.svg",
        "config.toml",
    ] {
        assert_eq!(
            std::fs::read(a.join(f)).unwrap(),
            std::fs::read(b.join(f)).unwrap(),
            "{f}"
        );
    }
    // the config a run wrote runs again to the same result
    common::ok(
        &[
            "study",
            "run",
            "table-4-1",
            "--config",
            b.join("config.toml").to_str().unwrap(),
            "--out",
            c.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(
        std::fs::read(b.join("table.csv")).unwrap(),
        std::fs::read(c.join("table.csv")).unwrap()
    );
}

#[test]
fn list_config_and_refusals() {
    let list = common::ok(&["study", "list"], "");
    assert!(list.starts_with("table-4-1 "), "{list}");
    let full = common::ok(
        &["study", "config", "table-4-1", "--full", "--seed", "7"],
        "",
    );
    assert!(
        full.contains("seed = 7") && full.contains("samples = 200"),
        "{full}"
    );
    assert!(
        !full.lines().any(|l| l.starts_with("pairs = ")),
        "all pairs: no field\n{full}"
    );
    let out = dir("refused");
    for (args, says) in [
        (vec!["--set", "pears=3"], "no field `pears`"),
        (vec!["--set", "pairs=0"], "pairs must be >= 1"),
        (vec!["--set", "pairs=many"], "expected usize"),
        (vec!["--set", "trial=sideways"], "sideways"),
    ] {
        let mut a = vec!["study", "run", "table-4-1", "--quick"];
        a.extend(args);
        a.extend(["--out", out.to_str().unwrap()]);
        let o = common::qrm(&a, "");
        assert_eq!(o.status.code(), Some(1), "{a:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(err.contains(says), "{a:?}: {err}");
        assert!(!out.exists(), "nothing written for a refused config");
    }
    let o = common::qrm(&["study", "run", "table-9-9", "--out", "x"], "");
    assert!(String::from_utf8_lossy(&o.stderr).contains("studies: table-4-1"));
}
