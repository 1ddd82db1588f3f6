//! Seeded scenarios (DESIGN §5) and the loop that drives a robot through them.
//!
//! | name | world | path | detector |
//! |---|---|---|---|
//! | `pqrm-100` | 10 landmarks uniform in 100 m × 100 m (thesis §2.3.1) | one loop of radius 50 m about the centre, a frame every 16° | range 60 m, Cartesian σ = 5 m |
//! | `qlink-200` | 200 landmarks uniform in 200 m × 200 m, at least 2 m apart, radius 0.3 m (§4.4.1; `with_landmark_radius` sets 0.1–0.7 m) | lawn-mower coverage, lanes 20 m apart | range 20 m, σ = 0.3 m, full occlusion |
//! | `hallway` | two walls of point landmarks 6 m apart, one every 3 m (§3.4.1) | a straight drive down the middle | range 15 m, variance 0.1 m² |
//! | `field` | a corridor between two long buildings (walls) with posts in front, bollards inside and trees by its end, a dense stand of pines, an open field with sparse posts, rocks and bushes on pitched ground, a basin off the corridor's open end (§4.4.2; the ground is a `Terrain`, which the lidar sees where it rises into the scan plane) | a teleop-like path through all three | range 60 m, σ = 0.7 m |

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError, check};
use crate::sensors::{
    Detection, DetectorConfig, DetectorNoise, LaserScan, LidarConfig, Pose, Unicycle,
};
use crate::terrain::{Bump, Terrain};
use crate::world::{Clutter, PointLandmark, Wall, World, WorldSpec};

/// Scenario names.
pub const SCENARIOS: [&str; 4] = ["pqrm-100", "qlink-200", "hallway", "field"];

/// A world, a path through it and the robot's sensors.
#[derive(Debug)]
pub struct Scenario {
    /// Name.
    pub name: String,
    /// The world.
    pub world: World,
    /// Start pose.
    pub start: Pose,
    /// Waypoints the robot drives through, in order.
    pub waypoints: Vec<[f64; 2]>,
    /// Cruise speed (m/s).
    pub speed: f64,
    /// Time between frames (s).
    pub frame_period: f64,
    /// The ideal landmark detector.
    pub detector: DetectorConfig,
    /// The lidar.
    pub lidar: LidarConfig,
    /// The ground under the world, when it is not flat: where the lidar sees it instead of
    /// the landmarks ([`Scenario::scan`]).
    pub terrain: Option<Terrain>,
}

/// What the robot recorded at one frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Simulated time (s).
    pub t: f64,
    /// True pose (for logs; the qualitative mapper never uses it).
    pub pose: Pose,
    /// Ideal detections (robot frame).
    pub detections: Vec<Detection>,
    /// The lidar scan, when asked for.
    pub scan: Option<LaserScan>,
}

/// `n` landmarks uniform in a square, rejecting any closer than `min_gap` to an earlier one
/// (so the occlusion study's largest size, 0.7 m, never makes two discs overlap).
fn uniform_landmarks(
    rng: &mut ChaCha8Rng,
    n: usize,
    side: f64,
    radius: f64,
    min_gap: f64,
) -> Vec<PointLandmark> {
    let mut out: Vec<PointLandmark> = Vec::with_capacity(n);
    while out.len() < n {
        let pos = [rng.random_range(0.0..side), rng.random_range(0.0..side)];
        if out
            .iter()
            .all(|l| (l.pos[0] - pos[0]).hypot(l.pos[1] - pos[1]) >= min_gap)
        {
            out.push(PointLandmark {
                id: out.len() as u32,
                pos,
                radius,
            });
        }
    }
    out
}

