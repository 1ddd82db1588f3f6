//! The distance guarantees of thesis §4.3.4 for one run, with the assumptions they need
//! checked against the world the run happened in.
//!
//! - **Proposition 2**: under Assumptions 1–2 a plan of |P| transitions drives at most
//!   `(2π + 1)·R·|P|` — each transition at worst drives R to a circle of radius R about the
//!   link and then the whole circle. Assumption 1 (i): every element's landmarks lie in a disc
//!   of radius R ([`Assumptions::disc`]); 1 (ii) and 2: the circle of radius R about a link can
//!   be driven and the link is sensed from all of it ([`Assumptions::circle`]).
//! - **Proposition 4**: under Assumptions 3–4 it drives at most `R·|P|`. Assumption 3 (i):
//!   every element's landmarks pairwise within R ([`Assumptions::pairwise`]); 3 (ii): the
//!   robot can drive from one landmark of an element to another keeping both in view
//!   ([`Assumptions::sight_lines`]); 4: it drives those straight lines — the direct controller,
//!   no search ([`Assumptions::straight`]).
//!
//! The bounds are on what the propositions bound: the length driven in transitions, over the
//! transitions the run made — |P| of its plan, or more when it re-planned (each re-plan is a
//! new plan whose transitions the propositions bound alike; the assumptions are checked on
//! every element and link the run used). A bound
//! exceeded while its assumptions hold would contradict the proposition
//! ([`BoundCheck::contradicts`]); exceeded while they fail, it says only that the run was
//! outside the guarantee. The world enters through [`Geometry`], so the same check serves a
//! simulator (which knows the truth) and a test.

use serde::{Deserialize, Serialize};

use crate::map::QualitativeMap;

/// Samples per full circle when checking Assumption 1 (ii) (every 10°).
const CIRCLE_SAMPLES: usize = 36;

/// Samples per metre along a sight line (Assumption 3 (ii)).
const LINE_SAMPLES_PER_M: f64 = 1.0;

/// What the world says about positions and sensing (ground truth, for checking assumptions).
pub struct Geometry<'a> {
    /// Where landmark `id` is; `None` for an id that is no point landmark (clutter
    /// recognised as one, a wall).
    pub position: &'a dyn Fn(u32) -> Option<[f64; 2]>,
    /// Whether the robot at `from` senses landmark `id`.
    pub sensed_from: &'a dyn Fn([f64; 2], u32) -> bool,
    /// Whether the robot can stand at `at` (free space inside the site).
    pub drivable: &'a dyn Fn([f64; 2]) -> bool,
}

/// Which assumptions of §4.3.4 the run's first plan meets (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Assumptions {
    /// 1 (i): every plan element's landmarks lie in a disc of radius R.
    pub disc: bool,
    /// 1 (ii) and 2: about every link of the plan, the circle of radius R is drivable and the
    /// link is sensed from every point of it.
    pub circle: bool,
    /// 3 (i): every plan element's landmarks are pairwise within R.
    pub pairwise: bool,
    /// 3 (ii): between any two landmarks of a plan element, the straight line is drivable
    /// and both are sensed from every point of it.
    pub sight_lines: bool,
    /// 4: the robot drives straight lines between landmarks (the direct controller).
    pub straight: bool,
}

/// Both bounds for one run at one R, and whether they and their assumptions hold.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoundCheck {
    /// R (m).
    pub range: f64,
    /// Transitions bounded: |P| of the first plan, or the transitions made when re-plans
    /// made more.
    pub transitions: usize,
    /// Length driven in transitions (m): what the propositions bound.
    pub length: f64,
    /// Proposition 2's bound (2π + 1)·R·|P| (m).
    pub prop2: f64,
    /// Proposition 4's bound R·|P| (m).
    pub prop4: f64,
    /// The assumptions.
    pub assumptions: Assumptions,
}

impl BoundCheck {
    /// The bounds for `length` driven over `transitions` transitions at `range`.
    #[must_use]
    pub fn new(range: f64, transitions: usize, length: f64, assumptions: Assumptions) -> Self {
        let n = transitions as f64;
        Self {
            range,
            transitions,
            length,
            prop2: (2.0 * std::f64::consts::PI + 1.0) * range * n,
            prop4: range * n,
            assumptions,
        }
    }

    /// The run drove no more than Proposition 2's bound.
    #[must_use]
    pub fn within_prop2(&self) -> bool {
        self.length <= self.prop2 + 1e-9
    }

