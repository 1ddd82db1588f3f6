//! # qsr-core — qualitative spatial calculi as data
//!
//! A *qualitative spatial relationship* locates one entity relative to a frame made of
//! reference entities (thesis §4.2): "C is left of A→B and inside the circle about A". A
//! *calculus* partitions the frame's normalised plane into labelled *states*. Everything
//! else in qrm — the probabilistic mapper, SERGE's learned calculi, Q-Link's planner — asks
//! this crate three questions: *which state is this configuration in*, *which states touch*,
//! and *what can be inferred by combining relations*.
//!
//! ## Why calculi are data
//! The thesis uses six point calculi that are merges of one another (§2.3.1), binary and
//! extended ones for navigation (§4.2, §4.4.2), and calculi *learned* from data by SERGE
//! (§3.3.2). Writing each as code would mean six classifiers, six neighbour graphs and six
//! compose tables typed by hand. Here a calculus is a [`CalculusSpec`] — lines and circles
//! with a sign-pattern merge table, or a label raster — validated once, and every derived
//! table is *computed* from it by one sampler ([`coverage`]) designed to reach thin,
//! unbounded and on-boundary configurations. The built-ins are spec files loaded through the
//! same path as a user's.
//!
//! ## Naming rule for operations
//! - `classify_*` maps configurations to states (`classify_triplet`, `classify_oriented`,
//!   `classify_extended`, `classify_row`, `classify_triplets` for batches,
//!   `classify_normalised` when the point is already in the frame); a `_as` suffix writes
//!   the states as the caller's integer type ([`StateIndex`]) in place.
//! - Nouns return derived structure, computed on first use and cached:
//!   [`Calculus::neighbours`], [`Calculus::permutation`], [`Calculus::compose_table`].
//! - `merge_*` goes from a finer calculus to a coarser one ([`Calculus::merge_map`],
//!   [`MergeMap::merge_distribution`]).
//! - `from_*` / `to_*` convert specs and frames.
//! - Reasoning over constraint networks (closure, scenarios) lives in [`reason`]; binary
//!   calculi (OPRA-m, STAR-m) with exact converse and composition in [`binary`].
//! - What work will take is a [`cost::Cost`] (peak bytes, core-seconds at measured rates),
//!   checked against a [`cost::Budget`] before anything is allocated; every crate of qrm
//!   estimates and refuses through it, so every refusal reads alike.
//!
//! ## Conventions
//! Normalised ternary frame: A = (0, 0), B = (0, 1), **x < 0 is left** of A→B (a proper
//! rotation; the thesis's printed Γ is a reflection, DESIGN §3). Each constraint's zero set
//! joins one side, so every point has exactly one state.
//!
//! ## Errors
//! Every fallible call returns [`QsrError`]:
//! | variant | raised by |
//! |---|---|
//! | `NonFinite` | NaN/∞ coordinates or parameters |
//! | `DegenerateFrame` | coincident reference points (see [`DEGENERATE_TOLERANCE`]), zero-length or opposed walls |
//! | `Spec` | malformed spec, duplicate label, bad pattern, overlap, gap, unreachable state, bad raster |
//! | `UnknownCalculus`, `UnknownState`, `UnknownOperation` | names that do not exist |
//! | `Unsupported` | permutations/composition of non-ternary spec calculi (binary ones: [`binary`]) |
//! | `TooLarge` | a derived table (e.g. OPRA-11 composition) beyond its [`cost::Budget`], with the estimate |
//! | `Arity` | wrong number of inputs, wrong frame kind, mismatched lengths |
//! | `NotARefinement` | merging into a calculus that is not coarser |
//! | `Network` | malformed constraint network (JSON or SparQ text), with line/column or constraint position |
//! | `Io` | unreadable spec file |
//!
//! ```
//! use qsr_core::{Calculus, Permutation};
//!
//! let dc = Calculus::builtin("double-cross")?;
//! let lf = dc.state("left-front")?;
//! // In general position, what is left-front of A→B is right-back of B→A ...
//! let generic = dc.permutation_with(Permutation::Inverse, false)?;
//! assert_eq!(generic.get(lf), &[dc.state("right-back")?]);
//! // ... and the table sound for every configuration adds the boundary case: C exactly on
//! // the perpendicular at B is "front" of A→B (y >= 1) but "middle" of B→A (y' = 0).
//! let sound = dc.permutation(Permutation::Inverse)?;
//! assert_eq!(sound.get(lf), &[dc.state("right-middle")?, dc.state("right-back")?]);
//! # Ok::<(), qsr_core::QsrError>(())
//! ```

pub mod binary;
mod builtin;
mod calculus;
mod compose;
pub mod cost;
pub mod coverage;
mod derived;
mod describe;
mod error;
mod frame;
mod fused;
mod merge;
mod neighbours;
mod partition;
mod permute;
pub mod progress;
pub mod reason;
#[cfg(feature = "svg")]
mod render;
mod sampled;
mod spec;
mod state;
pub mod stats;
pub mod table_cache;
pub mod table_text;
pub mod text_file;

pub use builtin::{BUILTIN_NAMES, BUILTIN_SPECS, POINT_CALCULI, builtin_spec};
pub use calculus::{Calculus, StateId};
pub use compose::{ComposeOptions, ComposeTable};
pub use error::{QsrError, Result};
pub use frame::{
    AnyFrame, DEGENERATE_TOLERANCE, ExtendedFrame, FrameKind, OrientedFrame, Segment, TernaryFrame,
};
pub use merge::MergeMap;
pub use neighbours::NeighbourGraph;
pub use partition::{ConstraintPartition, Partition, ROUNDING_MARGIN, RasterPartition};
pub use permute::{Permutation, PermutationTable, all_orderings};
#[cfg(feature = "svg")]
pub use render::{RenderOptions, register_font, render_svg};
pub use spec::{
    CalculusSpec, ConstraintSpec, MAX_CONSTRAINTS, MAX_FEATURE_EXTENT, MIN_FEATURE_SIZE,
    OutsideRule, RasterSpec, Shape, Side, StateSpec,
};
pub use state::StateIndex;

/// Re-exported so users need not depend on nalgebra to call the API.
pub use nalgebra::Point2;
