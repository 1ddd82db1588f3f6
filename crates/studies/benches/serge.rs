//! SERGE on the benchmark problem: K = 55 lab-like beliefs on a 200 × 200 grid,
//! T = 5,500 trials (100·K, the thesis's suggestion). Goal: ≤ 2 s on a 2-core machine.
//!
//! First a side-by-side measurement against the straightforward implementation
//! ([`serge::baseline::run_naive`], which scores every candidate merge from the cells) on the
//! same problem, same seed and same random merge orders, printed as a per-trial ratio; then
//! criterion timings of the parts (cell masses, one full run).
//!
//! `cargo bench -p studies --bench serge` (the lab dataset is a study's; the bench measures
//! the `serge` crate)

#![allow(clippy::unwrap_used, missing_docs)]

use std::hint::black_box;
use std::time::Instant;

use criterion::{Criterion, criterion_group};
use serge::{CellMasses, Grid, Serge, SergeParams, baseline};
use studies::serge::datasets::Dataset;

fn problem() -> CellMasses {
    let data = Dataset::generate("lab", 0).unwrap();
    let beliefs = data.beliefs(|_, _| true, 0).unwrap();
    let grid = Grid::around(&beliefs, 200, 200).unwrap();
    CellMasses::compute(&beliefs, grid).unwrap()
}

fn side_by_side() {
    let t = Instant::now();
    let masses = problem();
    let t_masses = t.elapsed().as_secs_f64();
    let serge = Serge::new(&masses).unwrap();
    let trials = 5_500;
    let params = SergeParams::new(20, 2.0).trials(trials).seed(1);
    serge.run(&params).unwrap(); // warm
    let t = Instant::now();
    let fast = serge.run(&params).unwrap();
    let t_fast = t.elapsed().as_secs_f64();
    let naive_trials = 3;
    let small = params.trials(naive_trials);
    let t = Instant::now();
    let slow = baseline::run_naive(&serge, &small).unwrap();
    let t_slow = t.elapsed().as_secs_f64() / naive_trials as f64;
    let same = serge.run(&small).unwrap();
    assert_eq!(
        same.cell_region, slow.cell_region,
        "baseline and incremental disagree"
    );
    let per_trial = t_fast / trials as f64;
    println!(
        "serge: K = 55, 200×200 grid, {} initial regions; masses {:.3} s; \
         {trials} trials in {:.3} s ({:.1} µs/trial, {} threads) → {} regions; \
         naive baseline {:.3} s/trial; ratio {:.0}x per trial",
        serge.n_initial_regions(),
        t_masses,
        t_fast,
        per_trial * 1e6,
        rayon::current_num_threads(),
        fast.n_regions,
        t_slow,
        t_slow / per_trial
    );
}

fn bench(c: &mut Criterion) {
    let masses = problem();
    let serge = Serge::new(&masses).unwrap();
    let mut g = c.benchmark_group("serge");
    g.sample_size(10);
    g.bench_function("cell_masses_55x200x200", |b| {
        let data = Dataset::generate("lab", 0).unwrap();
        let beliefs = data.beliefs(|_, _| true, 0).unwrap();
        let grid = Grid::around(&beliefs, 200, 200).unwrap();
        b.iter(|| CellMasses::compute(black_box(&beliefs), grid).unwrap());
    });
    g.bench_function("run_K55_T5500", |b| {
        let p = SergeParams::new(20, 2.0).trials(5_500).seed(1);
        b.iter(|| serge.run(black_box(&p)).unwrap());
    });
    g.finish();
}

criterion_group!(benches, bench);

fn main() {
    side_by_side();
    benches();
    Criterion::default().configure_from_args().final_summary();
}
