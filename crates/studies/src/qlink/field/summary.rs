//! What the trials say: success and failure counts per variant, the distance bounds, the
//! map's size and plans on a restricted map.

use std::collections::{BTreeMap, BTreeSet};

use serde::{Deserialize, Serialize};

use qlink::{BoundCheck, Layer, LinkGraph, Perception, QualitativeMap};

use super::mapping::FieldMap;
use super::perception::LidarPerception;
use super::trials::{FieldResult, FieldTask, FieldTrial, true_position};
use super::{FieldParams, FieldVariant, WALL_FRAME_END, WALL_FRAME_START};
use crate::error::Result;
/// Success and failure counts of one variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldSummary {
    /// The variant.
    pub variant: FieldVariant,
    /// Trials run.
    pub trials: usize,
    /// Trials with no path (not failures).
    pub no_path: usize,
    /// Successes.
    pub successes: usize,
    /// successes / (trials − no_path).
    pub success_rate: f64,
    /// Failures by cause.
    pub perceptual_aliasing: usize,
    /// Insufficient features only.
    pub insufficient_features: usize,
    /// Insufficient features after misrecognitions.
    pub insufficient_features_and_aliasing: usize,
    /// Mean trajectory length of the successes (m).
    pub mean_length: f64,
    /// Successes that re-planned at least once.
    pub replanned_successes: usize,
    /// Table 4.2: (|P|, successful paths, mean trajectory length m).
    pub by_plan_len: Vec<(usize, usize, f64)>,
}

impl FieldSummary {
    /// Trials judged for success: those that found a path to try.
    #[must_use]
    pub fn judged(&self) -> usize {
        self.trials - self.no_path
    }
}

/// Summaries per variant, in the order given.
#[must_use]
pub fn summarise(trials: &[FieldTrial], variants: &[FieldVariant]) -> Vec<FieldSummary> {
    variants
        .iter()
        .map(|&v| {
            let ts: Vec<&FieldTrial> = trials.iter().filter(|t| t.variant == v).collect();
            let count = |r: FieldResult| ts.iter().filter(|t| t.result == r).count();
            let ok: Vec<&&FieldTrial> = ts
                .iter()
                .filter(|t| t.result == FieldResult::Success)
                .collect();
            let no_path = count(FieldResult::NoPath);
            let mut by: BTreeMap<usize, (usize, f64)> = BTreeMap::new();
            for t in &ok {
                let e = by.entry(t.plan_len).or_insert((0, 0.0));
                e.0 += 1;
                e.1 += t.length;
            }
            FieldSummary {
                variant: v,
                trials: ts.len(),
                no_path,
                successes: ok.len(),
                success_rate: ok.len() as f64 / (ts.len() - no_path).max(1) as f64,
                perceptual_aliasing: count(FieldResult::PerceptualAliasing),
                insufficient_features: count(FieldResult::InsufficientFeatures),
                insufficient_features_and_aliasing: count(
                    FieldResult::InsufficientFeaturesAndAliasing,
                ),
                mean_length: ok.iter().map(|t| t.length).sum::<f64>() / ok.len().max(1) as f64,
                replanned_successes: ok.iter().filter(|t| t.replans > 0).count(),
                by_plan_len: by
                    .into_iter()
                    .map(|(k, (n, s))| (k, n, s / n as f64))
                    .collect(),
            }
        })
        .collect()
}

/// Which R a [`BoundSummary`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundRange {
    /// The lidar's range (the R the navigator plans arcs and circles with).
    Lidar,
    /// The effective range measured from the mapping drive.
    Effective,
}

impl BoundRange {
    /// Both, in [`FieldTrial::bounds`] order.
    pub const ALL: [Self; 2] = [Self::Lidar, Self::Effective];

    fn index(self) -> usize {
        match self {
            Self::Lidar => 0,
            Self::Effective => 1,
        }
    }

    /// Its name in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Lidar => "lidar range",
            Self::Effective => "effective range",
        }
    }
}

