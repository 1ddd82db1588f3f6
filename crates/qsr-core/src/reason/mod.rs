//! Qualitative reasoning over constraint networks: algebraic closure, consistency and
//! scenarios — what SparQ and GQR do, for every ternary calculus qsr-core derives tables for
//! (built-in, user spec, learned).
//!
//! ## Why
//! A qualitative map is more than a lookup table when its relations can be *combined*: a
//! robot that knows `{A,B:C}` and `{B,C:D}` but never saw A, B and D together can still bound
//! `{A,B:D}` through the composition table, and a map whose entries contradict each other can
//! be caught. The thesis builds the tables (§3.3.2) and calls this "one of the most useful
//! capabilities of QSRs"; this module uses them.
//!
//! ## Parts (one concept each)
//! - [`StateSet`]: a set of states (a disjunction of base relations), as a bitset.
//! - [`Algebra`]: a calculus's composition and permutation tables as bitsets
//!   ([`TableScope::Sound`] by default: boundaries included).
//! - [`Network`]: a set of states for every ordered triplet of named points; from points
//!   (exact), JSON or SparQ's text form.
//! - [`close`]: algebraic closure, with an explanation of a contradiction.
//! - [`find_scenario`]: backtracking with closure as forward checking.
//!
//! ## Naming rule
//! Nouns for data (`Network`, `Closure`, `Contradiction`), verbs for operations (`close`,
//! `find_scenario`); `from_*` / `to_*` convert; `*Options` structs carry settings, with
//! `Default` and named constructors, never positional flags.
//!
//! ```
//! use qsr_core::{Calculus, Point2, reason::{Algebra, Network, TableScope, close}};
//! let dc = Calculus::builtin("double-cross")?;
//! let alg = Algebra::of(&dc, TableScope::Sound)?;
//! // Four points; forget every relation that involves A, B and D together.
//! let pts = [Point2::new(0.0, 0.0), Point2::new(0.0, 1.0), Point2::new(-1.0, 2.0), Point2::new(-3.0, 4.0)];
//! let exact = Network::from_points(&dc, ["A", "B", "C", "D"], &pts)?;
//! let mut net = exact.clone();
//! let any = qsr_core::reason::StateSet::universal(dc.n_states());
//! for (a, b, c) in [(0, 1, 3), (1, 0, 3), (0, 3, 1), (3, 0, 1), (1, 3, 0), (3, 1, 0)] {
//!     net.set(a, b, c, &any);
//! }
//! let closed = close(net, &alg)?;
//! assert!(closed.is_consistent());
//! // The true relation survives, and closure narrowed what was unknown.
//! let inferred = closed.network.get(0, 1, 3);
//! assert!(inferred.is_superset(&exact.get(0, 1, 3)));
//! assert!(inferred.len() < dc.n_states());
//! # Ok::<(), qsr_core::QsrError>(())
//! ```

mod algebra;
mod closure;
pub(crate) mod network;
mod network_format;
mod scenario;
mod state_set;

pub use algebra::{Algebra, TableScope};
pub use closure::{
    Closure, ClosureOptions, ClosureStats, Contradiction, Rule, Step, close, close_with,
};
pub use network::{CLOSURE_SECONDS_PER_UNIT, Network, closure_cost};
pub use network_format::NetworkFormat;
pub use scenario::{ScenarioOptions, ScenarioOutcome, find_scenario};
pub use state_set::StateSet;
pub(crate) use state_set::{fill_universal, iter_bits};
