//! Classification kernels instantiated per constraint *shape*: how many thresholds on `x`, on
//! `y`, general lines and circles a [`ConstraintPartition`](crate::ConstraintPartition) has.
//!
//! **Why.** The general classifier takes any spec as data: one pass over a block of points per
//! constraint, the constraint's kind and its zero side chosen at run time. A kernel that knows
//! the shape at compile time instead keeps each point in registers from its normalisation to
//! its sign vector — every constraint a comparison against a constant, no pass stored between
//! — which is what a user writing a loop for one calculus (numba, C) gets. The built-in
//! calculi's shapes are instantiated (see [`Grouped::dispatch`]; a test keeps the list
//! complete); a user's or a learned calculus of another shape keeps the general path.
//!
//! **The same results, bit for bit.** Every comparison is the general path's: a side
//! `u ≥ t` becomes `u > t⁻` with `t⁻` the next double below `t` — the same outcome for every
//! double `u`, NaN included (both false) — so a kernel takes one strict comparison per
//! constraint, and a line or circle evaluates the same expression in the same order (Rust
//! never contracts `a·b + c` into an FMA).

use crate::spec::Shape;

/// The constraints of a partition grouped by kind, each with one strict comparison.
#[derive(Debug, Clone, Default)]
pub(crate) struct Grouped {
    /// Thresholds on `x` and on `y`: bit set when `u > t`.
    tx: Vec<f64>,
    ty: Vec<f64>,
    /// General lines `a·x + b·y + c > t` as `[a, b, c, t]`.
    lines: Vec<[f64; 4]>,
    /// Circles `(x − cx)² + (y − cy)² − r² > t` as `[cx, cy, r², t]`.
    circles: Vec<[f64; 4]>,
    /// Each group's bits, in the order above.
    bits: [Vec<u32>; 4],
}

/// `u ≥ t` ⇔ `u > strict(t, true)` for every double `u`; `u > t` ⇔ `u > strict(t, false)`.
fn strict(t: f64, zero_positive: bool) -> f64 {
    if zero_positive { t.next_down() } else { t }
}

impl Grouped {
    /// Groups `constraints` (spec order: bit `i` is constraint `i`).
    pub(crate) fn new(constraints: &[(Shape, bool)]) -> Self {
        let mut g = Self::default();
        for (i, &(shape, pos)) in constraints.iter().enumerate() {
            let bit = i as u32;
            match shape {
                // `u + c ≥ 0` ⇔ `u ≥ −c` exactly (as in the general path)
                Shape::Line { a: 1.0, b: 0.0, c } => {
                    g.tx.push(strict(-c, pos));
                    g.bits[0].push(bit);
                }
                Shape::Line { a: 0.0, b: 1.0, c } => {
                    g.ty.push(strict(-c, pos));
                    g.bits[1].push(bit);
                }
                Shape::Line { a, b, c } => {
                    g.lines.push([a, b, c, strict(0.0, pos)]);
                    g.bits[2].push(bit);
                }
                Shape::Circle { center, radius } => {
                    g.circles
                        .push([center[0], center[1], radius * radius, strict(0.0, pos)]);
                    g.bits[3].push(bit);
                }
            }
        }
        g
    }

    /// `[thresholds on x, on y, lines, circles]`.
    pub(crate) fn shape(&self) -> [usize; 4] {
        [
            self.tx.len(),
            self.ty.len(),
            self.lines.len(),
            self.circles.len(),
        ]
    }

    /// Whether [`Grouped::dispatch`] has a kernel for this shape.
    pub(crate) fn has_kernel(&self) -> bool {
        let mut v = [0u32; 1];
        self.dispatch(|_| (0.0, 0.0, true), &mut v).is_some()
    }

