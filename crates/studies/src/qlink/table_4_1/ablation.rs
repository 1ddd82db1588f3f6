//! The navigating robot with some of its errors switched off: what each error costs.
//!
//! Where a row of Table 4.1 differs from the thesis's, the report says why with a measurement
//! (issue 36 §4): the same setting run again with one error of [`qlink::Robot`] removed at a
//! time (and with all but the motion removed, and with none left). A cause is then the rate
//! that falls when it is removed — measured on the same world, pairs and seed — not a guess.

use qlink::{DetectionNoise, MotionNoise, Robot};
use serde::{Deserialize, Serialize};

/// Which of the navigating robot's errors a setting keeps.
#[derive(
    Debug, Clone, Copy, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize,
)]
#[serde(rename_all = "kebab-case")]
pub enum Ablation {
    /// Every error of the configured robot (the study's own rows).
    #[default]
    Full,
    /// None: the idealised robot.
    Exact,
    /// Every error but the missed detections.
    WithoutMisses,
    /// Every error but the detections' position noise.
    WithoutDetectionNoise,
    /// Every error but the false reports.
    WithoutFalseReports,
    /// Every error but the wheels'.
    WithoutMotionNoise,
    /// Only the wheels' errors: detections exact.
    MotionOnly,
}

impl Ablation {
    /// The ablations that remove one error, or all but one kind: what a run measures.
    pub const MEASURED: [Self; 6] = [
        Self::Exact,
        Self::WithoutMisses,
        Self::WithoutDetectionNoise,
        Self::WithoutFalseReports,
        Self::WithoutMotionNoise,
        Self::MotionOnly,
    ];

    /// Its name in files and on the command line.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Full => "full",
            Self::Exact => "exact",
            Self::WithoutMisses => "without-misses",
            Self::WithoutDetectionNoise => "without-detection-noise",
            Self::WithoutFalseReports => "without-false-reports",
            Self::WithoutMotionNoise => "without-motion-noise",
            Self::MotionOnly => "motion-only",
        }
    }

    /// What it removes, in a report's words (`None` for the full robot).
    #[must_use]
    pub fn removes(self) -> Option<&'static str> {
        match self {
            Self::Full => None,
            Self::Exact => Some("every error"),
            Self::WithoutMisses => Some("the missed detections"),
            Self::WithoutDetectionNoise => Some("the detections' position noise"),
            Self::WithoutFalseReports => Some("the false reports"),
            Self::WithoutMotionNoise => Some("the motion noise"),
            Self::MotionOnly => Some("every detection error"),
        }
    }

    /// The robot it leaves, in a report's words ("the exact robot", "without the missed
    /// detections").
    #[must_use]
    pub fn phrase(self) -> &'static str {
        match self {
            Self::Full => "the robot as configured",
            Self::Exact => "the exact robot",
            Self::WithoutMisses => "without the missed detections",
            Self::WithoutDetectionNoise => "without the detections' position noise",
            Self::WithoutFalseReports => "without the false reports",
            Self::WithoutMotionNoise => "without the motion noise",
            Self::MotionOnly => "with the motion noise only",
        }
    }

    /// Whether it removes one error and keeps the others (what "the largest single cause"
    /// is chosen among).
    #[must_use]
    pub fn is_single(self) -> bool {
        matches!(
            self,
            Self::WithoutMisses
                | Self::WithoutDetectionNoise
                | Self::WithoutFalseReports
                | Self::WithoutMotionNoise
        )
    }

    /// `robot` with this ablation's errors removed (its seed kept, so the draws that remain
    /// are the same ones).
    #[must_use]
    pub fn apply(self, robot: Robot) -> Robot {
        let mut r = robot;
        match self {
            Self::Full => {}
            Self::Exact => {
                r.detection = DetectionNoise::EXACT;
                r.motion = MotionNoise::EXACT;
            }
            Self::WithoutMisses => r.detection.miss_rate = 0.0,
            Self::WithoutDetectionNoise => r.detection.sigma = 0.0,
            Self::WithoutFalseReports => r.detection.false_rate = 0.0,
            Self::WithoutMotionNoise => r.motion = MotionNoise::EXACT,
            Self::MotionOnly => r.detection = DetectionNoise::EXACT,
        }
        r
    }

    /// Whether it changes `robot` at all (removing a false-report rate of 0 does not; such an
    /// ablation would only repeat the full robot's rows).
    #[must_use]
    pub fn changes(self, robot: &Robot) -> bool {
        self.apply(*robot) != *robot
    }
}

impl std::fmt::Display for Ablation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_ablation_removes_exactly_what_it_names() {
        let r = Robot {
            detection: DetectionNoise {
                sigma: 0.3,
                miss_rate: 0.19,
                false_rate: 0.01,
            },
            motion: MotionNoise::WHEELED,
            seed: 7,
        };
        assert_eq!(Ablation::Full.apply(r), r);
        assert!(Ablation::Exact.apply(r).is_exact());
        assert_eq!(Ablation::Exact.apply(r).seed, 7, "the seed is kept");
        let d = |a: Ablation| Ablation::apply(a, r).detection;
        assert_eq!(d(Ablation::WithoutMisses).miss_rate, 0.0);
        assert_eq!(d(Ablation::WithoutMisses).sigma, 0.3);
        assert_eq!(d(Ablation::WithoutDetectionNoise).sigma, 0.0);
        assert_eq!(d(Ablation::WithoutDetectionNoise).miss_rate, 0.19);
        assert_eq!(d(Ablation::WithoutFalseReports).false_rate, 0.0);
        assert_eq!(d(Ablation::WithoutFalseReports).miss_rate, 0.19);
        let without_motion = Ablation::WithoutMotionNoise.apply(r);
        assert!(without_motion.motion.is_exact() && without_motion.detection == r.detection);
        let motion_only = Ablation::MotionOnly.apply(r);
        assert!(motion_only.detection.is_exact() && motion_only.motion == r.motion);
        // the default robot reports nothing false: that ablation changes nothing
        let thesis = Robot::erring(0.3);
        assert!(!Ablation::WithoutFalseReports.changes(&thesis));
        assert!(
            Ablation::MEASURED
                .iter()
                .filter(|a| a.changes(&thesis))
                .count()
                == 5
        );
        assert!(!Ablation::Exact.changes(&Robot::EXACT));
    }
}