/// Propositions 2 and 4 over one variant's successful runs at one R: how many stayed within
/// each bound, how many met each assumption, and how many exceeded a bound whose assumptions
/// held (a contradiction; the propositions say it cannot happen).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoundSummary {
    /// The variant.
    pub variant: FieldVariant,
    /// Which R.
    pub range: BoundRange,
    /// Smallest and largest R over the worlds (m).
    pub r: [f64; 2],
    /// Successful runs.
    pub runs: usize,
    /// Of those, within Proposition 2's bound.
    pub within_prop2: usize,
    /// Of those, within Proposition 4's bound.
    pub within_prop4: usize,
    /// Runs meeting Assumption 1 (i).
    pub disc: usize,
    /// Runs meeting Assumptions 1 (ii) and 2.
    pub circle: usize,
    /// Runs meeting Assumption 3 (i).
    pub pairwise: usize,
    /// Runs meeting Assumption 3 (ii).
    pub sight_lines: usize,
    /// Runs meeting Assumption 4.
    pub straight: usize,
    /// Runs to which Proposition 2 applies.
    pub prop2_applies: usize,
    /// Runs to which Proposition 4 applies.
    pub prop4_applies: usize,
    /// Runs exceeding a bound whose assumptions held.
    pub contradictions: usize,
}

impl BoundSummary {
    /// Successful runs longer than Proposition 2's and Proposition 4's bound.
    #[must_use]
    pub fn exceeded(&self) -> [usize; 2] {
        [self.runs - self.within_prop2, self.runs - self.within_prop4]
    }

    /// The thesis's finding for its field runs: none exceeds either bound.
    #[must_use]
    pub fn none_exceeded(&self) -> bool {
        self.exceeded() == [0, 0]
    }
}

/// [`BoundSummary`] of `variant`'s successful trials at `range`.
#[must_use]
pub fn bound_summary(
    trials: &[FieldTrial],
    variant: FieldVariant,
    range: BoundRange,
) -> BoundSummary {
    let checks: Vec<&BoundCheck> = trials
        .iter()
        .filter(|t| t.variant == variant && t.result == FieldResult::Success)
        .map(|t| &t.bounds[range.index()])
        .collect();
    let count = |f: &dyn Fn(&BoundCheck) -> bool| checks.iter().filter(|c| f(c)).count();
    let r = checks
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |m, c| {
            [m[0].min(c.range), m[1].max(c.range)]
        });
    BoundSummary {
        variant,
        range,
        r: if checks.is_empty() { [0.0, 0.0] } else { r },
        runs: checks.len(),
        within_prop2: count(&BoundCheck::within_prop2),
        within_prop4: count(&BoundCheck::within_prop4),
        disc: count(&|c| c.assumptions.disc),
        circle: count(&|c| c.assumptions.circle),
        pairwise: count(&|c| c.assumptions.pairwise),
        sight_lines: count(&|c| c.assumptions.sight_lines),
        straight: count(&|c| c.assumptions.straight),
        prop2_applies: count(&BoundCheck::prop2_applies),
        prop4_applies: count(&BoundCheck::prop4_applies),
        contradictions: count(&BoundCheck::contradicts),
    }
}

/// How big the map is against what its landmarks allow, and what that does to plans.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSize {
    /// Point landmarks (recogniser ids) in the map.
    pub point_ids: usize,
    /// Triplets of them: C(n, 3).
    pub possible_triplets: usize,
    /// Landmark sets the point layer recorded (its PQRM's entries; a set may be recorded
    /// under several of its orderings).
    pub recorded_triplets: usize,
    /// Point-triplet map elements (distinct landmark sets co-observed in `min_observations`
    /// scans: what the thesis counts as its 44).
    pub point_elements: usize,
    /// Every element of the map, point and wall layers (what the thesis's "44 distinct QRM
    /// map elements" counts).
    #[serde(default)]
    pub elements: usize,
    /// Links of the link graph (directed edges, β of the params).
    pub links: usize,
    /// Mean number of elements a landmark belongs to.
    pub elements_per_landmark: f64,
}