/// Builds a named scenario from a seed; `world` replaces the generated world when given.
///
/// # Errors
/// [`SimError::UnknownScenario`]; world errors.
pub fn scenario(name: &str, seed: u64, world: Option<WorldSpec>) -> Result<Scenario> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let layout = match name {
        "pqrm-100" => pqrm_100(&mut rng),
        "qlink-200" => qlink_200(&mut rng),
        "hallway" => hallway(),
        "field" => field(&mut rng),
        other => return Err(SimError::UnknownScenario(other.to_owned())),
    };
    let world = World::new(world.unwrap_or(layout.spec))?;
    let bounds = world.spec().bounds;
    Ok(Scenario {
        name: name.to_owned(),
        world,
        start: layout.start,
        waypoints: layout.waypoints,
        speed: layout.speed,
        frame_period: layout.frame_period,
        detector: layout.detector,
        lidar: LidarConfig::default(),
        terrain: if layout.terrain.is_empty() {
            None
        } else {
            Some(Terrain::new(layout.terrain, bounds)?)
        },
    })
}

/// What a named scenario is made of, before its world is built.
struct Layout {
    spec: WorldSpec,
    start: Pose,
    waypoints: Vec<[f64; 2]>,
    speed: f64,
    frame_period: f64,
    detector: DetectorConfig,
    /// The ground's bumps and hollows (none: flat).
    terrain: Vec<Bump>,
}

/// Thesis §2.3: ten landmarks in a 100 m square, a circle driven about its centre, a noisy
/// detector of 60 m range.
fn pqrm_100(rng: &mut ChaCha8Rng) -> Layout {
    let spec = WorldSpec {
        bounds: [0.0, 100.0, 0.0, 100.0],
        landmarks: uniform_landmarks(rng, 10, 100.0, 0.1, 0.0),
        ..WorldSpec::default()
    };
    let pts: Vec<[f64; 2]> = (0..=23)
        .map(|k| (f64::from(k) * 16.0).to_radians())
        .map(|a| [50.0 + 50.0 * a.cos(), 50.0 + 50.0 * a.sin()])
        .collect();
    let step = 2.0 * 50.0 * (8f64.to_radians()).sin(); // chord of 16°
    let det = DetectorConfig {
        range: 60.0,
        full_occlusion: false,
        noise: DetectorNoise::Cartesian { sigma: 5.0 },
    };
    Layout {
        spec,
        start: Pose {
            x: 100.0,
            y: 50.0,
            theta: std::f64::consts::FRAC_PI_2,
        },
        waypoints: pts[1..].to_vec(),
        speed: 2.0,
        frame_period: step / 2.0,
        detector: det,
        terrain: Vec::new(),
    }
}

/// Thesis §4.4.1: 200 landmarks in a 200 m square, a boustrophedon drive, a 20 m detector
/// with full occlusion.
fn qlink_200(rng: &mut ChaCha8Rng) -> Layout {
    let spec = WorldSpec {
        bounds: [0.0, 200.0, 0.0, 200.0],
        landmarks: uniform_landmarks(rng, 200, 200.0, 0.3, 2.0),
        ..WorldSpec::default()
    };
    let mut pts = Vec::new();
    for (i, x) in (0..=10).map(|k| 10.0 + 18.0 * f64::from(k)).enumerate() {
        let (a, b) = if i % 2 == 0 {
            (5.0, 195.0)
        } else {
            (195.0, 5.0)
        };
        pts.push([x, a]);
        pts.push([x, b]);
    }
    let det = DetectorConfig {
        range: 20.0,
        full_occlusion: true,
        noise: DetectorNoise::Cartesian { sigma: 0.3 },
    };
    Layout {
        spec,
        start: Pose {
            x: 10.0,
            y: 0.0,
            theta: std::f64::consts::FRAC_PI_2,
        },
        waypoints: pts,
        speed: 2.0,
        frame_period: 2.0,
        detector: det,
        terrain: Vec::new(),
    }
}

