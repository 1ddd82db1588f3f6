//! The PQRM step's counts are exact integers: a faster kernel must give the same ones, bit
//! for bit, on every CPU and for any thread count. The fingerprints below were recorded from
//! the kernel of session 10 (f331344) before it was reworked; a change to the sampler, the
//! closed-form orderings or the sign keys that moves a single sample into another state
//! changes them.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::likelihood::{Orderings, step_counts};
use pqrm::{LandmarkId, Observation, Scan, ScanSamples};
use qsr_core::Calculus;

/// Twelve landmarks in general position (a fixed pseudo-random layout) plus three on a
/// lattice so that some samples land near boundaries.
fn scan() -> Scan {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let obs = (0..12)
        .map(|i| {
            let p = [next() * 20.0 - 10.0, next() * 20.0 - 10.0];
            Observation::isotropic(LandmarkId(i * 3 + 1), p, 0.2 + next() * 2.0).unwrap()
        })
        .collect();
    Scan::new(0.0, 0, obs).unwrap()
}

/// FNV-1a over the sets' ids and counts, in the order `step_counts` returns them.
fn fingerprint(calculus: &Calculus, orderings: Orderings, threads: usize) -> u64 {
    let samples = ScanSamples::draw(&scan(), 1500, 11, 2);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let counts = pool.install(|| step_counts(calculus, &samples, orderings).unwrap());
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut eat = |v: u32| {
        for b in v.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for (set, c) in &counts {
        set.ids().into_iter().for_each(&mut eat);
        c.iter().copied().for_each(&mut eat);
    }
    h
}

#[test]
fn step_counts_are_bit_identical_to_the_recorded_kernel() {
    let mut got = Vec::new();
    for name in qsr_core::BUILTIN_NAMES {
        let cal = Calculus::builtin(name).unwrap();
        if cal.frame() != qsr_core::FrameKind::Ternary {
            continue;
        }
        for orderings in [Orderings::All, Orderings::Canonical] {
            let one = fingerprint(&cal, orderings, 1);
            assert_eq!(
                one,
                fingerprint(&cal, orderings, 2),
                "{name} {orderings:?}: threads"
            );
            got.push(format!("{name} {orderings:?} {one:#018x}"));
        }
    }
    let expected: Vec<&str> = RECORDED
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if std::env::var_os("QRM_BLESS").is_some() {
        println!("{}", got.join("\n"));
    }
    assert_eq!(got, expected);
}

const RECORDED: &str = "
edc All 0xc88e847ee11c02a5
edc Canonical 0xe25f993095f89260
edc-lune All 0xdb6917e17e0188b9
edc-lune Canonical 0x4547612e24575e0c
triple-cross All 0x3daf837cabe959e5
triple-cross Canonical 0xeae2d4d203a9a720
double-cross All 0x3c0710e743946f71
double-cross Canonical 0xc4e3fef5bcb7aa94
quadrant All 0xdf2d5e8355852d45
quadrant Canonical 0x54532a57b2958445
left-right All 0x1753722f7f8dc531
left-right Canonical 0x87530c8c86779215
single-cross All 0xaf38ba00f9da20b5
single-cross Canonical 0x373d75acc9093eca
relative-distance All 0x1989750496d747e1
relative-distance Canonical 0xa50971d51145e233
tpcc All 0xc098ba8143944ea9
tpcc Canonical 0x050b2695aa3f3d67
";
