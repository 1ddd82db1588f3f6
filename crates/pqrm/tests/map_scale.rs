//! Maps that scale (issue 16 §3): the flat f32 store against a filter kept in f64, its
//! memory per set, and the binary map format — exact round trips and a typed error for every
//! kind of damage.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::BTreeMap;

use pqrm::likelihood::{LandmarkSet, Orderings, StepCounts, log_likelihood, step_counts};
use pqrm::map::normalise;
use pqrm::map_file::MapFormat;
use pqrm::metrics::entropy;
use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, PqrmError, Scan, ScanSamples};
use qsr_core::Calculus;

/// A small xorshift: the layouts below are fixed by their seed.
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// `steps` scans of a robot seeing a changing subset of `n` landmarks (noise 0.2–1.5 m).
fn recording(n: u32, steps: usize, seed: u64) -> Vec<Scan> {
    let mut s = seed | 1;
    let truth: Vec<([f64; 2], f64)> = (0..n)
        .map(|_| {
            (
                [uniform(&mut s) * 20.0, uniform(&mut s) * 20.0],
                0.2 + 1.3 * uniform(&mut s),
            )
        })
        .collect();
    (0..steps)
        .map(|t| {
            let obs = truth
                .iter()
                .enumerate()
                .filter(|(i, _)| (i + t) % 4 != 0)
                .map(|(i, (p, sigma))| {
                    let jitter = [
                        p[0] + sigma * (uniform(&mut s) - 0.5),
                        p[1] + sigma * (uniform(&mut s) - 0.5),
                    ];
                    Observation::isotropic(LandmarkId(i as u32), jitter, *sigma).unwrap()
                })
                .collect();
            Scan::new(t as f64, 0, obs).unwrap()
        })
        .collect()
}

fn config() -> PqrmConfig {
    PqrmConfig {
        samples: 500,
        seed: 5,
        ..PqrmConfig::default()
    }
}

fn mapped(n: u32, steps: usize) -> Pqrm {
    let mut map = Pqrm::new(Calculus::builtin("edc").unwrap(), config()).unwrap();
    for scan in recording(n, steps, 42) {
        map.update(&scan).unwrap();
    }
    map
}

/// The filter of eq. 2.10 written plainly in f64 (a `BTreeMap` of `Vec<f64>`), fed the same
/// counts: what the map computed before it stored f32.
#[test]
fn f32_storage_keeps_the_ml_states_and_entropies_of_an_f64_filter() {
    let edc = Calculus::builtin("edc").unwrap();
    let cfg = config();
    let mut map = Pqrm::new(edc.clone(), cfg).unwrap();
    let mut reference: BTreeMap<LandmarkSet, Vec<f64>> = BTreeMap::new();
    let scans = recording(9, 120, 7);
    let (mut compared, mut worst) = (0usize, 0.0f64);
    for (step, scan) in scans.iter().enumerate() {
        let samples = ScanSamples::draw(scan, cfg.samples, cfg.seed, step as u64);
        let counts = step_counts(&edc, &samples, Orderings::All).unwrap();
        map.apply_counts(&counts).unwrap();
        for (set, c) in &counts {
            let ll = log_likelihood(c, cfg.floor);
            let post = match reference.get(&set) {
                None => ll,
                Some(prior) => prior.iter().zip(&ll).map(|(a, b)| a + b).collect(),
            };
            reference.insert(set, normalise(post));
        }
        if step % 20 == 19 {
            assert_eq!(map.len(), reference.len());
            for (set, want) in &reference {
                let got = map.get(set).unwrap();
                let p: Vec<f64> = want.iter().map(|l| l.exp()).collect();
                let ml = (0..p.len()).fold(0, |b, i| if p[i] > p[b] { i } else { b });
                assert_eq!(usize::from(got.ml_state().0), ml, "step {step} {set:?}");
                let dh = (got.entropy() - entropy(&p)).abs();
                worst = worst.max(dh);
                compared += 1;
            }
        }
    }
    eprintln!("{compared} comparisons, largest entropy difference {worst:e} nats");
    assert!(compared > 3000, "{compared} comparisons");
    assert!(worst <= 1e-6, "entropy differs by {worst:e}");
}

