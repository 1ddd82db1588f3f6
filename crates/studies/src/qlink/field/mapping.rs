//! The mapping drive: lidar scans through the extractor and the triangle recogniser into a
//! hybrid map of point triplets and the walls' frame (see the parent module).

use std::collections::{BTreeMap, BTreeSet};

use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::{Calculus, FrameKind};
use serde::{Deserialize, Serialize};
use sim2d::{CandidateKind, ExtractorConfig, Hit, Pose, TriangleRecognizer, World, extract};

use qlink::{Layer, QualitativeMap};

use super::walls::{self, WallModel, WallSighting};
use super::{FieldParams, WALL_FRAME_END, WALL_FRAME_START};
use crate::error::{Result, StudyError};
/// Figures of the mapping drive.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MappingStats {
    /// Scans processed.
    pub frames: usize,
    /// Distinct recogniser ids in the map.
    pub mapped_ids: usize,
    /// Of those, ids most often recognised from a real landmark.
    pub real_landmarks: usize,
    /// Of those, ids most often recognised from something else: clutter (rocks, bushes), the
    /// ground, a wall, or nothing the extractor's majority agrees on.
    pub false_landmarks: usize,
    /// Landmarks in the world.
    pub world_landmarks: usize,
    /// Point detections during mapping.
    pub detections: usize,
    /// Detections whose object differs from the one their id was most often recognised from.
    pub aliased_detections: usize,
    /// Scans in which both walls were recognised.
    pub wall_frames: usize,
    /// Mean distance of the walls' frame points as the drive's scans placed them from where
    /// they truly are (m): how well the walls are recognised from scans.
    #[serde(default)]
    pub wall_frame_error: f64,
    /// Share of the drive's lidar rays that met the ground (pitched terrain).
    #[serde(default)]
    pub ground_share: f64,
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
    /// Ground truth: the walls' frame, world positions of [`WALL_FRAME_START`] and
    /// [`WALL_FRAME_END`] (for scoring; the robot places them from its scans, `walls`).
    pub wall_frame: [[f64; 2]; 2],
    /// The corridor as the drive learned it from its scans (`None`: never recognised).
    pub walls: Option<WallModel>,
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

