//! Executing a plan: the three levels together (thesis §4.3), with contingency re-planning.
//!
//! The robot starts wherever it is, localises in any element two of whose landmarks it sees
//! (circling the nearest visible landmark at sensor range if it sees none: Proposition 1's
//! search), plans over the Link Graph, and makes each transition `M_i → M_j`:
//!
//! 1. *Search for the link* `L ∈ M_i ∩ M_j` in the frame of `M_i`'s other two landmarks: the
//!    POMDP picks the state to search (the map's distribution over `{A, B : L}`), the
//!    controller drives there, "not seen" updates the belief; after the horizon a full
//!    circle about the references' midpoint at sensor range is the fallback.
//! 2. *Acquire `M_j`'s frame*: the transition completes when two landmarks of `M_j` are seen
//!    at once (`L_j^ref ⊆ L^vis`, §4.4.1). If seeing the link is not enough, the robot
//!    circles the link at sensor range (the link stays in view; Proposition 1 guarantees a
//!    second landmark of `M_j` comes into view when the assumptions hold).
//!
//! A failed transition is excluded and the robot re-plans from the elements it sees
//! (§4.4.2's contingency plan). Each outcome reports |P|, the trajectory length and the
//! bound of Proposition 2, `(2π + 1)·R·|P|`.
//!
//! The simulation moves the robot exactly along the controller's waypoints and checks what
//! it sees every `step` metres through a [`Perception`]: range only ([`RangePerception`]) or
//! sim2d's full occlusion ([`WorldPerception`]).

use std::collections::{BTreeSet, HashMap};

use serde::{Deserialize, Serialize};

use crate::controller::{Controller, circle, robot_state};
use crate::error::{QlinkError, Result};
use crate::graph::{DistanceField, LinkGraph, Plan};
use crate::map::QualitativeMap;
use crate::pomdp::SearchPomdp;

/// Search circles run at the sensor range, a hair inside so that the landmark circled stays
/// detected despite rounding (Proposition 1 needs the full range R).
const SEARCH_RADIUS: f64 = 1.0 - 1e-9;

/// What the robot detects.
pub trait Perception: Sync {
    /// The landmark's position (the simulator's; the robot uses it only as a measurement
    /// relative to itself when it sees the landmark).
    fn position(&self, id: u32) -> Option<[f64; 2]>;
    /// Whether `id` is detected from `pos`.
    fn sees(&self, pos: [f64; 2], id: u32) -> bool;
    /// Every landmark detected from `pos`, sorted.
    fn visible(&self, pos: [f64; 2]) -> Vec<u32>;
    /// The sensor range.
    fn range(&self) -> f64;
}

/// Point landmarks detected within a range (no occlusion).
#[derive(Debug, Clone)]
pub struct RangePerception {
    ids: Vec<u32>,
    pos: Vec<[f64; 2]>,
    index: HashMap<u32, usize>,
    range: f64,
}

impl RangePerception {
    /// Landmarks `(id, position)` seen within `range`.
    #[must_use]
    pub fn new(landmarks: &[(u32, [f64; 2])], range: f64) -> Self {
        let mut sorted = landmarks.to_vec();
        sorted.sort_by_key(|l| l.0);
        Self {
            index: sorted.iter().enumerate().map(|(i, l)| (l.0, i)).collect(),
            ids: sorted.iter().map(|l| l.0).collect(),
            pos: sorted.iter().map(|l| l.1).collect(),
            range,
        }
    }
}

fn d(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

impl Perception for RangePerception {
    fn position(&self, id: u32) -> Option<[f64; 2]> {
        self.index.get(&id).map(|&i| self.pos[i])
    }
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.index
            .get(&id)
            .is_some_and(|&i| d(pos, self.pos[i]) <= self.range)
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        self.ids
            .iter()
            .zip(&self.pos)
            .filter(|(_, p)| d(pos, **p) <= self.range)
            .map(|(id, _)| *id)
            .collect()
    }
    fn range(&self) -> f64 {
        self.range
    }
}

