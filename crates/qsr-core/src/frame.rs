//! Reference frames: how reference entities turn world coordinates into the normalised
//! coordinates in which a calculus's partition is written (thesis §4.2, §3.3.2 eq. 3.11).
//!
//! All frames share one convention: the frame's "forward" axis is +y and **x < 0 is the left**
//! (counter-clockwise) side. The thesis prints its rotation Γ with determinant −1 (a
//! reflection) and a quadrant-blind `atan`; we use a proper rotation so handedness survives
//! (DESIGN §3).
//!
//! | frame | reference entities | origin | +y axis | scale |
//! |---|---|---|---|---|
//! | [`TernaryFrame`] | points A, B | A | towards B | 1/\|AB\| (B lands on (0,1)) |
//! | [`OrientedFrame`] | oriented point (origin, yaw) | origin | heading | none (metres) |
//! | [`ExtendedFrame`] | two oriented segments (walls) | midpoint of the starts | towards the midpoint of the ends | 1/length of that axis |
//!
//! A frame is built with `new`, which rejects non-finite input and degenerate references
//! (see [`DEGENERATE_TOLERANCE`]) with a [`QsrError`] instead of producing NaN.

use nalgebra::{Point2, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::{QsrError, Result, check_finite};

/// Relative tolerance below which two reference points count as coincident.
///
/// Points `A` and `B` are coincident when `|B − A|² ≤ DEGENERATE_TOLERANCE² · (1 + |A|² + |B|²)`:
/// relative for large coordinates (where f64 cannot resolve smaller differences anyway) and
/// absolute (1e-9 of a unit) near the origin. Written with squares so that the batch path
/// ([`crate::Calculus::classify_triplets`]) applies exactly the same test without branches.
pub const DEGENERATE_TOLERANCE: f64 = 1e-9;

/// Which kind of reference frame a calculus is written in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum FrameKind {
    /// `{A, B : C}`: two reference points and a located point.
    Ternary,
    /// `{A : C}`: an oriented reference point and a located point.
    BinaryOriented,
    /// Two oriented segments (walls) and a located point.
    Extended,
}

impl FrameKind {
    /// Number of input coordinates one relation instance takes on the command line
    /// (`ax ay bx by cx cy`; `ox oy yaw cx cy`; `p1x p1y q1x q1y p2x p2y q2x q2y cx cy`).
    #[must_use]
    pub fn input_len(self) -> usize {
        match self {
            Self::Ternary => 6,
            Self::BinaryOriented => 5,
            Self::Extended => 10,
        }
    }

    /// The kebab-case name used in specs.
    #[must_use]
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Ternary => "ternary",
            Self::BinaryOriented => "binary-oriented",
            Self::Extended => "extended",
        }
    }

    /// Builds the frame from a flat row of inputs (without the located point) and returns it
    /// with the located point; the layout is the one of [`FrameKind::input_len`].
    pub fn frame_from_row(self, row: &[f64]) -> Result<(AnyFrame, Point2<f64>)> {
        if row.len() != self.input_len() {
            return Err(QsrError::Arity(format!(
                "a {} relation takes {} numbers, got {}",
                self.as_str(),
                self.input_len(),
                row.len()
            )));
        }
        let p = |i: usize| Point2::new(row[i], row[i + 1]);
        let n = row.len();
        let located = p(n - 2);
        check_finite("located point", &[located.x, located.y])?;
        let frame = match self {
            Self::Ternary => AnyFrame::Ternary(TernaryFrame::new(p(0), p(2))?),
            Self::BinaryOriented => AnyFrame::Oriented(OrientedFrame::new(p(0), row[2])?),
            Self::Extended => AnyFrame::Extended(ExtendedFrame::new(
                Segment::new(p(0), p(2)),
                Segment::new(p(4), p(6)),
            )?),
        };
        Ok((frame, located))
    }
}

/// `(x, y)` of `p` in the frame at `origin` whose forward axis is `axis`, with lengths in
/// units of `|axis|` (pass `inv_len2 = 1` for a unit axis):
/// `y = (p−o)·d / |d|²`, `x = −(d × (p−o)) / |d|²`: no square root, no trigonometry.
#[inline(always)]
fn normalise(
    origin: &Point2<f64>,
    axis: &Vector2<f64>,
    inv_len2: f64,
    p: &Point2<f64>,
) -> Point2<f64> {
    let v = p - origin;
    let cross = axis.x * v.y - axis.y * v.x;
    Point2::new(-cross * inv_len2, axis.dot(&v) * inv_len2)
}

/// Inverse of [`normalise`]: `p = o + y·d + x·(d_y, −d_x)`.
#[inline(always)]
fn denormalise(origin: &Point2<f64>, axis: &Vector2<f64>, q: &Point2<f64>) -> Point2<f64> {
    Point2::new(
        origin.x + q.y * axis.x + q.x * axis.y,
        origin.y + q.y * axis.y - q.x * axis.x,
    )
}

