//! Binary calculi: the derived tables are exact (independent of the grid, sound for random and
//! degenerate configurations), converse is an involution, neighbours are what motion allows,
//! closure keeps the truth and catches contradictions.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use qsr_core::Point2;
use qsr_core::binary::{BinaryCalculus, BinaryNetwork, close_binary};
use qsr_core::reason::StateSet;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[test]
fn tables_do_not_depend_on_the_grid_once_it_is_fine_enough() {
    for (name, finer) in [
        ("opra-1", &[7usize, 12][..]),
        ("opra-2", &[7]),
        ("star-8", &[7, 12]),
    ] {
        let c = BinaryCalculus::builtin(name).unwrap();
        let (conv6, comp6) = c.derive_tables_with(6);
        for &k in finer {
            let (conv, comp) = c.derive_tables_with(k);
            assert_eq!(conv, conv6, "{name}: converse at {k} ticks per unit");
            for r in c.states() {
                for s in c.states() {
                    assert_eq!(
                        comp.get(r, s),
                        comp6.get(r, s),
                        "{name}: {r} ∘ {s} at {k} ticks"
                    );
                }
            }
        }
    }
}

#[test]
fn a_grid_too_coarse_misses_compositions() {
    // The test above would pass vacuously if every grid gave the same table: one tick per
    // unit cannot place a point strictly inside a sector, so it must lose entries.
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    let (_, coarse) = c.derive_tables_with(1);
    assert!(coarse.n_entries() < c.compose_table().unwrap().n_entries());
}

type Config = [(Point2<f64>, f64); 3];

fn check_config(c: &BinaryCalculus, cfg: &Config) {
    // STAR's reference direction is shared by all points.
    let mut cfg = *cfg;
    if !c.is_oriented() {
        let shared = cfg[0].1;
        for p in &mut cfg {
            p.1 = shared;
        }
    }
    let rel = |i: usize, j: usize| c.classify(cfg[i].0, cfg[i].1, cfg[j].0, cfg[j].1).unwrap();
    let (r, s, t) = (rel(0, 1), rel(1, 2), rel(0, 2));
    assert!(
        c.compose_table().unwrap().get(r, s).contains(&t),
        "{}: {} ∘ {} lacks {} for {cfg:?}",
        c.name(),
        c.label(r),
        c.label(s),
        c.label(t)
    );
    assert_eq!(
        c.converse().get(r),
        &[rel(1, 0)],
        "{}: converse of {}",
        c.name(),
        c.label(r)
    );
}

#[test]
fn random_configurations_are_in_the_tables() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    for name in ["opra-1", "opra-2", "opra-3", "star-4", "star-8"] {
        let c = BinaryCalculus::builtin(name).unwrap();
        for _ in 0..20_000 {
            let mut cfg: Config = [(Point2::origin(), 0.0); 3];
            for p in &mut cfg {
                *p = (
                    Point2::new(rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)),
                    rng.random_range(0.0..TAU),
                );
            }
            check_config(&c, &cfg);
        }
    }
}

#[test]
fn degenerate_configurations_are_in_the_tables() {
    // Points on a lattice with headings on multiples of π/4: collinear triples, rays and
    // coincident points, all exact up to the classifier's ray tolerance.
    let lattice: Vec<Point2<f64>> = (-1..=1)
        .flat_map(|x| (-1..=1).map(move |y| Point2::new(f64::from(x), f64::from(y))))
        .collect();
    let headings: Vec<f64> = (0..8).map(|k| f64::from(k) * PI / 4.0).collect();
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for name in ["opra-1", "opra-2", "star-8"] {
        let c = BinaryCalculus::builtin(name).unwrap();
        let mut seen = StateSet::empty(c.n_states());
        for _ in 0..30_000 {
            let mut cfg: Config = [(Point2::origin(), 0.0); 3];
            for p in &mut cfg {
                *p = (
                    lattice[rng.random_range(0..lattice.len())],
                    headings[rng.random_range(0..headings.len())],
                );
            }
            seen.insert(c.classify(cfg[0].0, cfg[0].1, cfg[1].0, cfg[1].1).unwrap());
            check_config(&c, &cfg);
        }
        assert_eq!(
            seen.len(),
            c.n_states(),
            "{name}: the lattice reaches every relation"
        );
    }
}

