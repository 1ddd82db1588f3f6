//! The Trajectory level (thesis §4.3.2): interchangeable controllers that turn a command
//! "go to qualitative state `q` of the frame (A, B)" into a path in the world.
//!
//! All of them work in the local frame of the reference landmarks the robot sees — the
//! only localisation Q-Link has — and return waypoints starting at the robot:
//!
//! | controller | path | thesis |
//! |---|---|---|
//! | [`ControllerKind::Arc`] | to the circle of radius R about the references' midpoint, then along the arc of that circle inside `q` | §4.4.1 |
//! | [`ControllerKind::MidpointSweep`] | to the references' midpoint; the sensor sweeps `q` from there | §4.4.2 |
//! | [`ControllerKind::ClosestPoint`] | straight to the closest point of `q` (a QP over the state's half-planes, clarabel) | §4.3.2 |
//! | [`ControllerKind::SafeSearch`] | a tour of lattice points of `q` that keep both references within range | §4.4.1's proposed improvement |
//! | [`ControllerKind::Direct`] | straight to the link landmark when it is in view (maps meeting Assumption 3; Proposition 4), else like the closest sampled point of `q` | §4.3.4 |
//!
//! [`circle`] is the full-circle search used when a command does not find the link.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
};
use qsr_core::{Calculus, Point2, Shape, StateId};
use serde::{Deserialize, Serialize};

use crate::error::{QlinkError, Result};

/// Which low-level controller.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum ControllerKind {
    /// Arc of radius R through the target state.
    Arc,
    /// Drive to the references' midpoint and sweep the sensor.
    MidpointSweep,
    /// Closest point of the target state (QP).
    ClosestPoint,
    /// Cover the target state keeping the references in view.
    SafeSearch,
    /// Drive straight to the link landmark when it is in view (Proposition 4).
    Direct,
}

impl std::str::FromStr for ControllerKind {
    type Err = QlinkError;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "arc" => Ok(Self::Arc),
            "midpoint-sweep" => Ok(Self::MidpointSweep),
            "closest-point" => Ok(Self::ClosestPoint),
            "safe-search" => Ok(Self::SafeSearch),
            "direct" => Ok(Self::Direct),
            _ => Err(QlinkError::InvalidParameter(format!(
                "unknown controller `{s}` (arc, midpoint-sweep, closest-point, safe-search, direct)"
            ))),
        }
    }
}

