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
            "trial,value,schedule,robot,pairs,no_path,failures,failure_rate,thesis_failure_rate,mean_length,over_prop2_bound,over_prop2_bound_trajectory"
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
    // 9 main rows, the 4 occlusion sizes under 3 further schedules, and R' = 0.9 R with the
    // robot's errors removed in 5 ways (the default robot reports nothing false)
    assert_eq!(all.len(), 26);
    let ablations: Vec<&str> = all
        .iter()
        .filter(|r| r[3] != "full")
        .map(|r| r[3].as_str())
        .collect();
    assert_eq!(
        ablations,
        [
            "exact",
            "without-misses",
            "without-detection-noise",
            "without-motion-noise",
            "motion-only"
        ]
    );
    let rows: Vec<Vec<String>> = all
        .iter()
        .filter(|r| r[2] == "continuous, 1 fallback" && r[3] == "full")
        .map(|r| {
            let mut r = r.clone();
            r.remove(3);
            r.remove(2);
            r
        })
        .collect();
    assert_eq!(rows.len(), 9);
    // issue 18: the occlusion study can fail (sensing only at stops, no fallback circle)
    let sparse: usize = all
        .iter()
        .filter(|r| r[2] == "stops every 30°, 0 fallbacks")
        .map(|r| r[6].parse::<usize>().unwrap())
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
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("invalid value 'nope'") && err.contains("all, sensor-range, occlusion"),
        "{err}"
    );
}

