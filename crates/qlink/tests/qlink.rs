//! Q-Link's three levels on hand-made maps (thesis §4.3), the POMDP against hand
//! computations, the controllers, and the guarantees of §4.3.4 on worlds that meet
//! Assumptions 1–2.
#![allow(clippy::unwrap_used)]

mod common;
use common::exact_map;
use std::collections::{BTreeMap, BTreeSet};

use qlink::{
    Controller, ControllerKind, Layer, LinkGraph, NavConfig, Navigator, QlinkError, QualitativeMap,
    RangePerception, SearchPomdp, robot_state,
};
use qsr_core::Calculus;

fn line_world() -> BTreeMap<u32, [f64; 2]> {
    // five landmarks 8 m apart on a line, slightly off so no three are collinear
    (0..5u32)
        .map(|i| (i, [8.0 * f64::from(i), if i % 2 == 0 { 0.0 } else { 1.0 }]))
        .collect()
}

#[test]
fn link_graph_edges_and_plans_on_a_hand_made_map() {
    // range 9: only consecutive triplets {0,1,2}, {1,2,3}, {2,3,4} fit in a disc
    let map = exact_map(&line_world(), 9.0);
    let sets: Vec<[u32; 3]> = map.elements().iter().map(|e| e.landmarks).collect();
    assert_eq!(sets, vec![[0, 1, 2], [1, 2, 3], [2, 3, 4]]);
    let unit = |_: usize, _: usize, _: &[u32]| 1.0;
    // β = 2: a chain; β = 1 adds {0,1,2}–{2,3,4} through landmark 2
    let g2 = LinkGraph::new(&map, 2, unit).unwrap();
    assert_eq!(g2.n_edges(), 4);
    let g1 = LinkGraph::new(&map, 1, unit).unwrap();
    assert_eq!(g1.n_edges(), 6);
    assert_eq!(g1.edge(0, 2).unwrap().links(), &[2]);
    assert_eq!(g2.edge(0, 1).unwrap().links(), &[1, 2]);
    let none = BTreeSet::new();
    assert_eq!(
        g2.plan(&map, &[0], 4, &none).unwrap().elements,
        vec![0, 1, 2]
    );
    assert_eq!(g1.plan(&map, &[0], 4, &none).unwrap().elements, vec![0, 2]);
    // the distance field gives the same plans
    let f = g2.distance_field(&map, 4).unwrap();
    assert_eq!(f.path_from(&g2, &[0]).unwrap().elements, vec![0, 1, 2]);
    // contingency: excluding the failed edge re-routes, or leaves no path
    let ex: BTreeSet<(usize, usize)> = [(0, 2)].into_iter().collect();
    assert_eq!(g1.plan(&map, &[0], 4, &ex).unwrap().elements, vec![0, 1, 2]);
    let ex: BTreeSet<(usize, usize)> = [(0, 1)].into_iter().collect();
    assert!(matches!(
        g2.plan(&map, &[0], 4, &ex),
        Err(QlinkError::NoPath { goal: 4 })
    ));
    // costs steer the plan: make the direct β = 1 edge expensive
    let pricey =
        LinkGraph::new(&map, 1, |i, j, _| if (i, j) == (0, 2) { 5.0 } else { 1.0 }).unwrap();
    assert_eq!(
        pricey.plan(&map, &[0], 4, &none).unwrap().elements,
        vec![0, 1, 2]
    );
}

