//! Every numeric flag of every command, at every extreme, on the real binary (issue 39): each
//! run is refused with a message naming the flag, or finishes within its time limit with no
//! NaN or infinity in what it prints — never a panic, an abort or a hang. A count of 10¹² or a
//! length of 1e308 that drives the work must be refused before the work starts.
//!
//! The flags come from the binary itself (`qrm numeric-flags`, clap's command tree), so a flag
//! added tomorrow is walked without being listed here; a command with numeric flags and no
//! base invocation below fails the test until it gets one.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz/corpus")
        .join(rel)
}

/// The smallest valid invocation of each command with numeric flags (`{out}`: a fresh output
/// path, `{mrclam}`: a tiny MRCLAM folder, `{mrclam7}`: MRCLAM Dataset 7 from `shared/`), and
/// its stdin. The walked flag is appended, so it
/// wins over a value given here.
fn base(command: &str) -> Option<(Vec<String>, String)> {
    let c = |rel: &str| corpus(rel).to_str().unwrap().to_owned();
    let (args, stdin): (Vec<String>, String) = match command {
        "pqrm prob" => (
            words("pqrm prob --calculus left-right --samples 50"),
            std::fs::read_to_string(corpus("prob_line/readme.json")).unwrap(),
        ),
        "pqrm study" => (
            words(
                "pqrm study --quick --calculi left-right --trials 1 --samples 20 --sigmas 5 \
                 --landmarks 4 --out {out}",
            ),
            String::new(),
        ),
        "pqrm real" => (
            words("pqrm real --input {mrclam7} --samples 20 --max-frames 5 --out {out}"),
            String::new(),
        ),
        "map" => {
            let mut a = words("map --format mcap --calculus left-right --samples 20 --out {out}");
            a.extend(["--input".into(), c("mcap/ros2_laserscan.mcap")]);
            (a, String::new())
        }
        "sim" => (
            words("sim --scenario hallway --no-lidar --out {out}"),
            String::new(),
        ),
        "serge run" => {
            let mut a = words("serge run --mu 2 --grid 20 --trials 5 --out {out}");
            a.extend(["--beliefs".into(), c("beliefs/mixed.json")]);
            (a, String::new())
        }
        "serge learn" => {
            let mut a = words(
                "serge learn --mu 2 --max-triplets 3 --min-frames 1 --samples 50 --grid 16 \
                 --trials 5 --out {out}",
            );
            a.extend(["--input".into(), c("observation_csv/sim.csv")]);
            (a, String::new())
        }
        "serge study" => (
            words("serge study --quick --dataset well-separated --out {out}"),
            String::new(),
        ),
        "qlink study" => (
            words("qlink study --quick --trial sensor-range --pairs 2 --out {out}"),
            String::new(),
        ),
        "qlink field" => (
            words("qlink field --quick --trials 1 --worlds 1 --out {out}"),
            String::new(),
        ),
        "demo" => (words("demo --out {out}"), String::new()),
        "study config" => (words("study config demo"), String::new()),
        "study shard" => (
            words("study shard serge-cv --quick --set folds=2 --index 0 --out {out}"),
            String::new(),
        ),
        "study run" => (
            words("study run serge-cv --quick --set folds=2 --out {out}"),
            String::new(),
        ),
        "study aggregate" => return None,
        "reason export" => {
            let mut a = words("reason export");
            a.push(c("saved_map/left-right.json"));
            (a, String::new())
        }
        "reason infer" => {
            let mut a = words("reason infer --out {out}");
            a.push(c("saved_map/left-right.json"));
            (a, String::new())
        }
        "reason scenario" => {
            let mut a = words("reason scenario --calculus double-cross");
            a.extend(["--input".into(), c("network/json.json")]);
            (a, String::new())
        }
        "reason study" => (
            words(
                "reason study --quick --calculi double-cross --input {mrclam7} --max-frames 5 \
                 --out {out}",
            ),
            String::new(),
        ),
        "convert" => (
            words("convert --from mrclam --input {mrclam} --out {out}.mcap"),
            String::new(),
        ),
        "calculus render" => (
            words("calculus render left-right --out {out}.svg"),
            String::new(),
        ),
        _ => return None,
    };
    Some((args, stdin))
}

