//! `qrm pqrm prob`, `qrm map`, `qrm pqrm study --quick` and `qrm pqrm real` as a user runs them.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use common::{ok, qrm};

use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("qrm-pqrm-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn prob_gives_the_single_observation_distribution() {
    let line = r#"{"points": [[0,0],[0,10],[-1,5]], "cov": [[0,0,0],[0,0,0],[1,0,1]]}"#;
    let out = ok(
        &[
            "pqrm",
            "prob",
            "--calculus",
            "left-right",
            "--samples",
            "40000",
            "--seed",
            "3",
        ],
        &format!("{line}\n{line}\n"),
    );
    let lines: Vec<serde_json::Value> = out
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines.len(), 2);
    assert_eq!(lines[0]["states"], serde_json::json!(["left", "right"]));
    let p_left = lines[0]["p"][0].as_f64().unwrap();
    // Φ(1) = 0.8413; sampling error ≈ 0.002.
    assert!((p_left - 0.8413).abs() < 0.01, "{p_left}");
    assert_eq!(lines[0], lines[1], "same seed, same answer");
    // No floor by default: a certain configuration gives exactly 1.
    let sure = r#"{"points": [[0,0],[0,1],[-3,0.5]], "cov": [[0,0,0],[0,0,0],[0,0,0]]}"#;
    let v: serde_json::Value = serde_json::from_str(
        ok(
            &["pqrm", "prob", "--calculus", "edc", "--samples", "100"],
            sure,
        )
        .trim(),
    )
    .unwrap();
    let p: Vec<f64> = v["p"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(p[4], 1.0, "state 5 (left, upper middle, far)");
    // Bad input: line number in the message, non-zero exit, no partial output.
    let out = qrm(
        &["pqrm", "prob", "--calculus", "edc"],
        &format!(
            "{sure}\n{{\"points\": [[0,0],[0,0],[1,1]], \"cov\": [[0,0,0],[0,0,0],[0,0,0]]}}\n"
        ),
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("line 2"));
    assert!(out.stdout.is_empty());
    let out = qrm(
        &["pqrm", "prob", "--calculus", "edc"],
        "{\"points\": [[0,0],[0,1],[1,1]], \"cov\": [[1,2,1],[0,0,0],[0,0,0]]}\n",
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("positive semi-definite"));
}

fn write_csv_dataset(dir: &Path) -> (PathBuf, PathBuf) {
    // Four landmarks seen from three poses (robot frame = world frame here), σ = 0.2 m.
    let lm = [(1, 0.0, 0.0), (2, 0.3, 4.0), (3, 3.1, 2.6), (4, -2.2, 1.3)];
    let mut csv = String::from("t,robot,landmark,x,y,cxx,cxy,cyy\n");
    for t in 0..3 {
        for (id, x, y) in lm {
            let jitter = 0.05 * f64::from(t);
            csv.push_str(&format!(
                "{t},0,{id},{},{},0.04,0,0.04\n",
                x + jitter,
                y - jitter
            ));
        }
    }
    let mut truth = String::from("landmark,x,y\n");
    for (id, x, y) in lm {
        truth.push_str(&format!("{id},{x},{y}\n"));
    }
    std::fs::write(dir.join("obs.csv"), csv).unwrap();
    std::fs::write(dir.join("truth.csv"), truth).unwrap();
    (dir.join("obs.csv"), dir.join("truth.csv"))
}