/// Landmarks of a sim2d world, detected within range only when fully visible (§4.4.1).
#[derive(Debug)]
pub struct WorldPerception<'w> {
    world: &'w sim2d::World,
    index: HashMap<u32, usize>,
    range: f64,
}

impl<'w> WorldPerception<'w> {
    /// Perception in `world` with `range`.
    #[must_use]
    pub fn new(world: &'w sim2d::World, range: f64) -> Self {
        Self {
            index: world
                .spec()
                .landmarks
                .iter()
                .enumerate()
                .map(|(i, l)| (l.id, i))
                .collect(),
            world,
            range,
        }
    }
}

impl Perception for WorldPerception<'_> {
    fn position(&self, id: u32) -> Option<[f64; 2]> {
        self.index
            .get(&id)
            .map(|&i| self.world.spec().landmarks[i].pos)
    }
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.index.get(&id).is_some_and(|&i| {
            d(pos, self.world.spec().landmarks[i].pos) <= self.range
                && self.world.is_fully_visible(pos, i)
        })
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        let mut out: Vec<u32> = self
            .world
            .spec()
            .landmarks
            .iter()
            .enumerate()
            .filter(|(i, l)| d(pos, l.pos) <= self.range && self.world.is_fully_visible(pos, *i))
            .map(|(_, l)| l.id)
            .collect();
        out.sort_unstable();
        out
    }
    fn range(&self) -> f64 {
        self.range
    }
}

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
            length: 0.0,
            transit_length: 0.0,
            bound: 0.0,
            bound_direct: 0.0,
            trajectory: Vec::new(),
            transitions: Vec::new(),
        }
    }
}

/// Runs navigations against one map and graph.
pub struct Navigator<'a, P: Perception> {
    map: &'a QualitativeMap,
    graph: &'a LinkGraph,
    perception: &'a P,
    config: &'a NavConfig,
}

struct Walker<'p, P: Perception> {
    perception: &'p P,
    pos: [f64; 2],
    length: f64,
    step: f64,
    trajectory: Vec<[f64; 2]>,
    record: bool,
}

impl<P: Perception> Walker<'_, P> {
    /// Follows waypoints, checking `stop` every `step`; true when it stopped.
    fn walk(&mut self, path: &[[f64; 2]], stop: &mut dyn FnMut(&P, [f64; 2]) -> bool) -> bool {
        if stop(self.perception, self.pos) {
            return true;
        }
        for &target in path {
            let seg = d(self.pos, target);
            if seg == 0.0 {
                continue;
            }
            let n = (seg / self.step).ceil().max(1.0) as usize;
            let from = self.pos;
            for k in 1..=n {
                let t = k as f64 / n as f64;
                let p = [
                    from[0] + t * (target[0] - from[0]),
                    from[1] + t * (target[1] - from[1]),
                ];
                self.length += d(self.pos, p);
                self.pos = p;
                if self.record {
                    self.trajectory.push(p);
                }
                if stop(self.perception, p) {
                    return true;
                }
            }
        }
        false
    }
}