#[test]
fn bad_input_gets_clear_errors() {
    let map = exact_map(&line_world(), 9.0);
    let unit = |_: usize, _: usize, _: &[u32]| 1.0;
    let g = LinkGraph::new(&map, 1, unit).unwrap();
    let none = BTreeSet::new();
    assert!(matches!(
        g.plan(&map, &[0], 99, &none),
        Err(QlinkError::UnknownLandmark(99))
    ));
    assert!(matches!(
        g.plan(&map, &[], 4, &none),
        Err(QlinkError::InvalidParameter(_))
    ));
    assert!(matches!(
        LinkGraph::new(&map, 0, unit),
        Err(QlinkError::InvalidParameter(_))
    ));
    assert!(matches!(
        LinkGraph::new(&map, 1, |_, _, _| f64::NAN),
        Err(QlinkError::InvalidParameter(_))
    ));
    // a map with nothing in it
    let empty =
        Layer::exact_from_positions(Calculus::builtin("quadrant").unwrap(), &line_world(), 1.0)
            .unwrap();
    assert!(matches!(
        QualitativeMap::new(vec![empty]),
        Err(QlinkError::EmptyMap)
    ));
    // a disconnected map: two far groups
    let mut two = line_world();
    for i in 0..3u32 {
        two.insert(
            10 + i,
            [500.0 + 8.0 * f64::from(i), if i == 1 { 1.0 } else { 0.0 }],
        );
    }
    let map2 = exact_map(&two, 9.0);
    let g2 = LinkGraph::new(&map2, 1, unit).unwrap();
    let start = map2.elements_with(0)[0];
    assert!(matches!(
        g2.plan(&map2, &[start], 12, &none),
        Err(QlinkError::NoPath { goal: 12 })
    ));
    // start = goal, unknown start
    let landmarks: Vec<(u32, [f64; 2])> = line_world().into_iter().collect();
    let perception = RangePerception::new(&landmarks, 20.0);
    let config = config(ControllerKind::Arc, 20.0);
    let nav = Navigator::new(&map, &g, &perception, &config).unwrap();
    assert!(matches!(
        nav.navigate_between(3, 3, 0.5),
        Err(QlinkError::SameStartGoal(3))
    ));
    assert!(matches!(
        nav.navigate_between(77, 3, 0.5),
        Err(QlinkError::UnknownLandmark(77))
    ));
    // a degenerate frame for a controller
    let c = Controller::new(ControllerKind::Arc, 10.0);
    assert!(
        c.path(
            &Calculus::builtin("quadrant").unwrap(),
            [1.0, 1.0],
            [1.0, 1.0],
            0,
            [0.0, 0.0]
        )
        .is_err()
    );
    // the closest-point QP refuses circles
    let edc = Calculus::builtin("edc").unwrap();
    assert!(matches!(
        Controller::new(ControllerKind::ClosestPoint, 10.0).path(
            &edc,
            [0.0, 0.0],
            [0.0, 5.0],
            0,
            [3.0, 3.0]
        ),
        Err(QlinkError::Unsupported(_))
    ));
}

fn config(kind: ControllerKind, range: f64) -> NavConfig {
    let quadrant = Calculus::builtin("quadrant").unwrap();
    NavConfig {
        step: 0.5,
        replan: true,
        max_replans: 3,
        ..NavConfig::thesis(
            Controller::new(kind, range),
            SearchPomdp::builder(&quadrant).build().unwrap(),
        )
    }
}

