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
//! distance driven since it was last seen, and vanishes when it is seen again. The robot
//! drives its waypoints exactly; the drift lives in where it believes the references are,
//! which is where it decides and plans its arcs.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};
use crate::perception::{Perception, distance as d};

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

/// The last sighting of a landmark: its measured position and where the robot was.
#[derive(Debug, Clone, Copy)]
struct Sighting {
    at: [f64; 2],
    from: [f64; 2],
}

/// The robot as it drives: position, distance, trajectory, and what it remembers of the
/// landmarks it watches.
pub(crate) struct Walker<'p, P: Perception> {
    pub(crate) perception: &'p P,
    pub(crate) pos: [f64; 2],
    pub(crate) length: f64,
    pub(crate) trajectory: Vec<[f64; 2]>,
    /// Index ranges of `trajectory` spent searching (see `NavOutcome::searches`).
    pub(crate) searches: Vec<[usize; 2]>,
    step: f64,
    sensing: Sensing,
    pub(crate) record: bool,
    watched: Vec<u32>,
    memory: HashMap<u32, Sighting>,
}

impl<'p, P: Perception> Walker<'p, P> {
    pub(crate) fn new(
        perception: &'p P,
        start: [f64; 2],
        step: f64,
        sensing: Sensing,
        record: bool,
    ) -> Self {
        Self {
            perception,
            pos: start,
            length: 0.0,
            trajectory: vec![start],
            searches: Vec::new(),
            step,
            sensing,
            record,
            watched: Vec::new(),
            memory: HashMap::new(),
        }
    }

    /// Remember `ids` whenever they are sensed from now on (and now).
    pub(crate) fn watch(&mut self, ids: &[u32]) {
        self.watched = ids.to_vec();
        self.sense_watched(self.pos);
    }

    fn sense_watched(&mut self, x: [f64; 2]) {
        for &id in &self.watched {
            if self.perception.sees(x, id)
                && let Some(at) = self.perception.position(id)
            {
                self.memory.insert(id, Sighting { at, from: x });
            }
        }
    }

    /// Where the robot places landmark `id` now, per `references`: measured if seen, else
    /// remembered and carried forward; `None` when it has no measurement to go on.
    pub(crate) fn place(&mut self, id: u32, references: References) -> Option<[f64; 2]> {
        match references {
            References::Oracle => self.perception.position(id),
            References::Perceived(odometry) => {
                if self.perception.sees(self.pos, id)
                    && let Some(at) = self.perception.position(id)
                {
                    self.memory.insert(id, Sighting { at, from: self.pos });
                    return Some(at);
                }
                self.memory
                    .get(&id)
                    .map(|s| odometry.carry(s.at, s.from, self.pos))
            }
        }
    }

    /// Follows waypoints, sensing where the schedule says and asking `stop` there; true when
    /// it stopped. The robot always senses where it stands before it moves.
    pub(crate) fn walk(
        &mut self,
        path: &[[f64; 2]],
        leg: Leg,
        stop: &mut dyn FnMut(&P, [f64; 2]) -> bool,
    ) -> bool {
        if stop(self.perception, self.pos) {
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
        let last = path.len().saturating_sub(1);
        for (i, &target) in path.iter().enumerate() {
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
                let senses = match every {
                    None => true,
                    Some(e) => k == n && (i == last || (e != usize::MAX && i % e == 0)),
                };
                if senses {
                    self.sense_watched(p);
                    if stop(self.perception, p) {
                        return true;
                    }
                }
            }
        }
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