#[test]
fn converse_is_an_involution_and_identity_composes_neutrally() {
    for name in ["opra-1", "opra-4", "star-8", "star-32"] {
        let c = BinaryCalculus::builtin(name).unwrap();
        let id = c
            .state(if name.starts_with("opra") {
                "s_0"
            } else {
                "eq"
            })
            .unwrap();
        for r in c.states() {
            let conv = c.converse().get(r);
            assert_eq!(conv.len(), 1);
            assert_eq!(
                c.converse().get(conv[0]),
                &[r],
                "{name}: conv(conv({}))",
                c.label(r)
            );
            if name != "opra-4" {
                assert_eq!(c.compose_table().unwrap().get(r, id), &[r]);
                assert_eq!(c.compose_table().unwrap().get(id, r), &[r]);
            }
        }
    }
}

#[test]
fn opra_sizes_match_the_literature() {
    for m in 1..=4usize {
        let c = BinaryCalculus::builtin(&format!("opra-{m}")).unwrap();
        assert_eq!(c.n_states(), 16 * m * m + 4 * m);
    }
    assert_eq!(BinaryCalculus::builtin("opra-4").unwrap().n_states(), 272);
    assert!(BinaryCalculus::builtin("opra-0").is_err());
    assert!(BinaryCalculus::builtin("star-7").is_err());
}

#[test]
fn neighbours_follow_motion() {
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    let g = c.neighbours().unwrap();
    let s = |l: &str| c.state(l).unwrap();
    // B straight ahead of A, A straight behind B: moving B onto A leaves B's heading = A's.
    assert!(g.is_adjacent(s("0_2"), s("s_0")));
    assert!(!g.is_adjacent(s("0_2"), s("s_1")));
    // Turning B's heading a little moves A off the ray behind B into an open sector.
    assert!(g.is_adjacent(s("0_2"), s("0_1")));
    assert!(g.is_adjacent(s("0_2"), s("0_3")));
    // Opposite rays are not one step apart.
    assert!(!g.is_adjacent(s("0_2"), s("2_2")));
    assert!(g.diameter().is_some(), "connected");
    let star = BinaryCalculus::builtin("star-8").unwrap();
    let sg = star.neighbours().unwrap();
    let t = |l: &str| star.state(l).unwrap();
    assert!(sg.is_adjacent(t("front"), t("front-left")));
    assert!(!sg.is_adjacent(t("front"), t("left")));
    assert!(sg.is_adjacent(t("front"), t("eq")));
}

#[test]
fn closure_keeps_the_truth_of_real_configurations() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let c = BinaryCalculus::builtin("opra-2").unwrap();
    for _ in 0..20 {
        let pts: Vec<(Point2<f64>, f64)> = (0..6)
            .map(|_| {
                (
                    Point2::new(rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)),
                    rng.random_range(0.0..TAU),
                )
            })
            .collect();
        let names = ["A", "B", "C", "D", "E", "F"];
        let exact = BinaryNetwork::from_points(&c, names, &pts).unwrap();
        let mut net = exact.clone();
        // Forget everything about A–D and B–E.
        let any = StateSet::universal(c.n_states());
        net.set(0, 3, &any);
        net.set(1, 4, &any);
        let closed = close_binary(net).unwrap();
        assert!(closed.is_consistent());
        for (i, j) in [(0, 3), (1, 4), (3, 0)] {
            let inferred = closed.network.get(i, j);
            assert!(inferred.is_superset(&exact.get(i, j)));
            assert!(inferred.len() < c.n_states(), "closure narrowed {i}–{j}");
        }
    }
}

#[test]
fn closure_finds_a_contradiction_and_names_it() {
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    // Facing each other in a row, but C both ahead of A and on A's left.
    let net = BinaryNetwork::from_sparq_str(&c, "((A 0_0 B) (B 0_0 C) (A (1_1 1_3) C))").unwrap();
    let closed = close_binary(net).unwrap();
    assert!(!closed.is_consistent());
    let why = closed.describe().unwrap();
    assert!(why.contains('A') && why.contains('C'), "{why}");
}

#[test]
fn bad_networks_are_refused_with_their_position() {
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    for (text, needle) in [
        ("((A 9_9 B))", "no relation `9_9`"),
        ("((A 0_0 A))", "related to itself"),
        ("((A 0_0))", "(A r B)"),
        ("((A 0_0 B)", "never closed"),
    ] {
        let e = BinaryNetwork::from_sparq_str(&c, text)
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{text}: {e}");
    }
}