/// A configured controller.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Controller {
    /// Which one.
    pub kind: ControllerKind,
    /// Arc radius and the range within which references must stay (m).
    pub radius: f64,
    /// Lattice spacing of the safe search (m).
    pub spacing: f64,
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn state_at(calculus: &Calculus, a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> Option<usize> {
    calculus
        .classify_triplet(
            Point2::new(a[0], a[1]),
            Point2::new(b[0], b[1]),
            Point2::new(p[0], p[1]),
        )
        .ok()
        .map(StateId::index)
}

/// The qualitative state of `p` in the frame (A, B).
///
/// # Errors
/// Frame errors (coincident references).
pub fn robot_state(calculus: &Calculus, a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> Result<usize> {
    Ok(calculus
        .classify_triplet(
            Point2::new(a[0], a[1]),
            Point2::new(b[0], b[1]),
            Point2::new(p[0], p[1]),
        )?
        .index())
}

/// A full circle of radius `r` about `centre`: from `from`, straight to the circle, then
/// once around (counter-clockwise), as waypoints every `step_deg` degrees (at least 0.5°).
///
/// A radius that is not finite and ≥ 0, or a non-finite point, gives no circle: the path is
/// just `from` when it is finite, else empty — never NaN waypoints (issue 17).
#[must_use]
pub fn circle(centre: [f64; 2], r: f64, from: [f64; 2], step_deg: f64) -> Vec<[f64; 2]> {
    let finite = |p: [f64; 2]| p.iter().all(|v| v.is_finite());
    if !finite(from) {
        return Vec::new();
    }
    if !(r.is_finite() && r >= 0.0 && finite(centre)) {
        return vec![from];
    }
    let start = (from[1] - centre[1]).atan2(from[0] - centre[0]);
    let n = (360.0 / step_deg.max(0.5)).ceil() as usize;
    let mut out = vec![from];
    for k in 0..=n {
        let t = start + (k as f64) * std::f64::consts::TAU / n as f64;
        out.push([centre[0] + r * t.cos(), centre[1] + r * t.sin()]);
    }
    out
}

impl Controller {
    /// A controller of `kind` with radius/range `radius` and a safe-search spacing of
    /// `radius / 4`.
    #[must_use]
    pub fn new(kind: ControllerKind, radius: f64) -> Self {
        Self {
            kind,
            radius,
            spacing: radius / 4.0,
        }
    }

    /// Waypoints from `robot` into (and, for the arc and the search, through) state `target`
    /// of the frame of references `a`, `b`.
    ///
    /// # Errors
    /// [`QlinkError::Unsupported`] for the closest-point controller on a state bounded by
    /// circles; [`QlinkError::InvalidParameter`] for a non-positive radius; frame errors.
    pub fn path(
        &self,
        calculus: &Calculus,
        a: [f64; 2],
        b: [f64; 2],
        target: usize,
        robot: [f64; 2],
    ) -> Result<Vec<[f64; 2]>> {
        if self.radius.is_nan() || self.radius <= 0.0 || !self.radius.is_finite() {
            return Err(QlinkError::InvalidParameter(format!(
                "controller radius {} must be a positive number",
                self.radius
            )));
        }
        robot_state(calculus, a, b, robot)?; // rejects a degenerate frame
        let m = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        match self.kind {
            ControllerKind::Arc => Ok(self
                .arc(calculus, a, b, m, target, robot)
                .unwrap_or_else(|| self.nearest_sample(calculus, a, b, m, target, robot))),
            ControllerKind::MidpointSweep => Ok(vec![robot, m]),
            ControllerKind::ClosestPoint => {
                let p = closest_point(calculus, a, b, target, robot)?;
                Ok(vec![robot, p])
            }
            ControllerKind::SafeSearch => Ok(self.safe_search(calculus, a, b, m, target, robot)),
            // the navigator drives straight to a visible link; without one, head for the state
            ControllerKind::Direct => Ok(self.nearest_sample(calculus, a, b, m, target, robot)),
        }
    }

    fn arc(
        &self,
        calculus: &Calculus,
        a: [f64; 2],
        b: [f64; 2],
        m: [f64; 2],
        target: usize,
        robot: [f64; 2],
    ) -> Option<Vec<[f64; 2]>> {
        const N: usize = 180;
        let pt = |k: usize| {
            let t = k as f64 * std::f64::consts::TAU / N as f64;
            [m[0] + self.radius * t.cos(), m[1] + self.radius * t.sin()]
        };
        let inside: Vec<bool> = (0..N)
            .map(|k| state_at(calculus, a, b, pt(k)) == Some(target))
            .collect();
        if !inside.iter().any(|&x| x) {
            return None;
        }
        if inside.iter().all(|&x| x) {
            return Some(circle(m, self.radius, robot, 2.0));
        }
        // longest circular run of target samples
        let start0 = (0..N).find(|&k| !inside[k]).unwrap_or(0);
        let (mut best, mut cur) = ((0usize, 0usize), None::<(usize, usize)>);
        for i in 1..=N {
            let k = (start0 + i) % N;
            if inside[k] {
                cur = Some(match cur {
                    Some((s, l)) => (s, l + 1),
                    None => (k, 1),
                });
                if let Some(c) = cur
                    && c.1 > best.1
                {
                    best = c;
                }
            } else {
                cur = None;
            }
        }
        let (s, len) = best;
        let first = pt(s);
        let last = pt((s + len - 1) % N);
        let forward = dist(robot, first) <= dist(robot, last);
        let mut out = vec![robot];
        for i in 0..len {
            let k = if forward {
                (s + i) % N
            } else {
                (s + len - 1 - i) % N
            };
            out.push(pt(k));
        }
        Some(out)
    }

    /// Fallback: straight to the nearest sampled point of the state within the radius.
    fn nearest_sample(
        &self,
        calculus: &Calculus,
        a: [f64; 2],
        b: [f64; 2],
        m: [f64; 2],
        target: usize,
        robot: [f64; 2],
    ) -> Vec<[f64; 2]> {
        let mut best: Option<[f64; 2]> = None;
        for i in 1..=20 {
            let r = self.radius * f64::from(i) / 20.0;
            for k in 0..72 {
                let t = f64::from(k) * std::f64::consts::TAU / 72.0;
                let p = [m[0] + r * t.cos(), m[1] + r * t.sin()];
                if state_at(calculus, a, b, p) == Some(target)
                    && best.is_none_or(|q| dist(robot, p) < dist(robot, q))
                {
                    best = Some(p);
                }
            }
        }
        match best {
            Some(p) => vec![robot, p],
            None => vec![robot, m],
        }
    }

    fn safe_search(
        &self,
        calculus: &Calculus,
        a: [f64; 2],
        b: [f64; 2],
        m: [f64; 2],
        target: usize,
        robot: [f64; 2],
    ) -> Vec<[f64; 2]> {
        let s = self.spacing.max(0.5);
        let n = (self.radius / s).ceil() as i64;
        let reach = 0.95 * self.radius;
        let mut pts: Vec<[f64; 2]> = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                let p = [m[0] + i as f64 * s, m[1] + j as f64 * s];
                if dist(p, a) <= reach
                    && dist(p, b) <= reach
                    && state_at(calculus, a, b, p) == Some(target)
                {
                    pts.push(p);
                }
            }
        }
        if pts.is_empty() {
            return self
                .arc(calculus, a, b, m, target, robot)
                .unwrap_or_else(|| self.nearest_sample(calculus, a, b, m, target, robot));
        }
        // nearest-neighbour tour
        let mut out = vec![robot];
        let mut at = robot;
        while !pts.is_empty() {
            let (i, _) = pts
                .iter()
                .enumerate()
                .min_by(|x, y| dist(at, *x.1).total_cmp(&dist(at, *y.1)))
                .unwrap_or((0, &at));
            at = pts.swap_remove(i);
            out.push(at);
        }
        out
    }
}

