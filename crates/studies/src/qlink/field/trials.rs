//! The trials: start/goal draws, each variant's link graph and navigation settings, one
//! trial run and scored against the simulator, and the whole experiment.

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::progress::{FixedTotal, Progress, phase};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sim2d::{ExtractorConfig, Hit};

use qlink::graph::pomdp_cost;
use qlink::{
    BoundCheck, Controller, ControllerKind, CostModel, Failure, Geometry, LinkGraph, NavConfig,
    NavOutcome, Navigator, Perception, QlinkError, SearchPomdp, Stranded,
};

use super::mapping::{FieldMap, map_field};
use super::perception::LidarPerception;
use super::{FieldParams, FieldVariant, WALL_FRAME_END, WALL_FRAME_START};
use crate::error::Result;
/// One trial's start and goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FieldTask {
    /// Trial number.
    pub trial: usize,
    /// Start position (m).
    pub start: [f64; 2],
    /// Goal landmark (recogniser id; a real landmark).
    pub goal: u32,
    /// The goal's true position (m).
    pub goal_position: [f64; 2],
}

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FieldResult {
    /// Reached the goal element on the true goal.
    Success,
    /// Reached "the goal" on the wrong object.
    PerceptualAliasing,
    /// Could not localise or re-plan, nothing misrecognised on the way.
    InsufficientFeatures,
    /// Could not localise or re-plan after misrecognising landmarks on the way.
    InsufficientFeaturesAndAliasing,
    /// The link graph has no path (not counted as a failure).
    NoPath,
}

impl FieldResult {
    /// Every result, in declaration order.
    pub const ALL: [FieldResult; 5] = [
        Self::Success,
        Self::PerceptualAliasing,
        Self::InsufficientFeatures,
        Self::InsufficientFeaturesAndAliasing,
        Self::NoPath,
    ];

    /// Its name in files: the JSON's (until 2026-11-28 the files said
    /// "insufficient-features+aliasing" where the JSON and Python's `FieldResult` say
    /// "insufficient-features-and-aliasing").
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Success => "success",
            Self::PerceptualAliasing => "perceptual-aliasing",
            Self::InsufficientFeatures => "insufficient-features",
            Self::InsufficientFeaturesAndAliasing => "insufficient-features-and-aliasing",
            Self::NoPath => "no-path",
        }
    }
}

/// One trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldTrial {
    /// The variant.
    pub variant: FieldVariant,
    /// Start and goal.
    pub task: FieldTask,
    /// How it ended.
    pub result: FieldResult,
    /// |P| of the first plan (transitions).
    pub plan_len: usize,
    /// Re-plans made.
    pub replans: usize,
    /// For a run the navigator ended for insufficient features: what it was left without
    /// after its last contingency.
    #[serde(default)]
    pub stranded: Option<Stranded>,
    /// Trajectory length including the final drive to the goal element's centroid (m).
    pub length: f64,
    /// Distance from the end point to the true goal landmark (m).
    pub final_distance: f64,
    /// Detections of mapped ids during the trial.
    pub detections: usize,
    /// Of those, on the wrong object.
    pub aliased: usize,
    /// Share of the trial's lidar rays that met the ground (pitched terrain).
    #[serde(default)]
    pub ground_share: f64,
    /// The same over its last scans (20, `RECENT_SCANS` of the perception): where the robot
    /// was looking when it arrived or gave up.
    #[serde(default)]
    pub final_ground_share: f64,
    /// Length driven in transitions (m): what Propositions 2 and 4 bound.
    pub transit_length: f64,
    /// The first plan's map elements.
    pub plan: Vec<usize>,
    /// Propositions 2 and 4 for this run with their assumptions checked against the world:
    /// at R = the lidar's range, and at R = the effective range.
    pub bounds: [BoundCheck; 2],
    /// The path driven (every check).
    pub trajectory: Vec<[f64; 2]>,
}

