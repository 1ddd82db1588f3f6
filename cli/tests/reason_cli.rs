//! `qrm reason close|scenario|check|infer|study` as a user runs them, including the narrow
//! JSON interface of `qrm reason close` that acceptance checks use.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use common::{ok, qrm};

use std::path::{Path, PathBuf};

use serde_json::Value;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("qrm-reason-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn triplet_map(v: &Value) -> std::collections::BTreeMap<(String, String, String), Vec<String>> {
    v["constraints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let s = |i: usize| c[i].as_str().unwrap().to_owned();
            let labels = c[3]
                .as_array()
                .unwrap()
                .iter()
                .map(|l| l.as_str().unwrap().to_owned())
                .collect();
            ((s(0), s(1), s(2)), labels)
        })
        .collect()
}

#[test]
fn close_prints_the_closed_network_over_every_ordered_triplet() {
    // C left-front of A→B and D left-front of B→C: closure bounds {A,B:D} and fills the
    // permuted orderings; nothing else was said.
    let input =
        r#"{"constraints": [["A", "B", "C", ["left-front"]], ["B", "C", "D", ["left-front"]]]}"#;
    let out = ok(&["reason", "close", "--calculus", "double-cross"], input);
    let v: Value = serde_json::from_str(&out).unwrap();
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(keys, ["consistent", "constraints"]);
    assert_eq!(v["consistent"], true);
    let m = triplet_map(&v);
    assert_eq!(m.len(), 4 * 3 * 2, "every ordered triplet of 4 points");
    let key = |a: &str, b: &str, c: &str| (a.to_owned(), b.to_owned(), c.to_owned());
    assert_eq!(m[&key("A", "B", "C")], ["left-front"]);
    // Inverse of left-front (sound table: the boundary case on the perpendicular at B too).
    assert!(m[&key("B", "A", "C")].contains(&"right-back".to_owned()));
    assert!(!m[&key("B", "A", "C")].contains(&"left-front".to_owned()));
    // {A,B:D} is narrowed to the left half: C ahead-left of A→B makes B→C head up and to
    // the left, and the left of B→C ahead of C lies left of A→B.
    let abd = &m[&key("A", "B", "D")];
    assert_eq!(abd, &["left-front", "left-middle", "left-back"]);
}

#[test]
fn close_reports_an_inconsistent_network_and_explains_it() {
    let input = r#"{"constraints": [["A", "B", "C", ["left"]], ["B", "A", "C", ["left"]], ["A", "B", "D", ["right"]]]}"#;
    let out = qrm(&["reason", "close", "--calculus", "left-right"], input);
    assert!(out.status.success());
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["consistent"], false);
    let m = triplet_map(&v);
    assert!(
        m.values().any(Vec::is_empty),
        "the emptied constraint is in the output"
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("became empty"), "{err}");
}

#[test]
fn close_reads_sparq_networks() {
    let json = ok(
        &["reason", "close", "--calculus", "double-cross"],
        r#"{"constraints": [["A", "B", "C", ["left-front", "left-middle"]], ["B", "C", "D", ["right-back"]]]}"#,
    );
    let sparq = ok(
        &["reason", "close", "--calculus", "double-cross"],
        "((A B (left-front left-middle) C)\n (B C right-back D))",
    );
    assert_eq!(json, sparq);
}

#[test]
fn bad_networks_fail_with_the_place_and_the_cause() {
    for (input, needle) in [
        (
            r#"{"constraints": [["A", "B", "C", ["sideways"]]]}"#,
            "sideways",
        ),
        (r#"{"constraints": [["A", "B", "C", ["left"]"#, "line 1"),
        ("((A B (left) C)", "never closed"),
        ("hello", "first character"),
        ("", "empty input"),
    ] {
        let out = qrm(&["reason", "close", "--calculus", "left-right"], input);
        assert!(!out.status.success(), "{input} was accepted");
        assert_eq!(out.status.code(), Some(1), "typed error, no panic");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "`{err}` does not say `{needle}`");
    }
    // Extended calculi have no networks (a typed error); star-m is binary since issue 15
    // and closes its (here empty) network.
    let out = qrm(
        &["reason", "close", "--calculus", "front-between-behind"],
        r#"{"constraints": []}"#,
    );
    assert_eq!(out.status.code(), Some(1));
    let out = qrm(
        &["reason", "close", "--calculus", "star-4"],
        r#"{"constraints": []}"#,
    );
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn scenario_finds_one_or_says_none() {
    let out = ok(
        &["reason", "scenario", "--calculus", "double-cross"],
        r#"{"constraints": [["A", "B", "C", ["left-front", "right-back"]], ["A", "B", "D", ["left-back"]]]}"#,
    );
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["consistent"], true);
    assert!(triplet_map(&v).values().all(|l| l.len() == 1));
    let out = ok(
        &["reason", "scenario", "--calculus", "left-right"],
        r#"{"constraints": [["A", "B", "C", ["left"]], ["B", "A", "C", ["left"]]]}"#,
    );
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["consistent"], false);
    assert!(v["constraints"].is_null());
}

