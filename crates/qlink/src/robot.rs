//! The robot that errs, in one place: what its detector reports ([`DetectionNoise`]) and
//! what its wheels do with a command ([`MotionNoise`]), together a [`Robot`].
//!
//! The thesis's navigator "seamlessly incorporates uncertainty from the map, controls and
//! perception" (§4.3); its robots mapped with measurement noise N(0, 0.3) (the §4.4.1
//! simulation) and N(0, 0.7) (the §4.4.2 field site, "lidar and sensor processing"), and
//! their failures came from what they did not see. So the navigating robot here:
//!
//! - **detects** a landmark its [`crate::Perception`] says is detectable with probability
//!   `1 − miss_rate`, at its true position plus isotropic Gaussian noise of σ
//!   ([`DetectionNoise::sigma`], metres, the thesis's N(0, σ)); and reports a landmark it
//!   does not detect, with probability `false_rate`, at a point drawn uniformly in its sensor
//!   disc (a wrong data association: another feature taken for that landmark);
//! - **drives** its commands with random errors: each step's heading turns by
//!   N(0, `heading_sigma`·√d) and its length by N(0, `distance_sigma`·√d) for a step of d
//!   metres, so both grow as a random walk with the distance driven. The robot does not know:
//!   its odometry integrates what it commanded, so where it believes it is drifts from where
//!   it is, and every position it measures or remembers lives in that believed frame. What
//!   it sees again re-anchors it (a detection is relative to where it truly is).
//!
//! [`Robot::EXACT`] is the idealised robot (true positions, waypoints driven exactly) — the
//! navigator before this module existed, reproduced bit for bit.
//!
//! ```
//! use qlink::{RangePerception, Robot};
//! let robot = Robot::erring(0.3).with_seed(7); // the §4.4.1 robot
//! robot.check()?;
//! let sensor = RangePerception::new(&[(1, [3.0, 4.0])], 10.0);
//! // landmark 1 from the origin on scan 5 of run 0: noisy or missed, the same every time
//! let seen = robot.report(&sensor, [0.0, 0.0], 1, true, [0, 5]);
//! assert_eq!(seen, robot.report(&sensor, [0.0, 0.0], 1, true, [0, 5]));
//! assert_eq!(Robot::EXACT.report(&sensor, [0.0, 0.0], 1, true, [0, 5]), Some([3.0, 4.0]));
//! println!("{robot}"); // "errs: detections with N(0, 0.3 m) error, 19 % missed, …"
//! # Ok::<(), qlink::QlinkError>(())
//! ```
//!
//! ## Randomness
//! Every draw is keyed by (seed, run, scan, landmark, what), not taken from a stream, so the
//! answer to "is landmark 7 seen on scan 12 of this run" does not depend on which questions
//! the navigator asked before, on the thread that runs it, or on the order runs are made in.
//! A run's key is derived from its start and goal ([`crate::Navigator::navigate`]); a scan is
//! one place the robot senses from (questions asked again from the same place get the same
//! answers).

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};
use crate::perception::Perception;

/// What the detector gets wrong.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DetectionNoise {
    /// σ of the isotropic Gaussian error of a detected landmark's position (m).
    pub sigma: f64,
    /// Probability that a detectable landmark is not reported on a scan.
    pub miss_rate: f64,
    /// Probability that a landmark the detector does not see (one its perception knows) is
    /// reported anyway on a scan, at a point uniform in the sensor disc.
    pub false_rate: f64,
}

impl DetectionNoise {
    /// No error: the true position of every detectable landmark, nothing else.
    pub const EXACT: Self = Self {
        sigma: 0.0,
        miss_rate: 0.0,
        false_rate: 0.0,
    };

    /// The thesis's measurement noise N(0, σ) with the default miss and false rates
    /// ([`MISS_RATE`], [`FALSE_RATE`]).
    #[must_use]
    pub const fn thesis(sigma: f64) -> Self {
        Self {
            sigma,
            miss_rate: MISS_RATE,
            false_rate: FALSE_RATE,
        }
    }

    /// True when every detection is the truth.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.sigma == 0.0 && self.miss_rate == 0.0 && self.false_rate == 0.0
    }
}

/// A detectable landmark goes unreported on 19 % of scans: how often MRCLAM's camera misses
/// a barcoded landmark it has in view — detected on one frame and again two frames later
/// but not in between, against detected on successive frames: 0.176, 0.197 and 0.200 on
/// Datasets 2, 5 and 7, 0.189 pooled (`scripts/mrclam_miss_rate.py`).
pub const MISS_RATE: f64 = 0.19;

