//! The mapping drive: lidar scans through the extractor and the triangle recogniser into a
//! hybrid map of point triplets and the walls' frame (see the parent module).

use std::collections::{BTreeMap, BTreeSet};

use pqrm::{LandmarkId, Observation, Pqrm, PqrmConfig, Scan};
use qsr_core::{Calculus, FrameKind};
use serde::{Deserialize, Serialize};
use sim2d::{CandidateKind, ExtractorConfig, Hit, Pose, TriangleRecognizer, World, extract};

use qlink::{Layer, QualitativeMap};

use super::walls::{self, WallModel, WallSighting};
use super::{FieldElements, FieldParams, WALL_FRAME_END, WALL_FRAME_START};
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
    /// Per mapped id: the share of the drive's scans that recognised it out of those that
    /// recognised the rest of an element holding it (from the scans alone).
    pub visibility: BTreeMap<u32, f64>,
    /// Ground truth: the walls' frame, world positions of [`WALL_FRAME_START`] and
    /// [`WALL_FRAME_END`] (for scoring; the robot places them from its scans, `walls`).
    pub wall_frame: [[f64; 2]; 2],
    /// The corridor as the drive learned it from its scans (`None`: never recognised).
    pub walls: Option<WallModel>,
    /// The lidar's extractor (the drive's and the navigating robot's).
    pub extractor: ExtractorConfig,
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

/// The triangles of the Delaunay triangulation of one scan's landmarks, as sorted id
/// triplets (an id placed where another already is joins nothing; fewer than three places,
/// or all on one line, give none).
///
/// # Errors
/// [`StudyError::InvalidParameter`] for a position the triangulation cannot take (not
/// finite, or beyond its range).
fn delaunay_triplets(obs: &[Observation]) -> Result<Vec<[u32; 3]>> {
    use spade::{DelaunayTriangulation, Point2, Triangulation};
    let mut tri: DelaunayTriangulation<Point2<f64>> = DelaunayTriangulation::new();
    let mut ids = Vec::with_capacity(obs.len());
    for o in obs {
        let [x, y] = o.mean;
        let handle = tri.insert(Point2::new(x, y)).map_err(|e| {
            StudyError::InvalidParameter(format!(
                "landmark {} at ({x}, {y}) cannot be triangulated: {e:?}",
                o.id.0
            ))
        })?;
        // a repeated position returns the first one's vertex: it keeps that id
        if handle.index() == ids.len() {
            ids.push(o.id.0);
        }
    }
    Ok(tri
        .inner_faces()
        .map(|face| {
            let mut k = face.vertices().map(|v| ids[v.index()]);
            k.sort_unstable();
            k
        })
        .collect())
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
    /// Per scan: what it recognised, and where the drive was.
    per_frame: Vec<ScanRecord>,
}

/// One scan of the mapping drive, as the first pass recognised it.
struct ScanRecord {
    /// Simulated time (s).
    t: f64,
    /// Its observations (unique ids, robot frame).
    obs: Vec<Observation>,
    /// The walls, when it recognised them.
    walls: Option<WallSighting>,
    /// Where the drive's odometry had the robot (what the mapper uses).
    believed: Pose,
    /// Where the robot was (scoring only).
    truth: Pose,
}

