//! Saving and loading a map of a million landmark sets (101 landmarks, all six orderings,
//! EDC) in the binary format and in JSON: issue 16's goal is ≤ 1 s each for the binary one.
//! The map is built from synthetic histograms (the sampler is not what is measured here).

use criterion::{Criterion, criterion_group, criterion_main};
use pqrm::likelihood::{LandmarkSet, StepCounts};
use pqrm::map_file::MapFormat;
use pqrm::{Pqrm, PqrmConfig};
use qsr_core::Calculus;

const LANDMARKS: u32 = 101;

fn million() -> Pqrm {
    let edc = Calculus::builtin("edc").expect("built in");
    let q = edc.n_states();
    let mut counts = StepCounts::new(q);
    let mut hist = vec![0u32; q];
    for a in 0..LANDMARKS {
        for b in 0..LANDMARKS {
            for c in 0..LANDMARKS {
                if a == b || b == c || a == c {
                    continue;
                }
                // 1000 samples spread over a few states, varying with the set
                hist.fill(0);
                let k = ((a * 7 + b * 13 + c * 29) % q as u32) as usize;
                hist[k] = 700;
                hist[(k + 1) % q] = 200;
                hist[(k + 5) % q] = 100;
                counts
                    .push(LandmarkSet::new(a, b, c), &hist)
                    .expect("q bins");
            }
        }
    }
    let mut map = Pqrm::new(edc, PqrmConfig::default()).expect("valid");
    map.apply_counts(&counts).expect("fits");
    map
}

fn bench(c: &mut Criterion) {
    let map = million();
    assert_eq!(map.len(), 999_900);
    let dir = std::env::temp_dir().join(format!("qrm-map-file-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut g = c.benchmark_group("map_1e6_sets");
    g.sample_size(10);
    for format in [MapFormat::Binary, MapFormat::Json] {
        let path = dir.join(format!("map.{}", format.extension()));
        g.bench_function(format!("save_{}", format.extension()), |b| {
            b.iter(|| map.save_as(&path, format).expect("written"));
        });
        g.bench_function(format!("load_{}", format.extension()), |b| {
            b.iter(|| Pqrm::load(&path).expect("read back"));
        });
    }
    g.finish();
    std::fs::remove_dir_all(&dir).ok();
}

criterion_group!(benches, bench);
criterion_main!(benches);
