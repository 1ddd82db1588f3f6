//! [`Calculus`]: a validated, compiled calculus with classification and lazily computed
//! derived structure (neighbours, permutations, composition, merges).

use std::sync::{Arc, OnceLock};

use nalgebra::Point2;

use crate::compose::{ComposeOptions, ComposeTable};
use crate::coverage::{Features, StatePool, state_pools};
use crate::error::{QsrError, Result, spec_error};
use crate::frame::{AnyFrame, ExtendedFrame, FrameKind, OrientedFrame, Segment, TernaryFrame};
use crate::neighbours::NeighbourGraph;
use crate::partition::{BLOCK, ConstraintPartition, Partition, RasterPartition, complete_table};
use crate::permute::{Permutation, PermutationTable};
use crate::sampled::{DERIVED_SEED, Sampled};
use crate::spec::{CalculusSpec, OutsideRule, RasterSpec, format_vector, pattern_table};
pub use crate::state::StateId;
use crate::state::StateIndex;

/// Probe points used to validate a constraint spec (sign vectors that occur in the plane).
const VALIDATION_PROBES: usize = 200_000;
/// Probe points behind permutations, merges and the compose pools.
pub(crate) const DERIVED_PROBES: usize = 400_000;
/// Points kept per state for composition.
pub(crate) const POOL_CAPACITY: usize = 8192;

#[derive(Debug, Default)]
struct DerivedCache {
    probes: OnceLock<Vec<Point2<f64>>>,
    pools: OnceLock<Vec<StatePool>>,
    neighbours: OnceLock<NeighbourGraph>,
    compose: OnceLock<ComposeTable>,
    permutations: [OnceLock<PermutationTable>; 5],
}

/// A qualitative calculus: a frame kind, a partition of the normalised plane into labelled
/// states, and everything derived from it.
///
/// Built-in, user (spec file) and learned (raster) calculi are all this one type.
///
/// ```
/// use qsr_core::Calculus;
/// use nalgebra::Point2;
///
/// let edc = Calculus::builtin("edc")?;
/// let s = edc.classify_triplet(Point2::new(0.0, 0.0), Point2::new(0.0, 1.0), Point2::new(-0.2, 0.3))?;
/// assert_eq!(edc.label(s), "13"); // left of A→B, inside both circles, below the midpoint
/// assert_eq!(edc.neighbours().diameter(), Some(4));
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Calculus {
    spec: CalculusSpec,
    labels: Vec<String>,
    partition: Partition,
    features: Arc<Features>,
    derived: Arc<DerivedCache>,
}

impl Calculus {
    /// Compiles and validates a spec.
    ///
    /// Constraint specs: every sign vector met by a dense probe of the plane (see
    /// [`crate::coverage`]) must be claimed by a state, and every state must be met.
    /// Raster specs: every state must occur in the raster or as the outside state.
    ///
    /// # Errors
    /// [`QsrError::Spec`] naming the problem (duplicate label, bad pattern, overlapping
    /// patterns, a gap with an example point, an unreachable state, a bad raster, ...).
    pub fn from_spec(spec: CalculusSpec) -> Result<Self> {
        spec.check_static()?;
        let labels: Vec<String> = spec.states.iter().map(|s| s.label.clone()).collect();
        let partition = if let Some(r) = &spec.raster {
            Partition::Raster(compile_raster(&spec, r)?)
        } else {
            compile_constraints(&spec)?
        };
        let features = Arc::new(Features::of(&partition));
        Ok(Self {
            spec,
            labels,
            partition,
            features,
            derived: Arc::default(),
        })
    }

    /// Parses and validates a TOML spec.
    ///
    /// # Errors
    /// As [`CalculusSpec::from_toml_str`] and [`Calculus::from_spec`].
    pub fn from_toml_str(text: &str) -> Result<Self> {
        Self::from_spec(CalculusSpec::from_toml_str(text)?)
    }

    /// Parses and validates a JSON spec.
    ///
    /// # Errors
    /// As [`CalculusSpec::from_json_str`] and [`Calculus::from_spec`].
    pub fn from_json_str(text: &str) -> Result<Self> {
        Self::from_spec(CalculusSpec::from_json_str(text)?)
    }