/// Observations of 8 landmarks from two stops that see overlapping halves.
fn small_map(dir: &Path) -> PathBuf {
    small_map_with(dir, &[])
}

/// [`small_map`] mapped with `extra` flags.
fn small_map_with(dir: &Path, extra: &[&str]) -> PathBuf {
    // No triplet within 1 % (relative) of a double-cross line: the ML states are the truth.
    let pts: [(u32, f64, f64); 8] = [
        (1, -0.22, -0.44),
        (2, 3.35, 1.49),
        (3, 0.59, 4.3),
        (4, 4.91, 4.65),
        (5, 7.79, 2.27),
        (6, 9.37, 5.54),
        (7, 12.11, 0.54),
        (8, 13.22, 4.83),
    ];
    let mut csv = String::from("t,robot,landmark,x,y,cxx,cxy,cyy\n");
    for (t, lo, hi) in [(0, 1, 5), (1, 3, 8), (2, 1, 5), (3, 3, 8)] {
        for (id, x, y) in pts.iter().filter(|(id, _, _)| (lo..=hi).contains(id)) {
            csv.push_str(&format!("{t},0,{id},{x},{y},0.000001,0,0.000001\n"));
        }
    }
    std::fs::create_dir_all(dir).unwrap();
    let obs = dir.join("obs.csv");
    std::fs::write(&obs, csv).unwrap();
    let mut args = vec![
        "map",
        "--format",
        "csv",
        "--input",
        obs.to_str().unwrap(),
        "--calculus",
        "double-cross",
        "--samples",
        "200",
        "--out",
        dir.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    ok(&args, "");
    dir.join("map.json")
}

#[test]
fn check_and_infer_work_on_a_saved_map() {
    let dir = tmp("map");
    let map = small_map(&dir);
    let out = ok(&["reason", "check", map.to_str().unwrap(), "--json"], "");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["consistent"], true, "{out}");
    assert_eq!(v["flagged"].as_array().unwrap().len(), 0);
    // The map as a network closes consistent through the narrow interface, and the export
    // with a threshold keeps at least the most likely states.
    let net = ok(&["reason", "export", map.to_str().unwrap()], "");
    let closed: Value = serde_json::from_str(&ok(
        &["reason", "close", "--calculus", "double-cross"],
        &net,
    ))
    .unwrap();
    assert_eq!(closed["consistent"], true);
    assert_eq!(triplet_map(&closed).len(), 8 * 7 * 6);
    let loose: Value = serde_json::from_str(&ok(
        &[
            "reason",
            "export",
            map.to_str().unwrap(),
            "--threshold",
            "0.0001",
        ],
        "",
    ))
    .unwrap();
    let strict: Value = serde_json::from_str(&net).unwrap();
    for (k, labels) in triplet_map(&strict) {
        let l = &triplet_map(&loose)[&k];
        assert!(labels.iter().all(|x| l.contains(x)), "{k:?}");
    }
    let sparq = ok(
        &[
            "reason",
            "export",
            map.to_str().unwrap(),
            "--format",
            "sparq",
        ],
        "",
    );
    assert!(sparq.starts_with("(("), "{sparq}");
    let out = qrm(
        &[
            "reason",
            "export",
            map.to_str().unwrap(),
            "--threshold",
            "2",
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(1));
    // {1,2,8} was never seen together (1 and 8 are in different halves).
    let inferred = dir.join("inferred.json");
    let out = ok(
        &[
            "reason",
            "infer",
            map.to_str().unwrap(),
            "--out",
            inferred.to_str().unwrap(),
        ],
        "",
    );
    assert!(out.contains("inferred"), "{out}");
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&inferred).unwrap()).unwrap();
    let rows = v["inferences"].as_array().unwrap();
    let row = rows
        .iter()
        .find(|r| r["set"] == serde_json::json!([1, 2, 8]))
        .expect("the unseen set {1,2,8} is inferred");
    let p: Vec<f64> = row["p"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!((p.iter().sum::<f64>() - 1.0).abs() < 1e-9);
    assert!(row["round"].as_u64().unwrap() >= 1, "{row}");
    // 8 is right of 1→2 and ahead of 2: right-front.
    assert_eq!(row["ml"], "right-front", "{row}");
    // An explicit set, and a landmark the map does not have.
    ok(
        &[
            "reason",
            "infer",
            map.to_str().unwrap(),
            "--set",
            "8,1,2",
            "--out",
            inferred.to_str().unwrap(),
        ],
        "",
    );
    let out = qrm(
        &[
            "reason",
            "infer",
            map.to_str().unwrap(),
            "--set",
            "1,2,99",
            "--out",
            inferred.to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("99"));
}

/// Issue 35: inference over a layout map (`qrm map`'s default on a recording whose frames
/// agree on one layout) was measured overconfident where inference over the filter's maps
/// was closer to calibrated; `qrm reason infer` says so on stderr for a layout map and only for one.
#[test]
fn infer_over_a_layout_map_says_what_its_calibration_was_measured_to_be() {
    let dir = tmp("infer-layout-note");
    let map = small_map(&dir);
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["evidence"], "layout", "{summary}");
    let inferred = dir.join("inferred.json");
    let infer = |map: &Path| {
        let out = qrm(
            &[
                "reason",
                "infer",
                map.to_str().unwrap(),
                "--out",
                inferred.to_str().unwrap(),
            ],
            "",
        );
        assert!(out.status.success(), "{out:?}");
        String::from_utf8_lossy(&out.stderr).into_owned()
    };
    let note = infer(&map);
    assert!(
        note.contains("layout map") && note.contains("--evidence shared"),
        "{note}"
    );
    // The same frames mapped by the filter: no note.
    let filter = small_map_with(&dir.join("filter"), &["--evidence", "shared"]);
    let quiet = infer(&filter);
    assert!(!quiet.contains("layout map"), "{quiet}");
}

