//! The robot and its sensors: a unicycle, a raycast lidar, and an ideal landmark detector
//! (ids known, full occlusion) with Gaussian noise.

use rand::RngExt;
use rand_distr::{Distribution, Normal};
use serde::{Deserialize, Serialize};

use crate::error::{Result, check};
use crate::world::{Hit, World};

/// A planar pose: position (m) and heading (rad, counter-clockwise from world +x).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// Heading (rad).
    pub theta: f64,
}

impl Pose {
    /// A world point in this pose's frame (x forward, y left).
    #[must_use]
    pub fn to_local(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.theta.sin_cos();
        let (dx, dy) = (p[0] - self.x, p[1] - self.y);
        [c * dx + s * dy, -s * dx + c * dy]
    }

    /// A point of the robot's frame in the world frame (the inverse of [`Pose::to_local`]).
    #[must_use]
    pub fn to_world(&self, p: [f64; 2]) -> [f64; 2] {
        let (s, c) = self.theta.sin_cos();
        [self.x + c * p[0] - s * p[1], self.y + s * p[0] + c * p[1]]
    }
}

/// A unicycle / differential-drive robot with velocity limits, integrated at a fixed step.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Unicycle {
    /// Current pose.
    pub pose: Pose,
    /// Largest forward speed (m/s).
    pub v_max: f64,
    /// Largest turn rate (rad/s).
    pub w_max: f64,
    /// Integration step (s).
    pub dt: f64,
}

impl Unicycle {
    /// A robot at `pose`.
    ///
    /// # Errors
    /// [`crate::SimError::Invalid`] for non-positive limits or step.
    pub fn new(pose: Pose, v_max: f64, w_max: f64, dt: f64) -> Result<Self> {
        check(
            v_max > 0.0
                && w_max > 0.0
                && dt > 0.0
                && v_max.is_finite()
                && w_max.is_finite()
                && dt.is_finite(),
            || format!("v_max {v_max}, w_max {w_max} and dt {dt} must be finite and > 0"),
        )?;
        Ok(Self {
            pose,
            v_max,
            w_max,
            dt,
        })
    }

    /// One step with the command `(v, w)`, clamped to the limits (exact arc integration).
    pub fn step(&mut self, v: f64, w: f64) {
        let v = v.clamp(-self.v_max, self.v_max);
        let w = w.clamp(-self.w_max, self.w_max);
        let th = self.pose.theta;
        if w.abs() < 1e-12 {
            self.pose.x += v * self.dt * th.cos();
            self.pose.y += v * self.dt * th.sin();
        } else {
            let th2 = th + w * self.dt;
            self.pose.x += v / w * (th2.sin() - th.sin());
            self.pose.y -= v / w * (th2.cos() - th.cos());
            self.pose.theta = th2;
        }
    }
}

/// Lidar settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LidarConfig {
    /// Field of view (rad), in (0, 2π].
    pub fov: f64,
    /// Number of rays, ≥ 1.
    pub rays: usize,
    /// Maximum range (m).
    pub max_range: f64,
    /// Gaussian range noise σ (m).
    pub range_sigma: f64,
    /// Probability that a ray returns nothing.
    pub dropout: f64,
    /// Height of the scan plane above the ground (m): where the terrain rises above it, the
    /// rays see the ground ([`crate::Terrain`]). 0.3 m: a Hokuyo on a Clearpath Jackal.
    #[serde(default = "jackal_mount")]
    pub mount_height: f64,
}

fn jackal_mount() -> f64 {
    0.3
}

impl Default for LidarConfig {
    /// A Hokuyo UTM-30LX-like scanner (the thesis's in-vivo lidar): 270°, 1081 rays, 30 m.
    fn default() -> Self {
        Self {
            fov: 270f64.to_radians(),
            rays: 1081,
            max_range: 30.0,
            range_sigma: 0.0,
            dropout: 0.0,
            mount_height: jackal_mount(),
        }
    }
}

impl LidarConfig {
    /// Checks the ranges.
    ///
    /// # Errors
    /// [`crate::SimError::Invalid`] for a FOV outside (0, 2π], zero rays, a non-positive range,
    /// negative noise or a dropout outside [0, 1].
    pub fn validate(&self) -> Result<()> {
        check(
            self.fov > 0.0 && self.fov <= std::f64::consts::TAU + 1e-12,
            || format!("FOV {} must be in (0, 2π]", self.fov),
        )?;
        check(self.rays >= 1, || "a lidar needs at least one ray".into())?;
        check(self.max_range > 0.0 && self.max_range.is_finite(), || {
            format!("max range {} must be finite and > 0", self.max_range)
        })?;
        check(
            self.range_sigma >= 0.0 && self.range_sigma.is_finite(),
            || format!("range noise {} must be >= 0", self.range_sigma),
        )?;
        check((0.0..=1.0).contains(&self.dropout), || {
            format!("dropout {} must be in [0, 1]", self.dropout)
        })?;
        check(
            self.mount_height.is_finite() && self.mount_height >= 0.0,
            || {
                format!(
                    "mount height {} m must be finite and ≥ 0",
                    self.mount_height
                )
            },
        )
    }

    /// Ray angles relative to the heading, from −fov/2 to +fov/2 (a full circle omits the
    /// duplicate end).
    #[must_use]
    pub fn angles(&self) -> Vec<f64> {
        let full = self.fov >= std::f64::consts::TAU - 1e-9;
        let n = self.rays;
        let steps = if full || n == 1 {
            n as f64
        } else {
            (n - 1) as f64
        };
        (0..n)
            .map(|i| {
                if n == 1 {
                    0.0
                } else {
                    -self.fov / 2.0 + self.fov * i as f64 / steps
                }
            })
            .collect()
    }
}

