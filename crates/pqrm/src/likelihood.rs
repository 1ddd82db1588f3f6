//! `p(R = q | Z_t)` for landmark sets (thesis eq. 2.9): classify the sampled configurations,
//! histogram, and turn counts into a distribution with a pseudo-count floor.
//!
//! **The floor.** With `α` pseudo-counts per state, `p(q) = (count_q + α) / (s + αQ)`. Without
//! it (`α = 0`, the thesis's estimator), a state that no sample of one observation hit gets
//! probability 0, and the Bayes filter multiplies by 0 forever: a single outlier (a
//! mis-associated landmark, a gross range error) can rule the true state out for good. With
//! `α > 0` one observation changes a state's odds by at most `(s + α)/α` (≈ 1000 for
//! `s = 1000`, `α = 1`), so enough later evidence always recovers. The price is that a
//! perfectly consistent map never reaches probability exactly 1.

use qsr_core::{Calculus, MergeMap, StateId};
use rayon::prelude::*;

use crate::error::{PqrmError, Result};
use crate::observation::LandmarkId;
use crate::sampler::ScanSamples;

/// An ordered landmark set `{A, B : C}`.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
pub struct LandmarkSet(pub [LandmarkId; 3]);

impl LandmarkSet {
    /// The set `{a, b : c}`.
    #[must_use]
    pub fn new(a: u32, b: u32, c: u32) -> Self {
        Self([LandmarkId(a), LandmarkId(b), LandmarkId(c)])
    }

    /// Ids as plain numbers.
    #[must_use]
    pub fn ids(&self) -> [u32; 3] {
        [self.0[0].0, self.0[1].0, self.0[2].0]
    }

    /// Whether the ids are in increasing order (the canonical ordering of the unordered set).
    #[must_use]
    pub fn is_canonical(&self) -> bool {
        self.0[0] < self.0[1] && self.0[1] < self.0[2]
    }
}

/// Which orderings of each observed triplet the map records (thesis §2.3: "m³" vs "C(m,3)").
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Orderings {
    /// All six orderings (what the thesis reports).
    All,
    /// One ordering per unordered set (ids increasing); the other five are derived with the
    /// calculus's permutation operations when asked for.
    Canonical,
}

/// Histogram of the states of `s` sampled configurations of `{A, B : C}`.
///
/// # Errors
/// [`PqrmError::CoincidentLandmarks`] when a sample has A and B coincident (possible only
/// when two landmarks with zero noise sit on the same spot).
pub fn set_counts(
    calculus: &Calculus,
    samples: &ScanSamples,
    [i, j, k]: [usize; 3],
    buffer: &mut Vec<StateId>,
) -> Result<Vec<u32>> {
    buffer.clear();
    buffer.resize(samples.samples(), StateId(0));
    calculus
        .classify_columns(
            samples.columns(i),
            samples.columns(j),
            samples.columns(k),
            buffer,
        )
        .map_err(|e| {
            let ids = samples.ids();
            PqrmError::CoincidentLandmarks {
                set: [ids[i].0, ids[j].0, ids[k].0],
                reason: e.to_string(),
            }
        })?;
    let mut counts = vec![0u32; calculus.n_states()];
    for s in buffer.iter() {
        counts[s.index()] += 1;
    }
    Ok(counts)
}

/// Histograms of one step: each landmark set with its state counts.
pub type StepCounts = Vec<(LandmarkSet, Vec<u32>)>;

/// Samples processed per inner block of [`step_counts`].
const CHUNK: usize = 256;

