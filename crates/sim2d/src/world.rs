//! [`World`]: static rapier2d colliders for point landmarks (discs), walls (segments) and
//! clutter (discs that occlude but are not landmarks), with ray casts and exact occlusion
//! queries through rapier's query pipeline.
//!
//! rapier2d works in `f32`: ranges are exact to about 1e-6 relative (a few millimetres at
//! 200 m), far below any simulated sensor noise.

use rapier2d::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{Result, SimError, check};

/// A point landmark: a disc whose radius is its "size" (thesis §4.4.1).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointLandmark {
    /// Identity (what an ideal detector reports).
    pub id: u32,
    /// Centre (m).
    pub pos: [f64; 2],
    /// Radius (m), > 0.
    pub radius: f64,
}

/// A wall: an oriented extended landmark from `start` to `end`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Wall {
    /// Identity.
    pub id: u32,
    /// First end point (m).
    pub start: [f64; 2],
    /// Second end point (m).
    pub end: [f64; 2],
}

/// Clutter: occludes and returns lidar hits but is not a landmark (bushes, ground returns).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Clutter {
    /// Centre (m).
    pub pos: [f64; 2],
    /// Radius (m), > 0.
    pub radius: f64,
}

/// Everything static in a world, as a world file (TOML) holds it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// `[x_min, x_max, y_min, y_max]` of the area of interest (for drawing and scenarios).
    pub bounds: [f64; 4],
    /// Point landmarks.
    #[serde(default, rename = "landmark")]
    pub landmarks: Vec<PointLandmark>,
    /// Walls.
    #[serde(default, rename = "wall")]
    pub walls: Vec<Wall>,
    /// Clutter.
    #[serde(default)]
    pub clutter: Vec<Clutter>,
}

impl WorldSpec {
    /// Parses a TOML world file (not yet validated: [`World::new`] does that).
    ///
    /// # Errors
    /// [`SimError::World`] led by the field's path (`wall[0].id: invalid value: integer -1,
    /// expected u32`): a TOML error alone shows the line but not which entity it belongs to
    /// (issue 39).
    pub fn from_toml(text: &str) -> Result<Self> {
        let de = toml::Deserializer::parse(text).map_err(|e| SimError::World(e.to_string()))?;
        serde_path_to_error::deserialize(de).map_err(|e| {
            let path = e.path().to_string();
            let why = e.into_inner();
            // `.` is the whole file: no field to name
            SimError::World(if path == "." {
                why.to_string()
            } else {
                format!("{path}: {why}")
            })
        })
    }
}

/// What a ray or a query hit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Hit {
    /// The i-th point landmark.
    Landmark(usize),
    /// The i-th wall.
    Wall(usize),
    /// The i-th clutter disc.
    Clutter(usize),
    /// The ground (see [`crate::Terrain`]): a lidar ray that met the terrain.
    Ground,
}

impl Hit {
    fn encode(self) -> u128 {
        match self {
            Self::Landmark(i) => i as u128,
            Self::Wall(i) => (1u128 << 64) | i as u128,
            Self::Clutter(i) => (2u128 << 64) | i as u128,
            Self::Ground => 3u128 << 64,
        }
    }

    fn decode(v: u128) -> Self {
        let i = (v & u128::from(u64::MAX)) as usize;
        match v >> 64 {
            0 => Self::Landmark(i),
            1 => Self::Wall(i),
            2 => Self::Clutter(i),
            _ => Self::Ground,
        }
    }
}

/// A world: its spec plus the rapier structures that answer geometric queries.
pub struct World {
    spec: WorldSpec,
    bodies: RigidBodySet,
    colliders: ColliderSet,
    broad_phase: BroadPhaseBvh,
    narrow_phase: NarrowPhase,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("spec", &self.spec)
            .finish_non_exhaustive()
    }
}

fn v(p: [f64; 2]) -> Vector {
    Vector::new(p[0] as f32, p[1] as f32)
}

/// How far from the origin a world's bounds, landmarks and walls may lie (m).
pub const MAX_WORLD_EXTENT: f64 = 1e5;

/// The smallest width and height of a world's bounds (m).
pub const MIN_WORLD_SIZE: f64 = 0.01;

impl World {
    /// Builds and validates a world.
    ///
    /// # Errors
    /// [`SimError::Invalid`] for non-finite numbers, non-positive radii, zero-length walls,
    /// empty bounds or duplicate landmark/wall ids.
    pub fn new(spec: WorldSpec) -> Result<Self> {
        check_extent(&spec)?;
        check_entities(&spec)?;
        let (colliders, handles) = colliders_of(&spec);
        let bodies = RigidBodySet::new();
        let mut broad_phase = BroadPhaseBvh::new();
        let mut events = Vec::new();
        broad_phase.update(
            &IntegrationParameters::default(),
            &colliders,
            &bodies,
            &handles,
            &[],
            &mut events,
        );
        Ok(Self {
            spec,
            bodies,
            colliders,
            broad_phase,
            narrow_phase: NarrowPhase::new(),
        })
    }

