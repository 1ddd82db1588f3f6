//! How the robot drives, senses and remembers while it executes a plan — the choices that
//! decide whether a navigation study can fail.
//!
//! The thesis's robot (§4.3–4.4) knows only what it perceives: it plans an arc in the frame of
//! reference landmarks it sees, a transition into `M_j` is complete when `M_j`'s reference
//! landmarks are seen (`L_j^ref ⊆ L^vis_t`), and it drives arcs and circles of the mapping
//! robot's radius R. Each choice below has the thesis's behaviour as its default and an
//! *idealised* alternative, kept for comparison and labelled as such in the reports:
//!
//! | choice | thesis (default) | idealised |
//! |---|---|---|
//! | [`References`] — where an unseen reference is | where it was last seen, carried forward by the robot's odometry with its drift ([`Odometry`]) | [`References::Oracle`]: its true position |
//! | [`Arrival`] — when a transition is complete | the two landmarks of `M_j` that frame what comes next are seen at once | [`Arrival::AnyTwo`]: any two of `M_j` |
//! | [`Sensing`] — where the robot looks | every `step` metres ([`Sensing::Continuous`]) | — ([`Sensing::AtStops`] is the *sparser* schedule: arc ends and circle stops) |
//!
//! The odometry model is a systematic one: the robot's dead-reckoned displacement is its true
//! displacement scaled by `1 + scale_error` and rotated by `heading_error`. A landmark last
//! seen at `p_L` from `p_then` is believed, from `p_now`, to be at
//! `p_L + Δ − (1 + s)·Rot(θ)·Δ` with `Δ = p_now − p_then`: its error grows linearly with the
//! distance driven since it was last seen, and vanishes when it is seen again.
//!
//! What the robot's detector and wheels get wrong besides is its [`crate::Robot`]: noisy,
//! missed (and optionally false) detections, and random motion error its odometry does not
//! see. The walker below keeps both where the robot is and where it believes it is; every
//! decision is made in the believed frame from what was detected. A path is planned around
//! anchor landmarks (a frame's references, a circled landmark), and a robot whose wheels
//! err moves the rest of its path with them whenever it senses them — a steady-state Kalman
//! filter of its drift, so that noisy detections do not jerk it about. It looks three times
//! where it stands before it localises (one look misses a landmark in five at MRCLAM's
//! rate), and circles a landmark it must keep in view inside its range by
//! [`crate::Robot::margin`]. The exact robot ([`crate::Robot::EXACT`]) does none of this and
//! drives as the navigator did before the robot could err, bit for bit
//! (`tests/erring_robot.rs`).

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};
use crate::perception::{Look, Perception, distance as d};
use crate::robot::Robot;

/// Systematic odometry error.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Odometry {
    /// Relative error of the distance driven (0.02: 2 m per 100 m).
    pub scale_error: f64,
    /// Heading error of the dead-reckoned displacement (rad).
    pub heading_error: f64,
}

impl Odometry {
    /// Wheel odometry of a small ground robot: 2 % in distance, 1° in heading.
    pub const WHEELED: Self = Self {
        scale_error: 0.02,
        heading_error: std::f64::consts::PI / 180.0,
    };

    /// No drift: a remembered position stays exact.
    pub const PERFECT: Self = Self {
        scale_error: 0.0,
        heading_error: 0.0,
    };

    /// Where a landmark seen at `landmark` from `then` is believed to be from `now`.
    #[must_use]
    pub fn carry(&self, landmark: [f64; 2], then: [f64; 2], now: [f64; 2]) -> [f64; 2] {
        let delta = [now[0] - then[0], now[1] - then[1]];
        let (s, c) = self.heading_error.sin_cos();
        let k = 1.0 + self.scale_error;
        // p_L + (I − k·Rot(θ))·Δ, written so that no drift adds exactly zero
        [
            landmark[0] + (1.0 - k * c) * delta[0] + k * s * delta[1],
            landmark[1] - k * s * delta[0] + (1.0 - k * c) * delta[1],
        ]
    }

