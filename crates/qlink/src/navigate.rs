//! Executing a plan: the three levels together (thesis §4.3), with contingency re-planning.
//!
//! The robot starts wherever it is, localises in any element two of whose landmarks it sees
//! (circling the nearest visible landmark at radius R if it sees none: Proposition 1's
//! search), plans over the Link Graph, and makes each transition `M_i → M_j`:
//!
//! 1. *Search for the link* `L ∈ M_i ∩ M_j` in the frame of `M_i`'s other two landmarks: the
//!    POMDP picks the state to search (the map's distribution over `{A, B : L}`), the
//!    controller drives there, "not seen" updates the belief; after the horizon, full
//!    circles about the references' midpoint at radius R are the fallback
//!    ([`NavConfig::fallbacks`]). The frame is placed where the robot perceives the
//!    references, or where it last perceived them ([`References`]).
//! 2. *Acquire `M_j`'s frame*: the transition completes when `M_j`'s reference landmarks are
//!    seen at once (`L_j^ref ⊆ L^vis_t`, §4.4.1; [`Arrival`]). If seeing the link is not
//!    enough, the robot circles the link at radius R.
//!
//! R is the controller's radius — the mapping robot's range in the thesis's study, whatever
//! the navigating robot's sensor range R' is.
//!
//! A failed transition is excluded and the robot re-plans from the elements it sees
//! (§4.4.2's contingency plan). Each outcome reports |P|, the trajectory length and the
//! bound of Proposition 2, `(2π + 1)·R·|P|`.
//!
//! The robot senses where [`Sensing`] says through a [`Perception`] — range only
//! ([`RangePerception`]) or, in the studies, a simulator's full occlusion — and errs as its
//! [`Robot`] says: noisy, missed and false detections, and waypoints driven with random
//! motion error that its odometry does not see ([`crate::robot`]). It decides only from
//! what it detects, in the frame where it believes it is; the trajectory it reports is
//! where it truly drove.

use std::collections::BTreeSet;

use serde::{Deserialize, Serialize};

use crate::controller::{Controller, circle, robot_state};
use crate::error::{QlinkError, Result};
pub use crate::execution::{Arrival, Odometry, References, Sensing};
use crate::execution::{Leg, Walker};
use crate::graph::{DistanceField, LinkGraph, Plan};
use crate::map::QualitativeMap;
use crate::perception::distance as d;
pub use crate::perception::{Perception, RangePerception};
use crate::pomdp::SearchPomdp;
use crate::robot::{Robot, run_key};

/// Search circles run at the controller's radius R, a hair inside so that a landmark circled
/// at the sensor's full range stays detected despite rounding (Proposition 1 needs R' ≥ R).
const SEARCH_RADIUS: f64 = 1.0 - 1e-9;

/// Scans the robot takes where it stands before it localises (a detector's successive
/// frames): a landmark in view is missed on all of them with probability `miss_rate³`
/// (0.7 % at MRCLAM's 19 %, [`crate::robot::MISS_RATE`]), where one scan would miss one in
/// five and start the plan from too few landmarks.
const LOOKS: usize = 3;

/// Waypoint spacing of search circles (deg).
const CIRCLE_STEP_DEG: f64 = 2.0;

/// Navigation settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NavConfig {
    /// The trajectory-level controller.
    pub controller: Controller,
    /// The QSR-level POMDP (its horizon is the number of commands before the fallback).
    pub pomdp: SearchPomdp,
    /// Distance between perception checks along a path (m).
    pub step: f64,
    /// Re-plan around failed transitions.
    pub replan: bool,
    /// Most re-plans per navigation.
    pub max_replans: usize,
    /// Sensor range of the robot that made the map (R of Proposition 2).
    pub map_range: f64,
    /// On reaching an element holding the goal, also search for the goal landmark itself in
    /// the frame of the element's other two (the map's distribution over their relation
    /// says where), and fail if it is not found. Off, reaching the element's frame is
    /// arrival (§4.4.1); on, the robot must see its goal (the §4.4.2 field experiment, where
    /// the recogniser, not the simulator, says what is seen).
    #[serde(default)]
    pub find_goal: bool,
    /// Where the positions of unseen references come from (thesis: what was perceived,
    /// carried forward by odometry; [`References::Oracle`] is idealised).
    #[serde(default)]
    pub references: References,
    /// When a transition is complete (thesis: `M_j`'s reference landmarks seen).
    #[serde(default)]
    pub arrival: Arrival,
    /// Where along its paths the robot senses.
    #[serde(default)]
    pub sensing: Sensing,
    /// Full circles about the references' midpoint after the POMDP's commands fail to find
    /// a link (the fallback budget of a search).
    #[serde(default = "one")]
    pub fallbacks: usize,
    /// What the robot's detector and wheels get wrong ([`Robot::EXACT`] is idealised).
    /// A configuration written before the robot could err reads as the exact robot.
    #[serde(default = "exact")]
    pub robot: Robot,
}