/// The closest point of state `target` to `robot` (1 % of |AB| inside its boundary): a QP
/// `min ‖x − robot‖²` over the half-planes of each convex piece of the state, solved with
/// clarabel; the best piece wins.
///
/// # Errors
/// [`QlinkError::Unsupported`] when the state is bounded by circles or the calculus is a
/// raster; [`QlinkError::InvalidParameter`] when no piece is feasible.
pub fn closest_point(
    calculus: &Calculus,
    a: [f64; 2],
    b: [f64; 2],
    target: usize,
    robot: [f64; 2],
) -> Result<[f64; 2]> {
    let spec = calculus.spec();
    if spec.constraints.is_empty()
        || spec
            .constraints
            .iter()
            .any(|c| !matches!(c.shape, Shape::Line { .. }))
    {
        return Err(QlinkError::Unsupported(format!(
            "the closest-point controller needs a calculus of lines; `{}` has circles or a raster",
            calculus.name()
        )));
    }
    let state = spec
        .states
        .get(target)
        .ok_or_else(|| QlinkError::InvalidParameter(format!("state {target} does not exist")))?;
    let frame = qsr_core::TernaryFrame::new(Point2::new(a[0], a[1]), Point2::new(b[0], b[1]))?;
    // value of constraint k at a world point, in normalised units
    let g = |k: usize, x: [f64; 2]| {
        let p = frame.to_normalised(&Point2::new(x[0], x[1]));
        spec.constraints[k].shape.value(p.x, p.y)
    };
    let margin = 0.01;
    let mut best: Option<([f64; 2], f64)> = None;
    for pattern in &state.cells {
        // rows: −∇g·x' ≤ g(A) − margin for "+", ∇g·x' ≤ −g(A) − margin for "−" (x' = x − A)
        let mut rows: Vec<[f64; 2]> = Vec::new();
        let mut rhs: Vec<f64> = Vec::new();
        for (k, ch) in pattern.chars().enumerate() {
            let g0 = g(k, a);
            let gx = g(k, [a[0] + 1.0, a[1]]) - g0;
            let gy = g(k, [a[0], a[1] + 1.0]) - g0;
            match ch {
                '+' => {
                    rows.push([-gx, -gy]);
                    rhs.push(g0 - margin);
                }
                '-' => {
                    rows.push([gx, gy]);
                    rhs.push(-g0 - margin);
                }
                _ => {}
            }
        }
        if let Some(x) = nearest_in_piece(&rows, &rhs, a, robot)? {
            let d = dist(x, robot);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((x, d));
            }
        }
    }
    best.map(|(x, _)| x).ok_or_else(|| {
        QlinkError::InvalidParameter(format!("state {target} has no feasible convex piece"))
    })
}

