//! EDC classification throughput on 10^7 random triplets, one core and two.
//!
//! The baseline is the vectorised NumPy implementation of the same rule in
//! `crates/qrm-py/benches/classify_numpy.py` (with the wheel it imports), which runs this
//! bench (or reads its last result) and prints the ratio.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use qsr_core::{Calculus, StateId};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

/// Triplets per iteration (the 10^7).
const N: usize = 10_000_000;

/// Same generator as the NumPy script: coordinates uniform in [0, 100).
fn triplets() -> Vec<[f64; 6]> {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    (0..N)
        .map(|_| std::array::from_fn(|_| rng.random_range(0.0..100.0)))
        .collect()
}

fn bench(c: &mut Criterion) {
    let edc = Calculus::builtin("edc").expect("edc is built in");
    let t = triplets();
    let mut out = vec![StateId(0); N];
    let mut g = c.benchmark_group("edc_classify_1e7");
    g.sample_size(10);
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("qrm_1_thread", |b| {
        b.iter(|| edc.classify_triplets(&t, &mut out).expect("valid triplets"));
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("thread pool");
    g.bench_function("qrm_2_threads", |b| {
        b.iter(|| {
            pool.install(|| {
                t.par_chunks(1 << 16)
                    .zip(out.par_chunks_mut(1 << 16))
                    .for_each(|(ti, oi)| edc.classify_triplets(ti, oi).expect("valid triplets"));
            });
        });
    });
    g.finish();
    // Where the time goes: the partition alone, on points already in the normalised frame
    // (what `classify_triplets` does after normalising each row), and the normalisation alone.
    let (xs, ys): (Vec<f64>, Vec<f64>) = t
        .iter()
        .map(|r| {
            let (dx, dy) = (r[2] - r[0], r[3] - r[1]);
            let (vx, vy) = (r[4] - r[0], r[5] - r[1]);
            let l = dx * dx + dy * dy;
            (-(dx * vy - dy * vx) / l, (dx * vx + dy * vy) / l)
        })
        .unzip();
    let mut states = vec![0u16; N];
    let mut g = c.benchmark_group("edc_parts_1e7");
    g.sample_size(10);
    g.throughput(Throughput::Elements(N as u64));
    g.bench_function("partition_only_1_thread", |b| {
        b.iter(|| edc.classify_normalised_into(&xs, &ys, &mut states));
    });
    let (mut nx, mut ny) = (vec![0.0f64; N], vec![0.0f64; N]);
    g.bench_function("normalise_only_1_thread", |b| {
        b.iter(|| {
            for ((r, x), y) in t.iter().zip(nx.iter_mut()).zip(ny.iter_mut()) {
                let (dx, dy) = (r[2] - r[0], r[3] - r[1]);
                let (vx, vy) = (r[4] - r[0], r[5] - r[1]);
                let inv = 1.0 / (dx * dx + dy * dy);
                *x = -(dx * vy - dy * vx) * inv;
                *y = (dx * vx + dy * vy) * inv;
            }
            std::hint::black_box((&nx, &ny));
        });
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
