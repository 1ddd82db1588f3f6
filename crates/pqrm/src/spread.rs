//! Where a landmark's samples lie, and what that settles before any sample is classified.
//!
//! Most triplets of a scan sit far from every boundary of the calculus compared with their
//! landmarks' noise: all `s` sampled configurations fall in one state of every ordering, and
//! classifying them one by one only confirms it (53 % of the 166,650 EDC triplets of 101
//! landmarks with σ 0.2–0.8 m over 60 × 60 m, 90 % for left-right, at s = 1000). Each
//! landmark's samples lie in a disc; [`FrameBounds`] bounds C's base-frame position `(x, y)`
//! for *every* configuration of the three discs, so where a quantity keeps one sign over
//! those bounds every sample gives that sign. A triplet whose quantities all keep their sign
//! is counted at once — `s` in the state of its one key — which is exactly what classifying
//! the samples gives: a proof about the samples, not an estimate of their histogram, so the
//! counts stay bit for bit what they were.
//!
//! The bound is the worst case of three independent discs (all three samples at their rims,
//! aligned), looser than the samples' joint spread: it settles 23 % of those EDC triplets
//! (canonical), of the 53 % in one state throughout. Discs per chunk of samples, and the
//! samples' own joint radius, settle more but cost as much as they save (measured; see
//! docs/performance.md).
//!
//! **Rounding.** The kernel computes each sample's quantities in floating point, and the
//! bounds here are computed in floating point too. Both err by at most a few units in the
//! last place of the terms' magnitudes (`|A|·n + |B|·|x| + |C|·|y| + |D|`, with `x` and `y`
//! off by `ε·√n`); a sign is taken only when the bound clears zero by `10⁻⁹` of that
//! magnitude, far more than the rounding can move it, and radii are rounded up by as much.
//! A sample on or within that margin of a boundary leaves the triplet to the sample-by-sample
//! count. The coincidence checks are settled the same way: the discs must keep the landmarks
//! apart by a margin, or the samples are checked one by one as before (and an error is the
//! same error).

/// The disc a landmark's samples lie in: its centre (the middle of their bounding box) and
/// radius (the farthest sample from it, rounded up), and the largest squared norm of a
/// sample (the coincidence checks' scale). `None` when a sample is not finite or there are
/// none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Spread {
    pub centre: [f64; 2],
    pub radius: f64,
    pub max_norm2: f64,
}

impl Spread {
    /// The disc of the samples `(xs[i], ys[i])`.
    pub fn of(xs: &[f64], ys: &[f64]) -> Option<Self> {
        if xs.is_empty() || xs.len() != ys.len() {
            return None;
        }
        // eight independent lanes, so that the extremes vectorise (a reduction of
        // `f64::min` over one accumulator does not: it cost 6 % of a step at σ = 10, where
        // nothing is settled)
        let mut lo = [[f64::INFINITY; LANES]; 2];
        let mut hi = [[f64::NEG_INFINITY; LANES]; 2];
        let mut norm2 = [0.0f64; LANES];
        // 0 while every sample is finite; `∞ · 0` and `NaN · 0` make it NaN
        let mut poison = [0.0f64; LANES];
        let mut lane = |l: usize, u: f64, v: f64| {
            lo[0][l] = if u < lo[0][l] { u } else { lo[0][l] };
            hi[0][l] = if u > hi[0][l] { u } else { hi[0][l] };
            lo[1][l] = if v < lo[1][l] { v } else { lo[1][l] };
            hi[1][l] = if v > hi[1][l] { v } else { hi[1][l] };
            let r = u * u + v * v;
            norm2[l] = if r > norm2[l] { r } else { norm2[l] };
            poison[l] += u * 0.0 + v * 0.0;
        };
        let (xc, yc) = (xs.chunks_exact(LANES), ys.chunks_exact(LANES));
        let (xr, yr) = (xc.remainder(), yc.remainder());
        for (u, v) in xc.zip(yc) {
            for l in 0..LANES {
                lane(l, u[l], v[l]);
            }
        }
        for (l, (&u, &v)) in xr.iter().zip(yr).enumerate() {
            lane(l, u, v);
        }
        if poison.iter().any(|p| *p != 0.0) {
            return None;
        }
        let fold =
            |v: &[f64; LANES], f: fn(f64, f64) -> f64| v[1..].iter().fold(v[0], |a, b| f(a, *b));
        let (x, y) = (
            [fold(&lo[0], f64::min), fold(&hi[0], f64::max)],
            [fold(&lo[1], f64::min), fold(&hi[1], f64::max)],
        );
        let max_norm2 = fold(&norm2, f64::max);
        let centre = [0.5 * x[0] + 0.5 * x[1], 0.5 * y[0] + 0.5 * y[1]];
        let mut r2 = [0.0f64; LANES];
        let mut lane = |l: usize, u: f64, v: f64| {
            let d = (u - centre[0]) * (u - centre[0]) + (v - centre[1]) * (v - centre[1]);
            r2[l] = if d > r2[l] { d } else { r2[l] };
        };
        for (u, v) in xs.chunks_exact(LANES).zip(ys.chunks_exact(LANES)) {
            for l in 0..LANES {
                lane(l, u[l], v[l]);
            }
        }
        for (l, (&u, &v)) in xr.iter().zip(yr).enumerate() {
            lane(l, u, v);
        }
        // rounded up: the radius only has to be at least the true one
        let radius = fold(&r2, f64::max).sqrt() * (1.0 + MARGIN) + f64::MIN_POSITIVE;
        Some(Self {
            centre,
            radius,
            max_norm2,
        })
    }
}

