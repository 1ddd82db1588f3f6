//! [`StateId`]: a state of a calculus, by index. Below every module that derives or
//! uses states, so the derivations need not import the calculus.

use std::fmt;

/// Index of a state within its calculus (`0..n_states`), in spec order.
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(transparent)]
pub struct StateId(pub u16);

impl StateId {
    /// The index as `usize`.
    #[inline(always)]
    #[must_use]
    pub fn index(self) -> usize {
        usize::from(self.0)
    }
}

/// A type a classifier writes a state index as: [`StateId`] itself, or a plain integer — the
/// int64 of a NumPy array, a `usize` index — so that the kernel fills a caller's output in
/// place ([`Calculus::classify_triplets_as`](crate::Calculus::classify_triplets_as)) instead of
/// the caller widening a buffer of ids in a second pass, which cost 0.3–0.8 ns a triplet from
/// memory (about a quarter of the classification; docs/performance.md, 2026-11-30).
pub trait StateIndex: Copy {
    /// The state `id` in this type (every `u16` fits each implementor).
    fn from_state(id: StateId) -> Self;
}

impl StateIndex for StateId {
    #[inline(always)]
    fn from_state(id: StateId) -> Self {
        id
    }
}

macro_rules! integer_state_index {
    ($($t:ty),*) => {$(
        impl StateIndex for $t {
            #[inline(always)]
            fn from_state(id: StateId) -> Self {
                Self::from(id.0)
            }
        }
    )*};
}
integer_state_index!(u16, u32, u64, usize, i32, i64);

impl fmt::Display for StateId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}