/// Why drawn start/goal pairs were redrawn (how connected the map is, seen from the field).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskDraws {
    /// Starts too close to an object or outside the site.
    pub blocked: usize,
    /// Goals already in view (or an element holding them): trivial.
    pub trivial: usize,
    /// Starts from which the robot localises in no element.
    pub no_start: usize,
    /// Pairs with no link-graph path from the elements in view at the start.
    pub no_path: usize,
    /// Pairs kept.
    pub kept: usize,
    /// Pairs asked for ([`FieldParams::trials`]): more than `kept` when 1000 draws per pair
    /// did not find them all — a map too sparse to plan in (0 for records that predate it).
    #[serde(default)]
    pub wanted: usize,
}

impl TaskDraws {
    /// Whether the draws ran out before every pair asked for was found.
    #[must_use]
    pub fn short(&self) -> bool {
        self.kept < self.wanted
    }
}

/// Random starts near the mapping drive and goals out of view from them, such that the
/// robot localises at the start and the link graph (β of `params`) has a path — the trials
/// the thesis ran were of that kind; how many draws were redrawn and why is returned.
///
/// When 1000 draws per pair find fewer pairs than asked (a map too sparse to plan in, as a
/// map of the thesis's size can be), the pairs found are returned — none, perhaps — and
/// [`TaskDraws::short`] says so: such a world is reported with the trials it could run, not
/// refused.
///
/// # Errors
/// [`QlinkError::EmptyMap`] when no mapped landmark is real; [`crate::error::StudyError::Cancelled`] when
/// `progress` asks (it ticks once per task kept).
pub fn tasks(
    field: &FieldMap,
    params: &FieldParams,
    progress: &dyn Progress,
) -> Result<(Vec<FieldTask>, TaskDraws)> {
    let graph = LinkGraph::new(&field.map, params.beta, |_, _, _| 1.0)?;
    let mut draws = TaskDraws {
        wanted: params.trials,
        ..TaskDraws::default()
    };
    let spec = field.scenario.world.spec();
    let goals: Vec<(u32, [f64; 2])> = field
        .map
        .landmarks()
        .into_iter()
        .filter_map(|id| match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => Some((id, spec.landmarks[*i].pos)),
            _ => None,
        })
        .filter(|(id, _)| *id != WALL_FRAME_START && *id != WALL_FRAME_END)
        .collect();
    if goals.is_empty() {
        return Err(QlinkError::EmptyMap.into());
    }
    let clear = |p: [f64; 2]| clear_of(spec, p, 1.0);
    let mut out = Vec::with_capacity(params.trials);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed ^ 0x0066_6965_6c64);
    let mut attempts = 0usize;
    while out.len() < params.trials {
        progress.check()?;
        attempts += 1;
        if attempts > 1000 * params.trials {
            break;
        }
        let base = field.drive[rng.random_range(0..field.drive.len())];
        let (r, a) = (
            8.0 * rng.random::<f64>().sqrt(),
            rng.random_range(0.0..std::f64::consts::TAU),
        );
        let start = [base[0] + r * a.cos(), base[1] + r * a.sin()];
        let (goal, goal_position) = goals[rng.random_range(0..goals.len())];
        if !clear(start) {
            draws.blocked += 1;
            continue;
        }
        // a goal already in view makes a trivial trial
        let probe = LidarPerception::new(field, 0);
        let in_view = field.map.elements_in_view(&probe.visible(start));
        if probe.sees(start, goal)
            || in_view
                .iter()
                .any(|&e| field.map.elements()[e].landmarks.contains(&goal))
        {
            draws.trivial += 1;
            continue;
        }
        if in_view.is_empty() {
            draws.no_start += 1;
            continue;
        }
        if graph
            .plan(&field.map, &in_view, goal, &BTreeSet::new())
            .is_err()
        {
            draws.no_path += 1;
            continue;
        }
        draws.kept += 1;
        out.push(FieldTask {
            trial: out.len(),
            start,
            goal,
            goal_position,
        });
        progress.tick();
    }
    Ok((out, draws))
}

