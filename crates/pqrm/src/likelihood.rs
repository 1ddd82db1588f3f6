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
use crate::spread::{FrameBounds, Spread};

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

/// `A,B,C`: three distinct landmark ids (a command line's `--set 4,7,9`).
impl std::str::FromStr for LandmarkSet {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let ids: Vec<u32> = s
            .split(',')
            .map(|t| t.trim().parse::<u32>().map_err(|e| format!("`{t}`: {e}")))
            .collect::<std::result::Result<_, _>>()?;
        match ids.as_slice() {
            [a, b, c] if a != b && b != c && a != c => Ok(Self::new(*a, *b, *c)),
            [_, _, _] => Err(format!("`{s}` repeats a landmark")),
            _ => Err(format!("`{s}`: expected three landmark ids A,B,C")),
        }
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
        .map_err(|e| match e {
            // Only a degenerate frame means coincident landmarks; any other calculus error
            // (a calculus of the wrong kind, say) is reported as what it is.
            qsr_core::QsrError::DegenerateFrame { .. } => {
                let ids = samples.ids();
                PqrmError::CoincidentLandmarks {
                    set: [ids[i].0, ids[j].0, ids[k].0],
                    reason: e.to_string(),
                }
            }
            other => PqrmError::Calculus(other),
        })?;
    let mut counts = vec![0u32; calculus.n_states()];
    for s in buffer.iter() {
        counts[s.index()] += 1;
    }
    Ok(counts)
}

/// Histograms of one step: each landmark set with its state counts, in one flat table
/// (`n_states` counts per set) so that a step over a million sets is two allocations, not a
/// million.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StepCounts {
    n_states: usize,
    sets: Vec<LandmarkSet>,
    counts: Vec<u32>,
}

impl StepCounts {
    /// No sets, histograms of `n_states` bins.
    #[must_use]
    pub fn new(n_states: usize) -> Self {
        Self {
            n_states,
            sets: Vec::new(),
            counts: Vec::new(),
        }
    }

    /// Histograms given set by set.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when a histogram does not have `n_states` bins.
    pub fn from_pairs<'a>(
        n_states: usize,
        pairs: impl IntoIterator<Item = (LandmarkSet, &'a [u32])>,
    ) -> Result<Self> {
        let mut out = Self::new(n_states);
        for (set, c) in pairs {
            out.push(set, c)?;
        }
        Ok(out)
    }

    /// Histograms given as `(set, counts)` pairs, the number of states taken from the first
    /// (a convenience for tests and hand-made evidence).
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when the histograms differ in length.
    pub fn from_vecs(pairs: &[(LandmarkSet, Vec<u32>)]) -> Result<Self> {
        let q = pairs.first().map_or(0, |(_, c)| c.len());
        Self::from_pairs(q, pairs.iter().map(|(s, c)| (*s, c.as_slice())))
    }

    /// Appends one set's histogram.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when it does not have `n_states` bins.
    pub fn push(&mut self, set: LandmarkSet, counts: &[u32]) -> Result<()> {
        if counts.len() != self.n_states {
            return Err(PqrmError::Mismatch(format!(
                "set {:?}: {} counts for a {}-state calculus",
                set.ids(),
                counts.len(),
                self.n_states
            )));
        }
        self.sets.push(set);
        self.counts.extend_from_slice(counts);
        Ok(())
    }

    /// Bins per histogram.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.n_states
    }

    /// Number of sets.
    #[must_use]
    pub fn len(&self) -> usize {
        self.sets.len()
    }

    /// Whether no set was observed.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.sets.is_empty()
    }

    /// The sets, in order.
    #[must_use]
    pub fn sets(&self) -> &[LandmarkSet] {
        &self.sets
    }

    /// The histogram of the `i`-th set.
    #[must_use]
    pub fn counts(&self, i: usize) -> &[u32] {
        &self.counts[i * self.n_states..(i + 1) * self.n_states]
    }

    /// Sets with their histograms, in order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = (LandmarkSet, &[u32])> + '_ {
        // `max(1)`: a zero-state table has no bins to chunk (and no sets either)
        self.sets
            .iter()
            .copied()
            .zip(self.counts.chunks_exact(self.n_states.max(1)))
    }

    /// The same sets with their counts summed into a coarser calculus.
    #[must_use]
    pub fn merged(&self, merge: &MergeMap) -> Self {
        let mut counts = vec![0u32; self.sets.len() * merge.n_coarse()];
        for (out, (_, c)) in counts
            .chunks_exact_mut(merge.n_coarse().max(1))
            .zip(self.iter())
        {
            for (n, s) in c.iter().zip(merge.as_slice()) {
                out[s.index()] += n;
            }
        }
        Self {
            n_states: merge.n_coarse(),
            sets: self.sets.clone(),
            counts,
        }
    }
}

