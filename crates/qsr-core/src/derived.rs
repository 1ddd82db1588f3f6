//! Derived tables computed once and shared, without a lock held while they are computed.
//!
//! Why this exists: a calculus derives its tables (neighbours, compose, permutations) on
//! first use and caches them in a `OnceLock`, and the derivations run in parallel on rayon's
//! pool. `OnceLock::get_or_init` blocks every other caller while its initialiser runs, and a
//! blocked rayon worker does no other work — so when rayon's workers call `get_or_init` on a
//! table another thread is deriving with parallel jobs, the jobs have no worker to run on and
//! every thread waits for ever (seen with two studies in one process: Monte Carlo trials on
//! both workers waiting for a neighbour graph whose derivation waited for them). Here the
//! table is computed with no lock held and only stored under it; two threads that miss the
//! cache at once both compute it, and since every derivation is deterministic they store the
//! same table.

use std::sync::OnceLock;

/// The value in `cell`, computed by `f` outside the cell's lock when it is empty (see the
/// module docs: the rayon-safe `get_or_init`).
pub(crate) fn get_or_derive<T>(cell: &OnceLock<T>, f: impl FnOnce() -> T) -> &T {
    if let Some(v) = cell.get() {
        return v;
    }
    let v = f();
    cell.get_or_init(|| v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rayon::prelude::*;
    use std::sync::Arc;
    use std::time::Duration;

    /// Regression: a thread outside the pool derived a table with parallel jobs while the
    /// pool's workers waited for that table under `get_or_init`: the jobs had no worker and
    /// every thread waited for ever (a Monte Carlo study and a Table 4.1 run in one process).
    /// With `get_or_derive` the workers derive it themselves and everyone gets the table.
    #[test]
    fn regression_workers_waiting_for_a_table_derived_in_parallel_do_not_deadlock() {
        let pool = Arc::new(
            rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .expect("a pool"),
        );
        let cell: Arc<OnceLock<u64>> = Arc::new(OnceLock::new());
        let derive =
            |pool: &rayon::ThreadPool| pool.install(|| (0..10_000u64).into_par_iter().sum());
        let (tx, rx) = std::sync::mpsc::channel();
        let outside = {
            let (pool, cell, tx) = (Arc::clone(&pool), Arc::clone(&cell), tx.clone());
            std::thread::spawn(move || {
                let v = *get_or_derive(&cell, || {
                    // the workers reach the cell while this derivation is under way
                    std::thread::sleep(Duration::from_millis(100));
                    derive(&pool)
                });
                let _ = tx.send(vec![v]);
            })
        };
        std::thread::sleep(Duration::from_millis(20));
        let inside = {
            let (pool2, cell) = (Arc::clone(&pool), Arc::clone(&cell));
            std::thread::spawn(move || {
                let got: Vec<u64> = pool2.install(|| {
                    (0..64)
                        .into_par_iter()
                        .map(|_| *get_or_derive(&cell, || derive(&pool2)))
                        .collect()
                });
                let _ = tx.send(got);
            })
        };
        for _ in 0..2 {
            let got = rx
                .recv_timeout(Duration::from_secs(30))
                .expect("deadlock: a caller still waits after 30 s");
            assert!(got.iter().all(|&v| v == 49_995_000), "{got:?}");
        }
        outside.join().expect("outside thread");
        inside.join().expect("inside thread");
    }
}
