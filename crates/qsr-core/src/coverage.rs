//! Probe points that cover a partition: the sampler behind validation, neighbours,
//! permutations, composition and merges.
//!
//! Uniform sampling misses exactly the states that matter most for soundness: thin ones
//! (the EDC lune tips, slivers between a circle and a tangent line), unbounded ones, and
//! configurations *on* a boundary (which belong to one side by the spec's convention). The
//! probe stream therefore mixes, with a fixed seed:
//!
//! | share | what | why |
//! |---|---|---|
//! | 30 % | uniform in the core box (all vertices and circles plus a margin) | bulk of every bounded state |
//! | 15 % | log-radial about each centre/vertex, radius 10^U(−7, 7) | tiny neighbourhoods and far, unbounded states |
//! | 35 % | on a boundary curve (lines out to 10^6 both ways), then 25 % exactly on it, 75 % offset along the normal by ±10^U(−12, −1)·max(1, \|p\|) | both sides of every boundary, thin slivers along it, the zero-set convention |
//! | 20 % | about a vertex (curve intersection), radius 10^U(−9, −1)·max(1, \|v\|), or exactly on it | corner adjacency and wedges that meet only at a point |
//!
//! Raster partitions use cell edges between different labels as their curves and cell
//! corners with three or more labels as vertices.

use nalgebra::{Point2, Vector2};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::partition::{Partition, RasterPartition};
use crate::spec::Shape;

/// A boundary curve a probe can be placed on.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Curve {
    /// `a·x + b·y + c = 0`.
    Line { a: f64, b: f64, c: f64 },
    /// A circle.
    Circle { centre: Point2<f64>, r: f64 },
    /// A finite segment (raster cell edges).
    Segment { p: Point2<f64>, q: Point2<f64> },
}

/// The geometric features of a partition that probes concentrate on.
#[derive(Debug, Clone)]
pub(crate) struct Features {
    pub curves: Vec<Curve>,
    pub vertices: Vec<Point2<f64>>,
    pub centres: Vec<Point2<f64>>,
    /// `[x_min, x_max, y_min, y_max]`.
    pub core: [f64; 4],
}

impl Features {
    pub(crate) fn of(partition: &Partition) -> Self {
        match partition {
            Partition::Constraints(c) => Self::of_shapes(c.shapes()),
            Partition::Raster(r) => Self::of_raster(r),
        }
    }

    fn of_shapes(shapes: &[Shape]) -> Self {
        let curves: Vec<Curve> = shapes
            .iter()
            .map(|s| match *s {
                Shape::Line { a, b, c } => Curve::Line { a, b, c },
                Shape::Circle { center, radius } => Curve::Circle {
                    centre: Point2::new(center[0], center[1]),
                    r: radius,
                },
            })
            .collect();
        let mut vertices = Vec::new();
        for i in 0..curves.len() {
            for j in i + 1..curves.len() {
                vertices.extend(intersections(&curves[i], &curves[j]));
            }
        }
        vertices.retain(|v| v.x.is_finite() && v.y.is_finite() && v.coords.norm() < 1e6);
        let mut centres = vec![
            Point2::new(0.0, 0.0),
            Point2::new(0.0, 0.5),
            Point2::new(0.0, 1.0),
        ];
        let mut lo = Vector2::new(-1.0f64, -1.0);
        let mut hi = Vector2::new(1.0f64, 2.0);
        for c in &curves {
            if let Curve::Circle { centre, r } = *c {
                centres.push(centre);
                lo = lo.inf(&(centre.coords - Vector2::new(r, r)));
                hi = hi.sup(&(centre.coords + Vector2::new(r, r)));
            }
        }
        for v in &vertices {
            lo = lo.inf(&v.coords);
            hi = hi.sup(&v.coords);
        }
        centres.extend(vertices.iter().copied());
        let margin = 0.5 * (hi - lo).max().max(1.0);
        Self {
            curves,
            vertices,
            centres,
            core: [lo.x - margin, hi.x + margin, lo.y - margin, hi.y + margin],
        }
    }