    /// The sign vectors of `v.len()` points (`point(i)` = `(x, y, valid)` of point `i`)
    /// through the kernel of this shape, and whether every point was valid; `None` when the
    /// shape has no kernel of its own.
    #[inline(always)]
    pub(crate) fn dispatch(
        &self,
        point: impl Fn(usize) -> (f64, f64, bool),
        v: &mut [u32],
    ) -> Option<bool> {
        macro_rules! shapes {
            ($([$a:literal, $b:literal, $c:literal, $d:literal]),*) => {
                match self.shape() {
                    $([$a, $b, $c, $d] => Some(self.signs::<$a, $b, $c, $d>(point, v)),)*
                    _ => None,
                }
            };
        }
        // the built-in calculi's shapes (`every_builtin_constraint_calculus_has_a_kernel`)
        shapes!(
            [1, 3, 0, 2], // edc
            [1, 3, 0, 3], // edc-lune
            [1, 3, 0, 0], // triple-cross
            [1, 2, 0, 0], // double-cross
            [1, 1, 0, 0], // quadrant, single-cross
            [1, 0, 0, 0], // left-right
            [0, 0, 0, 1], // relative-distance
            [1, 1, 2, 1], // tpcc
            [0, 2, 0, 0], // front-between-behind
            [0, 0, 2, 0], // star-4
            [0, 0, 4, 0]  // star-8 (other star-m: the general path)
        )
    }

    /// [`Grouped::dispatch`]'s kernel for one shape: each point's sign vector in registers,
    /// every constraint one comparison against a constant.
    #[inline(always)]
    fn signs<const NX: usize, const NY: usize, const NL: usize, const NC: usize>(
        &self,
        point: impl Fn(usize) -> (f64, f64, bool),
        v: &mut [u32],
    ) -> bool {
        fn take<const N: usize, T: Copy + Default>(v: &[T]) -> [T; N] {
            let mut out = [T::default(); N];
            out.iter_mut().zip(v).for_each(|(o, v)| *o = *v);
            out
        }
        fn masks<const N: usize>(bits: &[u32]) -> [u32; N] {
            std::array::from_fn(|i| bits.get(i).map_or(0, |b| 1u32 << b))
        }
        let (tx, ty): ([f64; NX], [f64; NY]) = (take(&self.tx), take(&self.ty));
        let (lines, circles): ([[f64; 4]; NL], [[f64; 4]; NC]) =
            (take(&self.lines), take(&self.circles));
        let (mx, my, ml, mc): ([u32; NX], [u32; NY], [u32; NL], [u32; NC]) = (
            masks(&self.bits[0]),
            masks(&self.bits[1]),
            masks(&self.bits[2]),
            masks(&self.bits[3]),
        );
        let mut valid = true;
        for (i, vi) in v.iter_mut().enumerate() {
            let (x, y, ok) = point(i);
            valid &= ok;
            let mut s = 0u32;
            for k in 0..NX {
                s |= if x > tx[k] { mx[k] } else { 0 };
            }
            for k in 0..NY {
                s |= if y > ty[k] { my[k] } else { 0 };
            }
            for k in 0..NL {
                let [a, b, c, t] = lines[k];
                s |= if a * x + b * y + c > t { ml[k] } else { 0 };
            }
            for k in 0..NC {
                let [cx, cy, r2, t] = circles[k];
                let f = (x - cx) * (x - cx) + (y - cy) * (y - cy) - r2;
                s |= if f > t { mc[k] } else { 0 };
            }
            *vi = s;
        }
        valid
    }
}

#[cfg(test)]
mod tests {
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    use crate::partition::BLOCK;
    use crate::spec::Shape;
    use crate::{BUILTIN_NAMES, Calculus, ConstraintPartition, FrameKind, Partition, StateId};

    #[test]
    fn every_builtin_constraint_calculus_has_a_kernel() {
        let mut missing = Vec::new();
        for name in BUILTIN_NAMES {
            let c = Calculus::builtin(name).unwrap();
            if let Partition::Constraints(p) = c.partition()
                && !p.grouped.has_kernel()
            {
                missing.push(format!("{name}: {:?}", p.grouped.shape()));
            }
        }
        assert!(missing.is_empty(), "shapes without a kernel: {missing:?}");
    }