    fn check(&self) -> Result<()> {
        if !(self.scale_error.is_finite()
            && self.heading_error.is_finite()
            && self.scale_error > -1.0)
        {
            return Err(QlinkError::InvalidParameter(format!(
                "odometry scale error {} must be finite and > -1, heading error {} finite",
                self.scale_error, self.heading_error
            )));
        }
        Ok(())
    }
}

/// Where the robot takes the positions of the references it plans in.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum References {
    /// Measured when seen now; otherwise the last measurement carried forward by odometry
    /// (a reference never seen cannot be planned in: the search fails).
    Perceived(Odometry),
    /// Idealised: the true position, seen or not.
    Oracle,
}

impl Default for References {
    fn default() -> Self {
        Self::Perceived(Odometry::WHEELED)
    }
}

/// When a transition `M_i → M_j` is complete.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Arrival {
    /// `L_j^ref ⊆ L^vis_t` (§4.4.1): the two landmarks of `M_j` that frame what comes next —
    /// the next link's search, or the goal on the plan's last element — are seen at once.
    #[default]
    References,
    /// Idealised: any two landmarks of `M_j` seen at once.
    AnyTwo,
}

/// Where along its paths the robot senses.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Sensing {
    /// Every `step` metres (the navigation's `step`), wherever it drives.
    #[default]
    Continuous,
    /// Only where it stops: at the end of each command's path, and every `degrees` of a
    /// search circle.
    AtStops {
        /// Angle between stops on a circle (deg).
        degrees: f64,
    },
}

impl Sensing {
    /// Checks the schedule.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for stops at a non-positive or non-finite angle.
    pub fn check(&self) -> Result<()> {
        match *self {
            Self::AtStops { degrees } if !(degrees.is_finite() && degrees > 0.0) => {
                Err(QlinkError::InvalidParameter(format!(
                    "sensing stops every {degrees}° must be a positive angle"
                )))
            }
            _ => Ok(()),
        }
    }
}

impl References {
    /// Checks the odometry's errors.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] for a negative or non-finite error.
    pub fn check(&self) -> Result<()> {
        match self {
            Self::Perceived(o) => o.check(),
            Self::Oracle => Ok(()),
        }
    }
}

/// The idealised options among `references` and `arrival`, described (empty: the thesis's
/// robot).
#[must_use]
pub fn idealised(references: References, arrival: Arrival) -> Vec<&'static str> {
    let mut out = Vec::new();
    if references == References::Oracle {
        out.push("unseen references at their true positions");
    }
    if arrival == Arrival::AnyTwo {
        out.push("any two landmarks of the next element complete a transition");
    }
    out
}

/// What a path is, for the sensing schedule.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Leg {
    /// A controller's path for one command (or a straight drive).
    Command,
    /// A search circle from [`crate::circle`] with waypoints every `step_deg` degrees.
    Circle { step_deg: f64 },
}

/// The last sighting of a landmark: where it was measured and where the robot believed it
/// was then (both in the robot's believed frame).
#[derive(Debug, Clone, Copy)]
struct Sighting {
    at: [f64; 2],
    from: [f64; 2],
}

/// The robot as it drives: where it is and where it believes it is, distance, trajectory,
/// what it detects from here and what it remembers of the landmarks it watches.
///
/// Positions the navigator works with — detections, remembered landmarks, waypoints — are in
/// the robot's *believed* frame ([`Walker::here`] is its origin's position in it); the
/// trajectory and length are what the robot truly drove. For a robot with exact motion the
/// two frames are one and no conversion is made (so the exact robot's numbers are the
/// navigator's before it could err, bit for bit).
pub(crate) struct Walker<'p, P: Perception> {
    pub(crate) perception: &'p P,
    /// Where the robot truly is.
    pos: [f64; 2],
    /// Where its odometry says it is.
    odo: [f64; 2],
    /// The rotation from the believed frame's directions to the world's (rad).
    heading: f64,
    pub(crate) length: f64,
    pub(crate) trajectory: Vec<[f64; 2]>,
    /// Index ranges of `trajectory` spent searching (see `NavOutcome::searches`).
    pub(crate) searches: Vec<[usize; 2]>,
    step: f64,
    sensing: Sensing,
    pub(crate) record: bool,
    watched: Vec<u32>,
    memory: HashMap<u32, Sighting>,
    robot: Robot,
    /// This run's key for the robot's draws.
    run: u64,
    /// Scans made (a scan is one place sensed from), steps driven.
    scans: u64,
    steps: u64,
    /// Moved since the last scan: the next question is a new scan.
    moved: bool,
    /// This scan's answers: id and the detected position, if any.
    scan: HashMap<u32, Option<[f64; 2]>>,
    /// Which way the sensor looks: a sweep where the robot stands (at the start and at the
    /// end of each path), ahead along its true heading while it drives.
    look: Look,
}

