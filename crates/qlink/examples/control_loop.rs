//! How a Rust robot embeds Q-Link: its own perception gives landmark observations in the
//! robot frame each cycle, Q-Link decides what to do with the qualitative map, and the loop
//! turns the controller's next waypoint into a velocity command `(v, ω)` for a unicycle.
//!
//! The map here is a deterministic QRM of a small field of posts (what a mapping robot with
//! a 12 m sensor recorded); the robot knows only that map and what it sees now.
//!
//! Run: `cargo run -p qlink --example control_loop`

use std::collections::BTreeMap;

use qlink::{
    Controller, ControllerKind, Layer, LinkGraph, QualitativeMap, SearchPomdp, robot_state,
};
use qsr_core::Calculus;

/// Posts the robot does not know (only its simulated sensor uses them).
const WORLD: [(u32, [f64; 2]); 9] = [
    (1, [0.0, 0.0]),
    (2, [6.0, 3.0]),
    (3, [3.0, 8.0]),
    (4, [11.0, 7.0]),
    (5, [14.0, 1.0]),
    (6, [18.0, 9.0]),
    (7, [23.0, 4.0]),
    (8, [26.0, 11.0]),
    (9, [30.0, 2.0]),
];
const RANGE: f64 = 12.0;

/// The robot's sensor: ids and positions in the robot frame (x forward, y left).
fn perceive(pose: (f64, f64, f64)) -> Vec<(u32, [f64; 2])> {
    let (x, y, th) = pose;
    let (s, c) = th.sin_cos();
    WORLD
        .iter()
        .filter(|(_, p)| (p[0] - x).hypot(p[1] - y) <= RANGE)
        .map(|(id, p)| {
            let (dx, dy) = (p[0] - x, p[1] - y);
            (*id, [c * dx + s * dy, -s * dx + c * dy])
        })
        .collect()
}

/// Velocity command towards a waypoint given in the robot frame.
fn command(target: [f64; 2]) -> (f64, f64) {
    let heading = target[1].atan2(target[0]);
    let dist = target[0].hypot(target[1]);
    (dist.min(1.0) * heading.cos().max(0.0), 2.0 * heading)
}

/// The loop; returns the landmarks the robot passed through (the links) and whether it saw
/// two landmarks of the goal's element at the end.
pub fn run() -> (Vec<u32>, bool) {
    let quadrant = Calculus::builtin("quadrant").expect("built in");
    // the map: every triplet a 12 m sensor could see at once, with its qualitative states
    let positions: BTreeMap<u32, [f64; 2]> = WORLD.iter().copied().collect();
    let layer =
        Layer::exact_from_positions(quadrant.clone(), &positions, RANGE).expect("distinct posts");
    let map = QualitativeMap::new(vec![layer]).expect("non-empty map");
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0).expect("β = 1");
    let pomdp = SearchPomdp::builder(&quadrant)
        .build()
        .expect("valid POMDP");
    let controller = Controller::new(ControllerKind::Arc, RANGE);
    let goal = 9;
    // the robot's own pose estimate (dead reckoning from its commands, as good as its wheels)
    let mut pose = (0.5, -1.0, 0.0f64);
    let dt = 0.1;
    let mut links = Vec::new();
    // localise: any element two of whose landmarks are in view
    let seen: Vec<u32> = perceive(pose).iter().map(|o| o.0).collect();
    let starts = map.elements_in_view(&seen);
    let plan = graph
        .plan(&map, &starts, goal, &Default::default())
        .expect("a path to the goal");
    println!(
        "plan over {} map elements: {:?}",
        plan.elements.len(),
        plan.elements
    );
    for pair in plan.elements.windows(2) {
        let (i, j) = (pair[0], pair[1]);
        let link = graph.edge(i, j).expect("planned edge").links()[0];
        links.push(link);
        let refs: Vec<u32> = map.elements()[i]
            .landmarks
            .iter()
            .copied()
            .filter(|&l| l != link)
            .collect();
        // where the references are, from what the robot sees now (robot frame → its odometry frame)
        let obs = perceive(pose);
        let to_odom = |p: [f64; 2]| {
            let (s, c) = pose.2.sin_cos();
            [pose.0 + c * p[0] - s * p[1], pose.1 + s * p[0] + c * p[1]]
        };
        let find = |id: u32| obs.iter().find(|o| o.0 == id).map(|o| to_odom(o.1));
        let in_goal_frame = |obs: &[(u32, [f64; 2])]| {
            map.elements()[j]
                .landmarks
                .iter()
                .filter(|l| obs.iter().any(|o| o.0 == **l))
                .count()
                >= 2
        };
        if in_goal_frame(&obs) {
            continue;
        }
        let (Some(a), Some(b)) = (find(refs[0]), find(refs[1])) else {
            println!("references of element {i} not in view; stopping");
            return (links, false);
        };
        let mut belief = map
            .belief(i, [refs[0], refs[1], link])
            .expect("recorded ordering");
        'commands: for step in 0..pomdp.horizon {
            let r = robot_state(&quadrant, a, b, [pose.0, pose.1]).expect("distinct references");
            let decision = pomdp
                .decide_with(r, &belief, pomdp.horizon - step)
                .expect("valid belief");
            let path = controller
                .path(&quadrant, a, b, decision.action, [pose.0, pose.1])
                .expect("a path");
            println!(
                "  element {i} → {j}: search state {} for link {link} (P(success) {:.2})",
                quadrant.labels()[decision.action],
                decision.p_success
            );
            for wp in &path[1..] {
                // drive to the waypoint with (v, ω) commands, watching for the link
                for _ in 0..400 {
                    let (s, c) = pose.2.sin_cos();
                    let (dx, dy) = (wp[0] - pose.0, wp[1] - pose.1);
                    if dx.hypot(dy) < 0.3 {
                        break;
                    }
                    let (v, w) = command([c * dx + s * dy, -s * dx + c * dy]);
                    pose = (pose.0 + v * c * dt, pose.1 + v * s * dt, pose.2 + w * dt);
                    if in_goal_frame(&perceive(pose)) {
                        break 'commands;
                    }
                }
            }
            belief = pomdp.update_not_seen(&belief, decision.action);
        }
    }
    let done = map.elements_with(goal).iter().any(|&e| {
        map.elements()[e]
            .landmarks
            .iter()
            .filter(|l| perceive(pose).iter().any(|o| o.0 == **l))
            .count()
            >= 2
    });
    println!(
        "links {links:?}; goal element in view: {done}; pose ({:.1}, {:.1})",
        pose.0, pose.1
    );
    (links, done)
}

fn main() {
    run();
}
