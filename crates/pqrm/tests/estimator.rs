//! The estimator `p(R | Z)` (eq. 2.9) against things derived independently of the sampler,
//! and the Bayes filter's algebra.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use pqrm::likelihood::{
    LandmarkSet, Orderings, StepCounts, log_likelihood, merge_counts, step_counts,
};
use pqrm::study::single_observation;
use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, PqrmError, Scan, ScanSamples};
use qsr_core::{Calculus, Point2};

const Z: [[f64; 2]; 2] = [[0.0, 0.0], [0.0, 0.0]];

fn iso(s: f64) -> [[f64; 2]; 2] {
    [[s * s, 0.0], [0.0, s * s]]
}

/// Standard normal CDF (Abramowitz–Stegun 7.1.26 through erf, |error| < 1.5e-7).
fn phi(x: f64) -> f64 {
    let z = x / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z.abs());
    let y = 1.0
        - (((((1.061_405_429 * t - 1.453_152_027) * t) + 1.421_413_741) * t - 0.284_496_736) * t
            + 0.254_829_592)
            * t
            * (-z * z).exp();
    0.5 * (1.0 + if z >= 0.0 { y } else { -y })
}

#[test]
fn left_right_with_noise_on_c_only_is_phi_of_distance_over_sigma() {
    let lr = Calculus::builtin("left-right").unwrap();
    let s = 40_000;
    for (d, sigma) in [(0.5, 1.0), (1.0, 1.0), (-0.3, 0.5), (2.0, 1.5), (0.0, 1.0)] {
        // A = (0,0), B = (0,10): C = (−d, 5) is d to the left of A→B.
        let p = single_observation(
            &lr,
            [[0.0, 0.0], [0.0, 10.0], [-d, 5.0]],
            [Z, Z, iso(sigma)],
            s,
            0.0,
            11,
        )
        .unwrap();
        let want = phi(d / sigma);
        let se = (want * (1.0 - want) / s as f64).sqrt().max(1e-4);
        assert!(
            (p[0] - want).abs() < 4.0 * se,
            "d={d} σ={sigma}: p(left)={} want {want}",
            p[0]
        );
    }
}

#[test]
fn tiny_noise_concentrates_on_the_true_state() {
    let edc = Calculus::builtin("edc").unwrap();
    for (c, label) in [
        ([-0.3, 0.25], "13"),
        ([0.9, 0.75], "9"),
        ([2.0, -3.0], "20"),
    ] {
        let p = single_observation(
            &edc,
            [[0.0, 0.0], [0.0, 1.0], c],
            [iso(1e-7); 3],
            500,
            0.0,
            3,
        )
        .unwrap();
        let s = edc.state(label).unwrap().index();
        assert_eq!(p[s], 1.0, "{label}: {p:?}");
    }
}

/// The huge-noise limit, derived without the sampler. With A, B, C i.i.d. N(m_i, σ²I) and
/// σ → ∞ the means do not matter; u = B − A ~ N(0, 2σ²I) is independent of C − M (M the
/// midpoint) ~ N(0, 1.5σ²I), and C's normalised position is (x, y − ½) = (−w₂, w₁)/|u| with
/// w ~ N(0, 1.5σ²I): √(3/4)·Z/R with Z, R = |Z'| independent, i.e. √(3/8)·T with T a standard
/// bivariate t with 2 degrees of freedom. In coordinates (v, θ) with r² = 2s²·v/(1 − v)
/// (s² = 3/8) its measure is uniform, dv·dθ/2π, so a midpoint grid integrates it exactly up to
/// the grid's resolution.
fn huge_noise_limit(calc: &Calculus, n: usize) -> Vec<f64> {
    let s2 = 3.0 / 8.0;
    let mut p = vec![0.0; calc.n_states()];
    for i in 0..n {
        let v = (i as f64 + 0.5) / n as f64;
        let r = (2.0 * s2 * v / (1.0 - v)).sqrt();
        for j in 0..n {
            let th = std::f64::consts::TAU * (j as f64 + 0.5) / n as f64;
            let q = Point2::new(r * th.cos(), 0.5 + r * th.sin());
            p[calc.classify_normalised(&q).index()] += 1.0;
        }
    }
    p.iter().map(|c| c / (n * n) as f64).collect()
}