/// No false reports by default: the thesis's robots are given the data association ("a
/// data association to the landmarks", §2.2), and the field experiment's recogniser makes
/// its own wrong associations (aliasing) without this model. A rate above zero makes a
/// search stop where the link is not — at one report in a thousand per landmark and scan,
/// the §4.4.1 study's quick run fails 6.8 % of its pairs at R' = R against 1.5 % without
/// (`qrm study run table-4-1 --quick --set trial='"sensor-range"' --set range_factors=[1.0]
/// --set robot.detection.false_rate=0.001`).
pub const FALSE_RATE: f64 = 0.0;

/// The largest detection σ (m): a kilometre, far beyond any sensor's range.
pub const MAX_DETECTION_SIGMA: f64 = 1000.0;
/// The largest length σ (m/√m): a metre per metre driven.
pub const MAX_DISTANCE_SIGMA: f64 = 1.0;
/// The largest heading σ (rad/√m): a radian per metre driven.
pub const MAX_HEADING_SIGMA: f64 = 1.0;

/// What the wheels get wrong (random, on top of [`crate::Odometry`]'s systematic drift).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionNoise {
    /// σ of the length error per √metre driven (m/√m).
    pub distance_sigma: f64,
    /// σ of the heading error per √metre driven (rad/√m).
    pub heading_sigma: f64,
}

impl MotionNoise {
    /// No error: waypoints driven exactly.
    pub const EXACT: Self = Self {
        distance_sigma: 0.0,
        heading_sigma: 0.0,
    };

    /// A small wheeled robot: 2 cm/√m in length and 1°/√m in heading — the size of
    /// [`crate::Odometry::WHEELED`]'s systematic errors, as random ones.
    pub const WHEELED: Self = Self {
        distance_sigma: 0.02,
        heading_sigma: std::f64::consts::PI / 180.0,
    };

    /// True when the robot drives its waypoints exactly.
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.distance_sigma == 0.0 && self.heading_sigma == 0.0
    }
}

/// The navigating robot's errors: detection and motion, and the seed of their draws.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Robot {
    /// What the detector gets wrong.
    pub detection: DetectionNoise,
    /// What the wheels get wrong.
    pub motion: MotionNoise,
    /// Seed of every draw (with each run's own key).
    pub seed: u64,
}

impl Default for Robot {
    /// The §4.4.1 robot: N(0, 0.3) detections with the default misses and false reports,
    /// wheeled motion noise.
    fn default() -> Self {
        Self::erring(0.3)
    }
}

impl Robot {
    /// Idealised: detections at the true positions, waypoints driven exactly.
    pub const EXACT: Self = Self {
        detection: DetectionNoise::EXACT,
        motion: MotionNoise::EXACT,
        seed: 0,
    };

    /// A robot whose detections have the thesis's noise N(0, `sigma`), with the default
    /// miss and false rates and wheeled motion noise.
    #[must_use]
    pub const fn erring(sigma: f64) -> Self {
        Self {
            detection: DetectionNoise::thesis(sigma),
            motion: MotionNoise::WHEELED,
            seed: 0,
        }
    }

    /// The same robot with `seed`.
    #[must_use]
    pub const fn with_seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// This robot seeded with `seed` — or, when `exact`, the exact robot: what a study's
    /// `robot` and `exact_robot` settings make the navigating robot.
    #[must_use]
    pub const fn or_exact(self, exact: bool, seed: u64) -> Self {
        if exact {
            Self::EXACT
        } else {
            self.with_seed(seed)
        }
    }

    /// True for the idealised robot (reports label its runs).
    #[must_use]
    pub fn is_exact(&self) -> bool {
        self.detection.is_exact() && self.motion.is_exact()
    }

    /// How far inside its range the robot keeps a landmark it must not lose (m), sensing
    /// every `step` metres: three σ of a detection plus three σ of one step's drive
    /// (length and heading). Zero for the exact robot, which circles at its full range
    /// (Proposition 1).
    #[must_use]
    pub fn margin(&self, step: f64) -> f64 {
        let m = self.motion;
        3.0 * (self.detection.sigma + step.sqrt() * (m.distance_sigma + m.heading_sigma * step))
    }

