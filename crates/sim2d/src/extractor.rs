//! The realistic landmark detector (thesis §4.4.2): landmarks from raw lidar returns, without
//! ids.
//!
//! 1. **Two-pass clustering.** Consecutive returns split where the range jumps by more than
//!    `max(jump_abs, jump_rel · r)` or a ray returns nothing; neighbouring clusters whose end
//!    points are closer than `merge_distance` join again (one dropped ray must not cut a trunk
//!    in two).
//! 2. **Classification.** A cluster of `min_points..=max_points` returns (stated for a 0.25°
//!    scanner and scaled to the scan's resolution, at least three), or one with a corner
//!    (a point farther than `corner_distance` from the chord), is a point-landmark candidate
//!    if its returns bulge like an arc (farthest point ≥ 10 % of the chord from it) and fit in
//!    a landmark's diameter (`2·max_radius`) — unless its returns lie on one circle bigger than
//!    `max_radius` (a bush, a rock: round, but no landmark, however far its arc bulges);
//!    a long straight cluster (longer than `wall_length`, all points within `wall_residual` of
//!    the chord) is a wall candidate.
//! 3. **Centre.** A circle fit (algebraic, Kåsa) of the cluster, kept when its radius is
//!    plausible (`≤ max_radius`) and its centre lies behind the returns; otherwise the centroid
//!    pushed back along the bearing by half the cluster's chord. The test
//!    `extractor_finds_landmarks_and_recognition_is_precise` measures both.
//! 4. **Recognition without ids** ([`TriangleRecognizer`]): landmarks seen together form
//!    triangles whose side lengths do not depend on the robot's pose; a new frame's candidates
//!    are matched to known landmarks by triangles whose sorted sides agree within a tolerance,
//!    each match voting for an id; unmatched candidates become new landmarks.

use serde::{Deserialize, Serialize};

use crate::sensors::LaserScan;
use crate::world::Hit;

/// Settings of the extractor.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ExtractorConfig {
    /// Absolute range jump that splits clusters (m).
    pub jump_abs: f64,
    /// Relative range jump that splits clusters.
    pub jump_rel: f64,
    /// Clusters whose facing end points are closer than this merge (m).
    pub merge_distance: f64,
    /// Fewest returns of a point-landmark candidate.
    pub min_points: usize,
    /// Most returns of a point-landmark candidate.
    pub max_points: usize,
    /// A point this far from the chord makes a corner (m).
    pub corner_distance: f64,
    /// Shortest wall candidate (m).
    pub wall_length: f64,
    /// Largest distance of a wall point from its chord (m).
    pub wall_residual: f64,
    /// Largest plausible landmark radius (m): for the circle fit, the size check, and the
    /// round objects that are not landmarks (bigger than this).
    pub max_radius: f64,
    /// The angular resolution (rad) `min_points` and `max_points` are stated for. A scan of
    /// another resolution scales both by `points_resolution / its resolution` (the minimum
    /// never below [`MIN_POINTS_FLOOR`]): a pole covers a quarter of the returns on a 1°
    /// scanner that it does on a 0.25° one, and the fixed 10-return rule gave a 360-beam
    /// lidar an empty map (issue 40). Zero: the counts as given, whatever the scan.
    #[serde(default = "quarter_degree")]
    pub points_resolution: f64,
}

/// The fewest returns a point-landmark candidate has at any resolution: three points fix a
/// circle.
pub const MIN_POINTS_FLOOR: usize = 3;

/// Frames a tracked landmark out of view is still looked for where it was last seen.
const MAX_TRACK_AGE: u32 = 4;

/// The farthest a return of an up-close landmark (more returns than `max_points`) may lie from
/// its fitted circle (m): a few times a scanner's range noise.
const UP_CLOSE_RESIDUAL: f64 = 0.05;

/// The fewest returns a landmark's centre is fitted from as a circle.
const MIN_FIT_POINTS: usize = 5;

fn quarter_degree() -> f64 {
    0.25f64.to_radians()
}

impl Default for ExtractorConfig {
    /// The thesis's 10–50 point rule with thresholds for a 0.25° scanner.
    fn default() -> Self {
        Self {
            jump_abs: 0.3,
            jump_rel: 0.03,
            merge_distance: 0.2,
            min_points: 10,
            max_points: 50,
            corner_distance: 0.25,
            wall_length: 4.0,
            wall_residual: 0.1,
            max_radius: 1.0,
            points_resolution: quarter_degree(),
        }
    }
}