#[test]
fn huge_noise_tends_to_the_derived_bivariate_t_limit() {
    // Closed form for the double cross: P(y ≥ 1) = P(T ≥ (1/2)/s) = 1/4 for the t₂ marginal
    // F(t) = 1/2 + t / (2√(2 + t²)), so front/middle/back = 1/4, 1/2, 1/4, halved by side.
    let dc = Calculus::builtin("double-cross").unwrap();
    let grid = huge_noise_limit(&dc, 600);
    for (label, want) in [
        ("left-front", 0.125),
        ("right-front", 0.125),
        ("left-middle", 0.25),
        ("right-middle", 0.25),
    ] {
        assert!(
            (grid[dc.state(label).unwrap().index()] - want).abs() < 2e-3,
            "{label}: grid {grid:?}"
        );
    }
    // The sampler with σ = 10^6 on all three (means far apart, irrelevant at that noise).
    let samples = 200_000;
    for name in ["double-cross", "edc"] {
        let calc = Calculus::builtin(name).unwrap();
        let want = huge_noise_limit(&calc, 1500);
        let got = single_observation(
            &calc,
            [[3.0, -2.0], [40.0, 7.0], [-5.0, 12.0]],
            [iso(1e6); 3],
            samples,
            0.0,
            5,
        )
        .unwrap();
        for (q, (g, w)) in got.iter().zip(&want).enumerate() {
            let se = (w * (1.0 - w) / samples as f64).sqrt();
            assert!(
                (g - w).abs() < 5.0 * se + 1e-3,
                "{name} state {}: sampled {g}, derived {w}",
                calc.labels()[q]
            );
        }
    }
}

fn scan(points: &[(u32, [f64; 2])], sigma: f64) -> Scan {
    Scan::new(
        0.0,
        0,
        points
            .iter()
            .map(|(i, p)| Observation::isotropic(LandmarkId(*i), *p, sigma).unwrap())
            .collect(),
    )
    .unwrap()
}

#[test]
fn the_filter_is_commutative_in_the_order_of_observations() {
    let edc = Calculus::builtin("edc").unwrap();
    let steps: Vec<StepCounts> = (0..6)
        .map(|k| {
            let sc = scan(
                &[
                    (1, [0.0, 0.0]),
                    (2, [0.0, 1.0]),
                    (3, [0.2 + 0.05 * f64::from(k), 0.45]),
                ],
                0.3,
            );
            step_counts(
                &edc,
                &ScanSamples::draw(&sc, 300, 9, k as u64),
                Orderings::All,
            )
            .unwrap()
        })
        .collect();
    let build = |order: &[usize]| {
        let mut m = Pqrm::new(edc.clone(), PqrmConfig::default()).unwrap();
        for &k in order {
            m.apply_counts(&steps[k]).unwrap();
        }
        m
    };
    let (a, b) = (build(&[0, 1, 2, 3, 4, 5]), build(&[5, 3, 1, 0, 4, 2]));
    for (set, belief) in a.iter() {
        let other = b.record(set).unwrap();
        // the map keeps log-probabilities in f32 between steps: equal up to that rounding
        for (x, y) in belief.log_p.iter().zip(&other.log_p) {
            assert!(
                (x - y).abs() < 1e-5 * x.abs().max(1.0),
                "{set:?}: {x} vs {y}"
            );
        }
    }
}

#[test]
fn ten_million_updates_stay_finite_and_normalised() {
    let q = Calculus::builtin("quadrant").unwrap();
    let mut m = Pqrm::new(
        q,
        PqrmConfig {
            floor: 0.5,
            ..PqrmConfig::default()
        },
    )
    .unwrap();
    let set = LandmarkSet::new(1, 2, 3);
    // Evidence mildly against the true state half the time: no underflow, no NaN.
    let e1 = StepCounts::from_vecs(&[(set, vec![600, 200, 150, 50])]).unwrap();
    let e2 = StepCounts::from_vecs(&[(set, vec![100, 500, 300, 100])]).unwrap();
    for k in 0..10_000_000u32 {
        m.apply_counts(if k % 2 == 0 { &e1 } else { &e2 }).unwrap();
    }
    let b = m.record(&set).unwrap();
    assert!(b.log_p.iter().all(|v| v.is_finite()), "{:?}", b.log_p);
    let total: f64 = b.probabilities().iter().sum();
    assert!((total - 1.0).abs() < 1e-9, "{total}");
    assert_eq!(b.updates, 10_000_000);
    // Per pair of updates state q gains ln((c1_q + ½)(c2_q + ½)): state 1 (200.5·500.5) beats
    // state 0 (600.5·100.5); after 5·10^6 pairs the log-odds are, in exact arithmetic, 5·10^6 times that.
    assert_eq!(b.ml_state().0, 1);
    let want = 5e6 * ((600.5f64 * 100.5) / (200.5 * 500.5)).ln();
    let got = b.log_p[0] - b.log_p[1];
    // The map keeps log-probabilities in f32 between steps: at 2.5e6 nats a step's rounding
    // is up to 0.125, so the ruled-out state's log-odds drift by about 1 % over 10^7 steps
    // (its probability is 0 in either precision). A filter adding the wrong evidence, or
    // dropping the normalisation, is off by far more.
    assert!(
        ((got - want) / want).abs() < 0.05,
        "log-odds {got} vs {want}"
    );
}