impl<'a> IntoIterator for &'a StepCounts {
    type Item = (LandmarkSet, &'a [u32]);
    type IntoIter = Box<dyn ExactSizeIterator<Item = (LandmarkSet, &'a [u32])> + 'a>;
    fn into_iter(self) -> Self::IntoIter {
        Box::new(self.iter())
    }
}

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
/// so a step costs one frame per unordered triplet instead of six. Parallel over the pairs
/// `(i, j)`, each writing its own slice of one preallocated table; the result does not depend
/// on the thread count. Sets come out grouped by unordered triplet, in the order of the table.
///
/// # Errors
/// [`PqrmError::CoincidentLandmarks`] when two landmarks of a triplet coincide in a sample
/// (within [`qsr_core::DEGENERATE_TOLERANCE`]): possible only with zero noise.
pub fn step_counts(
    calculus: &Calculus,
    samples: &ScanSamples,
    orderings: Orderings,
) -> Result<StepCounts> {
    let mut out = StepCounts::default();
    step_counts_with(calculus, samples, orderings, Kernel::FAST, &mut out)?;
    Ok(out)
}

/// [`step_counts`] into the tables of an earlier step's counts, reused: a map's steps then
/// write into memory they already hold instead of a fresh table each (for 10⁶ sets, 90 MB a
/// step that the kernel would first have to fault in — 7 % of mapping them).
///
/// # Errors
/// As [`step_counts`]; `out` then holds no meaningful counts.
pub fn step_counts_into(
    calculus: &Calculus,
    samples: &ScanSamples,
    orderings: Orderings,
    out: &mut StepCounts,
) -> Result<()> {
    step_counts_with(calculus, samples, orderings, Kernel::FAST, out)
}

/// Which fast paths a step takes — all of them but in the tests that compare each with the
/// plain loops.
#[derive(Debug, Clone, Copy)]
struct Kernel {
    /// The fused key loops where the calculus's shape has one (else a pass per quantity).
    fused: bool,
    /// A triplet whose samples' discs settle every quantity's sign is counted at once
    /// ([`crate::spread`]).
    decided: bool,
}

impl Kernel {
    const FAST: Self = Self {
        fused: true,
        decided: true,
    };
}

/// [`step_counts`] with the fast paths of `kernel` (without `fused`: the pass per quantity
/// every calculus can take; without `decided`: every sample classified).
fn step_counts_with(
    calculus: &Calculus,
    samples: &ScanSamples,
    orderings: Orderings,
    kernel: Kernel,
    out: &mut StepCounts,
) -> Result<()> {
    let ids = samples.ids();
    let m = ids.len();
    let q = calculus.n_states();
    let n_orders = match orderings {
        Orderings::All => 6,
        Orderings::Canonical => 1,
    };
    // the keys' state table is built once per step, not per triplet
    let forms = SixForms::new(calculus, n_orders).map(|f| SixForms {
        fused: kernel.fused,
        decided: kernel.decided,
        ..f
    });
    let forms = forms.as_ref();
    // parallel over the pairs (i, j): tasks of m − j − 1 triplets each balance the two
    // cores far better than one task per first landmark (m − 1 − i pairs, very unequal)
    let pairs: Vec<(usize, usize)> = (0..m)
        .flat_map(|i| (i + 1..m).map(move |j| (i, j)))
        .collect();
    let n_sets: usize = pairs.iter().map(|&(_, j)| (m - j - 1) * n_orders).sum();
    let StepCounts {
        n_states,
        sets,
        counts,
    } = out;
    *n_states = q;
    sets.clear();
    sets.reserve_exact(n_sets);
    for &(i, j) in &pairs {
        for k in j + 1..m {
            let [a, b, c] = [ids[i], ids[j], ids[k]];
            let six = [
                [a, b, c],
                [b, a, c],
                [a, c, b],
                [c, a, b],
                [b, c, a],
                [c, b, a],
            ];
            sets.extend(six.into_iter().take(n_orders).map(LandmarkSet));
        }
    }
    // every triplet writes all its counts (`triplet_counts`), so a reused table needs no
    // clearing: only growing or shrinking to this step's size
    counts.resize(n_sets * q, 0);
    // each pair's slice of the table: (m − j − 1) triplets × n_orders histograms
    let mut slices = Vec::with_capacity(pairs.len());
    let mut rest = counts.as_mut_slice();
    for &(_, j) in &pairs {
        let (mine, tail) = rest.split_at_mut((m - j - 1) * n_orders * q);
        slices.push(mine);
        rest = tail;
    }
    let spreads = spreads(samples);
    pairs
        .into_par_iter()
        .zip(slices)
        .try_for_each(|((i, j), out)| {
            let mut scratch = Scratch::default();
            for (k, triplet_out) in (j + 1..m).zip(out.chunks_exact_mut((n_orders * q).max(1))) {
                let spread = [&spreads[i], &spreads[j], &spreads[k]];
                let apart =
                    Apart::new(spread.map(|s| s.as_ref().map_or(f64::INFINITY, |s| s.max_norm2)));
                triplet_counts(
                    calculus,
                    forms,
                    samples,
                    ([i, j, k], apart, spread),
                    orderings,
                    &mut scratch,
                    triplet_out,
                )?;
            }
            Ok::<(), PqrmError>(())
        })?;
    Ok(())
}

/// [`step_counts_with`] into a new table (the tests' form).
#[cfg(test)]
fn counts_with(
    calculus: &Calculus,
    samples: &ScanSamples,
    orderings: Orderings,
    kernel: Kernel,
) -> Result<StepCounts> {
    let mut out = StepCounts::default();
    step_counts_with(calculus, samples, orderings, kernel, &mut out)?;
    Ok(out)
}

/// Each landmark's samples' disc and largest squared norm ([`Spread`]; `None` where a sample
/// is not finite): with the norms, one comparison per pair of a sample settles the
/// coincidence check (see `Apart`); with the discs, a triplet may be settled before its
/// samples are classified.
fn spreads(samples: &ScanSamples) -> Vec<Option<Spread>> {
    (0..samples.ids().len())
        .map(|i| {
            let (x, y) = samples.columns(i);
            Spread::of(x, y)
        })
        .collect()
}

/// Buffers one task reuses for all its triplets (no allocation per triplet).
#[derive(Default)]
struct Scratch {
    /// Sign-key histogram, four interleaved lanes per key: `HIST_BINS` long once used (a
    /// fixed length, so that a masked key needs no bounds check).
    hist: Vec<[u32; 4]>,
    /// Whether `hist` may hold counts (a triplet stopped by an error before folding them).
    hist_dirty: bool,
    /// One chunk of samples in the scaled base frame (`x·d`, `y·d`, `n·d`, `d`; see
    /// [`ScaledFrame`]) and their keys: kept here, not
    /// zeroed on the stack for every triplet.
    frame: Vec<[[f64; CHUNK]; 4]>,
    keys: Vec<[u64; CHUNK]>,
    /// Per-ordering histograms of the generic path, four lanes per state.
    lanes: Vec<[u32; 4]>,
}

/// Conservative thresholds for the coincidence checks of [`base_sample`], from each
/// landmark's largest squared norm over its samples (`r²`): `tol²·(1 + r²_a + r²_b)` is at
/// least `tol²·(1 + a² + b²)` for every sample (rounding is monotone), so `|AB|² > ab`
/// implies the exact check passes. A chunk where a sample fails the bound is settled with the
/// exact checks: the outcome is the exact one, at one comparison per pair.
#[derive(Debug, Clone, Copy)]
struct Apart {
    ab: f64,
    ac: f64,
    bc: f64,
}

impl Apart {
    fn new([ra, rb, rc]: [f64; 3]) -> Self {
        let tol2 = qsr_core::DEGENERATE_TOLERANCE * qsr_core::DEGENERATE_TOLERANCE;
        Self {
            ab: tol2 * (1.0 + ra + rb),
            ac: tol2 * (1.0 + ra + rc),
            bc: tol2 * (1.0 + rb + rc),
        }
    }
}

/// One sample of a triplet in its base frame scaled by `d = |AB|²`: `x·d`, `y·d`,
/// `n·d = |AC|²`, `d`, and `|BC|²` — no division.
///
/// A quantity `u − t` of [`SixForms`] has the sign of `u·d − t·d` and a general one
/// `A·n + B·x + C·y + D` the sign of `A·(n·d) + B·(x·d) + C·(y·d) + D·d` (`d > 0`), so the keys
/// are taken from these polynomials in the coordinates: a handful of roundings each, relative
/// to the magnitude of their terms, where the normalised frame adds a division's. A sample's
/// key can differ from the exact one only within ~10⁻¹⁵ (relative) of a boundary;
/// `exact_reference::keys_agree_with_exact_arithmetic` checks it against exact dyadic
/// arithmetic.
#[derive(Debug, Clone, Copy)]
struct ScaledFrame {
    x: f64,
    y: f64,
    n: f64,
    d: f64,
    bc: f64,
}

impl ScaledFrame {
    #[inline(always)]
    fn of(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> Self {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let (vx, vy) = (c[0] - a[0], c[1] - a[1]);
        let (wx, wy) = (c[0] - b[0], c[1] - b[1]);
        Self {
            x: dy * vx - dx * vy,
            y: dx * vx + dy * vy,
            n: vx * vx + vy * vy,
            d: dx * dx + dy * dy,
            bc: wx * wx + wy * wy,
        }
    }
}

/// One sample of a triplet in its base normalised frame: `(x, y, n = x² + y²,
/// m = x² + (y − 1)²)` (the general classifier's input), whether A and B are distinct, and
/// whether C is distinct from both (relative to their magnitude; the squared distances of
/// [`ScaledFrame`], so that every path checks coincidence on the same numbers).
#[inline(always)]
fn base_sample(a: [f64; 2], b: [f64; 2], c: [f64; 2], tol2: f64) -> ([f64; 4], bool, bool) {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let (vx, vy) = (c[0] - a[0], c[1] - a[1]);
    let inv = 1.0 / (dx * dx + dy * dy);
    let x = -(dx * vy - dy * vx) * inv;
    let y = (dx * vx + dy * vy) * inv;
    let xynm = [x, y, x * x + y * y, x * x + (y - 1.0) * (y - 1.0)];
    let scaled = ScaledFrame::of(a, b, c);
    let a2 = a[0] * a[0] + a[1] * a[1];
    let b2 = b[0] * b[0] + b[1] * b[1];
    let c2 = c[0] * c[0] + c[1] * c[1];
    let ab = scaled.d > tol2 * (1.0 + a2 + b2);
    let c_apart = (scaled.n > tol2 * (1.0 + a2 + c2)) & (scaled.bc > tol2 * (1.0 + b2 + c2));
    (xynm, ab, c_apart)
}

/// The exact coincidence checks of samples `range` (where the conservative bounds failed).
fn check_apart<const ORDERS: usize>(
    samples: &ScanSamples,
    [i, j, k]: [usize; 3],
    range: std::ops::Range<usize>,
) -> Result<()> {
    let tol2 = qsr_core::DEGENERATE_TOLERANCE * qsr_core::DEGENERATE_TOLERANCE;
    let ((ax, ay), (bx, by), (cx, cy)) =
        (samples.columns(i), samples.columns(j), samples.columns(k));
    for u in range {
        let (_, ab, c_apart) = base_sample([ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]], tol2);
        if !(ab & (ORDERS == 1 || c_apart)) {
            return Err(coincident(samples, [i, j, k]));
        }
    }
    Ok(())
}

/// The error for a triplet with two coincident landmarks in a sample.
/// Or, where the coordinates are so large that a squared distance overflows (the checks then
/// read `inf ≤ inf`), that: the real cause rather than "coincide".
fn coincident(samples: &ScanSamples, [i, j, k]: [usize; 3]) -> PqrmError {
    let set = [samples.ids()[i].0, samples.ids()[j].0, samples.ids()[k].0];
    let largest = [i, j, k]
        .iter()
        .flat_map(|&l| {
            let (x, y) = samples.columns(l);
            x.iter().chain(y)
        })
        .fold(0.0f64, |m, v| m.max(v.abs()));
    // |B − A|² can reach (2·largest)²·2
    if !(8.0 * largest * largest).is_finite() {
        return PqrmError::NonFinite(format!(
            "landmarks {set:?}: sample coordinates up to {largest:e} are too large for squared \
             distances (they overflow); keep them below 1e150"
        ));
    }
    PqrmError::CoincidentLandmarks {
        set,
        reason: "two of the three landmarks coincide in a sample (zero noise on one spot?)".into(),
    }
}

/// Histograms of the orderings of one unordered triplet (six, or one for
/// [`Orderings::Canonical`]).
///
/// On x86-64 CPUs with AVX-512 or AVX2 the same code runs compiled for them (picked at run
/// time, so the binary and the wheel stay portable): the normalisation and the constraint
/// loops of the classifier vectorise over eight or four doubles instead of two. The arithmetic is the same
/// IEEE operations in the same order (Rust never contracts `a * b + c` into an FMA), so the
/// counts are identical on every CPU.
fn triplet_counts(
    calculus: &Calculus,
    forms: Option<&SixForms>,
    samples: &ScanSamples,
    triplet: ([usize; 3], Apart, [&Option<Spread>; 3]),
    orderings: Orderings,
    scratch: &mut Scratch,
    out: &mut [u32],
) -> Result<()> {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx512f")
        && std::arch::is_x86_feature_detected!("avx512dq")
        && std::arch::is_x86_feature_detected!("avx512vl")
        && std::arch::is_x86_feature_detected!("avx512bw")
    {
        #[allow(unsafe_code)]
        // SAFETY: `triplet_counts_avx512` only requires these AVX-512 parts, just detected.
        return unsafe {
            triplet_counts_avx512(calculus, forms, samples, triplet, orderings, scratch, out)
        };
    }
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        #[allow(unsafe_code)]
        // SAFETY: `triplet_counts_avx2` only requires AVX2, which was just detected.
        return unsafe {
            triplet_counts_avx2(calculus, forms, samples, triplet, orderings, scratch, out)
        };
    }
    triplet_counts_portable(calculus, forms, samples, triplet, orderings, scratch, out)
}

/// [`triplet_counts`] compiled for AVX-512 (eight doubles per operation, compare masks in
/// mask registers): about 12 % faster than the AVX2 build where the CPU has it (0.95–0.98
/// against 1.08–1.13 ms, `cargo run --release -p pqrm --example step_timing`), the same operations in the same
/// order.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
fn triplet_counts_avx512(
    calculus: &Calculus,
    forms: Option<&SixForms>,
    samples: &ScanSamples,
    triplet: ([usize; 3], Apart, [&Option<Spread>; 3]),
    orderings: Orderings,
    scratch: &mut Scratch,
    out: &mut [u32],
) -> Result<()> {
    triplet_counts_portable(calculus, forms, samples, triplet, orderings, scratch, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn triplet_counts_avx2(
    calculus: &Calculus,
    forms: Option<&SixForms>,
    samples: &ScanSamples,
    triplet: ([usize; 3], Apart, [&Option<Spread>; 3]),
    orderings: Orderings,
    scratch: &mut Scratch,
    out: &mut [u32],
) -> Result<()> {
    triplet_counts_portable(calculus, forms, samples, triplet, orderings, scratch, out)
}

/// `forms` is [`SixForms::new`] of `calculus` for the orderings wanted when the calculus
/// has such forms (built once per step by the caller). `out` receives the orderings'
/// histograms one after the other (`n_states` counts each).
#[inline(always)]
fn triplet_counts_portable(
    calculus: &Calculus,
    forms: Option<&SixForms>,
    samples: &ScanSamples,
    ([i, j, k], apart, spread): ([usize; 3], Apart, [&Option<Spread>; 3]),
    orderings: Orderings,
    scratch: &mut Scratch,
    out: &mut [u32],
) -> Result<()> {
    if let Some(forms) = forms {
        if forms.decided {
            match settle(forms, spread, apart) {
                Settled::All(key) => {
                    decided_counts(forms, calculus.n_states(), key, samples.samples(), out);
                    return Ok(());
                }
                Settled::Partly(partial) if partial.free.len() <= MAX_FREE => {
                    let at = (calculus, forms, samples, [i, j, k]);
                    // the orderings and the open quantities as constants: each pair its loop
                    return match (forms.orders == 6, partial.free.len()) {
                        (true, 1) => partial_counts::<6, 1>(at, &partial, out),
                        (true, 2) => partial_counts::<6, 2>(at, &partial, out),
                        (true, 3) => partial_counts::<6, 3>(at, &partial, out),
                        (true, _) => partial_counts::<6, 4>(at, &partial, out),
                        (false, 1) => partial_counts::<1, 1>(at, &partial, out),
                        (false, 2) => partial_counts::<1, 2>(at, &partial, out),
                        (false, 3) => partial_counts::<1, 3>(at, &partial, out),
                        (false, _) => partial_counts::<1, 4>(at, &partial, out),
                    };
                }
                Settled::Partly(_) | Settled::Not => {}
            }
        }
        // the number of orderings as a constant: the canonical kernel skips the checks and
        // the table columns of the other five
        return if forms.orders == 6 {
            six_counts::<6>(calculus, forms, samples, ([i, j, k], apart), scratch, out)
        } else {
            six_counts::<1>(calculus, forms, samples, ([i, j, k], apart), scratch, out)
        };
    }
    let q = calculus.n_states();
    let n_orders = if orderings == Orderings::All { 6 } else { 1 };
    // Four interleaved sub-histograms per ordering: consecutive samples mostly share a state,
    // and a single counter would serialise on its own increments.
    let lanes = &mut scratch.lanes;
    lanes.clear();
    lanes.resize(n_orders * q, [0u32; 4]);
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
        for (o, c) in lanes.chunks_exact_mut(q.max(1)).enumerate() {
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
    for (o, l) in out.iter_mut().zip(lanes.iter()) {
        *o = l.iter().sum();
    }
    Ok(())
}

/// The constraints of a line-and-circle calculus, rewritten for each of the six orderings
/// as forms in the *base* frame of the unordered triplet, and grouped into the few
/// *quantities* whose signs decide them all.
///
/// Every constraint is `f(X, Y) = α(X² + Y²) + βX + γY + δ` (lines: α = 0). The orderings'
/// positions are Möbius-like maps of the base position `(x, y)` (see [`step_counts`]), and
/// multiplying `f(T(x, y))` by the positive factor 1, `n` or `m` turns each into a form
/// `A·n + B·x + C·y + D` with `n = x² + y²` — the same sign, so the same side of the curve:
///
/// | ordering | A | B | C | D |
/// |---|---|---|---|---|
/// | `(x, y)` | α | β | γ | δ |
/// | `(−x, 1 − y)` | α | −β | −2α − γ | α + γ + δ |
/// | `(−x/n, y/n)` ×n | δ | −β | γ | α |
/// | `(x/n, 1 − y/n)` ×n | α + γ + δ | β | −2α − γ | α |
/// | `(x/m, (1 − y)/m)` ×m | δ | β | −γ − 2δ | α + γ + δ |
/// | `(−x/m, (n − y)/m)` ×m | α + γ + δ | −β | −γ − 2δ | δ |
///
/// Many of the 6k forms are the same quantity up to sign or a power-of-two factor (the EDC's
/// 36 are 7 quantities: `x`, `y`, `y − ½`, `y − 1`, `n − 1`, `n − y`, `n − 2y`). A sample is
/// then classified in all six orderings by the signs of those quantities: one *key* with a
/// bit per quantity, one histogram bin per key, and a table from keys to the six states
/// applied once per triplet. Scaling by a power of two and negating are exact in IEEE
/// arithmetic, so a quantity's sign is exactly each member form's sign; a single-term form
/// `a·u + d` with `a = ±2^e` is the exact comparison `u ≷ −d/a`. Samples where a quantity
/// is exactly zero (on a boundary, where the `zero` side of each constraint decides) take a
/// slow path per sample. The counts are identical to classifying each ordering directly.
///
/// Built for the canonical ordering alone ([`Orderings::Canonical`]), only its own quantities
/// are kept (the EDC's 5 of 7): the same keys, a sixth of the table.
struct SixForms {
    /// How many orderings, in the order of the table above: 6, or 1 (the base ordering).
    orders: usize,
    /// The distinct quantities.
    quantities: Vec<Quantity>,
    /// Per ordering, per constraint: which quantity decides it and how.
    members: [Vec<Member>; 6],
    /// The orderings' states for each key with no quantity zero (bit g: quantity g > 0);
    /// `orders` of the six are used.
    states: Vec<[u16; 6]>,
    /// The quantities grouped by kind for the fused key loop ([`fused_keys`]).
    grouped: Grouped,
    /// Whether the fused loop is used where the shape has one (false only in the test that
    /// compares the two loops).
    fused: bool,
    /// Whether a triplet the samples' discs settle is counted at once (false only in the
    /// test that compares it with classifying every sample).
    decided: bool,
}

/// The quantities of a [`SixForms`] grouped by kind — single-term ones on `n`, on `x`, on
/// `y`, then general forms — each with its key bits, so that a loop specialised to the
/// group sizes ([`fused_keys`]) takes every sign with no per-quantity choice left to run
/// time. The sizes of the built-in calculi are dispatched to such loops (see
/// [`fused_dispatch`]); a calculus of another shape keeps the pass-per-quantity loop.
#[derive(Debug, Clone, Default)]
struct Grouped {
    /// Thresholds of the single-term quantities on `n`, `x`, `y`.
    t: [Vec<f64>; 3],
    /// Their key bits (the quantity's index).
    t_bit: [Vec<u32>; 3],
    /// Coefficients of the general forms and their key bits.
    coef: Vec<[f64; 4]>,
    coef_bit: Vec<u32>,
}

impl Grouped {
    fn new(quantities: &[Quantity]) -> Self {
        let mut g = Self::default();
        for (bit, q) in quantities.iter().enumerate() {
            match *q {
                Quantity::Single { var, t } => {
                    g.t[var].push(t);
                    g.t_bit[var].push(bit as u32);
                }
                Quantity::General { coef } => {
                    g.coef.push(coef);
                    g.coef_bit.push(bit as u32);
                }
            }
        }
        g
    }

    /// `[on n, on x, on y, general]`.
    fn shape(&self) -> [usize; 4] {
        [
            self.t[0].len(),
            self.t[1].len(),
            self.t[2].len(),
            self.coef.len(),
        ]
    }
}

/// A quantity whose sign decides forms: `u − t` (`u` = `[n, x, y][var]`, compared, never
/// subtracted) or `A·n + B·x + C·y + D` evaluated in that order.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Quantity {
    /// `u − t`.
    Single { var: usize, t: f64 },
    /// `A·n + B·x + C·y + D`, scaled so that the largest |coefficient| is in [1, 2) and the
    /// first non-zero one is positive.
    General { coef: [f64; 4] },
}

/// A constraint of one ordering: its form is `±2^e ×` quantity `q`.
#[derive(Debug, Clone, Copy)]
struct Member {
    q: usize,
    negated: bool,
    /// True on the boundary (the constraint's `zero` side is positive).
    inclusive: bool,
    bit: u32,
}

/// Most quantities handled by keys (2^10 histogram bins).
const MAX_QUANTITIES: usize = 10;

/// Bins of the key histogram: every key of `MAX_QUANTITIES` bits.
const HIST_BINS: usize = 1 << MAX_QUANTITIES;

fn power_of_two(v: f64) -> bool {
    v.is_normal() && v.abs().to_bits() & ((1u64 << 52) - 1) == 0
}

impl Quantity {
    /// The quantity of the form `[A, B, C, D]` and whether the form is its negation.
    fn of([a, b, c, d]: [f64; 4]) -> (Self, bool) {
        let terms = [a, b, c];
        let nonzero: Vec<usize> = (0..3).filter(|&i| terms[i] != 0.0).collect();
        if let [var] = nonzero.as_slice()
            && power_of_two(terms[*var])
        {
            // a·u + d = a·(u − t) exactly in sign, t = −d/a exact
            let t = -d / terms[*var] + 0.0;
            return (Self::Single { var: *var, t }, terms[*var] < 0.0);
        }
        let m = [a, b, c, d].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if m == 0.0 || !m.is_finite() {
            return (Self::General { coef: [0.0; 4] }, false);
        }
        let scale = 2f64.powi(-(m.log2().floor() as i32));
        let mut coef = [a * scale, b * scale, c * scale, d * scale];
        let negated = coef.iter().find(|v| **v != 0.0).is_some_and(|v| *v < 0.0);
        if negated {
            coef.iter_mut().for_each(|v| *v = -*v);
        }
        coef.iter_mut().for_each(|v| *v += 0.0); // no −0.0
        (Self::General { coef }, negated)
    }
}

impl SixForms {
    fn new(calculus: &Calculus, orders: usize) -> Option<Self> {
        let qsr_core::Partition::Constraints(partition) = calculus.partition() else {
            return None;
        };
        let spec = calculus.spec();
        if spec.constraints.len() > 8 {
            return None; // 2^k sign-vector bins per ordering stay small (≤ 256)
        }
        let mut quantities: Vec<Quantity> = Vec::new();
        let mut members: [Vec<Member>; 6] = Default::default();
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
            let inclusive = c.zero == qsr_core::Side::Positive;
            let rows = [
                [al, be, ga, de],
                [al, -be, -2.0 * al - ga, al + ga + de],
                [de, -be, ga, al],
                [al + ga + de, be, -2.0 * al - ga, al],
                [de, be, -ga - 2.0 * de, al + ga + de],
                [al + ga + de, -be, -ga - 2.0 * de, de],
            ];
            for (o, r) in rows.into_iter().enumerate().take(orders) {
                let (quantity, negated) = Quantity::of(r);
                let q = match quantities.iter().position(|x| *x == quantity) {
                    Some(q) => q,
                    None => {
                        quantities.push(quantity);
                        quantities.len() - 1
                    }
                };
                members[o].push(Member {
                    q,
                    negated,
                    inclusive,
                    bit: k as u32,
                });
            }
        }
        if quantities.len() > MAX_QUANTITIES {
            return None;
        }
        let table = partition.table();
        let mut signs = vec![0i8; quantities.len()];
        let states = (0..1usize << quantities.len())
            .map(|key| {
                for (g, s) in signs.iter_mut().enumerate() {
                    *s = if key >> g & 1 == 1 { 1 } else { -1 };
                }
                let mut out = [0u16; 6];
                for (o, st) in out.iter_mut().enumerate().take(orders) {
                    *st = table[Self::bin(&members[o], &signs)];
                }
                out
            })
            .collect();
        let grouped = Grouped::new(&quantities);
        Some(Self {
            orders,
            quantities,
            members,
            states,
            grouped,
            fused: true,
            decided: true,
        })
    }

    /// The sign-vector bin of one ordering given the quantities' signs (−1, 0, 1).
    fn bin(members: &[Member], signs: &[i8]) -> usize {
        members.iter().fold(0usize, |acc, m| {
            let s = if m.negated { -signs[m.q] } else { signs[m.q] };
            acc | usize::from(s > 0 || (s == 0 && m.inclusive)) << m.bit
        })
    }
}

/// One chunk of samples from their coordinates to their keys in one pass, specialised to
/// the group sizes of [`Grouped`]: each sample's base frame stays in registers and every
/// quantity's sign is taken there (bit `b`: quantity `b` > 0, bit `32 + b`: exactly zero),
/// so the loop vectorises over samples with nothing stored between passes and nothing
/// chosen per quantity at run time. The arithmetic is [`ScaledFrame`]'s and [`fill_keys`]'s,
/// operation for operation: the keys are the same bits. Returns whether every sample passed
/// the conservative coincidence bounds.
#[inline(always)]
fn fused_keys<
    const ORDERS: usize,
    const NN: usize,
    const NX: usize,
    const NY: usize,
    const NG: usize,
>(
    grouped: &Grouped,
    [ax, ay, bx, by, cx, cy]: [&[f64]; 6],
    apart: Apart,
    key: &mut [u64],
) -> bool {
    fn take<const N: usize, T: Copy + Default>(v: &[T]) -> [T; N] {
        let mut out = [T::default(); N];
        out.iter_mut().zip(v).for_each(|(o, v)| *o = *v);
        out
    }
    // a quantity's bits: where it is positive, where it is exactly zero
    fn bits<const N: usize>(b: &[u32]) -> ([u64; N], [u64; N]) {
        let at = |i: usize| b.get(i).copied().unwrap_or(0);
        (
            std::array::from_fn(|i| 1u64 << at(i)),
            std::array::from_fn(|i| 1u64 << (32 + at(i))),
        )
    }
    let (tn, tx, ty): ([f64; NN], [f64; NX], [f64; NY]) = (
        take(&grouped.t[0]),
        take(&grouped.t[1]),
        take(&grouped.t[2]),
    );
    let coef: [[f64; 4]; NG] = take(&grouped.coef);
    let (gn, zn) = bits::<NN>(&grouped.t_bit[0]);
    let (gx, zx) = bits::<NX>(&grouped.t_bit[1]);
    let (gy, zy) = bits::<NY>(&grouped.t_bit[2]);
    let (gg, zg) = bits::<NG>(&grouped.coef_bit);
    let len = key.len();
    let (ax, ay, bx, by, cx, cy) = (
        &ax[..len],
        &ay[..len],
        &bx[..len],
        &by[..len],
        &cx[..len],
        &cy[..len],
    );
    let mut valid = true;
    for u in 0..len {
        let ScaledFrame { x, y, n, d, bc } =
            ScaledFrame::of([ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]]);
        // the canonical ordering alone needs only A ≠ B; the others use C as a reference
        valid &= (d > apart.ab) & (ORDERS == 1 || ((n > apart.ac) & (bc > apart.bc)));
        let mut k = 0u64;
        for i in 0..NN {
            let t = tn[i] * d;
            k |= (if n > t { gn[i] } else { 0 }) | (if n == t { zn[i] } else { 0 });
        }
        for i in 0..NX {
            let t = tx[i] * d;
            k |= (if x > t { gx[i] } else { 0 }) | (if x == t { zx[i] } else { 0 });
        }
        for i in 0..NY {
            let t = ty[i] * d;
            k |= (if y > t { gy[i] } else { 0 }) | (if y == t { zy[i] } else { 0 });
        }
        for i in 0..NG {
            let [fa, fb, fc, fd] = coef[i];
            let v = fa * n + fb * x + fc * y + fd * d;
            k |= (if v > 0.0 { gg[i] } else { 0 }) | (if v == 0.0 { zg[i] } else { 0 });
        }
        key[u] = k;
    }
    valid
}

/// [`fused_keys`] for `shape` if it has a loop of its own (`None` otherwise): the shapes
/// of the built-in ternary calculi, all orderings and the canonical one
/// (`every_builtin_has_a_fused_loop` keeps the list complete).
#[inline(always)]
fn fused_dispatch<const ORDERS: usize>(
    shape: [usize; 4],
    grouped: &Grouped,
    coords: [&[f64]; 6],
    apart: Apart,
    key: &mut [u64],
) -> Option<bool> {
    macro_rules! shapes {
        ($([$a:literal, $b:literal, $c:literal, $d:literal]),*) => {
            match shape {
                $([$a, $b, $c, $d] => Some(fused_keys::<ORDERS, $a, $b, $c, $d>(grouped, coords, apart, key)),)*
                _ => None,
            }
        };
    }
    // the built-in ternary calculi's shapes (all orderings; canonical)
    shapes!(
        [1, 1, 3, 2], // edc, edc-lune, triple-cross
        [1, 1, 3, 1], // edc, edc-lune (canonical)
        [0, 1, 3, 0], // triple-cross (canonical)
        [0, 1, 2, 1], // double-cross, single-cross
        [0, 1, 2, 0], // double-cross (canonical)
        [1, 1, 1, 1], // quadrant
        [0, 1, 1, 0], // quadrant, single-cross (canonical)
        [0, 1, 0, 0], // left-right
        [1, 0, 1, 1], // relative-distance
        [1, 0, 0, 0], // relative-distance (canonical)
        [0, 1, 1, 3]  // tpcc (canonical; all orderings exceed the key's quantities)
    )
}

/// Each sample's key from its scaled frame `(x·d, y·d, n·d, d)` ([`ScaledFrame`]): bit `b`
/// says quantity `b` is positive, bit `32 + b` that it is exactly zero.
#[inline(always)]
fn fill_keys(forms: &SixForms, key: &mut [u64], [x, y, n, d]: [&[f64]; 4]) {
    let vars = [n, x, y];
    for (b, quantity) in forms.quantities.iter().enumerate() {
        // masks selected by the comparisons (compare, and, or), not bits shifted into
        // place per lane
        let (gt, zero) = (1u64 << b, 1u64 << (32 + b));
        match *quantity {
            Quantity::Single { var, t } => {
                key.iter_mut()
                    .zip(vars[var])
                    .zip(d)
                    .for_each(|((kv, &u), &d)| {
                        let t = t * d;
                        *kv |= (if u > t { gt } else { 0 }) | (if u == t { zero } else { 0 });
                    });
            }
            Quantity::General {
                coef: [fa, fb, fc, fd],
            } => {
                key.iter_mut().zip(x).zip(y).zip(n).zip(d).for_each(
                    |((((kv, &x), &y), &n), &d)| {
                        let v = fa * n + fb * x + fc * y + fd * d;
                        *kv |= (if v > 0.0 { gt } else { 0 }) | (if v == 0.0 { zero } else { 0 });
                    },
                );
            }
        }
    }
}

/// The histogram of keys without a zero quantity, folded into each ordering's state counts
/// and left zeroed for the next triplet (one pass instead of a fold and a fill).
#[inline(always)]
fn fold_histogram<const ORDERS: usize>(
    forms: &SixForms,
    hist: &mut [[u32; 4]],
    q: usize,
    out: &mut [u32],
) {
    for (kv, lanes) in hist.iter_mut().enumerate() {
        let n: u32 = lanes.iter().sum();
        *lanes = [0; 4];
        if n > 0 {
            for (o, c) in out.chunks_exact_mut(q).enumerate().take(ORDERS) {
                c[usize::from(forms.states[kv][o])] += n;
            }
        }
    }
}

/// A triplet's key counts. A chunk whose samples all share one key with no zero quantity
/// (as the chunks of a triplet do that sits far from its boundaries for its landmarks'
/// noise, yet not far enough for the discs to settle it) is one addition to a *run*: a
/// vectorised pass over the keys instead of a read-modify-write per sample (that loop was
/// about 40 % of the canonical kernel's time, by `perf annotate`). A triplet whose chunks are all one run never
/// touches the histogram, so it is neither folded nor cleared. Checking blocks of 64 or 128
/// samples instead of whole chunks was slower on `map_scaling.py`'s scene: a mixed chunk
/// pays for every check.
struct KeyTally<'h> {
    /// Zero between triplets ([`fold_histogram`] clears what it reads).
    hist: &'h mut [[u32; 4]; HIST_BINS],
    /// The current run's key and count.
    run: Option<(usize, u32)>,
    /// Whether anything went into the histogram.
    used: bool,
}