#[test]
fn an_edc_map_costs_at_most_200_bytes_per_set() {
    // 30 landmarks all in view: 24,360 ordered sets
    let scans: Vec<Scan> = recording(30, 2, 3)
        .into_iter()
        .map(|s| {
            let obs = (0..30)
                .map(|i| {
                    let p = [f64::from(i % 6) * 3.1, f64::from(i / 6) * 2.7];
                    Observation::isotropic(LandmarkId(i), p, 0.5).unwrap()
                })
                .collect();
            Scan::new(s.t, 0, obs).unwrap()
        })
        .collect();
    let mut map = Pqrm::new(Calculus::builtin("edc").unwrap(), config()).unwrap();
    for s in &scans {
        map.update(s).unwrap();
    }
    assert_eq!(map.len(), 30 * 29 * 28);
    let per_set = map.heap_bytes() as f64 / map.len() as f64;
    assert!(per_set <= 200.0, "{per_set:.0} bytes per set");
    // and not suspiciously small: 20 f32 log-probabilities and a 12-byte key at least
    assert!(per_set >= 92.0, "{per_set:.0} bytes per set");
}

#[test]
fn a_map_updates_identically_on_one_thread_and_two() {
    let run = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| mapped(14, 6).to_binary().unwrap())
    };
    assert_eq!(run(1), run(2));
}

#[test]
fn a_set_twice_in_one_step_is_folded_in_twice() {
    let calc = Calculus::builtin("left-right").unwrap();
    let set = LandmarkSet::new(0, 1, 2);
    let mut twice = Pqrm::new(calc.clone(), PqrmConfig::default()).unwrap();
    twice
        .apply_counts(
            &StepCounts::from_vecs(&[(set, vec![700, 300]), (set, vec![600, 400])]).unwrap(),
        )
        .unwrap();
    let mut apart = Pqrm::new(calc, PqrmConfig::default()).unwrap();
    apart
        .apply_counts(&StepCounts::from_vecs(&[(set, vec![700, 300])]).unwrap())
        .unwrap();
    apart
        .apply_counts(&StepCounts::from_vecs(&[(set, vec![600, 400])]).unwrap())
        .unwrap();
    assert_eq!(twice.get(&set), apart.get(&set));
    assert_eq!(twice.get(&set).unwrap().updates, 2);
}

#[test]
fn binary_and_json_round_trips_are_exact() {
    let map = mapped(8, 5);
    let bytes = map.to_binary().unwrap();
    let back = Pqrm::from_binary(&bytes).unwrap();
    assert_eq!(back.to_binary().unwrap(), bytes);
    let via_json = Pqrm::from_json(&map.to_json().unwrap()).unwrap();
    assert_eq!(via_json.to_binary().unwrap(), bytes);
    assert_eq!(back.steps(), map.steps());
    // the mean entropy is summed exactly: the loaded map's set order (not the mapped one's
    // insertion order) and the thread count change no bit of it
    assert_eq!(back.mean_entropy(), map.mean_entropy());
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    assert_eq!(one.install(|| map.mean_entropy()), map.mean_entropy());
    for (set, b) in map.iter() {
        assert_eq!(back.get(set).unwrap(), b);
    }
    // the layout of the module docs: 32-byte prefix, header, 12 + 4 + 4·Q bytes per set, CRC
    let q = map.calculus().n_states();
    let header_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    assert_eq!(bytes.len(), 32 + header_len + map.len() * (16 + 4 * q) + 4);
    assert_eq!(
        u64::from_le_bytes(bytes[16..24].try_into().unwrap()),
        map.len() as u64
    );
}

