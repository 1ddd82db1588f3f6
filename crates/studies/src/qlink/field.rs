//! The field-site experiment of thesis §4.4.2, in simulation: a map made with nothing but a
//! lidar, navigated with nothing but that lidar.
//!
//! **Mapping.** The sim2d `field` scenario's teleop-like drive. Every scan goes through the
//! realistic extractor (two-pass clustering, the 10–50-return rule, circle fits; sim2d's
//! [`extract`]) and the [`TriangleRecognizer`]: landmarks get the recogniser's ids, never the
//! world's — clutter recognised as a landmark is in the map as it would be on a real robot.
//! Detections are modelled as N(0, 0.7) as in the thesis. Two layers make a hybrid map:
//!
//! - **point triplets** with the flip-flop calculus (`left-right`);
//! - **wall pairs + one point** with front / between / behind. The two walls of the corridor
//!   are the reference; their extended frame (qsr-core's `ExtendedFrame`: origin at the
//!   midpoint of the walls' start points, (0, 1) at the midpoint of their end points) is a
//!   ternary frame over two *virtual landmarks*, [`WALL_FRAME_START`] and [`WALL_FRAME_END`],
//!   so the layer is an ordinary PQRM over triplets `(S, E, P)` with the same partition
//!   written for a ternary frame. The walls are oriented from the field towards the front
//!   of the buildings, so "behind" is the pines and the open field, "front" the posts by the
//!   entrance, as in the thesis. The robot perceives the frame when the extractor finds both
//!   walls as wall candidates; which wall is which is taken as known (the thesis's walls are
//!   an apartment building and artificial walls, which look nothing alike), and the frame's
//!   points come from the walls' true end points — the extractor sees only the visible
//!   stretch of a wall, not where it ends.
//!
//! **Navigation.** [`LidarPerception`] is the same pipeline at navigation time: at every
//! check the robot sweeps a full circle with the scanner, extracts candidates and recognises
//! them against the catalogue the mapping drive built (it keeps learning, as it would).
//! A landmark is *seen* when the recogniser gives a candidate an id that is in the map, and
//! its position is the extracted centre. Recognition can be wrong — that is perceptual
//! aliasing, and the robot then measures and drives relative to the wrong object. Short
//! effective range comes for free: a 0.2 m trunk gives 10 returns only within ≈ 9 m.
//!
//! β = 2, −log P(success) edge costs from horizon-4 POMDPs with direct transitions, the
//! midpoint-and-sweep controller, contingency re-planning. Arrival needs the goal landmark
//! itself ([`NavConfig::find_goal`]): having reached the frame of an element holding the
//! goal, the robot searches for the goal in that frame with the POMDP (the map's relation
//! says where it is); an element in whose frame the goal is not found is given up and the
//! robot re-plans to another. A trial succeeds when the object the robot took for the goal
//! truly is the goal (checked against the simulator); it then drives to the element's
//! centroid.
//! Failures are classified as the thesis does: *perceptual aliasing* (the goal element was
//! reached but on the wrong object) and *insufficient features* (nothing to localise or
//! re-plan from), with the runs where aliasing also happened on the way marked.
//!
//! **Improvements** ([`FieldVariant`]), the two the thesis proposes: the safe-search
//! controller (covers the target state while keeping the references within the extractor's
//! *effective* range, measured from the mapping drive), and visibility-aware edge costs
//! (each link's detection probability in its POMDP is how often the mapping drive
//! recognised that landmark when it was within effective range, instead of one value for
//! every landmark).

use std::collections::{BTreeMap, BTreeSet};
use std::sync::Mutex;

use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::progress::Progress;
use qsr_core::{Calculus, FrameKind};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use sim2d::{
    CandidateKind, ExtractorConfig, Hit, LidarConfig, Pose, TriangleRecognizer, World, extract,
};

use qlink::graph::pomdp_cost;
use qlink::{
    BoundCheck, Controller, ControllerKind, CostModel, Failure, Geometry, Layer, LinkGraph,
    NavConfig, NavOutcome, Navigator, Perception, QlinkError, QualitativeMap, SearchPomdp,
};

use crate::error::{Result, StudyError};

/// Virtual landmark id of the walls' frame origin (midpoint of the walls' start points).
pub const WALL_FRAME_START: u32 = 1_000_000;
/// Virtual landmark id of the walls' frame end (midpoint of the walls' end points).
pub const WALL_FRAME_END: u32 = 1_000_001;

/// Settings of the field experiment.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldParams {
    /// Seed of the world, the drive and the trials.
    pub seed: u64,
    /// Navigation trials (random start and goal) per variant.
    pub trials: usize,
    /// PQRM samples per landmark per step.
    pub samples: usize,
    /// Detection noise of the map (m): N(0, σ) per axis, 0.7 in §4.4.2.
    pub sigma: f64,
    /// Side-length tolerance of the triangle recogniser (m).
    pub tolerance: f64,
    /// Matching triangles the recogniser needs to accept a known id.
    pub min_votes: u32,
    /// Range noise of the scanner (m, 1 σ; the UTM-30LX is specified to ±30 mm).
    pub range_sigma: f64,
    /// Scans a triplet (or a landmark, for the wall layer) must be seen in to become a map
    /// element: one-off co-observations are dropped.
    pub min_observations: usize,
    /// Landmarks two elements must share for a link (2 in §4.4.2).
    pub beta: usize,
    /// POMDP horizon (4 in §4.4.2).
    pub horizon: usize,
    /// Most contingency re-plans per trial.
    pub max_replans: usize,
    /// Distance between perception checks along a path (m).
    pub step: f64,
}

impl FieldParams {
    /// The full experiment: 200 trials per variant.
    #[must_use]
    pub fn full(seed: u64) -> Self {
        Self {
            seed,
            trials: 200,
            samples: 300,
            sigma: 0.7,
            tolerance: 0.15,
            min_votes: 2,
            range_sigma: 0.02,
            min_observations: 3,
            beta: 2,
            horizon: 4,
            max_replans: 3,
            step: 1.0,
        }
    }