#[test]
fn pomdp_values_match_a_hand_computation() {
    let lr = Calculus::builtin("left-right").unwrap();
    let left = lr.state("left").unwrap().index();
    let right = lr.state("right").unwrap().index();
    let mut belief = vec![0.0; 2];
    belief[left] = 0.3;
    belief[right] = 0.7;
    // perfect moves and detection
    let p = SearchPomdp::builder(&lr)
        .p_detect(1.0)
        .horizon(1)
        .build()
        .unwrap();
    let d = p.decide(left, &belief).unwrap();
    assert_eq!(d.action, right);
    assert!((d.value - (0.7 * 100.0 - 0.3)).abs() < 1e-12);
    assert!((d.p_success - 0.7).abs() < 1e-12);
    let d2 = p.decide_with(left, &belief, 2).unwrap();
    assert_eq!(d2.action, right);
    assert!((d2.value - (0.7 * 100.0 + 0.3 * (-1.0 + 100.0))).abs() < 1e-12);
    assert!((d2.p_success - 1.0).abs() < 1e-12);
    // detection 0.8, horizon 2 (eqs. 4.2–4.3 by hand)
    let p = SearchPomdp::builder(&lr)
        .p_detect(0.8)
        .horizon(2)
        .build()
        .unwrap();
    let d = p.decide(left, &belief).unwrap();
    let p0 = 0.7 * 0.8; // look right first and see it
    let miss = 1.0 - p0;
    let b_left = 0.3 / miss; // posterior on "left" after not seeing it on the right
    let p1 = b_left * 0.8; // then look left
    assert_eq!(d.action, right);
    assert!((d.p_success - (p0 + miss * p1)).abs() < 1e-12, "{d:?}");
    let v = p0 * 100.0 + miss * (-1.0 + p1 * 100.0 - (1.0 - p1));
    assert!((d.value - v).abs() < 1e-9, "{} vs {v}", d.value);
    // the belief update is Bayes' rule
    let nb = p.update_not_seen(&belief, right);
    assert!((nb[left] - b_left).abs() < 1e-12);
    // bad input
    assert!(p.decide(0, &[0.5]).is_err());
    assert!(p.decide(5, &belief).is_err());
    assert!(
        SearchPomdp::builder(&lr)
            .p_move(1.5)
            .p_detect(0.8)
            .horizon(2)
            .build()
            .is_err()
    );
    assert!(
        SearchPomdp::builder(&lr)
            .p_detect(0.8)
            .horizon(0)
            .build()
            .is_err()
    );
}

#[test]
fn each_controller_reaches_its_target_state_in_an_open_world() {
    let quadrant = Calculus::builtin("quadrant").unwrap();
    let (a, b) = ([0.0, 0.0], [0.0, 10.0]);
    let robot = [3.0, -4.0];
    for kind in [
        ControllerKind::Arc,
        ControllerKind::ClosestPoint,
        ControllerKind::SafeSearch,
    ] {
        let c = Controller::new(kind, 15.0);
        for target in 0..quadrant.n_states() {
            let path = c.path(&quadrant, a, b, target, robot).unwrap();
            assert_eq!(path[0], robot);
            let end = *path.last().unwrap();
            assert_eq!(
                robot_state(&quadrant, a, b, end).unwrap(),
                target,
                "{kind:?} → {target}"
            );
            if kind != ControllerKind::ClosestPoint {
                // the arc and the search stay inside the state after entering it
                for p in &path[1..] {
                    assert_eq!(
                        robot_state(&quadrant, a, b, *p).unwrap(),
                        target,
                        "{kind:?} {p:?}"
                    );
                }
            }
        }
    }
    // the closest point is the projection onto the state (robot right-back → left-back: x = 0⁻)
    let lb = quadrant.state("left-back").unwrap().index();
    let p = qlink::closest_point(&quadrant, a, b, lb, robot).unwrap();
    assert!(
        p[0] < 0.0 && p[0] > -0.2 && (p[1] - robot[1]).abs() < 0.2,
        "{p:?}"
    );
    // midpoint and sweep goes to the references' midpoint
    let m = Controller::new(ControllerKind::MidpointSweep, 15.0)
        .path(&quadrant, a, b, 0, robot)
        .unwrap();
    assert_eq!(*m.last().unwrap(), [0.0, 5.0]);
}