#[test]
fn merged_counts_equal_sampling_the_coarser_calculus_statistically() {
    let edc = Calculus::builtin("edc").unwrap();
    let sc = scan(
        &[
            (1, [0.0, 0.0]),
            (2, [0.0, 2.0]),
            (3, [0.4, 1.2]),
            (4, [-1.0, 0.1]),
        ],
        0.6,
    );
    let s = 20_000;
    let fine = step_counts(&edc, &ScanSamples::draw(&sc, s, 1, 0), Orderings::All).unwrap();
    for name in &qsr_core::POINT_CALCULI[1..] {
        let coarse = Calculus::builtin(name).unwrap();
        let merge = edc.merge_map(&coarse).unwrap();
        let direct =
            step_counts(&coarse, &ScanSamples::draw(&sc, s, 2, 0), Orderings::All).unwrap();
        for ((set, f), (set2, d)) in fine.iter().zip(direct.iter()) {
            assert_eq!(set, set2);
            let m = merge_counts(&merge, f);
            // Two independent binomial estimates of the same p: |p1 − p2| < 5·√(2p(1−p)/s).
            for (a, b) in m.iter().zip(d) {
                let (pa, pb) = (f64::from(*a) / s as f64, f64::from(*b) / s as f64);
                let p = 0.5 * (pa + pb);
                assert!(
                    (pa - pb).abs() <= 5.0 * (2.0 * p * (1.0 - p) / s as f64).sqrt() + 1e-9,
                    "{name} {set:?}: {m:?} vs {d:?}"
                );
            }
        }
    }
}

#[test]
fn the_floor_keeps_every_state_possible() {
    let counts = [10, 0, 0, 0];
    let ll = log_likelihood(&counts, 0.0);
    assert_eq!(ll[1], f64::NEG_INFINITY);
    let ll = log_likelihood(&counts, 1.0);
    assert!((ll[0].exp() - 11.0 / 14.0).abs() < 1e-12);
    assert!((ll[1].exp() - 1.0 / 14.0).abs() < 1e-12);
    // Without a floor, contradicting evidence restarts the set and is reported.
    let mut m = Pqrm::new(
        Calculus::builtin("quadrant").unwrap(),
        PqrmConfig {
            floor: 0.0,
            ..PqrmConfig::default()
        },
    )
    .unwrap();
    let set = LandmarkSet::new(1, 2, 3);
    m.apply_counts(&StepCounts::from_vecs(&[(set, vec![5, 0, 0, 0])]).unwrap())
        .unwrap();
    let r = m
        .apply_counts(&StepCounts::from_vecs(&[(set, vec![0, 5, 0, 0])]).unwrap())
        .unwrap();
    assert_eq!(r.conflicts, 1);
    assert_eq!(m.record(&set).unwrap().ml_state().0, 1);
}

#[test]
fn range_bearing_covariance_matches_the_propagated_noise() {
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    let (r, b, sr, sb) = (8.0, 0.7, 0.1, 0.01);
    let o = Observation::from_range_bearing(LandmarkId(1), r, b, sr, sb).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let (nr, nb) = (Normal::new(0.0, sr).unwrap(), Normal::new(0.0, sb).unwrap());
    let n = 200_000;
    let pts: Vec<[f64; 2]> = (0..n)
        .map(|_| {
            let (rr, bb) = (r + nr.sample(&mut rng), b + nb.sample(&mut rng));
            [rr * bb.cos(), rr * bb.sin()]
        })
        .collect();
    let mean = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n as f64,
        pts.iter().map(|p| p[1]).sum::<f64>() / n as f64,
    ];
    let cov = |i: usize, j: usize| {
        pts.iter()
            .map(|p| (p[i] - mean[i]) * (p[j] - mean[j]))
            .sum::<f64>()
            / n as f64
    };
    for (i, j) in [(0, 0), (0, 1), (1, 1)] {
        assert!(
            (cov(i, j) - o.cov[i][j]).abs() < 0.03 * o.cov[0][0].max(o.cov[1][1]),
            "cov[{i}][{j}] {} vs {}",
            cov(i, j),
            o.cov[i][j]
        );
    }
    assert!((mean[0] - o.mean[0]).abs() < 1e-3 && (mean[1] - o.mean[1]).abs() < 1e-3);
}