    /// Reads and validates a spec file (`.json` → JSON, otherwise TOML).
    ///
    /// # Errors
    /// As [`CalculusSpec::from_path`] and [`Calculus::from_spec`].
    pub fn from_path(path: &std::path::Path) -> Result<Self> {
        Self::from_spec(CalculusSpec::from_path(path)?)
    }

    /// A built-in calculus by name, or a spec file when `name_or_path` names an existing file.
    ///
    /// # Errors
    /// [`QsrError::UnknownCalculus`] when it is neither; spec errors for a bad file.
    pub fn resolve(name_or_path: &str) -> Result<Self> {
        match Self::builtin(name_or_path) {
            Ok(c) => Ok(c),
            Err(e @ QsrError::UnknownCalculus { .. }) => {
                let path = std::path::Path::new(name_or_path);
                if path.is_file() {
                    Self::from_path(path)
                } else {
                    Err(e)
                }
            }
            Err(e) => Err(e),
        }
    }

    /// Name.
    #[must_use]
    pub fn name(&self) -> &str {
        &self.spec.name
    }

    /// One-line description.
    #[must_use]
    pub fn description(&self) -> &str {
        &self.spec.description
    }

    /// The frame kind.
    #[must_use]
    pub fn frame(&self) -> FrameKind {
        self.spec.frame
    }

    /// The spec it was built from.
    #[must_use]
    pub fn spec(&self) -> &CalculusSpec {
        &self.spec
    }

    /// The compiled partition.
    #[must_use]
    pub fn partition(&self) -> &Partition {
        &self.partition
    }

