//! `docs/reliability.md`, produced by this test: every input surface of the CLI × every class
//! of bad input, run as a user would, with what happened. The test fails when any run panics,
//! is killed, leaves an output directory behind after failing, or prints NaN/inf in an
//! accepted result — and when the committed table differs from what the binary does now
//! (regenerate with `QRM_BLESS=1 cargo test -p qrm-cli --test reliability_table`).
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use std::path::{Path, PathBuf};
use std::time::Duration;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn corpus(rel: &str) -> String {
    std::fs::read_to_string(root().join("fuzz/corpus").join(rel)).unwrap()
}

/// How an input surface is fed: a file argument, a MRCLAM directory, or stdin.
enum Feed {
    File {
        args: &'static [&'static str],
        name: &'static str,
    },
    Mrclam,
    Stdin(&'static [&'static str]),
}

struct Surface {
    name: &'static str,
    seed: Vec<u8>,
    feed: Feed,
    /// Whether the command takes `--out` (then a failure must leave no directory).
    writes: bool,
}

fn surfaces() -> Vec<Surface> {
    use Feed::{File, Mrclam, Stdin};
    let s = |name, seed: &str, feed, writes| Surface {
        name,
        // The MRCLAM seed holds several files; the measurements (third part) are spoiled.
        seed: match seed {
            "mrclam/tiny.txt" => corpus(seed)
                .split("\n%%\n")
                .nth(2)
                .unwrap()
                .as_bytes()
                .to_vec(),
            _ => std::fs::read(root().join("fuzz/corpus").join(seed)).unwrap(),
        },
        feed,
        writes,
    };
    vec![
        s(
            "calculus spec (TOML)",
            "spec_toml/double-cross.toml",
            File {
                args: &["calculus", "show", "{file}"],
                name: "spec.toml",
            },
            false,
        ),
        s(
            "calculus classify (stdin)",
            "classify_row/row0.txt",
            Stdin(&["calculus", "classify", "edc"]),
            false,
        ),
        s(
            "observation CSV",
            "observation_csv/sim.csv",
            File {
                args: &[
                    "map",
                    "--format",
                    "csv",
                    "--input",
                    "{file}",
                    "--calculus",
                    "left-right",
                    "--samples",
                    "50",
                    "--out",
                    "{out}",
                ],
                name: "obs.csv",
            },
            true,
        ),
        s(
            "truth CSV",
            "truth_csv/sim.csv",
            File {
                args: &[
                    "map",
                    "--format",
                    "csv",
                    "--input",
                    "{good_csv}",
                    "--truth",
                    "{file}",
                    "--calculus",
                    "left-right",
                    "--samples",
                    "50",
                    "--out",
                    "{out}",
                ],
                name: "truth.csv",
            },
            true,
        ),
        s(
            "g2o",
            "g2o/small.g2o",
            File {
                args: &[
                    "map",
                    "--format",
                    "g2o",
                    "--input",
                    "{file}",
                    "--calculus",
                    "left-right",
                    "--samples",
                    "50",
                    "--out",
                    "{out}",
                ],
                name: "data.g2o",
            },
            true,
        ),
        s("MRCLAM measurements", "mrclam/tiny.txt", Mrclam, true),
        s(
            "SERGE beliefs (JSON)",
            "beliefs/mixed.json",
            File {
                args: &[
                    "serge",
                    "run",
                    "--beliefs",
                    "{file}",
                    "--mu",
                    "2",
                    "--trials",
                    "5",
                    "--out",
                    "{out}",
                ],
                name: "beliefs.json",
            },
            true,
        ),
        s(
            "world file (TOML)",
            "world/small.toml",
            File {
                args: &[
                    "sim",
                    "--scenario",
                    "pqrm-100",
                    "--no-lidar",
                    "--world",
                    "{file}",
                    "--out",
                    "{out}",
                ],
                name: "world.toml",
            },
            true,
        ),
        s(
            "saved map (JSON)",
            "saved_map/left-right.json",
            File {
                args: &["reason", "check", "{file}"],
                name: "map.json",
            },
            false,
        ),
        s(
            "saved map (binary)",
            "saved_map/left-right.pqrm",
            File {
                args: &["reason", "check", "{file}"],
                name: "map.pqrm",
            },
            false,
        ),
        s(
            "study config (TOML, --config)",
            "study_config/small-monte-carlo.toml",
            File {
                args: &[
                    "study",
                    "run",
                    "monte-carlo",
                    "--quick",
                    "--config",
                    "{file}",
                    "--out",
                    "{out}",
                ],
                name: "config.toml",
            },
            true,
        ),
        s(
            "pqrm prob line (stdin)",
            "prob_line/readme.json",
            Stdin(&[
                "pqrm",
                "prob",
                "--calculus",
                "left-right",
                "--samples",
                "100",
            ]),
            false,
        ),
        s(
            "MCAP log (detections)",
            "mcap/detections.mcap",
            File {
                args: &[
                    "map",
                    "--format",
                    "mcap",
                    "--input",
                    "{file}",
                    "--calculus",
                    "left-right",
                    "--samples",
                    "50",
                    "--out",
                    "{out}",
                ],
                name: "run.mcap",
            },
            true,
        ),
        s(
            "MCAP log (ROS 2 LaserScan)",
            "mcap/ros2_laserscan.mcap",
            File {
                args: &[
                    "map",
                    "--format",
                    "mcap",
                    "--input",
                    "{file}",
                    "--samples",
                    "50",
                    "--out",
                    "{out}",
                ],
                name: "bag.mcap",
            },
            true,
        ),
        s(
            "ternary network (stdin)",
            "network/json.json",
            Stdin(&["reason", "close", "--calculus", "double-cross"]),
            false,
        ),
        s(
            "binary network (stdin)",
            "binary_network/sparq.lisp",
            Stdin(&["reason", "close", "--calculus", "opra-1"]),
            false,
        ),
    ]
}

