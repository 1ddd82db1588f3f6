//! How a Rust robot embeds the mapper: its perception produces landmark observations frame by
//! frame (here a simulated range-bearing sensor on a robot driving a circle), the mapper folds
//! them in, and the robot asks for beliefs when it needs them.
//!
//! Run: `cargo run -p pqrm --example perception_loop`

use pqrm::{LandmarkId, LandmarkSet, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::Calculus;

/// Landmark positions the robot does not know (used only to simulate its sensor).
const WORLD: [(u32, [f64; 2]); 5] = [
    (1, [2.0, 8.0]),
    (2, [9.0, 9.0]),
    (3, [5.0, 2.0]),
    (4, [1.0, 3.0]),
    (5, [8.0, 4.0]),
];

fn perceive(step: usize) -> Scan {
    // The robot circles the centre; it reports range and bearing to what it sees.
    let th = step as f64 * 0.3;
    let (px, py, heading) = (
        5.0 + 4.0 * th.cos(),
        5.5 + 4.0 * th.sin(),
        th + std::f64::consts::FRAC_PI_2,
    );
    let observations = WORLD
        .iter()
        .filter_map(|(id, p)| {
            let (dx, dy) = (p[0] - px, p[1] - py);
            let range = dx.hypot(dy);
            let bearing = dy.atan2(dx) - heading;
            // A sensor with 5 cm range and 1° bearing noise; the robot reports its model.
            (range < 7.0).then(|| {
                Observation::from_range_bearing(
                    LandmarkId(*id),
                    range,
                    bearing,
                    0.05,
                    1f64.to_radians(),
                )
            })
        })
        .collect::<Result<Vec<_>, _>>()
        .expect("finite measurements");
    Scan::new(step as f64 * 0.1, 0, observations).expect("one observation per landmark")
}

/// The loop; returns the belief the robot ends with for {1, 2 : 3}.
pub fn run() -> Vec<f64> {
    let edc = Calculus::builtin("edc").expect("built in");
    let mut map = Pqrm::new(
        edc.clone(),
        PqrmConfig {
            samples: 300,
            seed: 42,
            ..PqrmConfig::default()
        },
    )
    .expect("valid config");
    for step in 0..30 {
        let scan = perceive(step);
        let report = map.update(&scan).expect("well-formed scan");
        if step % 10 == 0 {
            println!(
                "step {step:>2}: {} landmarks, {} sets updated ({} new)",
                scan.observations.len(),
                report.observed,
                report.new
            );
        }
    }
    let set = LandmarkSet::new(1, 2, 3);
    let p = map.belief(set).expect("the robot saw 1, 2 and 3 together");
    let best = p
        .iter()
        .enumerate()
        .fold(0, |b, (i, v)| if *v > p[b] { i } else { b });
    println!(
        "{{1, 2 : 3}}: most likely EDC state {} with p = {:.3}; map has {} sets, mean entropy {:.3} nats",
        edc.labels()[best],
        p[best],
        map.len(),
        map.mean_entropy().unwrap_or(0.0)
    );
    p
}

fn main() {
    run();
}
