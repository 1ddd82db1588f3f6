//! Worlds and maps the integration tests share.
#![allow(clippy::unwrap_used, dead_code)]

use std::collections::BTreeMap;

use qlink::{Layer, QualitativeMap};
use qsr_core::Calculus;

/// `n` landmarks uniform in a `side` × `side` square, from `seed`.
pub fn random_world(seed: u64, n: u32, side: f64) -> BTreeMap<u32, [f64; 2]> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|i| {
            (
                i,
                [rng.random_range(0.0..side), rng.random_range(0.0..side)],
            )
        })
        .collect()
}

/// The exact `quadrant` map a robot of range `range` would record of `positions`.
pub fn exact_map(positions: &BTreeMap<u32, [f64; 2]>, range: f64) -> QualitativeMap {
    let layer =
        Layer::exact_from_positions(Calculus::builtin("quadrant").unwrap(), positions, range)
            .unwrap();
    QualitativeMap::new(vec![layer]).unwrap()
}
