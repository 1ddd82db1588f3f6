//! The PQRM step's counts are exact integers: a faster kernel must give the same ones, bit
//! for bit, on every CPU and for any thread count. The fingerprints below were recorded from
//! the kernel of session 10 (f331344) before it was reworked; a change to the closed-form
//! orderings or the sign keys that moves a single sample into another state changes them.
//! The samples are drawn here the way the sampler drew them then (ChaCha8 per landmark), so
//! the kernel stays pinned to those counts when the sampler's generator changes; the
//! sampler's own stream is pinned separately (`draws_are_the_recorded_stream`).
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::likelihood::{Orderings, step_counts};
use pqrm::sampler::mix;
use pqrm::{LandmarkId, Observation, Scan, ScanSamples};
use qsr_core::Calculus;
use rand::SeedableRng;
use rand_distr::{Distribution, StandardNormal};

/// `s` samples per landmark as the sampler drew them until 2026-11-29: ChaCha8 seeded from
/// `(seed, step, id)`, two standard normals per sample through the Cholesky factor.
fn recorded_draw(scan: &Scan, s: usize, seed: u64, step: u64) -> ScanSamples {
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for o in &scan.observations {
        let mut rng =
            rand_chacha::ChaCha8Rng::seed_from_u64(mix(seed ^ mix(step ^ mix(u64::from(o.id.0)))));
        let [l11, l21, l22] = o.cholesky();
        let (mut x, mut y) = (Vec::with_capacity(s), Vec::with_capacity(s));
        for _ in 0..s {
            let z1: f64 = StandardNormal.sample(&mut rng);
            let z2: f64 = StandardNormal.sample(&mut rng);
            x.push(o.mean[0] + l11 * z1);
            y.push(o.mean[1] + l21 * z1 + l22 * z2);
        }
        xs.push(x);
        ys.push(y);
    }
    let ids = scan.observations.iter().map(|o| o.id).collect();
    ScanSamples::from_columns(ids, xs, ys).unwrap()
}

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
    let samples = recorded_draw(&scan(), 1500, 11, 2);
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

/// FNV-1a over every sample's bits, landmark by landmark: the sampler's stream for a seed.
fn draws_fingerprint(samples: &ScanSamples) -> u64 {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for i in 0..samples.ids().len() {
        let (x, y) = samples.columns(i);
        for v in x.iter().chain(y) {
            for b in v.to_bits().to_le_bytes() {
                h ^= u64::from(b);
                h = h.wrapping_mul(0x0100_0000_01b3);
            }
        }
    }
    h
}

/// Pins the sampler (seeded xoshiro256++ per landmark since 2026-11-29): a map's figures for
/// a seed change only when this does. Independent of the thread count, and of which other
/// landmarks a scan holds.
#[test]
fn draws_are_the_recorded_stream() {
    let scan = scan();
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap();
    let a = one.install(|| ScanSamples::draw(&scan, 1500, 11, 2));
    let b = two.install(|| ScanSamples::draw(&scan, 1500, 11, 2));
    assert_eq!(draws_fingerprint(&a), draws_fingerprint(&b));
    // one landmark alone draws what it drew among the others
    let alone = Scan::new(0.0, 0, vec![scan.observations[4]]).unwrap();
    let c = ScanSamples::draw(&alone, 1500, 11, 2);
    assert_eq!(c.columns(0), a.columns(4));
    // another step or seed is another stream
    assert_ne!(
        draws_fingerprint(&ScanSamples::draw(&scan, 1500, 11, 3)),
        draws_fingerprint(&a)
    );
    assert_ne!(
        draws_fingerprint(&ScanSamples::draw(&scan, 1500, 12, 2)),
        draws_fingerprint(&a)
    );
    if std::env::var_os("QRM_BLESS").is_some() {
        println!("draws {:#018x}", draws_fingerprint(&a));
    }
    assert_eq!(draws_fingerprint(&a), RECORDED_DRAWS);
}

/// [`draws_fingerprint`] of `ScanSamples::draw(&scan(), 1500, 11, 2)`.
const RECORDED_DRAWS: u64 = 0x31a7_283f_d175_e286;

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