fn exact() -> Robot {
    Robot::EXACT
}

fn one() -> usize {
    1
}

impl NavConfig {
    /// The thesis's navigator (§4.4.1) with `controller` and `pomdp`: sensing every metre, no
    /// re-planning, arrival when the next frame's references are seen, unseen references
    /// where they were last seen (wheel odometry), one fallback circle per search, and a
    /// mapping range equal to the controller's radius.
    #[must_use]
    pub fn thesis(controller: Controller, pomdp: SearchPomdp) -> Self {
        Self {
            map_range: controller.radius,
            controller,
            pomdp,
            step: 1.0,
            replan: false,
            max_replans: 0,
            find_goal: false,
            references: References::default(),
            arrival: Arrival::default(),
            sensing: Sensing::default(),
            fallbacks: 1,
            robot: Robot::default(),
        }
    }

    /// The idealised options that are on (the reports label such runs).
    #[must_use]
    pub fn idealised(&self) -> Vec<&'static str> {
        let mut out = crate::execution::idealised(self.references, self.arrival);
        if self.robot.is_exact() {
            out.push("exact detections and motion");
        }
        out
    }
}

/// Why a navigation failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Failure {
    /// The robot could not localise in any element at the start.
    NoStart,
    /// No path in the link graph (counted apart from failures).
    NoPath,
    /// A transition failed and no alternative path was left: not enough landmarks seen.
    InsufficientFeatures,
}

/// What a run that failed for insufficient features was left without, after its last
/// contingency (a failed transition or goal search).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stranded {
    /// No map element in view, even after the localisation circle.
    NoElementInView,
    /// Elements in view, but no path to the goal once the failed links (and the goal
    /// elements searched in vain) are excluded.
    NoPathLeft,
    /// The re-plan budget ([`NavConfig::max_replans`]) was spent, or re-planning is off.
    ReplanBudget,
}

impl Stranded {
    /// Its name in files (as in JSON).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::NoElementInView => "no-element-in-view",
            Self::NoPathLeft => "no-path-left",
            Self::ReplanBudget => "replan-budget",
        }
    }
}

/// One transition as executed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TransitionRecord {
    /// From element.
    pub from: usize,
    /// To element.
    pub to: usize,
    /// The link searched for.
    pub link: u32,
    /// Commands (POMDP decisions) issued.
    pub commands: Vec<usize>,
    /// Whether it completed.
    pub success: bool,
    /// Trajectory length of this transition (m).
    pub length: f64,
    /// Where the robot was when the transition ended.
    #[serde(default)]
    pub end: [f64; 2],
}

