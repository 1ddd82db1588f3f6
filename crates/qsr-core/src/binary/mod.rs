//! Binary point calculi — OPRA-m and STAR-m — with converse, composition and conceptual
//! neighbours derived *exactly*, and closure over binary constraint networks.
//!
//! ## Why a separate family
//! The ternary calculi of [`crate::Calculus`] are partitions of one normalised plane, and
//! their tables are derived by sampling that plane. A binary calculus over oriented points
//! relates *two* frames at once (OPRA: where B is for A's heading, and where A is for B's),
//! and its interesting relations are measure-zero: OPRA's rays (`0_2`: B straight ahead of
//! A, A straight behind B) and same-position relations (`s_k`). Sampling never lands on
//! them. Here every relation is a condition on *angles*, so the tables are computed by
//! angle arithmetic instead.
//!
//! ## Why the tick grid is exact
//! Three points A, B, C with headings are, up to rotation, translation and scale, the three
//! edge directions A→B, B→C, C→A and the three headings; the edge directions form a
//! triangle exactly when their turning angles are all in `(0, π)` (counter-clockwise), all
//! in `(π, 2π)` (clockwise), or `0, π, π` in some order (collinear). Each relation of `{A:B}`, `{B:C}`, `{A:C}` —
//! and each triangle condition — bounds a *difference of two of these six angles* by whole
//! units (`π/m`). A satisfiable system of difference bounds over `n` variables, some strict,
//! has a solution on the grid `1/n` of the unit (shift the strict bounds by `1/n`; shortest
//! paths then lie on that grid). So enumerating every configuration on a grid of
//! [`TICKS_PER_UNIT`] `= 6` ticks per unit meets *every* realisable triple and nothing else:
//! the composition is exact — sound and complete — with the rays and coincidences included.
//! (Tests re-derive with 7 and 12 ticks per unit and get the same tables, and check OPRA-1
//! against GQR's published table and STAR-8 against SparQ's.)
//!
//! ## Parts (one concept each)
//! - [`DirectionPartition`]: how a calculus cuts the circle of directions.
//! - [`BinaryCalculus`]: names, relations, classification, derived tables.
//! - [`ConverseTable`]: `X r Y ⇒ Y conv(r) X`; composition reuses [`crate::ComposeTable`].
//! - the on-disk table cache ([`BinaryCalculus::load_or_derive_tables`], [`CacheOutcome`],
//!   [`default_cache_dir`]).
//! - [`BinaryAlgebra`]: the tables reasoning needs, derived ([`BinaryAlgebra::of`]) or read
//!   from GQR's `.spec` and SparQ's `def-calculus` files (RCC-8, Allen, the point algebra,
//!   cardinal directions, …), with [`BinaryAlgebra::check`] saying which algebraic laws they
//!   obey.
//! - [`BinaryNetwork`]: a network over an algebra, in SparQ's text, JSON or GQR's `.csp`
//!   ([`from_gqr_csp_str`], [`BinaryNetwork::to_gqr_csp`]).
//! - [`close_binary`]: path consistency (PC-2 over block tables of set composition);
//!   [`solve_binary`]: consistency by search, with a node budget, splitting into base
//!   relations or a [`SplitSet`] (a tractable subclass, GQR's cover sets).
//! - [`render_binary_svg`]: a picture of the partition of directions.
//!
//! ## Naming rule
//! As the rest of the crate: nouns for derived structure computed on first use
//! (`converse`, `compose_table`, `neighbours`), `classify*` for configurations → relations,
//! `from_*`/`to_*` for conversions, verbs for operations (`close_binary`).

mod algebra;
mod algebra_check;
mod cache;
mod calculus;
mod closure;
mod consistency;
mod csp;
mod derive;
mod direction;
mod edge_queue;
mod network;
mod picture;
mod relations;
pub(crate) mod set_ops;
mod split_set;
mod table_files;

pub use algebra::{AsBinaryAlgebra, BinaryAlgebra, MAX_LOADED_RELATIONS};
pub use algebra_check::{AlgebraCheck, AlgebraLaw, LawVerdict, MAX_ASSOCIATIVITY_CHECK};
pub(crate) use cache::fnv1a;
pub use cache::{CacheOutcome, cache_path, default_cache_dir};
pub use calculus::{
    BINARY_NAMES, BinaryCalculus, BinaryFamily, DERIVATION_BUDGET, MAX_OPRA_M, MAX_STAR_M,
    SECONDS_PER_DERIVATION_STEP, is_binary_name, name_out_of_range,
};
pub use closure::{BinaryClosure, BinaryContradiction, close_binary};
pub use consistency::{BinarySolution, SolveOptions, SolveOutcome, solve_binary};
pub use csp::{GqrNetwork, from_gqr_csp_str};
pub use derive::ConverseTable;
pub use direction::{DirectionPartition, RAY_TOLERANCE, TICKS_PER_UNIT};
pub use network::{BinaryNetwork, MAX_BINARY_POINTS, relation_set};
pub use picture::render_binary_svg;
pub use split_set::SplitSet;
pub use table_files::GqrTables;