#[test]
fn map_builds_saves_and_scores_a_pqrm() {
    let dir = tmp("map");
    let (obs, truth) = write_csv_dataset(&dir);
    let out = dir.join("out");
    // `qrm map` of the CSV with EDC into `out`, and `extra` flags
    let map_csv = |out: &Path, extra: &[&str]| {
        let mut args = vec![
            "map",
            "--format",
            "csv",
            "--input",
            obs.to_str().unwrap(),
            "--calculus",
            "edc",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        qrm(&args, "")
    };
    let o = map_csv(
        &out,
        &["--truth", truth.to_str().unwrap(), "--samples", "300"],
    );
    assert!(o.status.success(), "{o:?}");
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["n_sets"], 24, "4 landmarks: 4·3·2 ordered triplets");
    for key in [
        "mean_entropy",
        "error_rate",
        "mean_neighbor_distance",
        "p_ml_mean",
    ] {
        assert!(s[key].is_number(), "{key} in {s}");
    }
    assert_eq!(s["top_n_error"].as_array().unwrap().len(), 20);
    assert!(s["error_rate"].as_f64().unwrap() < 0.2);
    assert!(out.join("map.json").exists());
    // Three frames cannot measure the error they share: `shared:auto` falls back to N = 4,
    // says so on stderr and in the summary.
    let auto = dir.join("auto");
    let o = map_csv(&auto, &["--evidence", "shared:auto", "--samples", "100"]);
    assert!(o.status.success(), "{o:?}");
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot measure N"));
    let a: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(auto.join("summary.json")).unwrap()).unwrap();
    assert_eq!(a["evidence"], "shared:4", "{a}");
    assert!(
        a["evidence_choice"]
            .as_str()
            .unwrap()
            .contains("measured: false"),
        "{a}"
    );
    // A malformed file names its line.
    std::fs::write(
        dir.join("bad.csv"),
        "t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,0,0,1,0,1\n0,0,2,zero,0,1,0,1\n",
    )
    .unwrap();
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            dir.join("bad.csv").to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("bad.csv:3"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let o = qrm(
        &[
            "map",
            "--format",
            "xml",
            "--input",
            obs.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    // a closed set of names: clap refuses the value and lists the ones there are
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("invalid value 'xml'") && err.contains("csv, mrclam, g2o, mcap"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn mrclam() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/mrclam-dataset7");
    d.is_dir().then_some(d)
}

#[test]
fn map_reads_mrclam_with_its_ground_truth() {
    let Some(data) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let out = tmp("mrclam");
    ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            data.to_str().unwrap(),
            "--calculus",
            "double-cross",
            "--samples",
            "60",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(s["n_sets"].as_u64().unwrap() > 500);
    assert!(
        s["error_rate"].as_f64().unwrap() < 5.0 / 6.0,
        "better than a random guess: {s}"
    );
    assert_eq!(s["top_n_error"].as_array().unwrap().len(), 6);
    // A layout map (the default here) also says which N a filter map of the recording would
    // be read under: σ_frame² / σ_shared², as `--evidence shared:N`. Dataset 7's frames share
    // little (the constant N = 4 leaves its filter map underconfident: docs/calibration.md).
    assert_eq!(s["evidence"], "layout", "{s}");
    let shared = &s["layout"]["shared_error"];
    let ratio = (shared["sigma_frame"].as_f64().unwrap()
        / shared["sigma_shared"].as_f64().unwrap())
    .powi(2);
    let said = s["layout"]["filter_evidence"].as_str().unwrap();
    let n: f64 = said.strip_prefix("shared:").unwrap().parse().unwrap();
    assert!(
        (n - ratio).abs() < 1e-9 * ratio && n > 4.0,
        "{said} against {ratio}"
    );
    std::fs::remove_dir_all(&out).ok();
}

/// Regression (issue 17): sizes that overflowed an allocation (`--samples 2^64−1`: capacity
/// overflow, exit 101) or ran away (`--trials 10^9`, `--landmarks 100000`) are refused up
/// front with a typed error and the estimate, before anything is written.
#[test]
fn impossible_sizes_are_refused_before_any_work() {
    let out = tmp("sizes");
    let max = u64::MAX.to_string();
    let line = r#"{"points": [[0,0],[0,10],[-1,5]], "cov": [[0,0,0],[0,0,0],[1,0,1]]}"#;
    let o = qrm(
        &["pqrm", "prob", "--calculus", "edc", "--samples", &max],
        line,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("GiB per landmark"));
    let study_out = out.join("study");
    for flags in [
        vec!["--samples", max.as_str()],
        vec!["--trials", "1000000000"],
        vec!["--landmarks", "100000"],
    ] {
        let mut args = vec![
            "pqrm",
            "study",
            "--quick",
            "--out",
            study_out.to_str().unwrap(),
        ];
        args.extend(flags.iter().copied());
        let start = std::time::Instant::now();
        let o = qrm(&args, "");
        assert_eq!(o.status.code(), Some(1), "{flags:?}");
        assert!(
            start.elapsed().as_secs() < 20,
            "{flags:?} was not refused up front"
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("samples") || err.contains("triplet-samples") || err.contains("landmarks"),
            "{err}"
        );
    }
    let obs = out.join("obs.csv");
    std::fs::write(&obs, "t,robot,landmark,x,y,cxx,cxy,cyy\n0,0,1,0,0,1,0,1\n").unwrap();
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            obs.to_str().unwrap(),
            "--calculus",
            "edc",
            "--samples",
            &max,
            "--out",
            out.join("m").to_str().unwrap(),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(!out.join("m").join("map.json").exists());
    std::fs::remove_dir_all(&out).ok();
}

/// Regression (issue 17): every calculus error inside the mapper was reported as "landmarks
/// … coincide" (`pqrm prob --calculus star-4` → "landmarks [0, 1, 2] coincide: arity
/// mismatch"). The real cause is named now.
#[test]
fn a_calculus_of_the_wrong_kind_is_not_called_coincident_landmarks() {
    let line = r#"{"points": [[0,0],[0,10],[-1,5]], "cov": [[0,0,0],[0,0,0],[1,0,1]]}"#;
    let o = qrm(
        &["pqrm", "prob", "--calculus", "star-4", "--samples", "10"],
        line,
    );
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !err.contains("coincide") && err.contains("not ternary"),
        "{err}"
    );
}

/// Regression (issue 17): `--calculi` with a spec file indexed the baselines by the path
/// instead of the calculus name and panicked after writing most outputs.
#[test]
fn study_with_a_spec_file_calculus_does_not_panic() {
    let out = tmp("study-spec");
    let spec = out.join("mine.toml");
    // a name with a comma and a quote: joined by hand into levels.csv it shifted every
    // column after it (issue 19); the csv crate quotes it
    let text = ok(&["calculus", "spec", "double-cross"], "").replacen(
        "name = \"double-cross\"",
        "name = 'double-cross, \"mine\"'",
        1,
    );
    assert!(text.contains("mine"), "the spec names its calculus: {text}");
    std::fs::write(&spec, text).unwrap();
    let calculi = format!("edc,{}", spec.display());
    ok(
        &[
            "pqrm",
            "study",
            "--quick",
            "--calculi",
            &calculi,
            "--trials",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("Fig 2.11a"));
    assert!(out.join("fig2_11a_error_rate.svg").exists());
    let mut levels = csv::Reader::from_path(out.join("levels.csv")).unwrap();
    let width = levels.headers().unwrap().len();
    let rows: Vec<csv::StringRecord> = levels.records().map(Result::unwrap).collect();
    assert!(rows.iter().all(|r| r.len() == width));
    assert!(
        rows.iter().any(|r| &r[0] == "double-cross, \"mine\""),
        "{:?}",
        rows.iter().map(|r| r[0].to_owned()).collect::<Vec<_>>()
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_quick_study_writes_data_plots_and_a_report() {
    let out = tmp("study");
    ok(
        &[
            "pqrm",
            "study",
            "--quick",
            "--seed",
            "2",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    for f in [
        "levels.csv",
        "baselines.csv",
        "wrong_triplets.csv",
        "study.json",
        "report.md",
        "fig2_6_neighbor_distance.svg",
        "fig2_7_edc_entropy.png",
        "fig2_8a_wrong_triplets.svg",
        "fig2_9b_confusion.png",
        "fig2_10a_entropy.svg",
        "fig2_10b_normalized_entropy.png",
        "fig2_11a_error_rate.svg",
        "fig2_11b_p_ml.png",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let levels = std::fs::read_to_string(out.join("levels.csv")).unwrap();
    assert_eq!(
        levels.lines().count(),
        1 + 6 * 5,
        "six calculi × five levels"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| Fig 2.6") && report.contains("| Fig 2.11a"));
    let png = std::fs::read(out.join("fig2_7_edc_entropy.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn the_real_data_study_runs_on_a_subset() {
    let Some(data) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    // the default (a layout map), then the filter, whose τ the report also fits
    for evidence in ["layout", "shared"] {
        real_study_on_a_subset(&data, evidence);
    }
}

fn real_study_on_a_subset(data: &Path, evidence: &str) {
    let out = tmp(&format!("real-{evidence}"));
    let mut args = vec![
        "pqrm",
        "real",
        "--input",
        data.to_str().unwrap(),
        "--max-frames",
        "120",
        "--samples",
        "80",
        "--out",
        out.to_str().unwrap(),
    ];
    if evidence != "layout" {
        args.extend(["--evidence", evidence]);
    }
    ok(&args, "");
    for f in [
        "real.json",
        "real.csv",
        "report.md",
        "fig2_14_entropy_histogram.svg",
        "fig2_15_neighbor_distance.png",
        "fig2_16_top_n_error.svg",
    ] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("real.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + 18,
        "six calculi × (PQRM, majority vote, per-frame)"
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    for part in [
        "# PQRM on mrclam-dataset7",
        "| calculus | PQRM error ≤ majority vote |",
        "Reliability diagram",
        "## Many robots, one map",
    ] {
        assert!(report.contains(part), "report.md lacks {part:?}");
    }
    let sweep = std::fs::read_to_string(out.join("sensor_models.csv")).unwrap();
    assert_eq!(
        sweep.lines().count(),
        1 + 6 * 6,
        "six variants × six calculi"
    );
    assert!(sweep.contains("\nstudent-t:4,0.3,edc,"), "{sweep}");
    assert!(report.contains(&format!(
        "Evidence model: **{}",
        if evidence == "layout" {
            "layout"
        } else {
            "shared error"
        }
    )));
    // the robots' maps are compared either way (under the layout model, the filter's)
    let robots = std::fs::read_to_string(out.join("robots.csv")).unwrap();
    assert!(
        robots.lines().any(|l| l.starts_with("edc,merged,")),
        "{robots}"
    );
    if evidence == "layout" {
        // a layout map has no frames to temper: no τ fitted, and the report says why
        assert!(!out.join("temper.csv").exists());
        assert!(report.contains("layout model reads no frame"), "{report}");
        std::fs::remove_dir_all(&out).ok();
        return;
    }
    let temper = std::fs::read_to_string(out.join("temper.csv")).unwrap();
    assert_eq!(temper.lines().count(), 1 + 6 * 15, "six calculi × 15 τ");
    assert_eq!(
        temper.lines().filter(|l| l.ends_with(",true")).count(),
        6,
        "one chosen τ per calculus"
    );
    assert!(report.contains("## Tempering chosen from the data"));
    assert!(out.join("temper_fit.svg").exists());
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn per_robot_maps_merge_into_the_pooled_map() {
    let Some(data) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let out = tmp("robots");
    let s = |p: &Path| p.to_str().unwrap().to_owned();
    let d = s(&data);
    let per = out.join("per");
    let summary = ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--samples",
            "300",
            "--per-robot",
            // merging is the filter's: a layout map merges with nothing; `shared:auto` reads
            // every robot's map with the N of the whole recording's layout, so they merge
            "--evidence",
            "shared:auto",
            "--out",
            &s(&per),
        ],
        "",
    );
    let per_robot: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(per_robot.as_object().unwrap().len(), 5, "{summary}");
    let pooled = out.join("pooled");
    ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--samples",
            "300",
            "--evidence",
            "shared:auto",
            "--out",
            &s(&pooled),
        ],
        "",
    );
    let maps: Vec<String> = (1..=5)
        .map(|r| s(&per.join(format!("robot{r}/map.json"))))
        .collect();
    let merged = out.join("merged.json");
    let mut args = vec!["pqrm", "merge"];
    args.extend(maps.iter().map(String::as_str));
    let merged_s = s(&merged);
    args.extend(["--truth", &d, "--out", &merged_s]);
    let m: serde_json::Value = serde_json::from_str(&ok(&args, "")).unwrap();
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(pooled.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(m["n_sets"], p["n_sets"]);
    // one N for all: the recording's, σ_frame² / σ_shared² of its layout
    let evidence = p["evidence"].as_str().unwrap();
    let n: f64 = evidence.strip_prefix("shared:").unwrap().parse().unwrap();
    assert!(n.is_finite() && n > 1.0, "{evidence}");
    assert!(
        p["evidence_choice"]
            .as_str()
            .unwrap()
            .starts_with("shared:auto: the filter"),
        "{p}"
    );
    for r in 1..=5 {
        assert_eq!(per_robot[format!("robot{r}")]["evidence"], evidence);
    }
    let (em, ep) = (
        m["error_rate"].as_f64().unwrap(),
        p["error_rate"].as_f64().unwrap(),
    );
    assert!((em - ep).abs() < 0.02, "merged {em} vs pooled {ep}");
    // The merged map is a map: it loads and can be merged again.
    ok(&["reason", "check", &merged_s], "");
    // A layout map (the default) is of a whole recording: merging it is refused by name.
    let layout = out.join("layout");
    ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--out",
            &s(&layout),
        ],
        "",
    );
    let layout_map = s(&layout.join("map.json"));
    let o = qrm(
        &[
            "pqrm",
            "merge",
            &layout_map,
            &merged_s,
            "--out",
            &s(&out.join("never.json")),
        ],
        "",
    );
    assert!(!o.status.success());
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("layout map"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert!(!out.join("never.json").exists());
    // --robots keeps only those robots' scans.
    let two = ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--samples",
            "100",
            "--robots",
            "1,2",
            "--out",
            &s(&out.join("two")),
        ],
        "",
    );
    assert!(two.contains("\"robots\": [\n    1,\n    2\n  ]"), "{two}");
    let o = qrm(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--robots",
            "9",
            "--out",
            &s(&out.join("nine")),
        ],
        "",
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("robot 9 has no scans"));
    // Maps of different calculi do not merge.
    let lr = out.join("lr");
    ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            &d,
            "--samples",
            "100",
            "--calculus",
            "left-right",
            "--robots",
            "1",
            "--out",
            &s(&lr),
        ],
        "",
    );
    let o = qrm(
        &[
            "pqrm",
            "merge",
            &maps[0],
            &s(&lr.join("map.json")),
            "--out",
            &s(&out.join("x.json")),
        ],
        "",
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("cannot merge"));
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn calibrate_fits_the_noise_without_truth_and_map_uses_it_with_noise_auto() {
    let Some(data) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let out = tmp("calibrate");
    let d = data.to_str().unwrap();
    let cal = out.join("cal");
    let text = ok(
        &[
            "pqrm",
            "calibrate",
            "--format",
            "mrclam",
            "--input",
            d,
            "--out",
            cal.to_str().unwrap(),
        ],
        "",
    );
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let (sr, sb) = (
        v["fit"]["sigma_range"].as_f64().unwrap(),
        v["fit"]["sigma_bearing"].as_f64().unwrap(),
    );
    // MRCLAM's README: median absolute errors of ~0.1 m and ~0.006 rad, i.e. σ of order
    // 0.15 m and 0.009 rad for a Gaussian; the fit must land in that range, not at 0 or ∞.
    assert!(
        (0.02..0.3).contains(&sr) && (0.0005..0.03).contains(&sb),
        "{text}"
    );
    assert!(cal.join("residuals.svg").exists() && cal.join("calibration.json").exists());
    let m = ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            d,
            "--noise",
            "auto",
            "--samples",
            "200",
            "--out",
            out.join("m").to_str().unwrap(),
        ],
        "",
    );
    let m: serde_json::Value = serde_json::from_str(&m).unwrap();
    assert_eq!(m["noise_fit"]["sigma_range"].as_f64().unwrap(), sr);
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            d,
            "--noise",
            "auto",
            "--out",
            out.join("x").to_str().unwrap(),
        ],
        "",
    );
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("--noise auto fits a range-bearing sensor")
    );
    std::fs::remove_dir_all(&out).ok();
}