/// Whether `p` is inside the site and at least `margin` m from every object.
fn clear_of(spec: &sim2d::WorldSpec, p: [f64; 2], margin: f64) -> bool {
    let [x0, x1, y0, y1] = spec.bounds;
    let free = spec
        .landmarks
        .iter()
        .map(|l| (l.pos, l.radius))
        .chain(spec.clutter.iter().map(|c| (c.pos, c.radius)))
        .all(|(q, r)| (p[0] - q[0]).hypot(p[1] - q[1]) > r + margin);
    let off_walls = spec
        .walls
        .iter()
        .all(|w| seg_dist(p, w.start, w.end) > margin);
    free && off_walls && p[0] > x0 && p[0] < x1 && p[1] > y0 && p[1] < y1
}

/// Where a mapped id truly is: the landmark it was most often recognised from, or the
/// walls' frame points; `None` for clutter or a wall recognised as a point landmark.
pub(super) fn true_position(field: &FieldMap, id: u32) -> Option<[f64; 2]> {
    match id {
        WALL_FRAME_START => Some(field.wall_frame[0]),
        WALL_FRAME_END => Some(field.wall_frame[1]),
        _ => match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => field.scenario.world.spec().landmarks.get(*i).map(|l| l.pos),
            _ => None,
        },
    }
}

/// Propositions 2 and 4 for a run, at R = the lidar's range and at R = the effective range,
/// with the assumptions checked against the simulated site: a landmark is sensed from `x`
/// when the extractor can get its minimum number of returns from it there (its angular
/// width over the scanner's resolution) within the scanner's range, with nothing in between
/// (sim2d's full occlusion) and over the ground (its terrain); the walls' virtual frame
/// points count as sensed within range.
/// The field's controllers search, so Assumption 4 (straight lines) never holds.
#[must_use]
pub fn bound_checks(
    field: &FieldMap,
    plan: &[usize],
    made: &[(usize, usize)],
    transit_length: f64,
) -> [BoundCheck; 2] {
    let world = &field.scenario.world;
    let spec = world.spec();
    let lidar = &field.scenario.lidar;
    let min_returns = ExtractorConfig::default().min_points as f64;
    let resolution = lidar.fov / (lidar.rays.max(2) - 1) as f64;
    let position = |id: u32| true_position(field, id);
    let sensed_from = |x: [f64; 2], id: u32| -> bool {
        let Some(p) = true_position(field, id) else {
            return false;
        };
        let d = (p[0] - x[0]).hypot(p[1] - x[1]);
        if d > lidar.max_range {
            return false;
        }
        match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => {
                let r = spec.landmarks[*i].radius;
                let returns = if d <= r {
                    f64::INFINITY
                } else {
                    2.0 * (r / d).asin() / resolution
                };
                returns >= min_returns
                    && world.is_fully_visible(x, *i)
                    && field
                        .scenario
                        .terrain
                        .as_ref()
                        .is_none_or(|t| t.clears(x, p, lidar.mount_height))
            }
            _ => matches!(id, WALL_FRAME_START | WALL_FRAME_END),
        }
    };
    let drivable = |x: [f64; 2]| clear_of(spec, x, 0.5);
    let geometry = Geometry {
        position: &position,
        sensed_from: &sensed_from,
        drivable: &drivable,
    };
    [lidar.max_range, field.stats.effective_range]
        .map(|r| qlink::bounds::check(&field.map, plan, made, r, false, transit_length, &geometry))
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// The link graph of a variant: −log P(success) from horizon-`h` POMDPs (direct
/// transitions); with visibility-aware costs each link's POMDP detects it with the
/// probability the mapping drive measured.
///
/// # Errors
/// POMDP and graph errors.
pub fn field_graph(
    field: &FieldMap,
    params: &FieldParams,
    variant: FieldVariant,
) -> Result<(LinkGraph, Vec<SearchPomdp>)> {
    let pomdps = field.map.search_pomdps(|b| {
        b.moves(qlink::Moves::Direct)
            .p_move(0.9)
            .horizon(params.horizon)
    })?;
    let graph = if variant.visibility_costs() {
        let map = &field.map;
        let per_link: BTreeMap<u32, Vec<SearchPomdp>> = map
            .landmarks()
            .into_iter()
            .map(|l| {
                let p = field.visibility.get(&l).copied().unwrap_or(0.5);
                let list = pomdps
                    .iter()
                    .map(|q| q.clone().with_p_detect(p))
                    .collect::<qlink::Result<Vec<_>>>()?;
                Ok((l, list))
            })
            .collect::<Result<_>>()?;
        LinkGraph::new(map, params.beta, |i, j, links| {
            let link = links.first().copied().unwrap_or(0);
            match per_link.get(&link) {
                Some(list) => pomdp_cost(map, list, CostModel::NegLogSuccess)(i, j, links),
                None => f64::INFINITY,
            }
        })?
    } else {
        LinkGraph::new(
            &field.map,
            params.beta,
            pomdp_cost(&field.map, &pomdps, CostModel::NegLogSuccess),
        )?
    };
    Ok((graph, pomdps))
}

