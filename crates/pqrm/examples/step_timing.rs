//! Best-of-N timing of one PQRM step (10 landmarks, s = 1000, EDC, every ordering) on one
//! thread (or the number given): the draws alone, the counting kernel (`step_counts`, draws
//! included), the filter alone (`apply_counts` of a step's counts) and the whole update,
//! interleaved, best wall time of each — what each part of a
//! step costs, so what any kernel change can gain at most. Steadier than a mean on a loaded machine; used to
//! compare kernel changes (the fair comparison with numba is
//! `crates/qrm-py/benches/sampling_numpy.py`).
//!
//! `cargo run --release -p pqrm --example step_timing [rounds] [threads]`
#![allow(clippy::unwrap_used, clippy::print_stdout)] // an example: a panic is the report

use pqrm::likelihood::{Orderings, step_counts};
use pqrm::{LandmarkId, Observation, Scan, ScanSamples};
use qsr_core::Calculus;
use rand::{RngExt, SeedableRng};
use std::time::Instant;

fn main() {
    let rounds: usize = std::env::args().nth(1).map_or(200, |v| v.parse().unwrap());
    let threads: usize = std::env::args().nth(2).map_or(1, |v| v.parse().unwrap());
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let obs = (0..10)
        .map(|i| {
            let p = [rng.random_range(0.0..100.0), rng.random_range(0.0..100.0)];
            Observation::isotropic(LandmarkId(i), p, 10.0).unwrap()
        })
        .collect();
    let scan = Scan::new(0.0, 0, obs).unwrap();
    let edc = Calculus::builtin("edc").unwrap();
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut map = pqrm::Pqrm::new(edc.clone(), pqrm::PqrmConfig::default()).unwrap();
    let (mut draw, mut step, mut filter, mut update) =
        (f64::INFINITY, f64::INFINITY, f64::INFINITY, f64::INFINITY);
    let counts = pool.install(|| {
        step_counts(&edc, &ScanSamples::draw(&scan, 1000, 7, 0), Orderings::All).unwrap()
    });
    pool.install(|| {
        for r in 0..rounds {
            let t = Instant::now();
            std::hint::black_box(ScanSamples::draw(&scan, 1000, 7, r as u64));
            draw = draw.min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            let samples = ScanSamples::draw(&scan, 1000, 7, r as u64);
            std::hint::black_box(step_counts(&edc, &samples, Orderings::All).unwrap());
            step = step.min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            std::hint::black_box(map.apply_counts(&counts).unwrap());
            filter = filter.min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            std::hint::black_box(map.update(&scan).unwrap());
            update = update.min(t.elapsed().as_secs_f64());
        }
    });
    let per = 1e9 / 720_000.0;
    println!(
        "best of {rounds}, {threads} thread(s): draws {:.3} ms, step_counts {:.3} ms ({:.2} ns per ordered triplet-sample), filter {:.3} ms, update {:.3} ms ({:.2} ns)",
        draw * 1e3,
        step * 1e3,
        step * per,
        filter * 1e3,
        update * 1e3,
        update * per
    );
}