    /// A quick run for tests: 12 trials per variant, coarser checks.
    #[must_use]
    pub fn quick(seed: u64) -> Self {
        Self {
            trials: 12,
            samples: 100,
            step: 2.0,
            ..Self::full(seed)
        }
    }

    fn validate(&self) -> Result<()> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.trials == 0 || self.samples == 0 || self.horizon == 0 {
            return Err(StudyError::InvalidParameter(
                "trials, samples and horizon must be ≥ 1".into(),
            ));
        }
        if !(self.range_sigma.is_finite() && self.range_sigma >= 0.0) {
            return Err(StudyError::InvalidParameter(format!(
                "range noise {} m must be ≥ 0",
                self.range_sigma
            )));
        }
        if !positive(self.sigma) || !positive(self.tolerance) || !positive(self.step) {
            return Err(StudyError::InvalidParameter(format!(
                "σ = {}, tolerance = {} and step = {} must be positive",
                self.sigma, self.tolerance, self.step
            )));
        }
        Ok(())
    }
}

/// The navigation variants: the thesis's set-up and the improvements it proposes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FieldVariant {
    /// Midpoint-and-sweep, one detection probability for every link (§4.4.2).
    Thesis,
    /// The safe-search controller instead of midpoint-and-sweep.
    SafeSearch,
    /// Visibility-aware edge costs.
    VisibilityCosts,
    /// Both improvements.
    #[serde(rename = "safe-search+visibility-costs")]
    Both,
}

impl FieldVariant {
    /// Every variant, in report order.
    pub const ALL: [Self; 4] = [
        Self::Thesis,
        Self::SafeSearch,
        Self::VisibilityCosts,
        Self::Both,
    ];

    /// Its name in files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Thesis => "thesis",
            Self::SafeSearch => "safe-search",
            Self::VisibilityCosts => "visibility-costs",
            Self::Both => "safe-search+visibility-costs",
        }
    }

    fn safe_search(self) -> bool {
        matches!(self, Self::SafeSearch | Self::Both)
    }

    fn visibility_costs(self) -> bool {
        matches!(self, Self::VisibilityCosts | Self::Both)
    }
}

/// Figures of the mapping drive.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MappingStats {
    /// Scans processed.
    pub frames: usize,
    /// Distinct recogniser ids in the map.
    pub mapped_ids: usize,
    /// Of those, ids most often recognised from a real landmark.
    pub real_landmarks: usize,
    /// Of those, ids most often recognised from clutter (ground returns) or a wall.
    pub false_landmarks: usize,
    /// Landmarks in the world.
    pub world_landmarks: usize,
    /// Point detections during mapping.
    pub detections: usize,
    /// Detections whose object differs from the one their id was most often recognised from.
    pub aliased_detections: usize,
    /// Scans in which both walls were extracted.
    pub wall_frames: usize,
    /// Elements of the point-triplet layer.
    pub point_elements: usize,
    /// Elements of the wall layer.
    pub wall_elements: usize,
    /// Median distance at which landmarks were recognised during the drive (m): the range
    /// the navigating robot searches with.
    pub effective_range: f64,
}

/// The map the robot made of the field site, with what the simulation needs to score it.
#[derive(Debug)]
pub struct FieldMap {
    /// The scenario.
    pub scenario: sim2d::Scenario,
    /// The mapping drive's true poses (for pictures; the mapper never uses them).
    pub drive: Vec<[f64; 2]>,
    /// The hybrid map: layer 0 point triplets (`left-right`), layer 1 walls + point.
    pub map: QualitativeMap,
    /// The recogniser's catalogue after the drive.
    pub recognizer: TriangleRecognizer,
    /// Ground truth: the object each recogniser id was most often recognised from.
    pub truth: BTreeMap<u32, Hit>,
    /// Ground truth: every object each id was recognised from during the drive, with counts.
    pub recognitions: BTreeMap<u32, Vec<(Hit, usize)>>,
    /// Per mapped id: fraction of the drive's scans within effective range in which it was
    /// recognised.
    pub visibility: BTreeMap<u32, f64>,
    /// The walls' frame: world positions of [`WALL_FRAME_START`] and [`WALL_FRAME_END`].
    pub wall_frame: [[f64; 2]; 2],
    /// Figures.
    pub stats: MappingStats,
}

/// The front / between / behind partition written for a ternary frame over the walls'
/// virtual frame points (identical regions: the extended frame *is* the ternary frame of
/// those two points).
///
/// # Errors
/// Calculus errors (none for the built-in spec).
pub fn wall_calculus() -> Result<Calculus> {
    let mut spec = qsr_core::builtin_spec("front-between-behind")?;
    spec.frame = FrameKind::Ternary;
    spec.name = "front-between-behind-ternary".into();
    Ok(Calculus::from_spec(spec)?)
}

/// The walls' frame points: the walls run from the open end of the corridor (x = 0) to the
/// pines (x = 40) in the scenario; the frame starts at the pines' end so that the pines and
/// the open field are "behind" and the entrance "front" (thesis §4.4.2).
fn wall_frame(world: &World) -> Result<[[f64; 2]; 2]> {
    let walls = &world.spec().walls;
    let [w1, w2] = walls.as_slice() else {
        return Err(StudyError::InvalidParameter(format!(
            "the field experiment needs exactly two walls, the world has {}",
            walls.len()
        )));
    };
    let mid = |a: [f64; 2], b: [f64; 2]| [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
    Ok([mid(w1.end, w2.end), mid(w1.start, w2.start)])
}

/// Point candidates and whether both walls were extracted, from one scan.
fn point_and_walls(
    scan: &sim2d::LaserScan,
    cfg: &ExtractorConfig,
) -> (Vec<sim2d::Candidate>, bool) {
    let cands = extract(scan, cfg);
    let wall_seen = |i: usize| {
        cands
            .iter()
            .any(|c| c.kind == CandidateKind::Wall && c.truth == Some(Hit::Wall(i)))
    };
    let both = wall_seen(0) && wall_seen(1);
    let points = cands
        .into_iter()
        .filter(|c| c.kind == CandidateKind::Point)
        .collect();
    (points, both)
}

/// Every triplet of a scan's observations: its sorted ids and the three observations.
fn triplets(obs: &[Observation]) -> impl Iterator<Item = ([u32; 3], [Observation; 3])> + '_ {
    obs.iter().enumerate().flat_map(move |(i, a)| {
        obs.iter().enumerate().skip(i + 1).flat_map(move |(j, b)| {
            obs[j + 1..].iter().map(move |c| {
                let mut k = [a.id.0, b.id.0, c.id.0];
                k.sort_unstable();
                (k, [*a, *b, *c])
            })
        })
    })
}