/// The size of a field map (see [`MapSize`]).
///
/// # Errors
/// Graph errors.
pub fn map_size(field: &FieldMap, params: &FieldParams) -> Result<MapSize> {
    let graph = LinkGraph::new(&field.map, params.beta, |_, _, _| 1.0)?;
    let points: Vec<u32> = field
        .map
        .landmarks()
        .into_iter()
        .filter(|&id| id != WALL_FRAME_START && id != WALL_FRAME_END)
        .collect();
    let n = points.len();
    let is_point = |e: &qlink::MapElement| {
        e.landmarks
            .iter()
            .all(|&l| l != WALL_FRAME_START && l != WALL_FRAME_END)
    };
    let point_elements = field.map.elements().iter().filter(|e| is_point(e)).count();
    let per: usize = points
        .iter()
        .map(|&l| {
            field
                .map
                .elements_with(l)
                .iter()
                .filter(|&&e| is_point(&field.map.elements()[e]))
                .count()
        })
        .sum();
    Ok(MapSize {
        point_ids: n,
        possible_triplets: n * n.saturating_sub(1) * n.saturating_sub(2) / 6,
        recorded_triplets: field.stats.point_elements,
        point_elements,
        elements: field.map.elements().len(),
        links: graph.n_edges(),
        elements_per_landmark: per as f64 / n.max(1) as f64,
    })
}

/// Plans on the map as built against plans on the map restricted as §4.3.4's second case:
/// only point triplets whose landmarks are pairwise within the effective range (the wall
/// layer kept). Same tasks, unit costs, β of the params.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RestrictedPlans {
    /// Point elements of the map as built, and of the restricted map.
    pub elements: [usize; 2],
    /// Links (directed edges) of each.
    pub links: [usize; 2],
    /// Mean |P| (transitions) over the tasks with a path, on each.
    pub mean_plan_len: [f64; 2],
    /// Tasks with no path on each.
    pub no_path: [usize; 2],
    /// Tasks.
    pub tasks: usize,
}

/// [`RestrictedPlans`] for `tasks`.
///
/// # Errors
/// Map and graph errors.
pub fn restricted_plans(
    field: &FieldMap,
    params: &FieldParams,
    tasks: &[FieldTask],
) -> Result<RestrictedPlans> {
    let r = field.stats.effective_range;
    let close = |ids: [u32; 3]| {
        let p: Option<Vec<[f64; 2]>> = ids.iter().map(|&i| true_position(field, i)).collect();
        p.is_some_and(|p| {
            (0..3).all(|k| {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                (a[0] - b[0]).hypot(a[1] - b[1]) <= r
            })
        })
    };
    let layers: Vec<Layer> = field
        .map
        .layers()
        .iter()
        .enumerate()
        .map(|(k, l)| match (k, l) {
            (0, Layer::Probabilistic(m)) => {
                let mut m = m.clone();
                m.retain(|s| close([s.0[0].0, s.0[1].0, s.0[2].0]));
                Layer::Probabilistic(m)
            }
            _ => l.clone(),
        })
        .collect();
    let restricted = QualitativeMap::new(layers)?;
    let probe = LidarPerception::new(field, 0);
    let mut out = RestrictedPlans {
        elements: [0; 2],
        links: [0; 2],
        mean_plan_len: [0.0; 2],
        no_path: [0; 2],
        tasks: tasks.len(),
    };
    for (k, map) in [&field.map, &restricted].into_iter().enumerate() {
        let graph = LinkGraph::new(map, params.beta, |_, _, _| 1.0)?;
        out.elements[k] = map
            .elements()
            .iter()
            .filter(|e| {
                e.landmarks
                    .iter()
                    .all(|&l| l != WALL_FRAME_START && l != WALL_FRAME_END)
            })
            .count();
        out.links[k] = graph.n_edges();
        let mut lens = Vec::new();
        for t in tasks {
            let starts = map.elements_in_view(&probe.visible(t.start));
            match graph.plan(map, &starts, t.goal, &BTreeSet::new()) {
                Ok(p) => lens.push(p.len() as f64),
                Err(_) => out.no_path[k] += 1,
            }
        }
        out.mean_plan_len[k] = lens.iter().sum::<f64>() / lens.len().max(1) as f64;
    }
    Ok(out)
}