impl<'a, P: Perception> Navigator<'a, P> {
    /// A navigator.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for a non-positive step or range.
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
        let range = self.perception.range();
        let mut w = Walker {
            perception: self.perception,
            pos: start,
            length: 0.0,
            step: self.config.step,
            trajectory: vec![start],
            record,
        };
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
                if self.config.find_goal && !self.perception.sees(w.pos, goal) {
                    let mut commands = Vec::new();
                    if !self.search_link(&mut w, e, goal, &mut commands)? {
                        // a contingency like a failed transition: plan to another element
                        // holding the goal, never back into this one
                        if !self.config.replan || out.replans >= self.config.max_replans {
                            out.failure = Some(Failure::InsufficientFeatures);
                            break;
                        }
                        out.replans += 1;
                        failed_goals.insert(e);
                        for src in self.graph.graph().neighbors_directed(
                            petgraph::graph::NodeIndex::new(e),
                            petgraph::Direction::Incoming,
                        ) {
                            excluded.insert((src.index(), e));
                        }
                        match self.localise(&mut w, range) {
                            Some(s) => starts = s,
                            None => {
                                out.failure = Some(Failure::InsufficientFeatures);
                                break;
                            }
                        }
                        first = false;
                        continue;
                    }
                }
                out.success = true;
                break;
            }
            if starts.is_empty() {
                out.failure = Some(Failure::InsufficientFeatures);
                break;
            }
            let plan: Result<Plan> = match (first, field) {
                (true, Some(f)) => f.path_from(self.graph, &starts),
                _ => self.graph.plan(self.map, &starts, goal, &excluded),
            };
            let plan = match plan {
                Ok(p) => p,
                Err(QlinkError::NoPath { .. }) => {
                    out.failure = Some(if first {
                        Failure::NoPath
                    } else {
                        Failure::InsufficientFeatures
                    });
                    break;
                }
                Err(e) => return Err(e),
            };
            if first {
                out.plan_len = plan.len();
                out.bound =
                    (2.0 * std::f64::consts::PI + 1.0) * self.config.map_range * plan.len() as f64;
                out.bound_direct = self.config.map_range * plan.len() as f64;
                first = false;
            }
            let mut failed = None;
            for pair in plan.elements.windows(2) {
                let rec = self.transition(&mut w, pair[0], pair[1])?;
                let ok = rec.success;
                out.transitions.push(rec);
                if !ok {
                    failed = Some((pair[0], pair[1]));
                    break;
                }
            }
            match failed {
                None => {
                    // the plan's last element holds the goal: the check above ends the run
                    let last = plan.elements.last().copied();
                    starts = self.map.elements_in_view(&self.perception.visible(w.pos));
                    starts.extend(last);
                    starts.sort_unstable();
                    starts.dedup();
                }
                Some(edge) => {
                    if !self.config.replan || out.replans >= self.config.max_replans {
                        out.failure = Some(Failure::InsufficientFeatures);
                        break;
                    }
                    out.replans += 1;
                    excluded.insert(edge);
                    match self.localise(&mut w, range) {
                        Some(s) => starts = s,
                        None => {
                            out.failure = Some(Failure::InsufficientFeatures);
                            break;
                        }
                    }
                }
            }
        }
        Ok(self.finish(out, w))
    }

    fn finish(&self, mut out: NavOutcome, w: Walker<'_, P>) -> NavOutcome {
        out.length = w.length;
        out.transit_length = out.transitions.iter().map(|t| t.length).sum();
        out.trajectory = w.trajectory;
        out
    }

    /// Elements in view; if none, circle the nearest visible landmark at sensor range.
    fn localise(&self, w: &mut Walker<'_, P>, range: f64) -> Option<Vec<usize>> {
        let visible = self.perception.visible(w.pos);
        let starts = self.map.elements_in_view(&visible);
        // The direct controller starts from an element of the landmark the robot stands at
        // (Proposition 3's x_t = L_n): from there every landmark of the element is in view.
        if self.config.controller.kind == crate::controller::ControllerKind::Direct
            && let Some(&here) = visible.iter().find(|&&id| {
                self.perception
                    .position(id)
                    .is_some_and(|p| d(p, w.pos) <= 1.0)
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
        let pos = w.pos;
        let anchor = visible
            .iter()
            .filter_map(|&id| self.perception.position(id).map(|p| (id, p)))
            .min_by(|a, b| d(a.1, pos).total_cmp(&d(b.1, pos)))?;
        let path = circle(anchor.1, range * SEARCH_RADIUS, pos, 2.0);
        let map = self.map;
        let found = w.walk(&path, &mut |p: &P, x| {
            !map.elements_in_view(&p.visible(x)).is_empty()
        });
        if found {
            Some(self.map.elements_in_view(&self.perception.visible(w.pos)))
        } else {
            None
        }
    }

    /// Whether two landmarks of element `j` are seen from `x`.
    fn in_frame(p: &P, map: &QualitativeMap, j: usize, x: [f64; 2]) -> bool {
        map.elements()[j]
            .landmarks
            .iter()
            .filter(|&&l| p.sees(x, l))
            .count()
            >= 2
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
        let range = self.perception.range();
        let others: Vec<u32> = map.elements()[i]
            .landmarks
            .iter()
            .copied()
            .filter(|&l| l != link)
            .collect();
        let refs: Option<([f64; 2], [f64; 2], [u32; 2])> = match others.as_slice() {
            [a, b] => match (self.perception.position(*a), self.perception.position(*b)) {
                (Some(pa), Some(pb)) => Some((pa, pb, [*a, *b])),
                _ => None,
            },
            _ => None,
        };
        let Some((pa, pb, [a, b])) = refs else {
            return Ok(false);
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
            let r = robot_state(calculus, pa, pb, w.pos)?;
            let dec = pomdp.decide_with(r, &belief, pomdp.horizon - step)?;
            commands.push(dec.action);
            let path = self
                .config
                .controller
                .path(calculus, pa, pb, dec.action, w.pos)?;
            let stop = &mut |p: &P, x: [f64; 2]| p.sees(x, link);
            if w.walk(&path[1..], stop) {
                return Ok(true);
            }
            belief = pomdp.update_not_seen(&belief, dec.action);
        }
        // fallback: a full circle about the references' midpoint at sensor range
        let m = [(pa[0] + pb[0]) / 2.0, (pa[1] + pb[1]) / 2.0];
        let path = circle(m, range * SEARCH_RADIUS, w.pos, 2.0);
        Ok(w.walk(&path[1..], &mut |p: &P, x| p.sees(x, link)))
    }

    fn transition(&self, w: &mut Walker<'_, P>, i: usize, j: usize) -> Result<TransitionRecord> {
        let start_len = w.length;
        let map = self.map;
        let links = self
            .graph
            .edge(i, j)
            .map(|e| e.links().to_vec())
            .unwrap_or_default();
        // with β ≥ 2 the link set has several landmarks: search for one the robot does not
        // see yet (a visible one is no progress towards M_j's frame)
        let link = links
            .iter()
            .copied()
            .find(|&l| !self.perception.sees(w.pos, l))
            .or(links.first().copied())
            .unwrap_or(map.elements()[j].landmarks[0]);
        let mut rec = TransitionRecord {
            from: i,
            to: j,
            link,
            commands: Vec::new(),
            success: false,
            length: 0.0,
        };
        let range = self.perception.range();
        let done = |w: &mut Walker<'_, P>, rec: &mut TransitionRecord| {
            rec.success = true;
            rec.length = w.length - start_len;
        };
        // the direct controller (Proposition 4): a visible link is driven to in a straight
        // line; at a landmark of M_j all of M_j is in view when Assumption 3 holds
        if self.config.controller.kind == crate::controller::ControllerKind::Direct
            && self.perception.sees(w.pos, link)
            && let Some(pl) = self.perception.position(link)
        {
            // all the way to the link (not just until M_j is in view), so the next
            // transition starts at a landmark again (Proposition 3)
            rec.commands.push(usize::MAX);
            w.walk(&[pl], &mut |_: &P, _| false);
            if Self::in_frame(self.perception, map, j, w.pos) {
                done(w, &mut rec);
                return Ok(rec);
            }
        }
        if Self::in_frame(self.perception, map, j, w.pos) {
            done(w, &mut rec);
            return Ok(rec);
        }
        // phase 1: find the link in M_i's frame
        if !self.perception.sees(w.pos, link) && !self.search_link(w, i, link, &mut rec.commands)? {
            rec.length = w.length - start_len;
            return Ok(rec);
        }
        // phase 2: two landmarks of M_j at once
        if Self::in_frame(self.perception, map, j, w.pos) {
            done(w, &mut rec);
            return Ok(rec);
        }
        let Some(pl) = self.perception.position(link) else {
            rec.length = w.length - start_len;
            return Ok(rec);
        };
        let path = circle(pl, range * SEARCH_RADIUS, w.pos, 2.0);
        let ok = w.walk(&path[1..], &mut |p: &P, x| Self::in_frame(p, map, j, x));
        if ok {
            done(w, &mut rec);
        } else {
            rec.length = w.length - start_len;
        }
        Ok(rec)
    }
}
