//! Compiled partitions of the normalised plane: classification is a pure function from a
//! normalised point to a state index.
//!
//! - [`ConstraintPartition`]: sign vector of the constraints → base cell → state through a
//!   `2^k` table. Sign vectors that no spec pattern claims and that the validation sampler
//!   never met take the state of the nearest claimed vector (fewest differing signs, lowest
//!   index on ties), so classification is total even for a vector the sampler missed.
//! - [`RasterPartition`]: a label raster over a window plus an [`OutsideRule`].

use nalgebra::Point2;

use crate::fused::Grouped;
use crate::spec::{OutsideRule, RasterSpec, Shape, Side};
use crate::state::{StateId, StateIndex};

/// Sign-vector classification by lines and circles.
#[derive(Debug, Clone)]
pub struct ConstraintPartition {
    /// `(a, b, c, bit, zero_positive)` of each general line.
    lines: Vec<([f64; 3], u32, bool)>,
    /// Lines `x + c` and `y + c` as one comparison: `(axis (0 = x, 1 = y), −c, bit, ≥ or >)`.
    thresholds: Vec<(usize, f64, u32, bool)>,
    /// `(cx, cy, r², bit, zero_positive)` of each circle.
    circles: Vec<([f64; 3], u32, bool)>,
    shapes: Vec<Shape>,
    table: Vec<u16>,
    /// The constraints grouped for the kernels per shape, and whether this shape has one.
    /// (Boxed: a partition is passed by value in enums and kept small.)
    pub(crate) grouped: Box<Grouped>,
    pub(crate) fused: bool,
}

impl ConstraintPartition {
    /// Compiles constraints and a (complete) `2^k` table.
    pub(crate) fn new(constraints: &[(Shape, Side)], table: Vec<u16>) -> Self {
        let mut lines = Vec::new();
        let mut thresholds = Vec::new();
        let mut circles = Vec::new();
        for (i, (shape, zero)) in constraints.iter().enumerate() {
            let pos = *zero == Side::Positive;
            match *shape {
                // `u + c ≥ 0` ⇔ `u ≥ −c` exactly in IEEE arithmetic (a rounded sum is zero only
                // when the exact sum is, and keeps its sign), so lines `x + c` and `y + c` (all
                // the built-ins' lines) become one comparison with identical results.
                Shape::Line { a: 1.0, b: 0.0, c } => thresholds.push((0, -c, i as u32, pos)),
                Shape::Line { a: 0.0, b: 1.0, c } => thresholds.push((1, -c, i as u32, pos)),
                Shape::Line { a, b, c } => lines.push(([a, b, c], i as u32, pos)),
                Shape::Circle { center, radius } => {
                    circles.push(([center[0], center[1], radius * radius], i as u32, pos));
                }
            }
        }
        let grouped = Box::new(Grouped::new(
            &constraints
                .iter()
                .map(|(s, z)| (*s, *z == Side::Positive))
                .collect::<Vec<_>>(),
        ));
        let fused = grouped.has_kernel();
        Self {
            lines,
            thresholds,
            circles,
            shapes: constraints.iter().map(|(s, _)| *s).collect(),
            table,
            grouped,
            fused,
        }
    }

    /// The sign vector of a point (bit i set when constraint i is on its positive side).
    #[inline(always)]
    #[must_use]
    pub fn sign_vector(&self, x: f64, y: f64) -> u32 {
        // Branch-free: the sign of f is random data, so a branch per constraint would be
        // mispredicted half the time (it cost 3x in the classification benchmark).
        let mut v = 0u32;
        for &(axis, t, bit, pos) in &self.thresholds {
            let u = if axis == 0 { x } else { y };
            let s = u32::from(u > t) | (u32::from(u == t) & u32::from(pos));
            v |= s << bit;
        }
        for &([a, b, c], bit, pos) in &self.lines {
            let f = a * x + b * y + c;
            let s = u32::from(f > 0.0) | (u32::from(f == 0.0) & u32::from(pos));
            v |= s << bit;
        }
        for &([cx, cy, r2], bit, pos) in &self.circles {
            let dx = x - cx;
            let dy = y - cy;
            let f = dx * dx + dy * dy - r2;
            let s = u32::from(f > 0.0) | (u32::from(f == 0.0) & u32::from(pos));
            v |= s << bit;
        }
        v
    }