/// Counts for every landmark set of one scan.
///
/// For each unordered triplet `{i < j < k}` the position `(x, y)` of `k` in the frame of
/// `(i, j)` is computed once per sample; the other five orderings follow in closed form (with
/// `n = x² + y²`, `m = x² + (y − 1)²`):
///
/// | ordering | normalised position |
/// |---|---|
/// | `{i, j : k}` | `(x, y)` |
/// | `{j, i : k}` (inverse) | `(−x, 1 − y)` |
/// | `{i, k : j}` (shortcut) | `(−x/n, y/n)` |
/// | `{k, i : j}` (shortcut-inverse) | `(x/n, 1 − y/n)` |
/// | `{j, k : i}` (homing) | `(x/m, (1 − y)/m)` |
/// | `{k, j : i}` (homing-inverse) | `(−x/m, (n − y)/m)` |
///
/// so a step costs one frame per unordered triplet instead of six. Parallel over the first
/// landmark; the result does not depend on the thread count. Sets come out grouped by
/// unordered triplet, in the order of the table.
///
/// # Errors
/// [`PqrmError::CoincidentLandmarks`] when two landmarks of a triplet coincide in a sample
/// (within [`qsr_core::DEGENERATE_TOLERANCE`]): possible only with zero noise.
pub fn step_counts(
    calculus: &Calculus,
    samples: &ScanSamples,
    orderings: Orderings,
) -> Result<StepCounts> {
    let ids = samples.ids();
    let m = ids.len();
    let per_first: Vec<Result<StepCounts>> = (0..m)
        .into_par_iter()
        .map(|i| {
            let mut out = Vec::new();
            for j in i + 1..m {
                for k in j + 1..m {
                    let counts = triplet_counts(calculus, samples, [i, j, k], orderings)?;
                    let [a, b, c] = [ids[i], ids[j], ids[k]];
                    let sets = [
                        [a, b, c],
                        [b, a, c],
                        [a, c, b],
                        [c, a, b],
                        [b, c, a],
                        [c, b, a],
                    ];
                    out.extend(
                        sets.into_iter()
                            .zip(counts)
                            .map(|(s, c)| (LandmarkSet(s), c)),
                    );
                }
            }
            Ok(out)
        })
        .collect();
    let mut all = Vec::new();
    for r in per_first {
        all.extend(r?);
    }
    Ok(all)
}

/// One sample of a triplet in its base normalised frame: `(x, y, n = x² + y²,
/// m = x² + (y − 1)²)`, whether A and B are distinct, and whether C is distinct from both
/// (relative to their magnitude; `|AC|² = n·|AB|²`, `|BC|² = m·|AB|²`). Shared by both
/// counting paths so they normalise identically.
#[inline(always)]
fn base_sample(a: [f64; 2], b: [f64; 2], c: [f64; 2], tol2: f64) -> ([f64; 4], bool, bool) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let len2 = dx * dx + dy * dy;
    let (vx, vy) = (c[0] - a[0], c[1] - a[1]);
    let a2 = a[0] * a[0] + a[1] * a[1];
    let b2 = b[0] * b[0] + b[1] * b[1];
    let c2 = c[0] * c[0] + c[1] * c[1];
    let inv = 1.0 / len2;
    let x = -(dx * vy - dy * vx) * inv;
    let y = (dx * vx + dy * vy) * inv;
    let n = x * x + y * y;
    let m = x * x + (y - 1.0) * (y - 1.0);
    let ab = len2 > tol2 * (1.0 + a2 + b2);
    let c_apart = (n * len2 > tol2 * (1.0 + a2 + c2)) & (m * len2 > tol2 * (1.0 + b2 + c2));
    ([x, y, n, m], ab, c_apart)
}

/// The error for a triplet with two coincident landmarks in a sample.
fn coincident(samples: &ScanSamples, [i, j, k]: [usize; 3]) -> PqrmError {
    PqrmError::CoincidentLandmarks {
        set: [samples.ids()[i].0, samples.ids()[j].0, samples.ids()[k].0],
        reason: "two of the three landmarks coincide in a sample (zero noise on one spot?)".into(),
    }
}

/// Histograms of the orderings of one unordered triplet (six, or one for
/// [`Orderings::Canonical`]).
///
/// On x86-64 CPUs with AVX2 the same code runs compiled for AVX2 (picked at run time, so
/// the binary and the wheel stay portable): the normalisation and the constraint loops of
/// the classifier vectorise over four doubles instead of two. The arithmetic is the same
/// IEEE operations in the same order (Rust never contracts `a * b + c` into an FMA), so the
/// counts are identical on every CPU.
fn triplet_counts(
    calculus: &Calculus,
    samples: &ScanSamples,
    triplet: [usize; 3],
    orderings: Orderings,
) -> Result<Vec<Vec<u32>>> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[allow(unsafe_code)]
        // SAFETY: `triplet_counts_avx2` only requires AVX2, which was just detected.
        return unsafe { triplet_counts_avx2(calculus, samples, triplet, orderings) };
    }
    triplet_counts_portable(calculus, samples, triplet, orderings)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn triplet_counts_avx2(
    calculus: &Calculus,
    samples: &ScanSamples,
    triplet: [usize; 3],
    orderings: Orderings,
) -> Result<Vec<Vec<u32>>> {
    triplet_counts_portable(calculus, samples, triplet, orderings)
}