/// The result of one navigation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NavOutcome {
    /// Reached an element holding the goal.
    pub success: bool,
    /// Why not.
    pub failure: Option<Failure>,
    /// |P| of the first plan.
    pub plan_len: usize,
    /// Re-plans made.
    pub replans: usize,
    /// For a run that failed for insufficient features: what it was left without.
    #[serde(default)]
    pub stranded: Option<Stranded>,
    /// Trajectory length (m).
    pub length: f64,
    /// Length driven inside transitions (excludes the start-up localisation search): what
    /// Proposition 2 bounds (m).
    pub transit_length: f64,
    /// Proposition 2's bound for the first plan, (2π + 1)·R·|P| (m).
    pub bound: f64,
    /// Proposition 4's bound, R·|P| (m): valid for maps meeting Assumptions 3–4 with the
    /// direct controller.
    pub bound_direct: f64,
    /// Positions visited (every `step`).
    pub trajectory: Vec<[f64; 2]>,
    /// Transitions made.
    pub transitions: Vec<TransitionRecord>,
    /// The first plan's map elements, start to goal (empty when none was made).
    #[serde(default)]
    pub plan: Vec<usize>,
    /// Where the robot searched for a link (or the goal): index ranges `[from, to]` into
    /// `trajectory` (inclusive) covering the POMDP's commands and the fallback circles, so
    /// a picture can tell searching from driving (empty when the trajectory is not kept).
    #[serde(default)]
    pub searches: Vec<[usize; 2]>,
}

impl NavOutcome {
    /// An outcome before anything happened (or when nothing can: `failure`).
    #[must_use]
    pub fn unfinished(failure: Option<Failure>) -> Self {
        Self {
            success: false,
            failure,
            plan_len: 0,
            replans: 0,
            stranded: None,
            length: 0.0,
            transit_length: 0.0,
            bound: 0.0,
            bound_direct: 0.0,
            trajectory: Vec::new(),
            transitions: Vec::new(),
            plan: Vec::new(),
            searches: Vec::new(),
        }
    }
}

/// What follows an element of a plan: the next element, or the goal.
#[derive(Debug, Clone, Copy)]
enum Next {
    Element(usize),
    Goal(u32),
}

const CIRCLE: Leg = Leg::Circle {
    step_deg: CIRCLE_STEP_DEG,
};

/// Runs navigations against one map and graph.
pub struct Navigator<'a, P: Perception> {
    map: &'a QualitativeMap,
    graph: &'a LinkGraph,
    perception: &'a P,
    config: &'a NavConfig,
}

impl<'a, P: Perception> Navigator<'a, P> {
    /// A navigator.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for a non-positive step or range, or a robot's
    /// rate or spread out of range ([`Robot::check`]).
    pub fn new(
        map: &'a QualitativeMap,
        graph: &'a LinkGraph,
        perception: &'a P,
        config: &'a NavConfig,
    ) -> Result<Self> {
        let positive = |v: f64| v > 0.0 && v.is_finite();
        if !positive(config.step) || !positive(perception.range()) || !positive(config.map_range) {
            return Err(QlinkError::InvalidParameter(format!(
                "step {} m, sensor range {} m and map range {} m must be positive",
                config.step,
                perception.range(),
                config.map_range
            )));
        }
        config.references.check()?;
        config.sensing.check()?;
        config.robot.check()?;
        Ok(Self {
            map,
            graph,
            perception,
            config,
        })
    }

    /// Navigates from next to landmark `start` (offset by `offset` m along x) to landmark
    /// `goal`.
    ///
    /// # Errors
    /// [`QlinkError::SameStartGoal`]; [`QlinkError::UnknownLandmark`] for either landmark;
    /// as [`Navigator::navigate`].
    pub fn navigate_between(&self, start: u32, goal: u32, offset: f64) -> Result<NavOutcome> {
        if start == goal {
            return Err(QlinkError::SameStartGoal(start));
        }
        let p = self
            .perception
            .position(start)
            .ok_or(QlinkError::UnknownLandmark(start))?;
        self.navigate([p[0] + offset, p[1]], goal, None, true)
    }