/// The classes of bad input, each a transformation of a valid input.
const CLASSES: [&str; 11] = [
    "NaN",
    "infinity",
    "1e308",
    "1e12",
    "1e-12",
    "negative (-1)",
    "empty",
    "truncated",
    "not the format",
    "2 MB field",
    "binary bytes",
];

/// The byte range of the last number in `text` (digits with sign, dot and exponent).
fn last_number(text: &str) -> Option<(usize, usize)> {
    let b = text.as_bytes();
    let mut end = b.len();
    while end > 0 && !b[end - 1].is_ascii_digit() {
        end -= 1;
    }
    if end == 0 {
        return None;
    }
    let mut start = end;
    while start > 0 && (b[start - 1].is_ascii_digit() || b".eE+-".contains(&b[start - 1])) {
        start -= 1;
    }
    Some((start, end))
}

fn apply(class: &str, seed: &[u8]) -> Vec<u8> {
    // A binary seed (an MCAP log): the same classes on its bytes. The last number sits in
    // the last message's JSON; changing its length also breaks the record's length field,
    // so these runs test a damaged log as much as a bad value.
    let Ok(seed) = std::str::from_utf8(seed) else {
        let at = seed.iter().rposition(u8::is_ascii_digit).unwrap_or(0);
        let mut start = at;
        while start > 0 && (seed[start - 1].is_ascii_digit() || b".eE+-".contains(&seed[start - 1]))
        {
            start -= 1;
        }
        let replace = |with: &[u8]| [&seed[..start], with, &seed[at + 1..]].concat();
        return match class {
            "NaN" => replace(b"NaN"),
            "infinity" => replace(b"inf"),
            "1e308" => replace(b"1e308"),
            "1e12" => replace(b"1e12"),
            "1e-12" => replace(b"1e-12"),
            "negative (-1)" => replace(b"-1"),
            "empty" => Vec::new(),
            "truncated" => seed[..seed.len() / 2].to_vec(),
            "not the format" => b"hello, this is a README\n".to_vec(),
            "2 MB field" => replace("7".repeat(2 << 20).as_bytes()),
            _ => vec![0xff, 0xfe, 0x00, 0x9c, b'\n', 0x80],
        };
    };
    // The last number replaced; a text without numbers (a network of labels) gets the value
    // where a label would be.
    let replace = |with: &str| match last_number(seed) {
        Some((s, e)) => format!("{}{with}{}", &seed[..s], &seed[e..]).into_bytes(),
        None => seed.replacen("left-front", with, 1).into_bytes(),
    };
    match class {
        "NaN" => replace("NaN"),
        "infinity" => replace("inf"),
        "1e308" => replace("1e308"),
        "1e12" => replace("1e12"),
        "1e-12" => replace("1e-12"),
        "negative (-1)" => replace("-1"),
        "empty" => Vec::new(),
        "truncated" => seed.as_bytes()[..seed.len() / 2].to_vec(),
        "not the format" => b"hello, this is a README\n".to_vec(),
        "2 MB field" => replace(&"7".repeat(2 << 20)),
        _ => vec![0xff, 0xfe, 0x00, 0x9c, b'\n', 0x80],
    }
}

