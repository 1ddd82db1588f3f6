//! `qrm serge` end to end: a user's beliefs → map.json; the quick study and its report;
//! learning a calculus from a simulated drive and composing it with Algorithm 3.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::Path;

use serde_json::Value;

fn tmp(name: &str) -> std::path::PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn serge_run_writes_the_map_in_the_documented_form() {
    let dir = tmp("serge_run");
    // the exact input form of the issue: Gaussians and a sample set
    let beliefs = r#"{"beliefs": [
        {"mean": [0, 0], "cov": [[0.05, 0], [0, 0.05]]},
        {"mean": [6, 0], "cov": [[0.05, 0.01], [0.01, 0.05]]},
        {"samples": [[6.2, 0.3], [6.1, 0.2], [5.9, 0.4], [6.3, 0.1]]},
        {"mean": [0, 6], "cov": [[0.1, 0], [0, 0.1]]}
    ]}"#;
    let input = dir.join("beliefs.json");
    std::fs::write(&input, beliefs).unwrap();
    let out = dir.join("out");
    let stdout = common::ok(
        &[
            "serge",
            "run",
            "--beliefs",
            input.to_str().unwrap(),
            "--mu",
            "3",
            "--sigma",
            "0",
            "--trials",
            "40",
            "--grid",
            "80",
            "--seed",
            "4",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(stdout.contains("→ 3 regions"), "{stdout}");
    let map: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).unwrap()).unwrap();
    assert_eq!(map["n_regions"], 3);
    // beliefs 1 and 2 sit together; 0 and 3 alone
    let a: Vec<u64> = map["assignment"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_u64().unwrap())
        .collect();
    assert_eq!(a[1], a[2]);
    assert_ne!(a[0], a[1]);
    assert_ne!(a[0], a[3]);
    assert!(map["log_saliency"].as_f64().unwrap() <= 0.0);
    assert!(map["log_saliency"].as_f64().unwrap() > -0.1);
    assert!(out.join("map.svg").is_file() && out.join("map.png").is_file());
}

