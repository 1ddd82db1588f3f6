//! Uneven ground under a flat world: where a line-scan lidar sees the ground plane.
//!
//! The worlds are 2-D, but a real line scanner sweeps a plane fixed to the robot a few tens
//! of centimetres above the ground, tilted with the terrain under the wheels. Where the ground
//! ahead rises faster than that plane — the far side of a hollow, a hummock in front, the foot
//! of a slope — the rays hit the ground instead of the landmarks behind it, and the scan holds
//! a smooth arc of ground returns (thesis §4.4.2: "the robot encounters pitched terrain and the
//! line scan lidar only views the ground plane", "drives into a natural basin where the lidar
//! only views ground plane"). That is the field experiment's main cause of failure, so it is
//! modelled rather than assumed away.
//!
//! **Model.** The ground's height is a sum of Gaussian bumps (positive) and hollows
//! (negative), sampled once on a grid and read bilinearly. A scan from a pose: the scanner sits
//! [`LidarConfig::mount_height`](crate::LidarConfig::mount_height) above the ground, its plane
//! tilted as the ground's gradient there (small angles: a ray along `u` climbs at the slope
//! `∇h·u`); each ray is marched in [`MARCH_STEP_M`] steps up to what it hit and is replaced by
//! a ground return ([`Hit::Ground`](crate::Hit::Ground)) where the ground first reaches it.
//! Landmarks are taken as tall (trunks, posts, walls): a ray that clears the ground hits them.

use rand::Rng;
use rand_distr::{Distribution, Normal};

use crate::error::{Result, SimError, check};
use crate::sensors::{LaserScan, LidarConfig, Pose};
use crate::world::Hit;

/// Distance between the height checks along a ray (m).
pub const MARCH_STEP_M: f64 = 0.25;
/// The height grid's cell (m).
pub const CELL_M: f64 = 0.5;
/// The most grid cells a terrain may hold.
pub const MAX_CELLS: usize = 4_000_000;

/// One bump (height > 0) or hollow (< 0) of the ground: `height · exp(−|x − centre|² / 2σ²)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Bump {
    /// Centre (m).
    pub centre: [f64; 2],
    /// Width σ (m), > 0.
    pub sigma: f64,
    /// Height at the centre (m).
    pub height: f64,
}

/// The ground's height over a rectangle (flat outside it).
#[derive(Debug, Clone, PartialEq)]
pub struct Terrain {
    bumps: Vec<Bump>,
    /// [x0, y0] of the grid.
    origin: [f64; 2],
    nx: usize,
    ny: usize,
    heights: Vec<f64>,
}

impl Terrain {
    /// The ground of `bumps` over `bounds` = [x0, x1, y0, y1].
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a bump that is not finite or of non-positive width, or bounds
    /// that are empty, not finite or too large for the grid.
    pub fn new(bumps: Vec<Bump>, bounds: [f64; 4]) -> Result<Self> {
        for (i, b) in bumps.iter().enumerate() {
            check(
                b.centre.iter().all(|v| v.is_finite())
                    && b.sigma.is_finite()
                    && b.sigma > 0.0
                    && b.height.is_finite(),
                || format!("terrain bump {i}: {b:?} needs a finite centre and height and σ > 0"),
            )?;
        }
        let [x0, x1, y0, y1] = bounds;
        check(
            bounds.iter().all(|v| v.is_finite()) && x1 > x0 && y1 > y0,
            || format!("terrain bounds {bounds:?} must be finite and non-empty"),
        )?;
        let nx = ((x1 - x0) / CELL_M).ceil() as usize + 1;
        let ny = ((y1 - y0) / CELL_M).ceil() as usize + 1;
        check(nx.saturating_mul(ny) <= MAX_CELLS, || {
            format!("terrain bounds {bounds:?} need {nx} × {ny} cells; the limit is {MAX_CELLS}")
        })?;
        let mut heights = vec![0.0; nx * ny];
        for (k, h) in heights.iter_mut().enumerate() {
            let p = [x0 + (k % nx) as f64 * CELL_M, y0 + (k / nx) as f64 * CELL_M];
            *h = exact_height(&bumps, p);
        }
        Ok(Self {
            bumps,
            origin: [x0, y0],
            nx,
            ny,
            heights,
        })
    }

    /// The bumps and hollows.
    #[must_use]
    pub fn bumps(&self) -> &[Bump] {
        &self.bumps
    }