/// Thesis §3.4: two rows of landmarks 6 m apart, a drive down the middle.
fn hallway() -> Layout {
    let mut landmarks = Vec::new();
    for k in 0..20 {
        let x = 3.0 * f64::from(k);
        landmarks.push(PointLandmark {
            id: 2 * k as u32,
            pos: [x, 3.0],
            radius: 0.1,
        });
        landmarks.push(PointLandmark {
            id: 2 * k as u32 + 1,
            pos: [x + 1.5, -3.0],
            radius: 0.1,
        });
    }
    let spec = WorldSpec {
        bounds: [-5.0, 65.0, -6.0, 6.0],
        landmarks,
        ..WorldSpec::default()
    };
    let det = DetectorConfig {
        range: 15.0,
        full_occlusion: false,
        noise: DetectorNoise::Cartesian {
            sigma: 0.1f64.sqrt(),
        },
    };
    Layout {
        spec,
        start: Pose {
            x: -3.0,
            y: 0.0,
            theta: 0.0,
        },
        waypoints: vec![[62.0, 0.0]],
        speed: 1.0,
        frame_period: 1.0,
        detector: det,
        terrain: Vec::new(),
    }
}

/// The field site's landmarks (pines, posts, bins, bollards, trees; overlapping ones
/// removed) and its clutter, drawn in this order from `rng`.
fn field_landmarks(rng: &mut ChaCha8Rng) -> (Vec<PointLandmark>, Vec<Clutter>) {
    let mut landmarks = Vec::new();
    let mut clutter = Vec::new();
    let mut id = 0u32;
    // Dense pines north of the corridor's end.
    for _ in 0..45 {
        landmarks.push(PointLandmark {
            id,
            pos: [rng.random_range(45.0..80.0), rng.random_range(20.0..45.0)],
            radius: rng.random_range(0.15..0.3),
        });
        id += 1;
    }
    // Sparse posts in the open field to the east.
    for _ in 0..8 {
        landmarks.push(PointLandmark {
            id,
            pos: [rng.random_range(90.0..150.0), rng.random_range(-30.0..30.0)],
            radius: 0.2,
        });
        id += 1;
    }
    // Rocks and bushes in the open field: objects that return lidar hits and occlude but
    // are not the site's landmarks (the ground itself is the scenario's `Terrain`).
    for _ in 0..25 {
        clutter.push(Clutter {
            pos: [rng.random_range(90.0..150.0), rng.random_range(-30.0..30.0)],
            radius: rng.random_range(0.3..1.0),
        });
    }
    // Posts and bins in front of the buildings, bollards inside the corridor and a
    // few trees by its far end, so the wall-pair relation has front, between and
    // behind states (drawn last: the pines, posts and clutter above are unchanged).
    let sides = |rng: &mut ChaCha8Rng| if rng.random::<bool>() { 1.0 } else { -1.0 };
    for _ in 0..6 {
        let side = sides(rng);
        landmarks.push(PointLandmark {
            id,
            pos: [
                rng.random_range(-16.0..-2.0),
                side * rng.random_range(9.0..14.0),
            ],
            radius: rng.random_range(0.3..0.45),
        });
        id += 1;
    }
    for k in 0..4 {
        landmarks.push(PointLandmark {
            id,
            pos: [
                rng.random_range(4.0..36.0),
                if k % 2 == 0 { 5.5 } else { -5.5 },
            ],
            radius: 0.3,
        });
        id += 1;
    }
    for _ in 0..5 {
        landmarks.push(PointLandmark {
            id,
            pos: [rng.random_range(44.0..56.0), rng.random_range(-14.0..14.0)],
            radius: rng.random_range(0.25..0.35),
        });
        id += 1;
    }
    // Remove pines overlapping each other (the detector assumes disjoint discs).
    let mut kept: Vec<PointLandmark> = Vec::new();
    for l in landmarks {
        if kept
            .iter()
            .all(|k| (k.pos[0] - l.pos[0]).hypot(k.pos[1] - l.pos[1]) > k.radius + l.radius + 0.5)
        {
            kept.push(l);
        }
    }
    (kept, clutter)
}

