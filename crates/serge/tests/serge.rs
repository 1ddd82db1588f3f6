//! SERGE on hand-checkable cases and its invariants (thesis §3.2–3.3).
#![allow(clippy::unwrap_used)]

use serge::{
    Belief, BeliefSet, CellMasses, Grid, ResolutionTree, Serge, SergeError, SergeParams, baseline,
};

fn iso(mean: [f64; 2], var: f64) -> Belief {
    Belief::gaussian(mean, [[var, 0.0], [0.0, var]])
}

fn masses(beliefs: Vec<Belief>, n: usize) -> CellMasses {
    let set = BeliefSet::new(beliefs).unwrap();
    let grid = Grid::around(&set, n, n).unwrap();
    CellMasses::compute(&set, grid).unwrap()
}

#[test]
fn two_far_apart_gaussians_give_two_perfect_regions_or_one() {
    let m = masses(vec![iso([0.0, 0.0], 0.01), iso([10.0, 0.0], 0.01)], 40);
    let serge = Serge::new(&m).unwrap();
    let two = serge.run(&SergeParams::new(2, 0.0).trials(10)).unwrap();
    assert_eq!(two.n_regions, 2);
    assert_eq!(two.assignment, vec![0, 1]);
    assert!(two.log_saliency > -1e-9, "{}", two.log_saliency);
    let one = serge.run(&SergeParams::new(1, 0.0).trials(10)).unwrap();
    assert_eq!(one.n_regions, 1);
    assert_eq!(one.assignment, vec![0, 0]);
    // one region holds all of both beliefs (border cells extend to infinity)
    assert!(one.saliency.iter().all(|&s| (s - 1.0).abs() < 1e-12));
    // with σ > 0 and μ = 2, merging gains nothing in saliency: it stays at μ
    let soft = serge.run(&SergeParams::new(2, 2.0).trials(10)).unwrap();
    assert_eq!(soft.n_regions, 2);
}

#[test]
fn overlapping_beliefs_merge_when_sigma_allows_it() {
    // two beliefs on top of each other, one far away: separating the pair costs saliency
    // (each keeps only ~half its mass), so σ = 2, μ = 3 settles on 2 regions
    let m = masses(
        vec![
            iso([0.0, 0.0], 1.0),
            iso([0.2, 0.0], 1.0),
            iso([20.0, 0.0], 1.0),
        ],
        60,
    );
    let serge = Serge::new(&m).unwrap();
    let exact = serge.run(&SergeParams::new(3, 0.0).trials(30)).unwrap();
    assert_eq!(exact.n_regions, 3);
    let soft = serge.run(&SergeParams::new(3, 2.0).trials(30)).unwrap();
    assert_eq!(soft.n_regions, 2);
    assert_eq!(soft.assignment, vec![0, 0, 1]);
    assert!(soft.log_saliency > exact.log_saliency + 0.5);
    // and the potential agrees that this was worth it
    assert!(soft.log_phi() > exact.log_psi1_at(3, 2.0) + exact.log_saliency);
}

trait AtSigma {
    fn log_psi1_at(&self, mu: usize, sigma: f64) -> f64;
}
impl AtSigma for serge::SalientRegionMap {
    fn log_psi1_at(&self, mu: usize, sigma: f64) -> f64 {
        serge::log_psi1(self.n_regions, mu, sigma, self.beliefs.len())
    }
}

fn random_beliefs(seed: u64, k: usize) -> Vec<Belief> {
    use rand::{RngExt, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..k)
        .map(|_| {
            let v = rng.random_range(0.05..0.6);
            let c = rng.random_range(-0.5..0.5) * v;
            Belief::gaussian(
                [rng.random_range(0.0..6.0), rng.random_range(0.0..6.0)],
                [[v, c], [c, v * rng.random_range(0.5..1.5)]],
            )
        })
        .collect()
}

#[test]
fn invariants_hold_on_random_problems() {
    for seed in 0..4 {
        let m = masses(random_beliefs(seed, 12), 50);
        let serge = Serge::new(&m).unwrap();
        for (mu, sigma) in [(1, 2.0), (4, 0.0), (6, 2.0), (12, 1.0)] {
            let p = SergeParams::new(mu, sigma).trials(40).seed(seed);
            let map = serge.run(&p).unwrap();
            // every region contiguous and non-empty, every belief in one
            for r in 0..map.n_regions as u32 {
                assert_eq!(map.components(r), 1, "seed {seed} μ {mu}: region {r}");
                assert!(!map.region_beliefs(r).is_empty());
            }
            assert!(map.saliency.iter().all(|&s| (0.0..=1.0).contains(&s)));
            if sigma == 0.0 {
                assert_eq!(map.n_regions, mu);
            }
            // ψ never decreases across an accepted merge
            let trace = serge.trace(&p, 3).unwrap();
            // (σ = 0: log ψ1 is −∞ until |R| = μ, so only non-decrease can be asked)
            if sigma > 0.0 {
                assert!(trace.windows(2).all(|w| w[1] > w[0]), "{trace:?}");
            } else {
                assert!(trace.windows(2).all(|w| w[1] >= w[0]), "{trace:?}");
                assert!(trace.last().unwrap().is_finite());
            }
        }
    }
}