struct Outcome {
    code: Option<i32>,
    stderr: String,
    stdout: String,
    left_dir: bool,
}

fn run(surface: &Surface, input: &[u8], dir: &Path) -> Outcome {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).unwrap();
    let out = dir.join("out");
    let good_csv = dir.join("good.csv");
    std::fs::write(&good_csv, corpus("observation_csv/sim.csv")).unwrap();
    let (args, stdin): (Vec<String>, Vec<u8>) = match &surface.feed {
        Feed::File { args, name } => {
            let file = dir.join(name);
            std::fs::write(&file, input).unwrap();
            let args = args
                .iter()
                .map(|a| {
                    a.replace("{file}", file.to_str().unwrap())
                        .replace("{out}", out.to_str().unwrap())
                        .replace("{good_csv}", good_csv.to_str().unwrap())
                })
                .collect();
            (args, Vec::new())
        }
        Feed::Mrclam => {
            let data = dir.join("mrclam");
            std::fs::create_dir_all(&data).unwrap();
            let seed = corpus("mrclam/tiny.txt");
            let parts: Vec<&str> = seed.split("\n%%\n").collect();
            std::fs::write(data.join("Landmark_Groundtruth.dat"), parts[0]).unwrap();
            std::fs::write(data.join("Barcodes.dat"), parts[1]).unwrap();
            std::fs::write(data.join("Robot1_Measurement.dat"), input).unwrap();
            let args = [
                "map",
                "--format",
                "mrclam",
                "--input",
                data.to_str().unwrap(),
                "--calculus",
                "left-right",
                "--samples",
                "50",
                "--out",
                out.to_str().unwrap(),
            ]
            .map(str::to_owned)
            .to_vec();
            (args, Vec::new())
        }
        Feed::Stdin(args) => (
            args.iter().map(|a| (*a).to_owned()).collect(),
            input.to_vec(),
        ),
    };
    let o = common::run_within(
        &args,
        &[("QRM_CACHE_DIR", "")],
        &stdin,
        Duration::from_secs(600),
    );
    let shown = |b: &str| b.replace(dir.to_str().unwrap(), "<dir>");
    Outcome {
        code: o.code,
        stderr: shown(&o.stderr),
        stdout: shown(&o.stdout),
        left_dir: out.exists(),
    }
}

fn cell(o: &Outcome) -> String {
    let first = o
        .stderr
        .lines()
        .rev()
        .find(|l| l.starts_with("error:"))
        .unwrap_or("")
        .trim_start_matches("error: ");
    let mut msg: String = first.chars().take(110).collect();
    if first.chars().count() > 110 {
        msg.push('…');
    }
    let msg = msg.replace('|', "\\|").replace('`', "'");
    match o.code {
        Some(0) => "accepted".to_owned(),
        Some(1) => format!("error: {msg}"),
        other => format!("**exit {other:?}**"),
    }
}