/// Thesis §4.4.2: the field site — a corridor between two buildings, pines, posts, clutter,
/// pitched ground.
fn field(rng: &mut ChaCha8Rng) -> Layout {
    let (kept, clutter) = field_landmarks(rng);
    let walls = vec![
        Wall {
            id: 1000,
            start: [0.0, -7.5],
            end: [40.0, -7.5],
        },
        Wall {
            id: 1001,
            start: [0.0, 7.5],
            end: [40.0, 7.5],
        },
    ];
    let spec = WorldSpec {
        bounds: [-20.0, 160.0, -40.0, 50.0],
        landmarks: kept,
        walls,
        clutter,
    };
    let det = DetectorConfig {
        range: 60.0,
        full_occlusion: true,
        noise: DetectorNoise::Cartesian { sigma: 0.7 },
    };
    // The ground (drawn from its own generator so the objects above are unchanged): soft
    // pitched terrain in the open field, a natural basin off the corridor's open end, a
    // gentle roll under the pines; the corridor is paved (flat).
    let mut ground = ChaCha8Rng::seed_from_u64(rng.random::<u64>());
    let mut terrain = Vec::new();
    let signed = |g: &mut ChaCha8Rng, lo: f64, hi: f64| {
        let h: f64 = g.random_range(lo..hi);
        if g.random::<bool>() { h } else { -h }
    };
    for _ in 0..10 {
        terrain.push(Bump {
            centre: [
                ground.random_range(90.0..150.0),
                ground.random_range(-30.0..30.0),
            ],
            sigma: ground.random_range(4.0..10.0),
            height: signed(&mut ground, 0.5, 1.5),
        });
    }
    let side = if ground.random::<bool>() { 1.0 } else { -1.0 };
    terrain.push(Bump {
        centre: [
            ground.random_range(-18.0..-8.0),
            side * ground.random_range(18.0..30.0),
        ],
        sigma: ground.random_range(5.0..8.0),
        height: -ground.random_range(1.0..2.0),
    });
    for _ in 0..6 {
        terrain.push(Bump {
            centre: [
                ground.random_range(45.0..80.0),
                ground.random_range(20.0..45.0),
            ],
            sigma: ground.random_range(3.0..6.0),
            height: signed(&mut ground, 0.2, 0.5),
        });
    }
    let path = vec![
        [40.0, 0.0],
        [60.0, 10.0],
        [85.0, 30.0],
        [110.0, 10.0],
        [140.0, -15.0],
        [120.0, -25.0],
    ];
    Layout {
        spec,
        start: Pose {
            x: -10.0,
            y: 0.0,
            theta: 0.0,
        },
        waypoints: path,
        speed: 1.5,
        frame_period: 1.0,
        detector: det,
        terrain,
    }
}

impl Scenario {
    /// A lidar scan from `pose`: the world's ray casts, and where the scenario's ground rises
    /// into the scan plane, ground returns ([`Terrain::ground_returns`]).
    ///
    /// # Errors
    /// As [`LidarConfig::validate`].
    pub fn scan(
        &self,
        pose: &Pose,
        cfg: &LidarConfig,
        rng: &mut impl rand::Rng,
    ) -> Result<LaserScan> {
        let mut scan = self.world.lidar(pose, cfg, rng)?;
        if let Some(t) = &self.terrain {
            t.ground_returns(pose, cfg, &mut scan, rng)?;
        }
        Ok(scan)
    }