/// Pass 1: every scan through the extractor and the recogniser; `believed`: each frame's pose
/// as the drive's odometry has it.
fn recognise(
    frames: &[sim2d::Frame],
    believed: &[Pose],
    recognizer: &mut TriangleRecognizer,
    cov: [[f64; 2]; 2],
    lidar: &sim2d::LidarConfig,
    extractor: &ExtractorConfig,
) -> Result<Recognised> {
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
        let (cands, walls) = point_and_walls(scan, extractor, lidar, None);
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
        r.per_frame.push(ScanRecord {
            t: f.t,
            obs,
            walls,
            believed: believed.get(fi).copied().unwrap_or(f.pose),
            truth: f.pose,
        });
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
    let mapped = |id: &u32| r.seen_at.get(id).map_or(0, Vec::len) >= params.min_landmark_scans;
    let mut count: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    let mut together: BTreeMap<[u32; 3], usize> = BTreeMap::new();
    for ScanRecord { obs, .. } in &r.per_frame {
        match params.elements {
            FieldElements::CoObserved => {
                for (k, _) in triplets(obs) {
                    *count.entry(k).or_insert(0) += 1;
                }
            }
            FieldElements::Delaunay => {
                // neighbours among the map's landmarks: one seen too rarely to be mapped
                // would otherwise split triangles the map then drops
                let kept: Vec<Observation> =
                    obs.iter().filter(|o| mapped(&o.id.0)).copied().collect();
                for k in delaunay_triplets(&kept)? {
                    *count.entry(k).or_insert(0) += 1;
                }
                for (k, _) in triplets(&kept) {
                    *together.entry(k).or_insert(0) += 1;
                }
            }
        }
    }
    let often = |k: &[u32; 3]| {
        count.get(k).is_some_and(|&n| {
            n >= params.min_observations
                && (params.elements == FieldElements::CoObserved
                    || 2 * n > together.get(k).copied().unwrap_or(0))
        }) && k.iter().all(mapped)
    };
    let mut points_layer = Pqrm::new(Calculus::builtin("left-right")?, config)?;
    let mut wall_layer = Pqrm::new(wall_calculus()?, config)?;
    for ScanRecord {
        t,
        obs,
        walls,
        believed: pose,
        ..
    } in &r.per_frame
    {
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

/// Per mapped id: how often the drive recognised it when it could have — of the scans that
/// recognised the other landmarks of an element holding it (the robot in that element's
/// frame, where a POMDP looks for it), the share that recognised it too. The walls' frame
/// points are one sighting: theirs is the share of the scans that recognised a point of a
/// wall-layer element in which both walls were recognised. From the scans alone: no pose, no
/// truth (at least 0.02, so that no link is impossible).
fn visibility(map: &QualitativeMap, r: &Recognised) -> BTreeMap<u32, f64> {
    let is_frame = |l: u32| l == WALL_FRAME_START || l == WALL_FRAME_END;
    let scans: Vec<(BTreeSet<u32>, bool)> = r
        .per_frame
        .iter()
        .map(|s| (s.obs.iter().map(|o| o.id.0).collect(), s.walls.is_some()))
        .collect();
    let seen = |(ids, walls): &(BTreeSet<u32>, bool), l: u32| {
        if is_frame(l) {
            *walls
        } else {
            ids.contains(&l)
        }
    };
    let mut visibility = BTreeMap::new();
    for id in map.landmarks() {
        // the other members of each element holding `id` that its sighting does not bring
        let frames: Vec<Vec<u32>> = map
            .elements_with(id)
            .iter()
            .map(|&e| {
                map.elements()[e]
                    .landmarks
                    .iter()
                    .copied()
                    .filter(|&l| l != id && !(is_frame(id) && is_frame(l)))
                    .collect()
            })
            .collect();
        let (mut chances, mut hits) = (0_usize, 0_usize);
        for scan in &scans {
            if frames.iter().any(|f| f.iter().all(|&l| seen(scan, l))) {
                chances += 1;
                hits += usize::from(seen(scan, id));
            }
        }
        visibility.insert(id, (hits as f64 / chances.max(1) as f64).clamp(0.02, 1.0));
    }
    visibility
}

/// The mapping drive's poses as its odometry has them ([`qlink::Robot::odometry`] of the
/// field's robot; the exact robot's are the true poses): the wall model's heading and ends
/// come from these, never from where the robot truly was.
fn drive_odometry(frames: &[sim2d::Frame], params: &FieldParams) -> Result<Vec<Pose>> {
    let truth: Vec<[f64; 3]> = frames
        .iter()
        .map(|f| [f.pose.x, f.pose.y, f.pose.theta])
        .collect();
    Ok(params
        .navigating_robot()
        .odometry(&truth, 0)?
        .into_iter()
        .map(|[x, y, theta]| Pose { x, y, theta })
        .collect())
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
    let believed = drive_odometry(&frames, params)?;
    let mut r = recognise(
        &frames,
        &believed,
        &mut recognizer,
        cov,
        &scenario.lidar,
        &params.extractor(),
    )?;
    let sightings: Vec<(Pose, WallSighting)> = r
        .per_frame
        .iter()
        .filter_map(|s| s.walls.map(|w| (s.believed, w)))
        .collect();
    let wall_model = walls::learn(&sightings);
    // how far the scans put the frame from the truth (scoring only): each scan's frame as the
    // robot orients it (its believed heading against the model's), placed from its true pose
    let wall_frame_error = wall_model.map_or(0.0, |m| {
        let errors: Vec<f64> = r
            .per_frame
            .iter()
            .filter_map(|s| s.walls.map(|w| (s, w)))
            .flat_map(|(s, w)| {
                let f = w.frame(&s.believed, m.heading, m.length);
                let truth = s.truth;
                (0..2).map(move |k| {
                    let p = truth.to_world(f[k]);
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
    let visibility = visibility(&map, &r);
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
        extractor: params.extractor(),
        stats,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn obs(points: &[(u32, [f64; 2])]) -> Vec<Observation> {
        let cov = [[0.01, 0.0], [0.0, 0.01]];
        points
            .iter()
            .map(|&(id, p)| Observation::new(LandmarkId(id), p, cov).unwrap())
            .collect()
    }

    fn sorted(mut v: Vec<[u32; 3]>) -> Vec<[u32; 3]> {
        v.sort_unstable();
        v
    }

    /// A small deterministic scatter in general position (splitmix64 draws; a lattice-like
    /// sequence would put four points on one circle, where the triangulation is not unique).
    fn scatter(n: u32, scale: f64) -> Vec<(u32, [f64; 2])> {
        let mut state = 0x9e37_79b9_7f4a_7c15_u64;
        let mut draw = move || {
            state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
            let mut z = state;
            z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
            (z ^ (z >> 31)) as f64 / u64::MAX as f64
        };
        (0..n)
            .map(|i| (100 + 3 * i, [scale * draw(), scale * draw()]))
            .collect()
    }

    #[test]
    fn a_square_and_its_centre_give_the_four_triangles_about_the_centre() {
        let o = obs(&[
            (7, [0.0, 0.0]),
            (3, [2.0, 0.0]),
            (9, [2.0, 2.0]),
            (1, [0.0, 2.0]),
            (5, [1.0, 1.1]),
        ]);
        assert_eq!(
            sorted(delaunay_triplets(&o).unwrap()),
            [[1, 5, 7], [1, 5, 9], [3, 5, 7], [3, 5, 9]]
        );
    }

    #[test]
    fn every_triangle_has_an_empty_circumcircle_and_there_are_2n_minus_2_minus_h() {
        let pts = scatter(40, 30.0);
        let at: BTreeMap<u32, [f64; 2]> = pts.iter().copied().collect();
        let tris = delaunay_triplets(&obs(&pts)).unwrap();
        for k in &tris {
            let [a, b, c] = k.map(|id| at[&id]);
            // circumcentre
            let d = 2.0 * (a[0] * (b[1] - c[1]) + b[0] * (c[1] - a[1]) + c[0] * (a[1] - b[1]));
            let sq = |p: [f64; 2]| p[0] * p[0] + p[1] * p[1];
            let ux = (sq(a) * (b[1] - c[1]) + sq(b) * (c[1] - a[1]) + sq(c) * (a[1] - b[1])) / d;
            let uy = (sq(a) * (c[0] - b[0]) + sq(b) * (a[0] - c[0]) + sq(c) * (b[0] - a[0])) / d;
            let r = (a[0] - ux).hypot(a[1] - uy);
            for (id, p) in &pts {
                if !k.contains(id) {
                    assert!(
                        (p[0] - ux).hypot(p[1] - uy) > r - 1e-9,
                        "{id} inside the circumcircle of {k:?}"
                    );
                }
            }
        }
        // Euler: a triangulation of n points in general position, h of them on the hull
        let hull = {
            use spade::Triangulation as _;
            let mut t: spade::DelaunayTriangulation<spade::Point2<f64>> =
                spade::DelaunayTriangulation::new();
            for (_, p) in &pts {
                t.insert(spade::Point2::new(p[0], p[1])).unwrap();
            }
            t.convex_hull_size()
        };
        assert_eq!(tris.len(), 2 * pts.len() - 2 - hull);
        assert_eq!(tris.iter().collect::<BTreeSet<_>>().len(), tris.len());
    }

    #[test]
    fn the_triangles_do_not_depend_on_the_robots_frame() {
        let pts = scatter(25, 20.0);
        let (s, c) = 1.1_f64.sin_cos();
        let moved: Vec<(u32, [f64; 2])> = pts
            .iter()
            .map(|&(id, [x, y])| (id, [c * x - s * y - 7.0, s * x + c * y + 3.5]))
            .collect();
        assert_eq!(
            sorted(delaunay_triplets(&obs(&pts)).unwrap()),
            sorted(delaunay_triplets(&obs(&moved)).unwrap())
        );
    }

    // regression: the vertex of a repeated position is the first id's; the ids after it must
    // still name their own vertices (an index per observation would shift them by one)
    #[test]
    fn a_repeated_position_keeps_the_first_id_and_shifts_no_other() {
        let o = obs(&[
            (10, [0.0, 0.0]),
            (11, [0.0, 0.0]),
            (12, [1.0, 0.0]),
            (13, [0.0, 1.0]),
        ]);
        assert_eq!(delaunay_triplets(&o).unwrap(), [[10, 12, 13]]);
    }

    #[test]
    fn too_few_or_collinear_landmarks_give_no_triangle_and_a_huge_one_is_an_error() {
        assert!(delaunay_triplets(&[]).unwrap().is_empty());
        assert!(
            delaunay_triplets(&obs(&[(1, [0.0, 0.0]), (2, [1.0, 1.0])]))
                .unwrap()
                .is_empty()
        );
        let line = obs(&[
            (1, [0.0, 0.0]),
            (2, [1.0, 1.0]),
            (3, [2.0, 2.0]),
            (4, [5.0, 5.0]),
        ]);
        assert!(delaunay_triplets(&line).unwrap().is_empty());
        let huge = obs(&[(1, [0.0, 0.0]), (2, [1e300, 0.0]), (3, [0.0, 1.0])]);
        let err = delaunay_triplets(&huge).unwrap_err().to_string();
        assert!(err.contains("landmark 2"), "{err}");
    }
    /// Issue 36: the link detection probabilities came from the drive's true poses and the
    /// walls' true frame; now from which scans recognised what. Three landmarks (1, 2, 3) and
    /// the walls over four scans — {1, 2, 3} + walls, {1, 2, 3}, {1, 2} + walls, {2, 3}.
    #[test]
    fn visibility_is_the_share_of_chances_the_scans_took() {
        let cov = [[0.01, 0.0], [0.0, 0.01]];
        let at = |id: u32, p: [f64; 2]| Observation::new(LandmarkId(id), p, cov).unwrap();
        let wall = walls::tests::wall;
        let sighting = walls::sight(
            &[
                wall([5.0, -7.5], [25.0, -7.5]),
                wall([5.0, 7.5], [25.0, 7.5]),
            ],
            30.0,
            std::f64::consts::TAU,
            None,
        );
        assert!(sighting.is_some());
        let p = [(1, [3.0, 1.0]), (2, [4.0, -2.0]), (3, [6.0, 0.5])];
        let scan = |ids: &[u32], walls: bool| {
            let obs: Vec<Observation> = p
                .iter()
                .filter(|(id, _)| ids.contains(id))
                .map(|&(id, q)| at(id, q))
                .collect();
            ScanRecord {
                t: 0.0,
                obs,
                walls: if walls { sighting } else { None },
                believed: Pose::default(),
                truth: Pose::default(),
            }
        };
        let r = Recognised {
            hits: BTreeMap::new(),
            seen_at: BTreeMap::new(),
            distances: Vec::new(),
            detections: 0,
            wall_frames: 2,
            rays: 0,
            ground_rays: 0,
            drive: Vec::new(),
            per_frame: vec![
                scan(&[1, 2, 3], true),
                scan(&[1, 2, 3], false),
                scan(&[1, 2], true),
                scan(&[2, 3], false),
            ],
        };
        let config = PqrmConfig {
            samples: 20,
            ..PqrmConfig::default()
        };
        let mut points = Pqrm::new(Calculus::builtin("left-right").unwrap(), config).unwrap();
        points
            .update(&Scan::new(0.0, 0, r.per_frame[0].obs.clone()).unwrap())
            .unwrap();
        let mut walled = Pqrm::new(wall_calculus().unwrap(), config).unwrap();
        let frame = vec![
            at(1, [3.0, 1.0]),
            at(WALL_FRAME_START, [25.0, 0.0]),
            at(WALL_FRAME_END, [5.0, 0.0]),
        ];
        walled.update(&Scan::new(0.0, 0, frame).unwrap()).unwrap();
        let map = QualitativeMap::new(vec![
            Layer::Probabilistic(points),
            Layer::Probabilistic(walled),
        ])
        .unwrap();
        let v = visibility(&map, &r);
        // 3: the scans with 1 and 2 (three), two of them with 3
        assert!((v[&3] - 2.0 / 3.0).abs() < 1e-12, "{v:?}");
        // 2: the scans with 1 and 3 (two), both with 2
        assert!((v[&2] - 1.0).abs() < 1e-12, "{v:?}");
        // 1: the scans with 2 and 3, or with the walls (all four), three with 1
        assert!((v[&1] - 0.75).abs() < 1e-12, "{v:?}");
        // the frame points: the scans with 1 (three), two with both walls
        for f in [WALL_FRAME_START, WALL_FRAME_END] {
            assert!((v[&f] - 2.0 / 3.0).abs() < 1e-12, "{v:?}");
        }
    }
}