impl KeyTally<'_> {
    /// Counts one chunk's keys: a pure chunk into the run, else each key without a zero
    /// quantity into the histogram (four lanes), one with a zero quantity straight into
    /// `out` through the constraints' zero sides.
    #[inline(always)]
    fn chunk<const ORDERS: usize>(
        &mut self,
        forms: &SixForms,
        table: (&[u16], usize),
        key: &[u64],
        signs: &mut [i8],
        out: &mut [u32],
    ) {
        let Some(&first) = key.first() else {
            return;
        };
        let differ = key.iter().fold(0u64, |acc, &kv| acc | (kv ^ first));
        if differ == 0 && first >> 32 == 0 {
            // a chunk is at most CHUNK samples long
            let (kv, n) = (first as usize & (HIST_BINS - 1), key.len() as u32);
            match &mut self.run {
                Some((k, c)) if *k == kv => *c += n,
                run => {
                    if let Some((k, c)) = run.replace((kv, n)) {
                        self.hist[k][0] += c;
                        self.used = true;
                    }
                }
            }
            return;
        }
        self.used = true;
        count_keys::<ORDERS>(forms, table, key, self.hist, signs, out);
    }

    /// Adds the triplet's counts to `out` (each ordering's states) and leaves the histogram
    /// zeroed.
    #[inline(always)]
    fn finish<const ORDERS: usize>(self, forms: &SixForms, q: usize, out: &mut [u32]) {
        let g = forms.quantities.len();
        if let Some((k, c)) = self.run {
            if !self.used {
                for (o, counts) in out.chunks_exact_mut(q).enumerate().take(ORDERS) {
                    counts[usize::from(forms.states[k][o])] += c;
                }
                return;
            }
            self.hist[k][0] += c;
        }
        if self.used {
            fold_histogram::<ORDERS>(forms, &mut self.hist[..1 << g], q, out);
        }
    }
}