    /// State index of a normalised point.
    #[inline(always)]
    #[must_use]
    pub fn classify(&self, x: f64, y: f64) -> u16 {
        self.table[self.sign_vector(x, y) as usize]
    }

    /// States of a block of normalised points (`xs`, `ys`, `out` of equal length).
    ///
    /// Through the kernel of the partition's shape where it has one (every built-in: see
    /// `crate::fused`), else by the general loops — the same states either way.
    #[inline]
    pub fn classify_block(&self, xs: &[f64], ys: &[f64], out: &mut [u16]) {
        let n = xs.len().min(ys.len()).min(out.len());
        let (xs, ys) = (&xs[..n], &ys[..n]);
        if self.fused {
            self.classify_points(n, |i| (xs[i], ys[i], true), out);
            return;
        }
        self.classify_block_general(xs, ys, &mut out[..n]);
    }

    /// States of `n` points given by `point(i) = (x, y, valid)` into `out[..n]` (in the
    /// caller's [`StateIndex`] type, written in place rather than copied from a buffer block
    /// by block), and whether every point was valid: through the kernel of this partition's
    /// shape when it has one (each point in registers from `point` to its sign vector: a
    /// caller that normalises in `point` fuses the two), else the general block loop.
    #[inline(always)]
    pub(crate) fn classify_points<O: StateIndex>(
        &self,
        n: usize,
        point: impl Fn(usize) -> (f64, f64, bool),
        out: &mut [O],
    ) -> bool {
        let mut v = [0u32; BLOCK];
        let mut valid = true;
        let mask = self.table.len() - 1;
        for start in (0..n).step_by(BLOCK) {
            let end = (start + BLOCK).min(n);
            let at = |i: usize| point(start + i);
            // a full block as an array: its length a constant, the kernel's loop has no tail
            let kernel = if end - start == BLOCK {
                self.grouped.dispatch(at, &mut v)
            } else {
                self.grouped.dispatch(at, &mut v[..end - start])
            };
            let bv = &v[..end - start];
            match kernel {
                Some(ok) => valid &= ok,
                None => {
                    let (mut xs, mut ys) = ([0.0; BLOCK], [0.0; BLOCK]);
                    for i in 0..end - start {
                        let (x, y, ok) = point(start + i);
                        (xs[i], ys[i]) = (x, y);
                        valid &= ok;
                    }
                    let m = end - start;
                    let mut states = [0u16; BLOCK];
                    self.classify_block_general(&xs[..m], &ys[..m], &mut states[..m]);
                    for (o, s) in out[start..end].iter_mut().zip(&states[..m]) {
                        *o = O::from_state(StateId(*s));
                    }
                    continue;
                }
            }
            for (o, vi) in out[start..end].iter_mut().zip(bv.iter()) {
                *o = O::from_state(StateId(self.table[*vi as usize & mask]));
            }
        }
        valid
    }