fn words(s: &str) -> Vec<String> {
    s.split_whitespace().map(str::to_owned).collect()
}

/// Flags whose value may be huge without driving the work: seeds, an index or a goal the
/// inputs bound (refused when out of range, but only once the inputs are known), a cap the
/// input bounds anyway, a search's node budget (it stops work, never makes it).
const NOT_WORK: [&str; 8] = [
    "--seed",
    "--max-nodes",
    "--goal",
    "--index",
    "--robots",
    "--max-frames",
    "--max-triplets",
    "--threshold",
];

/// Float flags that may be 1e308: tolerances and thresholds (larger only accepts more).
const FLOATS_UNBOUNDED: [(&str, &str); 3] = [
    ("serge run", "--sigma"),
    ("serge learn", "--sigma"),
    ("reason infer", "--epsilon"),
];

fn run(args: &[String], stdin: &str, limit: Duration) -> common::Run {
    common::run_within(args, &[], stdin.as_bytes(), limit)
}

/// The values each kind of flag is walked with.
fn extremes(kind: &str) -> &'static [&'static str] {
    if kind.starts_with('f') {
        &["1e-12", "1e12", "1e308", "-1", "0", "nan", "inf"]
    } else {
        &[
            "0",
            "1000000000000",
            "18446744073709551615",
            "-1",
            "1e-12",
            "nan",
        ]
    }
}

/// MRCLAM Dataset 7 beside the repository (`shared/data`); `None` (with a message) where it
/// is missing outside CI.
fn mrclam7() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/mrclam-dataset7");
    if d.is_dir() {
        return Some(d);
    }
    assert!(
        std::env::var("CI").is_err(),
        "CI must walk the flags of the commands that read a recording (shared/data needed)"
    );
    eprintln!("SKIPPED: the commands that need shared/data/mrclam-dataset7");
    None
}

/// The base invocation's words with its placeholders filled; `None` when it needs Dataset 7
/// and there is none.
fn fill(args: &[String], out: &Path, mrclam: &Path, mrclam7: Option<&Path>) -> Option<Vec<String>> {
    args.iter()
        .map(|x| {
            let x = x
                .replace("{out}", out.to_str().unwrap())
                .replace("{mrclam}", mrclam.to_str().unwrap());
            if x.contains("{mrclam7}") {
                Some(x.replace("{mrclam7}", mrclam7?.to_str().unwrap()))
            } else {
                Some(x)
            }
        })
        .collect()
}

/// Removes whatever a run wrote at `out` (a folder, a file, `out.mcap`, `out.svg`).
fn clean(out: &Path) {
    let _ = std::fs::remove_dir_all(out);
    let _ = std::fs::remove_file(out);
    let _ = std::fs::remove_file(out.with_extension("mcap"));
    let _ = std::fs::remove_file(out.with_extension("svg"));
}

/// A tiny MRCLAM folder (the fuzz corpus's seed: survey, barcodes, one robot's measurements).
fn mrclam(dir: &Path) -> PathBuf {
    let data = dir.join("mrclam");
    std::fs::create_dir_all(&data).unwrap();
    let seed = std::fs::read_to_string(corpus("mrclam/tiny.txt")).unwrap();
    let parts: Vec<&str> = seed.split("\n%%\n").collect();
    std::fs::write(data.join("Landmark_Groundtruth.dat"), parts[0]).unwrap();
    std::fs::write(data.join("Barcodes.dat"), parts[1]).unwrap();
    std::fs::write(data.join("Robot1_Measurement.dat"), parts[2]).unwrap();
    data
}

/// Whether the refusal names the flag (as typed, or as the config field it sets).
fn names_flag(err: &str, flag: &str) -> bool {
    let bare = flag.trim_start_matches("--");
    err.contains(flag) || err.contains(bare) || err.contains(&bare.replace('-', "_"))
}