    /// The ground's height at `p` (m; 0 outside the grid).
    #[must_use]
    pub fn height(&self, p: [f64; 2]) -> f64 {
        let gx = (p[0] - self.origin[0]) / CELL_M;
        let gy = (p[1] - self.origin[1]) / CELL_M;
        if !(gx >= 0.0 && gy >= 0.0) {
            return 0.0;
        }
        let (i, j) = (gx.floor() as usize, gy.floor() as usize);
        if i + 1 >= self.nx || j + 1 >= self.ny {
            return 0.0;
        }
        let (fx, fy) = (gx - i as f64, gy - j as f64);
        let at = |a: usize, b: usize| self.heights[b * self.nx + a];
        let bottom = at(i, j) * (1.0 - fx) + at(i + 1, j) * fx;
        let top = at(i, j + 1) * (1.0 - fx) + at(i + 1, j + 1) * fx;
        bottom * (1.0 - fy) + top * fy
    }

    /// The ground's gradient at `p` (central differences over a cell).
    #[must_use]
    pub fn gradient(&self, p: [f64; 2]) -> [f64; 2] {
        let h = CELL_M;
        [
            (self.height([p[0] + h, p[1]]) - self.height([p[0] - h, p[1]])) / (2.0 * h),
            (self.height([p[0], p[1] + h]) - self.height([p[0], p[1] - h])) / (2.0 * h),
        ]
    }

    /// Where each ray of `scan`, taken from `pose` with `cfg`, first meets the ground: the
    /// ray becomes a ground return there (range noise as the scanner's, drawn from `rng`).
    /// Returns how many rays the ground took.
    ///
    /// # Errors
    /// As [`LidarConfig::validate`].
    pub fn ground_returns(
        &self,
        pose: &Pose,
        cfg: &LidarConfig,
        scan: &mut LaserScan,
        rng: &mut impl Rng,
    ) -> Result<usize> {
        cfg.validate()?;
        let noise =
            Normal::new(0.0, cfg.range_sigma).map_err(|e| SimError::Invalid(e.to_string()))?;
        let at = [pose.x, pose.y];
        let mut taken = 0;
        for (k, a) in scan.angles.iter().enumerate() {
            let u = [(pose.theta + a).cos(), (pose.theta + a).sin()];
            let reach = scan.ranges[k].min(cfg.max_range);
            if let Some(hit) = self.meets_ground(at, u, reach, cfg.mount_height) {
                let n = if cfg.range_sigma > 0.0 {
                    noise.sample(rng)
                } else {
                    0.0
                };
                scan.ranges[k] = (hit + n).max(0.0);
                if let Some(h) = scan.hits.get_mut(k) {
                    *h = Some(Hit::Ground);
                }
                taken += 1;
            }
        }
        Ok(taken)
    }
}

impl Terrain {
    /// Where a ray from a scanner `mount` m above the ground at `at`, along the unit `u`,
    /// first meets the ground before `reach` (m), if it does (see the module docs).
    #[must_use]
    pub fn meets_ground(&self, at: [f64; 2], u: [f64; 2], reach: f64, mount: f64) -> Option<f64> {
        let z0 = self.height(at) + mount;
        let grad = self.gradient(at);
        let climb = grad[0] * u[0] + grad[1] * u[1];
        let mut prev = (0.0, mount);
        let mut s = MARCH_STEP_M;
        while s < reach {
            let clearance = z0 + climb * s - self.height([at[0] + u[0] * s, at[1] + u[1] * s]);
            if clearance <= 0.0 {
                // where the clearance crossed zero, between the two checks
                return Some(prev.0 + (s - prev.0) * prev.1 / (prev.1 - clearance).max(1e-12));
            }
            prev = (s, clearance);
            s += MARCH_STEP_M;
        }
        None
    }

    /// Whether a scanner `mount` m above the ground at `from` sees over the ground to `to`.
    #[must_use]
    pub fn clears(&self, from: [f64; 2], to: [f64; 2], mount: f64) -> bool {
        let d = (to[0] - from[0]).hypot(to[1] - from[1]);
        if d <= 0.0 {
            return true;
        }
        let u = [(to[0] - from[0]) / d, (to[1] - from[1]) / d];
        self.meets_ground(from, u, d, mount).is_none()
    }
}

