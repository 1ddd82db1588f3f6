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
            "--set",
            "ablation_pairs=30",
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
    let names: Vec<&str> = list.lines().filter_map(|l| l.split(' ').next()).collect();
    assert_eq!(
        names,
        [
            "monte-carlo",
            "real-data",
            "reason",
            "serge-cv",
            "table-4-1",
            "field",
            "demo"
        ],
        "{list}"
    );
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
    // the demo is a study: its config is checked before anything is written
    let o = common::qrm(
        &[
            "study",
            "run",
            "demo",
            "--set",
            "nav_range=-2",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("nav_range must be a positive"), "{err}");
    assert!(!out.exists(), "nothing written for a refused config");
    let o = common::qrm(&["study", "run", "table-9-9", "--out", "x"], "");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("invalid value 'table-9-9'")
            && err.contains("monte-carlo, real-data, reason, serge-cv, table-4-1, field, demo"),
        "{err}"
    );
}

#[test]
fn shards_written_anywhere_aggregate_into_the_run() {
    let (run, agg, shards) = (dir("mc-run"), dir("mc-agg"), dir("mc-shards"));
    std::fs::create_dir_all(&shards).unwrap();
    let config = [
        "--quick",
        "--set",
        "trials=3",
        "--set",
        "samples=40",
        "--seed",
        "5",
    ];
    let mut a = vec!["study", "run", "monte-carlo"];
    a.extend(config);
    a.extend(["--out", run.to_str().unwrap()]);
    common::ok(&a, "");
    let mut a = vec!["study", "shard", "monte-carlo"];
    a.extend(config);
    assert_eq!(common::ok(&a, "").trim(), "3", "one shard per trial");
    let files: Vec<String> = (0..3)
        .rev()
        .map(|i| {
            shards
                .join(format!("s{i}.json"))
                .to_str()
                .unwrap()
                .to_owned()
        })
        .collect();
    for (i, f) in (0..3).rev().zip(&files) {
        let index = i.to_string();
        let mut a = vec!["study", "shard", "monte-carlo"];
        a.extend(config);
        a.extend(["--index", &index, "--out", f]);
        common::ok(&a, "");
    }
    let mut a = vec!["study", "aggregate", "monte-carlo"];
    a.extend(config);
    a.extend(["--out", agg.to_str().unwrap(), "--shard"]);
    a.extend(files.iter().map(String::as_str));
    common::ok(&a, "");
    for f in [
        "study.json",
        "levels.csv",
        "wrong_triplets.csv",
        "fig2_7_edc_entropy.svg",
    ] {
        assert_eq!(
            std::fs::read(run.join(f)).unwrap(),
            std::fs::read(agg.join(f)).unwrap(),
            "{f}"
        );
    }
    // a shard of another config, or one missing, is refused
    let mut a = vec![
        "study",
        "aggregate",
        "monte-carlo",
        "--quick",
        "--set",
        "trials=4",
    ];
    a.extend(["--out", agg.to_str().unwrap(), "--shard"]);
    a.extend(files.iter().map(String::as_str));
    let o = common::qrm(&a, "");
    let e = String::from_utf8_lossy(&o.stderr).to_string();
    assert!(
        e.contains("another config of `monte-carlo`") && e.contains("`trials`"),
        "{e}"
    );
    let mut a = vec!["study", "aggregate", "monte-carlo"];
    a.extend(config);
    a.extend(["--out", agg.to_str().unwrap(), "--shard", &files[0]]);
    let o = common::qrm(&a, "");
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("missing [0, 1]"), "{err}");
}