/// Maps the field site with the lidar (see the module docs).
///
/// # Errors
/// Simulation and mapping errors; [`QlinkError::EmptyMap`] when no scan recognised three
/// landmarks at once.
pub fn map_field(params: &FieldParams) -> Result<FieldMap> {
    params.validate()?;
    let mut scenario = sim2d::scenario("field", params.seed, None)?;
    scenario.lidar.range_sigma = params.range_sigma;
    let frames = scenario.run(params.seed, true)?;
    let frame_pts = wall_frame(&scenario.world)?;
    let extractor = ExtractorConfig::default();
    let mut recognizer = TriangleRecognizer::new(params.tolerance).with_min_votes(params.min_votes);
    let var = params.sigma * params.sigma;
    let cov = [[var, 0.0], [0.0, var]];
    let config = PqrmConfig {
        samples: params.samples,
        seed: params.seed,
        ..PqrmConfig::default()
    };
    // pass 1: recognise every scan; what each id was seen as (for scoring only)
    let mut hits: BTreeMap<u32, Vec<(Hit, usize)>> = BTreeMap::new();
    // per id: (frame, world position estimate)
    let mut seen_at: BTreeMap<u32, Vec<(usize, [f64; 2])>> = BTreeMap::new();
    let mut distances: Vec<f64> = Vec::new();
    let (mut detections, mut wall_frames) = (0usize, 0usize);
    let mut drive = Vec::with_capacity(frames.len());
    // per frame: its observations (unique ids) and whether both walls were extracted
    let mut per_frame: Vec<(f64, Vec<Observation>, bool, Pose)> = Vec::new();
    for (fi, f) in frames.iter().enumerate() {
        drive.push([f.pose.x, f.pose.y]);
        let Some(scan) = &f.scan else { continue };
        let (cands, walls) = point_and_walls(scan, &extractor);
        let ids = recognizer.recognise(&cands.iter().map(|c| c.centre).collect::<Vec<_>>());
        let mut obs = Vec::new();
        let mut unique = BTreeSet::new();
        let (s, c) = f.pose.theta.sin_cos();
        for (cand, &id) in cands.iter().zip(&ids) {
            detections += 1;
            if let Some(h) = cand.truth {
                let list = hits.entry(id).or_default();
                match list.iter_mut().find(|(k, _)| *k == h) {
                    Some((_, n)) => *n += 1,
                    None => list.push((h, 1)),
                }
            }
            if !unique.insert(id) {
                continue;
            }
            let [x, y] = cand.centre;
            let world = [f.pose.x + c * x - s * y, f.pose.y + s * x + c * y];
            seen_at.entry(id).or_default().push((fi, world));
            distances.push(x.hypot(y));
            obs.push(Observation::new(LandmarkId(id), cand.centre, cov)?);
        }
        if walls {
            wall_frames += 1;
        }
        per_frame.push((f.t, obs, walls, f.pose));
    }
    // an id stands for the object it was most often recognised from
    let truth: BTreeMap<u32, Hit> = hits
        .iter()
        .filter_map(|(&id, list)| list.iter().max_by_key(|x| x.1).map(|(h, _)| (id, *h)))
        .collect();
    let aliased: usize = hits
        .iter()
        .map(|(id, list)| {
            list.iter()
                .filter(|(h, _)| truth.get(id) != Some(h))
                .map(|(_, n)| n)
                .sum::<usize>()
        })
        .sum();
    // pass 2: the layers, from triplets (and landmarks) seen often enough
    let mut count: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    for (_, obs, _, _) in &per_frame {
        for (k, _) in triplets(obs) {
            *count.entry(k).or_insert(0) += 1;
        }
    }
    let often = |k: &[u32; 3]| count.get(k).is_some_and(|&n| n >= params.min_observations);
    let mut points_layer = Pqrm::new(Calculus::builtin("left-right")?, config)?;
    let mut wall_layer = Pqrm::new(wall_calculus()?, config)?;
    for (t, obs, walls, pose) in &per_frame {
        for (k, three) in triplets(obs) {
            if often(&k) {
                points_layer.update(&Scan::new(*t, 0, three.to_vec())?)?;
            }
        }
        if *walls {
            let sl = pose.to_local(frame_pts[0]);
            let el = pose.to_local(frame_pts[1]);
            for o in obs {
                if seen_at.get(&o.id.0).map_or(0, Vec::len) < params.min_observations {
                    continue;
                }
                let scan = Scan::new(
                    *t,
                    0,
                    vec![
                        *o,
                        Observation::new(LandmarkId(WALL_FRAME_START), sl, cov)?,
                        Observation::new(LandmarkId(WALL_FRAME_END), el, cov)?,
                    ],
                )?;
                wall_layer.update(&scan)?;
            }
        }
    }
    distances.sort_by(f64::total_cmp);
    let effective_range = distances.get(distances.len() / 2).copied().unwrap_or(10.0);
    let (point_elements, wall_elements) = (points_layer.len(), wall_layer.len());
    let map = QualitativeMap::new(vec![
        Layer::Probabilistic(points_layer),
        Layer::Probabilistic(wall_layer),
    ])?;
    // visibility: recognised / scans taken within effective range of the id's mean position
    let mut visibility = BTreeMap::new();
    for id in map.landmarks() {
        let v = match seen_at.get(&id) {
            Some(list) => {
                let n = list.len() as f64;
                let mean = list
                    .iter()
                    .fold([0.0, 0.0], |m, (_, p)| [m[0] + p[0] / n, m[1] + p[1] / n]);
                let near = drive
                    .iter()
                    .zip(&frames)
                    .filter(|(p, f)| {
                        f.scan.is_some()
                            && (p[0] - mean[0]).hypot(p[1] - mean[1]) <= effective_range
                    })
                    .count();
                (n / near.max(1) as f64).clamp(0.02, 1.0)
            }
            // the walls' frame: seen in the scans that extracted both walls, out of the
            // scans taken in or by the corridor
            None => {
                let near = drive
                    .iter()
                    .filter(|p| (p[0] - frame_pts[0][0]).abs() <= 50.0 && p[1].abs() <= 20.0)
                    .count();
                (wall_frames as f64 / near.max(1) as f64).clamp(0.02, 1.0)
            }
        };
        visibility.insert(id, v);
    }
    let mapped: BTreeSet<u32> = map
        .landmarks()
        .into_iter()
        .filter(|&l| l != WALL_FRAME_START && l != WALL_FRAME_END)
        .collect();
    let real = mapped
        .iter()
        .filter(|id| matches!(truth.get(id), Some(Hit::Landmark(_))))
        .count();
    let stats = MappingStats {
        frames: frames.iter().filter(|f| f.scan.is_some()).count(),
        mapped_ids: mapped.len(),
        real_landmarks: real,
        false_landmarks: mapped.len() - real,
        world_landmarks: scenario.world.spec().landmarks.len(),
        detections,
        aliased_detections: aliased,
        wall_frames,
        point_elements,
        wall_elements,
        effective_range,
    };
    Ok(FieldMap {
        scenario,
        drive,
        map,
        recognizer,
        truth,
        recognitions: hits,
        visibility,
        wall_frame: frame_pts,
        stats,
    })
}