impl ExtractorConfig {
    /// `min_points..=max_points` for a scan of angular resolution `resolution` (rad): scaled
    /// from [`ExtractorConfig::points_resolution`], the minimum at least [`MIN_POINTS_FLOOR`].
    #[must_use]
    pub fn points_for(&self, resolution: f64) -> (usize, usize) {
        let scale = self.points_resolution / resolution;
        if !(scale.is_finite() && scale > 0.0) || self.points_resolution <= 0.0 {
            return (self.min_points, self.max_points);
        }
        let min = ((self.min_points as f64 * scale).round() as usize).max(MIN_POINTS_FLOOR);
        let max = ((self.max_points as f64 * scale).round() as usize).max(min);
        (min, max)
    }
}

/// A scan's angular resolution (rad): the median spacing of its rays (robust to a gap).
#[must_use]
pub fn angular_resolution(scan: &LaserScan) -> f64 {
    let mut steps: Vec<f64> = scan
        .angles
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| d.is_finite() && *d > 0.0)
        .collect();
    if steps.is_empty() {
        return f64::NAN;
    }
    let mid = steps.len() / 2;
    *steps.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// What a cluster was classified as.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum CandidateKind {
    /// A point landmark (tree, pole).
    Point,
    /// A wall (extended landmark).
    Wall,
}

/// A landmark candidate in the robot frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    /// Point or wall.
    pub kind: CandidateKind,
    /// Estimated centre (points) or midpoint (walls), robot frame (m).
    pub centre: [f64; 2],
    /// Wall end points (walls only).
    pub ends: Option<[[f64; 2]; 2]>,
    /// The plain centroid of the returns (for comparison; biased towards the sensor).
    pub centroid: [f64; 2],
    /// Number of returns.
    pub points: usize,
    /// What most of the cluster's rays hit (ground truth for evaluation, not used by the
    /// extractor).
    pub truth: Option<Hit>,
}

fn majority(hits: &[Option<Hit>]) -> Option<Hit> {
    let mut counts: Vec<(Hit, usize)> = Vec::new();
    for h in hits.iter().flatten() {
        match counts.iter_mut().find(|(k, _)| k == h) {
            Some((_, c)) => *c += 1,
            None => counts.push((*h, 1)),
        }
    }
    counts.into_iter().max_by_key(|(_, c)| *c).map(|(h, _)| h)
}