/// Issue 39: a knob outside the cost estimate ran for minutes, aborted on allocation or
/// panicked (`serge learn --samples 18446744073709551615`: capacity overflow); a refusal
/// blamed a line of the input instead of the flag.
#[test]
fn every_numeric_flag_at_every_extreme_is_refused_by_name_or_bounded() {
    let listing = common::ok(&["numeric-flags"], "");
    let flags: Vec<(String, String, String)> = listing
        .lines()
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            (f[0].to_owned(), f[1].to_owned(), f[2].to_owned())
        })
        .collect();
    assert!(
        flags.len() >= 40,
        "the listing misses flags: {} found",
        flags.len()
    );
    let dir = common::scratch("flags-walk");
    let data = mrclam(&dir);
    let data7 = mrclam7();
    let limit = Duration::from_secs(60);
    let mut problems = Vec::new();
    let mut runs = 0;
    let mut slowest = (Duration::ZERO, String::new());
    // Each base invocation runs as given: a refusal below is the flag's doing.
    let mut commands: Vec<&str> = flags.iter().map(|f| f.0.as_str()).collect();
    commands.dedup();
    for command in commands {
        let Some((args, stdin)) = base(command) else {
            continue;
        };
        let out = dir.join("out-base");
        let Some(a) = fill(&args, &out, &data, data7.as_deref()) else {
            continue;
        };
        let o = run(&a, &stdin, limit);
        assert!(
            o.code == Some(0),
            "the base invocation `qrm {}` fails ({:?} after {:.1?}): {}",
            a.join(" "),
            o.code,
            o.took,
            o.stderr
        );
        clean(&out);
    }
    for (command, flag, kind) in &flags {
        if command == "study aggregate" {
            // its only numeric flag is the config's --seed, walked through `study run`
            continue;
        }
        let Some((args, stdin)) = base(command) else {
            problems.push(format!(
                "`qrm {command}` has numeric flag {flag} but no base invocation in this test"
            ));
            continue;
        };
        for value in extremes(kind) {
            runs += 1;
            let out = dir.join(format!("out-{runs}"));
            let Some(mut a) = fill(&args, &out, &data, data7.as_deref()) else {
                continue;
            };
            a.push(format!("{flag}={value}"));
            let o = run(&a, &stdin, limit);
            let shown = format!("qrm {}", a.join(" "));
            if o.took > slowest.0 {
                slowest = (o.took, shown.clone());
            }
            let err_head: String = o.stderr.chars().take(300).collect();
            if o.timed_out {
                problems.push(format!("{shown}: still running after {limit:?}"));
                continue;
            }
            match o.code {
                Some(0) => {
                    let huge_count = !kind.starts_with('f') && *value == "1000000000000";
                    let huge_float = kind.starts_with('f') && *value == "1e308";
                    let allowed = NOT_WORK.contains(&flag.as_str())
                        || FLOATS_UNBOUNDED.contains(&(command.as_str(), flag.as_str()));
                    if (huge_count || huge_float) && !allowed {
                        problems.push(format!(
                            "{shown}: accepted (in {:.1?}); a value that drives the work must \
                             be refused before it starts",
                            o.took
                        ));
                    }
                    if o.stdout.contains("NaN") || o.stdout.contains("inf,") {
                        problems.push(format!("{shown}: NaN or inf in the output"));
                    }
                }
                Some(1) | Some(2) => {
                    if !names_flag(&o.stderr, flag) {
                        problems.push(format!("{shown}: the refusal names no flag: {err_head}"));
                    }
                }
                other => problems.push(format!("{shown}: exit {other:?}: {err_head}")),
            }
            clean(&out);
        }
    }
    eprintln!(
        "{} flags, {runs} runs; slowest {:.1?}: {}",
        flags.len(),
        slowest.0,
        slowest.1
    );
    let _ = std::fs::remove_dir_all(&dir);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// Dotted paths of every number in a TOML value (array elements by index).
