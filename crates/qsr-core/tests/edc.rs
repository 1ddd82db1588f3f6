//! The EDC facts the thesis relies on (§2.3.1) and its literature numbering (DESIGN §3).
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use qsr_core::{Calculus, Point2, StateId};

fn state_of(edc: &Calculus, x: f64, y: f64) -> String {
    edc.label(edc.classify_normalised(&Point2::new(x, y)))
        .to_owned()
}

#[test]
fn edc_has_twenty_states_numbered_as_in_the_literature() {
    let edc = Calculus::builtin("edc").unwrap();
    assert_eq!(edc.n_states(), 20);
    assert!((edc.max_entropy() - 20f64.ln()).abs() < 1e-12);
    assert!(
        (edc.max_entropy() - 3.00).abs() < 0.005,
        "thesis: 3.00 nats"
    );
    // One interior point per state, from the numbering in DESIGN §3.
    let cases = [
        (-2.0, 3.0, "1"),
        (2.0, 3.0, "2"),
        (-0.3, 1.5, "3"),
        (0.3, 1.5, "4"),
        (-2.0, 0.75, "5"),
        (-0.9, 0.75, "6"),
        (-0.3, 0.75, "7"),
        (0.3, 0.75, "8"),
        (0.9, 0.75, "9"),
        (2.0, 0.75, "10"),
        (-2.0, 0.25, "11"),
        (-0.9, 0.25, "12"),
        (-0.3, 0.25, "13"),
        (0.3, 0.25, "14"),
        (0.9, 0.25, "15"),
        (2.0, 0.25, "16"),
        (-0.3, -0.5, "17"),
        (0.3, -0.5, "18"),
        (-2.0, -0.5, "19"),
        (2.0, -0.5, "20"),
    ];
    for (x, y, want) in cases {
        assert_eq!(state_of(&edc, x, y), want, "({x}, {y})");
    }
}

#[test]
fn edc_boundaries_follow_the_documented_convention() {
    let edc = Calculus::builtin("edc").unwrap();
    // On line AB: right. On y = 1: the upper row. On a circle: near.
    assert_eq!(state_of(&edc, 0.0, 3.0), "2");
    assert_eq!(state_of(&edc, -2.0, 1.0), "1");
    assert_eq!(state_of(&edc, -2.0, 0.5), "5");
    assert_eq!(state_of(&edc, -2.0, 0.0), "11");
    assert_eq!(state_of(&edc, 0.0, -1.0), "18");
    assert_eq!(state_of(&edc, 0.0, 0.0), "14"); // A itself: right, lower middle, in both circles
    assert_eq!(state_of(&edc, 0.0, 1.0), "4"); // B itself
}

#[test]
fn edc_neighbour_graph_matches_the_thesis() {
    let edc = Calculus::builtin("edc").unwrap();
    let g = edc.neighbours();
    assert_eq!(g.diameter(), Some(4));
    let s = |l: &str| edc.state(l).unwrap();
    // Thesis §2.3.1: "there is an edge between ... state 1 and those that represent states 2-6".
    let n1: Vec<StateId> = g.neighbours_of(s("1"));
    assert_eq!(n1, ["2", "3", "4", "5", "6"].map(s).to_vec());
    // Wedges meeting only at a corner count: at (−√3/2, 1/2) six states meet.
    for (a, b) in [("5", "13"), ("6", "12"), ("7", "11")] {
        assert!(g.is_adjacent(s(a), s(b)), "{a}-{b} share a corner");
    }
    // 1 and 20 are the farthest apart.
    assert_eq!(g.distance(s("1"), s("20")), Some(4));
    assert_eq!(g.distance(s("7"), s("7")), Some(0));
    // Symmetric.
    for a in edc.states() {
        for b in edc.states() {
            assert_eq!(g.distance(a, b), g.distance(b, a));
        }
    }
}

#[test]
fn coarser_calculi_have_the_documented_sizes_and_diameters() {
    for (name, n, diameter) in [
        ("edc-lune", 17, 4),
        ("triple-cross", 8, 3),
        ("double-cross", 6, 2),
        ("quadrant", 4, 1),
        ("left-right", 2, 1),
        ("star-4", 4, 1),
        ("front-between-behind", 3, 2),
    ] {
        let c = Calculus::builtin(name).unwrap();
        assert_eq!(c.n_states(), n, "{name}");
        assert_eq!(c.neighbours().diameter(), Some(diameter), "{name}");
    }
}

#[test]
fn star_and_extended_calculi_classify_in_their_frames() {
    let star = Calculus::builtin("star-4").unwrap();
    let o = Point2::new(10.0, 10.0);
    // Facing world +y: +y is front, −x is left, −y back, +x right.
    let yaw = std::f64::consts::FRAC_PI_2;
    for (p, want) in [
        ((10.0, 20.0), "front"),
        ((0.0, 10.0), "left"),
        ((10.0, 0.0), "back"),
        ((20.0, 10.0), "right"),
    ] {
        let s = star
            .classify_oriented(o, yaw, Point2::new(p.0, p.1))
            .unwrap();
        assert_eq!(star.label(s), want);
    }
    let fbb = Calculus::builtin("front-between-behind").unwrap();
    let w1 = qsr_core::Segment::new(Point2::new(0.0, 0.0), Point2::new(30.0, 0.0));
    let w2 = qsr_core::Segment::new(Point2::new(0.0, 10.0), Point2::new(30.0, 10.0));
    for (x, want) in [(-5.0, "behind"), (15.0, "between"), (40.0, "front")] {
        let s = fbb.classify_extended(w1, w2, Point2::new(x, 5.0)).unwrap();
        assert_eq!(fbb.label(s), want);
    }
    // Non-ternary calculi have no composition.
    assert!(matches!(
        star.compose_table(),
        Err(qsr_core::QsrError::Unsupported { .. })
    ));
}