    /// Checks every rate and spread.
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] naming the field: a negative or non-finite σ, a rate
    /// outside [0, 1) (a miss rate of 1: the robot would never see anything), a σ above its
    /// limit ([`MAX_DETECTION_SIGMA`], [`MAX_DISTANCE_SIGMA`], [`MAX_HEADING_SIGMA`]: past
    /// them a detection or a step lands so far away that a path to it takes for ever).
    pub fn check(&self) -> Result<()> {
        let spread = |name: &str, v: f64, max: f64| {
            if v.is_finite() && (0.0..=max).contains(&v) {
                Ok(())
            } else {
                Err(QlinkError::InvalidParameter(format!(
                    "robot {name} {v} must be in 0..={max}"
                )))
            }
        };
        let rate = |name: &str, v: f64| {
            if (0.0..1.0).contains(&v) {
                Ok(())
            } else {
                Err(QlinkError::InvalidParameter(format!(
                    "robot {name} {v} must be a probability in [0, 1)"
                )))
            }
        };
        spread("detection sigma", self.detection.sigma, MAX_DETECTION_SIGMA)?;
        rate("miss rate", self.detection.miss_rate)?;
        rate("false rate", self.detection.false_rate)?;
        spread(
            "distance sigma",
            self.motion.distance_sigma,
            MAX_DISTANCE_SIGMA,
        )?;
        spread(
            "heading sigma",
            self.motion.heading_sigma,
            MAX_HEADING_SIGMA,
        )
    }
}

impl std::fmt::Display for Robot {
    /// What the robot gets wrong, as a report says it.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.is_exact() {
            return write!(
                f,
                "exact (idealised): true detections, waypoints driven exactly"
            );
        }
        let d = self.detection;
        let m = self.motion;
        let det = if d.is_exact() {
            "detections as its perception reports them".to_owned()
        } else {
            let fals = if d.false_rate > 0.0 {
                format!("{:.2} % falsely reported", 100.0 * d.false_rate)
            } else {
                "no false reports".to_owned()
            };
            format!(
                "detections with N(0, {} m) error, {:.0} % missed, {fals}",
                d.sigma,
                100.0 * d.miss_rate
            )
        };
        let mot = if m.is_exact() {
            "waypoints driven exactly".to_owned()
        } else {
            format!(
                "wheels off by N(0, {:.1} cm/√m) in length and N(0, {:.2}°/√m) in heading",
                100.0 * m.distance_sigma,
                m.heading_sigma.to_degrees()
            )
        };
        write!(f, "errs: {det}; {mot} (seed {})", self.seed)
    }
}

/// One step as the wheels drove it ([`Robot::step`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Step {
    /// The true displacement (world frame, m).
    pub moved: [f64; 2],
    /// The rotation from the believed frame to the world's after the step (rad).
    pub heading: f64,
    /// The distance truly driven (m).
    pub length: f64,
}

impl Robot {
    /// What the detector reports on landmark `id` from `from` (the true position), which the
    /// `perception` `truly` detects or not: its measured position (world frame) or `None`.
    /// `key` is (run, scan): the same key gives the same report.
    pub fn report<P: Perception + ?Sized>(
        &self,
        perception: &P,
        from: [f64; 2],
        id: u32,
        truly: bool,
        [run, scan]: [u64; 2],
    ) -> Option<[f64; 2]> {
        let noise = self.detection;
        if noise.is_exact() {
            return if truly { perception.position(id) } else { None };
        }
        let key = |what| keyed(run, scan, u64::from(id), what);
        if truly {
            if noise.miss_rate > 0.0 && uniform(&mut key(Draw::Miss)) < noise.miss_rate {
                return None;
            }
            let p = perception.position(id)?;
            let mut rng = key(Draw::Position);
            let (ex, ey) = (normal(&mut rng), normal(&mut rng));
            Some([p[0] + noise.sigma * ex, p[1] + noise.sigma * ey])
        } else if noise.false_rate > 0.0
            && uniform(&mut key(Draw::False)) < noise.false_rate
            && perception.position(id).is_some()
        {
            // another feature taken for `id` (a landmark the sensor knows): anywhere in the
            // sensor disc
            let mut rng = key(Draw::Position);
            let r = perception.range() * uniform(&mut rng).sqrt();
            let a = std::f64::consts::TAU * uniform(&mut rng);
            Some([from[0] + r * a.cos(), from[1] + r * a.sin()])
        } else {
            None
        }
    }