    /// [`ConstraintPartition::classify_block`] by the general loops, one pass per constraint
    /// (kept for shapes without a kernel, and as the reference the kernels are tested on).
    ///
    /// Constraint-outer, point-inner: each inner loop is one comparison over the block,
    /// which LLVM vectorises; classifying point by point this way runs ~3x slower.
    pub(crate) fn classify_block_general(&self, xs: &[f64], ys: &[f64], out: &mut [u16]) {
        let n = xs.len().min(ys.len()).min(out.len());
        let (xs, ys) = (&xs[..n], &ys[..n]);
        // Sign vectors in u32 lanes: a spec has at most MAX_CONSTRAINTS = 16 constraints, and
        // u32 measured fastest (criterion `classify`, EDC, one core: u64 8.6 ns, u16 8.4,
        // u32 8.1 per triplet).
        let mut v = [0u32; BLOCK];
        for start in (0..n).step_by(BLOCK) {
            let end = (start + BLOCK).min(n);
            let (bx, by) = (&xs[start..end], &ys[start..end]);
            let bv = &mut v[..end - start];
            bv.fill(0);
            // The zero-set side is chosen once per constraint and block, outside the loop.
            for &(axis, t, bit, pos) in &self.thresholds {
                let coords = if axis == 0 { bx } else { by };
                let points = bv.iter_mut().zip(coords);
                if pos {
                    points.for_each(|(vi, &u)| *vi |= u32::from(u >= t) << bit);
                } else {
                    points.for_each(|(vi, &u)| *vi |= u32::from(u > t) << bit);
                }
            }
            for &([a, b, c], bit, pos) in &self.lines {
                let points = bv.iter_mut().zip(bx).zip(by);
                if pos {
                    points.for_each(|((vi, &x), &y)| {
                        *vi |= u32::from(a * x + b * y + c >= 0.0) << bit
                    });
                } else {
                    points.for_each(|((vi, &x), &y)| {
                        *vi |= u32::from(a * x + b * y + c > 0.0) << bit
                    });
                }
            }
            for &([cx, cy, r2], bit, pos) in &self.circles {
                let points = bv.iter_mut().zip(bx).zip(by);
                let f = |x: f64, y: f64| (x - cx) * (x - cx) + (y - cy) * (y - cy) - r2;
                if pos {
                    points.for_each(|((vi, &x), &y)| *vi |= u32::from(f(x, y) >= 0.0) << bit);
                } else {
                    points.for_each(|((vi, &x), &y)| *vi |= u32::from(f(x, y) > 0.0) << bit);
                }
            }
            for (o, vi) in out[start..end].iter_mut().zip(bv.iter()) {
                *o = self.table[*vi as usize];
            }
        }
    }

    /// The constraint curves, in spec order.
    #[must_use]
    pub fn shapes(&self) -> &[Shape] {
        &self.shapes
    }

    /// The full `2^k` base-cell → state table.
    #[must_use]
    pub fn table(&self) -> &[u16] {
        &self.table
    }
}

/// Points per block in [`ConstraintPartition::classify_block`].
pub(crate) const BLOCK: usize = 128;

/// Relative distance below which a point's side of a curve is decided by rounding.
pub const ROUNDING_MARGIN: f64 = 1e-10;

impl Partition {
    /// Whether f64 rounding can decide the state of `p`: it lies within
    /// `ROUNDING_MARGIN · scale` of a circle or a raster cell edge, or of a line without
    /// being exactly on it. `scale` should bound the magnitudes `p` was computed from.
    ///
    /// Points exactly on a line are *not* ambiguous: the spec's zero-set rule decides them
    /// and the arithmetic that puts them there (dyadic coordinates) is exact.
    #[must_use]
    pub fn is_ambiguous(&self, p: &Point2<f64>, scale: f64) -> bool {
        self.near_boundary(p, scale, false)
    }

    /// [`Partition::is_ambiguous`], and with `exact_lines_too` also points exactly on a line:
    /// true for every point that is not in general position.
    #[must_use]
    pub fn near_boundary(&self, p: &Point2<f64>, scale: f64, exact_lines_too: bool) -> bool {
        let tol = ROUNDING_MARGIN * scale.max(1.0);
        match self {
            Self::Constraints(c) => c.shapes.iter().any(|s| match *s {
                Shape::Line { a, b, c } => {
                    let f = a * p.x + b * p.y + c;
                    (exact_lines_too || f != 0.0) && f.abs() < tol * a.hypot(b)
                }
                Shape::Circle { center, radius } => {
                    ((p.x - center[0]).hypot(p.y - center[1]) - radius).abs() < tol
                }
            }),
            Self::Raster(r) => {
                let fx = (p.x - r.x0) / r.dx;
                let fy = (p.y - r.y0) / r.dy;
                let near = |f: f64, d: f64| (f - f.round()).abs() * d < tol;
                near(fx, r.dx) || near(fy, r.dy)
            }
        }
    }
}

/// Fills unclaimed table entries with the state of the nearest claimed sign vector.
pub(crate) fn complete_table(table: &mut [u16]) {
    let claimed: Vec<(u32, u16)> = table
        .iter()
        .enumerate()
        .filter(|(_, s)| **s != u16::MAX)
        .map(|(v, s)| (v as u32, *s))
        .collect();
    for (v, slot) in table.iter_mut().enumerate() {
        if *slot == u16::MAX
            && let Some(&(_, s)) = claimed
                .iter()
                .min_by_key(|(w, _)| ((*w ^ v as u32).count_ones(), *w))
        {
            *slot = s;
        }
    }
}