#[test]
fn gating_drops_a_few_detections_and_says_how_many() {
    let Some(data) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let out = tmp("gate");
    let s = ok(
        &[
            "map",
            "--format",
            "mrclam",
            "--input",
            data.to_str().unwrap(),
            "--noise",
            "auto",
            "--gate",
            "--samples",
            "100",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    let v: serde_json::Value = serde_json::from_str(&s).unwrap();
    let (g, of) = (
        v["gated"]["detections"].as_u64().unwrap(),
        v["gated"]["of"].as_u64().unwrap(),
    );
    assert!(g > 0 && (g as f64) < 0.05 * of as f64, "{g} of {of}");
    // issue 35: gating is the default where the noise is fitted (every fold of leaving one
    // MRCLAM recording out chose it); `--gate false` keeps every detection
    let map = |extra: &[&str]| -> serde_json::Value {
        let mut args = vec![
            "map",
            "--format",
            "mrclam",
            "--input",
            data.to_str().unwrap(),
            "--samples",
            "100",
            "--out",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        serde_json::from_str(&ok(&args, "")).unwrap()
    };
    assert_eq!(map(&[])["gated"], v["gated"]);
    assert!(map(&["--gate", "false"]).get("gated").is_none());
    assert!(map(&["--noise", "fixed"]).get("gated").is_none());
    std::fs::remove_dir_all(&out).ok();
}

/// `n` distinct frames of six almost collinear landmarks (a deterministic jitter of ~0.3 m), each written
/// `repeat` times in a row: a robot that stands still.
fn repeated_frames_csv(path: &Path, n: usize, repeat: usize) {
    // nearly on a line, so that left-right is in doubt frame by frame
    let lm = [
        (1, 0.0, 0.0),
        (2, 1.0, 0.1),
        (3, 2.0, -0.15),
        (4, 3.0, 0.05),
        (5, 4.0, -0.1),
        (6, 5.0, 0.2),
    ];
    let mut csv = String::from("t,robot,landmark,x,y,cxx,cxy,cyy\n");
    let mut t = 0;
    for f in 0..n {
        for _ in 0..repeat {
            for (k, (id, x, y)) in lm.iter().enumerate() {
                let u = (f * 7 + k) as f64;
                let (dx, dy) = (0.3 * (u * 12.9898).sin(), 0.3 * (u * 78.233).cos());
                csv.push_str(&format!("{t},0,{id},{},{},0.09,0,0.09\n", x + dx, y + dy));
            }
            t += 1;
        }
    }
    std::fs::write(path, csv).unwrap();
}

#[test]
fn map_chooses_tau_from_the_data_and_sees_through_repeated_frames() {
    let dir = tmp("temper");
    let chosen = |repeat: usize, evidence: &str| {
        let input = dir.join(format!("x{repeat}.csv"));
        repeated_frames_csv(&input, 30, repeat);
        let out = dir.join(format!("out{repeat}-{evidence}"));
        let o = qrm(
            &[
                "map",
                "--format",
                "csv",
                "--input",
                input.to_str().unwrap(),
                "--calculus",
                "left-right",
                "--samples",
                "200",
                "--temper",
                "auto",
                "--evidence",
                evidence,
                "--out",
                out.to_str().unwrap(),
            ],
            "",
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(
            String::from_utf8_lossy(&o.stderr).contains("chosen from held-out frames"),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        let tau = s["temper_fit"]["chosen"].as_f64().unwrap();
        assert_eq!(
            s["temper"].as_f64().unwrap(),
            tau,
            "the map is made with the chosen τ"
        );
        let map: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("map.json")).unwrap()).unwrap();
        assert_eq!(
            map["config"]["temper"].as_f64(),
            Some(tau),
            "map.json says how it was made"
        );
        tau
    };
    // Under eq. 2.10 every copy counts: τ must fall by about the repeat.
    let (once, five) = (chosen(1, "independent"), chosen(5, "independent"));
    assert!(
        five * 2.8 <= once,
        "τ {five} for each frame five times vs {once} for each once"
    );
    // Under the shared-error model (the default) the model already discounts a set's n
    // frames, and τ is fitted on top of it (issue 35): it must not repeat eq. 2.10's
    // correction (before the fix it was the same τ as above).
    let five_shared = chosen(5, "shared");
    assert!(
        five_shared >= 2.0 * five,
        "τ {five_shared} on top of the shared model vs {five} under eq. 2.10: corrected twice"
    );
    // Too few frames to hold any out: a typed error, nothing written.
    let input = dir.join("short.csv");
    repeated_frames_csv(&input, 3, 1);
    let out = dir.join("short-out");
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            input.to_str().unwrap(),
            "--temper",
            "auto",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--temper auto") && err.contains("at least 5 frames"),
        "{err}"
    );
    assert!(!out.exists());
    // a layout map has no frames to temper: refused by name, nothing written (the default,
    // `auto`, takes the filter when τ is asked for: above)
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            input.to_str().unwrap(),
            "--evidence",
            "layout",
            "--temper",
            "auto",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--temper") && err.contains("layout"), "{err}");
    assert!(!out.exists());
    let o = qrm(
        &[
            "map",
            "--format",
            "csv",
            "--input",
            input.to_str().unwrap(),
            "--temper",
            "1.5",
            "--out",
            out.to_str().unwrap(),
        ],
        "",
    );
    assert!(String::from_utf8_lossy(&o.stderr).contains("temper must be in (0, 1]"));
    std::fs::remove_dir_all(&dir).ok();
}

/// A recording of one scan that sees `n` landmarks on a jittered grid, σ = 0.3 m.
fn one_scan_csv(path: &Path, n: usize) {
    let mut csv = String::from("t,robot,landmark,x,y,cxx,cxy,cyy\n");
    for i in 0..n {
        let (x, y) = (
            (i % 9) as f64 * 4.0,
            (i / 9) as f64 * 4.0 + 0.37 * (i % 3) as f64,
        );
        csv.push_str(&format!("0,1,{i},{x},{y},0.09,0,0.09\n"));
    }
    std::fs::write(path, csv).unwrap();
}

#[test]
fn large_recordings_record_canonical_orderings_and_say_so() {
    let dir = tmp("orderings");
    let rec = dir.join("many.csv");
    // 66 landmarks could give 66·65·64 = 274,560 ordered sets: above the auto threshold.
    one_scan_csv(&rec, 66);
    let map = |orderings: &str, out: &Path| {
        let o = qrm(
            &[
                "map",
                "--format",
                "csv",
                "--input",
                rec.to_str().unwrap(),
                "--samples",
                "20",
                "--orderings",
                orderings,
                "--out",
                out.to_str().unwrap(),
            ],
            "",
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let s: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap())
                .unwrap();
        (s, String::from_utf8_lossy(&o.stderr).into_owned())
    };
    let (s, stderr) = map("auto", &dir.join("auto"));
    assert_eq!(s["orderings"], "canonical", "{s}");
    assert_eq!(
        s["n_sets"],
        66 * 65 * 64 / 6,
        "one set per unordered triplet"
    );
    assert!(
        stderr.contains("274560 ordered landmark sets") && stderr.contains("--orderings all"),
        "the choice is said: {stderr}"
    );
    // Asked for explicitly, all six orderings are recorded, and nothing is noted.
    let (s, stderr) = map("all", &dir.join("all"));
    assert_eq!(s["orderings"], "all");
    assert_eq!(s["n_sets"], 66 * 65 * 64);
    assert!(!stderr.contains("note:"), "{stderr}");
    // Small recordings keep the thesis's six orderings under auto.
    one_scan_csv(&rec, 12);
    let (s, _) = map("auto", &dir.join("small"));
    assert_eq!(s["orderings"], "all");
    assert_eq!(s["n_sets"], 12 * 11 * 10);
    std::fs::remove_dir_all(&dir).ok();
}

/// `qrm pqrm real --input A --input B`: one `recordings.csv` row per recording and calculus,
/// a reliability diagram each, the evidence model named in the report; a bad `--evidence`
/// is refused by name before any work.
#[test]
fn the_real_data_study_scores_every_recording_given() {
    let Some(seven) = mrclam() else {
        eprintln!("SKIPPED: shared/data/mrclam-dataset7 not found");
        return;
    };
    let two = seven.with_file_name("mrclam-dataset2");
    if !two.is_dir() {
        eprintln!("SKIPPED: shared/data/mrclam-dataset2 not found");
        return;
    }
    let out = tmp("real-recordings");
    let base = [
        "pqrm",
        "real",
        "--input",
        seven.to_str().unwrap(),
        "--input",
        two.to_str().unwrap(),
        "--max-frames",
        "60",
        "--samples",
        "40",
        "--out",
        out.to_str().unwrap(),
    ];
    let bad = qrm(&[&base[..], &["--evidence", "shared:-2"]].concat(), "");
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(
        err.contains("--evidence") && err.contains("shared:-2"),
        "{err}"
    );
    assert!(
        !out.join("report.md").exists() && !out.join("recordings.csv").exists(),
        "nothing written for a refused flag"
    );
    ok(&[&base[..], &["--evidence", "shared:inf"]].concat(), "");
    let csv = std::fs::read_to_string(out.join("recordings.csv")).unwrap();
    assert_eq!(
        csv.lines().count(),
        1 + 2 * 6,
        "two recordings × six calculi:\n{csv}"
    );
    assert!(csv.lines().any(|l| l.starts_with("mrclam-dataset7,edc,")));
    assert!(csv.lines().any(|l| l.starts_with("mrclam-dataset2,edc,")));
    for f in ["reliability_1.svg", "reliability_2.png"] {
        assert!(out.join(f).exists(), "{f} missing");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("Evidence model: **shared error** worth inf"),
        "report"
    );
    assert!(report.contains("Every recording: log loss below the smoothed vote's"));
    // what chance gives a calibrated map of the same triplets, per row and in a verdict
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    for col in ["chance_ece_95", "chance_gap_95", "chance_pass"] {
        let at = header.iter().position(|h| *h == col).expect(col);
        for line in csv.lines().skip(1) {
            let v: f64 = line.split(',').nth(at).unwrap().parse().unwrap();
            assert!((0.0..=1.0).contains(&v), "{col} = {v} in {line}");
        }
    }
    assert!(report.contains("Every recording: ECE within what chance gives a calibrated map"));
    assert!(report.contains("passes all 12 rows with probability"));
    // the survey against the robots: every row splits its scored sets in two
    let survey = std::fs::read_to_string(out.join("survey.csv")).unwrap();
    assert_eq!(survey.lines().count(), 1 + 2 * 6, "{survey}");
    let head: Vec<&str> = survey.lines().next().unwrap().split(',').collect();
    let col = |k: &str| head.iter().position(|h| *h == k).expect(k);
    for line in survey.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let n = |k: &str| f[col(k)].parse::<usize>().unwrap();
        assert!(
            n("pairs_seen") > 0 && n("pairs_off") <= n("pairs_seen"),
            "{line}"
        );
        assert!(n("sets_agreed") + n("sets_disputed") > 0, "{line}");
    }
    assert!(report.contains("The survey against the robots"));
    std::fs::remove_dir_all(&out).ok();
}
