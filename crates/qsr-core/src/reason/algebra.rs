//! [`Algebra`]: a ternary calculus's composition and permutation tables as bitsets — what
//! algebraic closure needs of a calculus, and nothing else.

use crate::binary::set_ops::{SetOps, SetView};
use crate::calculus::{Calculus, StateId};
use crate::compose::{ComposeOptions, ComposeTable};
use crate::error::QsrError;
use crate::permute::{Permutation, PermutationTable};
use crate::reason::state_set::{StateSet, fill_universal, superset, words_for};

/// Which configurations the derived tables hold (see [`ComposeOptions::boundaries`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum TableScope {
    /// Every configuration, points exactly on boundaries included: closure never removes a
    /// relation that some configuration of distinct points realises (the default).
    #[default]
    Sound,
    /// Configurations in general position only (what SparQ's planar relations describe, and
    /// what noisy measurements produce with probability 1): closure prunes more, but may
    /// remove a relation that only a collinear or cocircular configuration realises.
    GeneralPosition,
}

/// The operation tables of one ternary calculus, as bitsets.
///
/// `compose(r, s)` is `{A,B:D}` given `{A,B:C} = r`, `{B,C:D} = s`; `permute(op, r)` is the
/// permuted relation (see [`Permutation`]). Built from the tables [`Calculus`] derives, or
/// from tables computed elsewhere ([`Algebra::from_tables`], e.g. SERGE's Algorithm 3 for a
/// learned calculus).
#[derive(Debug, Clone)]
pub struct Algebra {
    calculus: Calculus,
    words: usize,
    /// `compose[(r * n + s) * words ..][..words]`.
    compose: Vec<u64>,
    /// Union over `r` of `compose(r, s)`, per `s` (`{A,B:C}` unknown).
    compose_any_left: Vec<u64>,
    /// Union over `s` of `compose(r, s)`, per `r` (`{B,C:D}` unknown).
    compose_any_right: Vec<u64>,
    /// Union of everything: the composition of two unknown relations.
    compose_any_any: Vec<u64>,
    /// `permute[op][r * words ..][..words]`.
    permute: [Vec<u64>; 5],
    universal: Vec<u64>,
    /// Set composition by block tables, for calculi of at most 64 states (one word per set):
    /// closure's hot loop (see [`crate::binary::set_ops`]).
    ops: Option<std::sync::Arc<SetOps>>,
}

impl Algebra {
    /// The tables of `calculus`, derived by qsr-core (sound ones are computed once and cached
    /// by the calculus).
    ///
    /// # Errors
    /// [`QsrError::Unsupported`] for a calculus that is not ternary.
    pub fn of(calculus: &Calculus, scope: TableScope) -> crate::Result<Self> {
        match scope {
            TableScope::Sound => {
                let compose = calculus.compose_table()?.clone();
                let perms = Permutation::ALL
                    .iter()
                    .map(|op| calculus.permutation(*op).cloned())
                    .collect::<crate::Result<Vec<_>>>()?;
                Self::from_tables(calculus, &compose, &perms)
            }
            TableScope::GeneralPosition => {
                let compose = calculus.compose_table_with(&ComposeOptions::generic())?;
                let perms = Permutation::ALL
                    .iter()
                    .map(|op| calculus.permutation_with(*op, false))
                    .collect::<crate::Result<Vec<_>>>()?;
                Self::from_tables(calculus, &compose, &perms)
            }
        }
    }

    /// Tables computed elsewhere; `permutations` holds one table per operation, in any order.
    ///
    /// # Errors
    /// [`QsrError::Arity`] when a table's size differs from the calculus's state count or an
    /// operation is missing.
    pub fn from_tables(
        calculus: &Calculus,
        compose: &ComposeTable,
        permutations: &[PermutationTable],
    ) -> crate::Result<Self> {
        let n = calculus.n_states();
        if compose.n_states() != n {
            return Err(QsrError::Arity(format!(
                "compose table has {} states, calculus `{}` has {n}",
                compose.n_states(),
                calculus.name()
            )));
        }
        let words = words_for(n);
        let set_bits = |dst: &mut [u64], states: &[StateId]| {
            for t in states {
                dst[t.index() / 64] |= 1 << (t.index() % 64);
            }
        };
        let mut comp = vec![0u64; n * n * words];
        for r in calculus.states() {
            for s in calculus.states() {
                let at = (r.index() * n + s.index()) * words;
                set_bits(&mut comp[at..at + words], compose.get(r, s));
            }
        }
        let mut permute: [Vec<u64>; 5] = Default::default();
        for op in Permutation::ALL {
            let table = permutations
                .iter()
                .find(|t| t.op() == op)
                .ok_or_else(|| QsrError::Arity(format!("no `{op}` table given")))?;
            if table.n_states() != n {
                return Err(QsrError::Arity(format!(
                    "`{op}` table has {} states, calculus `{}` has {n}",
                    table.n_states(),
                    calculus.name()
                )));
            }
            let dst = &mut permute[op as usize];
            *dst = vec![0u64; n * words];
            for r in calculus.states() {
                let at = r.index() * words;
                set_bits(&mut dst[at..at + words], table.get(r));
            }
        }
        let mut any_left = vec![0u64; n * words];
        let mut any_right = vec![0u64; n * words];
        let mut any_any = vec![0u64; words];
        for r in 0..n {
            for s in 0..n {
                let src = &comp[(r * n + s) * words..][..words];
                for k in 0..words {
                    any_left[s * words + k] |= src[k];
                    any_right[r * words + k] |= src[k];
                    any_any[k] |= src[k];
                }
            }
        }
        let mut universal = vec![0u64; words];
        fill_universal(&mut universal, n);
        // Composition is all closure needs of the block tables; converse is not used.
        let ops = (words == 1).then(|| {
            let identity: Vec<Vec<StateId>> = calculus.states().map(|s| vec![s]).collect();
            std::sync::Arc::new(SetOps::new(compose, &identity, &vec![1; n]))
        });
        Ok(Self {
            calculus: calculus.clone(),
            words,
            compose: comp,
            compose_any_left: any_left,
            compose_any_right: any_right,
            compose_any_any: any_any,
            permute,
            universal,
            ops,
        })
    }

