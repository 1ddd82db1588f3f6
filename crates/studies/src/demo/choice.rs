//! Which navigation the demo shows: the longest plan that succeeds for the seed, by a rule
//! stated in the summary ([`RUN_RULE`]), so the picture is not a hand-picked success.

use qlink::{LinkGraph, NavConfig, NavOutcome, Navigator, Perception, QualitativeMap};
use qsr_core::progress::Progress;
use serde::{Deserialize, Serialize};

use crate::error::{Result, StudyError};
use crate::world_perception::WorldPerception;

/// Navigations run side by side while looking for the first success: the choice is the first
/// success in [`RUN_RULE`]'s order whatever the batch, so it does not depend on the thread
/// count.
const BATCH: usize = 8;

/// Poses of the mapping drive considered as starts: every this many frames that saw three
/// landmarks.
pub const START_EVERY: usize = 10;

/// The rule the demo picks its run by (in `summary.json`).
pub const RUN_RULE: &str = "starts: every 10th pose of the mapping drive that saw three landmarks; \
goals: every mapped landmark out of view there; pairs tried longest plan first (ties: the \
farthest goal); every pair is tried in that order until one reaches its goal, and that run is shown; when none does, the demo says so and shows the longest plan's run";

/// What a navigation runs in.
pub struct Setting<'a> {
    /// The qualitative map.
    pub map: &'a QualitativeMap,
    /// Its Link Graph.
    pub graph: &'a LinkGraph,
    /// What the navigating robot senses.
    pub perception: &'a WorldPerception<'a>,
    /// The navigator's settings.
    pub config: &'a NavConfig,
}

/// The run the demo shows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chosen {
    /// Start position (m).
    pub start: [f64; 2],
    /// Goal landmark.
    pub goal: u32,
    /// The navigation.
    pub outcome: NavOutcome,
    /// Navigations run to find it.
    pub tried: usize,
    /// Start/goal pairs with a plan.
    pub candidates: usize,
}

/// A start/goal pair with a plan: `(|P|, distance to the goal, start, goal)`.
type Pair = (usize, f64, [f64; 2], u32);

/// Every start/goal pair along the mapping drive with a plan, in the order [`RUN_RULE`] tries
/// them. With `goal`, only that goal.
fn pairs(s: &Setting<'_>, frames: &[sim2d::Frame], goal: Option<u32>) -> Vec<Pair> {
    let landmarks = s.map.landmarks();
    let mut pairs: Vec<Pair> = Vec::new();
    for f in frames
        .iter()
        .filter(|f| f.detections.len() >= 3)
        .step_by(START_EVERY)
    {
        let start = [f.pose.x, f.pose.y];
        let visible = s.perception.visible(start);
        let starts = s.map.elements_in_view(&visible);
        if starts.is_empty() {
            continue;
        }
        for &l in &landmarks {
            if goal.is_some_and(|g| g != l) || visible.contains(&l) {
                continue;
            }
            let Ok(plan) = s.graph.plan(s.map, &starts, l, &Default::default()) else {
                continue;
            };
            let Some(p) = s.perception.position(l) else {
                continue;
            };
            pairs.push((
                plan.len(),
                (p[0] - start[0]).hypot(p[1] - start[1]),
                start,
                l,
            ));
        }
    }
    pairs.sort_by(|x, y| {
        y.0.cmp(&x.0)
            .then(y.1.total_cmp(&x.1))
            .then(x.3.cmp(&y.3))
            .then(x.2[0].total_cmp(&y.2[0]))
            .then(x.2[1].total_cmp(&y.2[1]))
    });
    pairs
}

/// Picks the run by [`RUN_RULE`]: the longest plan that succeeds, trying every pair with a
/// plan before it says none does. With `goal`, only that goal is considered.
///
/// # Errors
/// Q-Link's; [`StudyError::InvalidParameter`] when no pair has a plan;
/// [`StudyError::Cancelled`] between navigations when `progress` asks.
pub fn choose_run(
    s: &Setting<'_>,
    frames: &[sim2d::Frame],
    goal: Option<u32>,
    progress: &dyn Progress,
) -> Result<Chosen> {
    use rayon::prelude::*;
    let pairs = pairs(s, frames, goal);
    let candidates = pairs.len();
    let nav = Navigator::new(s.map, s.graph, s.perception, s.config)?;
    let mut longest: Option<Chosen> = None;
    for (b, batch) in pairs.chunks(BATCH).enumerate() {
        let runs = batch
            .par_iter()
            .enumerate()
            .map(|(k, &(_, _, start, l))| {
                progress.check()?;
                Ok(Chosen {
                    start,
                    goal: l,
                    outcome: nav.navigate(start, l, None, true)?,
                    tried: b * BATCH + k + 1,
                    candidates,
                })
            })
            .collect::<Result<Vec<Chosen>>>()?;
        let mut runs = runs.into_iter();
        if longest.is_none() {
            longest = runs.clone().next();
        }
        if let Some(run) = runs.find(|r| r.outcome.success) {
            return Ok(run);
        }
    }
    match longest {
        Some(mut run) => {
            run.tried = candidates;
            Ok(run)
        }
        // The navigating robot's range is said: too short a one (`--nav-range 1e-12`) is
        // the usual reason no pair has a plan (issue 39).
        None => Err(StudyError::InvalidParameter(match goal {
            Some(g) => format!(
                "goal: no pose of the mapping drive has a plan to landmark {g} (navigating \
                 with nav_range = {} m)",
                s.perception.range()
            ),
            None => format!(
                "no start/goal pair along the mapping drive has a plan (navigating with \
                 nav_range = {} m)",
                s.perception.range()
            ),
        })),
    }
}