    /// Navigates from `start` (a position) to any element holding landmark `goal`; `field`
    /// (the goal's distance field) makes the first plan cheap when many runs share a goal.
    /// `record` keeps the trajectory points.
    ///
    /// # Errors
    /// [`QlinkError::UnknownLandmark`] for a goal not in the map; controller and frame errors.
    pub fn navigate(
        &self,
        start: [f64; 2],
        goal: u32,
        field: Option<&DistanceField>,
        record: bool,
    ) -> Result<NavOutcome> {
        if self.map.elements_with(goal).is_empty() {
            return Err(QlinkError::UnknownLandmark(goal));
        }
        let range = self.config.controller.radius;
        let (step, sensing) = (self.config.step, self.config.sensing);
        let robot = self.config.robot;
        let run = run_key(
            robot.seed,
            &[start[0].to_bits(), start[1].to_bits(), u64::from(goal)],
        );
        let mut w = Walker::new(self.perception, start, step, sensing, record, robot, run);
        let mut out = NavOutcome::unfinished(None);
        let Some(mut starts) = self.localise(&mut w, range) else {
            out.failure = Some(Failure::NoStart);
            return Ok(self.finish(out, w));
        };
        let mut excluded: BTreeSet<(usize, usize)> = BTreeSet::new();
        // goal elements in whose frame the goal was searched for and not found
        let mut failed_goals: BTreeSet<usize> = BTreeSet::new();
        let mut first = true;
        loop {
            starts.retain(|e| !failed_goals.contains(e));
            if let Some(&e) = starts
                .iter()
                .find(|&&e| self.map.elements()[e].landmarks.contains(&goal))
            {
                if self.goal_found(&mut w, e, goal)? {
                    out.success = true;
                    break;
                }
                // a contingency like a failed transition: plan to another element holding
                // the goal, never back into this one
                failed_goals.insert(e);
                excluded.extend(self.edges_into(e));
                first = false;
                match self.recover(&mut w, &mut out, range) {
                    Some(s) => {
                        starts = s;
                        continue;
                    }
                    None => break,
                }
            }
            if starts.is_empty() {
                // every element in view holds the goal and was given up
                out.failure = Some(Failure::InsufficientFeatures);
                out.stranded = Some(Stranded::NoPathLeft);
                break;
            }
            let plan = match self.next_plan(first, field, &starts, goal, &excluded)? {
                Ok(p) => p,
                Err(failure) => {
                    if failure == Failure::InsufficientFeatures {
                        out.stranded = Some(Stranded::NoPathLeft);
                    }
                    out.failure = Some(failure);
                    break;
                }
            };
            if first {
                self.note_first_plan(&mut out, &plan);
                first = false;
            }
            match self.follow(&mut w, &plan, goal, &mut out)? {
                None => {
                    // the plan's last element holds the goal: the check above ends the run
                    starts = self.map.elements_in_view(&w.visible());
                    starts.extend(plan.elements.last().copied());
                    starts.sort_unstable();
                    starts.dedup();
                }
                Some(edge) => {
                    excluded.insert(edge);
                    match self.recover(&mut w, &mut out, range) {
                        Some(s) => starts = s,
                        None => break,
                    }
                }
            }
        }
        Ok(self.finish(out, w))
    }

    /// The plan from `starts` to the goal avoiding `excluded` (the first from the goal's
    /// distance field when one is given); `Err(failure)` when there is none: no path at all
    /// at the start, too few features after a contingency.
    fn next_plan(
        &self,
        first: bool,
        field: Option<&DistanceField>,
        starts: &[usize],
        goal: u32,
        excluded: &BTreeSet<(usize, usize)>,
    ) -> Result<std::result::Result<Plan, Failure>> {
        let plan = match (first, field) {
            (true, Some(f)) => f.path_from(self.graph, starts),
            _ => self.graph.plan(self.map, starts, goal, excluded),
        };
        match plan {
            Ok(p) => Ok(Ok(p)),
            Err(QlinkError::NoPath { .. }) if first => Ok(Err(Failure::NoPath)),
            Err(QlinkError::NoPath { .. }) => Ok(Err(Failure::InsufficientFeatures)),
            Err(e) => Err(e),
        }
    }

    /// In goal element `e`: whether the goal is in view, or found by searching `e`'s link
    /// (when the navigator searches for it).
    fn goal_found(&self, w: &mut Walker<'_, P>, e: usize, goal: u32) -> Result<bool> {
        if !self.config.find_goal || w.sees(goal) {
            return Ok(true);
        }
        let mut commands = Vec::new();
        self.search_link(w, e, goal, &mut commands)
    }

    /// The Link Graph's edges into element `e` (what a failed search of `e` excludes).
    fn edges_into(&self, e: usize) -> Vec<(usize, usize)> {
        self.graph
            .graph()
            .neighbors_directed(
                petgraph::graph::NodeIndex::new(e),
                petgraph::Direction::Incoming,
            )
            .map(|src| (src.index(), e))
            .collect()
    }