/// Counts one chunk's keys into the histogram (four lanes), a key with a zero quantity
/// straight into `out` through the constraints' zero sides.
#[inline(always)]
fn count_keys<const ORDERS: usize>(
    forms: &SixForms,
    (table, q): (&[u16], usize),
    key: &[u64],
    hist: &mut [[u32; 4]; HIST_BINS],
    signs: &mut [i8],
    out: &mut [u32],
) {
    let mut quads = key.chunks_exact(4);
    let mut slow = |kv: u64, out: &mut [u32]| {
        // a quantity exactly zero: the constraints' zero sides decide
        for (b, sg) in signs.iter_mut().enumerate() {
            *sg = if kv >> (32 + b) & 1 == 1 {
                0
            } else if kv >> b & 1 == 1 {
                1
            } else {
                -1
            };
        }
        for (o, c) in out.chunks_exact_mut(q).enumerate().take(ORDERS) {
            c[usize::from(table[SixForms::bin(&forms.members[o], signs)])] += 1;
        }
    };
    for quad in &mut quads {
        for (lane, &kv) in quad.iter().enumerate() {
            if kv >> 32 == 0 {
                hist[kv as usize & (HIST_BINS - 1)][lane] += 1;
            } else {
                slow(kv, out);
            }
        }
    }
    for &kv in quads.remainder() {
        if kv >> 32 == 0 {
            hist[kv as usize & (HIST_BINS - 1)][0] += 1;
        } else {
            slow(kv, out);
        }
    }
}

