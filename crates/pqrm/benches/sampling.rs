//! One PQRM step as in the Monte Carlo study: 10 landmarks, s = 1000 samples each, every
//! ordered triplet (720) classified in the EDC and histogrammed — 720,000 triplet-samples.
//! Measured on one core and on two. The comparison with NumPy and numba is
//! `crates/qrm-py/benches/sampling_numpy.py` (through the wheel, every implementation timed
//! the same way in one process); `examples/step_timing.rs` gives best-of-N figures that hold
//! up on a loaded machine better than criterion's mean.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use pqrm::likelihood::{Orderings, step_counts};
use pqrm::{LandmarkId, Observation, Scan, ScanSamples};
use qsr_core::Calculus;
use rand::{RngExt, SeedableRng};

/// Landmarks per step and samples per landmark.
const M: usize = 10;
const S: usize = 1000;

fn scan() -> Scan {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let obs = (0..M)
        .map(|i| {
            let p = [rng.random_range(0.0..100.0), rng.random_range(0.0..100.0)];
            Observation::isotropic(LandmarkId(i as u32), p, 10.0).expect("valid")
        })
        .collect();
    Scan::new(0.0, 0, obs).expect("valid")
}

fn bench(c: &mut Criterion) {
    let edc = Calculus::builtin("edc").expect("built in");
    let scan = scan();
    let mut g = c.benchmark_group("pqrm_step_m10_s1000");
    g.sample_size(20);
    g.throughput(Throughput::Elements((M * (M - 1) * (M - 2) * S) as u64));
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        g.bench_function(format!("qrm_{threads}_thread"), |b| {
            b.iter(|| {
                pool.install(|| {
                    let samples = ScanSamples::draw(&scan, S, 7, 0);
                    step_counts(&edc, &samples, Orderings::All).expect("distinct landmarks")
                })
            });
        });
    }
    g.finish();
    // The whole update (sampling, counts, Bayes filter) as the Python binding calls it.
    let mut g = c.benchmark_group("pqrm_update_m10_s1000");
    g.sample_size(20);
    g.throughput(Throughput::Elements((M * (M - 1) * (M - 2) * S) as u64));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let mut map = pqrm::Pqrm::new(edc.clone(), pqrm::PqrmConfig::default()).expect("valid");
    g.bench_function("qrm_1_thread", |b| {
        b.iter(|| pool.install(|| map.update(&scan).expect("distinct landmarks")));
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