    fn of_raster(r: &RasterPartition) -> Self {
        let (nx, ny) = r.shape();
        let mut curves = Vec::new();
        let mut vertices = Vec::new();
        for iy in 0..ny {
            for ix in 0..nx {
                let here = r.cell(ix, iy);
                let o = r.cell_origin(ix, iy);
                let (dx, dy) = r.cell_size();
                if ix + 1 < nx && r.cell(ix + 1, iy) != here {
                    curves.push(Curve::Segment {
                        p: Point2::new(o.x + dx, o.y),
                        q: Point2::new(o.x + dx, o.y + dy),
                    });
                }
                if iy + 1 < ny && r.cell(ix, iy + 1) != here {
                    curves.push(Curve::Segment {
                        p: Point2::new(o.x, o.y + dy),
                        q: Point2::new(o.x + dx, o.y + dy),
                    });
                }
                if ix + 1 < nx && iy + 1 < ny {
                    let mut four = [
                        here,
                        r.cell(ix + 1, iy),
                        r.cell(ix, iy + 1),
                        r.cell(ix + 1, iy + 1),
                    ];
                    four.sort_unstable();
                    let distinct = 1 + four.windows(2).filter(|w| w[0] != w[1]).count();
                    if distinct >= 3 || (distinct == 2 && here == r.cell(ix + 1, iy + 1)) {
                        vertices.push(Point2::new(o.x + dx, o.y + dy));
                    }
                }
            }
        }
        let [x0, x1, y0, y1] = r.window();
        if let Some(out) = r.outside_state() {
            // The window border separates the raster from the outside state.
            let (dx, dy) = r.cell_size();
            for ix in 0..nx {
                for (iy, y) in [(0, y0), (ny - 1, y1)] {
                    if r.cell(ix, iy) != out {
                        let x = x0 + ix as f64 * dx;
                        curves.push(Curve::Segment {
                            p: Point2::new(x, y),
                            q: Point2::new(x + dx, y),
                        });
                    }
                }
            }
            for iy in 0..ny {
                for (ix, x) in [(0, x0), (nx - 1, x1)] {
                    if r.cell(ix, iy) != out {
                        let y = y0 + iy as f64 * dy;
                        curves.push(Curve::Segment {
                            p: Point2::new(x, y),
                            q: Point2::new(x, y + dy),
                        });
                    }
                }
            }
        }
        let mut centres = vec![
            Point2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1)),
            Point2::new(0.0, 0.0),
            Point2::new(0.0, 1.0),
        ];
        centres.extend(vertices.iter().copied());
        Self {
            curves,
            vertices,
            centres,
            core: [x0, x1, y0, y1],
        }
    }

    /// A point exactly on a random curve.
    fn on_curve(&self, rng: &mut ChaCha8Rng) -> Option<(Point2<f64>, Vector2<f64>)> {
        if self.curves.is_empty() {
            return None;
        }
        let curve = self.curves[rng.random_range(0..self.curves.len())];
        let [x0, x1, y0, y1] = self.core;
        Some(match curve {
            Curve::Line { a, b, c } => {
                let n = Vector2::new(a, b);
                let len = n.norm();
                let n = n / len;
                let u = Vector2::new(-n.y, n.x);
                let mid = Vector2::new(0.5 * (x0 + x1), 0.5 * (y0 + y1));
                // Foot of the core centre on the line.
                let foot = mid - n * ((a * mid.x + b * mid.y + c) / len);
                let half = 0.5 * ((x1 - x0).hypot(y1 - y0));
                let t = if rng.random::<bool>() {
                    rng.random_range(-half..half)
                } else {
                    let m = 10f64.powf(rng.random_range(-3.0..6.0));
                    if rng.random::<bool>() { m } else { -m }
                };
                (Point2::from(foot + u * t), n)
            }
            Curve::Circle { centre, r } => {
                let th = rng.random_range(0.0..std::f64::consts::TAU);
                let n = Vector2::new(th.cos(), th.sin());
                (centre + n * r, n)
            }
            Curve::Segment { p, q } => {
                let t: f64 = rng.random();
                let d = q - p;
                let n = Vector2::new(-d.y, d.x).normalize();
                (p + d * t, n)
            }
        })
    }

    /// Points exactly on boundaries (`false`) and on vertices (`true`), for neighbour rings.
    pub(crate) fn boundary_points(&self, n: usize, seed: u64) -> Vec<(Point2<f64>, bool)> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut out: Vec<(Point2<f64>, bool)> = self.vertices.iter().map(|v| (*v, true)).collect();
        for _ in 0..n {
            if let Some((p, _)) = self.on_curve(&mut rng) {
                out.push((p, false));
            }
        }
        out
    }

    /// The mixed probe stream described in the module docs.
    pub(crate) fn probes(&self, n: usize, seed: u64) -> Vec<Point2<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let [x0, x1, y0, y1] = self.core;
        let mut out = Vec::with_capacity(n + self.vertices.len());
        out.extend(self.vertices.iter().copied());
        for _ in 0..n {
            let u: f64 = rng.random();
            let p = if u < 0.30 {
                Point2::new(rng.random_range(x0..x1), rng.random_range(y0..y1))
            } else if u < 0.45 {
                let c = self.centres[rng.random_range(0..self.centres.len())];
                let r = 10f64.powf(rng.random_range(-7.0..7.0));
                let th = rng.random_range(0.0..std::f64::consts::TAU);
                c + Vector2::new(th.cos(), th.sin()) * r
            } else if u < 0.80 {
                match self.on_curve(&mut rng) {
                    Some((p, n)) => {
                        if rng.random::<f64>() < 0.25 {
                            p
                        } else {
                            let scale = 1f64.max(p.coords.norm());
                            let e = 10f64.powf(rng.random_range(-12.0..-1.0)) * scale;
                            if rng.random::<bool>() {
                                p + n * e
                            } else {
                                p - n * e
                            }
                        }
                    }
                    None => Point2::new(rng.random_range(x0..x1), rng.random_range(y0..y1)),
                }
            } else if self.vertices.is_empty() {
                Point2::new(rng.random_range(x0..x1), rng.random_range(y0..y1))
            } else {
                let v = self.vertices[rng.random_range(0..self.vertices.len())];
                if rng.random::<f64>() < 0.1 {
                    v
                } else {
                    let scale = 1f64.max(v.coords.norm());
                    let r = 10f64.powf(rng.random_range(-9.0..-1.0)) * scale;
                    let th = rng.random_range(0.0..std::f64::consts::TAU);
                    v + Vector2::new(th.cos(), th.sin()) * r
                }
            };
            out.push(p);
        }
        out
    }
}