    /// The run drove no more than Proposition 4's bound.
    #[must_use]
    pub fn within_prop4(&self) -> bool {
        self.length <= self.prop4 + 1e-9
    }

    /// Assumptions 1 and 2 hold: Proposition 2 applies.
    #[must_use]
    pub fn prop2_applies(&self) -> bool {
        self.assumptions.disc && self.assumptions.circle
    }

    /// Assumptions 3 and 4 hold: Proposition 4 applies.
    #[must_use]
    pub fn prop4_applies(&self) -> bool {
        let a = self.assumptions;
        a.pairwise && a.sight_lines && a.straight
    }

    /// A bound exceeded although its assumptions hold — a contradiction of the proposition
    /// (a bug, or an assumption checked too loosely).
    #[must_use]
    pub fn contradicts(&self) -> bool {
        (self.prop2_applies() && !self.within_prop2())
            || (self.prop4_applies() && !self.within_prop4())
    }
}

/// Checks the assumptions for a run whose first plan was `plan` (map elements, start to
/// goal), which made the transitions `made` (from, to; re-plans included) and drove `length`
/// in them, at range `range`; `straight` says whether the robot drives straight lines
/// between landmarks (Assumption 4: the direct controller).
#[must_use]
pub fn check(
    map: &QualitativeMap,
    plan: &[usize],
    made: &[(usize, usize)],
    range: f64,
    straight: bool,
    length: f64,
    world: &Geometry<'_>,
) -> BoundCheck {
    let transitions = plan.len().saturating_sub(1).max(made.len());
    // every step the run planned or took: consecutive plan elements and the transitions made
    let steps: Vec<(usize, usize)> = plan
        .windows(2)
        .map(|w| (w[0], w[1]))
        .chain(made.iter().copied())
        .collect();
    let mut used: Vec<usize> = steps
        .iter()
        .flat_map(|&(a, b)| [a, b])
        .chain(plan.iter().copied())
        .collect();
    used.sort_unstable();
    used.dedup();
    let landmarks = |e: usize| map.elements().get(e).map(|m| m.landmarks);
    let elements: Vec<[u32; 3]> = used.iter().filter_map(|&e| landmarks(e)).collect();
    let points = |ids: &[u32; 3]| -> Option<[[f64; 2]; 3]> {
        Some([
            (world.position)(ids[0])?,
            (world.position)(ids[1])?,
            (world.position)(ids[2])?,
        ])
    };
    let located: Vec<Option<[[f64; 2]; 3]>> = elements.iter().map(points).collect();
    let all_points = located.iter().all(Option::is_some);
    let disc = all_points
        && located
            .iter()
            .flatten()
            .all(|p| enclosing_radius(p) <= range + 1e-9);
    let pairwise = all_points
        && located
            .iter()
            .flatten()
            .all(|p| (0..3).all(|i| dist(p[i], p[(i + 1) % 3]) <= range + 1e-9));
    // the links: landmarks consecutive plan elements share
    let mut links: Vec<u32> = elements
        .windows(2)
        .flat_map(|w| {
            w[0].iter()
                .copied()
                .filter(|l| w[1].contains(l))
                .collect::<Vec<_>>()
        })
        .collect();
    links.sort_unstable();
    links.dedup();
    let circle = links.iter().all(|&l| circle_clear(world, l, range));
    let sight_lines = all_points
        && elements
            .iter()
            .zip(&located)
            .all(|(ids, p)| p.is_some_and(|p| sides_clear(world, ids, &p)));
    BoundCheck::new(
        range,
        transitions,
        length,
        Assumptions {
            disc,
            circle,
            pairwise,
            sight_lines,
            straight,
        },
    )
}

/// Assumptions 1 (ii) and 2 for link `l`: the circle of radius `range` about it is drivable
/// and `l` is sensed from every point of it.
fn circle_clear(world: &Geometry<'_>, l: u32, range: f64) -> bool {
    (world.position)(l).is_some_and(|c| {
        (0..CIRCLE_SAMPLES).all(|k| {
            let a = std::f64::consts::TAU * k as f64 / CIRCLE_SAMPLES as f64;
            let x = [c[0] + range * a.cos(), c[1] + range * a.sin()];
            (world.drivable)(x) && (world.sensed_from)(x, l)
        })
    })
}