#[test]
fn bad_inputs_get_typed_errors() {
    let id = LandmarkId(1);
    // Regression (issue 17): the determinant 1e200·1e200 − (1e250)² overflowed to
    // inf − inf = NaN, and NaN compares false, so this passed as positive semi-definite; the
    // same with the symmetry test. The check is scale-free now.
    assert!(matches!(
        Observation::new(id, [0.0, 0.0], [[1e200, 1e250], [1e250, 1e200]]),
        Err(PqrmError::BadCovariance {
            reason: "negative determinant",
            ..
        })
    ));
    assert!(matches!(
        Observation::new(id, [0.0, 0.0], [[1e300, 1e300], [-1e300, 1e300]]),
        Err(PqrmError::BadCovariance {
            reason: "not symmetric",
            ..
        })
    ));
    // Large but valid covariances still pass, tiny ones too.
    assert!(Observation::new(id, [0.0, 0.0], [[1e300, 0.5e300], [0.5e300, 1e300]]).is_ok());
    assert!(Observation::new(id, [0.0, 0.0], [[1e-300, 0.0], [0.0, 1e-300]]).is_ok());
    assert!(matches!(
        Observation::new(id, [f64::NAN, 0.0], Z),
        Err(PqrmError::NonFinite(_))
    ));
    assert!(matches!(
        Observation::new(id, [0.0, 0.0], [[1.0, 0.5], [0.4, 1.0]]),
        Err(PqrmError::BadCovariance {
            reason: "not symmetric",
            ..
        })
    ));
    assert!(matches!(
        Observation::new(id, [0.0, 0.0], [[-1.0, 0.0], [0.0, 1.0]]),
        Err(PqrmError::BadCovariance {
            reason: "negative variance",
            ..
        })
    ));
    assert!(matches!(
        Observation::new(id, [0.0, 0.0], [[1.0, 2.0], [2.0, 1.0]]),
        Err(PqrmError::BadCovariance {
            reason: "negative determinant",
            ..
        })
    ));
    assert!(matches!(
        Observation::from_range_bearing(id, -1.0, 0.0, 0.1, 0.1),
        Err(PqrmError::InvalidConfig(_))
    ));
    let o = Observation::isotropic(id, [0.0, 0.0], 1.0).unwrap();
    assert!(matches!(
        Scan::new(0.0, 0, vec![o, o]),
        Err(PqrmError::DuplicateLandmark(1))
    ));
    assert!(matches!(
        Scan::new(f64::INFINITY, 0, vec![o]),
        Err(PqrmError::NonFinite(_))
    ));
    let edc = Calculus::builtin("edc").unwrap();
    assert!(matches!(
        Pqrm::new(
            edc.clone(),
            PqrmConfig {
                samples: 0,
                ..PqrmConfig::default()
            }
        ),
        Err(PqrmError::InvalidConfig(_))
    ));
    assert!(matches!(
        Pqrm::new(
            edc.clone(),
            PqrmConfig {
                floor: -1.0,
                ..PqrmConfig::default()
            }
        ),
        Err(PqrmError::InvalidConfig(_))
    ));
    assert!(matches!(
        Pqrm::new(Calculus::builtin("star-4").unwrap(), PqrmConfig::default()),
        Err(PqrmError::InvalidConfig(_))
    ));
    // Coincident landmarks without noise: a typed error, and the map is unchanged.
    let mut m = Pqrm::new(edc, PqrmConfig::default()).unwrap();
    let err = m
        .update(&scan(
            &[(1, [1.0, 1.0]), (2, [1.0, 1.0]), (3, [0.0, 5.0])],
            0.0,
        ))
        .unwrap_err();
    assert!(
        matches!(err, PqrmError::CoincidentLandmarks { .. }),
        "{err}"
    );
    assert!(m.is_empty());
    assert!(matches!(
        Pqrm::from_json("{\"format\": \"other\"}"),
        Err(PqrmError::Format(_))
    ));
}