    /// A commanded step `delta` (believed frame, non-zero) as the wheels drive it, with the
    /// believed frame rotated by `heading` from the world's; `key` is (run, step).
    #[must_use]
    pub fn step(&self, delta: [f64; 2], heading: f64, [run, step]: [u64; 2]) -> Step {
        let want = delta[0].hypot(delta[1]);
        let m = self.motion;
        let mut rng = keyed(run, step, 0, Draw::Motion);
        let heading = heading + m.heading_sigma * want.sqrt() * normal(&mut rng);
        let got = (want + m.distance_sigma * want.sqrt() * normal(&mut rng)).max(0.0);
        let (s, c) = heading.sin_cos();
        let k = if want > 0.0 { got / want } else { 0.0 };
        Step {
            moved: [
                k * (c * delta[0] - s * delta[1]),
                k * (s * delta[0] + c * delta[1]),
            ],
            heading,
            length: got,
        }
    }

    /// A drive's poses `(x, y, θ)` as this robot's odometry has them: each move between
    /// consecutive poses, measured in the robot's frame at the first, is integrated with the
    /// wheels' errors — its length off by N(0, `distance_sigma`·√d) and the heading after it
    /// by N(0, `heading_sigma`·√d) for a move of d metres — from the true first pose. So the
    /// believed drive drifts from the true one as a random walk in the distance driven, as
    /// [`Robot::step`]'s does. `drive` keys the draws (with the seed); the exact robot's
    /// odometry is the drive itself, bit for bit.
    ///
    /// ```
    /// use qlink::Robot;
    /// let drive: Vec<[f64; 3]> = (0..=100).map(|i| [f64::from(i), 0.0, 0.0]).collect();
    /// assert_eq!(Robot::EXACT.odometry(&drive, 0)?, drive);
    /// let believed = Robot::default().with_seed(3).odometry(&drive, 0)?;
    /// assert_eq!(believed[0], drive[0]); // it starts where it is
    /// assert_ne!(believed[100], drive[100]); // and drifts
    /// # Ok::<(), qlink::QlinkError>(())
    /// ```
    ///
    /// # Errors
    /// [`QlinkError::InvalidParameter`] naming the pose: a coordinate or heading that is not
    /// finite, or a move so large that the believed pose is not (past about 10¹⁵⁴ m).
    pub fn odometry(&self, poses: &[[f64; 3]], drive: u64) -> Result<Vec<[f64; 3]>> {
        if let Some(i) = poses.iter().position(|p| !p.iter().all(|v| v.is_finite())) {
            return Err(QlinkError::InvalidParameter(format!(
                "odometry: pose {i} of the drive, {:?}, is not finite",
                poses[i]
            )));
        }
        let m = self.motion;
        if m.is_exact() {
            return Ok(poses.to_vec());
        }
        let run = run_key(self.seed, &[drive]);
        let mut out = Vec::with_capacity(poses.len());
        let Some(&first) = poses.first() else {
            return Ok(out);
        };
        let mut believed = first;
        out.push(believed);
        for (i, w) in poses.windows(2).enumerate() {
            let ([x0, y0, t0], [x1, y1, t1]) = (w[0], w[1]);
            // the move in the robot's frame at the first pose, and its turn
            let (s0, c0) = t0.sin_cos();
            let (dx, dy) = (x1 - x0, y1 - y0);
            let local = [c0 * dx + s0 * dy, -s0 * dx + c0 * dy];
            let turn = (t1 - t0 + std::f64::consts::PI).rem_euclid(std::f64::consts::TAU)
                - std::f64::consts::PI;
            let d = local[0].hypot(local[1]);
            let mut rng = keyed(run, i as u64, 0, Draw::Odometry);
            let k = if d > 0.0 {
                (d + m.distance_sigma * d.sqrt() * normal(&mut rng)).max(0.0) / d
            } else {
                0.0
            };
            let heading_error = m.heading_sigma * d.sqrt() * normal(&mut rng);
            let (s, c) = believed[2].sin_cos();
            believed = [
                believed[0] + k * (c * local[0] - s * local[1]),
                believed[1] + k * (s * local[0] + c * local[1]),
                believed[2] + turn + heading_error,
            ];
            if !believed.iter().all(|v| v.is_finite()) {
                return Err(QlinkError::InvalidParameter(format!(
                    "odometry: the move to pose {} of the drive ({:?} from {:?}) is too large \
                     to integrate",
                    i + 1,
                    w[1],
                    w[0]
                )));
            }
            out.push(believed);
        }
        Ok(out)
    }
}

/// What a keyed draw is for (part of its key, so the draws are independent).
#[derive(Debug, Clone, Copy)]
enum Draw {
    Miss = 1,
    False = 2,
    Position = 3,
    Motion = 4,
    Odometry = 5,
}