/// Random worlds where every element was recordable by a robot of range R (Assumption 1)
/// and the navigating robot has R' = R without occlusion: every navigation succeeds
/// (Proposition 1) and no transition sequence is longer than (2π + 1)·R·|P|
/// (Proposition 2).
#[test]
fn guarantees_hold_when_the_assumptions_do() {
    use rand::{RngExt, SeedableRng};
    for seed in 0..3u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let positions: BTreeMap<u32, [f64; 2]> = (0..25u32)
            .map(|i| {
                (
                    i,
                    [rng.random_range(0.0..60.0), rng.random_range(0.0..60.0)],
                )
            })
            .collect();
        let range = 15.0;
        let map = exact_map(&positions, range);
        let g = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
        let landmarks: Vec<(u32, [f64; 2])> = positions.clone().into_iter().collect();
        let perception = RangePerception::new(&landmarks, range);
        let mut cfg = config(ControllerKind::Arc, range);
        cfg.replan = false;
        // the propositions are about a robot that sees and drives exactly; the erring one
        // can fail (crates/qlink/tests/erring_robot.rs)
        cfg.robot = qlink::Robot::EXACT;
        let nav = Navigator::new(&map, &g, &perception, &cfg).unwrap();
        let mut runs = 0;
        for s in 0..25u32 {
            for t in (0..25u32).step_by(4) {
                if s == t || map.elements_with(s).is_empty() || map.elements_with(t).is_empty() {
                    continue;
                }
                let out = nav.navigate_between(s, t, 0.5).unwrap();
                if out.failure == Some(qlink::Failure::NoPath) {
                    continue;
                }
                runs += 1;
                assert!(
                    out.success,
                    "seed {seed}: {s} → {t} failed: {:?}",
                    out.failure
                );
                assert!(
                    out.transit_length <= out.bound + 1e-6,
                    "{} > {}",
                    out.transit_length,
                    out.bound
                );
            }
        }
        assert!(runs > 50, "{runs}");
    }
}

#[test]
fn replanning_recovers_from_a_forced_failure() {
    // the link of the first plan's first edge is made invisible, so that transition fails
    // and the robot must re-plan around it (§4.4.2's contingency plan)
    struct Blind(RangePerception, u32);
    impl qlink::Perception for Blind {
        fn position(&self, id: u32) -> Option<[f64; 2]> {
            self.0.position(id)
        }
        fn sees(&self, pos: [f64; 2], id: u32) -> bool {
            id != self.1 && self.0.sees(pos, id)
        }
        fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
            self.0
                .visible(pos)
                .into_iter()
                .filter(|&i| i != self.1)
                .collect()
        }
        fn ids(&self) -> Vec<u32> {
            self.0.ids()
        }
        fn range(&self) -> f64 {
            self.0.range()
        }
    }
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let positions: BTreeMap<u32, [f64; 2]> = (0..30u32)
        .map(|i| {
            (
                i,
                [rng.random_range(0.0..90.0), rng.random_range(0.0..90.0)],
            )
        })
        .collect();
    let range = 15.0;
    let map = exact_map(&positions, range);
    let g = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
    let landmarks: Vec<(u32, [f64; 2])> = positions.clone().into_iter().collect();
    let full = RangePerception::new(&landmarks, range);
    let cfg = config(ControllerKind::Arc, range);
    let mut tried = 0;
    let pairs = (0..30u32)
        .flat_map(|s| (0..30u32).map(move |t| (s, t)))
        .filter(|(s, t)| s != t);
    for (s, t) in pairs {
        if tried >= 4 {
            break;
        }
        let start = positions[&s];
        let starts = map.elements_in_view(&qlink::Perception::visible(
            &full,
            [start[0] + 0.5, start[1]],
        ));
        let Ok(plan) = g.plan(&map, &starts, t, &BTreeSet::new()) else {
            continue;
        };
        if plan.len() < 2 {
            continue;
        }
        let hidden = g.edge(plan.elements[0], plan.elements[1]).unwrap().links()[0];
        if hidden == s || hidden == t {
            continue;
        }
        let blind = Blind(RangePerception::new(&landmarks, range), hidden);
        let nav = Navigator::new(&map, &g, &blind, &cfg).unwrap();
        let out = nav.navigate_between(s, t, 0.5).unwrap();
        tried += 1;
        assert!(
            out.replans >= 1,
            "{s} → {t}: the first transition should have failed"
        );
        assert!(!out.transitions[0].success);
        if out.success {
            assert!(
                out.transitions
                    .iter()
                    .filter(|x| x.success)
                    .all(|x| x.link != hidden)
            );
        }
    }
    assert!(tried >= 2, "{tried}");
}

#[allow(dead_code)]
#[path = "../examples/control_loop.rs"]
mod control_loop;