    /// Normalised points on and beside every constraint of `p` (exactly on a threshold, one
    /// ulp either side, on a line or circle as nearly as doubles get, on dyadic lattices) and
    /// non-finite ones.
    fn probe_points(p: &ConstraintPartition) -> Vec<[f64; 2]> {
        let mut pts = Vec::new();
        let lattice: Vec<f64> = (-16..=16).map(|k| f64::from(k) / 8.0).collect();
        let near = |v: f64| [v, v.next_up(), v.next_down()];
        for shape in p.shapes() {
            match *shape {
                Shape::Line { a, b, c } => {
                    for &s in &lattice {
                        // the point of the line nearest the origin, moved along it by s
                        let n2 = a * a + b * b;
                        let (x0, y0) = (-a * c / n2, -b * c / n2);
                        for x in near(x0 - b * s) {
                            for y in near(y0 + a * s) {
                                pts.push([x, y]);
                            }
                        }
                    }
                    for &u in &lattice {
                        if b != 0.0 {
                            pts.push([u, -(a * u + c) / b]);
                        }
                        if a != 0.0 {
                            pts.push([-(b * u + c) / a, u]);
                        }
                    }
                }
                Shape::Circle { center, radius } => {
                    for k in 0..64 {
                        let t = f64::from(k) * std::f64::consts::TAU / 64.0;
                        for x in near(center[0] + radius * t.cos()) {
                            for y in near(center[1] + radius * t.sin()) {
                                pts.push([x, y]);
                            }
                        }
                    }
                    for d in [[radius, 0.0], [-radius, 0.0], [0.0, radius], [0.0, -radius]] {
                        pts.push([center[0] + d[0], center[1] + d[1]]);
                    }
                }
            }
        }
        for &x in &lattice {
            for &y in &lattice {
                pts.push([x, y]);
            }
        }
        for v in [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            1e300,
            -1e-300,
        ] {
            pts.push([v, 0.5]);
            pts.push([0.5, v]);
        }
        pts
    }

