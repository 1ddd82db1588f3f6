//! The simulated perception of the studies: sim2d's full occlusion behind qlink's
//! `Perception` trait.

#![allow(clippy::unwrap_used, missing_docs)]

use qlink::RangePerception;
use studies::world_perception::WorldPerception;

#[test]
fn occlusion_hides_landmarks_that_range_alone_would_show() {
    let sc = sim2d::scenario("qlink-200", 0, None)
        .unwrap()
        .with_landmark_radius(0.7)
        .unwrap();
    let occl = WorldPerception::new(&sc.world, 20.0);
    let landmarks: Vec<(u32, [f64; 2])> = sc.world.landmark_positions().collect();
    let range = RangePerception::new(&landmarks, 20.0);
    let (mut seen_occl, mut seen_range) = (0, 0);
    for i in 0..20 {
        let p = [10.0 * f64::from(i) + 3.0, 100.0];
        seen_occl += qlink::Perception::visible(&occl, p).len();
        seen_range += qlink::Perception::visible(&range, p).len();
    }
    assert!(seen_occl < seen_range, "{seen_occl} vs {seen_range}");
}
