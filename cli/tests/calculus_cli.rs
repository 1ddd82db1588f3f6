//! The `qrm calculus ...` interfaces that acceptance checks use (issue 2 §3), run as a user
//! would: the real binary, stdin in, stdout/stderr/exit code out.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use common::{ok, qrm};

fn json(args: &[&str]) -> serde_json::Value {
    serde_json::from_str(&ok(args, "")).unwrap()
}

#[test]
fn list_prints_one_name_per_line() {
    let names: Vec<String> = ok(&["calculus", "list"], "")
        .lines()
        .map(str::to_owned)
        .collect();
    for want in [
        "edc",
        "edc-lune",
        "triple-cross",
        "double-cross",
        "quadrant",
        "left-right",
        "front-between-behind",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "{want} missing from {names:?}"
        );
    }
    assert!(names.iter().any(|n| n.starts_with("star-")));
}

#[test]
fn classify_prints_one_label_per_line() {
    // Rotated, scaled and translated configurations of EDC states 13, 2 and 20.
    let input = "0 0 0 1 -0.2 0.3\n10 10 12 10 14 12\n# comment\n\n5 5 5 7 6 3\n";
    assert_eq!(ok(&["calculus", "classify", "edc"], input), "13\n1\n20\n");
    assert_eq!(
        ok(
            &["calculus", "classify", "left-right"],
            "0 0 0 1 -1 0\n0 0 0 1 1 0\n"
        ),
        "left\nright\n"
    );
    assert_eq!(
        ok(
            &["calculus", "classify", "star-4"],
            "0 0 1.5707963267948966 0 5\n"
        ),
        "front\n"
    );
}

#[test]
fn classify_reports_the_bad_line_and_fails() {
    for (input, needle) in [
        ("0 0 0 1 1 1\n0 0 0 1 x 1\n", "line 2"),
        ("0 0 0 1 1 1\n1 1 1 1 0 0\n", "line 2"),
        ("0 0 0 1 1\n", "line 1"),
        ("0 0 0 1 1 NaN\n", "line 1"),
    ] {
        let out = qrm(&["calculus", "classify", "edc"], input);
        assert!(!out.status.success(), "{input:?} should fail");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{input:?}: {err}");
        assert!(out.stdout.is_empty(), "no partial output on failure");
    }
}

#[test]
fn neighbours_json_has_states_adjacency_and_distances() {
    let v = json(&["calculus", "neighbours", "edc", "--json"]);
    let states: Vec<&str> = v["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s.as_str().unwrap())
        .collect();
    assert_eq!(states, (1..=20).map(|i| i.to_string()).collect::<Vec<_>>());
    let adj = v["adjacent"].as_array().unwrap();
    assert!(adj.iter().any(|p| p[0] == "1" && p[1] == "6"));
    assert!(!adj.iter().any(|p| p[0] == "1" && p[1] == "20"));
    let d = v["distance"].as_array().unwrap();
    assert_eq!(d.len(), 20);
    assert_eq!(d[0][19], 4);
    assert_eq!(
        d.iter()
            .flat_map(|r| r.as_array().unwrap())
            .filter_map(|x| x.as_u64())
            .max(),
        Some(4)
    );
}

#[test]
fn compose_and_permute_json_use_labels() {
    let v = json(&["calculus", "compose", "double-cross", "--json"]);
    assert_eq!(v["states"].as_array().unwrap().len(), 6);
    let cell = v["table"]["right-front"]["left-front"].as_array().unwrap();
    let cell: Vec<&str> = cell.iter().map(|s| s.as_str().unwrap()).collect();
    assert_eq!(cell, ["left-front", "right-front"]);
    let v = json(&["calculus", "permute", "edc", "--op", "inverse", "--json"]);
    assert_eq!(
        v["table"]["13"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| s.as_str().unwrap())
            .collect::<Vec<_>>(),
        ["8"]
    );
    let out = qrm(
        &["calculus", "permute", "edc", "--op", "twist", "--json"],
        "",
    );
    assert!(!out.status.success());
    // clap refuses it and lists the operations there are
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("invalid value 'twist'") && err.contains("shortcut-inverse"),
        "{err}"
    );
}

#[test]
fn render_writes_an_svg_and_names_may_be_spec_files() {
    let dir = std::env::temp_dir().join(format!("qrm-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("edc.svg");
    ok(
        &["calculus", "render", "edc", "--out", svg.to_str().unwrap()],
        "",
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(text.starts_with("<svg") && text.contains("20 states") && text.contains("\n13\n"));
    // The spec of a built-in, saved as a user file, is accepted wherever a name is.
    let spec = dir.join("mine.toml");
    std::fs::write(
        &spec,
        ok(&["calculus", "spec", "quadrant"], "").replace("name = \"quadrant\"", "name = \"mine\""),
    )
    .unwrap();
    let shown = json(&["calculus", "show", spec.to_str().unwrap(), "--json"]);
    assert_eq!(shown["name"], "mine");
    assert_eq!(shown["n_states"], 4);
    assert_eq!(
        ok(
            &["calculus", "classify", spec.to_str().unwrap()],
            "0 0 0 1 -1 2\n"
        ),
        "left-front\n"
    );
    // Bad names and bad files get one clear error each.
    let out = qrm(&["calculus", "show", "nonsense"], "");
    assert!(String::from_utf8_lossy(&out.stderr).contains("unknown calculus `nonsense`"));
    std::fs::write(
        dir.join("bad.toml"),
        "name = \"bad\"\nframe = \"ternary\"\n",
    )
    .unwrap();
    let out = qrm(
        &["calculus", "show", dir.join("bad.toml").to_str().unwrap()],
        "",
    );
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("invalid calculus spec"));
    let out = qrm(
        &[
            "calculus",
            "render",
            "edc",
            "--out",
            dir.join("x.png").to_str().unwrap(),
        ],
        "",
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains(".svg"));
    std::fs::remove_dir_all(&dir).ok();
}