#[derive(Debug, Clone, Copy)]
struct Seen {
    id: u32,
    pos: [f64; 2],
    /// The object truly is the one the id was most often recognised from during the
    /// mapping drive.
    consistent: bool,
}

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
/// see [`TriangleRecognizer::identify`]).
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
    /// The *effective* range: the median distance at which the mapping drive recognised
    /// landmarks (the scanner reaches 30 m, but a trunk is a landmark candidate only when
    /// close; search circles at the scanner's range would lose every reference).
    fn range(&self) -> f64 {
        self.field.stats.effective_range
    }
}

/// One trial's start and goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FieldTask {
    /// Trial number.
    pub trial: usize,
    /// Start position (m).
    pub start: [f64; 2],
    /// Goal landmark (recogniser id; a real landmark).
    pub goal: u32,
    /// The goal's true position (m).
    pub goal_position: [f64; 2],
}

/// How a trial ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FieldResult {
    /// Reached the goal element on the true goal.
    Success,
    /// Reached "the goal" on the wrong object.
    PerceptualAliasing,
    /// Could not localise or re-plan, nothing misrecognised on the way.
    InsufficientFeatures,
    /// Could not localise or re-plan after misrecognising landmarks on the way.
    InsufficientFeaturesAndAliasing,
    /// The link graph has no path (not counted as a failure).
    NoPath,
}

impl FieldResult {
    /// Its name in files.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Success => "success",
            Self::PerceptualAliasing => "perceptual-aliasing",
            Self::InsufficientFeatures => "insufficient-features",
            Self::InsufficientFeaturesAndAliasing => "insufficient-features+aliasing",
            Self::NoPath => "no-path",
        }
    }
}

/// One trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldTrial {
    /// The variant.
    pub variant: FieldVariant,
    /// Start and goal.
    pub task: FieldTask,
    /// How it ended.
    pub result: FieldResult,
    /// |P| of the first plan (transitions).
    pub plan_len: usize,
    /// Re-plans made.
    pub replans: usize,
    /// Trajectory length including the final drive to the goal element's centroid (m).
    pub length: f64,
    /// Distance from the end point to the true goal landmark (m).
    pub final_distance: f64,
    /// Detections of mapped ids during the trial.
    pub detections: usize,
    /// Of those, on the wrong object.
    pub aliased: usize,
    /// Length driven in transitions (m): what Propositions 2 and 4 bound.
    pub transit_length: f64,
    /// The first plan's map elements.
    pub plan: Vec<usize>,
    /// Propositions 2 and 4 for this run with their assumptions checked against the world:
    /// at R = the lidar's range, and at R = the effective range.
    pub bounds: [BoundCheck; 2],
    /// The path driven (every check).
    pub trajectory: Vec<[f64; 2]>,
}

/// Why drawn start/goal pairs were redrawn (how connected the map is, seen from the field).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct TaskDraws {
    /// Starts too close to an object or outside the site.
    pub blocked: usize,
    /// Goals already in view (or an element holding them): trivial.
    pub trivial: usize,
    /// Starts from which the robot localises in no element.
    pub no_start: usize,
    /// Pairs with no link-graph path from the elements in view at the start.
    pub no_path: usize,
    /// Pairs kept.
    pub kept: usize,
}

