//! Navigation-time perception from the lidar: a sweep, the extractor and identification
//! against the mapping drive's catalogue (see the parent module).

use std::collections::{BTreeMap, BTreeSet, VecDeque};
use std::sync::Mutex;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sim2d::{ExtractorConfig, Hit, LidarConfig, Pose};

use qlink::{Look, Perception};

use super::mapping::{FieldMap, point_and_walls};
use super::{WALL_FRAME_END, WALL_FRAME_START};

/// A landmark the lidar saw at one check.
#[derive(Debug, Clone, Copy)]
struct Seen {
    id: u32,
    pos: [f64; 2],
    /// The object truly is the one the id was most often recognised from during the
    /// mapping drive.
    consistent: bool,
}

/// What the perception keeps between checks.
#[derive(Debug)]
struct LidarState {
    rng: ChaCha8Rng,
    cache: Option<([f64; 2], Look, Vec<Seen>)>,
    last: BTreeMap<u32, Seen>,
    scans: usize,
    detections: usize,
    aliased: usize,
    /// Rays of every scan, and of those the ground took.
    rays: usize,
    ground: usize,
    /// (ground, rays) of the last [`RECENT_SCANS`] scans.
    recent: VecDeque<(usize, usize)>,
}

/// Scans "at the end" of a navigation, for [`LidarPerception::ground_share`]: where a robot
/// that gave up was looking when it did.
pub const RECENT_SCANS: usize = 20;

/// Navigation-time perception from the lidar (see the module docs): the scanner's 270° ahead
/// while the robot drives, a full sweep where it stands; the extractor; triangle
/// identification against the mapping drive's catalogue (frozen: see
/// [`sim2d::TriangleRecognizer::identify`]).
#[derive(Debug)]
pub struct LidarPerception<'m> {
    field: &'m FieldMap,
    /// The scanner as mounted: its field of view ahead of the robot.
    ahead: LidarConfig,
    /// A sweep: the scanner turned through a full circle at the same angular resolution.
    sweep: LidarConfig,
    extractor: ExtractorConfig,
    mapped: BTreeSet<u32>,
    state: Mutex<LidarState>,
}

impl<'m> LidarPerception<'m> {
    /// Perception for one navigation; `seed` drives the scanner's range noise.
    #[must_use]
    pub fn new(field: &'m FieldMap, seed: u64) -> Self {
        let ahead = field.scenario.lidar;
        // the rays a full turn holds at the scanner's own resolution (1,440 for 270°/1,081)
        let resolution = ahead.fov / (ahead.rays.max(2) - 1) as f64;
        let sweep = LidarConfig {
            fov: std::f64::consts::TAU,
            rays: (std::f64::consts::TAU / resolution).round().max(1.0) as usize,
            ..ahead
        };
        Self {
            field,
            ahead,
            sweep,
            extractor: field.extractor,
            mapped: field.map.landmarks().into_iter().collect(),
            state: Mutex::new(LidarState {
                rng: ChaCha8Rng::seed_from_u64(seed),
                cache: None,
                last: BTreeMap::new(),
                scans: 0,
                detections: 0,
                aliased: 0,
                rays: 0,
                ground: 0,
                recent: VecDeque::new(),
            }),
        }
    }

