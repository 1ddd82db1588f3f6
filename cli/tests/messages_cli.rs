//! Refusals name the flag or field at fault and what its value was (issue 39: each case below
//! blamed something else — a line of the recording, "coinciding landmarks", no field at all —
//! or was accepted as "not set").
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use common::{qrm, scratch};

/// Runs `args`, expects a refusal (exit 1), and returns the error text.
fn refusal(args: &[&str]) -> String {
    let o = qrm(args, "");
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    err
}

#[test]
fn huge_noise_flags_are_blamed_not_the_recording() {
    let d = scratch("messages-noise");
    // A MRCLAM folder the flag check must come before: its files are never read.
    let out = d.join("out");
    for (flag, value, field) in [
        ("--sigma-range", "1e308", "sigma_range"),
        ("--sigma-range", "18446744073709551615", "sigma_range"),
        ("--sigma-bearing", "100", "sigma_bearing"),
    ] {
        let err = refusal(&[
            "map",
            "--format",
            "mrclam",
            "--input",
            d.to_str().unwrap(),
            "--calculus",
            "edc",
            flag,
            value,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(
            err.contains(field) && !err.contains(".dat") && !err.contains("coincide"),
            "{flag} {value}: {err}"
        );
        assert!(!out.exists());
    }
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn out_of_range_binary_names_say_the_range() {
    let err = refusal(&["calculus", "compose", "opra-64"]);
    assert!(
        err.contains("1 ≤ M ≤ 63") && err.contains("M = 64"),
        "{err}"
    );
    let err = refusal(&["calculus", "permute", "opra-100", "--op", "converse"]);
    assert!(err.contains("M = 100") && !err.contains("ternary"), "{err}");
}

#[test]
fn study_settings_are_refused_by_field_never_read_as_unset() {
    let d = scratch("messages-study");
    let out = d.join("out");
    let o = out.to_str().unwrap();
    for (study, set, said) in [
        ("monte-carlo", "floor=nan", ["`floor`", "finite"]),
        ("real-data", "gate_sigmas=nan", ["`gate_sigmas`", "finite"]),
        ("real-data", "max_frames=inf", ["`max_frames`", "finite"]),
        (
            "monte-carlo",
            "floor=\"x\"",
            ["field `floor`", "expected f64"],
        ),
        (
            "monte-carlo",
            "detail_sigmas=[-1]",
            ["detail_sigmas", ">= 0"],
        ),
        ("serge-cv", "mus=[0]", ["mus", "at least 1"]),
        ("field", "step=1e-12", ["step", "0.01"]),
    ] {
        let err = refusal(&["study", "run", study, "--quick", "--set", set, "--out", o]);
        assert!(said.iter().all(|s| err.contains(s)), "{set}: {err}");
    }
    // A config file: NaN by name, with the file.
    let file = d.join("c.toml");
    std::fs::write(&file, "max_frames = nan\n").unwrap();
    let err = refusal(&[
        "study",
        "run",
        "real-data",
        "--quick",
        "--config",
        file.to_str().unwrap(),
        "--out",
        o,
    ]);
    assert!(
        err.contains("c.toml") && err.contains("`max_frames`"),
        "{err}"
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_huge_sample_count_is_refused_with_its_estimate_not_a_capacity_overflow() {
    let d = scratch("messages-serge");
    let input = d.join("obs.csv");
    std::fs::write(&input, "t,robot,landmark,x,y,cxx,cxy,cyy\n").unwrap();
    let err = refusal(&[
        "serge",
        "learn",
        "--input",
        input.to_str().unwrap(),
        "--mu",
        "4",
        "--samples",
        "18446744073709551615",
        "--out",
        d.join("out").to_str().unwrap(),
    ]);
    assert!(
        err.contains("samples") && err.contains("GiB") && err.contains("the limits are"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn a_long_relation_name_is_cut_in_the_message() {
    let name = "x".repeat(2 << 20);
    let net = format!("{{\"constraints\": [[\"A\", \"B\", \"C\", [\"{name}\"]]]}}");
    let o = qrm(&["reason", "close", "--calculus", "double-cross"], &net);
    assert_eq!(o.status.code(), Some(1));
    assert!(o.stderr.len() < 4096, "{} bytes of stderr", o.stderr.len());
}