/// [`triplet_counts`] for the `ORDERS` orderings of a line-and-circle calculus via
/// [`SixForms`] (built for as many).
#[inline(always)]
fn six_counts<const ORDERS: usize>(
    calculus: &Calculus,
    forms: &SixForms,
    samples: &ScanSamples,
    ([i, j, k], apart): ([usize; 3], Apart),
    scratch: &mut Scratch,
    out: &mut [u32],
) -> Result<()> {
    let qsr_core::Partition::Constraints(partition) = calculus.partition() else {
        return Err(PqrmError::InvalidConfig(
            "six_counts needs a constraint calculus".into(),
        ));
    };
    let table = partition.table();
    let q = calculus.n_states();
    let g = forms.quantities.len();
    // four interleaved sub-histograms: consecutive samples mostly share a key, and a single
    // counter would serialise on its own increments
    scratch.hist.resize(HIST_BINS, [0u32; 4]);
    let Ok(hist): std::result::Result<&mut [[u32; 4]; HIST_BINS], _> =
        scratch.hist.as_mut_slice().try_into()
    else {
        return Err(PqrmError::InvalidConfig(
            "six_counts: histogram size".into(),
        ));
    };
    if scratch.hist_dirty {
        // a triplet left it mid-way (an error): clear it once
        hist.fill([0u32; 4]);
    }
    scratch.hist_dirty = true;
    let mut tally = KeyTally {
        hist,
        run: None,
        used: false,
    };
    out.fill(0);
    let ((ax, ay), (bx, by), (cx, cy)) =
        (samples.columns(i), samples.columns(j), samples.columns(k));
    let s = samples.samples();
    if scratch.frame.is_empty() {
        scratch.frame.push([[0.0; CHUNK]; 4]);
        scratch.keys.push([0; CHUNK]);
    }
    let ([[xs, ys, ns, ds], ..], [keys, ..]) =
        (scratch.frame.as_mut_slice(), scratch.keys.as_mut_slice())
    else {
        return Err(PqrmError::InvalidConfig("six_counts: scratch".into()));
    };
    // key lanes: bit g = quantity g > 0, bit 32 + g = quantity g == 0
    let mut signs = vec![0i8; g];
    let (shape, fused) = (forms.grouped.shape(), forms.fused);
    for start in (0..s).step_by(CHUNK) {
        let len = CHUNK.min(s - start);
        let range = start..start + len;
        let coords = [
            &ax[range.clone()],
            &ay[range.clone()],
            &bx[range.clone()],
            &by[range.clone()],
            &cx[range.clone()],
            &cy[range],
        ];
        if fused
            && let Some(valid) =
                fused_dispatch::<ORDERS>(shape, &forms.grouped, coords, apart, &mut keys[..len])
        {
            if !valid {
                check_apart::<ORDERS>(samples, [i, j, k], start..start + len)?;
            }
            tally.chunk::<ORDERS>(forms, (table, q), &keys[..len], &mut signs, out);
            continue;
        }
        let mut valid = true;
        for t in 0..len {
            let u = start + t;
            let ScaledFrame { x, y, n, d, bc } =
                ScaledFrame::of([ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]]);
            // the canonical ordering alone needs only A ≠ B; the others use C as a reference
            valid &= (d > apart.ab) & (ORDERS == 1 || ((n > apart.ac) & (bc > apart.bc)));
            xs[t] = x;
            ys[t] = y;
            ns[t] = n;
            ds[t] = d;
        }
        if !valid {
            check_apart::<ORDERS>(samples, [i, j, k], start..start + len)?;
        }
        let frame = [&xs[..len], &ys[..len], &ns[..len], &ds[..len]];
        let key = &mut keys[..len];
        key.fill(0);
        fill_keys(forms, key, frame);
        tally.chunk::<ORDERS>(forms, (table, q), key, &mut signs, out);
    }
    tally.finish::<ORDERS>(forms, q, out);
    scratch.hist_dirty = false;
    Ok(())
}