    /// The same scenario with every point landmark's radius set to `radius` (the landmark
    /// size of the occlusion study, thesis §4.4.1: 0.1 to 0.7 m).
    ///
    /// # Errors
    /// [`SimError::Invalid`] for a non-positive radius or one that makes landmarks overlap.
    pub fn with_landmark_radius(self, radius: f64) -> Result<Self> {
        // Named as the field (`landmark_radius`, the CLI's `--landmark-radius`), so the
        // refusal blames the setting, not landmark 0 of the world (issue 39).
        let smallest = crate::world::MIN_WORLD_SIZE / 100.0;
        check(
            radius.is_finite() && (smallest..=crate::world::MAX_WORLD_EXTENT).contains(&radius),
            || {
                format!(
                    "landmark_radius = {radius} m must be finite, at least {smallest} m and at \
                     most {:e} m",
                    crate::world::MAX_WORLD_EXTENT
                )
            },
        )?;
        let mut spec = self.world.spec().clone();
        spec.landmarks.iter_mut().for_each(|l| l.radius = radius);
        for (i, a) in spec.landmarks.iter().enumerate() {
            for b in &spec.landmarks[i + 1..] {
                check(
                    (a.pos[0] - b.pos[0]).hypot(a.pos[1] - b.pos[1]) > 2.0 * radius,
                    || {
                        format!(
                            "landmark_radius = {radius} m makes landmarks {} and {} overlap",
                            a.id, b.id
                        )
                    },
                )?;
            }
        }
        Ok(Self {
            world: World::new(spec)?,
            ..self
        })
    }

    /// Drives the path with a unicycle (pure pursuit, 0.05 s steps) and records a frame every
    /// `frame_period`: detections always, a lidar scan when `lidar` is set. Sensor noise is
    /// drawn from a generator seeded by `seed`.
    ///
    /// # Errors
    /// Sensor configuration errors.
    pub fn run(&self, seed: u64, lidar: bool) -> Result<Vec<Frame>> {
        check(self.speed > 0.0 && self.frame_period > 0.0, || {
            "speed and frame period must be > 0".into()
        })?;
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5e45_0a11);
        let dt = 0.05;
        let mut robot = Unicycle::new(self.start, self.speed, 1.5, dt)?;
        let mut frames = Vec::new();
        let mut t = 0.0;
        let per_frame = (self.frame_period / dt).round().max(1.0) as u64;
        let mut step: u64 = 0;
        let max_steps = 200_000;
        // the step of the last frame: reaching a waypoint on a frame step must not emit the
        // same frame again when the loop moves on to the next waypoint
        let mut last_frame: Option<u64> = None;
        for wp in &self.waypoints {
            loop {
                if step.is_multiple_of(per_frame) && last_frame != Some(step) {
                    last_frame = Some(step);
                    let detections = self.world.detect(&robot.pose, &self.detector, &mut rng)?;
                    let scan = if lidar {
                        Some(self.scan(&robot.pose, &self.lidar, &mut rng)?)
                    } else {
                        None
                    };
                    frames.push(Frame {
                        t,
                        pose: robot.pose,
                        detections,
                        scan,
                    });
                }
                let (dx, dy) = (wp[0] - robot.pose.x, wp[1] - robot.pose.y);
                let dist = dx.hypot(dy);
                if dist < 0.5 || step >= max_steps {
                    break;
                }
                let err = (dy.atan2(dx) - robot.pose.theta + std::f64::consts::PI)
                    .rem_euclid(std::f64::consts::TAU)
                    - std::f64::consts::PI;
                let v = if err.abs() > 1.2 {
                    0.2 * self.speed
                } else {
                    self.speed.min(dist / dt)
                };
                robot.step(v, 2.5 * err);
                t += dt;
                step += 1;
            }
        }
        Ok(frames)
    }
}

/// Writes frames' detections as the observation CSV the mapper reads
/// (`t,robot,landmark,x,y,cxx,cxy,cyy`, robot frame).
///
/// # Errors
/// I/O errors of the writer.
pub fn write_observations_csv(
    frames: &[Frame],
    out: &mut impl std::io::Write,
) -> std::io::Result<()> {
    writeln!(out, "t,robot,landmark,x,y,cxx,cxy,cyy")?;
    for f in frames {
        for d in &f.detections {
            writeln!(
                out,
                "{},0,{},{},{},{},{},{}",
                f.t, d.id, d.xy[0], d.xy[1], d.cov[0][0], d.cov[0][1], d.cov[1][1]
            )?;
        }
    }
    Ok(())
}