/// Regression (issue 14): `qrm reason infer --set A,B,D` composed through the sets a full
/// run had just inferred while saying "round 1", so one set got two answers: 42 paths and
/// another distribution with `--set`, 2 paths in the run over every unseen set. Asked alone
/// or read from the full run, a set now gets the same inference, in either number of rounds.
#[test]
fn infer_of_one_set_agrees_with_the_run_over_every_unseen_set() {
    let dir = tmp("infer-agrees");
    let map = small_map(&dir);
    let map = map.to_str().unwrap();
    for rounds in ["1", "2"] {
        let full = dir.join(format!("full{rounds}.json"));
        let args = ["reason", "infer", map, "--rounds", rounds, "--out"];
        ok(&[&args[..], &[full.to_str().unwrap()]].concat(), "");
        let v: Value = serde_json::from_str(&std::fs::read_to_string(&full).unwrap()).unwrap();
        let reached: Vec<&Value> = v["inferences"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["round"].as_u64().unwrap() >= 1)
            .collect();
        assert!(!reached.is_empty(), "{v}");
        for row in reached.iter().take(4) {
            let set: Vec<String> = row["set"]
                .as_array()
                .unwrap()
                .iter()
                .map(ToString::to_string)
                .collect();
            let one = dir.join("one.json");
            let joined = set.join(",");
            let mut a = args.to_vec();
            a.extend([one.to_str().unwrap(), "--set", joined.as_str()]);
            ok(&a, "");
            let w: Value = serde_json::from_str(&std::fs::read_to_string(&one).unwrap()).unwrap();
            let alone = &w["inferences"][0];
            for key in ["p", "paths", "round", "via", "ml"] {
                assert_eq!(
                    alone[key], row[key],
                    "{key} of {set:?} in {rounds} round(s)"
                );
            }
        }
    }
}