    /// Number of states `Q`.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.labels.len()
    }

    /// Labels in state-id order.
    #[must_use]
    pub fn labels(&self) -> &[String] {
        &self.labels
    }

    /// Label of a state.
    ///
    /// # Panics
    /// Never for ids this calculus returned; an id from another calculus may be out of range.
    #[must_use]
    pub fn label(&self, s: StateId) -> &str {
        &self.labels[s.index()]
    }

    /// State id of a label.
    ///
    /// # Errors
    /// [`QsrError::UnknownState`].
    pub fn state(&self, label: &str) -> Result<StateId> {
        self.labels
            .iter()
            .position(|l| l == label)
            .map(|i| StateId(i as u16))
            .ok_or_else(|| QsrError::UnknownState {
                calculus: self.name().to_owned(),
                state: label.to_owned(),
            })
    }

    /// All state ids.
    pub fn states(&self) -> impl ExactSizeIterator<Item = StateId> + '_ {
        (0..self.labels.len() as u16).map(StateId)
    }

    /// `ln Q`: the entropy of the uniform distribution over states, the maximum any belief
    /// over this calculus can have (thesis §2.3.1; 3.00 nats for the EDC).
    #[must_use]
    pub fn max_entropy(&self) -> f64 {
        (self.n_states() as f64).ln()
    }

    /// State of a point given in normalised coordinates.
    #[inline(always)]
    #[must_use]
    pub fn classify_normalised(&self, p: &Point2<f64>) -> StateId {
        StateId(self.partition.classify(p))
    }

    fn expect_frame(&self, kind: FrameKind) -> Result<()> {
        if self.frame() == kind {
            Ok(())
        } else {
            Err(QsrError::Arity(format!(
                "calculus `{}` is {}, not {}",
                self.name(),
                self.frame().as_str(),
                kind.as_str()
            )))
        }
    }

    /// `{A, B : C}` for a ternary calculus.
    ///
    /// # Errors
    /// [`QsrError::Arity`] for a non-ternary calculus, frame errors for degenerate or
    /// non-finite input.
    pub fn classify_triplet(
        &self,
        a: Point2<f64>,
        b: Point2<f64>,
        c: Point2<f64>,
    ) -> Result<StateId> {
        self.expect_frame(FrameKind::Ternary)?;
        crate::error::check_finite("located point", &[c.x, c.y])?;
        let f = TernaryFrame::new(a, b)?;
        Ok(self.classify_normalised(&f.to_normalised(&c)))
    }

    /// `{A : C}` for a binary oriented calculus; `yaw` is A's heading (radians from world +x).
    ///
    /// # Errors
    /// [`QsrError::Arity`] for another kind of calculus, [`QsrError::NonFinite`].
    pub fn classify_oriented(
        &self,
        origin: Point2<f64>,
        yaw: f64,
        c: Point2<f64>,
    ) -> Result<StateId> {
        self.expect_frame(FrameKind::BinaryOriented)?;
        crate::error::check_finite("located point", &[c.x, c.y])?;
        let f = OrientedFrame::new(origin, yaw)?;
        Ok(self.classify_normalised(&f.to_normalised(&c)))
    }

    /// The state of `c` relative to two walls, for an extended calculus.
    ///
    /// # Errors
    /// [`QsrError::Arity`] for another kind of calculus, frame errors.
    pub fn classify_extended(
        &self,
        wall1: Segment,
        wall2: Segment,
        c: Point2<f64>,
    ) -> Result<StateId> {
        self.expect_frame(FrameKind::Extended)?;
        crate::error::check_finite("located point", &[c.x, c.y])?;
        let f = ExtendedFrame::new(wall1, wall2)?;
        Ok(self.classify_normalised(&f.to_normalised(&c)))
    }

    /// Classifies one row of numbers in the layout of [`FrameKind::input_len`], for any frame.
    ///
    /// # Errors
    /// [`QsrError::Arity`] for a wrong length, frame errors.
    pub fn classify_row(&self, row: &[f64]) -> Result<StateId> {
        let (frame, c): (AnyFrame, _) = self.frame().frame_from_row(row)?;
        Ok(self.classify_normalised(&frame.to_normalised(&c)))
    }

    /// Classifies many ternary triplets `[ax, ay, bx, by, cx, cy]` into `out` (same length).
    ///
    /// This is the hot loop of mapping: no allocation, no square root, one table lookup.
    ///
    /// # Errors
    /// [`QsrError::Arity`] for a non-ternary calculus or mismatched lengths; the first
    /// non-finite or degenerate row is reported with its index and nothing after it is
    /// guaranteed written.
    pub fn classify_triplets(&self, triplets: &[[f64; 6]], out: &mut [StateId]) -> Result<()> {
        self.classify_triplets_as(triplets, out)
    }

    /// [`Calculus::classify_triplets`] into any [`StateIndex`] type: the kernel writes each
    /// state in place, so a caller that wants integers (a NumPy int64 array) needs no buffer
    /// of ids and no second pass.
    ///
    /// ```
    /// use qsr_core::Calculus;
    /// let lr = Calculus::builtin("left-right")?;
    /// let mut out = [0i64; 2];
    /// lr.classify_triplets_as(&[[0.0, 0.0, 0.0, 1.0, -1.0, 0.5], [0.0, 0.0, 0.0, 1.0, 1.0, 0.5]], &mut out)?;
    /// assert_eq!(out[0], i64::from(lr.state("left")?.0));
    /// assert_eq!(out[1], i64::from(lr.state("right")?.0));
    /// # Ok::<(), qsr_core::QsrError>(())
    /// ```
    ///
    /// # Errors
    /// As [`Calculus::classify_triplets`].
    pub fn classify_triplets_as<O: StateIndex>(
        &self,
        triplets: &[[f64; 6]],
        out: &mut [O],
    ) -> Result<()> {
        self.expect_frame(FrameKind::Ternary)?;
        if triplets.len() != out.len() {
            return Err(QsrError::Arity(format!(
                "{} triplets but an output of length {}",
                triplets.len(),
                out.len()
            )));
        }
        classify_rows(&self.partition, triplets, out)
    }

    /// State indices of many points already in normalised coordinates (`xs`, `ys`, `out` of
    /// equal length; extra entries of the longer slices are ignored). No validation: the
    /// caller computed the points, as the mapper does when it derives all six orderings of a
    /// triplet from one normalised position.
    #[inline] // so callers compiled for wider vectors (pqrm's AVX2 path) inline the loops
    pub fn classify_normalised_into(&self, xs: &[f64], ys: &[f64], out: &mut [u16]) {
        match &self.partition {
            Partition::Constraints(p) => p.classify_block(xs, ys, out),
            Partition::Raster(r) => {
                for ((s, x), y) in out.iter_mut().zip(xs).zip(ys) {
                    *s = r.classify(*x, *y);
                }
            }
        }
    }

    /// Classifies `n` configurations given as columns (`a = (ax, ay)` etc., each of length
    /// `n = out.len()`): how a sampler hands over its samples, with no row assembly.
    ///
    /// # Errors
    /// As [`Calculus::classify_triplets`].
    pub fn classify_columns(
        &self,
        a: (&[f64], &[f64]),
        b: (&[f64], &[f64]),
        c: (&[f64], &[f64]),
        out: &mut [StateId],
    ) -> Result<()> {
        self.classify_columns_as(a, b, c, out)
    }

    /// [`Calculus::classify_columns`] into any [`StateIndex`] type, written in place (as
    /// [`Calculus::classify_triplets_as`]).
    ///
    /// # Errors
    /// As [`Calculus::classify_triplets`].
    pub fn classify_columns_as<O: StateIndex>(
        &self,
        a: (&[f64], &[f64]),
        b: (&[f64], &[f64]),
        c: (&[f64], &[f64]),
        out: &mut [O],
    ) -> Result<()> {
        self.expect_frame(FrameKind::Ternary)?;
        let n = out.len();
        let lens = [
            a.0.len(),
            a.1.len(),
            b.0.len(),
            b.1.len(),
            c.0.len(),
            c.1.len(),
        ];
        if lens.iter().any(|&l| l != n) {
            return Err(QsrError::Arity(format!(
                "column lengths {lens:?} differ from the output length {n}"
            )));
        }
        if let Partition::Constraints(p) = &self.partition {
            let cols = [a.0, a.1, b.0, b.1, c.0, c.1];
            return with_wide_vectors!(columns_fused::<O: StateIndex>(p: &ConstraintPartition, cols: [&[f64]; 6], out: &mut [O]) -> Result<()>);
        }
        let mut xs = [0.0f64; BLOCK];
        let mut ys = [0.0f64; BLOCK];
        let mut states = [0u16; BLOCK];
        for start in (0..n).step_by(BLOCK) {
            let end = (start + BLOCK).min(n);
            let m = end - start;
            let cols = (
                &a.0[start..end],
                &a.1[start..end],
                &b.0[start..end],
                &b.1[start..end],
                &c.0[start..end],
                &c.1[start..end],
            );
            let mut valid = true;
            for i in 0..m {
                let row = [
                    cols.0[i], cols.1[i], cols.2[i], cols.3[i], cols.4[i], cols.5[i],
                ];
                let (x, y, ok) = normalise_row(&row);
                (xs[i], ys[i]) = (x, y);
                valid &= ok;
            }
            if !valid {
                for i in 0..m {
                    let row = [
                        cols.0[i], cols.1[i], cols.2[i], cols.3[i], cols.4[i], cols.5[i],
                    ];
                    if classify_rows_one_invalid(&row) {
                        return Err(row_error(start + i, &row));
                    }
                }
            }
            match &self.partition {
                Partition::Constraints(p) => p.classify_block(&xs[..m], &ys[..m], &mut states[..m]),
                Partition::Raster(r) => {
                    for ((s, x), y) in states[..m].iter_mut().zip(&xs[..m]).zip(&ys[..m]) {
                        *s = r.classify(*x, *y);
                    }
                }
            }
            for (o, s) in out[start..end].iter_mut().zip(&states[..m]) {
                *o = O::from_state(StateId(*s));
            }
        }
        Ok(())
    }

    pub(crate) fn features(&self) -> &Features {
        &self.features
    }

    /// The probe points behind derived structure (normalised coordinates).
    pub(crate) fn probes(&self) -> &[Point2<f64>] {
        crate::derived::get_or_derive(&self.derived.probes, || {
            self.features.probes(DERIVED_PROBES, DERIVED_SEED)
        })
        .as_slice()
    }

    pub(crate) fn pools(&self) -> &[StatePool] {
        crate::derived::get_or_derive(&self.derived.pools, || {
            state_pools(
                &self.partition,
                self.n_states(),
                self.probes(),
                POOL_CAPACITY,
                DERIVED_SEED ^ 0x9e37,
            )
        })
        .as_slice()
    }

    /// The conceptual-neighbourhood graph (computed once, then cached).
    #[must_use]
    pub fn neighbours(&self) -> &NeighbourGraph {
        crate::derived::get_or_derive(&self.derived.neighbours, || NeighbourGraph::compute(self))
    }

    /// The table of a permutation operation (computed once, then cached).
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for calculi that are not ternary.
    pub fn permutation(&self, op: Permutation) -> Result<&PermutationTable> {
        self.require_ternary(op.name())?;
        Ok(crate::derived::get_or_derive(
            &self.derived.permutations[op as usize],
            || PermutationTable::compute(self, op, true),
        ))
    }

    /// Whether the sound composition and every permutation table are in memory.
    pub(crate) fn has_reasoning_tables(&self) -> bool {
        self.derived.compose.get().is_some()
            && self.derived.permutations.iter().all(|p| p.get().is_some())
    }

    /// Installs tables read from the cache (ignored where a table is already derived).
    pub(crate) fn seed_reasoning_tables(
        &self,
        compose: ComposeTable,
        permutations: Vec<PermutationTable>,
    ) {
        let _ = self.derived.compose.set(compose);
        for table in permutations {
            let _ = self.derived.permutations[table.op() as usize].set(table);
        }
    }

    /// A permutation table, with (`boundaries = true`, as [`Calculus::permutation`]) or
    /// without configurations that have a point exactly on a boundary (not cached).
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for calculi that are not ternary.
    pub fn permutation_with(&self, op: Permutation, boundaries: bool) -> Result<PermutationTable> {
        self.require_ternary(op.name())?;
        Ok(PermutationTable::compute(self, op, boundaries))
    }

    /// The composition table `{AB:C} ∘ {BC:D} → {AB:D}` with default sampling (cached).
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for calculi that are not ternary.
    pub fn compose_table(&self) -> Result<&ComposeTable> {
        self.require_ternary("compose")?;
        Ok(crate::derived::get_or_derive(&self.derived.compose, || {
            ComposeTable::compute(self, &ComposeOptions::default())
        }))
    }

    /// The composition table with explicit sampling options (not cached).
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for calculi that are not ternary.
    pub fn compose_table_with(&self, options: &ComposeOptions) -> Result<ComposeTable> {
        self.require_ternary("compose")?;
        Ok(ComposeTable::compute(self, options))
    }

    /// This calculus as a label raster over `window` (`[x_min, x_max, y_min, y_max]`) with
    /// `nx × ny` cells (each labelled by its centre) and `outside` beyond it: a learned
    /// calculus in the form SERGE produces.
    ///
    /// # Errors
    /// Spec errors for an impossible raster (empty window, zero cells, a state no cell hits).
    pub fn rasterise(
        &self,
        window: [f64; 4],
        nx: usize,
        ny: usize,
        outside: OutsideRule,
    ) -> Result<Self> {
        let [x0, x1, y0, y1] = window;
        if !window.iter().all(|v| v.is_finite()) || x1 <= x0 || y1 <= y0 || nx == 0 || ny == 0 {
            return Err(spec_error(
                self.name(),
                format!("cannot rasterise over window {window:?} with {nx}×{ny} cells"),
            ));
        }
        let dx = (x1 - x0) / nx as f64;
        let dy = (y1 - y0) / ny as f64;
        let mut cells = Vec::with_capacity(nx * ny);
        for iy in 0..ny {
            for ix in 0..nx {
                let p = Point2::new(x0 + (ix as f64 + 0.5) * dx, y0 + (iy as f64 + 0.5) * dy);
                cells.push(self.partition.classify(&p));
            }
        }
        let mut spec = self.spec.clone();
        spec.name = format!("{}-raster", self.spec.name);
        spec.description = format!("{} rasterised over {window:?} at {nx}x{ny}", self.spec.name);
        spec.constraints.clear();
        spec.states.iter_mut().for_each(|s| s.cells.clear());
        spec.raster = Some(RasterSpec {
            window,
            nx,
            ny,
            cells,
            outside,
        });
        Self::from_spec(spec)
    }

    pub(crate) fn require_ternary(&self, operation: &str) -> Result<()> {
        if self.frame() == FrameKind::Ternary {
            Ok(())
        } else {
            Err(QsrError::Unsupported {
                operation: operation.to_owned(),
                calculus: self.name().to_owned(),
                reason: if crate::binary::is_binary_name(self.name()) {
                    format!(
                        "this is the oriented spec view of `{0}`; its converse and composition \
                         (STAR, a reference direction shared by all points) are in \
                         `qsr_core::binary::BinaryCalculus::builtin(\"{0}\")`",
                        self.name()
                    )
                } else {
                    format!(
                        "permutations and composition are defined for ternary point calculi \
                         and, through `qsr_core::binary`, for OPRA-m and STAR-m; a {} relation \
                         does not record what they need (e.g. the heading of the middle object)",
                        self.frame().as_str()
                    )
                },
            })
        }
    }
}

