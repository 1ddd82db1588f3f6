//! Algebraic closure over EDC networks of n = 10 … 200 points (issue 13 §1): wall time per n
//! on this machine's cores and the fitted exponent of time ∝ n^k.
//!
//! Two networks per n, both qualified from the same random points: *scenario* (every
//! triplet known, as a map's ML states give; closure must only verify) and *half known* (each
//! unordered triplet forgotten with probability 1/2, as a map of a short-range sensor leaves
//! them; closure infers). Run: `cargo bench -p qsr-core --bench closure [-- MAX_N]`.
//! Plain timing (median of 3 runs) rather than criterion: one n = 200 closure takes seconds.
#![allow(clippy::unwrap_used, clippy::print_stdout)] // a benchmark binary reports on stdout

use std::time::Instant;

use qsr_core::reason::{Algebra, ClosureOptions, Network, TableScope, close_with};
use qsr_core::{Calculus, Point2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn network(calc: &Calculus, n: usize, forget: f64, seed: u64) -> Network {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let pts: Vec<Point2<f64>> = (0..n)
        .map(|_| Point2::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0)))
        .collect();
    let names: Vec<String> = (0..n).map(|i| format!("L{i}")).collect();
    let mut net = Network::from_points(calc, names, &pts).unwrap();
    for a in 0..n {
        for b in a + 1..n {
            for c in b + 1..n {
                if rng.random::<f64>() < forget {
                    net.relax(a, b, c);
                }
            }
        }
    }
    net
}

fn median_secs(mut f: impl FnMut() -> f64) -> f64 {
    let mut t: Vec<f64> = (0..3).map(|_| f()).collect();
    t.sort_by(f64::total_cmp);
    t[1]
}

/// Least-squares slope of ln t against ln n.
fn exponent(rows: &[(usize, f64)]) -> f64 {
    let xs: Vec<f64> = rows.iter().map(|(n, _)| (*n as f64).ln()).collect();
    let ys: Vec<f64> = rows.iter().map(|(_, t)| t.ln()).collect();
    let k = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / k, ys.iter().sum::<f64>() / k);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    sxy / sxx
}

fn main() {
    let max_n: usize = std::env::args()
        .skip(1)
        .find_map(|a| a.parse().ok())
        .unwrap_or(200);
    let calc = Calculus::builtin("edc").unwrap();
    let t0 = Instant::now();
    let alg = Algebra::of(&calc, TableScope::Sound).unwrap();
    println!(
        "EDC tables derived in {:.2} s; {} threads",
        t0.elapsed().as_secs_f64(),
        rayon::current_num_threads()
    );
    println!("| n | ordered triplets | scenario (s) | half known (s) | states removed |");
    println!("|---|---|---|---|---|");
    let mut scen = Vec::new();
    let mut half = Vec::new();
    let options = ClosureOptions::without_explanation();
    for n in [10, 20, 30, 50, 70, 100, 140, 200]
        .into_iter()
        .filter(|n| *n <= max_n)
    {
        let exact = network(&calc, n, 0.0, n as u64);
        let partial = network(&calc, n, 0.5, n as u64);
        let ts = median_secs(|| {
            let t = Instant::now();
            let c = close_with(exact.clone(), &alg, &options).unwrap();
            assert!(c.is_consistent());
            t.elapsed().as_secs_f64()
        });
        let mut removed = 0;
        let th = median_secs(|| {
            let t = Instant::now();
            let c = close_with(partial.clone(), &alg, &options).unwrap();
            assert!(c.is_consistent());
            removed = partial.total_states() - c.network.total_states();
            t.elapsed().as_secs_f64()
        });
        println!(
            "| {n} | {} | {ts:.3} | {th:.3} | {removed} |",
            exact.n_triplets()
        );
        scen.push((n, ts));
        half.push((n, th));
    }
    let tail = |v: &[(usize, f64)]| {
        v.iter()
            .copied()
            .filter(|(n, _)| *n >= 30)
            .collect::<Vec<_>>()
    };
    println!(
        "\nfitted exponent (n ≥ 30): scenario {:.2}, half known {:.2}",
        exponent(&tail(&scen)),
        exponent(&tail(&half))
    );
}