/// What the discs a triplet's landmarks' samples span ([`crate::spread`]) settle.
enum Settled {
    /// Every quantity's sign and the coincidence checks: every sample has this key.
    All(usize),
    /// The coincidence checks and some quantities' signs.
    Partly(Partial),
    /// Not the coincidence checks.
    Not,
}

/// Most unsettled quantities [`partial_counts`] takes (2⁴ sign combinations, each counted
/// by comparison); a triplet with more takes the full kernel. Four rather than three: all
/// orderings CPU ×0.97 on map_scaling.py's recording (median of 6 interleaved pairs).
const MAX_FREE: usize = 4;

/// A triplet whose discs settle the coincidence checks and some quantities: the key bits of
/// the settled ones, and the others as forms `c₀·n + c₁·x + c₂·y + c₃·d` over the scaled
/// frame ([`ScaledFrame`]) with their key bits.
struct Partial {
    key: usize,
    free: Vec<(u32, [f64; 4])>,
}

/// The quantities' signs the discs settle (see [`Settled`]).
fn settle(forms: &SixForms, spread: [&Option<Spread>; 3], apart: Apart) -> Settled {
    let [Some(a), Some(b), Some(c)] = spread else {
        return Settled::Not;
    };
    let Some(bounds) =
        FrameBounds::new([a, b, c], [apart.ab, apart.ac, apart.bc], forms.orders > 1)
    else {
        return Settled::Not;
    };
    let mut key = 0usize;
    let mut free = Vec::new();
    for (bit, quantity) in forms.quantities.iter().enumerate() {
        let (positive, coef) = match *quantity {
            Quantity::Single { var, t } => {
                // u − t·d: the same sign as the fused loop's comparison of u with t·d
                let mut coef = [0.0; 4];
                coef[var] = 1.0;
                coef[3] = -t;
                (bounds.single(var, t), coef)
            }
            Quantity::General { coef } => (bounds.general(coef), coef),
        };
        match positive {
            Some(p) => key |= usize::from(p) << bit,
            None => free.push((bit as u32, coef)),
        }
    }
    if free.is_empty() {
        Settled::All(key)
    } else {
        Settled::Partly(Partial { key, free })
    }
}

