//! Every fuzz target (`qrm_tests::fuzz`, the bodies `cargo +nightly fuzz run NAME` drives) run
//! as an ordinary test: over its stored corpus (`fuzz/corpus/NAME/`, every crash ever found
//! joins it) and over seeded mutations of that corpus — numbers swapped for NaN, ±inf, 1e308,
//! subnormals, huge and negative ids; bytes flipped; lines cut, doubled and spliced — so CI
//! exercises every parser without a nightly toolchain. Bounded: a few thousand inputs per
//! target, well under a minute in all.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

use qrm_tests::fuzz::TARGETS;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Mutated inputs per target (MRCLAM writes a directory per input, so it gets fewer).
const MUTATIONS: usize = 5_000;
const MUTATIONS_MRCLAM: usize = 600;

const TOKENS: [&str; 22] = [
    "NaN",
    "nan",
    "inf",
    "-inf",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "5e-324",
    "0",
    "-0",
    "-1",
    "-6.7",
    "1e10",
    "18446744073709551615",
    "4294967296",
    "1e30",
    "\"\"",
    "[]",
    "{}",
    ",",
    "\n",
    "\u{0}",
];

fn corpus(name: &str) -> Vec<Vec<u8>> {
    let dir = qrm_tests::workspace_root().join("fuzz/corpus").join(name);
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    assert!(!files.is_empty(), "{} is empty", dir.display());
    files.iter().map(|f| std::fs::read(f).unwrap()).collect()
}

fn mutate(rng: &mut ChaCha8Rng, seeds: &[Vec<u8>]) -> Vec<u8> {
    let mut v = seeds[rng.random_range(0..seeds.len())].clone();
    for _ in 0..rng.random_range(1..4) {
        let len = v.len();
        match rng.random_range(0..7) {
            // Swap a number (a run of digits, signs, dots, e) for an interesting token.
            0 | 1 => {
                let starts: Vec<usize> = (0..len)
                    .filter(|&i| {
                        v[i].is_ascii_digit() && (i == 0 || !v[i - 1].is_ascii_alphanumeric())
                    })
                    .collect();
                if let Some(&s) = starts.get(rng.random_range(0..starts.len().max(1))) {
                    let mut e = s;
                    while e < len && (v[e].is_ascii_digit() || b".eE+-".contains(&v[e])) {
                        e += 1;
                    }
                    let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                    v.splice(s..e, t.iter().copied());
                }
            }
            2 if len > 0 => {
                let i = rng.random_range(0..len);
                v[i] ^= 1 << rng.random_range(0..8);
            }
            3 if len > 0 => v.truncate(rng.random_range(0..len)),
            4 => {
                let t = TOKENS[rng.random_range(0..TOKENS.len())].as_bytes();
                let at = rng.random_range(0..=len);
                v.splice(at..at, t.iter().copied());
            }
            5 => {
                // Double a line.
                let lines: Vec<&[u8]> = v.split(|b| *b == b'\n').collect();
                let k = rng.random_range(0..lines.len());
                let mut out = Vec::new();
                for (i, l) in lines.iter().enumerate() {
                    out.extend_from_slice(l);
                    out.push(b'\n');
                    if i == k {
                        out.extend_from_slice(l);
                        out.push(b'\n');
                    }
                }
                v = out;
            }
            _ if len > 0 => {
                // Splice the tail of another seed.
                let other = &seeds[rng.random_range(0..seeds.len())];
                let cut = rng.random_range(0..len);
                let from = rng.random_range(0..other.len().max(1));
                v.truncate(cut);
                v.extend_from_slice(&other[from.min(other.len())..]);
            }
            _ => {}
        }
    }
    v
}

fn run_one(name: &str, f: fn(&[u8]), input: &[u8], what: &str) {
    if catch_unwind(AssertUnwindSafe(|| f(input))).is_err() {
        let dir = qrm_tests::workspace_root().join("target/fuzz-failures");
        let _ = std::fs::create_dir_all(&dir);
        let file = dir.join(format!("{name}-{what}"));
        let _ = std::fs::write(&file, input);
        panic!(
            "fuzz target `{name}` failed on {what}; the input is in {} — fix the defect and add \
             the file to fuzz/corpus/{name}/",
            file.display()
        );
    }
}

#[test]
fn every_target_survives_its_corpus_and_mutations() {
    let start = std::time::Instant::now();
    for (i, (name, f)) in TARGETS.iter().enumerate() {
        let t0 = std::time::Instant::now();
        let seeds = corpus(name);
        for (k, s) in seeds.iter().enumerate() {
            run_one(name, *f, s, &format!("corpus-{k}"));
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed + i as u64);
        let n = if *name == "mrclam" {
            MUTATIONS_MRCLAM
        } else {
            MUTATIONS
        };
        for k in 0..n {
            let input = mutate(&mut rng, &seeds);
            run_one(name, *f, &input, &format!("mutation-{k}"));
        }
        eprintln!(
            "{name}: {} corpus + {n} mutated inputs in {:.1} s",
            seeds.len(),
            t0.elapsed().as_secs_f64()
        );
    }
    eprintln!("all targets in {:.1} s", start.elapsed().as_secs_f64());
}

#[test]
fn every_target_has_a_libfuzzer_binary_and_a_corpus() {
    let root = qrm_tests::workspace_root().join("fuzz");
    for (name, _) in TARGETS {
        let target = root.join("fuzz_targets").join(format!("{name}.rs"));
        let text = std::fs::read_to_string(&target)
            .unwrap_or_else(|e| panic!("{}: {e}", target.display()));
        assert!(
            text.contains(&format!("qrm_tests::fuzz::{name}")),
            "{} does not call qrm_tests::fuzz::{name}",
            target.display()
        );
        assert!(root.join("corpus").join(name).is_dir());
    }
}