/// Intersection points of two curves (only lines and circles occur here).
fn intersections(c1: &Curve, c2: &Curve) -> Vec<Point2<f64>> {
    match (*c1, *c2) {
        (Curve::Line { a, b, c }, Curve::Line { a: d, b: e, c: f }) => {
            let det = a * e - b * d;
            if det.abs() < 1e-12 {
                vec![]
            } else {
                vec![Point2::new((b * f - e * c) / det, (d * c - a * f) / det)]
            }
        }
        (Curve::Line { a, b, c }, Curve::Circle { centre, r })
        | (Curve::Circle { centre, r }, Curve::Line { a, b, c }) => {
            let n = Vector2::new(a, b);
            let len = n.norm();
            let n = n / len;
            let dist = (a * centre.x + b * centre.y + c) / len;
            if dist.abs() > r {
                return vec![];
            }
            let foot = centre - n * dist;
            let h = (r * r - dist * dist).max(0.0).sqrt();
            let u = Vector2::new(-n.y, n.x);
            vec![foot + u * h, foot - u * h]
        }
        (Curve::Circle { centre: p, r: r1 }, Curve::Circle { centre: q, r: r2 }) => {
            let d = q - p;
            let dist = d.norm();
            if dist < 1e-12 || dist > r1 + r2 || dist < (r1 - r2).abs() {
                return vec![];
            }
            let along = (r1 * r1 - r2 * r2 + dist * dist) / (2.0 * dist);
            let h = (r1 * r1 - along * along).max(0.0).sqrt();
            let e = d / dist;
            let base = p + e * along;
            let perp = Vector2::new(-e.y, e.x);
            vec![base + perp * h, base - perp * h]
        }
        _ => vec![],
    }
}