/// Kåsa circle fit: centre and radius minimising Σ (x² + y² + D x + E y + F)².
fn circle_fit(pts: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    let n = pts.len() as f64;
    let (mx, my) = (
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    );
    // Centred coordinates for conditioning.
    let (mut suu, mut svv, mut suv, mut suuu, mut svvv, mut suvv, mut svuu) =
        (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (u, v) = (p[0] - mx, p[1] - my);
        suu += u * u;
        svv += v * v;
        suv += u * v;
        suuu += u * u * u;
        svvv += v * v * v;
        suvv += u * v * v;
        svuu += v * u * u;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-12 {
        return None;
    }
    let (b1, b2) = (0.5 * (suuu + suvv), 0.5 * (svvv + svuu));
    let uc = (b1 * svv - b2 * suv) / det;
    let vc = (b2 * suu - b1 * suv) / det;
    let r = (uc * uc + vc * vc + (suu + svv) / n).sqrt();
    Some(([uc + mx, vc + my], r))
}

/// Extracts landmark candidates from one scan.
#[must_use]
pub fn extract(scan: &LaserScan, cfg: &ExtractorConfig) -> Vec<Candidate> {
    let resolution = angular_resolution(scan);
    let points = cfg.points_for(resolution);
    clusters(scan, cfg)
        .into_iter()
        .filter_map(|c| candidate(scan, cfg, points, resolution, &c))
        .collect()
}

/// A return's position in the scan's frame.
fn return_xy(scan: &LaserScan, i: usize) -> [f64; 2] {
    let (r, a) = (scan.ranges[i], scan.angles[i]);
    [r * a.cos(), r * a.sin()]
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

/// The scan's returns in clusters: split on range jumps and missing returns (pass 1), then
/// neighbours whose facing ends are close merged again (pass 2).
fn clusters(scan: &LaserScan, cfg: &ExtractorConfig) -> Vec<Vec<usize>> {
    let mut clusters: Vec<Vec<usize>> = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for (i, r) in scan.ranges.iter().enumerate() {
        if !r.is_finite() {
            if !current.is_empty() {
                clusters.push(std::mem::take(&mut current));
            }
            continue;
        }
        if let Some(&last) = current.last() {
            let prev = scan.ranges[last];
            if (r - prev).abs() > cfg.jump_abs.max(cfg.jump_rel * r.min(prev)) {
                clusters.push(std::mem::take(&mut current));
            }
        }
        current.push(i);
    }
    if !current.is_empty() {
        clusters.push(current);
    }
    let mut merged: Vec<Vec<usize>> = Vec::new();
    for c in clusters {
        if let Some(last) = merged.last_mut() {
            let (end, start) = (*last.last().unwrap_or(&0), c[0]);
            if start - end <= 3
                && dist(return_xy(scan, end), return_xy(scan, start)) < cfg.merge_distance
            {
                last.extend(c);
                continue;
            }
        }
        merged.push(c);
    }
    merged
}

/// One cluster as a candidate: a wall (long and straight), a point landmark (an arc of the
/// right size, or a corner), or nothing.
fn candidate(
    scan: &LaserScan,
    cfg: &ExtractorConfig,
    (min_points, max_points): (usize, usize),
    resolution: f64,
    c: &[usize],
) -> Option<Candidate> {
    let pts: Vec<[f64; 2]> = c.iter().map(|&i| return_xy(scan, i)).collect();
    let (a, b) = (pts[0], pts[pts.len() - 1]);
    let chord = dist(a, b);
    let off = |p: &[f64; 2]| {
        if chord < 1e-9 {
            dist(*p, a)
        } else {
            ((b[0] - a[0]) * (a[1] - p[1]) - (a[0] - p[0]) * (b[1] - a[1])).abs() / chord
        }
    };
    let max_off = pts.iter().map(off).fold(0.0, f64::max);
    let truth = majority(
        &c.iter()
            .map(|&i| scan.hits.get(i).copied().flatten())
            .collect::<Vec<_>>(),
    );
    if chord >= cfg.wall_length && max_off <= cfg.wall_residual {
        return Some(Candidate {
            kind: CandidateKind::Wall,
            centre: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
            ends: Some([a, b]),
            centroid: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
            points: pts.len(),
            truth,
        });
    }
    let corner = max_off > cfg.corner_distance && chord < cfg.wall_length;
    // A round object bigger than a landmark (a bush, a rock) bulges past `corner_distance`
    // like a corner, but its returns lie on one circle (root-mean-square off it within
    // `UP_CLOSE_RESIDUAL`, as the range noise allows; an L of two walls is far off any
    // circle), of more than `max_radius`: not a landmark, however it is seen.
    if corner
        && pts.len() >= MIN_FIT_POINTS
        && circle_fit(&pts).is_some_and(|(c, r)| {
            let off = pts.iter().map(|p| (dist(*p, c) - r).powi(2)).sum::<f64>();
            r > cfg.max_radius && (off / pts.len() as f64).sqrt() <= UP_CLOSE_RESIDUAL
        })
    {
        return None;
    }
    // Up close a landmark of `max_radius` covers more returns than `max_points` (a 0.25 m
    // pole at 2 m: 57 at 0.25°), and it dropped out of the frames nearest to it; the most a
    // plausible landmark can cover at this cluster's range is allowed too (its size is
    // checked by the chord below).
    let range = pts.iter().map(|p| p[0].hypot(p[1])).sum::<f64>() / pts.len() as f64;
    let subtended = 2.0 * (cfg.max_radius / range).min(1.0).asin();
    let up_close = if resolution.is_finite() && resolution > 0.0 {
        (subtended / resolution).ceil() as usize + 2
    } else {
        0
    };
    // Beyond `max_points` only a round landmark up close: its returns fit a circle of at most
    // `max_radius` to within the range noise (a piece of clutter or a corner does not).
    if pts.len() > max_points && !corner {
        let round = pts.len() <= up_close
            && circle_fit(&pts).is_some_and(|(c, r)| {
                r <= cfg.max_radius
                    && pts
                        .iter()
                        .all(|p| ((p[0] - c[0]).hypot(p[1] - c[1]) - r).abs() <= UP_CLOSE_RESIDUAL)
            });
        if !round {
            return None;
        }
    }
    if pts.len() < min_points && !corner {
        return None;
    }
    // A trunk's returns bulge (an arc) and fit within its diameter; a straight piece of wall
    // seen at a grazing angle does neither.
    let straight = max_off < 0.1 * chord;
    if !corner && (chord > 2.0 * cfg.max_radius || straight) {
        return None;
    }
    let n = pts.len() as f64;
    let centroid = [
        pts.iter().map(|p| p[0]).sum::<f64>() / n,
        pts.iter().map(|p| p[1]).sum::<f64>() / n,
    ];
    let cr = centroid[0].hypot(centroid[1]).max(1e-9);
    let fallback = [
        centroid[0] * (1.0 + 0.5 * chord / cr),
        centroid[1] * (1.0 + 0.5 * chord / cr),
    ];
    // A circle through three or four noisy returns of a small arc is anything up to
    // `max_radius` (the sagitta is below the range noise): fitted from five returns on, which
    // a 0.25° scanner always has (its minimum is ten); a coarser one's few-return clusters
    // take the centroid pushed back.
    let fit = if pts.len() >= MIN_FIT_POINTS {
        circle_fit(&pts)
    } else {
        None
    };
    let centre = match fit {
        // The centre must lie behind the returns (farther than their centroid).
        Some((c, r)) if r <= cfg.max_radius && c[0].hypot(c[1]) > cr => c,
        _ => fallback,
    };
    Some(Candidate {
        kind: CandidateKind::Point,
        centre,
        ends: None,
        centroid,
        points: pts.len(),
        truth,
    })
}

/// Recognises point landmarks across frames by the triangles they form (see the module docs).
#[derive(Debug, Clone, Default)]
pub struct TriangleRecognizer {
    /// Known pairwise distances: `(id_a, id_b)` with `id_a < id_b` → (sum, count).
    distances: std::collections::BTreeMap<(u32, u32), (f64, u32)>,
    next_id: u32,
    tolerance: f64,
    min_votes: u32,
    /// Where each landmark was last seen (robot frame), its id and how many frames ago,
    /// when frames are tracked.
    previous: Option<Vec<([f64; 2], u32, u32)>>,
}

impl TriangleRecognizer {
    /// A recognizer that accepts side lengths within `tolerance` (m).
    #[must_use]
    pub fn new(tolerance: f64) -> Self {
        Self {
            distances: Default::default(),
            next_id: 0,
            tolerance,
            min_votes: 1,
            previous: None,
        }
    }

    /// The same recogniser also tracking candidates from one frame to the next: a candidate
    /// takes the id of the landmark last seen within the tolerance of it (in the robot frame;
    /// a quarter more per frame for one last seen up to four frames ago) when exactly one is,
    /// before triangles are asked. Frames of a moving scanner are
    /// close (centimetres, a degree apart); a frame of three candidates of which one is new
    /// has no triangle of known sides at all (its two known landmarks got new ids), and three
    /// far poles matched a congruent triangle of three others by chance (issue 40). Only for
    /// consecutive frames of one robot.
    #[must_use]
    pub fn tracking(mut self) -> Self {
        self.previous = Some(Vec::new());
        self
    }

    /// The same recogniser accepting a known id only with at least `votes` matching
    /// triangles (default 1). Two votes need four candidates in view but rule out most chance
    /// matches of one triangle between distinct places.
    #[must_use]
    pub fn with_min_votes(mut self, votes: u32) -> Self {
        self.min_votes = votes.max(1);
        self
    }

    fn known(&self, a: u32, b: u32) -> Option<f64> {
        let key = if a < b { (a, b) } else { (b, a) };
        self.distances.get(&key).map(|(s, n)| s / f64::from(*n))
    }

    /// Assigns an id to each candidate position of one frame (robot frame): known landmarks
    /// where triangles match, new ids otherwise. Learns the frame's distances.
    pub fn recognise(&mut self, positions: &[[f64; 2]]) -> Vec<u32> {
        let n = positions.len();
        let d = |i: usize, j: usize| {
            (positions[i][0] - positions[j][0]).hypot(positions[i][1] - positions[j][1])
        };
        let mut found = self.identify(positions);
        if let Some(previous) = &self.previous {
            // Tracking first: consecutive frames are close, and a triangle of three
            // candidates can match a congruent triangle of other landmarks by chance (the
            // 0.3 m tolerance over a few dozen triangles); the track wins where both answer.
            let near = |i: usize| -> Option<u32> {
                // The robot moves on while a landmark is out of view: a frame later the
                // tolerance, each frame more a quarter of it more (not the whole: a landmark
                // a metre from one that left the view must not take its id).
                let mut ids = previous.iter().filter(|(p, _, age)| {
                    (p[0] - positions[i][0]).hypot(p[1] - positions[i][1])
                        <= self.tolerance * (1.0 + 0.25 * f64::from(age - 1))
                });
                match (ids.next(), ids.next()) {
                    (Some((_, id, _)), None) => Some(*id),
                    _ => None,
                }
            };
            let tracked: Vec<Option<u32>> = (0..n).map(near).collect();
            let count = |id: u32| tracked.iter().filter(|t| **t == Some(id)).count();
            let tracked: Vec<Option<u32>> = tracked
                .iter()
                .map(|t| t.filter(|id| count(*id) == 1))
                .collect();
            let taken: std::collections::BTreeSet<u32> =
                tracked.iter().flatten().copied().collect();
            // A triangle's answer must also agree with the tracked landmarks of the frame: two
            // landmarks a metre apart, seen again from afar, have triangles alike (issue 40).
            let anchors: Vec<(usize, u32)> = tracked
                .iter()
                .enumerate()
                .filter_map(|(j, t)| t.map(|id| (j, id)))
                .collect();
            for (i, (slot, t)) in found.iter_mut().zip(&tracked).enumerate() {
                *slot = match (*t, *slot) {
                    (Some(id), _) => Some(id),
                    (None, Some(id))
                        if !taken.contains(&id) && self.agrees(positions, i, id, &anchors) =>
                    {
                        Some(id)
                    }
                    _ => None,
                };
            }
            self.anchor(positions, &mut found);
        }
        let out: Vec<u32> = found
            .into_iter()
            .map(|a| {
                a.unwrap_or_else(|| {
                    self.next_id += 1;
                    self.next_id - 1
                })
            })
            .collect();
        if let Some(previous) = &mut self.previous {
            let seen: std::collections::BTreeSet<u32> = out.iter().copied().collect();
            previous.retain(|(_, id, age)| !seen.contains(id) && *age < MAX_TRACK_AGE);
            for entry in previous.iter_mut() {
                entry.2 += 1;
            }
            previous.extend(positions.iter().zip(&out).map(|(p, id)| (*p, *id, 1)));
        }
        for i in 0..n {
            for j in i + 1..n {
                let key = if out[i] < out[j] {
                    (out[i], out[j])
                } else {
                    (out[j], out[i])
                };
                let e = self.distances.entry(key).or_insert((0.0, 0));
                e.0 += d(i, j);
                e.1 += 1;
            }
        }
        out
    }

    /// Whether candidate `i` as landmark `id` keeps the known distances to the `anchors`
    /// (candidates identified otherwise) within twice the tolerance; true with fewer than two
    /// anchors of known distance.
    fn agrees(&self, positions: &[[f64; 2]], i: usize, id: u32, anchors: &[(usize, u32)]) -> bool {
        let errs: Vec<f64> = anchors
            .iter()
            .filter(|(j, a)| *j != i && *a != id)
            .filter_map(|&(j, a)| {
                let d =
                    (positions[i][0] - positions[j][0]).hypot(positions[i][1] - positions[j][1]);
                self.known(a, id).map(|e| (e - d).abs())
            })
            .collect();
        errs.len() < 2 || errs.iter().all(|e| *e <= 2.0 * self.tolerance)
    }

    /// Candidates left unidentified matched against the ones identified (tracked frames only):
    /// a far landmark seen again after a gap, its centre from three returns too noisy for
    /// every side of a triangle to agree, is still the one known landmark whose distances to
    /// two or more identified landmarks of the frame all agree within twice the tolerance —
    /// when no other known landmark comes within it.
    fn anchor(&self, positions: &[[f64; 2]], found: &mut [Option<u32>]) {
        let d = |i: usize, j: usize| {
            (positions[i][0] - positions[j][0]).hypot(positions[i][1] - positions[j][1])
        };
        let slack = 2.0 * self.tolerance;
        let known_ids: std::collections::BTreeSet<u32> =
            self.distances.keys().flat_map(|&(a, b)| [a, b]).collect();
        for k in 0..positions.len() {
            if found[k].is_some() {
                continue;
            }
            let anchors: Vec<(usize, u32)> = found
                .iter()
                .enumerate()
                .filter_map(|(j, id)| id.map(|id| (j, id)))
                .collect();
            if anchors.len() < 2 {
                return;
            }
            let used: std::collections::BTreeSet<u32> = anchors.iter().map(|a| a.1).collect();
            let mut fits: Vec<(f64, u32)> = known_ids
                .iter()
                .filter(|c| !used.contains(c))
                .filter_map(|&c| {
                    let errs: Vec<f64> = anchors
                        .iter()
                        .filter_map(|&(j, a)| self.known(a, c).map(|e| (e - d(k, j)).abs()))
                        .collect();
                    (errs.len() >= anchors.len().min(3))
                        .then(|| (errs.iter().copied().fold(0.0, f64::max), c))
                })
                .collect();
            fits.sort_by(|x, y| x.0.total_cmp(&y.0));
            if let Some(&(best, c)) = fits.first()
                && best <= slack
                && fits.get(1).is_none_or(|second| second.0 > slack)
            {
                found[k] = Some(c);
            }
        }
    }

    /// Identifies candidates against the catalogue without changing it: the known landmark
    /// each candidate's triangles vote for, `None` where no triangle matches. A navigating
    /// robot identifies against its map this way; learning from its own (possibly wrong)
    /// matches would let one id absorb ever more objects.
    #[must_use]
    pub fn identify(&self, positions: &[[f64; 2]]) -> Vec<Option<u32>> {
        let n = positions.len();
        let d = |i: usize, j: usize| {
            (positions[i][0] - positions[j][0]).hypot(positions[i][1] - positions[j][1])
        };
        // Known pairs sorted by distance: each candidate edge looks up the known edges of
        // (almost) the same length instead of scanning every known triple.
        let mut pairs_by_len: Vec<(f64, u32, u32)> = self
            .distances
            .iter()
            .map(|(&(a, b), &(sum, cnt))| (sum / f64::from(cnt), a, b))
            .collect();
        pairs_by_len.sort_by(|x, y| x.0.total_cmp(&y.0));
        let matching = |len: f64| {
            let lo = pairs_by_len.partition_point(|p| p.0 < len - self.tolerance);
            let hi = pairs_by_len.partition_point(|p| p.0 <= len + self.tolerance);
            &pairs_by_len[lo..hi]
        };
        // votes[candidate] = [(id, votes)]
        let mut votes: Vec<Vec<(u32, u32)>> = vec![Vec::new(); n];
        let add = |votes: &mut Vec<Vec<(u32, u32)>>, c: usize, id: u32| match votes[c]
            .iter_mut()
            .find(|(k, _)| *k == id)
        {
            Some((_, v)) => *v += 1,
            None => votes[c].push((id, 1)),
        };
        for i in 0..n {
            for j in i + 1..n {
                for &(_, p, q) in matching(d(i, j)) {
                    // Both orientations of the known edge.
                    for (a, b) in [(p, q), (q, p)] {
                        for k in j + 1..n {
                            for &(_, r, s) in matching(d(i, k)) {
                                let c = if r == a {
                                    s
                                } else if s == a {
                                    r
                                } else {
                                    continue;
                                };
                                if c == b {
                                    continue;
                                }
                                if self
                                    .known(b, c)
                                    .is_some_and(|dbc| (dbc - d(j, k)).abs() <= self.tolerance)
                                {
                                    add(&mut votes, i, a);
                                    add(&mut votes, j, b);
                                    add(&mut votes, k, c);
                                }
                            }
                        }
                    }
                }
            }
        }
        // Greedy assignment by vote count, each id at most once.
        let mut pairs: Vec<(u32, usize, u32)> = votes
            .iter()
            .enumerate()
            .flat_map(|(c, v)| v.iter().map(move |(id, n)| (*n, c, *id)))
            .filter(|p| p.0 >= self.min_votes)
            .collect();
        pairs.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)).then(x.2.cmp(&y.2)));
        let mut assigned: Vec<Option<u32>> = vec![None; n];
        let mut used = std::collections::BTreeSet::new();
        for (_, c, id) in pairs {
            if assigned[c].is_none() && !used.contains(&id) {
                assigned[c] = Some(id);
                used.insert(id);
            }
        }
        assigned
    }
}