/// Classifies rows block by block: normalise [`BLOCK`] triplets (vectorisable: no branch
/// but the validity check), then hand the block to the partition.
fn classify_rows<O: StateIndex>(
    partition: &Partition,
    triplets: &[[f64; 6]],
    out: &mut [O],
) -> Result<()> {
    if let Partition::Constraints(c) = partition {
        return with_wide_vectors!(rows_fused::<O: StateIndex>(c: &ConstraintPartition, triplets: &[[f64; 6]], out: &mut [O]) -> Result<()>);
    }
    let mut xs = [0.0f64; BLOCK];
    let mut ys = [0.0f64; BLOCK];
    let mut states = [0u16; BLOCK];
    for (bi, (rows, outs)) in triplets
        .chunks(BLOCK)
        .zip(out.chunks_mut(BLOCK))
        .enumerate()
    {
        let mut valid = true;
        for ((t, x), y) in rows.iter().zip(xs.iter_mut()).zip(ys.iter_mut()) {
            let ok;
            (*x, *y, ok) = normalise_row(t);
            valid &= ok;
        }
        if !valid {
            return Err(first_invalid(rows, bi * BLOCK));
        }
        let n = rows.len();
        match partition {
            Partition::Constraints(c) => c.classify_block(&xs[..n], &ys[..n], &mut states[..n]),
            Partition::Raster(r) => {
                for ((s, x), y) in states[..n].iter_mut().zip(&xs[..n]).zip(&ys[..n]) {
                    *s = r.classify(*x, *y);
                }
            }
        }
        for (o, s) in outs.iter_mut().zip(&states[..n]) {
            *o = O::from_state(StateId(*s));
        }
    }
    Ok(())
}

