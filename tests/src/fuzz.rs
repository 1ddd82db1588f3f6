//! The bodies of qrm's fuzz targets: one function per input surface, taking raw bytes.
//!
//! `fuzz/fuzz_targets/*.rs` hand these to libFuzzer (`cargo +nightly fuzz run NAME`), and
//! `tests/tests/fuzz_corpus.rs` runs them as ordinary tests over the stored corpus
//! (`fuzz/corpus/NAME/`) plus seeded mutations of it, so CI exercises every target without a
//! nightly toolchain. A target *fails* by panicking: a parser that panics, or an `Ok` result
//! holding NaN or infinity (which a typed error should have refused).
#![allow(clippy::missing_panics_doc)] // panicking is how a fuzz target reports

use std::path::Path;

use pqrm::loaders::{RangeBearingNoise, parse_csv, parse_g2o, parse_truth_csv, read_mrclam};
use qsr_core::binary::{
    BinaryAlgebra, BinaryCalculus, BinaryNetwork, SolveOptions, SplitSet, close_binary,
    from_gqr_csp_str, solve_binary,
};
use qsr_core::reason::{Algebra, Network, TableScope, close};
use qsr_core::{Calculus, Point2};

/// A fuzz target's body.
pub type Target = fn(&[u8]);

/// Every target by name (the names of `fuzz/fuzz_targets/*.rs` and `fuzz/corpus/*/`).
pub const TARGETS: [(&str, Target); 16] = [
    ("spec_toml", spec_toml),
    ("spec_json", spec_json),
    ("classify_row", classify_row),
    ("observation_csv", observation_csv),
    ("truth_csv", truth_csv),
    ("g2o", g2o),
    ("mrclam", mrclam),
    ("beliefs", beliefs),
    ("world", world),
    ("saved_map", saved_map),
    ("prob_line", prob_line),
    ("network", network),
    ("binary_network", binary_network),
    ("calculus_tables", calculus_tables),
    ("mcap", mcap),
    ("study_config", study_config),
];

/// Panics when a `Debug` rendering holds a NaN or an infinity.
pub fn assert_finite<T: std::fmt::Debug>(what: &str, value: &T) {
    let text = format!("{value:?}");
    let bad = text
        .split(|c: char| !(c.is_ascii_alphanumeric() || c == '.' || c == '-' || c == '_'))
        .find(|t| matches!(*t, "NaN" | "inf" | "-inf"));
    assert!(bad.is_none(), "{what}: accepted input produced {bad:?}");
}

fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// A few probe points in the normalised plane, including far and boundary ones.
const PROBES: [[f64; 2]; 6] = [
    [0.0, 0.0],
    [-0.3, 0.5],
    [0.5, 1.0],
    [2.0, -3.0],
    [-1e6, 1e6],
    [0.0, 0.5],
];

fn exercise(c: &Calculus) {
    for [x, y] in PROBES {
        let s = c.classify_normalised(&Point2::new(x, y));
        assert!(
            s.index() < c.n_states(),
            "{}: state {s} out of range",
            c.name()
        );
    }
}

/// A calculus spec in TOML (constraints or raster).
pub fn spec_toml(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(c) = Calculus::from_toml_str(t)
    {
        exercise(&c);
    }
}

/// A calculus spec in JSON.
pub fn spec_json(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(c) = Calculus::from_json_str(t)
    {
        exercise(&c);
    }
}

/// A row of numbers (as `qrm calculus classify` reads them) for every frame kind and OPRA.
pub fn classify_row(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let Ok(row) = t
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<Result<Vec<f64>, _>>()
    else {
        return;
    };
    for name in ["edc", "star-8", "front-between-behind"] {
        if let Ok(c) = Calculus::builtin(name)
            && let Ok(s) = c.classify_row(&row)
        {
            assert!(s.index() < c.n_states());
        }
    }
    for name in ["opra-2", "star-8"] {
        if let Ok(c) = BinaryCalculus::builtin(name)
            && let Ok(s) = c.classify_row(&row)
        {
            assert!(s.index() < c.n_states());
        }
    }
}

/// An observation CSV.
pub fn observation_csv(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(d) = parse_csv(t, Path::new("fuzz.csv"))
    {
        assert_finite("observation CSV", &d);
    }
}

/// A truth CSV.
pub fn truth_csv(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(g) = parse_truth_csv(t, Path::new("truth.csv"))
    {
        assert_finite("truth CSV", &g);
    }
}