/// The whole realistic detector: extract point candidates from a scan, recognise them across
/// frames by triangles, and report them as detections with an isotropic covariance `σ² I`.
#[derive(Debug, Clone)]
pub struct LidarDetector {
    /// Extraction settings.
    pub extractor: ExtractorConfig,
    /// The recogniser (keeps its catalogue across frames).
    pub recognizer: TriangleRecognizer,
    /// Position noise reported with each detection (m).
    pub sigma: f64,
    /// Fewest candidates a frame needs to be recognised (default 1). Triangles need three:
    /// a frame of one or two candidates matches nothing, and recognising it makes new ids for
    /// landmarks already known — at a 1° scanner, where far poles drop in and out, dozens per
    /// pole (issue 40). A map needs triplets, so mapping from scans uses 3
    /// ([`MAPPING_MIN_CANDIDATES`]); a navigating robot still wants to see one or two.
    pub min_candidates: usize,
}

/// [`LidarDetector::min_candidates`] for mapping: a frame with fewer candidates holds no
/// triplet and cannot be recognised by triangles.
pub const MAPPING_MIN_CANDIDATES: usize = 3;

impl LidarDetector {
    /// Replaces every frame's detections by the ones extracted from its scan (frames without
    /// a scan get none) and returns the landmark (index into the world spec) each recognised
    /// id was *first* recognised from — the association a simulation scores against or uses
    /// to simulate perception. Clutter recognised as a landmark has no entry.
    pub fn detect_frames(
        &mut self,
        frames: &mut [crate::scenario::Frame],
    ) -> std::collections::BTreeMap<u32, usize> {
        let mut first = std::collections::BTreeMap::new();
        for f in frames {
            let found = match &f.scan {
                Some(scan) => self.detect(scan),
                None => Vec::new(),
            };
            for (d, hit) in &found {
                if let Some(Hit::Landmark(i)) = hit {
                    first.entry(d.id).or_insert(*i);
                }
            }
            f.detections = found.into_iter().map(|(d, _)| d).collect();
        }
        first
    }