#[test]
fn the_closed_form_orderings_equal_classifying_each_frame_directly() {
    use pqrm::likelihood::set_counts;
    let edc = Calculus::builtin("edc").unwrap();
    let sc = scan(
        &[
            (4, [0.0, 0.0]),
            (7, [0.3, 1.1]),
            (9, [-0.4, 0.5]),
            (12, [1.5, 0.2]),
        ],
        0.5,
    );
    let samples = ScanSamples::draw(&sc, 2000, 17, 3);
    let fast = step_counts(&edc, &samples, Orderings::All).unwrap();
    assert_eq!(fast.len(), 4 * 3 * 2);
    let index = |id: LandmarkId| samples.ids().iter().position(|x| *x == id).unwrap();
    let mut buf = Vec::new();
    for (set, counts) in &fast {
        let [a, b, c] = set.0;
        let direct = set_counts(&edc, &samples, [index(a), index(b), index(c)], &mut buf).unwrap();
        assert_eq!(counts, &direct, "{set:?}");
    }
    let canonical = step_counts(&edc, &samples, Orderings::Canonical).unwrap();
    assert_eq!(canonical.len(), 4);
    assert!(canonical.iter().all(|(s, _)| s.is_canonical()));
}

/// The six orderings from one base frame (sign keys over shared quantities) against
/// classifying each ordered triplet directly, for every built-in ternary calculus.
#[test]
fn the_closed_form_orderings_equal_direct_classification_in_every_calculus() {
    use pqrm::likelihood::set_counts;
    let sc = scan(
        &[
            (1, [0.0, 0.0]),
            (2, [0.4, 1.2]),
            (3, [-0.5, 0.6]),
            (5, [1.3, 0.1]),
            (8, [0.2, -0.9]),
        ],
        0.6,
    );
    let samples = ScanSamples::draw(&sc, 3000, 23, 1);
    let index = |id: LandmarkId| samples.ids().iter().position(|x| *x == id).unwrap();
    let mut buf = Vec::new();
    let mut tried = 0;
    for name in qsr_core::BUILTIN_NAMES {
        let cal = Calculus::builtin(name).unwrap();
        if cal.frame() != qsr_core::FrameKind::Ternary {
            continue;
        }
        tried += 1;
        for (set, counts) in &step_counts(&cal, &samples, Orderings::All).unwrap() {
            let [a, b, c] = set.0;
            let direct =
                set_counts(&cal, &samples, [index(a), index(b), index(c)], &mut buf).unwrap();
            assert_eq!(counts, direct, "{name} {set:?}");
        }
    }
    assert_eq!(tried, 9, "the ternary built-ins");
}