#[test]
fn the_embedding_example_reaches_its_goal() {
    let (links, done) = control_loop::run();
    assert!(!links.is_empty());
    assert!(done);
}

#[test]
fn pomdp_edge_costs_follow_eqs_4_2_to_4_4() {
    // exact map: the link's state is certain, detection 0.9, horizon 4
    let map = exact_map(&line_world(), 9.0);
    let quadrant = Calculus::builtin("quadrant").unwrap();
    let pomdps = vec![SearchPomdp::builder(&quadrant).build().unwrap()];
    let neg_log = qlink::graph::pomdp_cost(&map, &pomdps, qlink::CostModel::NegLogSuccess);
    let p = 1.0 - 0.1f64.powi(4);
    assert!((neg_log(0, 1, &[1, 2]) - (-p.ln())).abs() < 1e-12);
    let moves = qlink::graph::pomdp_cost(&map, &pomdps, qlink::CostModel::ExpectedTransitions);
    assert!((moves(0, 1, &[1, 2]) - 1.111).abs() < 1e-12);
    let unit = qlink::graph::pomdp_cost(&map, &pomdps, qlink::CostModel::Unit);
    assert_eq!(unit(0, 1, &[1, 2]), 1.0);
    // and a graph priced this way plans
    let g = LinkGraph::new(&map, 1, neg_log).unwrap();
    assert!(g.plan(&map, &[0], 4, &BTreeSet::new()).is_ok());
}

/// Worlds whose map elements have landmarks pairwise within R (Assumption 3) and a robot
/// that drives straight lines (Assumption 4): with the direct controller every navigation
/// succeeds and no transition sequence is longer than R·|P| (Proposition 4).
#[test]
fn proposition_4_holds_for_the_direct_controller() {
    use rand::{RngExt, SeedableRng};
    for seed in 0..3u64 {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(100 + seed);
        let positions: BTreeMap<u32, [f64; 2]> = (0..30u32)
            .map(|i| {
                (
                    i,
                    [rng.random_range(0.0..60.0), rng.random_range(0.0..60.0)],
                )
            })
            .collect();
        let range = 15.0;
        let layer =
            Layer::exact_pairwise(Calculus::builtin("quadrant").unwrap(), &positions, range)
                .unwrap();
        let map = QualitativeMap::new(vec![layer]).unwrap();
        // every element is pairwise within R
        for e in map.elements() {
            for a in e.landmarks {
                for b in e.landmarks {
                    let (p, q) = (positions[&a], positions[&b]);
                    assert!((p[0] - q[0]).hypot(p[1] - q[1]) <= range);
                }
            }
        }
        let g = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
        let landmarks: Vec<(u32, [f64; 2])> = positions.clone().into_iter().collect();
        let perception = RangePerception::new(&landmarks, range);
        let mut cfg = config(ControllerKind::Direct, range);
        cfg.replan = false;
        cfg.robot = qlink::Robot::EXACT; // Proposition 4 is about the exact robot
        let nav = Navigator::new(&map, &g, &perception, &cfg).unwrap();
        let mut runs = 0;
        for s in 0..30u32 {
            for t in (1..30u32).step_by(5) {
                if s == t || map.elements_with(s).is_empty() || map.elements_with(t).is_empty() {
                    continue;
                }
                // start exactly at the start landmark (Proposition 3's x_t = L_n)
                let out = nav.navigate(positions[&s], t, None, false).unwrap();
                if out.failure == Some(qlink::Failure::NoPath) {
                    continue;
                }
                runs += 1;
                assert!(out.success, "seed {seed}: {s} → {t}: {:?}", out.failure);
                assert!(
                    out.transit_length <= out.bound_direct + 1e-6,
                    "{s} → {t}: {} > R·|P| = {}: {:?}",
                    out.transit_length,
                    out.bound_direct,
                    out.transitions
                );
            }
        }
        assert!(runs > 30, "{runs}");
    }
}

