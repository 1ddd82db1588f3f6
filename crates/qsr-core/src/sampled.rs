//! What a calculus's derived tables are computed from: its partition of the normalised plane,
//! its classification and the sample points the derivations draw on. The derivations
//! (neighbours, permutations, composition) take this view and [`crate::Calculus`], which
//! implements it, caches what they derive: the dependency runs one way, from the calculus
//! down to its derivations and from them down to this.

use nalgebra::Point2;

use crate::coverage::{Features, StatePool};
use crate::partition::Partition;
use crate::state::StateId;

/// Seed of every internal sampler: derived structure is a deterministic function of the spec.
pub(crate) const DERIVED_SEED: u64 = 0x5152_4d5f_7173_7231;

/// A partition with what the derivations sample from it.
pub(crate) trait Sampled: Sync {
    /// Number of states.
    fn n_states(&self) -> usize;
    /// The compiled partition.
    fn partition(&self) -> &Partition;
    /// The state of a point in normalised coordinates.
    fn classify_normalised(&self, p: &Point2<f64>) -> StateId;
    /// Probe points spread over the plane (normalised coordinates).
    fn probes(&self) -> &[Point2<f64>];
    /// Sample points per state, for composition.
    fn pools(&self) -> &[StatePool];
    /// The partition's boundary features.
    fn features(&self) -> &Features;
}