/// Random starts near the mapping drive and goals out of view from them, such that the
/// robot localises at the start and the link graph (β of `params`) has a path — the trials
/// the thesis ran were of that kind; how many draws were redrawn and why is returned.
///
/// # Errors
/// [`QlinkError::EmptyMap`] when no mapped landmark is real; [`StudyError::InvalidParameter`]
/// when 1000 draws per trial found too few pairs.
pub fn tasks(field: &FieldMap, params: &FieldParams) -> Result<(Vec<FieldTask>, TaskDraws)> {
    let graph = LinkGraph::new(&field.map, params.beta, |_, _, _| 1.0)?;
    let mut draws = TaskDraws::default();
    let spec = field.scenario.world.spec();
    let goals: Vec<(u32, [f64; 2])> = field
        .map
        .landmarks()
        .into_iter()
        .filter_map(|id| match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => Some((id, spec.landmarks[*i].pos)),
            _ => None,
        })
        .filter(|(id, _)| *id != WALL_FRAME_START && *id != WALL_FRAME_END)
        .collect();
    if goals.is_empty() {
        return Err(QlinkError::EmptyMap.into());
    }
    let clear = |p: [f64; 2]| clear_of(spec, p, 1.0);
    let mut out = Vec::with_capacity(params.trials);
    let mut rng = ChaCha8Rng::seed_from_u64(params.seed ^ 0x0066_6965_6c64);
    let mut attempts = 0usize;
    while out.len() < params.trials {
        attempts += 1;
        if attempts > 1000 * params.trials {
            return Err(StudyError::InvalidParameter(
                "could not draw start/goal pairs: no goal out of view from any start".into(),
            ));
        }
        let base = field.drive[rng.random_range(0..field.drive.len())];
        let (r, a) = (
            8.0 * rng.random::<f64>().sqrt(),
            rng.random_range(0.0..std::f64::consts::TAU),
        );
        let start = [base[0] + r * a.cos(), base[1] + r * a.sin()];
        let (goal, goal_position) = goals[rng.random_range(0..goals.len())];
        if !clear(start) {
            draws.blocked += 1;
            continue;
        }
        // a goal already in view makes a trivial trial
        let probe = LidarPerception::new(field, 0);
        let in_view = field.map.elements_in_view(&probe.visible(start));
        if probe.sees(start, goal)
            || in_view
                .iter()
                .any(|&e| field.map.elements()[e].landmarks.contains(&goal))
        {
            draws.trivial += 1;
            continue;
        }
        if in_view.is_empty() {
            draws.no_start += 1;
            continue;
        }
        if graph
            .plan(&field.map, &in_view, goal, &BTreeSet::new())
            .is_err()
        {
            draws.no_path += 1;
            continue;
        }
        draws.kept += 1;
        out.push(FieldTask {
            trial: out.len(),
            start,
            goal,
            goal_position,
        });
    }
    Ok((out, draws))
}

/// Whether `p` is inside the site and at least `margin` m from every object.
fn clear_of(spec: &sim2d::WorldSpec, p: [f64; 2], margin: f64) -> bool {
    let [x0, x1, y0, y1] = spec.bounds;
    let free = spec
        .landmarks
        .iter()
        .map(|l| (l.pos, l.radius))
        .chain(spec.clutter.iter().map(|c| (c.pos, c.radius)))
        .all(|(q, r)| (p[0] - q[0]).hypot(p[1] - q[1]) > r + margin);
    let off_walls = spec
        .walls
        .iter()
        .all(|w| seg_dist(p, w.start, w.end) > margin);
    free && off_walls && p[0] > x0 && p[0] < x1 && p[1] > y0 && p[1] < y1
}

/// Where a mapped id truly is: the landmark it was most often recognised from, or the
/// walls' frame points; `None` for clutter or a wall recognised as a point landmark.
fn true_position(field: &FieldMap, id: u32) -> Option<[f64; 2]> {
    match id {
        WALL_FRAME_START => Some(field.wall_frame[0]),
        WALL_FRAME_END => Some(field.wall_frame[1]),
        _ => match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => field.scenario.world.spec().landmarks.get(*i).map(|l| l.pos),
            _ => None,
        },
    }
}

/// Propositions 2 and 4 for a run, at R = the lidar's range and at R = the effective range,
/// with the assumptions checked against the simulated site: a landmark is sensed from `x`
/// when the extractor can get its minimum number of returns from it there (its angular
/// width over the scanner's resolution) within the scanner's range, with nothing in between
/// (sim2d's full occlusion); the walls' virtual frame points count as sensed within range.
/// The field's controllers search, so Assumption 4 (straight lines) never holds.
#[must_use]
pub fn bound_checks(
    field: &FieldMap,
    plan: &[usize],
    made: &[(usize, usize)],
    transit_length: f64,
) -> [BoundCheck; 2] {
    let world = &field.scenario.world;
    let spec = world.spec();
    let lidar = &field.scenario.lidar;
    let min_returns = ExtractorConfig::default().min_points as f64;
    let resolution = lidar.fov / (lidar.rays.max(2) - 1) as f64;
    let position = |id: u32| true_position(field, id);
    let sensed_from = |x: [f64; 2], id: u32| -> bool {
        let Some(p) = true_position(field, id) else {
            return false;
        };
        let d = (p[0] - x[0]).hypot(p[1] - x[1]);
        if d > lidar.max_range {
            return false;
        }
        match field.truth.get(&id) {
            Some(Hit::Landmark(i)) => {
                let r = spec.landmarks[*i].radius;
                let returns = if d <= r {
                    f64::INFINITY
                } else {
                    2.0 * (r / d).asin() / resolution
                };
                returns >= min_returns && world.is_fully_visible(x, *i)
            }
            _ => matches!(id, WALL_FRAME_START | WALL_FRAME_END),
        }
    };
    let drivable = |x: [f64; 2]| clear_of(spec, x, 0.5);
    let geometry = Geometry {
        position: &position,
        sensed_from: &sensed_from,
        drivable: &drivable,
    };
    [lidar.max_range, field.stats.effective_range]
        .map(|r| qlink::bounds::check(&field.map, plan, made, r, false, transit_length, &geometry))
}