/// The drive from `end` to the centroid of element `e`'s landmarks in view, in steps, and
/// whether the goal landmark came into view on the way, and its length (empty when none is
/// in view).
fn drive_to_centroid(
    field: &FieldMap,
    perception: &LidarPerception<'_>,
    e: usize,
    end: [f64; 2],
    goal: u32,
    config: &NavConfig,
) -> (Vec<[f64; 2]>, bool, f64) {
    let pts: Vec<[f64; 2]> = field.map.elements()[e]
        .landmarks
        .iter()
        .filter_map(|&l| perception.position(l))
        .collect();
    if pts.is_empty() {
        return (Vec::new(), false, 0.0);
    }
    let n = pts.len() as f64;
    let c = pts
        .iter()
        .fold([0.0, 0.0], |m, p| [m[0] + p[0] / n, m[1] + p[1] / n]);
    let dist = (c[0] - end[0]).hypot(c[1] - end[1]);
    let k = (dist / config.step).ceil().max(1.0) as usize;
    let mut seen = false;
    let drive = (1..=k)
        .map(|i| {
            let t = i as f64 / k as f64;
            let p = [end[0] + t * (c[0] - end[0]), end[1] + t * (c[1] - end[1])];
            seen |= perception.sees(p, goal);
            p
        })
        .collect();
    (drive, seen, dist)
}

/// Runs one trial.
///
/// # Errors
/// Navigation errors other than failures (those are results).
pub fn run_trial(
    field: &FieldMap,
    graph: &LinkGraph,
    config: &NavConfig,
    variant: FieldVariant,
    task: &FieldTask,
) -> Result<FieldTrial> {
    let perception = LidarPerception::new(field, task.trial as u64);
    let nav = Navigator::new(&field.map, graph, &perception, config)?;
    let out: NavOutcome = nav.navigate(task.start, task.goal, None, true)?;
    let mut trajectory = out.trajectory.clone();
    let mut length = out.length;
    let end = trajectory.last().copied().unwrap_or(task.start);
    let (_, detections, aliased) = perception.counts();
    let (ground_share, final_ground_share) = perception.ground_share();
    let result = if out.success {
        // drive to the centroid of the goal element in view (§4.4.2), looking for the goal
        // landmark itself on the way: reaching its element's frame is not enough to say
        // which object is the goal
        let visible = perception.visible(end);
        let element = field
            .map
            .elements_in_view(&visible)
            .into_iter()
            .find(|&e| field.map.elements()[e].landmarks.contains(&task.goal));
        let mut goal_seen = perception.sees(end, task.goal);
        if let Some(e) = element {
            let (drive, seen, dist) =
                drive_to_centroid(field, &perception, e, end, task.goal, config);
            goal_seen |= seen;
            length += dist;
            trajectory.extend(drive);
        }
        // the goal element was "reached" on objects that are not its landmarks: the
        // thesis's wrong goal triplet
        let wrong_element = element.is_some_and(|e| {
            field.map.elements()[e]
                .landmarks
                .iter()
                .any(|&l| perception.last_consistent(l) == Some(false))
        });
        match perception.last_consistent(task.goal) {
            Some(true) if goal_seen && !wrong_element => FieldResult::Success,
            _ if wrong_element
                || (goal_seen && perception.last_consistent(task.goal) == Some(false)) =>
            {
                FieldResult::PerceptualAliasing
            }
            _ if aliased > 0 => FieldResult::InsufficientFeaturesAndAliasing,
            _ => FieldResult::InsufficientFeatures,
        }
    } else if out.failure == Some(Failure::NoPath) {
        FieldResult::NoPath
    } else if aliased > 0 {
        FieldResult::InsufficientFeaturesAndAliasing
    } else {
        FieldResult::InsufficientFeatures
    };
    let fin = trajectory.last().copied().unwrap_or(task.start);
    let made: Vec<(usize, usize)> = out.transitions.iter().map(|t| (t.from, t.to)).collect();
    let bounds = bound_checks(field, &out.plan, &made, out.transit_length);
    Ok(FieldTrial {
        variant,
        task: *task,
        result,
        plan_len: out.plan_len,
        replans: out.replans,
        stranded: out.stranded,
        length,
        final_distance: (fin[0] - task.goal_position[0]).hypot(fin[1] - task.goal_position[1]),
        detections,
        aliased,
        ground_share,
        final_ground_share,
        transit_length: out.transit_length,
        plan: out.plan.clone(),
        bounds,
        trajectory,
    })
}