/// The point of the convex piece `rows · (x − a) ≤ rhs` nearest `robot` (clarabel QP), or
/// `None` when the piece is infeasible.
fn nearest_in_piece(
    rows: &[[f64; 2]],
    rhs: &[f64],
    a: [f64; 2],
    robot: [f64; 2],
) -> Result<Option<[f64; 2]>> {
    let p_mat = CscMatrix::from(&[[2.0, 0.0], [0.0, 2.0]]);
    let q = vec![-2.0 * (robot[0] - a[0]), -2.0 * (robot[1] - a[1])];
    // CSC by columns: column 0 holds the x coefficients, column 1 the y ones
    let m_rows = rows.len();
    let a_mat = CscMatrix::new(
        m_rows,
        2,
        vec![0, m_rows, 2 * m_rows],
        (0..m_rows).chain(0..m_rows).collect(),
        rows.iter()
            .map(|r| r[0])
            .chain(rows.iter().map(|r| r[1]))
            .collect(),
    );
    let cones = [NonnegativeConeT(rows.len())];
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .map_err(|e| QlinkError::InvalidParameter(format!("clarabel settings: {e:?}")))?;
    let mut solver = DefaultSolver::new(&p_mat, &q, &a_mat, rhs, &cones, settings)
        .map_err(|e| QlinkError::InvalidParameter(format!("clarabel: {e:?}")))?;
    solver.solve();
    Ok(matches!(
        solver.solution.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    )
    .then(|| [a[0] + solver.solution.x[0], a[1] + solver.solution.x[1]]))
}

#[cfg(test)]
mod circle_tests {
    use super::circle;

    /// Regression (issue 17): `circle` with `r = NaN` returned NaN waypoints.
    #[test]
    fn circle_never_returns_nan_waypoints() {
        for (c, r, from) in [
            ([0.0, 0.0], f64::NAN, [1.0, 0.0]),
            ([0.0, 0.0], f64::INFINITY, [1.0, 0.0]),
            ([0.0, 0.0], -1.0, [1.0, 0.0]),
            ([f64::NAN, 0.0], 1.0, [1.0, 0.0]),
            ([0.0, 0.0], 1.0, [f64::NAN, 0.0]),
        ] {
            let p = circle(c, r, from, f64::NAN);
            assert!(
                p.iter().flatten().all(|v| v.is_finite()),
                "{c:?} {r} {from:?}: {p:?}"
            );
        }
        assert!(circle([0.0, 0.0], 2.0, [5.0, 0.0], 10.0).len() > 30);
    }
}