/// The counts of a triplet whose discs settle all but a few quantities (most of a map's
/// triplets: of map_scaling.py's 10⁶ sets, 67 % leave one to three of the EDC's seven open
/// where 19 % settle all; 4 % more leave four). Only the open ones are evaluated per
/// sample, and each of their 2¹–2⁴ sign combinations is counted by comparison in vector
/// registers — no histogram, no coincidence checks (the discs settle them). A sample is
/// classified as the full kernel classifies it: a settled quantity keeps its sign by a
/// margin over the whole disc, an open one is the same floating-point form; a sample with
/// an open quantity exactly zero takes the constraints' zero sides, one at a time.
#[inline(always)]
fn partial_counts<const ORDERS: usize, const FREE: usize>(
    (calculus, forms, samples, [i, j, k]): (&Calculus, &SixForms, &ScanSamples, [usize; 3]),
    partial: &Partial,
    out: &mut [u32],
) -> Result<()> {
    let qsr_core::Partition::Constraints(partition) = calculus.partition() else {
        return Err(PqrmError::InvalidConfig(
            "partial_counts needs a constraint calculus".into(),
        ));
    };
    let (table, q) = (partition.table(), calculus.n_states());
    let ((ax, ay), (bx, by), (cx, cy)) =
        (samples.columns(i), samples.columns(j), samples.columns(k));
    let free = &partial.free;
    let coef: [[f64; 4]; FREE] = std::array::from_fn(|f| free.get(f).map_or([0.0; 4], |q| q.1));
    let mut combos = [0u32; 1 << MAX_FREE];
    let mut signs = vec![0i8; forms.quantities.len()];
    out.fill(0);
    let s = samples.samples();
    for start in (0..s).step_by(CHUNK) {
        let len = CHUNK.min(s - start);
        let coords = |u: usize| [[ax[u], ay[u]], [bx[u], by[u]], [cx[u], cy[u]]];
        // each sample's combination of open signs (bit f: open quantity f > 0), or
        // `ZERO` where one is exactly zero; counted by comparison, so the loop vectorises
        const ZERO: u32 = 1 << MAX_FREE;
        let combo_of = |u: usize| {
            let [a, b, c] = coords(u);
            let sf = ScaledFrame::of(a, b, c);
            let (mut combo, mut zero) = (0u32, false);
            for (f, [c0, c1, c2, c3]) in coef.iter().enumerate() {
                let v = c0 * sf.n + c1 * sf.x + c2 * sf.y + c3 * sf.d;
                combo |= u32::from(v > 0.0) << f;
                zero |= v == 0.0;
            }
            if zero { ZERO } else { combo }
        };
        let mut chunk = [0u32; 1 << MAX_FREE];
        let mut zeros = 0u32;
        for u in start..start + len {
            let combo = combo_of(u);
            for (k, n) in chunk.iter_mut().enumerate().take(1 << FREE) {
                *n += u32::from(combo == k as u32);
            }
            zeros += u32::from(combo == ZERO);
        }
        for (total, n) in combos.iter_mut().zip(chunk) {
            *total += n;
        }
        if zeros == 0 {
            continue;
        }
        // samples with an open quantity exactly zero: the constraints' zero sides decide
        for u in start..start + len {
            let [a, b, c] = coords(u);
            let sf = ScaledFrame::of(a, b, c);
            let values = coef.map(|[c0, c1, c2, c3]| c0 * sf.n + c1 * sf.x + c2 * sf.y + c3 * sf.d);
            if values.iter().all(|v| *v != 0.0) {
                continue;
            }
            for (bit, sg) in signs.iter_mut().enumerate() {
                *sg = if partial.key >> bit & 1 == 1 { 1 } else { -1 };
            }
            for ((b, _), v) in free.iter().zip(values) {
                signs[*b as usize] = if v > 0.0 {
                    1
                } else if v == 0.0 {
                    0
                } else {
                    -1
                };
            }
            for (o, c) in out.chunks_exact_mut(q).enumerate().take(ORDERS) {
                c[usize::from(table[SixForms::bin(&forms.members[o], &signs)])] += 1;
            }
        }
    }
    for (combo, &count) in combos.iter().enumerate().take(1 << FREE) {
        if count == 0 {
            continue;
        }
        let key = free
            .iter()
            .enumerate()
            .fold(partial.key, |key, (f, (bit, _))| {
                key | (combo >> f & 1) << bit
            });
        for (o, c) in out.chunks_exact_mut(q).enumerate().take(ORDERS) {
            c[usize::from(forms.states[key][o])] += count;
        }
    }
    Ok(())
}