fn seg_dist(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    let t = if l2 > 0.0 {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (p[0] - a[0] - t * dx).hypot(p[1] - a[1] - t * dy)
}

/// The link graph of a variant: −log P(success) from horizon-`h` POMDPs (direct
/// transitions); with visibility-aware costs each link's POMDP detects it with the
/// probability the mapping drive measured.
///
/// # Errors
/// POMDP and graph errors.
pub fn field_graph(
    field: &FieldMap,
    params: &FieldParams,
    variant: FieldVariant,
) -> Result<(LinkGraph, Vec<SearchPomdp>)> {
    let pomdps: Vec<SearchPomdp> = field
        .map
        .layers()
        .iter()
        .map(|l| {
            SearchPomdp::builder(l.calculus())
                .moves(qlink::Moves::Direct)
                .p_move(0.9)
                .horizon(params.horizon)
                .build()
        })
        .collect::<qlink::Result<_>>()?;
    let graph = if variant.visibility_costs() {
        let map = &field.map;
        let per_link: BTreeMap<u32, Vec<SearchPomdp>> = map
            .landmarks()
            .into_iter()
            .map(|l| {
                let p = field.visibility.get(&l).copied().unwrap_or(0.5);
                let list = pomdps
                    .iter()
                    .map(|q| q.clone().with_p_detect(p))
                    .collect::<qlink::Result<Vec<_>>>()?;
                Ok((l, list))
            })
            .collect::<Result<_>>()?;
        LinkGraph::new(map, params.beta, |i, j, links| {
            let link = links.first().copied().unwrap_or(0);
            match per_link.get(&link) {
                Some(list) => pomdp_cost(map, list, CostModel::NegLogSuccess)(i, j, links),
                None => f64::INFINITY,
            }
        })?
    } else {
        LinkGraph::new(
            &field.map,
            params.beta,
            pomdp_cost(&field.map, &pomdps, CostModel::NegLogSuccess),
        )?
    };
    Ok((graph, pomdps))
}

/// Runs one trial.
///
/// # Errors
/// Navigation errors other than failures (those are results).
pub fn run_trial(
    field: &FieldMap,
    graph: &LinkGraph,
    config: &NavConfig,
    variant: FieldVariant,
    task: &FieldTask,
) -> Result<FieldTrial> {
    let perception = LidarPerception::new(field, task.trial as u64);
    let nav = Navigator::new(&field.map, graph, &perception, config)?;
    let out: NavOutcome = nav.navigate(task.start, task.goal, None, true)?;
    let mut trajectory = out.trajectory.clone();
    let mut length = out.length;
    let end = trajectory.last().copied().unwrap_or(task.start);
    let (_, detections, aliased) = perception.counts();
    let result = if out.success {
        // drive to the centroid of the goal element in view (§4.4.2), looking for the goal
        // landmark itself on the way: reaching its element's frame is not enough to say
        // which object is the goal
        let visible = perception.visible(end);
        let element = field
            .map
            .elements_in_view(&visible)
            .into_iter()
            .find(|&e| field.map.elements()[e].landmarks.contains(&task.goal));
        let mut goal_seen = perception.sees(end, task.goal);
        if let Some(e) = element {
            let pts: Vec<[f64; 2]> = field.map.elements()[e]
                .landmarks
                .iter()
                .filter_map(|&l| perception.position(l))
                .collect();
            if !pts.is_empty() {
                let n = pts.len() as f64;
                let c = pts
                    .iter()
                    .fold([0.0, 0.0], |m, p| [m[0] + p[0] / n, m[1] + p[1] / n]);
                let dist = (c[0] - end[0]).hypot(c[1] - end[1]);
                let k = (dist / config.step).ceil().max(1.0) as usize;
                for i in 1..=k {
                    let t = i as f64 / k as f64;
                    let p = [end[0] + t * (c[0] - end[0]), end[1] + t * (c[1] - end[1])];
                    trajectory.push(p);
                    goal_seen |= perception.sees(p, task.goal);
                }
                length += dist;
            }
        }
        // the goal element was "reached" on objects that are not its landmarks: the
        // thesis's wrong goal triplet
        let wrong_element = element.is_some_and(|e| {
            field.map.elements()[e]
                .landmarks
                .iter()
                .any(|&l| perception.last_consistent(l) == Some(false))
        });
        match perception.last_consistent(task.goal) {
            Some(true) if goal_seen && !wrong_element => FieldResult::Success,
            _ if wrong_element
                || (goal_seen && perception.last_consistent(task.goal) == Some(false)) =>
            {
                FieldResult::PerceptualAliasing
            }
            _ if aliased > 0 => FieldResult::InsufficientFeaturesAndAliasing,
            _ => FieldResult::InsufficientFeatures,
        }
    } else if out.failure == Some(Failure::NoPath) {
        FieldResult::NoPath
    } else if aliased > 0 {
        FieldResult::InsufficientFeaturesAndAliasing
    } else {
        FieldResult::InsufficientFeatures
    };
    let fin = trajectory.last().copied().unwrap_or(task.start);
    let made: Vec<(usize, usize)> = out.transitions.iter().map(|t| (t.from, t.to)).collect();
    let bounds = bound_checks(field, &out.plan, &made, out.transit_length);
    Ok(FieldTrial {
        variant,
        task: *task,
        result,
        plan_len: out.plan_len,
        replans: out.replans,
        length,
        final_distance: (fin[0] - task.goal_position[0]).hypot(fin[1] - task.goal_position[1]),
        detections,
        aliased,
        transit_length: out.transit_length,
        plan: out.plan.clone(),
        bounds,
        trajectory,
    })
}

/// The navigation settings of a variant.
#[must_use]
pub fn nav_config(
    field: &FieldMap,
    params: &FieldParams,
    variant: FieldVariant,
    pomdp: SearchPomdp,
) -> NavConfig {
    let controller = if variant.safe_search() {
        Controller::new(ControllerKind::SafeSearch, field.stats.effective_range)
    } else {
        Controller::new(ControllerKind::MidpointSweep, field.stats.effective_range)
    };
    NavConfig {
        step: params.step,
        replan: true,
        max_replans: params.max_replans,
        map_range: field.scenario.lidar.max_range,
        find_goal: true,
        ..NavConfig::thesis(controller, pomdp)
    }
}

/// Maps the field and runs every variant's trials (in parallel; the result does not depend
/// on the thread count). `progress` is told the number of trials once the tasks are drawn,
/// ticks after each and is checked before the mapping drive, after it and before each trial
/// (a cancelled run returns [`QlinkError::Cancelled`]).
///
/// # Errors
/// As [`map_field`], [`tasks`], [`field_graph`], [`run_trial`].
pub fn run_field(
    params: &FieldParams,
    variants: &[FieldVariant],
    progress: &dyn Progress,
) -> Result<(FieldMap, TaskDraws, Vec<FieldTrial>)> {
    progress.check()?;
    let field = map_field(params)?;
    progress.check()?;
    let (tasks, draws) = tasks(&field, params)?;
    progress.add_total(tasks.len() * variants.len());
    let mut all = Vec::new();
    for &v in variants {
        let (graph, pomdps) = field_graph(&field, params, v)?;
        let config = nav_config(&field, params, v, pomdps[0].clone());
        let trials: Vec<FieldTrial> = tasks
            .par_iter()
            .map(|t| {
                progress.check()?;
                let r = run_trial(&field, &graph, &config, v, t);
                progress.tick();
                r
            })
            .collect::<Result<_>>()?;
        all.extend(trials);
    }
    Ok((field, draws, all))
}

/// Success and failure counts of one variant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FieldSummary {
    /// The variant.
    pub variant: FieldVariant,
    /// Trials run.
    pub trials: usize,
    /// Trials with no path (not failures).
    pub no_path: usize,
    /// Successes.
    pub successes: usize,
    /// successes / (trials − no_path).
    pub success_rate: f64,
    /// Failures by cause.
    pub perceptual_aliasing: usize,
    /// Insufficient features only.
    pub insufficient_features: usize,
    /// Insufficient features after misrecognitions.
    pub insufficient_features_and_aliasing: usize,
    /// Mean trajectory length of the successes (m).
    pub mean_length: f64,
    /// Successes that re-planned at least once.
    pub replanned_successes: usize,
    /// Table 4.2: (|P|, successful paths, mean trajectory length m).
    pub by_plan_len: Vec<(usize, usize, f64)>,
}