    /// A contingency (a failed transition or goal search): localise again and re-plan, if
    /// re-planning is on and its budget allows; `None` (the run failed for lack of
    /// features) otherwise.
    fn recover(
        &self,
        w: &mut Walker<'_, P>,
        out: &mut NavOutcome,
        range: f64,
    ) -> Option<Vec<usize>> {
        if !self.config.replan || out.replans >= self.config.max_replans {
            out.failure = Some(Failure::InsufficientFeatures);
            out.stranded = Some(Stranded::ReplanBudget);
            return None;
        }
        out.replans += 1;
        let starts = self.localise(w, range);
        if starts.is_none() {
            out.failure = Some(Failure::InsufficientFeatures);
            out.stranded = Some(Stranded::NoElementInView);
        }
        starts
    }

    /// The first plan's length, the two bounds of Propositions 1–2 for it, its elements.
    fn note_first_plan(&self, out: &mut NavOutcome, plan: &Plan) {
        out.plan_len = plan.len();
        out.bound = (2.0 * std::f64::consts::PI + 1.0) * self.config.map_range * plan.len() as f64;
        out.bound_direct = self.config.map_range * plan.len() as f64;
        out.plan.clone_from(&plan.elements);
    }

    /// Follows `plan` transition by transition; the first edge that failed, if one did.
    fn follow(
        &self,
        w: &mut Walker<'_, P>,
        plan: &Plan,
        goal: u32,
        out: &mut NavOutcome,
    ) -> Result<Option<(usize, usize)>> {
        for (k, pair) in plan.elements.windows(2).enumerate() {
            let next = match plan.elements.get(k + 2) {
                Some(&n) => Next::Element(n),
                None => Next::Goal(goal),
            };
            let mut rec = self.transition(w, pair[0], pair[1], next)?;
            rec.end = w.truly();
            let ok = rec.success;
            out.transitions.push(rec);
            if !ok {
                return Ok(Some((pair[0], pair[1])));
            }
        }
        Ok(None)
    }

    fn finish(&self, mut out: NavOutcome, w: Walker<'_, P>) -> NavOutcome {
        out.length = w.length;
        out.transit_length = out.transitions.iter().map(|t| t.length).sum();
        out.trajectory = w.trajectory;
        out.searches = w.searches;
        out
    }