/// A label raster over a window of the normalised plane.
#[derive(Debug, Clone)]
pub struct RasterPartition {
    x0: f64,
    y0: f64,
    dx: f64,
    dy: f64,
    nx: usize,
    ny: usize,
    cells: Vec<u16>,
    outside: Option<u16>,
}

impl RasterPartition {
    /// Compiles a validated raster spec; `outside_state` resolves an
    /// [`OutsideRule::State`] label.
    pub(crate) fn new(spec: &RasterSpec, outside_state: Option<u16>) -> Self {
        let [x0, x1, y0, y1] = spec.window;
        Self {
            x0,
            y0,
            dx: (x1 - x0) / spec.nx as f64,
            dy: (y1 - y0) / spec.ny as f64,
            nx: spec.nx,
            ny: spec.ny,
            cells: spec.cells.clone(),
            outside: match spec.outside {
                OutsideRule::Clamp => None,
                OutsideRule::State { .. } => outside_state,
            },
        }
    }

    /// State index of a normalised point.
    #[inline(always)]
    #[must_use]
    pub fn classify(&self, x: f64, y: f64) -> u16 {
        let fx = ((x - self.x0) / self.dx).floor();
        let fy = ((y - self.y0) / self.dy).floor();
        let inside = fx >= 0.0 && fy >= 0.0 && fx < self.nx as f64 && fy < self.ny as f64;
        if !inside && let Some(s) = self.outside {
            return s;
        }
        // Clamp (also guards the last-cell edge case x == x_max).
        let ix = fx.clamp(0.0, (self.nx - 1) as f64) as usize;
        let iy = fy.clamp(0.0, (self.ny - 1) as f64) as usize;
        self.cells[iy * self.nx + ix]
    }

    /// `(nx, ny)`.
    #[must_use]
    pub fn shape(&self) -> (usize, usize) {
        (self.nx, self.ny)
    }

    /// `[x_min, x_max, y_min, y_max]`.
    #[must_use]
    pub fn window(&self) -> [f64; 4] {
        [
            self.x0,
            self.x0 + self.dx * self.nx as f64,
            self.y0,
            self.y0 + self.dy * self.ny as f64,
        ]
    }

    /// Cell size `(dx, dy)`.
    #[must_use]
    pub fn cell_size(&self) -> (f64, f64) {
        (self.dx, self.dy)
    }

    /// Label of cell `(ix, iy)`.
    #[must_use]
    pub fn cell(&self, ix: usize, iy: usize) -> u16 {
        self.cells[iy * self.nx + ix]
    }

    /// The fixed outside state, if the rule is [`OutsideRule::State`].
    #[must_use]
    pub fn outside_state(&self) -> Option<u16> {
        self.outside
    }

    /// Lower-left corner of cell `(ix, iy)`.
    #[must_use]
    pub fn cell_origin(&self, ix: usize, iy: usize) -> Point2<f64> {
        Point2::new(self.x0 + ix as f64 * self.dx, self.y0 + iy as f64 * self.dy)
    }
}

/// A compiled partition of either kind.
#[derive(Debug, Clone)]
pub enum Partition {
    /// Lines and circles with a sign-vector table.
    Constraints(ConstraintPartition),
    /// A label raster.
    Raster(RasterPartition),
}

impl Partition {
    /// State index of a normalised point.
    #[inline(always)]
    #[must_use]
    pub fn classify(&self, p: &Point2<f64>) -> u16 {
        match self {
            Self::Constraints(c) => c.classify(p.x, p.y),
            Self::Raster(r) => r.classify(p.x, p.y),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unclaimed_vectors_take_the_nearest_claimed_state() {
        let mut t = vec![0, u16::MAX, u16::MAX, 3];
        complete_table(&mut t);
        // 0b01 is one flip from 0b00 (state 0) and from 0b11 (state 3); ties go to the
        // lower vector.
        assert_eq!(t, vec![0, 0, 0, 3]);
    }
}