/// Calls `$f($args)` compiled for AVX-512 or AVX2 where the CPU has them (picked at run time,
/// so the binary and the wheel stay portable), else for the baseline: a kernel per constraint
/// shape keeps a point in registers, and wider registers take four or eight at once. The
/// arithmetic is the same IEEE operations in the same order on every path.
macro_rules! with_wide_vectors {
    ($f:ident $(::<$g:ident: $bound:path>)? ($($arg:ident: $ty:ty),*) -> $ret:ty) => {{
        #[cfg(target_arch = "x86_64")]
        {
            #[target_feature(enable = "avx512f,avx512dq,avx512vl,avx512bw")]
            fn avx512 $(<$g: $bound>)? ($($arg: $ty),*) -> $ret {
                $f $(::<$g>)? ($($arg),*)
            }
            #[target_feature(enable = "avx2")]
            fn avx2 $(<$g: $bound>)? ($($arg: $ty),*) -> $ret {
                $f $(::<$g>)? ($($arg),*)
            }
            if std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512dq")
                && std::arch::is_x86_feature_detected!("avx512vl")
                && std::arch::is_x86_feature_detected!("avx512bw")
            {
                #[allow(unsafe_code)]
                // SAFETY: `avx512` only requires these AVX-512 parts, just detected.
                return unsafe { avx512 $(::<$g>)? ($($arg),*) };
            }
            if std::arch::is_x86_feature_detected!("avx2") {
                #[allow(unsafe_code)]
                // SAFETY: `avx2` only requires AVX2, just detected.
                return unsafe { avx2 $(::<$g>)? ($($arg),*) };
            }
        }
        $f $(::<$g>)? ($($arg),*)
    }};
}
use with_wide_vectors;

