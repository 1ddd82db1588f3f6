//! [`StateSet`]: a set of states of one calculus, as a bitset.

use crate::calculus::{Calculus, StateId};

/// Words of 64 bits needed for `n_states` states.
#[must_use]
pub(crate) fn words_for(n_states: usize) -> usize {
    n_states.div_ceil(64).max(1)
}

/// A set of states of one calculus (a disjunction of base relations), as a bitset.
///
/// ```
/// use qsr_core::{Calculus, reason::StateSet};
/// let dc = Calculus::builtin("double-cross")?;
/// let s = StateSet::from_labels(&dc, &["left-front", "right-back"])?;
/// assert_eq!(s.len(), 2);
/// assert_eq!(s.labels(&dc), ["left-front", "right-back"]);
/// assert!(StateSet::universal(dc.n_states()).is_superset(&s));
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct StateSet {
    n_states: usize,
    words: Vec<u64>,
}

impl StateSet {
    /// The empty set over `n_states` states.
    #[must_use]
    pub fn empty(n_states: usize) -> Self {
        Self {
            n_states,
            words: vec![0; words_for(n_states)],
        }
    }

    /// Every state (the universal relation: nothing is known).
    #[must_use]
    pub fn universal(n_states: usize) -> Self {
        let mut s = Self::empty(n_states);
        fill_universal(&mut s.words, n_states);
        s
    }

    /// The set holding one state.
    #[must_use]
    pub fn single(n_states: usize, state: StateId) -> Self {
        let mut s = Self::empty(n_states);
        s.insert(state);
        s
    }

    /// The set of the given states (ids `≥ n_states` are ignored).
    #[must_use]
    pub fn from_states(n_states: usize, states: impl IntoIterator<Item = StateId>) -> Self {
        let mut s = Self::empty(n_states);
        for t in states {
            if t.index() < n_states {
                s.insert(t);
            }
        }
        s
    }

    /// The set of the states with these labels.
    ///
    /// # Errors
    /// [`crate::QsrError::UnknownState`] for a label the calculus does not have.
    pub fn from_labels(calculus: &Calculus, labels: &[impl AsRef<str>]) -> crate::Result<Self> {
        let mut s = Self::empty(calculus.n_states());
        for l in labels {
            s.insert(resolve_label(calculus, l.as_ref())?);
        }
        Ok(s)
    }

    /// Wraps words of the network's storage.
    pub(crate) fn from_words(n_states: usize, words: &[u64]) -> Self {
        Self {
            n_states,
            words: words.to_vec(),
        }
    }

    /// The bit words (bit `i` of word `i / 64` is state `i`).
    #[must_use]
    pub fn words(&self) -> &[u64] {
        &self.words
    }

    /// The number of states of the calculus this set belongs to.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.n_states
    }

    /// Adds a state.
    pub fn insert(&mut self, state: StateId) {
        let i = state.index();
        self.words[i / 64] |= 1 << (i % 64);
    }

    /// Whether the set holds `state`.
    #[must_use]
    pub fn contains(&self, state: StateId) -> bool {
        let i = state.index();
        i < self.n_states && self.words[i / 64] & (1 << (i % 64)) != 0
    }

    /// Number of states in the set.
    #[must_use]
    pub fn len(&self) -> usize {
        count(&self.words)
    }

    /// Whether the set is empty (an inconsistent constraint).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.words.iter().all(|w| *w == 0)
    }

    /// Whether every state of `other` is in `self`.
    #[must_use]
    pub fn is_superset(&self, other: &StateSet) -> bool {
        superset(&self.words, &other.words)
    }

    /// The states, in id order.
    pub fn iter(&self) -> impl Iterator<Item = StateId> + '_ {
        iter_bits(&self.words)
    }

    /// The labels of the states, in id order.
    #[must_use]
    pub fn labels(&self, calculus: &Calculus) -> Vec<String> {
        self.iter().map(|s| calculus.label(s).to_owned()).collect()
    }
}

/// A label of `calculus`: exact, else the one label equal to it ignoring ASCII case (SparQ's
/// relation names are case-insensitive).
pub(crate) fn resolve_label(calculus: &Calculus, label: &str) -> crate::Result<StateId> {
    if let Ok(s) = calculus.state(label) {
        return Ok(s);
    }
    let mut found = calculus
        .states()
        .filter(|s| calculus.label(*s).eq_ignore_ascii_case(label));
    match (found.next(), found.next()) {
        (Some(s), None) => Ok(s),
        _ => calculus.state(label),
    }
}

pub(crate) fn fill_universal(words: &mut [u64], n_states: usize) {
    for (i, w) in words.iter_mut().enumerate() {
        let lo = i * 64;
        *w = if n_states >= lo + 64 {
            u64::MAX
        } else if n_states > lo {
            (1u64 << (n_states - lo)) - 1
        } else {
            0
        };
    }
}

pub(crate) fn count(words: &[u64]) -> usize {
    words.iter().map(|w| w.count_ones() as usize).sum()
}

pub(crate) fn superset(a: &[u64], b: &[u64]) -> bool {
    a.iter().zip(b).all(|(x, y)| y & !x == 0)
}

pub(crate) fn iter_bits(words: &[u64]) -> impl Iterator<Item = StateId> + '_ {
    words.iter().enumerate().flat_map(|(i, w)| {
        let mut w = *w;
        std::iter::from_fn(move || {
            if w == 0 {
                return None;
            }
            let b = w.trailing_zeros() as usize;
            w &= w - 1;
            // i * 64 + b < n_states ≤ u16::MAX + 1 (StateId is u16).
            Some(StateId(u16::try_from(i * 64 + b).unwrap_or(u16::MAX)))
        })
    })
}