/// Accumulators of [`Spread::of`].
const LANES: usize = 8;

/// How far a bound must clear zero, relative to the magnitude of the terms it sums.
const MARGIN: f64 = 1e-9;

/// Where C can be in the base frame of an unordered triplet `{A, B, C}` (A = (0, 0),
/// B = (0, 1), as the counting kernel computes it) for every configuration of three discs.
///
/// As complex numbers, the frame's `y − i·x` is `z = (C − A)/(B − A)`. Moving A, B, C by
/// `δA, δB, δC` moves it *exactly* by `(δC − z·δB − (1 − z)·δA)/(B − A + δB − δA)`, so
/// every configuration lies in the disc about the centres' `z₀` of radius
/// `ρ = (r_C + |z₀|·r_B + |1 − z₀|·r_A)/(|B₀ − A₀| − r_A − r_B)`. (Interval arithmetic over
/// the samples' bounding boxes was tried first: it counts each displacement twice and settled
/// a quarter as many triplets.)
#[derive(Debug, Clone, Copy)]
pub(crate) struct FrameBounds {
    /// The disc's centre `(x, y)` and radius.
    x: f64,
    y: f64,
    rho: f64,
}

impl FrameBounds {
    /// The bounds, or `None` when the discs let A and B come within `ab` (squared distance),
    /// or — with `others` — C come within `ac` of A or `bc` of B: the thresholds of the
    /// kernel's coincidence checks, so that a triplet given bounds passes them for every
    /// sample.
    pub fn new([a, b, c]: [&Spread; 3], [ab, ac, bc]: [f64; 3], others: bool) -> Option<Self> {
        let dist =
            |p: &Spread, q: &Spread| norm(q.centre[0] - p.centre[0], q.centre[1] - p.centre[1]);
        // the least distance two discs allow, squared, must clear the threshold
        let apart = |p: &Spread, q: &Spread, t: f64| {
            let least = dist(p, q) - p.radius - q.radius;
            least > 0.0 && (least * least).is_finite() && least * least * (1.0 - MARGIN) > t
        };
        if !apart(a, b, ab) || (others && !(apart(a, c, ac) && apart(b, c, bc))) {
            return None;
        }
        let (dx, dy) = (b.centre[0] - a.centre[0], b.centre[1] - a.centre[1]);
        let (vx, vy) = (c.centre[0] - a.centre[0], c.centre[1] - a.centre[1]);
        let len2 = dx * dx + dy * dy;
        let x = -(dx * vy - dy * vx) / len2;
        let y = (dx * vx + dy * vy) / len2;
        let (z, one_minus_z) = (norm(x, y), norm(x, 1.0 - y));
        let least_d = len2.sqrt() - a.radius - b.radius;
        let rho = (c.radius + z * b.radius + one_minus_z * a.radius) / least_d;
        let bounds = Self {
            x,
            y,
            rho: rho * (1.0 + MARGIN),
        };
        [x, y, bounds.rho]
            .iter()
            .all(|v| v.is_finite())
            .then_some(bounds)
    }