/// Radius decades a pool is stratified by: |p| < 1e-8, [1e-8, 1e-7), ..., [1e7, ∞).
pub(crate) const SCALE_BUCKETS: usize = 17;

fn scale_bucket(p: &Point2<f64>) -> usize {
    let r = p.coords.norm();
    if r < 1e-8 {
        0
    } else {
        ((r.log10() + 9.0).floor() as usize).clamp(1, SCALE_BUCKETS - 1)
    }
}

/// Probe points of one state, kept both as one reservoir and stratified by scale, so that
/// the far reaches of unbounded states and tiny neighbourhoods are drawn as often as the
/// bulk.
#[derive(Debug, Clone, Default)]
pub(crate) struct StatePool {
    pub all: Vec<Point2<f64>>,
    pub by_scale: Vec<Vec<Point2<f64>>>,
}

impl StatePool {
    /// Whether the pool holds no point.
    pub(crate) fn is_empty(&self) -> bool {
        self.all.is_empty()
    }

    /// A point: half the time from the whole reservoir, half from a random non-empty scale.
    #[inline]
    pub(crate) fn draw(&self, rng: &mut ChaCha8Rng) -> Point2<f64> {
        if rng.random::<bool>() {
            let bucket = &self.by_scale[rng.random_range(0..self.by_scale.len())];
            bucket[rng.random_range(0..bucket.len())]
        } else {
            self.all[rng.random_range(0..self.all.len())]
        }
    }
}

/// Per-state pools of probe points (deterministic for a seed).
pub(crate) fn state_pools(
    partition: &Partition,
    n_states: usize,
    probes: &[Point2<f64>],
    capacity: usize,
    seed: u64,
) -> Vec<StatePool> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let per_bucket = (capacity / 8).max(16);
    let mut all: Vec<Vec<Point2<f64>>> = vec![Vec::new(); n_states];
    let mut buckets: Vec<Vec<Vec<Point2<f64>>>> = vec![vec![Vec::new(); SCALE_BUCKETS]; n_states];
    let mut seen = vec![0usize; n_states];
    let mut seen_bucket = vec![vec![0usize; SCALE_BUCKETS]; n_states];
    let keep = |pool: &mut Vec<Point2<f64>>,
                seen: usize,
                cap: usize,
                p: Point2<f64>,
                rng: &mut ChaCha8Rng| {
        if pool.len() < cap {
            pool.push(p);
        } else {
            let j = rng.random_range(0..seen);
            if j < cap {
                pool[j] = p;
            }
        }
    };
    for p in probes {
        let s = usize::from(partition.classify(p));
        seen[s] += 1;
        keep(&mut all[s], seen[s], capacity, *p, &mut rng);
        let b = scale_bucket(p);
        seen_bucket[s][b] += 1;
        keep(
            &mut buckets[s][b],
            seen_bucket[s][b],
            per_bucket,
            *p,
            &mut rng,
        );
    }
    all.into_iter()
        .zip(buckets)
        .map(|(all, by_scale)| StatePool {
            all,
            by_scale: by_scale.into_iter().filter(|b| !b.is_empty()).collect(),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn circle_intersections_of_the_edc_circles() {
        let a = Curve::Circle {
            centre: Point2::new(0.0, 0.0),
            r: 1.0,
        };
        let b = Curve::Circle {
            centre: Point2::new(0.0, 1.0),
            r: 1.0,
        };
        let pts = intersections(&a, &b);
        assert_eq!(pts.len(), 2);
        for p in pts {
            assert!((p.y - 0.5).abs() < 1e-12);
            assert!((p.x.abs() - 3f64.sqrt() / 2.0).abs() < 1e-12);
        }
    }
}