/// One lidar scan: angles relative to the heading and ranges (`f64::INFINITY` = no return).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LaserScan {
    /// Ray angles (rad, robot frame).
    pub angles: Vec<f64>,
    /// Ranges (m); infinite where nothing was hit within range or the return dropped out.
    pub ranges: Vec<f64>,
    /// What each ray hit (ground truth, for evaluating extractors).
    #[serde(skip)]
    pub hits: Vec<Option<Hit>>,
}

impl World {
    /// A lidar scan from `pose` with real ray casts.
    ///
    /// # Errors
    /// As [`LidarConfig::validate`].
    pub fn lidar(
        &self,
        pose: &Pose,
        cfg: &LidarConfig,
        rng: &mut impl rand::Rng,
    ) -> Result<LaserScan> {
        cfg.validate()?;
        let angles = cfg.angles();
        let casts = self.cast_rays(
            [pose.x, pose.y],
            angles.iter().map(|a| pose.theta + a),
            cfg.max_range,
        );
        let noise = Normal::new(0.0, cfg.range_sigma)
            .map_err(|e| crate::SimError::Invalid(e.to_string()))?;
        let mut ranges = Vec::with_capacity(casts.len());
        let mut hits = Vec::with_capacity(casts.len());
        for c in casts {
            let dropped = cfg.dropout > 0.0 && rng.random::<f64>() < cfg.dropout;
            match c {
                Some((r, h)) if !dropped => {
                    let n = if cfg.range_sigma > 0.0 {
                        noise.sample(rng)
                    } else {
                        0.0
                    };
                    ranges.push((r + n).max(0.0));
                    hits.push(Some(h));
                }
                _ => {
                    ranges.push(f64::INFINITY);
                    hits.push(None);
                }
            }
        }
        Ok(LaserScan {
            angles,
            ranges,
            hits,
        })
    }
}

/// Noise of the ideal detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum DetectorNoise {
    /// Isotropic Cartesian noise σ (m) on the measured position.
    Cartesian {
        /// σ (m).
        sigma: f64,
    },
    /// Independent range (m) and bearing (rad) noise.
    RangeBearing {
        /// σ of the range (m).
        sigma_range: f64,
        /// σ of the bearing (rad).
        sigma_bearing: f64,
    },
}

/// Settings of the ideal landmark detector.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DetectorConfig {
    /// Detection range (m): the landmark centre must be within it.
    pub range: f64,
    /// Require the whole disc to be unoccluded (thesis §4.4.1's occlusion study).
    pub full_occlusion: bool,
    /// The measurement noise.
    pub noise: DetectorNoise,
}

/// A detected landmark: id, measured position in the robot frame, and the covariance the
/// detector reports (its noise model).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Detection {
    /// Landmark id.
    pub id: u32,
    /// Measured position (m, robot frame: x forward, y left).
    pub xy: [f64; 2],
    /// Covariance (m²).
    pub cov: [[f64; 2]; 2],
}

impl World {
    /// Ideal detections from `pose`: landmarks in range and (if asked) fully visible, with
    /// the configured noise, sorted by id.
    ///
    /// # Errors
    /// [`crate::SimError::Invalid`] for a non-positive range or negative noise.
    pub fn detect(
        &self,
        pose: &Pose,
        cfg: &DetectorConfig,
        rng: &mut impl rand::Rng,
    ) -> Result<Vec<Detection>> {
        check(cfg.range > 0.0 && cfg.range.is_finite(), || {
            format!("detector range {} must be finite and > 0", cfg.range)
        })?;
        let normal = |s: f64| {
            Normal::new(0.0, s).map_err(|e| crate::SimError::Invalid(format!("noise σ {s}: {e}")))
        };
        let mut out = Vec::new();
        for (i, l) in self.spec().landmarks.iter().enumerate() {
            let d = (l.pos[0] - pose.x).hypot(l.pos[1] - pose.y);
            if d > cfg.range || (cfg.full_occlusion && !self.is_fully_visible([pose.x, pose.y], i))
            {
                continue;
            }
            let truth = pose.to_local(l.pos);
            let (xy, cov) = match cfg.noise {
                DetectorNoise::Cartesian { sigma } => {
                    check(sigma >= 0.0, || format!("noise σ {sigma} must be >= 0"))?;
                    let n = normal(sigma)?;
                    (
                        [truth[0] + n.sample(rng), truth[1] + n.sample(rng)],
                        [[sigma * sigma, 0.0], [0.0, sigma * sigma]],
                    )
                }
                DetectorNoise::RangeBearing {
                    sigma_range,
                    sigma_bearing,
                } => {
                    check(sigma_range >= 0.0 && sigma_bearing >= 0.0, || {
                        "noise σ must be >= 0".into()
                    })?;
                    let r = truth[0].hypot(truth[1]) + normal(sigma_range)?.sample(rng);
                    let b = truth[1].atan2(truth[0]) + normal(sigma_bearing)?.sample(rng);
                    let (s, c) = b.sin_cos();
                    let (vr, vb) = (
                        sigma_range * sigma_range,
                        sigma_bearing * sigma_bearing * r * r,
                    );
                    (
                        [r * c, r * s],
                        [
                            [c * c * vr + s * s * vb, s * c * (vr - vb)],
                            [s * c * (vr - vb), s * s * vr + c * c * vb],
                        ],
                    )
                }
            };
            out.push(Detection { id: l.id, xy, cov });
        }
        out.sort_by_key(|d| d.id);
        Ok(out)
    }
}