pub(crate) fn coincident(a: &Point2<f64>, b: &Point2<f64>) -> bool {
    // Scale-free: divide by the largest coordinate first, so points 1e300 apart do not
    // overflow into "coincident" (inf ≤ inf) and the test means the same at every scale.
    let s = [a.x, a.y, b.x, b.y]
        .iter()
        .fold(1.0_f64, |m, v| m.max(v.abs()));
    let (a, b) = (a.coords / s, b.coords / s);
    let scale2 = 1.0 / (s * s) + a.norm_squared() + b.norm_squared();
    let d2 = (b - a).norm_squared();
    d2.is_nan() || d2 <= DEGENERATE_TOLERANCE * DEGENERATE_TOLERANCE * scale2
}

/// The ternary point frame `{A, B : ·}`: A ↦ (0, 0), B ↦ (0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TernaryFrame {
    origin: Point2<f64>,
    axis: Vector2<f64>,
    inv_len2: f64,
}

impl TernaryFrame {
    /// Frame of the reference points `a` and `b`.
    ///
    /// # Errors
    /// [`QsrError::NonFinite`] for NaN/∞ coordinates, [`QsrError::DegenerateFrame`] when
    /// `a` and `b` coincide (see [`DEGENERATE_TOLERANCE`]).
    pub fn new(a: Point2<f64>, b: Point2<f64>) -> Result<Self> {
        check_finite("reference points", &[a.x, a.y, b.x, b.y])?;
        if coincident(&a, &b) {
            return Err(QsrError::DegenerateFrame {
                reason: format!("reference points coincide: A = {a:?}, B = {b:?}"),
            });
        }
        let len2 = (b - a).norm_squared();
        if !len2.is_finite() {
            return Err(QsrError::NonFinite {
                what: format!(
                    "reference points A = {a:?}, B = {b:?} are too far apart to normalise \
                     (|B − A|² overflows)"
                ),
            });
        }
        Ok(Self::new_unchecked(a, b))
    }

    /// Frame without validation; the caller guarantees `a != b` and finite input.
    #[inline(always)]
    pub(crate) fn new_unchecked(a: Point2<f64>, b: Point2<f64>) -> Self {
        let axis = b - a;
        Self {
            origin: a,
            axis,
            inv_len2: 1.0 / axis.norm_squared(),
        }
    }

    /// Normalised coordinates of a world point.
    #[inline(always)]
    #[must_use]
    pub fn to_normalised(&self, p: &Point2<f64>) -> Point2<f64> {
        normalise(&self.origin, &self.axis, self.inv_len2, p)
    }

    /// World coordinates of a normalised point.
    #[inline(always)]
    #[must_use]
    pub fn to_world(&self, q: &Point2<f64>) -> Point2<f64> {
        denormalise(&self.origin, &self.axis, q)
    }

    /// `|AB|`, the length that becomes 1 in the normalised frame.
    #[must_use]
    pub fn scale(&self) -> f64 {
        self.axis.norm()
    }
}

/// The binary oriented frame `{A : ·}`: A at the origin, A's heading along +y, lengths kept
/// in world units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrientedFrame {
    origin: Point2<f64>,
    heading: Vector2<f64>,
}

impl OrientedFrame {
    /// Frame of an oriented point at `origin` facing `yaw` (radians, counter-clockwise from
    /// the world +x axis, the usual robotics convention).
    ///
    /// # Errors
    /// [`QsrError::NonFinite`] for NaN/∞ input.
    pub fn new(origin: Point2<f64>, yaw: f64) -> Result<Self> {
        check_finite("oriented reference", &[origin.x, origin.y, yaw])?;
        Ok(Self {
            origin,
            heading: Vector2::new(yaw.cos(), yaw.sin()),
        })
    }

    /// Frame-local coordinates of a world point (x < 0 is left of the heading).
    #[inline(always)]
    #[must_use]
    pub fn to_normalised(&self, p: &Point2<f64>) -> Point2<f64> {
        normalise(&self.origin, &self.heading, 1.0, p)
    }

    /// World coordinates of a frame-local point.
    #[inline(always)]
    #[must_use]
    pub fn to_world(&self, q: &Point2<f64>) -> Point2<f64> {
        denormalise(&self.origin, &self.heading, q)
    }
}

/// A directed segment: an extended landmark such as a wall, oriented from `start` to `end`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Segment {
    /// First end point.
    pub start: Point2<f64>,
    /// Second end point.
    pub end: Point2<f64>,
}

impl Segment {
    /// Segment from `start` to `end`.
    #[must_use]
    pub fn new(start: Point2<f64>, end: Point2<f64>) -> Self {
        Self { start, end }
    }
}

/// The extended frame of two oriented walls (the "front / between / behind" relation of
/// thesis §4.4.2): origin at the midpoint of the two start points, +y towards the midpoint
/// of the two end points, which lands on (0, 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtendedFrame {
    inner: TernaryFrame,
}