#[test]
fn result_does_not_depend_on_the_thread_count() {
    let m = masses(random_beliefs(11, 15), 50);
    let serge = Serge::new(&m).unwrap();
    let p = SergeParams::new(5, 2.0).trials(200).seed(3);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| serge.run(&p).unwrap());
    let two = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| serge.run(&p).unwrap());
    assert_eq!(one, two);
}

#[test]
fn the_naive_baseline_finds_the_same_map() {
    for seed in [1, 2] {
        let m = masses(random_beliefs(seed, 8), 24);
        let serge = Serge::new(&m).unwrap();
        let p = SergeParams::new(3, 2.0).trials(6).seed(seed);
        let fast = serge.run(&p).unwrap();
        let slow = baseline::run_naive(&serge, &p).unwrap();
        assert_eq!(fast.cell_region, slow.cell_region);
        assert_eq!(fast.best_trial, slow.best_trial);
        assert!((fast.log_phi() - slow.log_phi()).abs() < 1e-9);
    }
}

#[test]
fn bad_input_gets_typed_errors() {
    assert!(matches!(BeliefSet::new(vec![]), Err(SergeError::Empty(_))));
    // Regression (issue 17): 1e200·1e200 − (1e250)² overflowed to NaN and passed.
    assert!(matches!(
        BeliefSet::new(vec![Belief::gaussian(
            [0.0, 0.0],
            [[1e200, 1e250], [1e250, 1e200]]
        )]),
        Err(SergeError::DegenerateCovariance { .. })
    ));
    assert!(
        BeliefSet::new(vec![Belief::gaussian(
            [0.0, 0.0],
            [[1e300, 0.0], [0.0, 1e300]]
        )])
        .is_ok()
    );
    assert!(matches!(
        BeliefSet::new(vec![Belief::gaussian([0.0, 0.0], [[1.0, 1.0], [1.0, 1.0]])]),
        Err(SergeError::DegenerateCovariance { .. })
    ));
    assert!(matches!(
        BeliefSet::new(vec![Belief::gaussian(
            [f64::NAN, 0.0],
            [[1.0, 0.0], [0.0, 1.0]]
        )]),
        Err(SergeError::NonFinite(_))
    ));
    assert!(matches!(
        BeliefSet::new(vec![Belief::samples(vec![])]),
        Err(SergeError::Empty(_))
    ));
    assert!(matches!(
        BeliefSet::from_json_str(r#"{"beliefs": [{"mean": [0, 0]}]}"#, "x"),
        Err(SergeError::Parse { .. })
    ));
    let m = masses(vec![iso([0.0, 0.0], 0.1), iso([3.0, 0.0], 0.1)], 20);
    let serge = Serge::new(&m).unwrap();
    for p in [
        SergeParams::new(0, 1.0),
        SergeParams::new(3, 1.0),
        SergeParams::new(1, -1.0),
        SergeParams::new(1, f64::NAN),
        SergeParams::new(1, 1.0).trials(0),
    ] {
        assert!(
            matches!(serge.run(&p), Err(SergeError::InvalidParameter(_))),
            "{p:?}"
        );
    }
    assert!(matches!(
        Grid::new([0.0, 0.0, 0.0, 1.0], 3, 3),
        Err(SergeError::InvalidParameter(_))
    ));
}

#[test]
fn json_input_round_trips() {
    let text = r#"{"beliefs": [{"mean": [0, 0], "cov": [[1, 0.2], [0.2, 1]]},
                              {"samples": [[3, 3], [3.5, 3.1]]}]}"#;
    let set = BeliefSet::from_json_str(text, "inline").unwrap();
    assert_eq!(set.len(), 2);
    let again = BeliefSet::from_json_str(&set.to_json().to_string(), "again").unwrap();
    assert_eq!(set, again);
}