/// Point candidates and the walls recognised (see [`walls`]), from one scan of `lidar`;
/// `width` is the mapped corridor's, when known.
pub(super) fn point_and_walls(
    scan: &sim2d::LaserScan,
    cfg: &ExtractorConfig,
    lidar: &sim2d::LidarConfig,
    width: Option<f64>,
) -> (Vec<sim2d::Candidate>, Option<WallSighting>) {
    let cands = extract(scan, cfg);
    let sighting = walls::sight(&cands, lidar.max_range, lidar.fov, width);
    let points = cands
        .into_iter()
        .filter(|c| c.kind == CandidateKind::Point)
        .collect();
    (points, sighting)
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

/// What the drive's first pass recognised, scan by scan.
struct Recognised {
    /// Per id: every object it was recognised from, with counts (for scoring only).
    hits: BTreeMap<u32, Vec<(Hit, usize)>>,
    /// Per id: (frame, world position estimate) of every scan it was seen in.
    seen_at: BTreeMap<u32, Vec<(usize, [f64; 2])>>,
    /// Range of every recognised landmark (m).
    distances: Vec<f64>,
    /// Point detections.
    detections: usize,
    /// Scans in which both walls were recognised.
    wall_frames: usize,
    /// Rays of the drive's scans, and of those the ground took.
    rays: usize,
    ground_rays: usize,
    /// The drive's true positions.
    drive: Vec<[f64; 2]>,
    /// Per scan: time, its observations (unique ids), the walls recognised, the pose.
    per_frame: Vec<(f64, Vec<Observation>, Option<WallSighting>, Pose)>,
}

/// Pass 1: every scan through the extractor and the recogniser.
fn recognise(
    frames: &[sim2d::Frame],
    recognizer: &mut TriangleRecognizer,
    cov: [[f64; 2]; 2],
    lidar: &sim2d::LidarConfig,
) -> Result<Recognised> {
    let extractor = ExtractorConfig::default();
    let mut r = Recognised {
        hits: BTreeMap::new(),
        seen_at: BTreeMap::new(),
        distances: Vec::new(),
        detections: 0,
        wall_frames: 0,
        rays: 0,
        ground_rays: 0,
        drive: Vec::with_capacity(frames.len()),
        per_frame: Vec::new(),
    };
    for (fi, f) in frames.iter().enumerate() {
        r.drive.push([f.pose.x, f.pose.y]);
        let Some(scan) = &f.scan else { continue };
        r.rays += scan.ranges.len();
        r.ground_rays += scan
            .hits
            .iter()
            .filter(|h| **h == Some(Hit::Ground))
            .count();
        let (cands, walls) = point_and_walls(scan, &extractor, lidar, None);
        let ids = recognizer.recognise(&cands.iter().map(|c| c.centre).collect::<Vec<_>>());
        let mut obs = Vec::new();
        let mut unique = BTreeSet::new();
        let (s, c) = f.pose.theta.sin_cos();
        for (cand, &id) in cands.iter().zip(&ids) {
            r.detections += 1;
            if let Some(h) = cand.truth {
                let list = r.hits.entry(id).or_default();
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
            r.seen_at.entry(id).or_default().push((fi, world));
            r.distances.push(x.hypot(y));
            obs.push(Observation::new(LandmarkId(id), cand.centre, cov)?);
        }
        if walls.is_some() {
            r.wall_frames += 1;
        }
        r.per_frame.push((f.t, obs, walls, f.pose));
    }
    Ok(r)
}

/// Pass 2: the two layers, from the triplets (and, for the walls' layer, the landmarks) seen
/// in at least `min_observations` scans, of landmarks recognised in at least
/// `min_landmark_scans`.
fn layers(
    r: &Recognised,
    params: &FieldParams,
    model: Option<WallModel>,
    cov: [[f64; 2]; 2],
) -> Result<(Pqrm, Pqrm)> {
    let config = PqrmConfig {
        samples: params.samples,
        seed: params.seed,
        ..PqrmConfig::default()
    };
    let mut count: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    for (_, obs, _, _) in &r.per_frame {
        for (k, _) in triplets(obs) {
            *count.entry(k).or_insert(0) += 1;
        }
    }
    let mapped = |id: &u32| r.seen_at.get(id).map_or(0, Vec::len) >= params.min_landmark_scans;
    let often = |k: &[u32; 3]| {
        count.get(k).is_some_and(|&n| n >= params.min_observations) && k.iter().all(mapped)
    };
    let mut points_layer = Pqrm::new(Calculus::builtin("left-right")?, config)?;
    let mut wall_layer = Pqrm::new(wall_calculus()?, config)?;
    for (t, obs, walls, pose) in &r.per_frame {
        for (k, three) in triplets(obs) {
            if often(&k) {
                points_layer.update(&Scan::new(*t, 0, three.to_vec())?)?;
            }
        }
        if let (Some(sighting), Some(model)) = (walls, model) {
            let [sl, el] = sighting.frame(pose, model.heading, model.length);
            for o in obs {
                let scans = r.seen_at.get(&o.id.0).map_or(0, Vec::len);
                if scans < params.min_observations || !mapped(&o.id.0) {
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
    Ok((points_layer, wall_layer))
}

/// Per mapped id: recognised / scans taken within the effective range of the id's mean
/// position; for the walls' frame, the scans that extracted both walls out of those taken in
/// or by the corridor.
fn visibility(
    map: &QualitativeMap,
    r: &Recognised,
    frames: &[sim2d::Frame],
    effective_range: f64,
    frame_pts: [[f64; 2]; 2],
) -> BTreeMap<u32, f64> {
    let mut visibility = BTreeMap::new();
    for id in map.landmarks() {
        let v = match r.seen_at.get(&id) {
            Some(list) => {
                let n = list.len() as f64;
                let mean = list
                    .iter()
                    .fold([0.0, 0.0], |m, (_, p)| [m[0] + p[0] / n, m[1] + p[1] / n]);
                let near = r
                    .drive
                    .iter()
                    .zip(frames)
                    .filter(|(p, f)| {
                        f.scan.is_some()
                            && (p[0] - mean[0]).hypot(p[1] - mean[1]) <= effective_range
                    })
                    .count();
                (n / near.max(1) as f64).clamp(0.02, 1.0)
            }
            None => {
                let near = r
                    .drive
                    .iter()
                    .filter(|p| (p[0] - frame_pts[0][0]).abs() <= 50.0 && p[1].abs() <= 20.0)
                    .count();
                (r.wall_frames as f64 / near.max(1) as f64).clamp(0.02, 1.0)
            }
        };
        visibility.insert(id, v);
    }
    visibility
}

/// Maps the field site with the lidar (see the module docs).
///
/// # Errors
/// Simulation and mapping errors; [`qlink::QlinkError::EmptyMap`] when no scan recognised three
/// landmarks at once.
pub fn map_field(params: &FieldParams) -> Result<FieldMap> {
    params.validate()?;
    let mut scenario = sim2d::scenario("field", params.seed, None)?;
    scenario.lidar.range_sigma = params.range_sigma;
    let frames = scenario.run(params.seed, true)?;
    let frame_pts = wall_frame(&scenario.world)?;
    let mut recognizer = TriangleRecognizer::new(params.tolerance).with_min_votes(params.min_votes);
    let var = params.sigma * params.sigma;
    let cov = [[var, 0.0], [0.0, var]];
    let mut r = recognise(&frames, &mut recognizer, cov, &scenario.lidar)?;
    let sightings: Vec<(Pose, WallSighting)> = r
        .per_frame
        .iter()
        .filter_map(|(_, _, s, pose)| s.map(|s| (*pose, s)))
        .collect();
    let wall_model = walls::learn(&sightings);
    // how far the scans put the frame from the truth (scoring only)
    let wall_frame_error = wall_model.map_or(0.0, |m| {
        let errors: Vec<f64> = sightings
            .iter()
            .flat_map(|(pose, s)| {
                let f = s.frame(pose, m.heading, m.length);
                (0..2).map(move |k| {
                    let p = pose.to_world(f[k]);
                    (p[0] - frame_pts[k][0]).hypot(p[1] - frame_pts[k][1])
                })
            })
            .collect();
        errors.iter().sum::<f64>() / errors.len().max(1) as f64
    });
    // an id stands for the object it was most often recognised from
    let truth: BTreeMap<u32, Hit> = r
        .hits
        .iter()
        .filter_map(|(&id, list)| list.iter().max_by_key(|x| x.1).map(|(h, _)| (id, *h)))
        .collect();
    let aliased: usize = r
        .hits
        .iter()
        .map(|(id, list)| {
            list.iter()
                .filter(|(h, _)| truth.get(id) != Some(h))
                .map(|(_, n)| n)
                .sum::<usize>()
        })
        .sum();
    let (points_layer, wall_layer) = layers(&r, params, wall_model, cov)?;
    r.distances.sort_by(f64::total_cmp);
    let effective_range = r
        .distances
        .get(r.distances.len() / 2)
        .copied()
        .unwrap_or(10.0);
    let (point_elements, wall_elements) = (points_layer.len(), wall_layer.len());
    let map = QualitativeMap::new(vec![
        Layer::Probabilistic(points_layer),
        Layer::Probabilistic(wall_layer),
    ])?;
    let visibility = visibility(&map, &r, &frames, effective_range, frame_pts);
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
        detections: r.detections,
        aliased_detections: aliased,
        wall_frames: r.wall_frames,
        wall_frame_error,
        ground_share: r.ground_rays as f64 / r.rays.max(1) as f64,
        point_elements,
        wall_elements,
        effective_range,
    };
    Ok(FieldMap {
        scenario,
        drive: r.drive,
        map,
        recognizer,
        truth,
        recognitions: r.hits,
        visibility,
        wall_frame: frame_pts,
        walls: wall_model,
        stats,
    })
}