fn exact_height(bumps: &[Bump], p: [f64; 2]) -> f64 {
    bumps
        .iter()
        .map(|b| {
            let d2 = (p[0] - b.centre[0]).powi(2) + (p[1] - b.centre[1]).powi(2);
            b.height * (-d2 / (2.0 * b.sigma * b.sigma)).exp()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn flat_scan(n: usize, range: f64) -> LaserScan {
        let cfg = LidarConfig {
            rays: n,
            ..LidarConfig::default()
        };
        LaserScan {
            angles: cfg.angles(),
            ranges: vec![range; n],
            hits: vec![Some(Hit::Landmark(0)); n],
        }
    }

    #[test]
    fn the_grid_reads_the_bumps_and_flat_ground_takes_no_ray() {
        let b = Bump {
            centre: [10.0, 0.0],
            sigma: 3.0,
            height: 1.0,
        };
        let t = Terrain::new(vec![b], [-20.0, 40.0, -20.0, 20.0]).expect("valid");
        for p in [[10.0, 0.0], [12.3, 1.7], [5.1, -2.2]] {
            assert!((t.height(p) - exact_height(&[b], p)).abs() < 0.01, "{p:?}");
        }
        let flat = Terrain::new(vec![], [-20.0, 40.0, -20.0, 20.0]).expect("valid");
        let mut scan = flat_scan(181, 25.0);
        let cfg = LidarConfig::default();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let pose = Pose {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
        };
        assert_eq!(
            flat.ground_returns(&pose, &cfg, &mut scan, &mut rng).ok(),
            Some(0)
        );
    }

    #[test]
    fn a_hummock_ahead_takes_the_rays_towards_it_at_its_flank() {
        // a 1 m hummock 10 m ahead: the 0.3 m scanner's rays meet it where it is as high as
        // they are. Level rays would at h = 0.3, x ≈ 5.34; but the robot stands on its foot
        // (h₀ = e^{−100/18} ≈ 0.0039, slope h₀·10/9 ≈ 0.0043), so the ray starts 0.0039 higher
        // and climbs: exp(−(x − 10)²/18) = 0.3039 + 0.0043·x ⇒ x ≈ 5.52
        let b = Bump {
            centre: [10.0, 0.0],
            sigma: 3.0,
            height: 1.0,
        };
        let t = Terrain::new(vec![b], [-20.0, 40.0, -20.0, 20.0]).expect("valid");
        let cfg = LidarConfig::default();
        let mut scan = flat_scan(cfg.rays, 25.0);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let pose = Pose {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
        };
        let taken = t
            .ground_returns(&pose, &cfg, &mut scan, &mut rng)
            .expect("valid");
        assert!(taken > 0);
        let ahead = scan
            .angles
            .iter()
            .position(|a| a.abs() < 1e-9)
            .expect("a ray ahead");
        assert_eq!(scan.hits[ahead], Some(Hit::Ground));
        assert!(
            (scan.ranges[ahead] - 5.52).abs() < 0.02,
            "{}",
            scan.ranges[ahead]
        );
        // behind the robot the ground is flat: nothing taken
        let behind = scan
            .angles
            .iter()
            .position(|a| (a.abs() - 3.0 * std::f64::consts::FRAC_PI_4).abs() < 0.01)
            .expect("a ray behind");
        assert_eq!(scan.hits[behind], Some(Hit::Landmark(0)));
        // standing on a uniform slope the scanner tilts with it: nothing taken
        // (the flank of a hill 1 km wide, at its inflection: a 6 % grade, curvature nil)
        let slope = Terrain::new(
            vec![Bump {
                centre: [0.0, 1000.0],
                sigma: 1e3,
                height: 100.0,
            }],
            [-20.0, 40.0, -20.0, 20.0],
        )
        .expect("valid");
        let mut s2 = flat_scan(cfg.rays, 25.0);
        assert_eq!(
            slope.ground_returns(&pose, &cfg, &mut s2, &mut rng).ok(),
            Some(0)
        );
    }

    #[test]
    fn bad_terrain_is_refused() {
        let bad = Bump {
            centre: [f64::NAN, 0.0],
            sigma: 1.0,
            height: 1.0,
        };
        assert!(Terrain::new(vec![bad], [0.0, 1.0, 0.0, 1.0]).is_err());
        assert!(Terrain::new(vec![], [0.0, 1e9, 0.0, 1e9]).is_err());
        assert!(Terrain::new(vec![], [1.0, 0.0, 0.0, 1.0]).is_err());
    }
}