impl<'p, P: Perception> Walker<'p, P> {
    pub(crate) fn new(
        perception: &'p P,
        start: [f64; 2],
        step: f64,
        sensing: Sensing,
        record: bool,
        robot: Robot,
        run: u64,
    ) -> Self {
        Self {
            perception,
            pos: start,
            odo: start,
            heading: 0.0,
            length: 0.0,
            trajectory: vec![start],
            searches: Vec::new(),
            step,
            sensing,
            record,
            watched: Vec::new(),
            memory: HashMap::new(),
            robot,
            run,
            scans: 0,
            steps: 0,
            moved: false,
            scan: HashMap::new(),
            look: Look::Sweep,
        }
    }

    /// Where the robot believes it is: the origin of every position it works with.
    pub(crate) fn here(&self) -> [f64; 2] {
        self.odo
    }

    /// Where the robot truly is (for reports, never for decisions).
    pub(crate) fn truly(&self) -> [f64; 2] {
        self.pos
    }

    /// A world point in the believed frame (the identity for exact motion).
    fn believed(&self, p: [f64; 2]) -> [f64; 2] {
        if self.robot.motion.is_exact() {
            return p;
        }
        let (s, c) = self.heading.sin_cos();
        let v = [p[0] - self.pos[0], p[1] - self.pos[1]];
        [
            self.odo[0] + c * v[0] + s * v[1],
            self.odo[1] - s * v[0] + c * v[1],
        ]
    }

    /// Starts a new scan if the robot moved since the last question.
    fn fresh_scan(&mut self) {
        if self.moved {
            self.moved = false;
            self.scans += 1;
            self.scan.clear();
        }
    }

    /// What the detector reports for `id` from here: its measured position (believed
    /// frame), or `None`.
    pub(crate) fn detect(&mut self, id: u32) -> Option<[f64; 2]> {
        self.fresh_scan();
        if let Some(&at) = self.scan.get(&id) {
            return at;
        }
        let truly = self.perception.sees_looking(self.pos, self.look, id);
        let at = self.report(id, truly);
        self.scan.insert(id, at);
        at
    }

    /// The detector's report on `id`, which it truly detects or not (believed frame).
    fn report(&self, id: u32, truly: bool) -> Option<[f64; 2]> {
        self.robot
            .report(self.perception, self.pos, id, truly, [self.run, self.scans])
            .map(|p| self.believed(p))
    }

    /// Whether `id` is reported from here.
    pub(crate) fn sees(&mut self, id: u32) -> bool {
        self.detect(id).is_some()
    }

    /// Takes another look from where the robot stands: a new scan, whose misses and noise are
    /// drawn afresh (a detector's next frame).
    pub(crate) fn look(&mut self) {
        self.moved = true;
        self.fresh_scan();
    }