/// splitmix64's finaliser: spreads a key's bits before it seeds a generator.
fn mix(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The generator of one keyed draw.
fn keyed(run: u64, scan: u64, id: u64, what: Draw) -> ChaCha8Rng {
    let k = mix(run ^ mix(scan ^ mix(id ^ mix(what as u64))));
    ChaCha8Rng::seed_from_u64(k)
}

/// A run's key from the robot's seed and what identifies the run.
pub(crate) fn run_key(seed: u64, parts: &[u64]) -> u64 {
    parts.iter().fold(mix(seed), |k, &p| mix(k ^ p))
}

/// One standard normal draw.
fn normal(rng: &mut ChaCha8Rng) -> f64 {
    StandardNormal.sample(rng)
}

/// One uniform draw in [0, 1).
fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    rng.random::<f64>()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keyed_draws_depend_on_every_part_of_the_key() {
        let a = uniform(&mut keyed(1, 2, 3, Draw::Miss));
        assert_eq!(a, uniform(&mut keyed(1, 2, 3, Draw::Miss)));
        for b in [
            uniform(&mut keyed(0, 2, 3, Draw::Miss)),
            uniform(&mut keyed(1, 0, 3, Draw::Miss)),
            uniform(&mut keyed(1, 2, 0, Draw::Miss)),
            uniform(&mut keyed(1, 2, 3, Draw::False)),
        ] {
            assert_ne!(a, b);
        }
    }

    /// The mapping drive's odometry drifts as the configured random walk: over 100 m driven in
    /// quarter-metre moves, the heading's error has σ = `heading_sigma`·√100 and the length
    /// driven σ = `distance_sigma`·√100 (a σ per move rather than per √metre would give half).
    #[test]
    fn odometry_drifts_with_the_configured_spread() {
        let drive: Vec<[f64; 3]> = (0..=400).map(|i| [0.25 * f64::from(i), 0.0, 0.0]).collect();
        let robot = Robot::default().with_seed(11);
        let (mut headings, mut lengths) = (Vec::new(), Vec::new());
        for key in 0..2000 {
            let b = robot.odometry(&drive, key).unwrap();
            assert_eq!(b.len(), drive.len());
            headings.push(b[400][2]);
            lengths.push(
                b.windows(2)
                    .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
                    .sum::<f64>()
                    - 100.0,
            );
        }
        let sd = |v: &[f64]| {
            let m = v.iter().sum::<f64>() / v.len() as f64;
            (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
        };
        let m = robot.motion;
        let (h, l) = (
            sd(&headings) / (10.0 * m.heading_sigma),
            sd(&lengths) / (10.0 * m.distance_sigma),
        );
        assert!(
            (0.92..1.08).contains(&h),
            "heading spread {h} of the configured"
        );
        assert!(
            (0.92..1.08).contains(&l),
            "length spread {l} of the configured"
        );
        // the same key drifts the same way; turning on the spot adds no error
        assert_eq!(
            robot.odometry(&drive, 5).unwrap(),
            robot.odometry(&drive, 5).unwrap()
        );
        let spin = [[1.0, 2.0, 0.0], [1.0, 2.0, 1.0], [1.0, 2.0, -2.0]];
        assert_eq!(robot.odometry(&spin, 0).unwrap(), spin.to_vec());
        assert!(robot.odometry(&[], 0).unwrap().is_empty());
        // bad drives are refused by pose, by the exact robot too
        for r in [robot, Robot::EXACT] {
            let nan = [[0.0, 0.0, 0.0], [1.0, f64::NAN, 0.0]];
            let err = r.odometry(&nan, 0).unwrap_err().to_string();
            assert!(
                err.contains("pose 1") && err.contains("not finite"),
                "{err}"
            );
        }
        let huge = [[-1e308, 0.0, 0.0], [1e308, 0.0, 0.0]];
        let err = robot.odometry(&huge, 0).unwrap_err().to_string();
        assert!(err.contains("pose 1") && err.contains("too large"), "{err}");
    }

    #[test]
    fn bad_rates_and_spreads_are_refused_by_name() {
        let mut r = Robot::default();
        r.detection.miss_rate = 1.0;
        assert!(r.check().unwrap_err().to_string().contains("miss rate"));
        let mut r = Robot::default();
        r.motion.heading_sigma = f64::NAN;
        assert!(r.check().unwrap_err().to_string().contains("heading sigma"));
        let mut r = Robot::default();
        r.detection.sigma = -0.1;
        assert!(
            r.check()
                .unwrap_err()
                .to_string()
                .contains("detection sigma")
        );
        assert!(Robot::default().check().is_ok() && Robot::EXACT.is_exact());
    }
}