#[inline(always)]
fn triplet_counts_portable(
    calculus: &Calculus,
    samples: &ScanSamples,
    [i, j, k]: [usize; 3],
    orderings: Orderings,
) -> Result<Vec<Vec<u32>>> {
    if orderings == Orderings::All
        && let Some(forms) = SixForms::new(calculus)
    {
        return six_counts(calculus, &forms, samples, [i, j, k]);
    }
    let q = calculus.n_states();
    let n_orders = if orderings == Orderings::All { 6 } else { 1 };
    // Four interleaved sub-histograms per ordering: consecutive samples mostly share a state,
    // and a single counter would serialise on its own increments.
    let mut counts = vec![vec![[0u32; 4]; q]; n_orders];
    let ((ax, ay), (bx, by), (cx, cy)) =
        (samples.columns(i), samples.columns(j), samples.columns(k));
    let s = samples.samples();
    let mut px = [[0.0f64; CHUNK]; 6];
    let mut py = [[0.0f64; CHUNK]; 6];
    let mut states = [0u16; CHUNK];
    let tol2 = qsr_core::DEGENERATE_TOLERANCE * qsr_core::DEGENERATE_TOLERANCE;
    for start in (0..s).step_by(CHUNK) {
        let len = CHUNK.min(s - start);
        let mut valid = true;
        for t in 0..len {
            let u = start + t;
            let ([x, y, n, mm], ab, c_apart) =
                base_sample([ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]], tol2);
            // the canonical ordering alone needs only A ≠ B; the others use C as a reference
            valid &= ab & (c_apart | (n_orders == 1));
            px[0][t] = x;
            py[0][t] = y;
            if n_orders == 6 {
                let (inv_n, inv_m) = (1.0 / n, 1.0 / mm);
                px[1][t] = -x;
                py[1][t] = 1.0 - y;
                px[2][t] = -x * inv_n;
                py[2][t] = y * inv_n;
                px[3][t] = x * inv_n;
                py[3][t] = 1.0 - y * inv_n;
                px[4][t] = x * inv_m;
                py[4][t] = (1.0 - y) * inv_m;
                px[5][t] = -x * inv_m;
                py[5][t] = (n - y) * inv_m;
            }
        }
        if !valid {
            return Err(coincident(samples, [i, j, k]));
        }
        for (o, c) in counts.iter_mut().enumerate() {
            calculus.classify_normalised_into(&px[o][..len], &py[o][..len], &mut states[..len]);
            let mut quads = states[..len].chunks_exact(4);
            for quad in &mut quads {
                for (lane, st) in quad.iter().enumerate() {
                    c[usize::from(*st)][lane] += 1;
                }
            }
            for st in quads.remainder() {
                c[usize::from(*st)][0] += 1;
            }
        }
    }
    Ok(counts
        .into_iter()
        .map(|c| c.into_iter().map(|l| l.iter().sum()).collect())
        .collect())
}

/// The constraints of a line-and-circle calculus, rewritten for each of the six orderings
/// as forms in the *base* frame of the unordered triplet.
///
/// Every constraint is `f(X, Y) = α(X² + Y²) + βX + γY + δ` (lines: α = 0). The orderings'
/// positions are Möbius-like maps of the base position `(x, y)` (see [`step_counts`]), and
/// multiplying `f(T(x, y))` by the positive factor 1, `n` or `m` turns each into a form
/// `A·n + B·x + C·y + D` with `n = x² + y²` — the same sign, so the same side of the curve.
/// The six classifications then need no divisions and no transformed points:
///
/// | ordering | A | B | C | D |
/// |---|---|---|---|---|
/// | `(x, y)` | α | β | γ | δ |
/// | `(−x, 1 − y)` | α | −β | −2α − γ | α + γ + δ |
/// | `(−x/n, y/n)` ×n | δ | −β | γ | α |
/// | `(x/n, 1 − y/n)` ×n | α + γ + δ | β | −2α − γ | α |
/// | `(x/m, (1 − y)/m)` ×m | δ | β | −γ − 2δ | α + γ + δ |
/// | `(−x/m, (n − y)/m)` ×m | α + γ + δ | −β | −γ − 2δ | δ |
struct SixForms {
    /// The forms of each ordering, with their bits.
    forms: [Vec<(Form, u32)>; 6],
}

