//! Reasoning over a PQRM (issue 13 §2): a map as a constraint network, a consistency check
//! of its most likely states, and inference of relations between landmarks never observed
//! together.
//!
//! ## Inference: what it assumes
//! To predict `{a,b:d}`, every fourth landmark `c` and every ordering `(x,y,z)` of `(a,b,d)`
//! with both `{x,y:c}` and `{y,c:z}` in the map gives a *path*:
//!
//! ```text
//! p_path(t) = Σ_r Σ_s  p(x,y:c = r) · p(y,c:z = s) · [t ∈ r ∘ s] · w(t | r, s)
//! ```
//!
//! mapped back to `(a,b,d)` through the permutation that relates the orderings. Two
//! assumptions, stated because they matter:
//! 1. the two beliefs of a path are independent (they come from different sets of frames
//!    only in part — frames that saw a, b, c, d together feed both);
//! 2. the share `w(t | r, s)` of each state of a composition entry: by default
//!    ([`Composition::Learned`]) as often as the map's own observed quadruples show it (one
//!    pseudo-count spread evenly, so an entry never seen is uniform); or
//!    [`Composition::Uniform`], `1/|r ∘ s|` (maximum entropy: the table says which states are
//!    possible, not how often). On MRCLAM the uniform split left low-confidence inferences
//!    underconfident and cost log loss on every recording (`docs/reasoning.md`).
//!
//! Paths are then fused ([`Fusion`]): a *mixture* (linear pool), a *product* (independent
//! evidence: sharp, overconfident when paths share frames), the *tempered product*
//! (log-linear pool with weights 1/k: never more confident than the average path), or the
//! log-linear pool with weights `k^(−α)` where α is *fitted on the map itself* — every
//! observed set is predicted from the others and α minimises the cross-entropy against the
//! map's own belief, so no ground truth is needed (the default). With learned shares every
//! path carries the targets' base rate; the same fit chooses whether the pool divides it out
//! of each path and counts it once (`p ∝ b · Π (p_i / b)^w`) or not. Each path is smoothed with
//! weight ε towards uniform first, so a state one path rules out can still win when the other
//! paths insist. `qrm reason study` measures all four (`docs/reasoning.md`).
//!
//! A set whose landmarks share no fourth landmark with observed sets has no path. Chains of
//! composition reach further: [`Inferrer::infer_unseen`] runs in rounds, round r composing
//! what rounds before it inferred, and records each set's round.
//!
//! Probabilities are propagated with the calculus's *general-position* tables (a noisy
//! sensor puts no mass on boundaries); the consistency check uses the sound ones.
//!
//! ## Parts
//! - [`network`]: the map as a constraint network ([`to_network`]), its landmarks and sets;
//! - [`check`](mod@check): the consistency check of the most likely states ([`check()`]);
//! - [`inference`]: [`Inferrer`], paths and fusion.

pub mod check;
pub mod inference;
pub mod network;
pub mod report;

pub use check::{FlaggedEntry, MapCheck, check};
pub use inference::{Composition, Fusion, InferOptions, Inference, Inferrer, infer};
pub use network::{Selection, landmarks, observed_sets, to_network};
pub use report::{InferenceReport, InferredSet, calibration_note};
