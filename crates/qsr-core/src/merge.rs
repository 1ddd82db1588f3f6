//! Merges from a finer calculus to a coarser one (e.g. EDC → double cross): a coarser
//! calculus's distribution is the sum of the finer one's over the merged states, so studies
//! sample the finest calculus once and merge (DESIGN §3).

use std::collections::BTreeSet;

use crate::calculus::{Calculus, StateId};
use crate::error::{QsrError, Result};

/// The state map `fine → coarse`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MergeMap {
    fine: String,
    coarse: String,
    n_coarse: usize,
    map: Vec<StateId>,
}

impl MergeMap {
    /// Checks on every probe point of `fine` that each fine state lies in one coarse state.
    pub(crate) fn compute(fine: &Calculus, coarse: &Calculus) -> Result<Self> {
        if fine.frame() != coarse.frame() {
            return Err(QsrError::Arity(format!(
                "cannot merge {} calculus `{}` into {} calculus `{}`",
                fine.frame().as_str(),
                fine.name(),
                coarse.frame().as_str(),
                coarse.name()
            )));
        }
        let mut met: Vec<BTreeSet<StateId>> = vec![BTreeSet::new(); fine.n_states()];
        for p in fine.probes() {
            met[fine.classify_normalised(p).index()].insert(coarse.classify_normalised(p));
        }
        let mut map = Vec::with_capacity(fine.n_states());
        for (i, set) in met.iter().enumerate() {
            let fine_state = fine.label(StateId(i as u16)).to_owned();
            match set.len() {
                1 => map.extend(set.iter().copied()),
                _ => {
                    return Err(QsrError::NotARefinement {
                        fine: fine.name().to_owned(),
                        coarse: coarse.name().to_owned(),
                        fine_state,
                        coarse_states: set.iter().map(|s| coarse.label(*s).to_owned()).collect(),
                    });
                }
            }
        }
        Ok(Self {
            fine: fine.name().to_owned(),
            coarse: coarse.name().to_owned(),
            n_coarse: coarse.n_states(),
            map,
        })
    }

    /// The coarse state of a fine state.
    #[must_use]
    pub fn apply(&self, fine: StateId) -> StateId {
        self.map[fine.index()]
    }

    /// Number of states of the coarse calculus.
    #[must_use]
    pub fn n_coarse(&self) -> usize {
        self.n_coarse
    }

    /// The map as a slice indexed by fine state.
    #[must_use]
    pub fn as_slice(&self) -> &[StateId] {
        &self.map
    }

    /// Sums a distribution over fine states into one over coarse states.
    ///
    /// # Errors
    /// [`QsrError::Arity`] when `p` does not have one entry per fine state.
    pub fn merge_distribution(&self, p: &[f64]) -> Result<Vec<f64>> {
        if p.len() != self.map.len() {
            return Err(QsrError::Arity(format!(
                "distribution has {} entries, `{}` has {} states",
                p.len(),
                self.fine,
                self.map.len()
            )));
        }
        let mut out = vec![0.0; self.n_coarse];
        for (v, s) in p.iter().zip(&self.map) {
            out[s.index()] += v;
        }
        Ok(out)
    }

    /// Names `(fine, coarse)`.
    #[must_use]
    pub fn names(&self) -> (&str, &str) {
        (&self.fine, &self.coarse)
    }
}

impl Calculus {
    /// The map from this (finer) calculus's states to `coarse`'s.
    ///
    /// # Errors
    /// [`QsrError::Arity`] when the frames differ, [`QsrError::NotARefinement`] when a state
    /// of `self` meets two states of `coarse`.
    pub fn merge_map(&self, coarse: &Calculus) -> Result<MergeMap> {
        MergeMap::compute(self, coarse)
    }
}