    /// A detector with default extraction, recognition tolerance `tolerance` (m) and `sigma`.
    #[must_use]
    pub fn new(tolerance: f64, sigma: f64) -> Self {
        Self {
            extractor: ExtractorConfig::default(),
            recognizer: TriangleRecognizer::new(tolerance),
            sigma,
            min_candidates: 1,
        }
    }

    /// Detections of one scan (ids from the recogniser) with what each cluster truly was.
    pub fn detect(&mut self, scan: &LaserScan) -> Vec<(crate::sensors::Detection, Option<Hit>)> {
        self.recognise(points_of(scan, &self.extractor))
    }

    /// Detections of point candidates already extracted from one scan ([`points_of`]). A
    /// frame of fewer than [`LidarDetector::min_candidates`] gives none: nothing is learned
    /// from it and no id is made for it.
    pub fn recognise(
        &mut self,
        points: Vec<Candidate>,
    ) -> Vec<(crate::sensors::Detection, Option<Hit>)> {
        if points.len() < self.min_candidates {
            return Vec::new();
        }
        let ids = self
            .recognizer
            .recognise(&points.iter().map(|c| c.centre).collect::<Vec<_>>());
        let var = self.sigma * self.sigma;
        points
            .iter()
            .zip(ids)
            .map(|(c, id)| {
                (
                    crate::sensors::Detection {
                        id,
                        xy: c.centre,
                        cov: [[var, 0.0], [0.0, var]],
                    },
                    c.truth,
                )
            })
            .collect()
    }

    /// The same detector giving no detections for a frame of fewer than `n` candidates (see
    /// [`LidarDetector::min_candidates`]).
    #[must_use]
    pub fn with_min_candidates(mut self, n: usize) -> Self {
        self.min_candidates = n;
        self
    }
}

/// The point-landmark candidates of one scan.
#[must_use]
pub fn points_of(scan: &LaserScan, cfg: &ExtractorConfig) -> Vec<Candidate> {
    extract(scan, cfg)
        .into_iter()
        .filter(|c| c.kind == CandidateKind::Point)
        .collect()
}