fn numeric_paths(v: &toml::Value, at: &str, out: &mut Vec<String>) {
    match v {
        toml::Value::Integer(_) | toml::Value::Float(_) => out.push(at.to_owned()),
        toml::Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                numeric_paths(x, &format!("{at}[{i}]"), out);
            }
        }
        toml::Value::Table(t) => {
            for (k, x) in t {
                let p = if at.is_empty() {
                    k.clone()
                } else {
                    format!("{at}.{k}")
                };
                numeric_paths(x, &p, out);
            }
        }
        _ => {}
    }
}

fn slot<'a>(v: &'a mut toml::Value, path: &str) -> &'a mut toml::Value {
    let mut node = v;
    for part in path.split('.') {
        let mut pieces = part.split('[');
        let key = pieces.next().unwrap();
        node = node.get_mut(key).unwrap();
        for index in pieces {
            let i: usize = index.trim_end_matches(']').parse().unwrap();
            node = node.get_mut(i).unwrap();
        }
    }
    node
}

/// Issue 39: a clutter disc of radius 1e39 or 2³² m was accepted and the simulation ran for
/// minutes. Every number of a world file — bounds, each kind of entity's position, size and
/// id — at every extreme, through `qrm sim --world`: refused naming what is wrong, or a run
/// within its time limit.
#[test]
fn every_world_field_at_every_extreme_is_refused_by_name_or_bounded() {
    let world_text = "bounds = [0.0, 20.0, 0.0, 10.0]\n\n\
        [[wall]]\nid = 7\nstart = [1.0, 1.0]\nend = [5.0, 1.0]\n\n\
        [[landmark]]\nid = 0\npos = [3.0, 4.0]\nradius = 0.2\n\n\
        [[landmark]]\nid = 1\npos = [8.0, 6.0]\nradius = 0.2\n\n\
        [[landmark]]\nid = 2\npos = [12.0, 3.0]\nradius = 0.2\n\n\
        [[clutter]]\npos = [15.0, 7.0]\nradius = 0.5\n";
    let base: toml::Value = toml::from_str(world_text).unwrap();
    let mut paths = Vec::new();
    numeric_paths(&base, "", &mut paths);
    assert!(paths.len() >= 15, "{paths:?}");
    let dir = common::scratch("world-walk");
    let limit = Duration::from_secs(60);
    let mut problems = Vec::new();
    for path in &paths {
        let integer = path.ends_with(".id");
        for value in ["1e-12", "1e12", "1e308", "-1", "0", "nan", "inf", "-inf"] {
            let mut w = base.clone();
            *slot(&mut w, path) = if integer {
                match value.parse::<f64>() {
                    Ok(x) if x.fract() == 0.0 && x.abs() < 9e15 => toml::Value::Integer(x as i64),
                    Ok(x) => toml::Value::Float(x),
                    Err(_) => continue,
                }
            } else {
                toml::Value::Float(value.parse().unwrap())
            };
            let file = dir.join("world.toml");
            std::fs::write(&file, toml::to_string(&w).unwrap()).unwrap();
            let out = dir.join("out");
            let _ = std::fs::remove_dir_all(&out);
            let args: Vec<String> = [
                "sim",
                "--scenario",
                "hallway",
                "--no-lidar",
                "--world",
                file.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ]
            .map(str::to_owned)
            .to_vec();
            let o = run(&args, "", limit);
            let shown = format!("{path} = {value}");
            let entity = path.split(['[', '.']).next().unwrap();
            if o.timed_out {
                problems.push(format!("{shown}: still running after {limit:?}"));
                continue;
            }
            match o.code {
                Some(0) => {
                    if o.stdout.contains("NaN") {
                        problems.push(format!("{shown}: NaN in the output"));
                    }
                }
                Some(1) => {
                    if !o.stderr.contains(entity) {
                        problems.push(format!(
                            "{shown}: the refusal does not name the {entity}: {}",
                            o.stderr.chars().take(300).collect::<String>()
                        ));
                    }
                    if out.exists() {
                        problems.push(format!("{shown}: refused but left {}", out.display()));
                    }
                }
                other => problems.push(format!(
                    "{shown}: exit {other:?}: {}",
                    o.stderr.chars().take(300).collect::<String>()
                )),
            }
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}