#[test]
fn serge_run_rejects_bad_input_cleanly() {
    let dir = tmp("serge_bad");
    let cases = [
        (r#"{"beliefs": []}"#, "3", "empty"),
        (
            r#"{"beliefs": [{"mean": [0, 0], "cov": [[1, 1], [1, 1]]}]}"#,
            "1",
            "degenerate",
        ),
        (r#"{"beliefs": [{"mean": [0, 0]}"#, "1", "expected"),
        (
            r#"{"beliefs": [{"mean": [0, 0], "cov": [[1, 0], [0, 1]]}]}"#,
            "2",
            "μ = 2",
        ),
    ];
    for (i, (text, mu, want)) in cases.iter().enumerate() {
        let input = dir.join(format!("b{i}.json"));
        std::fs::write(&input, text).unwrap();
        let out = dir.join(format!("out{i}"));
        let r = common::qrm(
            &[
                "serge",
                "run",
                "--beliefs",
                input.to_str().unwrap(),
                "--mu",
                mu,
                "--out",
                out.to_str().unwrap(),
            ],
            "",
        );
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(!r.status.success());
        assert!(err.contains(want), "case {i}: {err}");
        assert!(!out.exists(), "case {i}: nothing may be written");
    }
}

#[test]
fn quick_study_reproduces_the_qualitative_statements() {
    let dir = tmp("serge_study");
    let out = dir.join("study");
    common::ok(
        &["serge", "study", "--quick", "--out", out.to_str().unwrap()],
        "",
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for line in [
        "well-separated: always \\|R\\| = μ",
        "well-separated: test log likelihood 0",
        "well-separated: no errors",
        "hallway: \\|R\\| falls as σ grows",
        "lab: μ = 55, σ = 0.01 → SRs | 55 | 55 |",
        "a learned calculus classifies as its map",
        "Algorithm 3 is sound",
    ] {
        let row = report
            .lines()
            .find(|l| l.contains(line))
            .unwrap_or_else(|| panic!("{line}"));
        assert!(
            row.ends_with("| **agree** |") || row.ends_with("| **holds** |"),
            "{row}"
        );
    }
    for f in [
        "fig3_7a_n_regions_vs_mu.svg",
        "fig3_7f_error_rate_vs_sigma.png",
        "lab/cv.csv",
        "lab/fig3_9_level1.svg",
        "hallway/calculus.json",
        "hallway/fig3_10_compose.svg",
        "well-separated/summary.csv",
        "well-separated/map_mu20_sigma2.json",
        "hallway/compose_algorithm3.json",
        "config.toml",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // the learned calculus is a qsr-core calculus the CLI composes with Algorithm 3
    let calc = out.join("hallway/calculus.json");
    let show = common::ok(&["calculus", "show", calc.to_str().unwrap()], "");
    assert!(show.contains("hallway-learned"), "{show}");
    let table: Value = serde_json::from_str(&common::ok(
        &[
            "calculus",
            "compose",
            calc.to_str().unwrap(),
            "--method",
            "cells",
            "--json",
        ],
        "",
    ))
    .unwrap();
    assert!(table["states"].as_array().unwrap().len() >= 2);
    // Algorithm 3 refuses a calculus without cells
    let r = common::qrm(&["calculus", "compose", "edc", "--method", "cells"], "");
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("not a learned"));
}

#[test]
fn learn_a_calculus_from_a_simulated_drive() {
    let dir = tmp("serge_learn");
    let sim = dir.join("sim");
    common::ok(
        &[
            "sim",
            "--scenario",
            "hallway",
            "--seed",
            "2",
            "--no-lidar",
            "--out",
            sim.to_str().unwrap(),
        ],
        "",
    );
    let out = dir.join("learned");
    let stdout = common::ok(
        &[
            "serge",
            "learn",
            "--input",
            sim.join("observations.csv").to_str().unwrap(),
            "--mu",
            "6",
            "--max-triplets",
            "12",
            "--samples",
            "500",
            "--grid",
            "32",
            "--trials",
            "200",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(stdout.contains("12 triplets"), "{stdout}");
    let spec = out.join("calculus.json");
    let classify = common::ok(
        &["calculus", "classify", spec.to_str().unwrap()],
        "0 0 0 1 -2 0.5\n0 0 0 1 40 -3\n",
    );
    assert_eq!(classify.lines().count(), 2, "{classify}");
    let compose: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("compose.json")).unwrap()).unwrap();
    assert_eq!(compose["method"], "algorithm-3-intervals");
}

/// Regression (issue 17): `--window x0,x1,y0,y1` as documented failed ("4 values required, 1
/// was provided"), and the space form refused any negative coordinate — so no window left of
/// or below the origin could be given. Both forms work now; a wrong count is a clear error.
#[test]
fn a_window_with_negative_coordinates_is_accepted() {
    let dir = tmp("serge_window");
    let input = dir.join("beliefs.json");
    std::fs::write(
        &input,
        r#"{"beliefs": [{"mean": [-4, -3], "cov": [[0.1, 0], [0, 0.1]]},
                        {"mean": [3, 2], "cov": [[0.1, 0], [0, 0.1]]}]}"#,
    )
    .unwrap();
    for window in [
        vec!["--window", "-10,10,-8,8"],
        vec!["--window=-10,10,-8,8"],
    ] {
        let out = dir.join("out");
        let mut args = vec![
            "serge",
            "run",
            "--beliefs",
            input.to_str().unwrap(),
            "--mu",
            "2",
            "--trials",
            "4",
            "--grid",
            "40",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend(window.iter().copied());
        common::ok(&args, "");
        let map: Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).unwrap()).unwrap();
        assert_eq!(map["n_regions"], 2, "{window:?}");
    }
    let o = common::qrm(
        &[
            "serge",
            "run",
            "--beliefs",
            input.to_str().unwrap(),
            "--mu",
            "2",
            "--window",
            "-10,10,-8",
            "--out",
            dir.join("bad").to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("four numbers"));
}