#[test]
fn resolution_tree_levels_and_coarse_to_fine_plan() {
    // four clusters of three objects in the corners of a square
    let mut beliefs = Vec::new();
    for (cx, cy) in [(0.0, 0.0), (10.0, 0.0), (0.0, 10.0), (10.0, 10.0)] {
        for d in [0.0, 1.5, 3.0] {
            beliefs.push(iso([cx + d, cy], 0.05));
        }
    }
    let m = masses(beliefs, 60);
    let mut tree = ResolutionTree::new(&m);
    let p = SergeParams::new(2, 0.5).trials(50).seed(1);
    tree.grow(2, &p).unwrap();
    let level1 = tree.map_of(&tree.cut_at_level(1)).unwrap();
    let level2 = tree.map_of(&tree.cut_at_level(2)).unwrap();
    assert_eq!(level1.n_regions, 2);
    assert_eq!(level2.n_regions, 4);
    // each level-2 region is one cluster: beliefs 3i..3i+3 together
    for r in 0..4 {
        let b = level2.region_beliefs(r);
        assert_eq!(b.len(), 3);
        assert_eq!(b[0] / 3, b[2] / 3);
    }
    // a mixed cut: one branch at level 1, the other at level 2
    let root_children = tree.node(0).unwrap().children.clone();
    let mut mixed = vec![root_children[0]];
    mixed.extend(tree.node(root_children[1]).unwrap().children.clone());
    assert_eq!(tree.map_of(&mixed).unwrap().n_regions, 3);
    // a cut that leaves a hole is rejected
    assert!(tree.map_of(&[root_children[0]]).is_err());
    // plan from the bottom-left object to the top-right one
    let mut tree = ResolutionTree::new(&m);
    let plan = tree.plan([0.0, 0.0], [13.0, 10.0], &p, 8).unwrap();
    let goal = tree.node(plan.goal_node).unwrap();
    assert_eq!(goal.beliefs, vec![11]);
    assert!(
        plan.regions_considered() < 12,
        "{}",
        plan.regions_considered()
    );
    for level in &plan.levels {
        assert_eq!(
            level.path.last(),
            level.regions.iter().find(|&&r| tree
                .node(r)
                .unwrap()
                .cells
                .contains(&m.grid().cell_of([13.0, 10.0])))
        );
    }
}

/// Regression (issue 17): `serge run --sigma 1e300` printed `log φ -inf` (the Gaussian's
/// normalising constant overflowed) and a window of ±1.7e308 gave infinitely wide cells.
#[test]
fn extreme_sigma_and_windows_stay_finite_or_are_refused() {
    for sigma in [1e300, 1e-300, 1e-160, 1.0] {
        let v = serge::log_psi1(3, 2, sigma, 5);
        assert!(!v.is_nan(), "σ = {sigma}: {v}");
        if sigma >= 1.0 {
            assert!(v.is_finite(), "σ = {sigma}: {v}");
        }
    }
    // σ → ∞: every region count equally likely, ψ1 = 1/K.
    assert!((serge::log_psi1(3, 2, 1e300, 5) + 5f64.ln()).abs() < 1e-12);
    assert!(Grid::new([-1.7e308, 1.7e308, 0.0, 1.0], 10, 10).is_err());
    let m = masses(
        vec![
            iso([0.0, 0.0], 1.0),
            iso([3.0, 0.0], 1.0),
            iso([0.0, 3.0], 1.0),
        ],
        30,
    );
    let map = Serge::new(&m)
        .unwrap()
        .run(&SergeParams::new(2, 1e300).trials(20))
        .unwrap();
    assert!(map.log_phi().is_finite(), "log φ {}", map.log_phi());
}

/// Issue 17: work and memory are estimated before starting; impossible sizes are refused
/// with the estimate instead of running forever or aborting in the allocator.
#[test]
fn runaway_trials_and_masses_are_refused_with_the_estimate() {
    let m = masses(
        vec![
            iso([0.0, 0.0], 1.0),
            iso([3.0, 0.0], 1.0),
            iso([0.0, 3.0], 1.0),
        ],
        30,
    );
    let e = Serge::new(&m)
        .unwrap()
        .run(&SergeParams::new(2, 1.0).trials(usize::MAX))
        .unwrap_err()
        .to_string();
    assert!(e.contains("limit") && e.contains("trials"), "{e}");
    let beliefs: Vec<Belief> = (0..400).map(|i| iso([f64::from(i), 0.0], 1.0)).collect();
    let set = BeliefSet::new(beliefs).unwrap();
    let grid = Grid::new([0.0, 400.0, -5.0, 5.0], 2000, 2000).unwrap();
    let e = CellMasses::compute(&set, grid).unwrap_err().to_string();
    assert!(e.contains("GiB"), "{e}");
}