    /// The one-word block kernel, for calculi of at most 64 states.
    pub(crate) fn one_word(&self) -> Option<SetView<'_, 1>> {
        self.ops.as_ref().and_then(|o| o.view::<1>())
    }

    /// The calculus.
    #[must_use]
    pub fn calculus(&self) -> &Calculus {
        &self.calculus
    }

    /// Number of states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.calculus.n_states()
    }

    /// `{A,B:D}` given `{A,B:C} = r` and `{B,C:D} = s`.
    #[must_use]
    pub fn compose(&self, r: StateId, s: StateId) -> StateSet {
        let n = self.n_states();
        let at = (r.index() * n + s.index()) * self.words;
        StateSet::from_words(n, &self.compose[at..at + self.words])
    }

    /// The permuted relation when the original is `r`.
    #[must_use]
    pub fn permute(&self, op: Permutation, r: StateId) -> StateSet {
        let at = r.index() * self.words;
        StateSet::from_words(
            self.n_states(),
            &self.permute[op as usize][at..at + self.words],
        )
    }

    /// Bit words per set.
    pub(crate) fn words(&self) -> usize {
        self.words
    }

    /// The universal set's words.
    pub(crate) fn universal_words(&self) -> &[u64] {
        &self.universal
    }

    /// `permute(op, set)` of a one-word set (`words() == 1`).
    #[inline]
    pub(crate) fn permute_word(&self, op: Permutation, set: u64) -> u64 {
        let table = &self.permute[op as usize];
        let (mut rest, mut out) = (set, 0);
        while rest != 0 {
            out |= table
                .get(rest.trailing_zeros() as usize)
                .copied()
                .unwrap_or(0);
            rest &= rest - 1;
        }
        out
    }

    /// `out = permute(op, set)`.
    pub(crate) fn permute_into(&self, op: Permutation, set: &[u64], out: &mut [u64]) {
        out.fill(0);
        let table = &self.permute[op as usize];
        for r in crate::reason::state_set::iter_bits(set) {
            let src = &table[r.index() * self.words..][..self.words];
            for (o, s) in out.iter_mut().zip(src) {
                *o |= s;
            }
        }
    }

    /// `out = left ∘ right`, stopping early once `out ⊇ target` (then nothing in `target`
    /// can be removed). Returns whether `out` misses part of `target`: `target ∩ out` is a
    /// strict refinement.
    pub(crate) fn compose_refines(
        &self,
        left: &[u64],
        right: &[u64],
        target: &[u64],
        out: &mut [u64],
    ) -> bool {
        let w = self.words;
        let n = self.n_states();
        let or_into = |out: &mut [u64], src: &[u64]| {
            for (o, s) in out.iter_mut().zip(src) {
                *o |= s;
            }
        };
        let left_any = left == self.universal.as_slice();
        let right_any = right == self.universal.as_slice();
        if left_any && right_any {
            out.copy_from_slice(&self.compose_any_any);
            return !superset(out, target);
        }
        out.fill(0);
        if left_any {
            for s in crate::reason::state_set::iter_bits(right) {
                or_into(out, &self.compose_any_left[s.index() * w..][..w]);
                if superset(out, target) {
                    return false;
                }
            }
        } else if right_any {
            for r in crate::reason::state_set::iter_bits(left) {
                or_into(out, &self.compose_any_right[r.index() * w..][..w]);
                if superset(out, target) {
                    return false;
                }
            }
        } else {
            for r in crate::reason::state_set::iter_bits(left) {
                let row = &self.compose[r.index() * n * w..][..n * w];
                for s in crate::reason::state_set::iter_bits(right) {
                    or_into(out, &row[s.index() * w..][..w]);
                }
                if superset(out, target) {
                    return false;
                }
            }
        }
        !superset(out, target)
    }
}