#[test]
fn classify_refuses_non_finite_input_and_handles_huge_coordinates() {
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    assert!(
        c.classify(Point2::new(f64::NAN, 0.0), 0.0, Point2::origin(), 0.0)
            .is_err()
    );
    assert!(c.classify_row(&[0.0, 0.0, 0.0, 1.0]).is_err());
    // 1e300 apart is not "the same position" (the test is scale-free, nothing overflows).
    let r = c
        .classify(
            Point2::new(-1e300, 0.0),
            0.0,
            Point2::new(1e300, 0.0),
            FRAC_PI_2,
        )
        .unwrap();
    assert_eq!(c.label(r), "0_1", "B faces +y and sees A on its left");
    let same = c
        .classify(Point2::new(1e300, 0.0), 0.0, Point2::new(1e300, 0.0), PI)
        .unwrap();
    assert_eq!(c.label(same), "s_2");
}

#[test]
fn binary_star_names_the_sectors_as_the_oriented_spec_calculus_does() {
    // `star-m` is one name for two views: the oriented spec calculus (Q-Link's frame) and
    // the STAR algebra. Off the boundary rays they must classify every point alike.
    let mut rng = ChaCha8Rng::seed_from_u64(8);
    for m in [4usize, 8, 16] {
        let name = format!("star-{m}");
        let spec = qsr_core::Calculus::builtin(&name).unwrap();
        let star = BinaryCalculus::builtin(&name).unwrap();
        for _ in 0..5_000 {
            let o = Point2::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            let yaw = rng.random_range(-PI..PI);
            let p = Point2::new(rng.random_range(-2.0..2.0), rng.random_range(-2.0..2.0));
            let a = spec.label(spec.classify_oriented(o, yaw, p).unwrap());
            let b = star.label(star.classify(o, yaw, p, 0.0).unwrap());
            assert_eq!(a, b, "{name}: {o:?} yaw {yaw} → {p:?}");
        }
    }
}

#[test]
fn any_opra_granularity_classifies_and_too_fine_tables_are_refused_with_the_estimate() {
    // OPRA-63 is the finest a 16-bit relation id holds: classification and converse work.
    let fine = BinaryCalculus::builtin("opra-63").unwrap();
    assert_eq!(fine.n_states(), 16 * 63 * 63 + 4 * 63);
    let r = fine
        .classify(Point2::origin(), 0.0, Point2::new(1.0, 0.0), PI)
        .unwrap();
    assert_eq!(fine.label(r), "0_0");
    assert_eq!(fine.converse().get(r), &[r]);
    // Its composition would need hundreds of GiB: refused before anything is allocated.
    let e = fine.compose_table().unwrap_err().to_string();
    assert!(e.contains("GiB") && e.contains("limits"), "{e}");
    assert!(fine.neighbours().unwrap_err().to_string().contains("GiB"));
    assert!(
        BinaryCalculus::builtin("opra-11")
            .unwrap()
            .compose_table()
            .is_err()
    );
    assert!(
        BinaryCalculus::builtin("opra-64").is_err(),
        "ids are 16 bits"
    );
    let cost = BinaryCalculus::builtin("opra-10").unwrap().compose_cost();
    assert!(cost.fits(&qsr_core::binary::DERIVATION_BUDGET), "{cost}");
}

/// Regression (issue 17): points 1e300 apart were "coincident" because the tolerance test
/// overflowed (inf ≤ inf), and points ~1e308 apart normalised every third point to (0, 0).
#[test]
fn far_apart_reference_points_are_not_coincident_and_overflow_is_named() {
    let edc = qsr_core::Calculus::builtin("edc").unwrap();
    let r = edc.classify_triplet(
        Point2::new(0.0, 0.0),
        Point2::new(0.0, 1e150),
        Point2::new(-2e149, 3e149),
    );
    assert_eq!(
        edc.label(r.unwrap()),
        "13",
        "a scaled copy of the doc example"
    );
    // Beyond ~1e154 apart |B − A|² overflows: named as such, not as "coincide".
    for far in [1e300, 1e308] {
        let e = edc
            .classify_triplet(
                Point2::new(0.0, -far),
                Point2::new(0.0, far),
                Point2::origin(),
            )
            .unwrap_err()
            .to_string();
        assert!(e.contains("too far apart"), "{e}");
    }
    let same = edc.classify_triplet(
        Point2::new(1e300, 0.0),
        Point2::new(1e300, 0.0),
        Point2::origin(),
    );
    assert!(same.unwrap_err().to_string().contains("coincide"));
}

/// Regression: two disjoint sets given for one pair of a two-point network left that pair
/// empty, and closure (with no third point to compose through) called the network consistent.
#[test]
fn a_pair_empty_as_given_is_inconsistent() {
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    let net = BinaryNetwork::from_sparq_str(&c, "((A 1_3 B) (A 3_1 B))").unwrap();
    let closed = close_binary(net).unwrap();
    assert!(!closed.is_consistent());
    assert!(closed.describe().unwrap().contains("given for A and B"));
}