/// With `find_goal` the run ends only when the goal landmark itself is seen: reaching the
/// frame of an element that holds it is not enough (the §4.4.2 field experiment's rule);
/// a goal that cannot be found is a failure after the goal element is given up.
#[test]
fn find_goal_searches_for_the_goal_itself() {
    let positions: BTreeMap<u32, [f64; 2]> =
        [(0, [0.0, 0.0]), (1, [10.0, 0.0]), (2, [5.0, 20.0])].into();
    let map = exact_map(&positions, 40.0);
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
    let list: Vec<(u32, [f64; 2])> = positions.iter().map(|(k, v)| (*k, *v)).collect();
    let perception = RangePerception::new(&list, 12.0);
    let start = [5.0, -3.0];
    // frame only: arrival at once
    let plain = config(ControllerKind::Arc, 12.0);
    let nav = Navigator::new(&map, &graph, &perception, &plain).unwrap();
    let out = nav.navigate(start, 2, None, true).unwrap();
    assert!(out.success && out.length == 0.0);
    // the goal itself: the robot searches in the frame of 0 and 1 and ends seeing 2
    let cfg = NavConfig {
        find_goal: true,
        ..config(ControllerKind::Arc, 12.0)
    };
    let nav = Navigator::new(&map, &graph, &perception, &cfg).unwrap();
    let out = nav.navigate(start, 2, None, true).unwrap();
    assert!(out.success, "{:?}", out.failure);
    assert_eq!(out.stranded, None);
    assert!(out.length > 5.0);
    let end = *out.trajectory.last().unwrap();
    assert!(qlink::Perception::sees(&perception, end, 2));
    // a goal the robot cannot detect: the element is given up, nothing else holds the goal
    let blind = RangePerception::new(&list[..2], 12.0);
    let nav = Navigator::new(&map, &graph, &blind, &cfg).unwrap();
    let out = nav.navigate(start, 2, None, false).unwrap();
    assert!(!out.success);
    assert_eq!(out.failure, Some(qlink::Failure::InsufficientFeatures));
    assert_eq!(out.replans, 1);
    // what it was left without: the one element in view holds the goal and was given up
    assert_eq!(out.stranded, Some(qlink::Stranded::NoPathLeft));
    // without re-planning, the first contingency ends the run
    let once = NavConfig {
        replan: false,
        ..cfg.clone()
    };
    let nav = Navigator::new(&map, &graph, &blind, &once).unwrap();
    let out = nav.navigate(start, 2, None, false).unwrap();
    assert_eq!(out.replans, 0);
    assert_eq!(out.stranded, Some(qlink::Stranded::ReplanBudget));
}

/// Hybrid maps search in layers of different sizes: the POMDP is rebuilt on the other
/// calculus with the same parameters.
#[test]
fn pomdp_for_another_calculus_keeps_its_parameters() {
    let lr = Calculus::builtin("left-right").unwrap();
    let q = Calculus::builtin("quadrant").unwrap();
    let p = SearchPomdp::builder(&lr)
        .moves(qlink::Moves::Direct)
        .p_move(0.9)
        .p_detect(0.7)
        .horizon(3)
        .build()
        .unwrap();
    let on_q = p.for_calculus(&q).unwrap();
    assert_eq!(on_q.n_states(), 4);
    assert_eq!(
        on_q,
        SearchPomdp::builder(&q)
            .moves(qlink::Moves::Direct)
            .p_move(0.9)
            .p_detect(0.7)
            .horizon(3)
            .build()
            .unwrap()
    );
    // neighbour-only moves stay neighbour-only
    // (front / between / behind: front and behind do not touch)
    let fbb = Calculus::builtin("front-between-behind").unwrap();
    let nb = SearchPomdp::builder(&fbb)
        .p_move(0.9)
        .p_detect(0.7)
        .horizon(3)
        .build()
        .unwrap();
    assert_ne!(
        nb,
        SearchPomdp::builder(&fbb)
            .moves(qlink::Moves::Direct)
            .p_move(0.9)
            .p_detect(0.7)
            .horizon(3)
            .build()
            .unwrap()
    );
    assert_eq!(nb.for_calculus(&fbb).unwrap(), nb);
    assert!(p.clone().with_p_detect(1.5).is_err());
    assert_eq!(
        p.clone()
            .with_p_detect(0.3)
            .unwrap()
            .decide(0, &[0.5, 0.5])
            .unwrap()
            .action,
        p.decide(0, &[0.5, 0.5]).unwrap().action
    );
}

