//! Navigation-time perception from the lidar: a sweep, the extractor and identification
//! against the mapping drive's catalogue (see the parent module).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Mutex;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use sim2d::{ExtractorConfig, LidarConfig, Pose};

use qlink::Perception;

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
    cache: Option<([f64; 2], Vec<Seen>)>,
    last: BTreeMap<u32, Seen>,
    scans: usize,
    detections: usize,
    aliased: usize,
}

/// Navigation-time perception from the lidar (see the module docs): a full sweep, the
/// extractor, and triangle identification against the mapping drive's catalogue (frozen:
/// see [`sim2d::TriangleRecognizer::identify`]).
#[derive(Debug)]
pub struct LidarPerception<'m> {
    field: &'m FieldMap,
    lidar: LidarConfig,
    extractor: ExtractorConfig,
    mapped: BTreeSet<u32>,
    state: Mutex<LidarState>,
}

impl<'m> LidarPerception<'m> {
    /// Perception for one navigation; `seed` drives the scanner's range noise.
    #[must_use]
    pub fn new(field: &'m FieldMap, seed: u64) -> Self {
        let lidar = LidarConfig {
            fov: std::f64::consts::TAU,
            rays: 1440,
            ..field.scenario.lidar
        };
        Self {
            field,
            lidar,
            extractor: ExtractorConfig::default(),
            mapped: field.map.landmarks().into_iter().collect(),
            state: Mutex::new(LidarState {
                rng: ChaCha8Rng::seed_from_u64(seed),
                cache: None,
                last: BTreeMap::new(),
                scans: 0,
                detections: 0,
                aliased: 0,
            }),
        }
    }

    fn observe(&self, pos: [f64; 2]) -> Vec<Seen> {
        let Ok(mut st) = self.state.lock() else {
            return Vec::new();
        };
        if let Some((p, seen)) = &st.cache
            && *p == pos
        {
            return seen.clone();
        }
        let pose = Pose {
            x: pos[0],
            y: pos[1],
            theta: 0.0,
        };
        let world = &self.field.scenario.world;
        let scan = match world.lidar(&pose, &self.lidar, &mut st.rng) {
            Ok(s) => s,
            Err(_) => return Vec::new(),
        };
        st.scans += 1;
        let (cands, walls) = point_and_walls(&scan, &self.extractor);
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
                pos: [pos[0] + c.centre[0], pos[1] + c.centre[1]],
                consistent,
            });
        }
        if walls {
            for (id, p) in [WALL_FRAME_START, WALL_FRAME_END]
                .into_iter()
                .zip(self.field.wall_frame)
            {
                seen.push(Seen {
                    id,
                    pos: p,
                    consistent: true,
                });
            }
        }
        seen.sort_by_key(|s| s.id);
        for s in &seen {
            st.last.insert(s.id, *s);
        }
        st.cache = Some((pos, seen.clone()));
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
    fn sees(&self, pos: [f64; 2], id: u32) -> bool {
        self.observe(pos).iter().any(|s| s.id == id)
    }
    fn visible(&self, pos: [f64; 2]) -> Vec<u32> {
        self.observe(pos).iter().map(|s| s.id).collect()
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