#[test]
fn the_demo_maps_learns_navigates_and_logs() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("demo");
    let _ = std::fs::remove_dir_all(&out);
    let t0 = std::time::Instant::now();
    let stdout = common::ok(&["demo", "--out", out.to_str().unwrap()], "");
    let seconds = t0.elapsed().as_secs_f64();
    assert!(stdout.contains("SERGE learned a"), "{stdout}");
    assert!(stdout.contains("reached"), "{stdout}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["success"], true);
    // issue 18: the demo crosses the site — several transitions, not the nearest landmark
    let plan_len = summary["plan_len"].as_u64().unwrap();
    assert!(plan_len >= 3, "|P| = {plan_len}: {stdout}");
    assert_eq!(
        summary["plan"].as_array().unwrap().len() as u64,
        plan_len + 1
    );
    assert!(
        summary["run_rule"]
            .as_str()
            .unwrap()
            .contains("longest plan")
    );
    assert!(
        summary["trajectory_length"].as_f64().unwrap() <= summary["prop2_bound"].as_f64().unwrap()
    );
    // the terminal story is short and says where the files are
    assert!(stdout.lines().count() <= 4, "{stdout}");
    assert!(
        stdout.contains("demo.png") && stdout.contains("run.mcap"),
        "{stdout}"
    );
    assert!(seconds < 60.0, "{seconds} s");
    // issue 14: the demo is the `demo` study; the alias writes its report and config too
    for f in [
        "run.mcap",
        "demo.svg",
        "demo.png",
        "learned_calculus.json",
        "report.md",
        "config.toml",
        "run.csv",
        "transitions.csv",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    // the picture has a legend naming what it draws, and the learned calculus's panel
    let svg = std::fs::read_to_string(out.join("demo.svg")).unwrap();
    for label in [
        "start",
        "goal landmark",
        "plan: map elements",
        "searching for a link",
        "trajectory",
        "Learned calculus",
    ] {
        assert!(svg.contains(label), "demo.svg lacks {label:?}");
    }
    foxglove_layout_names_only_logged_topics(&out.join("run.mcap"));
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
    // the report's tables as CSV (no field of these holds a comma)
    let table = |name: &str| -> Vec<std::collections::BTreeMap<String, String>> {
        let text = std::fs::read_to_string(out.join(format!("{name}.csv"))).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().unwrap().split(',').map(String::from).collect();
        lines
            .map(|l| {
                header
                    .iter()
                    .cloned()
                    .zip(l.split(',').map(String::from))
                    .collect()
            })
            .collect()
    };
    let num = |row: &std::collections::BTreeMap<String, String>, key: &str| -> f64 {
        row[key]
            .parse()
            .unwrap_or_else(|_| panic!("{key}: {row:?}"))
    };
    let variants = table("variants");
    assert_eq!(variants.len(), 1 + 4, "the thesis's row and 4 variants");
    assert_eq!(variants[0]["variant"], "thesis (in vivo)");
    for v in &variants {
        let rate = num(v, "success_rate");
        assert!((0.0..=1.0).contains(&rate), "{v:?}");
    }
    let worlds = table("maps");
    assert_eq!(worlds.len(), 2);
    assert_eq!(worlds[1]["seed"], "2", "world seeds follow --seed");
    for w in &worlds {
        assert!(num(w, "wall_elements") > 0.0);
    }
    let spread = table("success_per_world");
    assert_eq!(spread.len(), 4);
    assert!(spread.iter().all(|v| num(v, "sd") >= 0.0));
    assert!(
        spread[0].contains_key("success_rate_seed_1")
            && spread[0].contains_key("success_rate_seed_2")
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("72.2 %") && report.contains("Table 4.2"));
    // issue 18 defect 4: both bounds for every run, with their assumptions, per row
    let header: Vec<&str> = trials.lines().next().unwrap().split(',').collect();
    for col in [
        "transit_length",
        "prop2_bound",
        "prop4_bound",
        "within_prop2",
        "within_prop4",
        "a1_disc",
        "a1_circle",
        "a3_pairwise",
        "a3_sight_lines",
        "a4_straight",
        "eff_prop2_bound",
        "eff_within_prop4",
    ] {
        assert!(header.contains(&col), "trials.csv lacks {col}");
    }
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    for line in trials.lines().skip(1) {
        let f: Vec<&str> = line.split(',').collect();
        let num = |name: &str| f[col(name)].parse::<f64>().unwrap();
        // the field's controllers search: Assumption 4 never holds
        assert_eq!(f[col("a4_straight")], "false");
        let within2 = num("transit_length") <= num("prop2_bound") + 1e-6;
        assert_eq!(f[col("within_prop2")], within2.to_string(), "{line}");
        let n = num("bounded_transitions");
        assert!(n >= num("plan_len"), "re-plans add transitions: {line}");
        assert!(
            (num("prop4_bound") - num("lidar_range") * n).abs() < 1e-2,
            "{line}"
        );
    }
    assert!(report.contains("## Distance bounds: Propositions 2 and 4"));
    assert!(report.contains("## The map's size"));
    let bounds = table("bounds");
    assert_eq!(bounds.len(), 4 * 2, "4 variants × 2 ranges");
    assert!(
        bounds.iter().all(|b| b["contradictions"] == "0"),
        "{bounds:?}"
    );
    for z in &table("map_size") {
        assert_eq!(
            num(z, "recorded_triplets"),
            6.0 * num(z, "point_elements"),
            "a PQRM records each landmark set under its six orderings"
        );
    }
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

/// `docs/foxglove/qrm-layout.json` is a Foxglove layout (every panel of the tree configured,
/// every configured panel placed) whose panels read only topics — and fields — the demo's
/// log has.
fn foxglove_layout_names_only_logged_topics(log: &Path) {
    let layout_path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/foxglove/qrm-layout.json");
    let layout: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&layout_path).unwrap()).unwrap();
    let configs = layout["configById"].as_object().unwrap();
    fn leaves(node: &serde_json::Value, out: &mut Vec<String>) {
        match node {
            serde_json::Value::String(s) => out.push(s.clone()),
            serde_json::Value::Object(o) => {
                assert!(
                    matches!(o["direction"].as_str(), Some("row" | "column")),
                    "{node}"
                );
                leaves(&o["first"], out);
                leaves(&o["second"], out);
            }
            other => panic!("not a layout node: {other}"),
        }
    }
    let mut placed = Vec::new();
    leaves(&layout["layout"], &mut placed);
    placed.sort();
    let mut configured: Vec<String> = configs.keys().cloned().collect();
    configured.sort();
    assert_eq!(placed, configured, "panels placed vs configured");
    // (topic, field path or "") each panel reads
    let mut wanted: Vec<(String, String)> = Vec::new();
    let split = |path: &str| match path.split_once('.') {
        Some((t, f)) => (t.to_owned(), f.to_owned()),
        None => (path.to_owned(), String::new()),
    };
    for (id, cfg) in configs {
        match id.split('!').next().unwrap() {
            "3D" => {
                let topics = cfg["topics"].as_object().unwrap();
                assert!(topics.contains_key("/navigation"), "the plan is on");
                assert!(topics.contains_key("/world"), "the map is on");
                wanted.extend(topics.keys().map(|t| (t.clone(), String::new())));
                assert_eq!(
                    cfg["followTf"], "world",
                    "the 3D panel follows the log's fixed frame"
                );
            }
            "Plot" => wanted.extend(
                cfg["paths"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| split(p["value"].as_str().unwrap())),
            ),
            "RosOut" => wanted.push(split(cfg["topicToRender"].as_str().unwrap())),
            "RawMessages" => wanted.push(split(cfg["topicPath"].as_str().unwrap())),
            other => panic!("panel type {other} not checked"),
        }
    }
    assert!(
        wanted
            .iter()
            .any(|(t, f)| t == "/map/entropy" && f == "mean_entropy"),
        "an entropy plot"
    );
    let bytes = std::fs::read(log).unwrap();
    let mut seen: std::collections::BTreeMap<String, serde_json::Value> = Default::default();
    let mut counts: std::collections::BTreeMap<String, usize> = Default::default();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        *counts.entry(m.channel.topic.clone()).or_default() += 1;
        seen.entry(m.channel.topic.clone())
            .or_insert_with(|| serde_json::from_slice(&m.data).unwrap());
    }
    for (topic, field) in &wanted {
        let msg = seen
            .get(topic)
            .unwrap_or_else(|| panic!("layout reads {topic}, the log has {:?}", seen.keys()));
        if !field.is_empty() {
            assert!(
                msg.get(field).is_some_and(serde_json::Value::is_number),
                "{topic}.{field}"
            );
        }
    }
    assert!(
        counts["/map/entropy"] >= 10,
        "an entropy series, not one point"
    );
}
