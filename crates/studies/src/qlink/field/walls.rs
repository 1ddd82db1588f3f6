//! The corridor's walls recognised from a scan: which wall candidates are the two walls, and
//! where the walls' frame ([`super::WALL_FRAME_START`] → [`super::WALL_FRAME_END`]) lies —
//! from the extractor's wall candidates alone, never from the simulator's truth.
//!
//! **Recognition.** The walls are the pair of wall candidates that run parallel (within
//! [`PARALLEL_DEG`]), face each other (their stretches overlap along the corridor) and stand
//! a corridor's width apart; pieces of the same wall cut by an occluder join their pair when
//! they lie on its line. The mapping drive learns the corridor ([`WallModel`]: its width,
//! its length and which way the frame runs); at navigation a pair whose width differs from
//! the mapped one by more than [`WIDTH_TOLERANCE_M`] is not the corridor.
//!
//! **The frame.** The corridor's axis is the midline of the two walls; the frame's points lie
//! on it at the walls' ends. A scanner sees a wall's end only when it is in range (an end at
//! the range limit is where the scan stops, not the wall), so an end seen *open* is placed at
//! the mapped length from the closed one; with both open the frame is the stretch seen. The
//! frame runs from the walls' far end to their near end as the mapping drive first saw them
//! (the drive enters the corridor from its open end, which puts the pines and the open field
//! "behind", as in the thesis); later scans take the sense nearer that world heading.
//! Occluders that cut a wall short are not told apart from its end — a real robot's error
//! too, measured in the mapping figures (`wall_frame_error`).

use sim2d::{Candidate, CandidateKind, Pose};

/// Largest angle between the two walls' lines (deg).
pub const PARALLEL_DEG: f64 = 10.0;
/// Narrowest corridor taken for the walls (m): closer lines are one wall cut in two.
pub const MIN_WIDTH_M: f64 = 2.0;
/// Widest corridor taken for the walls (m).
pub const MAX_WIDTH_M: f64 = 40.0;
/// Largest difference from the mapped corridor's width at navigation (m).
pub const WIDTH_TOLERANCE_M: f64 = 2.0;
/// A wall piece within this of a wall's line is part of that wall (m).
const ON_LINE_M: f64 = 0.5;
/// An end point this close to the scanner's range is where the scan stops (m).
const RANGE_MARGIN_M: f64 = 1.0;
/// An end point seen at less than this angle to its wall is where the returns thinned out,
/// not where the wall ends (deg): with the default extractor (clusters split at range jumps
/// over max(0.3 m, 3 % of the range)) a 0.25° scanner loses a wall below
/// atan(0.25° / 3 %) ≈ 8.3° beyond 10 m; 12° leaves a margin.
const GRAZING_DEG: f64 = 12.0;
/// An end point this close to the edge of the scanner's field of view is where the view
/// stops (deg).
const FOV_MARGIN_DEG: f64 = 1.0;

/// The walls as one scan sees them (robot frame).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallSighting {
    /// A point on the corridor's axis.
    origin: [f64; 2],
    /// Unit vector along the axis (either sense).
    dir: [f64; 2],
    /// Extent seen along `dir` from `origin`: [lowest, highest].
    extent: [f64; 2],
    /// Whether each extent ends at a wall's end (not at the scanner's range).
    closed: [bool; 2],
    /// The corridor's width (m).
    pub width: f64,
}

/// What the mapping drive learned of the corridor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallModel {
    /// Median width (m).
    pub width: f64,
    /// The walls' length (m; see [`learn`]).
    pub length: Option<f64>,
    /// World heading of the frame, start → end (rad).
    pub heading: f64,
}

