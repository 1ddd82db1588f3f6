//! Learned calculi (thesis §3.3.2): export, round trip through qsr-core and pqrm, and the
//! soundness of the Algorithm 3 compose table.
#![allow(clippy::unwrap_used)]

use qsr_core::{Calculus, ComposeOptions, Point2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serge::learn::{TripletObservation, compose_coverage, compose_table, triplet_beliefs};
use serge::{CellMasses, Grid, SalientRegionMap, Serge, SergeParams};

/// Triplets in a few typical arrangements, observed with noise: F left, right, ahead,
/// behind and between D and E.
fn learned_map() -> SalientRegionMap {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let layouts = [
        [[0.0, 0.0], [0.0, 4.0], [-3.0, 2.0]],
        [[0.0, 0.0], [0.0, 4.0], [3.0, 2.0]],
        [[0.0, 0.0], [0.0, 4.0], [0.0, 9.0]],
        [[0.0, 0.0], [0.0, 4.0], [0.5, -4.0]],
        [[1.0, 1.0], [5.0, 1.0], [3.0, -2.0]],
        [[1.0, 1.0], [5.0, 1.0], [3.0, 3.0]],
    ];
    let cov = [[0.05, 0.0], [0.0, 0.05]];
    let mut obs = Vec::new();
    for (k, l) in layouts.iter().enumerate() {
        for _ in 0..10 {
            let jitter = |p: [f64; 2], rng: &mut ChaCha8Rng| {
                [
                    p[0] + rng.random_range(-0.1..0.1),
                    p[1] + rng.random_range(-0.1..0.1),
                ]
            };
            obs.push(TripletObservation {
                triplet: k,
                points: [
                    jitter(l[0], &mut rng),
                    jitter(l[1], &mut rng),
                    jitter(l[2], &mut rng),
                ],
                cov: [cov; 3],
            });
        }
    }
    let beliefs = triplet_beliefs(&obs, layouts.len(), 3_000, 9).unwrap();
    let grid = Grid::new([-2.0, 2.0, -1.5, 2.5], 32, 32).unwrap();
    let masses = CellMasses::compute(&beliefs, grid).unwrap();
    Serge::new(&masses)
        .unwrap()
        .run(&SergeParams::new(5, 2.0).trials(200).seed(2))
        .unwrap()
}

#[test]
fn the_learned_calculus_partitions_the_plane_and_round_trips() {
    let map = learned_map();
    let calc = map.to_calculus("toy", "test").unwrap();
    assert_eq!(calc.n_states(), map.n_regions);
    let back = Calculus::from_json_str(&calc.spec().to_json_string().unwrap()).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..20_000 {
        // near and far, including points exactly on cell edges
        let scale: f64 = [0.5, 3.0, 100.0][rng.random_range(0..3)];
        let p = [
            rng.random_range(-scale..scale),
            rng.random_range(-scale..scale),
        ];
        let s = back.classify_normalised(&Point2::new(p[0], p[1]));
        assert!(s.index() < calc.n_states());
        assert_eq!(Some(u32::from(s.0)), map.region_of(p), "{p:?}");
    }
    for i in -8..=8 {
        let p = [f64::from(i) * 0.125, f64::from(i) * 0.125];
        let s = back.classify_normalised(&Point2::new(p[0], p[1]));
        assert_eq!(Some(u32::from(s.0)), map.region_of(p));
    }
}

#[test]
fn pqrm_maps_with_a_learned_calculus() {
    use pqrm::{LandmarkId, LandmarkSet, Observation, Pqrm, PqrmConfig, Scan};
    let calc = learned_map().to_calculus("toy", "test").unwrap();
    let mut map = Pqrm::new(calc.clone(), PqrmConfig::default()).unwrap();
    // D, E, F as in the first layout: F left of D→E
    let pts = [[0.0, 0.0], [0.0, 4.0], [-3.0, 2.0]];
    for _ in 0..5 {
        let obs = pts
            .iter()
            .enumerate()
            .map(|(i, p)| Observation::isotropic(LandmarkId(i as u32), *p, 0.05).unwrap())
            .collect();
        map.update(&Scan::new(0.0, 0, obs).unwrap()).unwrap();
    }
    let set = LandmarkSet::new(0, 1, 2);
    let belief = map.belief(set).unwrap();
    let truth = calc.classify_triplet(
        Point2::new(0.0, 0.0),
        Point2::new(0.0, 4.0),
        Point2::new(-3.0, 2.0),
    );
    let truth = truth.unwrap();
    let ml = belief
        .iter()
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(b.1))
        .map(|(i, _)| i)
        .unwrap();
    assert_eq!(ml, truth.index());
    assert!(belief[ml] > 0.9, "{belief:?}");
}

#[test]
fn algorithm_3_is_sound_for_random_configurations() {
    let calc = learned_map().to_calculus("toy", "test").unwrap();
    let table = compose_table(&calc, &|| {}).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let a = Point2::new(0.0, 0.0);
    let b = Point2::new(0.0, 1.0);
    for i in 0..100_000 {
        let scale: f64 = [0.3, 2.0, 50.0][i % 3];
        let pick = |rng: &mut ChaCha8Rng| {
            if i % 5 == 0 {
                // on the dyadic lattice: exactly on cell edges
                Point2::new(
                    f64::from(rng.random_range(-24i32..24)) / 8.0,
                    f64::from(rng.random_range(-24i32..24)) / 8.0,
                )
            } else {
                Point2::new(
                    rng.random_range(-scale..scale),
                    rng.random_range(-scale..scale),
                )
            }
        };
        let c = pick(&mut rng);
        let d = pick(&mut rng);
        let (Ok(r), Ok(s), Ok(t)) = (
            calc.classify_triplet(a, b, c),
            calc.classify_triplet(b, c, d),
            calc.classify_triplet(a, b, d),
        ) else {
            continue; // coincident points
        };
        assert!(
            table.get(r, s).contains(&t),
            "{{AB:C}} = {r}, {{BC:D}} = {s}, {{AB:D}} = {t} missing (C {c:?}, D {d:?})"
        );
    }
    // and qsr-core's witnessed table is a subset
    let sampled = calc
        .compose_table_with(&ComposeOptions {
            samples_per_pair: 2_000,
            ..ComposeOptions::default()
        })
        .unwrap();
    for r in calc.states() {
        for s in calc.states() {
            for t in sampled.get(r, s) {
                assert!(table.get(r, s).contains(t));
            }
        }
    }
    assert!(table.n_entries() >= sampled.n_entries());
    // Fig 3.10: the coverage picture gives the same states as the table entry
    let (r, s) = (calc.states().next().unwrap(), calc.states().nth(1).unwrap());
    let (covered, states) = compose_coverage(&calc, r, s).unwrap();
    assert_eq!(states, table.get(r, s));
    assert!(covered.iter().any(|&c| c));
}

#[test]
fn algorithm_3_needs_a_raster_calculus() {
    let edc = Calculus::builtin("edc").unwrap();
    assert!(compose_table(&edc, &|| {}).is_err());
    // a rasterised EDC composes soundly against the original's configurations
    let raster = edc
        .rasterise([-3.0, 3.0, -2.0, 3.0], 24, 20, qsr_core::OutsideRule::Clamp)
        .unwrap();
    let table = compose_table(&raster, &|| {}).unwrap();
    let sampled = raster.compose_table().unwrap();
    for r in raster.states() {
        for s in raster.states() {
            for t in sampled.get(r, s) {
                assert!(table.get(r, s).contains(t), "{r} {s} {t}");
            }
        }
    }
}