#[test]
fn study_runs_on_mrclam_and_judges_its_claims() {
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/mrclam-dataset7");
    if !data.is_dir() {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    }
    let out = tmp("study");
    ok(
        &[
            "reason",
            "study",
            "--quick",
            "--calculi",
            "double-cross",
            "--max-frames",
            "300",
            "--input",
            data.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    for f in [
        "reason.json",
        "scores.csv",
        "report.md",
        "reliability_double-cross.svg",
        "reliability_double-cross.png",
        "reference_pair_double-cross.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let v: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("reason.json")).unwrap()).unwrap();
    let r = &v["results"][0];
    let inferred = r["hidden"]["inferred"]["fitted"]["error_rate"]
        .as_f64()
        .unwrap();
    let random = r["hidden"]["random"]["error_rate"].as_f64().unwrap();
    assert!(inferred < random, "inference {inferred} vs random {random}");
    // issue 14: the reasoning study is the registry's `reason`; its claims are judged in the
    // report by computed verdicts, its tables written as CSV
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("| claim | thesis | ours | verdict |"),
        "{report}"
    );
    assert!(
        report.contains("inferred hidden sets beat the marginal prior"),
        "{report}"
    );
    let csv = std::fs::read_to_string(out.join("scores.csv")).unwrap();
    assert!(
        csv.starts_with("calculus,part,predictor,n,error_rate,"),
        "{csv}"
    );
    // the hidden sets' inference carries what chance gives calibrated predictions of them
    // (median ≤ 95th percentile, both in [0, 1]); the baselines leave it empty
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (median, p95) = (col("chance_ece_median"), col("chance_ece_95"));
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let inferred = rows
        .iter()
        .find(|r| r[1] == "hidden" && r[2].starts_with("inferred"))
        .unwrap();
    let (m, p): (f64, f64) = (
        inferred[median].parse().unwrap(),
        inferred[p95].parse().unwrap(),
    );
    assert!((0.0..=p).contains(&m) && p <= 1.0, "{csv}");
    let prior = rows
        .iter()
        .find(|r| r[1] == "hidden" && r[2] == "prior")
        .unwrap();
    assert!(prior[median].is_empty(), "{csv}");
    assert!(out.join("check.csv").is_file() && out.join("config.toml").is_file());
}

/// GQR's point algebra laid out as GQR's data directory: `DIR/point.spec` and its tables.
fn gqr_point(dir: &Path) -> PathBuf {
    std::fs::create_dir_all(dir.join("point/calculus")).unwrap();
    std::fs::write(
        dir.join("point/calculus/point.conv"),
        "< :: >\n= :: =\n> :: <\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("point/calculus/point.comp"),
        "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n= : < :: ( < )\n= : = :: ( = )\n\
         = : > :: ( > )\n> : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n",
    )
    .unwrap();
    let spec = dir.join("point.spec");
    std::fs::write(
        &spec,
        "comp_table_file point/calculus/point.comp\nconverse_file point/calculus/point.conv\n\
         identity =\ncalculus_size 3\n",
    )
    .unwrap();
    spec
}

#[test]
fn a_gqr_user_runs_their_calculus_and_csp_files_unchanged() {
    let dir = tmp("gqr");
    let spec = gqr_point(&dir);
    let csp = dir.join("nets.csp");
    std::fs::write(
        &csp,
        "2 # chain\n0 1 ( < )\n1 2 ( < = )\n.\n\n2 # cycle\n0 1 ( < )\n1 2 ( < )\n2 0 ( < )\n.\n",
    )
    .unwrap();
    let run = |args: &[&str]| ok(args, "");
    let json_lines = |args: &[&str]| -> Vec<Value> {
        let out = run(args);
        out.lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    };
    // Path consistency: one JSON line per network, named by its header.
    let lines = json_lines(&[
        "reason",
        "close",
        "--calculus",
        spec.to_str().unwrap(),
        "--input",
        csp.to_str().unwrap(),
    ]);
    assert_eq!(lines.len(), 2, "{lines:?}");
    assert_eq!(
        (lines[0]["name"].as_str(), lines[0]["status"].as_str()),
        (Some("chain"), Some("consistent"))
    );
    assert_eq!(
        lines[0]["constraints"][1],
        serde_json::json!(["0", "2", ["<"]])
    );
    assert_eq!(
        (lines[1]["name"].as_str(), lines[1]["consistent"].as_bool()),
        (Some("cycle"), Some(false))
    );
    // GQR's form out, and read back in (the calculus by name from GQR_DATA_DIR, as GQR does).
    let gqr = std::process::Command::new(env!("CARGO_BIN_EXE_qrm"))
        .env("GQR_DATA_DIR", &dir)
        .args([
            "reason",
            "close",
            "--calculus",
            "point",
            "--input",
            csp.to_str().unwrap(),
            "--output",
            "gqr",
        ])
        .output()
        .unwrap();
    assert!(
        gqr.status.success(),
        "{}",
        String::from_utf8_lossy(&gqr.stderr)
    );
    let gqr = String::from_utf8(gqr.stdout).unwrap();
    assert!(
        gqr.starts_with("2 #chain consistent\n0 1 ( < )\n0 2 ( < )\n1 2 ( < = )\n.\n"),
        "{gqr}"
    );
    // Consistency by search: a scenario, none, or unknown past the budget.
    let lines = json_lines(&[
        "reason",
        "scenario",
        "--calculus",
        spec.to_str().unwrap(),
        "--input",
        csp.to_str().unwrap(),
    ]);
    assert_eq!(lines[0]["status"], "consistent");
    assert_eq!(
        lines[0]["constraints"][2],
        serde_json::json!(["1", "2", ["<"]])
    );
    assert_eq!(lines[1]["status"], "inconsistent");
    let out = run(&[
        "reason",
        "scenario",
        "--calculus",
        spec.to_str().unwrap(),
        "--max-nodes",
        "0",
        "--input",
        csp.to_str().unwrap(),
    ]);
    assert!(
        out.lines()
            .next()
            .unwrap()
            .contains("\"status\":\"unknown\""),
        "{out}"
    );
    // GQR's `-c convex`: the split set `point/calculus/convexalg` beside the spec; a
    // constraint already convex (`1 2 ( < = )`) is not split.
    std::fs::write(
        dir.join("point/calculus/convexalg"),
        "# the convex point relations\n( < )\n( = )\n( > )\n( < = )\n( = > )\n( < = > )\n",
    )
    .unwrap();
    let split = |name: &str| {
        json_lines(&[
            "reason",
            "scenario",
            "--calculus",
            spec.to_str().unwrap(),
            "--split",
            name,
            "--input",
            csp.to_str().unwrap(),
        ])
    };
    let lines = split("convex");
    assert_eq!(lines[0]["status"], "consistent");
    assert_eq!(
        lines[0]["constraints"][2],
        serde_json::json!(["1", "2", ["<", "="]])
    );
    assert_eq!(lines[1]["status"], "inconsistent");
    let by_path = dir.join("point/calculus/convexalg");
    assert_eq!(split(by_path.to_str().unwrap()), lines);
    let e = qrm(
        &[
            "reason",
            "scenario",
            "--calculus",
            spec.to_str().unwrap(),
            "--split",
            "horn",
            "--input",
            csp.to_str().unwrap(),
        ],
        "",
    );
    assert!(!e.status.success());
    let stderr = String::from_utf8_lossy(&e.stderr);
    assert!(
        stderr.contains("split set `horn`") && stderr.contains("hornalg"),
        "{stderr}"
    );
    // The laws of its tables.
    let laws = run(&["reason", "laws", "--calculus", spec.to_str().unwrap()]);
    assert!(
        laws.starts_with("point (3 relations)") && laws.matches(": holds").count() == 4,
        "{laws}"
    );
    // A broken table names its file and line.
    std::fs::write(
        dir.join("point/calculus/point.conv"),
        "< :: >\n= :: =\n> : <\n",
    )
    .unwrap();
    let e = qrm(
        &[
            "reason",
            "close",
            "--calculus",
            spec.to_str().unwrap(),
            "--input",
            csp.to_str().unwrap(),
        ],
        "",
    );
    let err = String::from_utf8_lossy(&e.stderr);
    assert!(
        !e.status.success() && err.contains("point.conv") && err.contains("line 3"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
