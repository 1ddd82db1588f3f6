//! The robot that errs ([`qlink::Robot`]): its detections and motion have the spread it is
//! configured with, and the exact robot ([`qlink::Robot::EXACT`]) drives exactly as the
//! navigator did before the erring robot existed — bit for bit.
#![allow(clippy::unwrap_used)]

mod common;
use common::{exact_map, random_world};
use qlink::robot::{DetectionNoise, MotionNoise};
use qlink::{
    Controller, ControllerKind, LinkGraph, NavConfig, NavOutcome, Navigator, RangePerception,
    Robot, SearchPomdp,
};
use qsr_core::Calculus;

fn config(kind: ControllerKind, radius: f64) -> NavConfig {
    let quadrant = Calculus::builtin("quadrant").unwrap();
    NavConfig {
        robot: Robot::EXACT,
        replan: true,
        max_replans: 2,
        find_goal: true,
        ..NavConfig::thesis(
            Controller::new(kind, radius),
            SearchPomdp::builder(&quadrant).build().unwrap(),
        )
    }
}

/// FNV-1a over everything an outcome reports, floats by their bits.
fn fingerprint(outcomes: &[NavOutcome]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |x: u64| {
        for b in x.to_le_bytes() {
            h ^= u64::from(b);
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    for o in outcomes {
        eat(u64::from(o.success));
        eat(o.plan_len as u64);
        eat(o.replans as u64);
        eat(o.length.to_bits());
        eat(o.transit_length.to_bits());
        for p in &o.trajectory {
            eat(p[0].to_bits());
            eat(p[1].to_bits());
        }
        for t in &o.transitions {
            eat(t.commands.len() as u64);
            eat(u64::from(t.success));
            eat(t.end[0].to_bits());
            eat(t.end[1].to_bits());
        }
    }
    h
}

/// Navigations between landmark pairs of a random world with `cfg`, sensor range 0.8 R.
fn runs(cfg: &NavConfig, seed: u64) -> Vec<NavOutcome> {
    let positions = random_world(seed, 30, 70.0);
    let map = exact_map(&positions, 15.0);
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
    let list: Vec<(u32, [f64; 2])> = positions.clone().into_iter().collect();
    let perception = RangePerception::new(&list, 0.8 * 15.0);
    let nav = Navigator::new(&map, &graph, &perception, cfg).unwrap();
    let mut out = Vec::new();
    for (&s, &ps) in &positions {
        for &t in positions.keys().step_by(4) {
            if s == t || map.elements_with(t).is_empty() {
                continue;
            }
            out.push(nav.navigate([ps[0] + 0.5, ps[1]], t, None, true).unwrap());
        }
    }
    out
}

#[test]
fn the_exact_robot_drives_as_the_navigator_did_before_it_could_err() {
    // fingerprints of the navigator before the erring robot (commit 93f9944)
    for (kind, want) in [
        (ControllerKind::Arc, 0xf7ba1401c6448fc_u64),
        (ControllerKind::Direct, 0xa3dbc0b1125c973f_u64),
    ] {
        let outs = runs(&config(kind, 15.0), 3);
        let ok = outs.iter().filter(|o| o.success).count();
        eprintln!(
            "{kind:?}: {} runs, {ok} reached, fingerprint {:#x}",
            outs.len(),
            fingerprint(&outs)
        );
        assert_eq!(fingerprint(&outs), want, "{kind:?}");
    }
    let stops = NavConfig {
        sensing: qlink::Sensing::AtStops { degrees: 30.0 },
        ..config(ControllerKind::Arc, 15.0)
    };
    let outs = runs(&stops, 5);
    eprintln!(
        "stops: {} runs, fingerprint {:#x}",
        outs.len(),
        fingerprint(&outs)
    );
    assert_eq!(fingerprint(&outs), 0x86b1b45f61f7d301);
}

fn std(xs: &[f64]) -> (f64, f64) {
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let v = xs.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, v.sqrt())
}

#[test]
fn detections_have_the_configured_spread_misses_and_false_reports() {
    let perception = RangePerception::new(&[(1, [3.0, 4.0]), (2, [40.0, 0.0])], 10.0);
    let robot = Robot {
        detection: DetectionNoise {
            sigma: 0.3,
            miss_rate: 0.1,
            false_rate: 0.02,
        },
        ..Robot::default()
    }
    .with_seed(11);
    let (n, from) = (40_000_u64, [0.0, 0.0]);
    let (mut ex, mut ey, mut missed) = (Vec::new(), Vec::new(), 0);
    let (mut false_reports, mut r2) = (0, 0.0);
    for scan in 0..n {
        match robot.report(&perception, from, 1, true, [5, scan]) {
            Some(p) => {
                ex.push(p[0] - 3.0);
                ey.push(p[1] - 4.0);
            }
            None => missed += 1,
        }
        if let Some(p) = robot.report(&perception, from, 2, false, [5, scan]) {
            false_reports += 1;
            let r = p[0].hypot(p[1]);
            assert!(r <= 10.0, "a false report outside the sensor disc: {p:?}");
            r2 += r * r;
        }
        // the same key, the same answer
        assert_eq!(
            robot.report(&perception, from, 1, true, [5, scan]),
            robot.report(&perception, from, 1, true, [5, scan])
        );
    }
    let ((mx, sx), (my, sy)) = (std(&ex), std(&ey));
    // σ of a sample standard deviation of 36,000 draws: 0.4 %; of the mean: 0.0016 m
    for s in [sx, sy] {
        assert!(
            (s / 0.3 - 1.0).abs() < 0.02,
            "residual spread {s}, configured 0.3"
        );
    }
    assert!(
        mx.abs() < 0.006 && my.abs() < 0.006,
        "residual mean {mx}, {my}"
    );
    let miss = f64::from(missed) / n as f64;
    assert!(
        (miss - 0.1).abs() < 0.006,
        "miss share {miss}, configured 0.1"
    );
    let fals = f64::from(false_reports) / n as f64;
    assert!(
        (fals - 0.02).abs() < 0.003,
        "false share {fals}, configured 0.02"
    );
    // uniform in the disc: E[r²] = R²/2
    let mean_r2 = r2 / f64::from(false_reports);
    assert!(
        (mean_r2 / 50.0 - 1.0).abs() < 0.08,
        "E[r²] {mean_r2}, uniform 50"
    );
    // the exact detector reports the truth and nothing else
    assert_eq!(
        Robot::EXACT.report(&perception, from, 1, true, [5, 0]),
        Some([3.0, 4.0])
    );
    assert_eq!(
        Robot::EXACT.report(&perception, from, 2, false, [5, 0]),
        None
    );
}

#[test]
fn motion_error_grows_as_a_random_walk_with_the_distance_driven() {
    let robot = Robot {
        motion: MotionNoise {
            distance_sigma: 0.02,
            heading_sigma: 0.01,
        },
        ..Robot::default()
    };
    let (runs, steps) = (4000_u64, 100_u64);
    let (mut headings, mut lengths, mut lateral) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..runs {
        let (mut heading, mut length, mut pos) = (0.0, 0.0, [0.0_f64, 0.0]);
        for k in 1..=steps {
            let s = robot.step([1.0, 0.0], heading, [run, k]);
            heading = s.heading;
            length += s.length;
            pos = [pos[0] + s.moved[0], pos[1] + s.moved[1]];
            assert!((s.moved[0].hypot(s.moved[1]) - s.length).abs() < 1e-12);
        }
        headings.push(heading);
        lengths.push(length);
        lateral.push(pos[1]);
    }
    // after d = 100 m: heading σ = 0.01·√100 = 0.1 rad, length σ = 0.02·√100 = 0.2 m
    let (mh, sh) = std(&headings);
    let (ml, sl) = std(&lengths);
    assert!(
        (sh / 0.1 - 1.0).abs() < 0.05 && mh.abs() < 0.005,
        "heading {mh} ± {sh}"
    );
    assert!(
        (sl / 0.2 - 1.0).abs() < 0.05 && (ml - 100.0).abs() < 0.01,
        "length {ml} ± {sl}"
    );
    // the lateral error integrates the heading walk: σ² = σ_h²·Σ_k (k-th step's offsets)
    // = 0.01²·Σ_{k=1}^{100} (100 − k + 1)² ·1 m ⇒ σ ≈ 0.01·√338350 ≈ 5.8 m (small angles)
    let (_, sy) = std(&lateral);
    let want = 0.01
        * ((1..=100)
            .map(|k: u64| ((101 - k) * (101 - k)) as f64)
            .sum::<f64>())
        .sqrt();
    assert!(
        (sy / want - 1.0).abs() < 0.08,
        "lateral σ {sy}, random walk {want}"
    );
    // the exact robot drives what it is told
    let s = Robot::EXACT.step([0.6, 0.8], 0.0, [0, 1]);
    assert_eq!((s.moved, s.heading, s.length), ([0.6, 0.8], 0.0, 1.0));
}

#[test]
fn the_erring_robot_errs_and_its_runs_do_not_depend_on_their_order() {
    let erring = NavConfig {
        robot: Robot::erring(0.5).with_seed(3),
        ..config(ControllerKind::Arc, 15.0)
    };
    let exact = runs(&config(ControllerKind::Arc, 15.0), 3);
    let outs = runs(&erring, 3);
    // again, and in reverse order: every run the same
    let positions = random_world(3, 30, 70.0);
    let map = exact_map(&positions, 15.0);
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
    let list: Vec<(u32, [f64; 2])> = positions.clone().into_iter().collect();
    let perception = RangePerception::new(&list, 0.8 * 15.0);
    let nav = Navigator::new(&map, &graph, &perception, &erring).unwrap();
    let mut pairs = Vec::new();
    for (&s, &ps) in &positions {
        for &t in positions.keys().step_by(4) {
            if s != t && !map.elements_with(t).is_empty() {
                pairs.push((ps, t));
            }
        }
    }
    let mut again: Vec<NavOutcome> = pairs
        .iter()
        .rev()
        .map(|&(ps, t)| nav.navigate([ps[0] + 0.5, ps[1]], t, None, true).unwrap())
        .collect();
    again.reverse();
    assert_eq!(fingerprint(&again), fingerprint(&outs));
    // another seed, other runs
    let reseeded = NavConfig {
        robot: Robot::erring(0.5).with_seed(4),
        ..erring.clone()
    };
    assert_ne!(fingerprint(&runs(&reseeded, 3)), fingerprint(&outs));
    // it errs: the trajectories leave the exact robot's, and it still navigates
    let differ = exact
        .iter()
        .zip(&outs)
        .filter(|(a, b)| a.trajectory != b.trajectory)
        .count();
    assert!(
        differ * 10 >= outs.len() * 9,
        "{differ} of {} differ",
        outs.len()
    );
    let ok = |o: &[NavOutcome]| o.iter().filter(|o| o.success).count();
    eprintln!(
        "reached: exact {} erring {} of {}",
        ok(&exact),
        ok(&outs),
        outs.len()
    );
    assert!(
        ok(&outs) * 10 >= outs.len() * 7,
        "{} of {}",
        ok(&outs),
        outs.len()
    );
    // labelled
    assert!(
        config(ControllerKind::Arc, 15.0)
            .idealised()
            .contains(&"exact detections and motion")
    );
    assert!(erring.idealised().is_empty());
}

#[test]
fn a_robot_that_cannot_be_is_refused_by_name() {
    let positions = random_world(3, 10, 30.0);
    let map = exact_map(&positions, 15.0);
    let graph = LinkGraph::new(&map, 1, |_, _, _| 1.0).unwrap();
    let list: Vec<(u32, [f64; 2])> = positions.into_iter().collect();
    let perception = RangePerception::new(&list, 15.0);
    let mut cfg = config(ControllerKind::Arc, 15.0);
    cfg.robot.detection.false_rate = 1.5;
    let err = Navigator::new(&map, &graph, &perception, &cfg)
        .err()
        .unwrap();
    assert!(err.to_string().contains("false rate 1.5"), "{err}");
}