    /// Parses and validates a TOML world file.
    ///
    /// # Errors
    /// [`SimError::World`] for TOML errors, then as [`World::new`].
    pub fn from_toml(text: &str) -> Result<Self> {
        Self::new(WorldSpec::from_toml(text)?)
    }

    /// The spec.
    #[must_use]
    pub fn spec(&self) -> &WorldSpec {
        &self.spec
    }

    /// Every landmark as `(id, centre)`, in the spec's order: what a perception, a truth file
    /// or a plot needs of them.
    pub fn landmark_positions(&self) -> impl Iterator<Item = (u32, [f64; 2])> + '_ {
        self.spec.landmarks.iter().map(|l| (l.id, l.pos))
    }

    fn pipeline(&self) -> QueryPipeline<'_> {
        self.broad_phase.as_query_pipeline(
            self.narrow_phase.query_dispatcher(),
            &self.bodies,
            &self.colliders,
            QueryFilter::default(),
        )
    }

    /// First hit of the ray from `origin` along `angle` (radians, world frame) within
    /// `max_range`: the distance and what was hit.
    #[must_use]
    pub fn cast_ray(&self, origin: [f64; 2], angle: f64, max_range: f64) -> Option<(f64, Hit)> {
        self.cast_rays(origin, std::iter::once(angle), max_range)
            .pop()
            .flatten()
    }

    /// Many rays from one origin (one query pipeline for all of them).
    pub(crate) fn cast_rays(
        &self,
        origin: [f64; 2],
        angles: impl Iterator<Item = f64>,
        max_range: f64,
    ) -> Vec<Option<(f64, Hit)>> {
        let pipeline = self.pipeline();
        angles
            .map(|a| {
                let ray = Ray::new(v(origin), Vector::new(a.cos() as f32, a.sin() as f32));
                let (h, toi) = pipeline.cast_ray(&ray, max_range as f32, true)?;
                Some((
                    f64::from(toi),
                    Hit::decode(self.colliders.get(h)?.user_data),
                ))
            })
            .collect()
    }

    /// Whether every point of landmark `index`'s disc can be seen from `sensor`: no other
    /// collider meets the region between the sensor and the disc, the "full occlusion" of
    /// thesis §4.4.1.
    ///
    /// The sight lines to a disc fill the convex hull of the sensor and the disc. Its part in
    /// front of the disc lies in the triangle (sensor, tangent point, tangent point); the rest
    /// of that triangle (behind the near arc, before the chord) is inside the disc, where no
    /// other collider of a non-overlapping world can be. So the test is one shape query of
    /// that triangle against the world, ignoring the landmark itself.
    #[must_use]
    pub fn is_fully_visible(&self, sensor: [f64; 2], index: usize) -> bool {
        let Some(l) = self.spec.landmarks.get(index) else {
            return false;
        };
        let (dx, dy) = (l.pos[0] - sensor[0], l.pos[1] - sensor[1]);
        let d = dx.hypot(dy);
        if d <= l.radius {
            return true; // the sensor is inside the landmark: nothing can be between
        }
        let centre_angle = dy.atan2(dx);
        let beta = (l.radius / d).acos(); // at the centre, between the sensor and a tangent point
        let tangent = |sign: f64| {
            let a = centre_angle + std::f64::consts::PI + sign * beta;
            Vector::new(
                (dx + l.radius * a.cos()) as f32,
                (dy + l.radius * a.sin()) as f32,
            )
        };
        let triangle = SharedShape::triangle(Vector::ZERO, tangent(1.0), tangent(-1.0));
        let pose = Pose::from_translation(v(sensor));
        let pipeline = self.pipeline();
        let blocked = pipeline
            .intersect_shape(pose, triangle.as_ref())
            .any(|(_, c)| Hit::decode(c.user_data) != Hit::Landmark(index));
        !blocked
    }
}