    /// The scale of a bound's rounding: the magnitudes of the base frame's `x`, `y`, `n`.
    fn reach(&self) -> f64 {
        norm(self.x, self.y) + self.rho + 1.0
    }

    /// The sign of `u − t` over the disc, `u` the base frame's `n = x² + y²` (`var` 0), `x`
    /// (1) or `y` (2).
    pub fn single(&self, var: usize, t: f64) -> Option<bool> {
        let reach = self.reach();
        let [lo, hi] = match var {
            0 => {
                let r = norm(self.x, self.y);
                [(r - self.rho).max(0.0).powi(2), (r + self.rho).powi(2)]
            }
            1 => [self.x - self.rho, self.x + self.rho],
            _ => [self.y - self.rho, self.y + self.rho],
        };
        sign([lo - t, hi - t], MARGIN * (reach * reach + t.abs()))
    }

    /// The sign of `A·n + B·x + C·y + D` over the disc: a line's is its value at the centre
    /// ± `ρ·|(B, C)|`; a circle's, `A·|p − p*|² + D − A·|p*|²` with `p* = −(B, C)/2A`, follows
    /// from the nearest and farthest distance of the disc from `p*`.
    pub fn general(&self, [fa, fb, fc, fd]: [f64; 4]) -> Option<bool> {
        let reach = self.reach();
        let scale = fa.abs() * reach * reach + (fb.abs() + fc.abs()) * reach + fd.abs();
        let [lo, hi] = if fa == 0.0 {
            let centre = fb * self.x + fc * self.y + fd;
            let half = self.rho * norm(fb, fc);
            [centre - half, centre + half]
        } else {
            let (px, py) = (-fb / (2.0 * fa), -fc / (2.0 * fa));
            let r = norm(self.x - px, self.y - py);
            let (near, far) = ((r - self.rho).max(0.0), r + self.rho);
            let base = fd - fa * (px * px + py * py);
            let (a, b) = (fa * near * near + base, fa * far * far + base);
            // the completed square's constant adds its own rounding
            let scale = scale + fa.abs() * (px * px + py * py);
            return sign([a.min(b), a.max(b)], MARGIN * scale);
        };
        sign([lo, hi], MARGIN * scale)
    }
}

/// `|(a, b)|` without `hypot`'s care for overflow (a profile's 2 % of a map): an overflow
/// gives infinity, which settles nothing ([`FrameBounds::new`] keeps finite bounds only).
fn norm(a: f64, b: f64) -> f64 {
    (a * a + b * b).sqrt()
}