/// Summaries per variant, in the order given.
#[must_use]
pub fn summarise(trials: &[FieldTrial], variants: &[FieldVariant]) -> Vec<FieldSummary> {
    variants
        .iter()
        .map(|&v| {
            let ts: Vec<&FieldTrial> = trials.iter().filter(|t| t.variant == v).collect();
            let count = |r: FieldResult| ts.iter().filter(|t| t.result == r).count();
            let ok: Vec<&&FieldTrial> = ts
                .iter()
                .filter(|t| t.result == FieldResult::Success)
                .collect();
            let no_path = count(FieldResult::NoPath);
            let mut by: BTreeMap<usize, (usize, f64)> = BTreeMap::new();
            for t in &ok {
                let e = by.entry(t.plan_len).or_insert((0, 0.0));
                e.0 += 1;
                e.1 += t.length;
            }
            FieldSummary {
                variant: v,
                trials: ts.len(),
                no_path,
                successes: ok.len(),
                success_rate: ok.len() as f64 / (ts.len() - no_path).max(1) as f64,
                perceptual_aliasing: count(FieldResult::PerceptualAliasing),
                insufficient_features: count(FieldResult::InsufficientFeatures),
                insufficient_features_and_aliasing: count(
                    FieldResult::InsufficientFeaturesAndAliasing,
                ),
                mean_length: ok.iter().map(|t| t.length).sum::<f64>() / ok.len().max(1) as f64,
                replanned_successes: ok.iter().filter(|t| t.replans > 0).count(),
                by_plan_len: by
                    .into_iter()
                    .map(|(k, (n, s))| (k, n, s / n as f64))
                    .collect(),
            }
        })
        .collect()
}

/// Which R a [`BoundSummary`] uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundRange {
    /// The lidar's range (the R the navigator plans arcs and circles with).
    Lidar,
    /// The effective range measured from the mapping drive.
    Effective,
}

impl BoundRange {
    /// Both, in [`FieldTrial::bounds`] order.
    pub const ALL: [Self; 2] = [Self::Lidar, Self::Effective];

    fn index(self) -> usize {
        match self {
            Self::Lidar => 0,
            Self::Effective => 1,
        }
    }

    /// Its name in reports.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Lidar => "lidar range",
            Self::Effective => "effective range",
        }
    }
}

/// Propositions 2 and 4 over one variant's successful runs at one R: how many stayed within
/// each bound, how many met each assumption, and how many exceeded a bound whose assumptions
/// held (a contradiction; the propositions say it cannot happen).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoundSummary {
    /// The variant.
    pub variant: FieldVariant,
    /// Which R.
    pub range: BoundRange,
    /// Smallest and largest R over the worlds (m).
    pub r: [f64; 2],
    /// Successful runs.
    pub runs: usize,
    /// Of those, within Proposition 2's bound.
    pub within_prop2: usize,
    /// Of those, within Proposition 4's bound.
    pub within_prop4: usize,
    /// Runs meeting Assumption 1 (i).
    pub disc: usize,
    /// Runs meeting Assumptions 1 (ii) and 2.
    pub circle: usize,
    /// Runs meeting Assumption 3 (i).
    pub pairwise: usize,
    /// Runs meeting Assumption 3 (ii).
    pub sight_lines: usize,
    /// Runs meeting Assumption 4.
    pub straight: usize,
    /// Runs to which Proposition 2 applies.
    pub prop2_applies: usize,
    /// Runs to which Proposition 4 applies.
    pub prop4_applies: usize,
    /// Runs exceeding a bound whose assumptions held.
    pub contradictions: usize,
}

impl BoundSummary {
    /// Successful runs longer than Proposition 2's and Proposition 4's bound.
    #[must_use]
    pub fn exceeded(&self) -> [usize; 2] {
        [self.runs - self.within_prop2, self.runs - self.within_prop4]
    }

    /// The thesis's finding for its field runs: none exceeds either bound.
    #[must_use]
    pub fn none_exceeded(&self) -> bool {
        self.exceeded() == [0, 0]
    }
}

