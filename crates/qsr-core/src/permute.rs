//! The five permutation ("unitary") operations of a ternary relation (SparQ semantics; see
//! `shared/oracles/README.md`):
//!
//! | operation | from `{A, B : C} = r` it gives |
//! |---|---|
//! | inverse | `{B, A : C}` |
//! | shortcut | `{A, C : B}` |
//! | shortcut-inverse | `{C, A : B}` |
//! | homing | `{B, C : A}` |
//! | homing-inverse | `{C, B : A}` |
//!
//! The table maps each state to the *set* of states the permuted relation can take. By
//! default configurations exactly on boundaries count (so the table is sound for every
//! configuration, and e.g. the double cross's `inverse(left-front)` holds `right-middle`:
//! C exactly on the perpendicular at B is "front" of A→B but "middle" of B→A under the
//! zero-set rule); [`Calculus::permutation_with`](crate::Calculus::permutation_with) with
//! `boundaries = false` gives the table of configurations in general position. It is
//! computed by classifying the permuted triplet for every probe point of the calculus (with
//! A = (0, 0), B = (0, 1), C the probe; see [`crate::coverage`]), so it is sound for every
//! configuration the probes reach, including points exactly on boundaries. Configurations
//! within rounding distance of a circle (see [`crate::ROUNDING_MARGIN`]) are dropped, since
//! there f64 rounding rather than geometry picks the side. Configurations
//! with coincident points (C on A or on B) are left out: SparQ gives them relations of their
//! own (`4_a`, `b_4`, `s`, `e`, ...), and no pair of distinct landmarks produces them.

use std::fmt;
use std::str::FromStr;

use nalgebra::Point2;
use rayon::prelude::*;

use crate::error::QsrError;
use crate::frame::TernaryFrame;
pub(crate) use crate::frame::coincident;
use crate::sampled::Sampled;
use crate::state::StateId;

/// One of the five permutation operations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Permutation {
    /// `{A,B:C} → {B,A:C}`.
    Inverse = 0,
    /// `{A,B:C} → {A,C:B}`.
    Shortcut = 1,
    /// `{A,B:C} → {C,A:B}`.
    ShortcutInverse = 2,
    /// `{A,B:C} → {B,C:A}`.
    Homing = 3,
    /// `{A,B:C} → {C,B:A}`.
    HomingInverse = 4,
}

impl Permutation {
    /// All five, in declaration order.
    pub const ALL: [Permutation; 5] = [
        Self::Inverse,
        Self::Shortcut,
        Self::ShortcutInverse,
        Self::Homing,
        Self::HomingInverse,
    ];

    /// The kebab-case name (`"shortcut-inverse"`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Inverse => "inverse",
            Self::Shortcut => "shortcut",
            Self::ShortcutInverse => "shortcut-inverse",
            Self::Homing => "homing",
            Self::HomingInverse => "homing-inverse",
        }
    }

    /// Reorders `(a, b, c)` into the permuted `(reference 1, reference 2, located)`.
    #[must_use]
    pub fn apply<T>(self, a: T, b: T, c: T) -> (T, T, T) {
        match self {
            Self::Inverse => (b, a, c),
            Self::Shortcut => (a, c, b),
            Self::ShortcutInverse => (c, a, b),
            Self::Homing => (b, c, a),
            Self::HomingInverse => (c, b, a),
        }
    }
}

/// The six orderings of `(a, b, c)`: the identity, then each operation of
/// [`Permutation::ALL`] applied, in that order.
#[must_use]
pub fn all_orderings<T: Copy>(a: T, b: T, c: T) -> [(T, T, T); 6] {
    let [i, s, si, h, hi] = Permutation::ALL.map(|op| op.apply(a, b, c));
    [(a, b, c), i, s, si, h, hi]
}

impl fmt::Display for Permutation {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Permutation {
    type Err = QsrError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Self::ALL
            .into_iter()
            .find(|p| p.name() == s)
            .ok_or_else(|| QsrError::UnknownOperation { name: s.to_owned() })
    }
}

/// The result sets of one permutation operation, indexed by state.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PermutationTable {
    op: Permutation,
    table: Vec<Vec<StateId>>,
}

impl PermutationTable {
    pub(crate) fn compute(calculus: &impl Sampled, op: Permutation, boundaries: bool) -> Self {
        let n = calculus.n_states();
        let a = Point2::new(0.0, 0.0);
        let b = Point2::new(0.0, 1.0);
        let hits = calculus
            .probes()
            .par_chunks(8192)
            .map(|chunk| {
                let mut hit = vec![vec![false; n]; n];
                for c in chunk {
                    if coincident(c, &a)
                        || coincident(c, &b)
                        || calculus
                            .partition()
                            .near_boundary(c, c.coords.norm(), !boundaries)
                    {
                        continue;
                    }
                    let r = calculus.classify_normalised(c);
                    let (p, q, located) = op.apply(a, b, *c);
                    if let Ok(frame) = TernaryFrame::new(p, q) {
                        let z = frame.to_normalised(&located);
                        let scale = z.coords.norm() + c.coords.norm() + 1.0;
                        if !calculus.partition().near_boundary(&z, scale, !boundaries) {
                            let s = calculus.classify_normalised(&z);
                            hit[r.index()][s.index()] = true;
                        }
                    }
                }
                hit
            })
            .reduce(|| vec![vec![false; n]; n], or_matrix);
        let table = hits
            .into_iter()
            .map(|row| {
                row.iter()
                    .enumerate()
                    .filter(|(_, h)| **h)
                    .map(|(i, _)| StateId(i as u16))
                    .collect()
            })
            .collect();
        Self { op, table }
    }

    /// Which operation this is.
    #[must_use]
    pub fn op(&self) -> Permutation {
        self.op
    }

    /// The states the permuted relation can take when the original is `r` (sorted).
    #[must_use]
    pub fn get(&self, r: StateId) -> &[StateId] {
        &self.table[r.index()]
    }

    /// All rows in state order.
    #[must_use]
    pub fn rows(&self) -> &[Vec<StateId>] {
        &self.table
    }

    /// Number of states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.table.len()
    }

    /// A table computed elsewhere: `rows[r]` lists the states of the permuted relation when
    /// the original is `r`. Each row is sorted and deduplicated here.
    ///
    /// # Errors
    /// [`QsrError::Arity`] when a row names a state `≥ rows.len()`.
    pub fn from_rows(op: Permutation, mut rows: Vec<Vec<StateId>>) -> crate::Result<Self> {
        let n = rows.len();
        for row in &mut rows {
            if let Some(bad) = row.iter().find(|t| t.index() >= n) {
                return Err(QsrError::Arity(format!(
                    "`{op}` table names state {bad}, the table has {n} states"
                )));
            }
            row.sort_unstable();
            row.dedup();
        }
        Ok(Self { op, table: rows })
    }
}

pub(crate) fn or_matrix(mut x: Vec<Vec<bool>>, y: Vec<Vec<bool>>) -> Vec<Vec<bool>> {
    for (rx, ry) in x.iter_mut().zip(y) {
        for (a, b) in rx.iter_mut().zip(ry) {
            *a |= b;
        }
    }
    x
}
