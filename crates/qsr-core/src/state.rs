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

impl fmt::Display for StateId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.0)
    }
}