/// One form, compiled. Most forms have a single term `±u + D` (`u` one of `n`, `x`, `y`);
/// those are one comparison, `u ≥ −D` or `u ≤ D`, which is exact in IEEE arithmetic (a
/// rounded sum is zero only when the exact sum is, and keeps its sign), so the result is the
/// same as evaluating the form.
#[derive(Debug, Clone, Copy)]
enum Form {
    /// `u ≥ t` (or `u > t` when not `inclusive`), `u` = `[n, x, y][var]`.
    Above { var: usize, t: f64, inclusive: bool },
    /// `u ≤ t` (or `u < t`).
    Below { var: usize, t: f64, inclusive: bool },
    /// `A·n + B·x + C·y + D ≥ 0` (or `> 0`).
    General { coef: [f64; 4], inclusive: bool },
}

impl Form {
    fn compile([a, b, c, d]: [f64; 4], inclusive: bool) -> Self {
        let terms = [a, b, c];
        let nonzero: Vec<usize> = (0..3).filter(|&i| terms[i] != 0.0).collect();
        match nonzero.as_slice() {
            [var] if terms[*var] == 1.0 => Self::Above {
                var: *var,
                t: -d,
                inclusive,
            },
            [var] if terms[*var] == -1.0 => Self::Below {
                var: *var,
                t: d,
                inclusive,
            },
            _ => Self::General {
                coef: [a, b, c, d],
                inclusive,
            },
        }
    }
}

impl SixForms {
    fn new(calculus: &Calculus) -> Option<Self> {
        let qsr_core::Partition::Constraints(_) = calculus.partition() else {
            return None;
        };
        let spec = calculus.spec();
        if spec.constraints.len() > 8 {
            return None; // 2^k sign-vector bins per ordering stay small (≤ 256)
        }
        let mut forms: [Vec<(Form, u32)>; 6] = Default::default();
        for (k, c) in spec.constraints.iter().enumerate() {
            let (al, be, ga, de) = match c.shape {
                qsr_core::Shape::Line { a, b, c } => (0.0, a, b, c),
                qsr_core::Shape::Circle { center, radius } => (
                    1.0,
                    -2.0 * center[0],
                    -2.0 * center[1],
                    center[0] * center[0] + center[1] * center[1] - radius * radius,
                ),
            };
            let pos = c.zero == qsr_core::Side::Positive;
            let rows = [
                [al, be, ga, de],
                [al, -be, -2.0 * al - ga, al + ga + de],
                [de, -be, ga, al],
                [al + ga + de, be, -2.0 * al - ga, al],
                [de, be, -ga - 2.0 * de, al + ga + de],
                [al + ga + de, -be, -ga - 2.0 * de, de],
            ];
            for (o, r) in rows.into_iter().enumerate() {
                forms[o].push((Form::compile(r, pos), k as u32));
            }
        }
        Some(Self { forms })
    }
}