/// [`classify_rows`] for a constraint partition: the normalisation fused into the kernel of
/// the partition's shape, a block of states at a time.
#[inline(always)]
fn rows_fused<O: StateIndex>(
    c: &ConstraintPartition,
    triplets: &[[f64; 6]],
    out: &mut [O],
) -> Result<()> {
    // one buffer for every block: filled whole before each use
    let mut cols = [[0.0f64; BLOCK]; 6];
    for (bi, (rows, outs)) in triplets
        .chunks(BLOCK)
        .zip(out.chunks_mut(BLOCK))
        .enumerate()
    {
        let n = rows.len();
        // a full block as an array: every index provably in range, the loop has no tail
        let valid = match <&[[f64; 6]; BLOCK]>::try_from(rows) {
            Ok(full) => {
                // moved into six columns first: the fused loop then loads each coordinate of
                // eight (four) rows as one vector, where reading the rows in place gathered
                // them one 48-byte stride at a time
                for (i, row) in full.iter().enumerate() {
                    for (col, v) in cols.iter_mut().zip(row) {
                        col[i] = *v;
                    }
                }
                c.classify_points(
                    BLOCK,
                    |i| normalise_row(&std::array::from_fn(|k| cols[k][i])),
                    outs,
                )
            }
            Err(_) => c.classify_points(n, |i| normalise_row(&rows[i]), outs),
        };
        if !valid {
            return Err(first_invalid(rows, bi * BLOCK));
        }
    }
    Ok(())
}