#[test]
fn save_picks_the_format_from_the_extension_and_load_tells_them_apart() {
    let dir = std::env::temp_dir().join(format!("qrm-map-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let map = mapped(7, 3);
    for (name, format) in [("m.pqrm", MapFormat::Binary), ("m.json", MapFormat::Json)] {
        let path = dir.join(name);
        assert_eq!(MapFormat::from_path(&path), format);
        map.save(&path).unwrap();
        let head = std::fs::read(&path).unwrap();
        assert_eq!(head.starts_with(b"QRM-PQRM"), format == MapFormat::Binary);
        let back = Pqrm::load(&path).unwrap();
        assert_eq!(back.to_binary().unwrap(), map.to_binary().unwrap());
        assert!(!dir.join(format!("{name}.tmp")).exists());
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Recomputes the trailing CRC after a deliberate edit (so the check under test is the one
/// after the checksum).
fn reseal(bytes: &mut [u8]) {
    let body = bytes.len() - 4;
    let crc = crc32fast::hash(&bytes[..body]);
    bytes[body..].copy_from_slice(&crc.to_le_bytes());
}

fn format_error(bytes: &[u8]) -> String {
    match Pqrm::from_binary(bytes) {
        Err(PqrmError::Format(m)) => m,
        Err(e) => panic!("not a format error: {e}"),
        Ok(_) => panic!("damaged bytes were accepted"),
    }
}

#[test]
fn every_kind_of_damage_is_a_typed_error_naming_the_field() {
    let good = mapped(6, 3).to_binary().unwrap();
    let header_len = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let tables = 32 + header_len;
    // empty, cut inside the prefix, the header, the tables and the checksum
    for cut in [
        0,
        5,
        20,
        tables - 3,
        tables + 7,
        good.len() / 2,
        good.len() - 1,
    ] {
        let m = format_error(&good[..cut]);
        assert!(
            m.contains("magic") || m.contains("n_sets"),
            "cut at {cut}: {m}"
        );
    }
    // one byte longer
    let mut long = good.clone();
    long.push(0);
    assert!(format_error(&long).contains("n_sets"));
    // not a map
    let mut other = good.clone();
    other[0] = b'X';
    assert!(format_error(&other).contains("magic"));
    // a flipped bit anywhere in the body
    for at in [9, 30, tables + 1, good.len() - 10] {
        let mut flipped = good.clone();
        flipped[at] ^= 0x10;
        let m = format_error(&flipped);
        assert!(
            m.contains("crc32") || m.contains("version") || m.contains("n_sets"),
            "flip at {at}: {m}"
        );
    }
    // another version
    let mut v2 = good.clone();
    v2[8..12].copy_from_slice(&2u32.to_le_bytes());
    assert!(format_error(&v2).contains("version"));
    // sizes that cannot be: a huge set count is refused before anything is allocated
    let mut huge = good.clone();
    huge[16..24].copy_from_slice(&u64::MAX.to_le_bytes());
    reseal(&mut huge);
    assert!(format_error(&huge).contains("n_sets"));
    let mut states = good.clone();
    states[24..28].copy_from_slice(&0u32.to_le_bytes());
    reseal(&mut states);
    assert!(format_error(&states).contains("n_sets"));
    // a header that is not the header
    let mut header = good.clone();
    header[32] = b'[';
    reseal(&mut header);
    assert!(format_error(&header).contains("header"));
    // a belief that is not a distribution (first log-probability of the last row set to +1)
    let q = 20;
    let mut belief = good.clone();
    let last_row = good.len() - 4 - 4 * q;
    belief[last_row..last_row + 4].copy_from_slice(&1.0f32.to_le_bytes());
    reseal(&mut belief);
    assert!(format_error(&belief).contains("not a normalised log-distribution"));
    let mut nan = good.clone();
    nan[last_row..last_row + 4].copy_from_slice(&f32::NAN.to_le_bytes());
    reseal(&mut nan);
    assert!(format_error(&nan).contains("not a normalised log-distribution"));
    // the same set twice (the second set's ids overwritten with the first's)
    let mut dup = good.clone();
    let first: [u8; 12] = dup[tables..tables + 12].try_into().unwrap();
    dup[tables + 12..tables + 24].copy_from_slice(&first);
    reseal(&mut dup);
    assert!(format_error(&dup).contains("twice"));
    // and the file path is named when loading
    let path = std::env::temp_dir().join(format!("qrm-damaged-{}.pqrm", std::process::id()));
    std::fs::write(&path, &good[..good.len() / 2]).unwrap();
    let e = Pqrm::load(&path).unwrap_err().to_string();
    assert!(e.contains(&path.display().to_string()), "{e}");
    std::fs::remove_file(&path).ok();
}