    /// Every landmark reported from here on any of `looks` scans (the current one and
    /// `looks − 1` more), sorted: what a robot standing still for a moment sees. It
    /// remembers where it saw each (so a landmark missed on the last look is still placed).
    pub(crate) fn visible_over(&mut self, looks: usize) -> Vec<u32> {
        let mut out = self.visible();
        if self.robot.detection.is_exact() {
            return out;
        }
        for k in 0..looks {
            if k > 0 {
                self.look();
                out.extend(self.visible());
            }
            for (&id, at) in &self.scan {
                if let Some(at) = *at {
                    self.memory.insert(id, Sighting { at, from: self.odo });
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Every landmark reported from here, sorted.
    pub(crate) fn visible(&mut self) -> Vec<u32> {
        let truly = self.perception.visible_looking(self.pos, self.look);
        if self.robot.detection.is_exact() {
            return truly;
        }
        self.fresh_scan();
        let candidates = if self.robot.detection.false_rate > 0.0 {
            self.perception.ids()
        } else {
            truly.clone()
        };
        let mut out = Vec::new();
        for id in candidates {
            let at = match self.scan.get(&id) {
                Some(&at) => at,
                None => {
                    let at = self.report(id, truly.binary_search(&id).is_ok());
                    self.scan.insert(id, at);
                    at
                }
            };
            if at.is_some() {
                out.push(id);
            }
        }
        out.sort_unstable();
        out
    }

    /// Remember `ids` whenever they are sensed from now on (and now).
    pub(crate) fn watch(&mut self, ids: &[u32]) {
        self.watched = ids.to_vec();
        self.sense_watched();
    }

    fn sense_watched(&mut self) {
        for i in 0..self.watched.len() {
            let id = self.watched[i];
            if let Some(at) = self.detect(id) {
                self.memory.insert(id, Sighting { at, from: self.odo });
            }
        }
    }

    /// Where the robot places landmark `id` now, per `references`: measured if seen, else
    /// remembered and carried forward; `None` when it has no measurement to go on.
    pub(crate) fn place(&mut self, id: u32, references: References) -> Option<[f64; 2]> {
        match references {
            References::Oracle => self.perception.position(id).map(|p| self.believed(p)),
            References::Perceived(odometry) => {
                if let Some(at) = self.detect(id) {
                    self.memory.insert(id, Sighting { at, from: self.odo });
                    return Some(at);
                }
                self.memory
                    .get(&id)
                    .map(|s| odometry.carry(s.at, s.from, self.odo))
            }
        }
    }

    /// One step towards `p` (believed frame): exactly there, or as the wheels take it.
    fn drive(&mut self, p: [f64; 2]) {
        self.moved = true;
        if self.robot.motion.is_exact() {
            self.length += d(self.pos, p);
            self.face(p[0] - self.pos[0], p[1] - self.pos[1]);
            self.pos = p;
            self.odo = p;
            return;
        }
        let delta = [p[0] - self.odo[0], p[1] - self.odo[1]];
        self.odo = p;
        if delta == [0.0, 0.0] {
            return;
        }
        self.steps += 1;
        let done = self.robot.step(delta, self.heading, [self.run, self.steps]);
        self.heading = done.heading;
        self.face(done.moved[0], done.moved[1]);
        self.pos = [self.pos[0] + done.moved[0], self.pos[1] + done.moved[1]];
        self.length += done.length;
    }

    /// The sensor looks ahead along a true step (`dx`, `dy`); a null step leaves it as it was.
    fn face(&mut self, dx: f64, dy: f64) {
        if dx != 0.0 || dy != 0.0 {
            self.look = Look::Ahead(dy.atan2(dx));
        }
    }

    /// Moves the plan's `frame` towards where the `anchor` landmarks (ids and where the path
    /// was planned with them) are detected now; unchanged when none is.
    fn reanchor(&mut self, anchor: &[(u32, [f64; 2])], frame: &mut Frame) {
        let seen: Vec<([f64; 2], [f64; 2])> = anchor
            .iter()
            .filter_map(|&(id, planned)| self.detect(id).map(|now| (planned, now)))
            .collect();
        let sigma = self.robot.detection.sigma;
        let m = self.robot.motion;
        let lever = seen
            .iter()
            .map(|(_, q)| d(*q, self.odo))
            .fold(0.0, f64::max);
        // per step: the drift's variance (heading turns the frame about the robot, moving an
        // anchor `lever` metres away), and one measurement's
        let drift = (m.distance_sigma.powi(2) + (m.heading_sigma * lever).powi(2)) * self.step;
        match seen.as_slice() {
            [] => {}
            [(p, q)] => frame.observe_shift(*p, *q, gain(drift, sigma * sigma)),
            [(p0, q0), (p1, q1), ..] => {
                let span = d(*p0, *p1).max(1e-9);
                let turn = angle(*q0, *q1) - angle(*p0, *p1);
                let turn_drift = m.heading_sigma.powi(2) * self.step;
                frame.observe_turn(turn, gain(turn_drift, 2.0 * sigma * sigma / (span * span)));
                let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
                frame.observe_shift(
                    mid(*p0, *p1),
                    mid(*q0, *q1),
                    gain(drift, sigma * sigma / 2.0),
                );
            }
        }
    }

    /// Follows waypoints (believed frame), sensing where the schedule says and asking `stop`
    /// there; true when it stopped. The robot always senses where it stands before it moves.
    ///
    /// The waypoints were planned around the `anchor` landmarks (ids and the positions the
    /// plan used). A robot whose wheels err drifts from its believed frame as it drives, so
    /// wherever it senses one of them it moves the rest of the path with them — it servos
    /// on what it sees, as the thesis's robot plans in "the frame it perceives". A robot that
    /// drives exactly has nothing to correct and follows the plan as given.
    pub(crate) fn walk(
        &mut self,
        path: &[[f64; 2]],
        leg: Leg,
        anchor: &[(u32, [f64; 2])],
        stop: &mut dyn FnMut(&mut Self) -> bool,
    ) -> bool {
        if stop(self) {
            return true;
        }
        // waypoint indices (into `path`) after which the robot senses, for the sparse schedule
        let every = match (self.sensing, leg) {
            (Sensing::AtStops { degrees }, Leg::Circle { step_deg }) => {
                Some((degrees / step_deg.max(1e-9)).round().max(1.0) as usize)
            }
            (Sensing::AtStops { .. }, Leg::Command) => Some(usize::MAX),
            (Sensing::Continuous, _) => None,
        };
        let servo = !self.robot.motion.is_exact() && !anchor.is_empty();
        let mut frame = Frame::about(anchor.first().map_or([0.0, 0.0], |a| a.1));
        let last = path.len().saturating_sub(1);
        for (i, &planned) in path.iter().enumerate() {
            let mut target = frame.apply(planned);
            let seg = d(self.odo, target);
            if seg == 0.0 {
                continue;
            }
            let n = (seg / self.step).ceil().max(1.0) as usize;
            let from = self.odo;
            for k in 1..=n {
                let p = if servo {
                    // the rest of the way to a target that may have moved, in equal steps
                    let left = (n - k + 1) as f64;
                    [
                        self.odo[0] + (target[0] - self.odo[0]) / left,
                        self.odo[1] + (target[1] - self.odo[1]) / left,
                    ]
                } else {
                    let t = k as f64 / n as f64;
                    [
                        from[0] + t * (target[0] - from[0]),
                        from[1] + t * (target[1] - from[1]),
                    ]
                };
                self.drive(p);
                if self.record {
                    self.trajectory.push(self.pos);
                }
                let senses = match every {
                    None => true,
                    Some(e) => k == n && (i == last || (e != usize::MAX && i % e == 0)),
                };
                if senses {
                    // the end of a path (or a stop of the sparse schedule): the robot stands
                    // and sweeps its sensor
                    if k == n && (i == last || every.is_some()) {
                        self.look = Look::Sweep;
                    }
                    self.sense_watched();
                    if servo {
                        self.reanchor(anchor, &mut frame);
                        target = frame.apply(planned);
                    }
                    if stop(self) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

/// How a path's frame moved since it was planned, as the robot estimates it: turned by
/// `turn` (rad) about `pivot`, then shifted by `shift`. Each sighting of an anchor moves the
/// estimate part of the way ([`gain`]): a steady-state Kalman filter of a random walk (the
/// drift) seen through noisy detections, so a robot with exact detections follows each
/// sighting and one with noisy ones does not jerk its path about by their noise.
#[derive(Debug, Clone, Copy)]
struct Frame {
    pivot: [f64; 2],
    turn: f64,
    shift: [f64; 2],
}

impl Frame {
    fn about(pivot: [f64; 2]) -> Self {
        Self {
            pivot,
            turn: 0.0,
            shift: [0.0, 0.0],
        }
    }

    fn apply(&self, p: [f64; 2]) -> [f64; 2] {
        if self.turn == 0.0 && self.shift == [0.0, 0.0] {
            return p;
        }
        let (s, c) = self.turn.sin_cos();
        let v = [p[0] - self.pivot[0], p[1] - self.pivot[1]];
        [
            self.pivot[0] + c * v[0] - s * v[1] + self.shift[0],
            self.pivot[1] + s * v[0] + c * v[1] + self.shift[1],
        ]
    }

    /// Planned point `p` seen at `q`: the shift that would put it there, weighted by `k`.
    fn observe_shift(&mut self, p: [f64; 2], q: [f64; 2], k: f64) {
        let now = self.apply(p);
        self.shift[0] += k * (q[0] - now[0]);
        self.shift[1] += k * (q[1] - now[1]);
    }

    /// A measured turn of the frame, weighted by `k`.
    fn observe_turn(&mut self, turn: f64, k: f64) {
        let err = (turn - self.turn + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
            - std::f64::consts::PI;
        self.turn += k * err;
    }
}

/// The steady-state gain of a Kalman filter tracking a random walk of variance `q` per step
/// through measurements of variance `r`: 1 for exact measurements.
fn gain(q: f64, r: f64) -> f64 {
    if r <= 0.0 {
        return 1.0;
    }
    // the prior variance P solves P = (P_post) + q with P_post = P·r/(P + r)
    let p = (q + (q * q + 4.0 * q * r).sqrt()) / 2.0;
    p / (p + r)
}

/// The direction from `a` to `b` (rad).
fn angle(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[1] - a[1]).atan2(b[0] - a[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_frame_filter_follows_exact_sightings_and_averages_noisy_ones() {
        assert_eq!(gain(0.1, 0.0), 1.0);
        // q = r: the golden ratio's conjugate
        assert!((gain(0.5, 0.5) - 0.618_033_988_749_895).abs() < 1e-12);
        // little drift against noisy sightings: a small step towards each
        let k = gain(1e-4, 0.09);
        assert!(k > 0.0 && k < 0.05, "{k}");
        // a frame that turned by 0.1 rad about the pivot and shifted by (1, 0)
        let mut f = Frame::about([0.0, 0.0]);
        f.observe_turn(0.1, 1.0);
        f.observe_shift(
            [10.0, 0.0],
            [11.0 + 10.0 * 0.1f64.cos() - 10.0, 10.0 * 0.1f64.sin()],
            1.0,
        );
        let q = f.apply([10.0, 0.0]);
        assert!((q[0] - (1.0 + 10.0 * 0.1f64.cos())).abs() < 1e-12);
        assert!((q[1] - 10.0 * 0.1f64.sin()).abs() < 1e-12);
        // a turn across ±π is taken the short way
        let mut f = Frame::about([0.0, 0.0]);
        f.observe_turn(std::f64::consts::TAU - 0.1, 1.0);
        assert!((f.turn + 0.1).abs() < 1e-12);
    }

    #[test]
    fn perfect_odometry_carries_a_landmark_unchanged() {
        let p = Odometry::PERFECT.carry([3.0, 4.0], [0.0, 0.0], [10.0, -2.0]);
        assert!((p[0] - 3.0).abs() < 1e-12 && (p[1] - 4.0).abs() < 1e-12);
    }

    #[test]
    fn drift_grows_with_the_distance_driven_since_the_sighting() {
        let o = Odometry::WHEELED;
        let err = |dist: f64| {
            let p = o.carry([0.0, 5.0], [0.0, 0.0], [dist, 0.0]);
            d(p, [0.0, 5.0])
        };
        let bound = (o.scale_error.abs() + o.heading_error.abs()) * 1.01;
        assert!(err(0.0) < 1e-12);
        assert!((err(20.0) - 2.0 * err(10.0)).abs() < 1e-9);
        assert!(err(10.0) > 0.1 && err(10.0) <= 10.0 * bound);
    }
}