fn sub(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn dot(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn unit(v: [f64; 2]) -> Option<[f64; 2]> {
    let n = v[0].hypot(v[1]);
    (n > 1e-9).then(|| [v[0] / n, v[1] / n])
}
/// Distance of `p` from the line through `a` along unit `u`.
fn off_line(p: [f64; 2], a: [f64; 2], u: [f64; 2]) -> f64 {
    let v = sub(p, a);
    (v[0] * u[1] - v[1] * u[0]).abs()
}

/// The two walls in a scan's candidates, or `None` (see the module docs). `max_range` and
/// `fov` (rad) are the scanner's; `width` the mapped corridor's, when known.
#[must_use]
pub fn sight(
    cands: &[Candidate],
    max_range: f64,
    fov: f64,
    width: Option<f64>,
) -> Option<WallSighting> {
    let walls: Vec<([f64; 2], [f64; 2], [f64; 2])> = cands
        .iter()
        .filter(|c| c.kind == CandidateKind::Wall)
        .filter_map(|c| {
            let [a, b] = c.ends?;
            Some((a, b, unit(sub(b, a))?))
        })
        .collect();
    let cos_max = PARALLEL_DEG.to_radians().cos();
    let mut best: Option<(f64, usize, usize, f64)> = None;
    for (i, &(a, b, u)) in walls.iter().enumerate() {
        for (j, &(c, d, v)) in walls.iter().enumerate().skip(i + 1) {
            if dot(u, v).abs() < cos_max {
                continue;
            }
            let mid = [(c[0] + d[0]) / 2.0, (c[1] + d[1]) / 2.0];
            let w = off_line(mid, a, u);
            if !(MIN_WIDTH_M..=MAX_WIDTH_M).contains(&w)
                || width.is_some_and(|m| (w - m).abs() > WIDTH_TOLERANCE_M)
            {
                continue;
            }
            // facing each other: the stretches overlap along the axis
            let (ta, tb) = (0.0_f64, dot(sub(b, a), u));
            let (tc, td) = (dot(sub(c, a), u), dot(sub(d, a), u));
            let overlap = ta.max(tb).min(tc.max(td)) - ta.min(tb).max(tc.min(td));
            if overlap <= 0.0 {
                continue;
            }
            let total = tb.abs() + (td - tc).abs();
            if best.is_none_or(|x| total > x.0) {
                best = Some((total, i, j, w));
            }
        }
    }
    let (_, i, j, w) = best?;
    let (a, _, u) = walls[i];
    let (c, _, _) = walls[j];
    // the axis: halfway between the two lines, along the first wall
    let n = [-u[1], u[0]];
    let side = dot(sub(c, a), n);
    let origin = [a[0] + n[0] * side / 2.0, a[1] + n[1] * side / 2.0];
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lo_at, mut hi_at) = ([0.0; 2], [0.0; 2]);
    for &(p, q, v) in &walls {
        let on = |base: [f64; 2]| {
            dot(u, v).abs() >= cos_max
                && off_line(p, base, u).max(off_line(q, base, u)) <= ON_LINE_M
        };
        if !(on(a) || on(c)) {
            continue;
        }
        for e in [p, q] {
            let t = dot(sub(e, origin), u);
            if t < lo {
                (lo, lo_at) = (t, e);
            }
            if t > hi {
                (hi, hi_at) = (t, e);
            }
        }
    }
    // an end within range, seen at a fair angle: a wall seen grazing breaks into returns too
    // sparse to cluster, so its stretch stops short of its end
    let sin_min = GRAZING_DEG.to_radians().sin();
    let half = fov / 2.0 - FOV_MARGIN_DEG.to_radians();
    let closed = |e: [f64; 2]| {
        let r = e[0].hypot(e[1]);
        r < max_range - RANGE_MARGIN_M
            && r > 0.0
            && (e[0] * u[1] - e[1] * u[0]).abs() / r >= sin_min
            && e[1].atan2(e[0]).abs() <= half
    };
    Some(WallSighting {
        origin,
        dir: u,
        extent: [lo, hi],
        closed: [closed(lo_at), closed(hi_at)],
        width: w,
    })
}

impl WallSighting {
    /// Whether both of the stretch's ends are the walls' ends.
    #[cfg(test)]
    fn closed(&self) -> bool {
        self.closed[0] && self.closed[1]
    }

    /// The stretch seen (m).
    #[must_use]
    pub fn length(&self) -> f64 {
        self.extent[1] - self.extent[0]
    }

    /// The sense of the axis whose end lies farther from the robot: the far end first, for
    /// the first sighting of the drive (robot frame, unit).
    #[must_use]
    pub fn far_to_near(&self) -> [f64; 2] {
        let at = |t: f64| {
            let p = [
                self.origin[0] + self.dir[0] * t,
                self.origin[1] + self.dir[1] * t,
            ];
            p[0].hypot(p[1])
        };
        if at(self.extent[1]) > at(self.extent[0]) {
            [-self.dir[0], -self.dir[1]]
        } else {
            self.dir
        }
    }

    /// The axis along the world `heading` as near as it allows from `pose`: its unit vector,
    /// the stretch seen along it and whether each end is closed, start first.
    fn oriented(&self, pose: &Pose, heading: f64) -> ([f64; 2], [f64; 2], [bool; 2]) {
        let local = heading - pose.theta;
        let along = [local.cos(), local.sin()];
        if dot(self.dir, along) >= 0.0 {
            (self.dir, self.extent, self.closed)
        } else {
            (
                [-self.dir[0], -self.dir[1]],
                [-self.extent[1], -self.extent[0]],
                [self.closed[1], self.closed[0]],
            )
        }
    }

    /// The frame's start and end points (robot frame), the frame running along the world
    /// `heading` as near as the axis allows from `pose`; an open end is placed at `length`
    /// from the closed one.
    #[must_use]
    pub fn frame(&self, pose: &Pose, heading: f64, length: Option<f64>) -> [[f64; 2]; 2] {
        let (u, [mut s, mut e], closed) = self.oriented(pose, heading);
        if let Some(l) = length {
            match closed {
                [true, false] => e = s + l,
                [false, true] => s = e - l,
                _ => {}
            }
        }
        let at = |t: f64| [self.origin[0] + u[0] * t, self.origin[1] + u[1] * t];
        [at(s), at(e)]
    }
}

/// The corridor learned from the drive's sightings (with each scan's pose, as the drive's
/// odometry has it): the median width; the frame's heading (far end to near end of the first
/// sighting); its length — the distance between where the drive saw the start closed and
/// where it saw the end closed (medians), a forward-looking scanner seldom seeing both ends at
/// once; the longest stretch seen when it never saw both. `None` without a sighting.
#[must_use]
pub fn learn(sightings: &[(Pose, WallSighting)]) -> Option<WallModel> {
    let (pose, first) = sightings.first()?;
    let mut widths: Vec<f64> = sightings.iter().map(|(_, s)| s.width).collect();
    widths.sort_by(f64::total_cmp);
    let u = first.far_to_near();
    let heading = pose.theta + u[1].atan2(u[0]);
    let mut ends: [Vec<[f64; 2]>; 2] = [Vec::new(), Vec::new()];
    for (pose, s) in sightings {
        let (_, _, closed) = s.oriented(pose, heading);
        let f = s.frame(pose, heading, None);
        for k in 0..2 {
            if closed[k] {
                ends[k].push(pose.to_world(f[k]));
            }
        }
    }
    let median = |v: &[[f64; 2]]| {
        let mut xs: Vec<f64> = v.iter().map(|p| p[0]).collect();
        let mut ys: Vec<f64> = v.iter().map(|p| p[1]).collect();
        xs.sort_by(f64::total_cmp);
        ys.sort_by(f64::total_cmp);
        [xs[xs.len() / 2], ys[ys.len() / 2]]
    };
    let length = if ends[0].is_empty() || ends[1].is_empty() {
        sightings
            .iter()
            .map(|(_, s)| s.length())
            .max_by(f64::total_cmp)
    } else {
        let (a, b) = (median(&ends[0]), median(&ends[1]));
        Some((a[0] - b[0]).hypot(a[1] - b[1]))
    };
    Some(WallModel {
        width: widths[widths.len() / 2],
        length,
        heading,
    })
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use std::f64::consts::TAU;

    /// A wall candidate from `a` to `b` (also the mapping tests').
    pub(in crate::qlink::field) fn wall(a: [f64; 2], b: [f64; 2]) -> Candidate {
        Candidate {
            kind: CandidateKind::Wall,
            centre: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
            ends: Some([a, b]),
            centroid: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
            points: 100,
            truth: None,
        }
    }

    #[test]
    fn two_facing_walls_make_the_frame_and_an_open_end_takes_the_mapped_length() {
        // a corridor along x from 5 to 25, 15 m wide, seen from the origin; range 30
        let c = [
            wall([5.0, -7.5], [25.0, -7.5]),
            wall([5.0, 7.5], [25.0, 7.5]),
        ];
        let s = sight(&c, 30.0, TAU, None).expect("the corridor");
        assert!((s.width - 15.0).abs() < 1e-9);
        assert!(s.closed());
        let pose = Pose {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
        };
        let model = learn(&[(pose, s)]).expect("a model");
        // far end (x = 25) first
        let [st, en] = s.frame(&pose, model.heading, model.length);
        assert!((st[0] - 25.0).abs() < 1e-9 && st[1].abs() < 1e-9, "{st:?}");
        assert!((en[0] - 5.0).abs() < 1e-9 && en[1].abs() < 1e-9, "{en:?}");
        // seen from the origin turned round (the corridor behind), with a 22 m scanner: the
        // near end (9 m off) is closed, the far one is cut at the range (open)
        let pose2 = Pose {
            x: 0.0,
            y: 0.0,
            theta: std::f64::consts::PI,
        };
        let far = (22.0f64 * 22.0 - 7.5 * 7.5).sqrt();
        let c2 = [
            wall([-5.0, 7.5], [-far, 7.5]),
            wall([-5.0, -7.5], [-far, -7.5]),
        ];
        let s2 = sight(&c2, 22.0, TAU, Some(model.width)).expect("the corridor again");
        assert!(!s2.closed());
        let [st2, en2] = s2.frame(&pose2, model.heading, model.length);
        let (st2, en2) = (pose2.to_world(st2), pose2.to_world(en2));
        assert!(
            (st2[0] - 25.0).abs() < 1e-9 && st2[1].abs() < 1e-9,
            "{st2:?}"
        );
        assert!(
            (en2[0] - 5.0).abs() < 1e-9 && en2[1].abs() < 1e-9,
            "{en2:?}"
        );
        // a 270° scanner facing away along +x from x = 10 inside the corridor: the stretch
        // behind it ends at the edge of its view (135°), which is no wall end
        let inside = [
            wall([-7.5, 7.5], [15.0, 7.5]),
            wall([-7.5, -7.5], [15.0, -7.5]),
        ];
        let s3 = sight(&inside, 30.0, 270f64.to_radians(), None).expect("the corridor");
        assert!(!s3.closed());
        // a far end seen grazing (7° to the wall) is no wall end either
        let grazing = [
            wall([5.0, 7.5], [61.0, 7.5]),
            wall([5.0, -7.5], [61.0, -7.5]),
        ];
        assert!(
            !sight(&grazing, 80.0, TAU, None)
                .expect("the corridor")
                .closed()
        );
        // a corridor of another width is not this one
        assert!(sight(&c, 30.0, TAU, Some(10.0)).is_none());
    }

    #[test]
    fn the_length_is_measured_between_ends_seen_from_two_places() {
        // a 40 m corridor (x = 5…45), a 30 m scanner: from the origin facing +x the near end
        // is seen and the far one cut by the range; from x = 60 facing −x the other way round
        let far = (30.0f64 * 30.0 - 7.5 * 7.5).sqrt();
        let a = Pose {
            x: 0.0,
            y: 0.0,
            theta: 0.0,
        };
        let sa = sight(
            &[wall([5.0, 7.5], [far, 7.5]), wall([5.0, -7.5], [far, -7.5])],
            30.0,
            TAU,
            None,
        )
        .expect("from a");
        let b = Pose {
            x: 60.0,
            y: 0.0,
            theta: std::f64::consts::PI,
        };
        let sb = sight(
            &[
                wall([15.0, 7.5], [far, 7.5]),
                wall([15.0, -7.5], [far, -7.5]),
            ],
            30.0,
            TAU,
            None,
        )
        .expect("from b");
        assert!(!sa.closed() && !sb.closed());
        let m = learn(&[(a, sa), (b, sb)]).expect("a model");
        assert!((m.length.expect("a length") - 40.0).abs() < 1e-9, "{m:?}");
        let [st, en] = sa.frame(&a, m.heading, m.length);
        assert!((a.to_world(st)[0] - 45.0).abs() < 1e-9 && (a.to_world(en)[0] - 5.0).abs() < 1e-9);
    }

    #[test]
    fn collinear_pieces_or_one_wall_are_not_a_corridor() {
        let c = [
            wall([5.0, 7.5], [12.0, 7.5]),
            wall([14.0, 7.5], [25.0, 7.5]),
        ];
        assert!(sight(&c, 30.0, TAU, None).is_none());
        let crossing = [
            wall([5.0, 7.5], [25.0, 7.5]),
            wall([10.0, -5.0], [10.0, 5.0]),
        ];
        assert!(sight(&crossing, 30.0, TAU, None).is_none());
        // not facing: one ends where the other begins
        let apart = [
            wall([0.0, 7.5], [10.0, 7.5]),
            wall([12.0, -7.5], [20.0, -7.5]),
        ];
        assert!(sight(&apart, 30.0, TAU, None).is_none());
    }
}