#[test]
fn every_surface_meets_every_bad_input_with_a_typed_error_or_a_clean_result() {
    let dir = std::env::temp_dir().join(format!("qrm-reliability-{}", std::process::id()));
    let mut problems = Vec::new();
    let mut doc = String::from(
        "# Reliability: input surfaces × bad inputs\n\n\
         Produced by `cli/tests/reliability_table.rs` (regenerate: `QRM_BLESS=1 cargo test -p \
         qrm-cli --test reliability_table`); the test fails when the binary does anything else. \
         Each cell is one run of the real `qrm` binary on a valid input (from `fuzz/corpus/`) \
         spoiled one way: the last number replaced by NaN, `inf`, `1e308`, `1e12`, `1e-12` or \
         `-1`; the file \
         empty, cut in half, replaced by prose, given a 2 MB number, or binary bytes. \
         *accepted* means exit 0 with no NaN or infinity in the output (a large but finite \
         value can be legitimate); *error* is exit 1 with the message shown (first 110 \
         characters). Every failing run that takes `--out` is checked to leave no output \
         directory. Deeper, in-process coverage: the fuzz targets in `fuzz/` \
         (`tests/tests/fuzz_corpus.rs` runs them over their corpus and 5,000 mutations each).\n\n\
         **A stopped run.** Ctrl-C, SIGTERM and SIGHUP (what `timeout`, `kill`, systemd and job \
         schedulers send) stop a run within a second: it says `interrupted`, removes its \
         unfinished output (the hidden `.NAME.partial-PID` beside `--out`) and exits 130 \
         (`cli/tests/interrupt_cli.rs`). SIGKILL, an abort or a power cut run no handler and \
         leave that directory; the next run that writes beside it removes every such directory \
         whose process no longer runs and says so on stderr (where running processes cannot \
         be told, without `/proc`, nothing is removed). Files are never half-written: each is \
         written beside its name and renamed.\n\n\
         **Caches.** The derived tables cached on disk (`~/.cache/qrm`, `QRM_CACHE_DIR`) carry a \
         checksum of their contents; a file that does not verify is derived again and \
         replaced, never believed.\n\n\
         **Work and memory.** Every knob that drives work — a study's trials, steps, landmarks \
         and samples, a network's points, a calculus's granularity, a grid's cells, a \
         look-ahead's horizon — feeds one estimate (`qsr_core::cost::Cost`: peak bytes and \
         core-seconds at measured rates) checked before anything is allocated against 4 GiB and \
         48 core-hours (a table derivation: 1 core-hour; one navigation decision: 60 \
         core-seconds). A refusal names the knobs with their values, the estimate and the \
         limits in one form (`… needs about 4.01 GiB and 1 core-hour; the limits are 4 GiB and \
         48 core-hours: fewer points`); work accepted but estimated past 5 core-seconds is \
         announced with the same estimate on stderr before it starts \
         (`cli/tests/network_walk.rs` holds a 120-point closure's peak memory and time to \
         it).\n\n",
    );
    for s in surfaces() {
        doc.push_str(&format!(
            "## {}\n\n| bad input | outcome |\n|---|---|\n",
            s.name
        ));
        for class in CLASSES {
            let o = run(&s, &apply(class, &s.seed), &dir);
            if o.stderr.contains("panicked") || !matches!(o.code, Some(0 | 1)) {
                problems.push(format!(
                    "{} / {class}: exit {:?}: {}",
                    s.name, o.code, o.stderr
                ));
            }
            if o.code != Some(0) && s.writes && o.left_dir {
                problems.push(format!(
                    "{} / {class}: failed but left an output directory",
                    s.name
                ));
            }
            if o.code == Some(0) {
                let bad = o
                    .stdout
                    .split(|c: char| !(c.is_ascii_alphanumeric() || c == '-'))
                    .any(|t| matches!(t, "NaN" | "inf" | "-inf"));
                if bad {
                    problems.push(format!(
                        "{} / {class}: accepted with NaN/inf in the output",
                        s.name
                    ));
                }
            }
            doc.push_str(&format!("| {class} | {} |\n", cell(&o)));
        }
        doc.push('\n');
    }
    let _ = std::fs::remove_dir_all(&dir);
    assert!(problems.is_empty(), "{}", problems.join("\n"));
    let path = root().join("docs/reliability.md");
    if std::env::var_os("QRM_BLESS").is_some() {
        std::fs::write(&path, &doc).unwrap();
    } else {
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        assert!(
            committed == doc,
            "docs/reliability.md is stale; regenerate with QRM_BLESS=1 cargo test -p qrm-cli \
             --test reliability_table"
        );
    }
}