/// Regression: with β = 2 the navigator searched for the first shared landmark even when
/// the robot already saw it (no progress), then circled it; it must search for the shared
/// landmark it does not see.
#[test]
fn beta_two_transitions_search_for_the_unseen_link() {
    let positions: BTreeMap<u32, [f64; 2]> = [
        (0, [0.0, 0.0]),
        (1, [8.0, 0.0]),
        (2, [4.0, 12.0]),
        (3, [12.0, 12.0]),
    ]
    .into();
    // range 7: only {0, 1, 2} and {1, 2, 3} fit a disc; they share {1, 2}
    let map = exact_map(&positions, 7.0);
    assert_eq!(map.elements().len(), 2);
    let graph = LinkGraph::new(&map, 2, |_, _, _| 1.0).unwrap();
    let list: Vec<(u32, [f64; 2])> = positions.iter().map(|(k, v)| (*k, *v)).collect();
    let perception = RangePerception::new(&list, 10.0);
    let cfg = config(ControllerKind::Arc, 10.0);
    let nav = Navigator::new(&map, &graph, &perception, &cfg).unwrap();
    // from (4, −2) the robot sees 0 and 1, not 2 or 3
    let out = nav.navigate([4.0, -2.0], 3, None, false).unwrap();
    assert!(out.success, "{:?}", out.failure);
    assert_eq!(out.transitions.len(), 1);
    assert_eq!(
        out.transitions[0].link, 2,
        "the shared landmark not yet in view"
    );
}

#[test]
fn agrees_with_petgraph_dijkstra_from_one_source() {
    // Plans and distance fields come from one multi-source Dijkstra of our own (petgraph's
    // starts from one node and returns no predecessors); from a single start, its costs must
    // be petgraph's.
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let positions: BTreeMap<u32, [f64; 2]> = (0..20u32)
        .map(|i| {
            (
                i,
                [rng.random_range(0.0..50.0), rng.random_range(0.0..50.0)],
            )
        })
        .collect();
    let map = exact_map(&positions, 15.0);
    let price = |i: usize, j: usize, _: &[u32]| ((i * 31 + j * 17) % 7 + 1) as f64 * 0.5;
    let g = LinkGraph::new(&map, 1, price).unwrap();
    assert!(g.n_edges() > 20, "a graph worth searching");
    let mut compared = 0;
    for goal in [0u32, 7, 13] {
        let goals = map.elements_with(goal).to_vec();
        let field = g.distance_field(&map, goal).unwrap();
        for s in 0..g.n_elements().min(40) {
            let reference = petgraph::algo::dijkstra(
                g.graph(),
                petgraph::graph::NodeIndex::new(s),
                None,
                |e| e.weight().cost,
            );
            let best = goals
                .iter()
                .filter_map(|t| reference.get(&petgraph::graph::NodeIndex::new(*t)))
                .copied()
                .fold(f64::INFINITY, f64::min);
            assert!(
                (field.cost(s) - best).abs() < 1e-9 || field.cost(s) == best,
                "field from {s}"
            );
            match g.plan(&map, &[s], goal, &BTreeSet::new()) {
                Ok(plan) => {
                    assert!(
                        (plan.cost - best).abs() < 1e-9,
                        "plan from {s}: {} vs {best}",
                        plan.cost
                    );
                    compared += 1;
                }
                Err(QlinkError::NoPath { .. }) => assert!(best.is_infinite()),
                Err(e) => panic!("{e}"),
            }
        }
    }
    assert!(compared > 30, "{compared} plans compared");
}