    /// Elements in view; if none, circle the nearest visible landmark at sensor range.
    fn localise(&self, w: &mut Walker<'_, P>, range: f64) -> Option<Vec<usize>> {
        let visible = w.visible_over(LOOKS);
        let starts = self.map.elements_in_view(&visible);
        // The direct controller starts from an element of the landmark the robot stands at
        // (Proposition 3's x_t = L_n): from there every landmark of the element is in view.
        if self.config.controller.kind == crate::controller::ControllerKind::Direct
            && let Some(&here) = visible.iter().find(|&&id| {
                let at = w.detect(id);
                at.is_some_and(|p| d(p, w.here()) <= 1.0)
            })
        {
            let own: Vec<usize> = starts
                .iter()
                .copied()
                .filter(|&e| self.map.elements()[e].landmarks.contains(&here))
                .collect();
            if !own.is_empty() {
                return Some(own);
            }
        }
        if !starts.is_empty() {
            return Some(starts);
        }
        let pos = w.here();
        let anchor = visible
            .iter()
            .filter_map(|&id| w.detect(id).map(|p| (id, p)))
            .min_by(|a, b| d(a.1, pos).total_cmp(&d(b.1, pos)))?;
        let path = circle(anchor.1, self.in_view(range), pos, CIRCLE_STEP_DEG);
        let map = self.map;
        let found = w.walk(&path, CIRCLE, &[anchor], &mut |w: &mut Walker<'_, P>| {
            !map.elements_in_view(&w.visible()).is_empty()
        });
        if found {
            Some(self.map.elements_in_view(&w.visible()))
        } else {
            None
        }
    }

    /// The radius of a circle about a landmark that keeps it in view: R, or R' when the
    /// sensor is shorter, less the robot's margin ([`Robot::margin`]: a robot that errs
    /// circles inside its range by what its detections and one step's drive can be off).
    fn in_view(&self, range: f64) -> f64 {
        let keep = range.min(self.perception.range()) * SEARCH_RADIUS;
        let margin = self.config.robot.margin(self.config.step);
        if margin == 0.0 {
            keep
        } else {
            (keep - margin).max(keep / 2.0)
        }
    }

    /// The pairs of `M_j`'s landmarks whose sight completes a transition into `j`: under
    /// [`Arrival::References`] those framing what comes next (the pair left when a link to
    /// the next element, or the goal, is taken out), under [`Arrival::AnyTwo`] all three.
    fn references(&self, j: usize, next: Next) -> Vec<[u32; 2]> {
        let [a, b, c] = self.map.elements()[j].landmarks;
        let all = [[b, c], [a, c], [a, b]];
        let framed: Vec<u32> = match (self.config.arrival, next) {
            (Arrival::AnyTwo, _) => return all.to_vec(),
            (Arrival::References, Next::Element(n)) => self
                .graph
                .edge(j, n)
                .map(|e| e.links().to_vec())
                .unwrap_or_default(),
            (Arrival::References, Next::Goal(g)) => vec![g],
        };
        let pairs: Vec<[u32; 2]> = [a, b, c]
            .iter()
            .zip(all)
            .filter(|(l, _)| framed.contains(l))
            .map(|(_, pair)| pair)
            .collect();
        // an element that holds neither (not reachable from a plan) keeps the loose rule
        if pairs.is_empty() {
            all.to_vec()
        } else {
            pairs
        }
    }

    /// Whether one of `pairs` is seen at once from where the robot is.
    fn in_frame(w: &mut Walker<'_, P>, pairs: &[[u32; 2]]) -> bool {
        pairs.iter().any(|&[a, b]| w.sees(a) && w.sees(b))
    }

    /// Searches for `link` in the frame of element `i`'s other two landmarks: the POMDP's
    /// commands through the controller until the link is seen, then a full circle about the
    /// references' midpoint at sensor range. True when it was seen.
    fn search_link(
        &self,
        w: &mut Walker<'_, P>,
        i: usize,
        link: u32,
        commands: &mut Vec<usize>,
    ) -> Result<bool> {
        let map = self.map;
        let others: Vec<u32> = map.elements()[i]
            .landmarks
            .iter()
            .copied()
            .filter(|&l| l != link)
            .collect();
        let [a, b] = others.as_slice() else {
            return Ok(false);
        };
        let (a, b) = (*a, *b);
        w.watch(&[a, b]);
        let from = w.trajectory.len().saturating_sub(1);
        let found = self.search_in_frame(w, i, [a, b], link, commands);
        if w.record && w.trajectory.len() > from + 1 {
            w.searches.push([from, w.trajectory.len() - 1]);
        }
        found
    }

    /// [`Navigator::search_link`] once the frame `[a, b]` is known.
    fn search_in_frame(
        &self,
        w: &mut Walker<'_, P>,
        i: usize,
        [a, b]: [u32; 2],
        link: u32,
        commands: &mut Vec<usize>,
    ) -> Result<bool> {
        let map = self.map;
        let range = self.config.controller.radius;
        let refs = self.config.references;
        // the frame as the robot places it now: measured, remembered, or not at all
        let frame = |w: &mut Walker<'_, P>| match (w.place(a, refs), w.place(b, refs)) {
            (Some(pa), Some(pb)) if d(pa, pb) > 0.0 => Some((pa, pb)),
            _ => None,
        };
        let calculus = map.calculus(i);
        let mut belief = map
            .belief(i, [a, b, link])
            .unwrap_or_else(|| vec![1.0; calculus.n_states()]);
        let own;
        let pomdp = if self.config.pomdp.n_states() == calculus.n_states() {
            &self.config.pomdp
        } else {
            own = self.config.pomdp.for_calculus(calculus)?;
            &own
        };
        for step in 0..pomdp.horizon {
            let Some((pa, pb)) = frame(w) else {
                return Ok(false);
            };
            let r = robot_state(calculus, pa, pb, w.here())?;
            let dec = pomdp.decide_with(r, &belief, pomdp.horizon - step)?;
            commands.push(dec.action);
            let path = self
                .config
                .controller
                .path(calculus, pa, pb, dec.action, w.here())?;
            let stop = &mut |w: &mut Walker<'_, P>| w.sees(link);
            if w.walk(&path[1..], Leg::Command, &[(a, pa), (b, pb)], stop) {
                return Ok(true);
            }
            belief = pomdp.update_not_seen(&belief, dec.action);
        }
        // fallback: full circles about the references' midpoint at radius R
        for _ in 0..self.config.fallbacks {
            let Some((pa, pb)) = frame(w) else {
                return Ok(false);
            };
            let m = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
            let path = circle(m, range * SEARCH_RADIUS, w.here(), CIRCLE_STEP_DEG);
            let anchor = [(a, pa), (b, pb)];
            if w.walk(&path[1..], CIRCLE, &anchor, &mut |w: &mut Walker<'_, P>| {
                w.sees(link)
            }) {
                return Ok(true);
            }
        }
        Ok(false)
    }

    /// The landmark of edge (i, j)'s link set to search for: with β ≥ 2 the set has several,
    /// and one the robot does not see yet is progress towards M_j's frame (a visible one is
    /// not).
    fn link_for(&self, w: &mut Walker<'_, P>, i: usize, j: usize) -> u32 {
        let links = self
            .graph
            .edge(i, j)
            .map(|e| e.links().to_vec())
            .unwrap_or_default();
        links
            .iter()
            .copied()
            .find(|&l| !w.sees(l))
            .or(links.first().copied())
            .unwrap_or(self.map.elements()[j].landmarks[0])
    }

    fn transition(
        &self,
        w: &mut Walker<'_, P>,
        i: usize,
        j: usize,
        next: Next,
    ) -> Result<TransitionRecord> {
        let start_len = w.length;
        let link = self.link_for(w, i, j);
        let mut rec = TransitionRecord {
            from: i,
            to: j,
            link,
            commands: Vec::new(),
            success: false,
            length: 0.0,
            end: w.truly(),
        };
        let range = self.config.controller.radius;
        let refs = self.references(j, next);
        let done = |w: &mut Walker<'_, P>, rec: &mut TransitionRecord| {
            rec.success = true;
            rec.length = w.length - start_len;
        };
        // the direct controller (Proposition 4): a visible link is driven to in a straight
        // line; at a landmark of M_j all of M_j is in view when Assumption 3 holds
        if self.config.controller.kind == crate::controller::ControllerKind::Direct
            && let Some(pl) = w.detect(link)
        {
            // all the way to the link (not just until M_j is in view), so the next
            // transition starts at a landmark again (Proposition 3)
            rec.commands.push(usize::MAX);
            w.walk(&[pl], Leg::Command, &[(link, pl)], &mut |_: &mut Walker<
                '_,
                P,
            >| {
                false
            });
            if Self::in_frame(w, &refs) {
                done(w, &mut rec);
                return Ok(rec);
            }
        }
        if Self::in_frame(w, &refs) {
            done(w, &mut rec);
            return Ok(rec);
        }
        // phase 1: find the link in M_i's frame
        if !w.sees(link) && !self.search_link(w, i, link, &mut rec.commands)? {
            rec.length = w.length - start_len;
            return Ok(rec);
        }
        // phase 2: two landmarks of M_j at once
        if Self::in_frame(w, &refs) {
            done(w, &mut rec);
            return Ok(rec);
        }
        let Some(pl) = w.detect(link) else {
            rec.length = w.length - start_len;
            return Ok(rec);
        };
        let path = circle(pl, self.in_view(range), w.here(), CIRCLE_STEP_DEG);
        let ok = w.walk(&path[1..], CIRCLE, &[(link, pl)], &mut |w: &mut Walker<
            '_,
            P,
        >| {
            Self::in_frame(w, &refs)
        });
        if ok {
            done(w, &mut rec);
        } else {
            rec.length = w.length - start_len;
        }
        Ok(rec)
    }
}