/// An MCAP log (ROS 2 bag, Foxglove or qrm log), read as `qrm map --format mcap` reads it:
/// topics chosen by the reader, a named scan topic, and a truncated file allowed.
pub fn mcap(data: &[u8]) {
    let path = Path::new("fuzz.mcap");
    for options in [
        qrm_log::ReadOptions::default(),
        qrm_log::ReadOptions::default().with_topic("/scan"),
        qrm_log::ReadOptions::default().allowing_truncated(),
    ] {
        if let Ok(r) = qrm_log::read_mcap_bytes(data, path, &options) {
            assert_finite("mcap", &r.dataset);
        }
    }
}

/// A g2o file.
pub fn g2o(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(d) = parse_g2o(t, Path::new("fuzz.g2o"))
    {
        assert_finite("g2o", &d);
    }
}

/// A MRCLAM directory: the input's parts, split at lines `%%`, become
/// `Landmark_Groundtruth.dat`, `Barcodes.dat`, `Robot1_Measurement.dat`, ...
pub fn mrclam(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let dir = std::env::temp_dir().join(format!(
        "qrm-fuzz-mrclam-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    if std::fs::create_dir_all(&dir).is_err() {
        return;
    }
    let names = [
        "Landmark_Groundtruth.dat",
        "Barcodes.dat",
        "Robot1_Measurement.dat",
        "Robot2_Measurement.dat",
    ];
    for (name, part) in names.iter().zip(t.split("\n%%\n")) {
        let _ = std::fs::write(dir.join(name), part);
    }
    let noise = RangeBearingNoise {
        sigma_range: 0.1,
        sigma_bearing: 0.05,
    };
    if let Ok(d) = read_mrclam(&dir, noise) {
        assert_finite("MRCLAM", &d);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// SERGE's beliefs JSON.
pub fn beliefs(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(b) = serge::BeliefSet::from_json_str(t, "fuzz")
    {
        assert_finite("beliefs", &b);
    }
}

/// A simulator world file.
pub fn world(data: &[u8]) {
    if let Some(t) = text(data)
        && let Ok(w) = sim2d::World::from_toml(t)
    {
        assert_finite("world", w.spec());
    }
}

/// A saved PQRM map, JSON or binary. Whatever a loader accepts must survive every later
/// stage the `reason` and `pqrm` commands run on a map: its network by every selection, the
/// check, inference, merging and saving again (issue 39: a set repeating an id loaded, then
/// `reason check` panicked).
pub fn saved_map(data: &[u8]) {
    let loaded = match text(data) {
        Some(t) if !pqrm::map_file::is_binary(data) => pqrm::Pqrm::from_json(t),
        _ => pqrm::Pqrm::from_binary(data),
    };
    let Ok(m) = loaded else { return };
    if let Some(h) = m.mean_entropy() {
        assert!(h.is_finite(), "saved map: entropy {h}");
    }
    for (_, b) in m.iter().take(64) {
        assert_finite("saved map beliefs", &b.probabilities());
    }
    // A loaded map must save again, in both formats.
    let json = m.to_json().expect("saved map: loads but does not save");
    let bin = m
        .to_binary()
        .expect("saved map: loads but does not save binary");
    // The first few hundred maps a process accepts go through every later stage; each stage
    // builds the calculus anew (~2 ms in a debug build, its reasoning tables ~6 ms), too slow
    // for all 5,000 mutations of the corpus test.
    static DEEP: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    if DEEP.fetch_add(1, std::sync::atomic::Ordering::Relaxed) >= 400 {
        return;
    }
    assert!(
        pqrm::Pqrm::from_json(&json).is_ok(),
        "saved map: its JSON does not load"
    );
    assert!(
        pqrm::Pqrm::from_binary(&bin).is_ok(),
        "saved map: its binary does not load"
    );
    // `pqrm merge`: with itself.
    let _ = pqrm::robots::merge_maps(&[m.clone(), m.clone()]);
    // `reason export`: every selection.
    for selection in [
        pqrm::reason::Selection::MostLikely,
        pqrm::reason::Selection::AboveProbability(0.3),
    ] {
        let _ = pqrm::reason::to_network(&m, selection);
    }
    // `reason check` and `reason infer`, where their tables are cheap to derive.
    if m.calculus().n_states() <= 9 && pqrm::reason::landmarks(&m).len() <= 12 {
        let _ = pqrm::reason::check(&m);
        if let Ok(mut inferrer) =
            pqrm::reason::Inferrer::new(&m, pqrm::reason::InferOptions::default())
        {
            for i in inferrer.infer_unseen() {
                assert_finite("inferred beliefs", &i);
            }
        }
    }
}

/// A `qrm pqrm prob` line.
pub fn prob_line(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let Ok(q) = pqrm::study::ObservationQuery::from_json(t, Path::new("stdin"), 1) else {
        return;
    };
    let Ok(c) = Calculus::builtin("double-cross") else {
        return;
    };
    if let Ok(p) = q.probabilities(&c, 64, 1.0, 0) {
        assert_finite("prob", &p);
        let sum: f64 = p.iter().sum();
        assert!((sum - 1.0).abs() < 1e-9, "probabilities sum to {sum}");
    }
}

/// The most points a fuzzed network may have before closure is skipped (closure is cubic;
/// a long input is not a hang).
const CLOSE_POINTS: usize = 10;

/// A ternary constraint network (JSON or SparQ) over double-cross, closed when small.
pub fn network(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let Ok(c) = Calculus::builtin("double-cross") else {
        return;
    };
    let parsed = match t.trim_start().chars().next() {
        Some('{') => Network::from_json_str(&c, t),
        _ => Network::from_sparq_str(&c, t),
    };
    if let Ok(net) = parsed
        && net.n_points() <= CLOSE_POINTS
        && let Ok(alg) = Algebra::of(&c, TableScope::Sound)
    {
        let _ = close(net, &alg);
    }
}

/// A binary network (JSON or SparQ) over OPRA-1, closed when small.
pub fn binary_network(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let Ok(c) = BinaryCalculus::builtin("opra-1") else {
        return;
    };
    let parsed = match t.trim_start().chars().next() {
        Some('{') => BinaryNetwork::from_json_str(&c, t).map(|n| vec![n]),
        Some(d) if d.is_ascii_digit() || d == '#' => {
            from_gqr_csp_str(&c, t).map(|v| v.into_iter().map(|g| g.network).collect())
        }
        _ => BinaryNetwork::from_sparq_str(&c, t).map(|n| vec![n]),
    };
    for net in parsed.unwrap_or_default() {
        if net.n_points() <= CLOSE_POINTS {
            let _ = close_binary(net.clone());
            for restarts in [true, false] {
                let options = SolveOptions {
                    max_nodes: 200,
                    restarts,
                    ..SolveOptions::default()
                };
                let _ = solve_binary(net.clone(), &options);
            }
        }
    }
}

/// A binary calculus's tables: GQR's converse and composition texts (split at a line `%%`,
/// the identity the first converse line's relation) or a SparQ definition; its laws checked
/// and a small network closed and solved when it loads.
pub fn calculus_tables(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let loaded = match t.split_once("\n%%\n") {
        Some((conv, comp)) => {
            let identity = conv.split("::").next().unwrap_or("").trim();
            BinaryAlgebra::from_gqr_tables("fuzz", conv, comp, identity, None)
        }
        None => BinaryAlgebra::from_sparq_str(t),
    };
    let Ok(alg) = loaded else { return };
    if alg.n_states() > 64 {
        return;
    }
    let _ = alg.check();
    let _ = alg.to_gqr_tables();
    let Ok(mut net) = BinaryNetwork::universal(&alg, ["A", "B", "C", "D"]) else {
        return;
    };
    let first = qsr_core::reason::StateSet::from_states(alg.n_states(), alg.states().take(1));
    net.constrain(0, 1, &first);
    let _ = close_binary(net.clone());
    // The same text read as a split set (GQR's cover-set format); one that loads is searched with.
    let split = SplitSet::from_gqr_str(&alg, t, "fuzz").ok();
    let options = SolveOptions {
        max_nodes: 200,
        split,
        restarts: true,
    };
    let _ = solve_binary(net, &options);
}

/// A study config file (`qrm study run NAME --config FILE`): its fields laid over every
/// study's built-in config, then the study's own check (the one every front end runs before
/// any work). Whatever the file holds, the check refuses or accepts; it never panics.
pub fn study_config(data: &[u8]) {
    let Some(t) = text(data) else { return };
    let Ok(top) = studies::config::from_toml(t, "fuzz.toml") else {
        return;
    };
    for study in studies::registry::STUDIES {
        let mut config = study.config(false, 0);
        studies::config::overlay(&mut config, top.clone());
        let _ = study.check(&config);
    }
}