/// Zero noise on a lattice puts landmarks exactly on lines and circles of each other's
/// frames: every quantity that is exactly zero must take its constraint's `zero` side. The
/// reference evaluates every form of every ordering on its own (the table in `likelihood`),
/// in exact arithmetic: on an integer lattice the frame scaled by `D = |AB|²` (`X = x·D`,
/// `Y = y·D`, `n·D = |AC|²`) has only exact products. (Regression, issue 37: with the
/// normalised frame this reference, like the kernel before it, put C = (0, 2) in the frame
/// (1, 0) → (2, 2) off the circle about A through B — x = −0.8 and y = 0.6 round, n ≠ 1.)
#[test]
fn boundary_configurations_take_each_constraints_zero_side() {
    let pts: Vec<(u32, [f64; 2])> = vec![
        (0, [0.0, 0.0]),
        (1, [2.0, 0.0]),
        (2, [1.0, 0.0]),
        (3, [2.0, 2.0]),
        (4, [0.0, 2.0]),
        (5, [1.0, 1.0]),
        (6, [1.0, -1.0]),
        (7, [4.0, 0.0]),
    ];
    let sc = scan(&pts, 0.0);
    let samples = ScanSamples::draw(&sc, 8, 1, 0);
    let pos = |id: LandmarkId| pts.iter().find(|p| p.0 == id.0).unwrap().1;
    for name in [
        "edc",
        "edc-lune",
        "double-cross",
        "triple-cross",
        "quadrant",
    ] {
        let cal = Calculus::builtin(name).unwrap();
        let qsr_core::Partition::Constraints(part) = cal.partition() else {
            panic!("{name} is a constraint calculus");
        };
        let table = part.table();
        let spec = cal.spec();
        let counts = step_counts(&cal, &samples, Orderings::All).unwrap();
        let mut on_boundary = 0;
        let pairs: Vec<_> = counts.iter().collect();
        for group in pairs.chunks(6) {
            let [a, b, c] = group[0].0.0;
            let (pa, pb, pc) = (pos(a), pos(b), pos(c));
            // the base frame scaled by d = |AB|²: integers, exactly
            let (dx, dy) = (pb[0] - pa[0], pb[1] - pa[1]);
            let (vx, vy) = (pc[0] - pa[0], pc[1] - pa[1]);
            let d = dx * dx + dy * dy;
            let x = -(dx * vy - dy * vx);
            let y = dx * vx + dy * vy;
            let n = vx * vx + vy * vy;
            for (o, (set, got)) in group.iter().enumerate() {
                let mut bin = 0usize;
                for (k, con) in spec.constraints.iter().enumerate() {
                    let (al, be, ga, de) = match con.shape {
                        qsr_core::Shape::Line { a, b, c } => (0.0, a, b, c),
                        qsr_core::Shape::Circle { center, radius } => (
                            1.0,
                            -2.0 * center[0],
                            -2.0 * center[1],
                            center[0] * center[0] + center[1] * center[1] - radius * radius,
                        ),
                    };
                    let [fa, fb, fc, fd] = [
                        [al, be, ga, de],
                        [al, -be, -2.0 * al - ga, al + ga + de],
                        [de, -be, ga, al],
                        [al + ga + de, be, -2.0 * al - ga, al],
                        [de, be, -ga - 2.0 * de, al + ga + de],
                        [al + ga + de, -be, -ga - 2.0 * de, de],
                    ][o];
                    let v = fa * n + fb * x + fc * y + fd * d;
                    if v == 0.0 {
                        on_boundary += 1;
                    }
                    let inclusive = con.zero == qsr_core::Side::Positive;
                    if v > 0.0 || (v == 0.0 && inclusive) {
                        bin |= 1 << k;
                    }
                }
                let mut want = vec![0u32; cal.n_states()];
                want[usize::from(table[bin])] = 8;
                assert_eq!(got, &want, "{name} {set:?}");
            }
        }
        assert!(
            on_boundary > 20,
            "{name}: {on_boundary} boundary cases exercised"
        );
        // The canonical kernel (its own quantities only) takes the same zero sides.
        let canonical = step_counts(&cal, &samples, Orderings::Canonical).unwrap();
        assert_eq!(canonical.len() * 6, counts.len());
        for (one, group) in canonical.iter().zip(pairs.chunks(6)) {
            assert_eq!(one.0, group[0].0, "{name}: the canonical set comes first");
            assert_eq!(one.1, group[0].1, "{name} {:?}", one.0);
        }
    }
}

/// Regression (issue 17): `normalise([inf, 0])` and `log_likelihood` with a negative floor
/// returned NaN silently.
#[test]
fn normalise_and_log_likelihood_never_return_nan() {
    use pqrm::map::normalise;
    let p = normalise(vec![f64::INFINITY, 0.0]);
    assert_eq!(p, vec![0.0, f64::NEG_INFINITY]);
    let p = normalise(vec![f64::INFINITY, f64::INFINITY, 1.0]);
    assert!((p[0] - 0.5f64.ln()).abs() < 1e-15 && p[2] == f64::NEG_INFINITY);
    let p = normalise(vec![f64::NAN, 0.0]);
    assert_eq!(p, vec![f64::NEG_INFINITY, 0.0]);
    let p = normalise(vec![f64::NAN, f64::NAN]);
    assert!(p.iter().all(|v| (v - 0.5f64.ln()).abs() < 1e-15));
    for floor in [-1.0, -0.5, f64::NAN, f64::NEG_INFINITY, f64::INFINITY] {
        for counts in [vec![0u32, 0], vec![3, 1], vec![0, 7]] {
            let l = log_likelihood(&counts, floor);
            assert!(
                l.iter().all(|v| !v.is_nan()),
                "floor {floor}, counts {counts:?}: {l:?}"
            );
            let total: f64 = l.iter().map(|v| v.exp()).sum();
            assert!((total - 1.0).abs() < 1e-12, "{l:?}");
        }
    }
}