/// [`Calculus::classify_columns`] for a constraint partition, as [`rows_fused`].
#[inline(always)]
fn columns_fused<O: StateIndex>(
    c: &ConstraintPartition,
    cols: [&[f64]; 6],
    out: &mut [O],
) -> Result<()> {
    let row = |cols: &[&[f64]; 6], i: usize| std::array::from_fn(|k| cols[k][i]);
    for (bi, outs) in out.chunks_mut(BLOCK).enumerate() {
        let (start, n) = (bi * BLOCK, outs.len());
        let block: [&[f64]; 6] = std::array::from_fn(|k| &cols[k][start..start + n]);
        // a full block as arrays: every index provably in range, the loop has no tail
        let valid = if n == BLOCK {
            let f = block.map(|b| b.first_chunk::<BLOCK>().unwrap_or(&[0.0; BLOCK]));
            c.classify_points(
                BLOCK,
                |i| normalise_row(&std::array::from_fn(|k| f[k][i])),
                outs,
            )
        } else {
            c.classify_points(n, |i| normalise_row(&row(&block, i)), outs)
        };
        if !valid {
            let i = (0..n)
                .find(|&i| classify_rows_one_invalid(&row(&block, i)))
                .unwrap_or(0);
            return Err(row_error(start + i, &row(&block, i)));
        }
    }
    Ok(())
}

/// The error of the first invalid row of a block that failed the check (`start`: the index
/// of its first row).
fn first_invalid(rows: &[[f64; 6]], start: usize) -> QsrError {
    let (i, t) = rows
        .iter()
        .enumerate()
        .find(|(_, t)| classify_rows_one_invalid(t))
        .unwrap_or((0, &rows[0]));
    row_error(start + i, t)
}

fn classify_rows_one_invalid(t: &[f64; 6]) -> bool {
    !normalise_row(t).2
}