/// Assumption 3 (ii) for one element: along each side of its triangle the robot can drive and
/// sees both end landmarks (the end points are the landmarks themselves: the robot drives
/// up to them).
fn sides_clear(world: &Geometry<'_>, ids: &[u32; 3], p: &[[f64; 2]; 3]) -> bool {
    (0..3).all(|i| {
        let (a, b) = (p[i], p[(i + 1) % 3]);
        let n = (dist(a, b) * LINE_SAMPLES_PER_M).ceil().max(1.0) as usize;
        (1..n).all(|k| {
            let t = k as f64 / n as f64;
            let x = [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
            (world.drivable)(x)
                && (world.sensed_from)(x, ids[i])
                && (world.sensed_from)(x, ids[(i + 1) % 3])
        })
    })
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// Radius of the smallest disc holding three points: half the longest side when the
/// triangle is right or obtuse (that side's midpoint is the centre), else the circumradius.
#[must_use]
pub fn enclosing_radius(p: &[[f64; 2]; 3]) -> f64 {
    let s = [dist(p[1], p[2]), dist(p[2], p[0]), dist(p[0], p[1])];
    let mut sorted = s;
    sorted.sort_by(f64::total_cmp);
    let [a, b, c] = sorted;
    if c * c >= a * a + b * b {
        return c / 2.0;
    }
    // circumradius abc / (4·area), area by the cross product
    let area2 = ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1])
        - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]))
        .abs();
    a * b * c / (2.0 * area2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn enclosing_radius_of_obtuse_and_acute_triangles() {
        // obtuse: half the longest side
        let r = enclosing_radius(&[[0.0, 0.0], [10.0, 0.0], [5.0, 1.0]]);
        assert!((r - 5.0).abs() < 1e-12);
        // equilateral of side s: s / √3
        let h = 3f64.sqrt() / 2.0;
        let r = enclosing_radius(&[[0.0, 0.0], [1.0, 0.0], [0.5, h]]);
        assert!((r - 1.0 / 3f64.sqrt()).abs() < 1e-12);
    }

    /// Regression (the full field run flagged 12 "contradictions"): a run whose first plan
    /// had |P| = 0 (its goal element in view) and which then re-planned was held to a bound
    /// of 0 m. The bound covers the transitions made.
    #[test]
    fn the_bound_covers_transitions_made_after_a_replan() {
        use crate::map::{Layer, QualitativeMap};
        let positions: std::collections::BTreeMap<u32, [f64; 2]> = [
            (0, [0.0, 0.0]),
            (1, [4.0, 0.0]),
            (2, [2.0, 3.0]),
            (3, [6.0, 3.0]),
        ]
        .into_iter()
        .collect();
        let calculus = qsr_core::Calculus::builtin("left-right").unwrap();
        let layer = Layer::exact_from_positions(calculus, &positions, 10.0).unwrap();
        let map = QualitativeMap::new(vec![layer]).unwrap();
        let (e, f) = (0, map.elements().len() - 1);
        let position = |id: u32| positions.get(&id).copied();
        let sensed = |_: [f64; 2], _: u32| true;
        let drivable = |_: [f64; 2]| true;
        let world = Geometry {
            position: &position,
            sensed_from: &sensed,
            drivable: &drivable,
        };
        let b = check(&map, &[e], &[(e, f)], 10.0, false, 30.0, &world);
        assert_eq!(b.transitions, 1);
        assert!(
            b.prop2_applies() && b.within_prop2() && !b.contradicts(),
            "{b:?}"
        );
        let first_plan_only = check(&map, &[e], &[], 10.0, false, 30.0, &world);
        assert!(
            first_plan_only.contradicts(),
            "30 m over no transition exceeds 0 m"
        );
    }

    #[test]
    fn a_bound_exceeded_only_counts_against_its_proposition_when_it_applies() {
        let all = Assumptions {
            disc: true,
            circle: true,
            pairwise: true,
            sight_lines: true,
            straight: true,
        };
        let b = BoundCheck::new(10.0, 2, 25.0, all);
        assert!((b.prop4 - 20.0).abs() < 1e-12 && !b.within_prop4() && b.within_prop2());
        assert!(b.contradicts(), "Prop 4 applies and is exceeded");
        let searching = BoundCheck::new(
            10.0,
            2,
            25.0,
            Assumptions {
                straight: false,
                ..all
            },
        );
        assert!(!searching.prop4_applies() && !searching.contradicts());
    }
}
