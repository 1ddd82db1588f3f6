//! The realistic landmark detector (thesis §4.4.2): landmarks from raw lidar returns, without
//! ids.
//!
//! 1. **Two-pass clustering.** Consecutive returns split where the range jumps by more than
//!    `max(jump_abs, jump_rel · r)` or a ray returns nothing; neighbouring clusters whose end
//!    points are closer than `merge_distance` join again (one dropped ray must not cut a trunk
//!    in two).
//! 2. **Classification.** A cluster of `min_points..=max_points` returns, or one with a corner
//!    (a point farther than `corner_distance` from the chord), is a point-landmark candidate
//!    if its returns bulge like an arc (farthest point ≥ 10 % of the chord from it) and fit in
//!    a landmark's diameter (`2·max_radius`);
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
    /// Largest plausible landmark radius for the circle fit (m).
    pub max_radius: f64,
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
        }
    }
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
    clusters(scan, cfg)
        .into_iter()
        .filter_map(|c| candidate(scan, cfg, &c))
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
fn candidate(scan: &LaserScan, cfg: &ExtractorConfig, c: &[usize]) -> Option<Candidate> {
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
    if !((cfg.min_points..=cfg.max_points).contains(&pts.len()) || corner) {
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
    let centre = match circle_fit(&pts) {
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
        }
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
        let out: Vec<u32> = self
            .identify(positions)
            .into_iter()
            .map(|a| {
                a.unwrap_or_else(|| {
                    self.next_id += 1;
                    self.next_id - 1
                })
            })
            .collect();
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
}

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
        }
    }

    /// Detections of one scan (ids from the recogniser) with what each cluster truly was.
    pub fn detect(&mut self, scan: &LaserScan) -> Vec<(crate::sensors::Detection, Option<Hit>)> {
        let points: Vec<Candidate> = extract(scan, &self.extractor)
            .into_iter()
            .filter(|c| c.kind == CandidateKind::Point)
            .collect();
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
}