/// [`triplet_counts`] for all six orderings of a line-and-circle calculus via [`SixForms`].
#[inline(always)]
fn six_counts(
    calculus: &Calculus,
    forms: &SixForms,
    samples: &ScanSamples,
    [i, j, k]: [usize; 3],
) -> Result<Vec<Vec<u32>>> {
    let qsr_core::Partition::Constraints(partition) = calculus.partition() else {
        return Err(PqrmError::InvalidConfig(
            "six_counts needs a constraint calculus".into(),
        ));
    };
    let table = partition.table();
    let q = calculus.n_states();
    // Histogram the sign vectors themselves (2^k bins, k ≤ 8 here) and map bins to states
    // once at the end: the per-sample table lookup disappears from the hot loop.
    let bins = table.len();
    let mut counts = vec![vec![[0u32; 4]; bins]; 6];
    let ((ax, ay), (bx, by), (cx, cy)) =
        (samples.columns(i), samples.columns(j), samples.columns(k));
    let s = samples.samples();
    let mut xs = [0.0f64; CHUNK];
    let mut ys = [0.0f64; CHUNK];
    let mut ns = [0.0f64; CHUNK];
    // u64 lanes: an f64 comparison yields a 64-bit mask, so no narrowing in the loops
    let mut v = [0u64; CHUNK];
    let tol2 = qsr_core::DEGENERATE_TOLERANCE * qsr_core::DEGENERATE_TOLERANCE;
    for start in (0..s).step_by(CHUNK) {
        let len = CHUNK.min(s - start);
        let mut valid = true;
        for t in 0..len {
            let u = start + t;
            let ([x, y, n, _], ab, c_apart) =
                base_sample([ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]], tol2);
            valid &= ab & c_apart;
            xs[t] = x;
            ys[t] = y;
            ns[t] = n;
        }
        if !valid {
            return Err(coincident(samples, [i, j, k]));
        }
        let (x, y, n) = (&xs[..len], &ys[..len], &ns[..len]);
        for (o, c) in counts.iter_mut().enumerate() {
            let bv = &mut v[..len];
            bv.fill(0);
            let vars = [n, x, y];
            for &(form, bit) in &forms.forms[o] {
                match form {
                    Form::Above { var, t, inclusive } => {
                        let pts = bv.iter_mut().zip(vars[var]);
                        if inclusive {
                            pts.for_each(|(vi, &u)| *vi |= u64::from(u >= t) << bit);
                        } else {
                            pts.for_each(|(vi, &u)| *vi |= u64::from(u > t) << bit);
                        }
                    }
                    Form::Below { var, t, inclusive } => {
                        let pts = bv.iter_mut().zip(vars[var]);
                        if inclusive {
                            pts.for_each(|(vi, &u)| *vi |= u64::from(u <= t) << bit);
                        } else {
                            pts.for_each(|(vi, &u)| *vi |= u64::from(u < t) << bit);
                        }
                    }
                    Form::General {
                        coef: [fa, fb, fc, fd],
                        inclusive,
                    } => {
                        let pts = bv.iter_mut().zip(x).zip(y).zip(n);
                        if inclusive {
                            pts.for_each(|(((vi, &x), &y), &n)| {
                                *vi |= u64::from(fa * n + fb * x + fc * y + fd >= 0.0) << bit;
                            });
                        } else {
                            pts.for_each(|(((vi, &x), &y), &n)| {
                                *vi |= u64::from(fa * n + fb * x + fc * y + fd > 0.0) << bit;
                            });
                        }
                    }
                }
            }
            let mut quads = bv.chunks_exact(4);
            for quad in &mut quads {
                for (lane, vi) in quad.iter().enumerate() {
                    c[*vi as usize][lane] += 1;
                }
            }
            for vi in quads.remainder() {
                c[*vi as usize][0] += 1;
            }
        }
    }
    Ok(counts
        .into_iter()
        .map(|c| {
            let mut out = vec![0u32; q];
            for (bin, lanes) in c.iter().enumerate() {
                out[usize::from(table[bin])] += lanes.iter().sum::<u32>();
            }
            out
        })
        .collect())
}

/// Sums counts of a finer calculus into a coarser one.
#[must_use]
pub fn merge_counts(merge: &MergeMap, counts: &[u32]) -> Vec<u32> {
    let mut out = vec![0u32; merge.n_coarse()];
    for (c, s) in counts.iter().zip(merge.as_slice()) {
        out[s.index()] += c;
    }
    out
}

/// Log-probabilities `ln p(q)` from counts with `floor` pseudo-counts per state.
///
/// With `floor = 0` a state with no count gets `-inf`.
#[must_use]
pub fn log_likelihood(counts: &[u32], floor: f64) -> Vec<f64> {
    let total: f64 =
        counts.iter().map(|&c| f64::from(c)).sum::<f64>() + floor * counts.len() as f64;
    counts
        .iter()
        .map(|&c| ((f64::from(c) + floor) / total).ln())
        .collect()
}