impl ExtendedFrame {
    /// Frame of two walls given in the same direction along the corridor they bound.
    ///
    /// # Errors
    /// [`QsrError::NonFinite`]; [`QsrError::DegenerateFrame`] when a wall has zero length,
    /// the walls point in opposite directions (their directions have a negative dot product),
    /// or the two midpoints coincide.
    pub fn new(wall1: Segment, wall2: Segment) -> Result<Self> {
        for (i, w) in [wall1, wall2].iter().enumerate() {
            check_finite(
                &format!("wall {}", i + 1),
                &[w.start.x, w.start.y, w.end.x, w.end.y],
            )?;
            if coincident(&w.start, &w.end) {
                return Err(QsrError::DegenerateFrame {
                    reason: format!("wall {} has zero length", i + 1),
                });
            }
        }
        let d1 = wall1.end - wall1.start;
        let d2 = wall2.end - wall2.start;
        if d1.dot(&d2) < 0.0 {
            return Err(QsrError::DegenerateFrame {
                reason: "walls point in opposite directions; give both in the same direction"
                    .into(),
            });
        }
        let start = nalgebra::center(&wall1.start, &wall2.start);
        let end = nalgebra::center(&wall1.end, &wall2.end);
        let inner = TernaryFrame::new(start, end).map_err(|_| QsrError::DegenerateFrame {
            reason: "the midpoints of the wall starts and ends coincide".into(),
        })?;
        Ok(Self { inner })
    }

    /// Normalised coordinates of a world point.
    #[inline(always)]
    #[must_use]
    pub fn to_normalised(&self, p: &Point2<f64>) -> Point2<f64> {
        self.inner.to_normalised(p)
    }

    /// World coordinates of a normalised point.
    #[must_use]
    pub fn to_world(&self, q: &Point2<f64>) -> Point2<f64> {
        self.inner.to_world(q)
    }
}

/// Any of the three frames, for code that handles every calculus alike.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyFrame {
    /// A ternary point frame.
    Ternary(TernaryFrame),
    /// A binary oriented frame.
    Oriented(OrientedFrame),
    /// An extended (two walls) frame.
    Extended(ExtendedFrame),
}

impl AnyFrame {
    /// Normalised coordinates of a world point.
    #[must_use]
    pub fn to_normalised(&self, p: &Point2<f64>) -> Point2<f64> {
        match self {
            Self::Ternary(f) => f.to_normalised(p),
            Self::Oriented(f) => f.to_normalised(p),
            Self::Extended(f) => f.to_normalised(p),
        }
    }

    /// The kind of this frame.
    #[must_use]
    pub fn kind(&self) -> FrameKind {
        match self {
            Self::Ternary(_) => FrameKind::Ternary,
            Self::Oriented(_) => FrameKind::BinaryOriented,
            Self::Extended(_) => FrameKind::Extended,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ternary_maps_a_and_b_and_keeps_handedness() {
        let f = TernaryFrame::new(Point2::new(2.0, 3.0), Point2::new(4.0, 3.0)).expect("frame");
        let a = f.to_normalised(&Point2::new(2.0, 3.0));
        let b = f.to_normalised(&Point2::new(4.0, 3.0));
        assert!((a - Point2::origin()).norm() < 1e-12);
        assert!((b - Point2::new(0.0, 1.0)).norm() < 1e-12);
        // Heading +x; the point at +y (counter-clockwise side) must be on the left (x < 0).
        let left = f.to_normalised(&Point2::new(3.0, 5.0));
        assert!((left - Point2::new(-1.0, 0.5)).norm() < 1e-12, "{left:?}");
        let back = f.to_world(&left);
        assert!((back - Point2::new(3.0, 5.0)).norm() < 1e-12);
    }

    #[test]
    fn degenerate_and_non_finite_references_are_errors() {
        let a = Point2::new(1.0, 1.0);
        assert!(matches!(
            TernaryFrame::new(a, a),
            Err(QsrError::DegenerateFrame { .. })
        ));
        assert!(matches!(
            TernaryFrame::new(a, Point2::new(f64::NAN, 0.0)),
            Err(QsrError::NonFinite { .. })
        ));
        assert!(matches!(
            OrientedFrame::new(a, f64::INFINITY),
            Err(QsrError::NonFinite { .. })
        ));
        let w = Segment::new(Point2::new(0.0, 0.0), Point2::new(0.0, 10.0));
        let w_back = Segment::new(Point2::new(5.0, 10.0), Point2::new(5.0, 0.0));
        assert!(matches!(
            ExtendedFrame::new(w, w_back),
            Err(QsrError::DegenerateFrame { .. })
        ));
    }

    #[test]
    fn oriented_frame_is_unscaled() {
        let f =
            OrientedFrame::new(Point2::new(1.0, 1.0), std::f64::consts::FRAC_PI_2).expect("frame");
        // Facing +y in the world: a point 3 m ahead is (0, 3); a point to the world −x is left.
        let q = f.to_normalised(&Point2::new(1.0, 4.0));
        assert!((q - Point2::new(0.0, 3.0)).norm() < 1e-12);
        let l = f.to_normalised(&Point2::new(-1.0, 1.0));
        assert!((l - Point2::new(-2.0, 0.0)).norm() < 1e-12);
    }
}