    /// Every built-in constraint calculus, its kernel against the general loops and the
    /// scalar rule, on `random` random points besides the boundary lattices; and its rows and
    /// columns paths (normalisation fused) against normalising then classifying.
    pub(crate) fn kernels_agree(random: usize, seed: u64) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for name in BUILTIN_NAMES {
            let c = Calculus::builtin(name).unwrap();
            let Partition::Constraints(p) = c.partition() else {
                continue;
            };
            assert!(p.fused, "{name} runs its kernel");
            let lattice = probe_points(p);
            let mut left = random;
            let mut chunks: Vec<Vec<[f64; 2]>> =
                lattice.chunks(1 << 16).map(<[_]>::to_vec).collect();
            while let Some(chunk) = chunks.pop().or_else(|| {
                // random points a chunk at a time (10^8 of them are not held at once)
                (left > 0).then(|| {
                    let k = left.min(1 << 16);
                    left -= k;
                    (0..k)
                        .map(|i| {
                            let scale = [1.0, 3.0, 1e-3, 1e6][i % 4];
                            [
                                scale * rng.random_range(-2.0..2.0),
                                scale * rng.random_range(-2.0..2.0),
                            ]
                        })
                        .collect()
                })
            }) {
                let chunk = chunk.as_slice();
                let (xs, ys): (Vec<f64>, Vec<f64>) = chunk.iter().map(|q| (q[0], q[1])).unzip();
                let mut fused = vec![0u16; chunk.len()];
                let mut general = vec![0u16; chunk.len()];
                p.classify_block(&xs, &ys, &mut fused);
                p.classify_block_general(&xs, &ys, &mut general);
                for (i, q) in chunk.iter().enumerate() {
                    assert_eq!(
                        fused[i], general[i],
                        "{name} at {q:?}: kernel vs general loops"
                    );
                    assert_eq!(
                        fused[i],
                        p.classify(q[0], q[1]),
                        "{name} at {q:?}: vs the scalar rule"
                    );
                }
                if c.frame() != FrameKind::Ternary {
                    continue;
                }
                // the same points as triplets: A = (0, 0), B = (0, 1) puts C at (x, y)
                // exactly; a random frame puts it there up to rounding, which both paths share
                let rows: Vec<[f64; 6]> = chunk
                    .iter()
                    .enumerate()
                    .filter(|(_, q)| q[0].is_finite() && q[1].is_finite())
                    .map(|(i, q)| {
                        if i % 2 == 0 {
                            [0.0, 0.0, 0.0, 1.0, q[0], q[1]]
                        } else {
                            let (ax, ay) =
                                (rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0));
                            let (ux, uy) =
                                (rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0));
                            // C = A + x·(−uy, ux) + y·(ux, uy)
                            [
                                ax,
                                ay,
                                ax + ux,
                                ay + uy,
                                ax - q[0] * uy + q[1] * ux,
                                ay + q[0] * ux + q[1] * uy,
                            ]
                        }
                    })
                    .collect();
                let mut out = vec![StateId(0); rows.len()];
                c.classify_triplets(&rows, &mut out).unwrap();
                let cols: Vec<Vec<f64>> = (0..6)
                    .map(|k| rows.iter().map(|r| r[k]).collect())
                    .collect();
                let mut out_cols = vec![StateId(0); rows.len()];
                c.classify_columns(
                    (&cols[0], &cols[1]),
                    (&cols[2], &cols[3]),
                    (&cols[4], &cols[5]),
                    &mut out_cols,
                )
                .unwrap();
                for (r, (o, oc)) in rows.iter().zip(out.iter().zip(&out_cols)) {
                    let (x, y, _) = crate::calculus::normalise_row(r);
                    let mut want = [0u16];
                    p.classify_block_general(&[x], &[y], &mut want);
                    assert_eq!(o.0, want[0], "{name}: row {r:?}");
                    assert_eq!(oc.0, want[0], "{name}: columns of row {r:?}");
                }
            }
        }
    }

    #[test]
    fn kernels_agree_with_the_general_classifier_on_lattices_and_random_points() {
        kernels_agree(200_000, 1);
    }

    /// The check at full size: 10^8 random triplets per calculus besides the
    /// lattices (about a minute per calculus in release):
    /// `cargo test -p qsr-core --release --lib -- --ignored kernels_agree_on_1e8`.
    #[test]
    #[ignore = "10^8 points per calculus: run by hand in release"]
    fn kernels_agree_on_1e8_points_per_calculus() {
        kernels_agree(100_000_000, 2);
    }

    #[test]
    fn a_partial_block_and_an_invalid_row_are_reported_as_before() {
        let c = Calculus::builtin("edc").unwrap();
        let mut rows = vec![[0.0, 0.0, 1.0, 0.0, 0.5, 0.5]; BLOCK + 5];
        rows[BLOCK + 2] = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0];
        let mut out = vec![StateId(0); rows.len()];
        let err = c
            .classify_triplets(&rows, &mut out)
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("triplet {}", BLOCK + 2)), "{err}");
        let cols: Vec<Vec<f64>> = (0..6)
            .map(|k| rows.iter().map(|r| r[k]).collect())
            .collect();
        let err = c
            .classify_columns(
                (&cols[0], &cols[1]),
                (&cols[2], &cols[3]),
                (&cols[4], &cols[5]),
                &mut out,
            )
            .unwrap_err()
            .to_string();
        assert!(err.contains(&format!("triplet {}", BLOCK + 2)), "{err}");
        rows[BLOCK + 2][4] = f64::NAN;
        rows[BLOCK + 2][2] = 2.0;
        let err = c
            .classify_triplets(&rows, &mut out)
            .unwrap_err()
            .to_string();
        assert!(err.contains("non-finite") || err.contains("NaN"), "{err}");
    }
}