/// `(x, y, valid)` of `C` in the frame of `(A, B)` for a row `[ax, ay, bx, by, cx, cy]`:
/// the branch-free core of the batch paths. Valid means finite and not coincident, the test of
/// `TernaryFrame::new` with the scale bounded by squares: |AB|² > tol² · (1 + |A|² + |B|²)
/// (false for NaN too, so one comparison guards A and B).
#[inline(always)]
pub(crate) fn normalise_row(t: &[f64; 6]) -> (f64, f64, bool) {
    let [ax, ay, bx, by, cx, cy] = *t;
    let (dx, dy) = (bx - ax, by - ay);
    let len2 = dx * dx + dy * dy;
    let scale2 = 1.0 + ax * ax + ay * ay + bx * bx + by * by;
    let tol2 = crate::frame::DEGENERATE_TOLERANCE * crate::frame::DEGENERATE_TOLERANCE;
    let valid = (len2 > tol2 * scale2) & cx.is_finite() & cy.is_finite();
    let inv = 1.0 / len2;
    let (vx, vy) = (cx - ax, cy - ay);
    (-(dx * vy - dy * vx) * inv, (dx * vx + dy * vy) * inv, valid)
}

fn row_error(i: usize, t: &[f64; 6]) -> QsrError {
    if t.iter().all(|v| v.is_finite()) {
        QsrError::DegenerateFrame {
            reason: format!("triplet {i}: reference points coincide ({t:?})"),
        }
    } else {
        QsrError::NonFinite {
            what: format!("triplet {i} {t:?}"),
        }
    }
}

fn compile_constraints(spec: &CalculusSpec) -> Result<Partition> {
    let k = spec.constraints.len();
    let shapes: Vec<_> = spec.constraints.iter().map(|c| (c.shape, c.zero)).collect();
    let mut table = pattern_table(spec);
    let draft = ConstraintPartition::new(&shapes, table.clone());
    let probes = Features::of(&Partition::Constraints(draft.clone()))
        .probes(VALIDATION_PROBES, DERIVED_SEED ^ 0xa11d);
    let mut met = vec![false; spec.states.len()];
    for p in &probes {
        let v = draft.sign_vector(p.x, p.y);
        match table[v as usize] {
            u16::MAX => {
                return Err(spec_error(
                    &spec.name,
                    format!(
                        "sign vector `{}` occurs (e.g. at ({}, {})) but no state claims it",
                        format_vector(v, k),
                        p.x,
                        p.y
                    ),
                ));
            }
            s => met[usize::from(s)] = true,
        }
    }
    if let Some(i) = met.iter().position(|m| !m) {
        return Err(spec_error(
            &spec.name,
            format!(
                "state `{}` is unreachable: none of its sign patterns occurs in the plane",
                spec.states[i].label
            ),
        ));
    }
    complete_table(&mut table);
    Ok(Partition::Constraints(ConstraintPartition::new(
        &shapes, table,
    )))
}

fn compile_raster(spec: &CalculusSpec, r: &RasterSpec) -> Result<RasterPartition> {
    let outside = match &r.outside {
        OutsideRule::Clamp => None,
        OutsideRule::State { label } => spec
            .states
            .iter()
            .position(|s| &s.label == label)
            .map(|i| i as u16),
    };
    let mut met = vec![false; spec.states.len()];
    for &c in &r.cells {
        met[usize::from(c)] = true;
    }
    if let Some(o) = outside {
        met[usize::from(o)] = true;
    }
    if let Some(i) = met.iter().position(|m| !m) {
        return Err(spec_error(
            &spec.name,
            format!(
                "state `{}` is unreachable: no raster cell carries it",
                spec.states[i].label
            ),
        ));
    }
    Ok(RasterPartition::new(r, outside))
}

impl Sampled for Calculus {
    fn n_states(&self) -> usize {
        Calculus::n_states(self)
    }
    fn partition(&self) -> &Partition {
        Calculus::partition(self)
    }
    fn classify_normalised(&self, p: &Point2<f64>) -> StateId {
        Calculus::classify_normalised(self, p)
    }
    fn probes(&self) -> &[Point2<f64>] {
        Calculus::probes(self)
    }
    fn pools(&self) -> &[StatePool] {
        Calculus::pools(self)
    }
    fn features(&self) -> &Features {
        Calculus::features(self)
    }
}