/// The navigation settings of a variant.
#[must_use]
pub fn nav_config(
    field: &FieldMap,
    params: &FieldParams,
    variant: FieldVariant,
    pomdp: SearchPomdp,
) -> NavConfig {
    let controller = if variant.safe_search() {
        Controller::new(ControllerKind::SafeSearch, field.stats.effective_range)
    } else {
        Controller::new(ControllerKind::MidpointSweep, field.stats.effective_range)
    };
    NavConfig {
        step: params.step,
        replan: true,
        max_replans: params.max_replans,
        map_range: field.scenario.lidar.max_range,
        find_goal: true,
        robot: params.navigating_robot(),
        ..NavConfig::thesis(controller, pomdp)
    }
}

/// Maps the field and runs every variant's trials (in parallel; the result does not depend
/// on the thread count). `progress` is told [`field_units`] before any work, ticks after the
/// map, each task drawn and each trial, and is checked between them (a cancelled run returns
/// [`crate::error::StudyError::Cancelled`]).
///
/// # Errors
/// As [`map_field`], [`tasks`], [`field_graph`], [`run_trial`].
pub fn run_field(
    params: &FieldParams,
    variants: &[FieldVariant],
    progress: &dyn Progress,
) -> Result<(FieldMap, TaskDraws, Vec<FieldTrial>)> {
    progress.add_total(field_units(params, variants));
    let progress = &FixedTotal(progress);
    progress.check()?;
    let field = phase(progress, 1, |_| map_field(params))?;
    let (tasks, draws) = phase(progress, params.trials, |p| tasks(&field, params, p))?;
    let mut all = Vec::new();
    for &v in variants {
        // as many units as promised even when the map gave fewer pairs (the phase tops up)
        let trials: Vec<FieldTrial> = phase(progress, params.trials, |p| {
            let (graph, pomdps) = field_graph(&field, params, v)?;
            let config = nav_config(&field, params, v, pomdps[0].clone());
            tasks
                .par_iter()
                .map(|t| {
                    p.check()?;
                    let r = run_trial(&field, &graph, &config, v, t);
                    p.tick();
                    r
                })
                .collect::<Result<_>>()
        })?;
        all.extend(trials);
    }
    Ok((field, draws, all))
}

/// The units of progress [`run_field`] ticks: the map, each task drawn, each variant's trials.
#[must_use]
pub fn field_units(params: &FieldParams, variants: &[FieldVariant]) -> usize {
    params
        .trials
        .saturating_mul(1 + variants.len())
        .saturating_add(1)
}