/// The counts of a triplet all of whose `s` samples have `key`: `s` in the key's state of
/// each ordering (what [`fold_histogram`] makes of a histogram holding that key alone).
fn decided_counts(forms: &SixForms, q: usize, key: usize, s: usize, out: &mut [u32]) {
    out.fill(0);
    let s = u32::try_from(s).unwrap_or(u32::MAX);
    for (o, c) in out
        .chunks_exact_mut(q.max(1))
        .enumerate()
        .take(forms.orders)
    {
        c[usize::from(forms.states[key][o])] = s;
    }
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
/// With `floor = 0` a state with no count gets `-inf`. A negative or non-finite floor is
/// treated as 0 (the mapper's configuration refuses one; this keeps the function total and
/// free of NaN), and all-zero counts give uniform.
#[must_use]
pub fn log_likelihood(counts: &[u32], floor: f64) -> Vec<f64> {
    let floor = if floor.is_finite() && floor > 0.0 {
        floor
    } else {
        0.0
    };
    let total: f64 =
        counts.iter().map(|&c| f64::from(c)).sum::<f64>() + floor * counts.len() as f64;
    if total <= 0.0 {
        return vec![-(counts.len().max(1) as f64).ln(); counts.len()];
    }
    counts
        .iter()
        .map(|&c| ((f64::from(c) + floor) / total).ln())
        .collect()
}

#[cfg(test)]
mod exact_reference;

#[cfg(test)]
mod tests {
    use super::LandmarkSet;

    /// Every built-in ternary calculus has a fused key loop for its shape, all orderings and
    /// the canonical one — a new calculus whose shape is missing fails here, not silently.
    #[test]
    fn every_builtin_has_a_fused_loop() {
        let mut missing = Vec::new();
        for name in qsr_core::BUILTIN_NAMES {
            let cal = qsr_core::Calculus::builtin(name).expect("built in");
            if cal.frame() != qsr_core::FrameKind::Ternary {
                continue;
            }
            for orders in [6, 1] {
                let Some(forms) = super::SixForms::new(&cal, orders) else {
                    continue;
                };
                let shape = forms.grouped.shape();
                let apart = super::Apart::new([0.0; 3]);
                let got =
                    super::fused_dispatch::<1>(shape, &forms.grouped, [&[]; 6], apart, &mut []);
                if got.is_none() {
                    missing.push(format!("{name}, {orders} orderings: {shape:?}"));
                }
            }
        }
        assert!(
            missing.is_empty(),
            "shapes with no fused loop: {missing:#?}"
        );
    }

    /// Pure chunks are counted as runs (a run of one key, then another, then mixed chunks
    /// around and between them) exactly as counting every key into the histogram counts
    /// them, and the histogram is left zeroed for the next triplet either way.
    #[test]
    fn runs_of_pure_chunks_count_as_their_keys_do() {
        use super::{CHUNK, HIST_BINS, KeyTally, SixForms, count_keys, fold_histogram};
        let cal = qsr_core::Calculus::builtin("edc").expect("built in");
        let qsr_core::Partition::Constraints(partition) = cal.partition() else {
            panic!("edc is a constraint calculus");
        };
        let q = cal.n_states();
        for orders in [6, 1] {
            let forms = SixForms::new(&cal, orders).expect("edc has forms");
            let g = forms.quantities.len();
            let (a, b) = (3u64, (1u64 << g) - 2);
            let pure = |k: u64, n: usize| vec![k; n];
            let mixed: Vec<u64> = (0..CHUNK as u64)
                .map(|t| match t % 5 {
                    0 => a,
                    1 => b,
                    2 => 1u64 << 32 | 1, // quantity 0 exactly zero
                    _ => t % (1 << g),
                })
                .collect();
            let triplets: Vec<Vec<Vec<u64>>> = vec![
                vec![pure(a, CHUNK), pure(a, CHUNK), pure(a, 100)],
                vec![pure(a, CHUNK), pure(b, CHUNK), pure(a, 7)],
                vec![pure(a, CHUNK), mixed.clone(), pure(a, CHUNK)],
                vec![mixed.clone(), pure(b, CHUNK)],
                vec![pure(b, 1)],
                vec![pure(1u64 << 33, CHUNK)], // pure, but on a boundary
            ];
            let mut hist = Box::new([[0u32; 4]; HIST_BINS]);
            for chunks in &triplets {
                let mut signs = vec![0i8; g];
                let mut got = vec![0u32; orders * q];
                let mut tally = KeyTally {
                    hist: &mut hist,
                    run: None,
                    used: false,
                };
                for c in chunks {
                    tally.chunk::<6>(&forms, (partition.table(), q), c, &mut signs, &mut got);
                }
                tally.finish::<6>(&forms, q, &mut got);
                assert!(hist.iter().all(|l| *l == [0; 4]), "left zeroed");
                let mut want = vec![0u32; orders * q];
                let mut reference = Box::new([[0u32; 4]; HIST_BINS]);
                for c in chunks {
                    count_keys::<6>(
                        &forms,
                        (partition.table(), q),
                        c,
                        &mut reference,
                        &mut signs,
                        &mut want,
                    );
                }
                fold_histogram::<6>(&forms, &mut reference[..1 << g], q, &mut want);
                assert_eq!(
                    got,
                    want,
                    "{orders} orderings, chunks of {:?}",
                    chunks.iter().map(Vec::len).collect::<Vec<_>>()
                );
                let total: u32 = want.iter().sum();
                let samples: usize = chunks.iter().map(Vec::len).sum();
                assert_eq!(
                    total as usize,
                    samples * orders,
                    "every sample counted once per ordering"
                );
            }
        }
    }

    /// The fused loops give the pass-per-quantity loop's counts, bit for bit, for every
    /// built-in, both orderings, on samples that visit every state and on a lattice that puts
    /// samples exactly on boundaries.
    #[test]
    fn fused_and_per_quantity_loops_count_alike() {
        use crate::{LandmarkId, Observation, Scan, ScanSamples};
        let noisy: Vec<Observation> = (0..7u32)
            .map(|i| {
                let p = [f64::from(i % 3) * 0.7, f64::from(i / 3) * 0.9 - 0.4];
                Observation::isotropic(LandmarkId(i), p, 0.6).expect("valid")
            })
            .collect();
        let lattice: Vec<Observation> = [
            [0.0, 0.0],
            [2.0, 0.0],
            [1.0, 0.0],
            [2.0, 2.0],
            [0.0, 2.0],
            [1.0, 1.0],
            [1.0, -1.0],
        ]
        .iter()
        .enumerate()
        .map(|(i, p)| Observation::isotropic(LandmarkId(i as u32), *p, 0.0).expect("valid"))
        .collect();
        for (obs, s) in [(noisy, 700), (lattice, 9)] {
            let scan = Scan::new(0.0, 0, obs).expect("valid");
            let samples = ScanSamples::draw(&scan, s, 3, 0);
            let mut tried = 0;
            for name in qsr_core::BUILTIN_NAMES {
                let cal = qsr_core::Calculus::builtin(name).expect("built in");
                if cal.frame() != qsr_core::FrameKind::Ternary {
                    continue;
                }
                for orderings in [super::Orderings::All, super::Orderings::Canonical] {
                    let fast = super::Kernel {
                        decided: false,
                        ..super::Kernel::FAST
                    };
                    let plain = super::Kernel {
                        fused: false,
                        decided: false,
                    };
                    let fused = super::counts_with(&cal, &samples, orderings, fast).expect("apart");
                    let plain =
                        super::counts_with(&cal, &samples, orderings, plain).expect("apart");
                    assert_eq!(fused.counts, plain.counts, "{name} {orderings:?}");
                    tried += 1;
                }
            }
            assert_eq!(tried, 18, "the ternary built-ins, both orderings");
        }
    }

    /// A triplet settled by its samples' discs gets the counts classifying every sample
    /// gives, bit for bit: every built-in, both orderings, on scenes whose triplets range
    /// from far from every boundary to on one — noisy landmarks over a wide area, a tight
    /// cluster, zero-noise landmarks on a lattice (samples exactly on boundaries), and
    /// landmarks that nearly coincide — and the settled share is what makes it worth having.
    #[test]
    fn settled_triplets_count_as_their_samples_do() {
        use crate::{LandmarkId, Observation, Scan, ScanSamples};
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut scenes: Vec<(Vec<Observation>, usize)> = Vec::new();
        for (spread, sigma) in [(30.0, 0.5), (3.0, 0.3), (1.0, 1e-6)] {
            scenes.push((
                (0..14u32)
                    .map(|i| {
                        let p = [
                            rng.random_range(-spread..spread),
                            rng.random_range(-spread..spread),
                        ];
                        Observation::isotropic(LandmarkId(i), p, sigma).expect("valid")
                    })
                    .collect(),
                400,
            ));
        }
        let lattice = (0..9u32)
            .map(|i| {
                let p = [f64::from(i % 3), f64::from(i / 3)];
                Observation::isotropic(LandmarkId(i), p, 0.0).expect("valid")
            })
            .collect();
        scenes.push((lattice, 5));
        let close = (0..6u32)
            .map(|i| {
                let p = [1e-9 * f64::from(i % 2), 10.0 * f64::from(i / 2)];
                Observation::isotropic(LandmarkId(i), p, 1e-10).expect("valid")
            })
            .collect();
        scenes.push((close, 50));
        let (mut settled, mut triplets) = (0usize, 0usize);
        for (obs, s) in scenes {
            let scan = Scan::new(0.0, 0, obs).expect("valid");
            let samples = ScanSamples::draw(&scan, s, 3, 0);
            for name in qsr_core::BUILTIN_NAMES {
                let cal = qsr_core::Calculus::builtin(name).expect("built in");
                if cal.frame() != qsr_core::FrameKind::Ternary {
                    continue;
                }
                for orderings in [super::Orderings::All, super::Orderings::Canonical] {
                    let every = super::Kernel {
                        decided: false,
                        ..super::Kernel::FAST
                    };
                    let fast = super::counts_with(&cal, &samples, orderings, super::Kernel::FAST);
                    let slow = super::counts_with(&cal, &samples, orderings, every);
                    match (fast, slow) {
                        (Ok(fast), Ok(slow)) => {
                            assert_eq!(fast.counts, slow.counts, "{name} {orderings:?}");
                            // how many were settled: those with one state per ordering
                            // are the candidates
                            let per = if orderings == super::Orderings::All {
                                6
                            } else {
                                1
                            };
                            triplets += fast.len() / per;
                        }
                        (Err(a), Err(b)) => assert_eq!(a.to_string(), b.to_string()),
                        (a, b) => panic!("{name} {orderings:?}: {a:?} against {b:?}"),
                    }
                }
            }
        }
        // the share settled, measured through the kernel's own decision
        let scan = Scan::new(
            0.0,
            0,
            (0..30u32)
                .map(|i| {
                    let p = [rng.random_range(-30.0..30.0), rng.random_range(-30.0..30.0)];
                    Observation::isotropic(LandmarkId(i), p, 0.5).expect("valid")
                })
                .collect(),
        )
        .expect("valid");
        let samples = ScanSamples::draw(&scan, 200, 3, 0);
        let cal = qsr_core::Calculus::builtin("edc").expect("built in");
        let forms = super::SixForms::new(&cal, 6).expect("edc has forms");
        let spreads = super::spreads(&samples);
        let m = spreads.len();
        for i in 0..m {
            for j in i + 1..m {
                for k in j + 1..m {
                    let spread = [&spreads[i], &spreads[j], &spreads[k]];
                    let apart = super::Apart::new([0.0; 3]);
                    let all =
                        matches!(super::settle(&forms, spread, apart), super::Settled::All(_));
                    settled += usize::from(all);
                }
            }
        }
        assert!(triplets > 0);
        // 4,060 triplets of 30 landmarks with σ = 0.5 m over 60 × 60 m, s = 200: 857 are
        // settled (at s = 1000 over 101 landmarks, 53 % of triplets have one state throughout)
        assert!(settled * 6 > 4060, "a sixth at least is settled: {settled}");
    }

    /// Regression: landmarks at 1e300 were reported as coinciding (their squared distances
    /// overflow and the coincidence check reads inf ≤ inf); the error names the overflow.
    /// Landmarks that do coincide still say so.
    #[test]
    fn coordinates_whose_squares_overflow_are_named_not_called_coincident() {
        use super::{Orderings, PqrmError, ScanSamples, step_counts};
        use crate::observation::LandmarkId;
        use qsr_core::Calculus;
        let ids = vec![LandmarkId(1), LandmarkId(2), LandmarkId(3)];
        let edc = Calculus::builtin("edc").unwrap();
        let huge = ScanSamples::from_columns(
            ids.clone(),
            vec![vec![1e300, -1e300], vec![-1e300, 1e300], vec![1e299, 5e299]],
            vec![vec![1e300; 2], vec![-1e300; 2], vec![0.0; 2]],
        )
        .unwrap();
        for orderings in [Orderings::All, Orderings::Canonical] {
            let e = step_counts(&edc, &huge, orderings).unwrap_err();
            assert!(
                matches!(&e, PqrmError::NonFinite(m) if m.contains("overflow")),
                "{e}"
            );
        }
        let same = ScanSamples::from_columns(
            ids,
            vec![vec![1.0; 4], vec![1.0; 4], vec![2.0; 4]],
            vec![vec![0.0; 4]; 3],
        )
        .unwrap();
        let e = step_counts(&edc, &same, Orderings::All).unwrap_err();
        assert!(matches!(e, PqrmError::CoincidentLandmarks { .. }), "{e}");
    }

    #[test]
    fn a_set_parses_from_three_distinct_ids_and_nothing_else() {
        assert_eq!("4, 7,9".parse(), Ok(LandmarkSet::new(4, 7, 9)));
        assert!(
            "4,7,4"
                .parse::<LandmarkSet>()
                .is_err_and(|e| e.contains("repeats"))
        );
        assert!(
            "4,7"
                .parse::<LandmarkSet>()
                .is_err_and(|e| e.contains("three"))
        );
        assert!(
            "4,x,9"
                .parse::<LandmarkSet>()
                .is_err_and(|e| e.contains("`x`"))
        );
        assert!("4,7,9,1".parse::<LandmarkSet>().is_err());
    }
}