/// [`BoundSummary`] of `variant`'s successful trials at `range`.
#[must_use]
pub fn bound_summary(
    trials: &[FieldTrial],
    variant: FieldVariant,
    range: BoundRange,
) -> BoundSummary {
    let checks: Vec<&BoundCheck> = trials
        .iter()
        .filter(|t| t.variant == variant && t.result == FieldResult::Success)
        .map(|t| &t.bounds[range.index()])
        .collect();
    let count = |f: &dyn Fn(&BoundCheck) -> bool| checks.iter().filter(|c| f(c)).count();
    let r = checks
        .iter()
        .fold([f64::INFINITY, f64::NEG_INFINITY], |m, c| {
            [m[0].min(c.range), m[1].max(c.range)]
        });
    BoundSummary {
        variant,
        range,
        r: if checks.is_empty() { [0.0, 0.0] } else { r },
        runs: checks.len(),
        within_prop2: count(&BoundCheck::within_prop2),
        within_prop4: count(&BoundCheck::within_prop4),
        disc: count(&|c| c.assumptions.disc),
        circle: count(&|c| c.assumptions.circle),
        pairwise: count(&|c| c.assumptions.pairwise),
        sight_lines: count(&|c| c.assumptions.sight_lines),
        straight: count(&|c| c.assumptions.straight),
        prop2_applies: count(&BoundCheck::prop2_applies),
        prop4_applies: count(&BoundCheck::prop4_applies),
        contradictions: count(&BoundCheck::contradicts),
    }
}

/// How big the map is against what its landmarks allow, and what that does to plans.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSize {
    /// Point landmarks (recogniser ids) in the map.
    pub point_ids: usize,
    /// Triplets of them: C(n, 3).
    pub possible_triplets: usize,
    /// Landmark sets the point layer recorded (its PQRM's entries; a set may be recorded
    /// under several of its orderings).
    pub recorded_triplets: usize,
    /// Point-triplet map elements (distinct landmark sets co-observed in `min_observations`
    /// scans: what the thesis counts as its 44).
    pub point_elements: usize,
    /// Links of the link graph (directed edges, β of the params).
    pub links: usize,
    /// Mean number of elements a landmark belongs to.
    pub elements_per_landmark: f64,
}

/// The size of a field map (see [`MapSize`]).
///
/// # Errors
/// Graph errors.
pub fn map_size(field: &FieldMap, params: &FieldParams) -> Result<MapSize> {
    let graph = LinkGraph::new(&field.map, params.beta, |_, _, _| 1.0)?;
    let points: Vec<u32> = field
        .map
        .landmarks()
        .into_iter()
        .filter(|&id| id != WALL_FRAME_START && id != WALL_FRAME_END)
        .collect();
    let n = points.len();
    let is_point = |e: &qlink::MapElement| {
        e.landmarks
            .iter()
            .all(|&l| l != WALL_FRAME_START && l != WALL_FRAME_END)
    };
    let point_elements = field.map.elements().iter().filter(|e| is_point(e)).count();
    let per: usize = points
        .iter()
        .map(|&l| {
            field
                .map
                .elements_with(l)
                .iter()
                .filter(|&&e| is_point(&field.map.elements()[e]))
                .count()
        })
        .sum();
    Ok(MapSize {
        point_ids: n,
        possible_triplets: n * n.saturating_sub(1) * n.saturating_sub(2) / 6,
        recorded_triplets: field.stats.point_elements,
        point_elements,
        links: graph.n_edges(),
        elements_per_landmark: per as f64 / n.max(1) as f64,
    })
}

/// Plans on the map as built against plans on the map restricted as §4.3.4's second case:
/// only point triplets whose landmarks are pairwise within the effective range (the wall
/// layer kept). Same tasks, unit costs, β of the params.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RestrictedPlans {
    /// Point elements of the map as built, and of the restricted map.
    pub elements: [usize; 2],
    /// Links (directed edges) of each.
    pub links: [usize; 2],
    /// Mean |P| (transitions) over the tasks with a path, on each.
    pub mean_plan_len: [f64; 2],
    /// Tasks with no path on each.
    pub no_path: [usize; 2],
    /// Tasks.
    pub tasks: usize,
}

/// [`RestrictedPlans`] for `tasks`.
///
/// # Errors
/// Map and graph errors.
pub fn restricted_plans(
    field: &FieldMap,
    params: &FieldParams,
    tasks: &[FieldTask],
) -> Result<RestrictedPlans> {
    let r = field.stats.effective_range;
    let close = |ids: [u32; 3]| {
        let p: Option<Vec<[f64; 2]>> = ids.iter().map(|&i| true_position(field, i)).collect();
        p.is_some_and(|p| {
            (0..3).all(|k| {
                let (a, b) = (p[k], p[(k + 1) % 3]);
                (a[0] - b[0]).hypot(a[1] - b[1]) <= r
            })
        })
    };
    let layers: Vec<Layer> = field
        .map
        .layers()
        .iter()
        .enumerate()
        .map(|(k, l)| match (k, l) {
            (0, Layer::Probabilistic(m)) => {
                let mut m = m.clone();
                m.retain(|s| close([s.0[0].0, s.0[1].0, s.0[2].0]));
                Layer::Probabilistic(m)
            }
            _ => l.clone(),
        })
        .collect();
    let restricted = QualitativeMap::new(layers)?;
    let probe = LidarPerception::new(field, 0);
    let mut out = RestrictedPlans {
        elements: [0; 2],
        links: [0; 2],
        mean_plan_len: [0.0; 2],
        no_path: [0; 2],
        tasks: tasks.len(),
    };
    for (k, map) in [&field.map, &restricted].into_iter().enumerate() {
        let graph = LinkGraph::new(map, params.beta, |_, _, _| 1.0)?;
        out.elements[k] = map
            .elements()
            .iter()
            .filter(|e| {
                e.landmarks
                    .iter()
                    .all(|&l| l != WALL_FRAME_START && l != WALL_FRAME_END)
            })
            .count();
        out.links[k] = graph.n_edges();
        let mut lens = Vec::new();
        for t in tasks {
            let starts = map.elements_in_view(&probe.visible(t.start));
            match graph.plan(map, &starts, t.goal, &BTreeSet::new()) {
                Ok(p) => lens.push(p.len() as f64),
                Err(_) => out.no_path[k] += 1,
            }
        }
        out.mean_plan_len[k] = lens.iter().sum::<f64>() / lens.len().max(1) as f64;
    }
    Ok(out)
}