    fn observe(&self, pos: [f64; 2], look: Look) -> Vec<Seen> {
        let Ok(mut st) = self.state.lock() else {
            return Vec::new();
        };
        if let Some((p, l, seen)) = &st.cache
            && *p == pos
            && *l == look
        {
            return seen.clone();
        }
        let (theta, lidar) = match look {
            Look::Sweep => (0.0, &self.sweep),
            Look::Ahead(heading) => (heading, &self.ahead),
        };
        let pose = Pose {
            x: pos[0],
            y: pos[1],
            theta,
        };
        let scan = match self.field.scenario.scan(&pose, lidar, &mut st.rng) {
            Ok(s) => s,
            Err(_) => return Vec::new(),
        };
        st.scans += 1;
        let ground = scan
            .hits
            .iter()
            .filter(|h| **h == Some(Hit::Ground))
            .count();
        st.rays += scan.ranges.len();
        st.ground += ground;
        st.recent.push_back((ground, scan.ranges.len()));
        if st.recent.len() > RECENT_SCANS {
            st.recent.pop_front();
        }
        let width = self.field.walls.map(|m| m.width);
        let (cands, walls) = point_and_walls(&scan, &self.extractor, lidar, width);
        let ids = self
            .field
            .recognizer
            .identify(&cands.iter().map(|c| c.centre).collect::<Vec<_>>());
        let mut seen: Vec<Seen> = Vec::new();
        for (c, id) in cands.iter().zip(ids) {
            let Some(id) = id else { continue };
            if !self.mapped.contains(&id) || seen.iter().any(|s| s.id == id) {
                continue;
            }
            let consistent = c.truth.is_some() && self.field.truth.get(&id) == c.truth.as_ref();
            st.detections += 1;
            if !consistent {
                st.aliased += 1;
            }
            seen.push(Seen {
                id,
                pos: pose.to_world(c.centre),
                consistent,
            });
        }
        if let (Some(sighting), Some(model)) = (walls, self.field.walls) {
            let frame = sighting.frame(&pose, model.heading, model.length);
            for (id, p) in [WALL_FRAME_START, WALL_FRAME_END].into_iter().zip(frame) {
                seen.push(Seen {
                    id,
                    pos: pose.to_world(p),
                    consistent: true,
                });
            }
        }
        seen.sort_by_key(|s| s.id);
        for s in &seen {
            st.last.insert(s.id, *s);
        }
        st.cache = Some((pos, look, seen.clone()));
        seen
    }

    /// Whether the last detection of `id` truly was the object it was mapped from.
    #[must_use]
    pub fn last_consistent(&self, id: u32) -> Option<bool> {
        self.state
            .lock()
            .ok()
            .and_then(|s| s.last.get(&id).map(|x| x.consistent))
    }

    /// The share of the scans' rays that met the ground: over every scan, and over the last
    /// `RECENT_SCANS`.
    #[must_use]
    pub fn ground_share(&self) -> (f64, f64) {
        self.state
            .lock()
            .map(|s| {
                let (g, r) = s
                    .recent
                    .iter()
                    .fold((0, 0), |(g, r), &(a, b)| (g + a, r + b));
                (
                    s.ground as f64 / s.rays.max(1) as f64,
                    g as f64 / r.max(1) as f64,
                )
            })
            .unwrap_or((0.0, 0.0))
    }

    /// (scans, detections of mapped ids, detections on the wrong object).
    #[must_use]
    pub fn counts(&self) -> (usize, usize, usize) {
        self.state
            .lock()
            .map(|s| (s.scans, s.detections, s.aliased))
            .unwrap_or((0, 0, 0))
    }
}

impl Perception for LidarPerception<'_> {
    /// The last measured position of `id` (where the robot saw it, not the simulator's).
    fn position(&self, id: u32) -> Option<[f64; 2]> {
        self.state
            .lock()
            .ok()
            .and_then(|s| s.last.get(&id).map(|x| x.pos))
    }
    /// From a standing robot: a sweep.
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.sees_looking(pos, Look::Sweep, id)
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        self.visible_looking(pos, Look::Sweep)
    }
    fn sees_looking(&self, pos: [f64; 2], look: Look, id: u32) -> bool {
        self.observe(pos, look).iter().any(|s| s.id == id)
    }
    fn visible_looking(&self, pos: [f64; 2], look: Look) -> Vec<u32> {
        self.observe(pos, look).iter().map(|s| s.id).collect()
    }
    fn ids(&self) -> Vec<u32> {
        self.mapped.iter().copied().collect()
    }
    /// The *effective* range: the median distance at which the mapping drive recognised
    /// landmarks (the scanner reaches 30 m, but a trunk is a landmark candidate only when
    /// close; search circles at the scanner's range would lose every reference).
    fn range(&self) -> f64 {
        self.field.stats.effective_range
    }
}