/// `Some(true)` when `[lo, hi]` lies above `margin`, `Some(false)` when below `-margin`,
/// `None` when it reaches within `margin` of zero.
fn sign([lo, hi]: [f64; 2], margin: f64) -> Option<bool> {
    if lo > margin {
        Some(true)
    } else if hi < -margin {
        Some(false)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    fn disc(centre: [f64; 2], radius: f64) -> Spread {
        Spread {
            centre,
            radius,
            max_norm2: 0.0,
        }
    }

    /// The base frame as the kernel computes it.
    fn frame(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> [f64; 3] {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let (vx, vy) = (c[0] - a[0], c[1] - a[1]);
        let len2 = dx * dx + dy * dy;
        let x = -(dx * vy - dy * vx) / len2;
        let y = (dx * vx + dy * vy) / len2;
        [x, y, x * x + y * y]
    }

    /// Every configuration of the discs has the sign the bounds give: points on the discs'
    /// rims (where the extremes are) and inside, for a circle, a line and thresholds on `x`,
    /// `y` and `n`; and the bounds settle most signs of discs far from the boundaries.
    #[test]
    fn a_settled_sign_holds_for_every_configuration_of_the_discs() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
        let forms = [
            [0.5, -0.3, 0.2, -1.0],
            [0.0, 1.0, -0.5, 0.25],
            [1.0, 0.0, -2.0, 0.0],
        ];
        let (mut settled, mut asked) = (0, 0);
        for _ in 0..3000 {
            let mut discs = Vec::new();
            for _ in 0..3 {
                let c = [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)];
                discs.push(disc(c, rng.random_range(0.0..0.4)));
            }
            let Some(b) = FrameBounds::new([&discs[0], &discs[1], &discs[2]], [0.0; 3], true)
            else {
                continue;
            };
            let general = forms.map(|f| b.general(f));
            let single = [(0, 1.0), (1, 0.3), (2, -0.2)].map(|(v, t)| (v, t, b.single(v, t)));
            asked += 6;
            settled += general
                .iter()
                .chain(single.iter().map(|s| &s.2))
                .flatten()
                .count();
            for _ in 0..300 {
                let mut p = |d: &Spread| {
                    let angle = rng.random_range(0.0..std::f64::consts::TAU);
                    // half of the points on the rim
                    let r = if rng.random_bool(0.5) {
                        d.radius
                    } else {
                        d.radius * rng.random_range(0.0f64..1.0).sqrt()
                    };
                    [d.centre[0] + r * angle.cos(), d.centre[1] + r * angle.sin()]
                };
                let (pa, pb, pc) = (p(&discs[0]), p(&discs[1]), p(&discs[2]));
                let [x, y, n] = frame(pa, pb, pc);
                for (f, s) in forms.iter().zip(general) {
                    if let Some(pos) = s {
                        assert_eq!(f[0] * n + f[1] * x + f[2] * y + f[3] > 0.0, pos, "{f:?}");
                    }
                }
                for (v, t, s) in single {
                    if let Some(pos) = s {
                        assert_eq!([n, x, y][v] > t, pos);
                    }
                }
            }
        }
        assert!(
            settled * 2 > asked,
            "most signs settled: {settled} of {asked}"
        );
    }

    /// A point exactly on a boundary, discs that let A and B meet, and samples that are not
    /// finite settle nothing.
    #[test]
    fn a_boundary_or_a_coincidence_settles_nothing() {
        let p = |x: f64, y: f64| disc([x, y], 0.0);
        let (a, b) = (p(0.0, 0.0), p(0.0, 1.0));
        // A = (0, 0), B = (0, 1), C = (0.5, 0.5): x = 0.5, y = 0.5 in the base frame
        let on = FrameBounds::new([&a, &b, &p(0.5, 0.5)], [0.0; 3], true).expect("apart");
        assert_eq!(on.single(1, 0.5), None);
        assert_eq!(on.single(1, 0.4), Some(true));
        assert_eq!(on.single(2, 0.6), Some(false));
        assert_eq!(on.single(0, 0.5), None);
        assert_eq!(on.general([0.0, 1.0, 0.0, -0.5]), None);
        assert_eq!(
            on.general([1.0, 0.0, 0.0, -0.5]),
            None,
            "on the circle n = 1/2"
        );
        assert_eq!(on.general([1.0, 0.0, 0.0, -0.4]), Some(true));
        let wide = disc([0.0, 0.5], 1.0);
        assert!(FrameBounds::new([&wide, &a, &b], [0.0; 3], false).is_none());
        // a threshold the discs' least distance does not clear
        assert!(FrameBounds::new([&a, &b, &p(5.0, 5.0)], [1.0; 3], false).is_none());
        // squares that overflow settle nothing (the kernel's own frame is then inf/NaN)
        let far = p(1e200, 0.0);
        assert!(FrameBounds::new([&a, &far, &p(1.0, 1.0)], [0.0; 3], false).is_none());
        assert!(Spread::of(&[1.0, f64::NAN], &[0.0, 0.0]).is_none());
        assert!(Spread::of(&[], &[]).is_none());
        let s = Spread::of(&[0.0, 2.0, 1.0], &[0.0, 0.0, 1.0]).expect("finite");
        assert_eq!(s.centre, [1.0, 0.5]);
        assert!(s.radius >= 0.5f64.hypot(1.0) && s.radius < 1.2);
    }
}