/// Bounds, landmarks and walls within [`MAX_WORLD_EXTENT`], bounds at least
/// [`MIN_WORLD_SIZE`] wide and high: rapier works in f32 and the pictures in pixels, so a
/// world of 1e30 m, or one narrower than a centimetre, has no meaningful simulation (and
/// used to hang the plot).
fn check_extent(spec: &WorldSpec) -> Result<()> {
    let [x0, x1, y0, y1] = spec.bounds;
    check(
        spec.bounds.iter().all(|b| b.is_finite()) && x1 > x0 && y1 > y0,
        || format!("bounds {:?} must be finite with min < max", spec.bounds),
    )?;
    let inside = |v: f64| v.abs() <= MAX_WORLD_EXTENT;
    check(
        spec.bounds.iter().all(|b| inside(*b))
            && x1 - x0 >= MIN_WORLD_SIZE
            && y1 - y0 >= MIN_WORLD_SIZE,
        || {
            format!(
                "bounds {:?} must lie within ±{MAX_WORLD_EXTENT:e} m and be at least \
                 {MIN_WORLD_SIZE} m wide and high",
                spec.bounds
            )
        },
    )?;
    let sized = |pos: &[f64; 2], r: f64| {
        pos.iter().all(|c| inside(*c)) && (MIN_WORLD_SIZE / 100.0..=MAX_WORLD_EXTENT).contains(&r)
    };
    for l in &spec.landmarks {
        check(
            sized(&l.pos, l.radius) || !l.radius.is_finite() || l.radius <= 0.0,
            || {
                format!(
                    "landmark {}: position {:?} and radius {} must lie within ±{MAX_WORLD_EXTENT:e} m \
                 (radius at least {} m)",
                    l.id,
                    l.pos,
                    l.radius,
                    MIN_WORLD_SIZE / 100.0
                )
            },
        )?;
    }
    // Clutter too (issue 39: a clutter disc of radius 1e39 or 2³² m was accepted, and the
    // simulation ran for minutes).
    for (i, c) in spec.clutter.iter().enumerate() {
        check(
            sized(&c.pos, c.radius) || !c.radius.is_finite() || c.radius <= 0.0,
            || {
                format!(
                    "clutter {i}: position {:?} and radius {} must lie within \
                     ±{MAX_WORLD_EXTENT:e} m (radius at least {} m)",
                    c.pos,
                    c.radius,
                    MIN_WORLD_SIZE / 100.0
                )
            },
        )?;
    }
    for w in &spec.walls {
        check(
            w.start
                .iter()
                .chain(&w.end)
                .all(|c| !c.is_finite() || inside(*c)),
            || {
                format!(
                    "wall {}: end points must lie within ±{MAX_WORLD_EXTENT:e} m",
                    w.id
                )
            },
        )?;
    }
    Ok(())
}

/// Finite positions, positive radii, walls of non-zero length, ids used once.
fn check_entities(spec: &WorldSpec) -> Result<()> {
    let mut ids = std::collections::BTreeSet::new();
    for l in &spec.landmarks {
        check(
            l.pos.iter().all(|c| c.is_finite()) && l.radius.is_finite(),
            || format!("landmark {}: non-finite position or radius", l.id),
        )?;
        check(l.radius > 0.0, || {
            format!("landmark {}: radius {} must be > 0", l.id, l.radius)
        })?;
        check(ids.insert(l.id), || {
            format!("landmark id {} is used twice", l.id)
        })?;
    }
    for w in &spec.walls {
        check(w.start.iter().chain(&w.end).all(|c| c.is_finite()), || {
            format!("wall {}: non-finite end point", w.id)
        })?;
        check(
            (w.start[0] - w.end[0]).hypot(w.start[1] - w.end[1]) > 1e-6,
            || format!("wall {} has zero length", w.id),
        )?;
        check(ids.insert(w.id), || {
            format!("wall id {} is also used by another landmark or wall", w.id)
        })?;
    }
    for (i, c) in spec.clutter.iter().enumerate() {
        check(
            c.pos.iter().all(|x| x.is_finite()) && c.radius.is_finite() && c.radius > 0.0,
            || format!("clutter {i}: needs a finite position and a radius > 0"),
        )?;
    }
    Ok(())
}

/// The world's colliders (landmarks, walls, clutter, each tagged with what it is) and their
/// handles, in that order.
fn colliders_of(spec: &WorldSpec) -> (ColliderSet, Vec<ColliderHandle>) {
    let mut colliders = ColliderSet::new();
    let mut handles = Vec::new();
    for (i, l) in spec.landmarks.iter().enumerate() {
        handles.push(
            colliders.insert(
                ColliderBuilder::ball(l.radius as f32)
                    .translation(v(l.pos))
                    .user_data(Hit::Landmark(i).encode())
                    .build(),
            ),
        );
    }
    for (i, w) in spec.walls.iter().enumerate() {
        handles.push(
            colliders.insert(
                ColliderBuilder::segment(v(w.start), v(w.end))
                    .user_data(Hit::Wall(i).encode())
                    .build(),
            ),
        );
    }
    for (i, c) in spec.clutter.iter().enumerate() {
        handles.push(
            colliders.insert(
                ColliderBuilder::ball(c.radius as f32)
                    .translation(v(c.pos))
                    .user_data(Hit::Clutter(i).encode())
                    .build(),
            ),
        );
    }
    (colliders, handles)
}
