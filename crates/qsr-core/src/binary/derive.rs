//! Exact derivation of a binary calculus's converse, composition and neighbours by
//! enumerating configurations on the tick grid (see [`crate::binary`] for why the grid is
//! exhaustive).

use rayon::prelude::*;

use super::relations::Relations;
use crate::calculus::StateId;
use crate::compose::ComposeTable;
use crate::neighbours::NeighbourGraph;

/// Bumped whenever the derivation changes what it produces: part of the on-disk cache key.
pub(crate) const DERIVATION_VERSION: u32 = 1;

/// The converse of each base relation: `X r Y ⇒ Y conv(r) X`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ConverseTable {
    rows: Vec<Vec<StateId>>,
}

impl ConverseTable {
    /// A table from rows (`rows[r]` lists the converses of `r`; sorted and deduplicated).
    ///
    /// # Errors
    /// [`crate::QsrError::Arity`] when a row names a relation `≥ rows.len()`.
    pub fn from_rows(mut rows: Vec<Vec<StateId>>) -> crate::Result<Self> {
        let n = rows.len();
        for row in &mut rows {
            if let Some(bad) = row.iter().find(|t| t.index() >= n) {
                return Err(crate::QsrError::Arity(format!(
                    "converse table names relation {bad}, the table has {n} relations"
                )));
            }
            row.sort_unstable();
            row.dedup();
        }
        Ok(Self { rows })
    }

    /// The converses of `r` (one for OPRA and STAR; sorted).
    #[must_use]
    pub fn get(&self, r: StateId) -> &[StateId] {
        &self.rows[r.index()]
    }

    /// All rows in relation order.
    #[must_use]
    pub fn rows(&self) -> &[Vec<StateId>] {
        &self.rows
    }

    /// Number of relations.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.rows.len()
    }
}

/// Converse and composition together (they are cached together on disk).
#[derive(Debug, Clone)]
pub(crate) struct BinaryTables {
    pub(crate) converse: ConverseTable,
    pub(crate) compose: ComposeTable,
}

/// A dense `n × n` table of relation bitsets.
struct BitTable {
    n: usize,
    words: usize,
    bits: Vec<u64>,
}

impl BitTable {
    fn new(n: usize) -> Self {
        let words = n.div_ceil(64);
        Self {
            n,
            words,
            bits: vec![0; n * n * words],
        }
    }

    #[inline(always)]
    fn set(&mut self, r: usize, s: usize, t: usize) {
        self.bits[(r * self.n + s) * self.words + t / 64] |= 1u64 << (t % 64);
    }

    fn merge(mut self, other: Self) -> Self {
        for (a, b) in self.bits.iter_mut().zip(other.bits) {
            *a |= b;
        }
        self
    }

    fn entry(&self, r: usize, s: usize) -> Vec<StateId> {
        let base = (r * self.n + s) * self.words;
        let mut out = Vec::new();
        for w in 0..self.words {
            let mut word = self.bits[base + w];
            while word != 0 {
                let b = word.trailing_zeros() as usize;
                out.push(state_id(w * 64 + b));
                word &= word - 1;
            }
        }
        out
    }
}

fn state_id(i: usize) -> StateId {
    StateId(u16::try_from(i).unwrap_or(u16::MAX))
}

/// The triangles `(t1, t2)` of turning angles (ticks) between the edge directions
/// A→B, B→C, C→A: counter-clockwise (all turns in `(0, π)`, summing to 2π), clockwise (all
/// in `(π, 2π)`, summing to 4π) or collinear (turns `0, π, π` in some order). Every such
/// triple is realised by three distinct points, and every three distinct points give one.
fn triangles(turn: usize) -> Vec<(usize, usize)> {
    let half = turn / 2;
    let mut out = Vec::new();
    for t1 in 0..turn {
        for t2 in 0..turn {
            let t3 = (2 * turn - t1 - t2) % turn;
            let proper = |lo: usize, hi: usize| [t1, t2, t3].iter().all(|t| lo < *t && *t < hi);
            let ccw = proper(0, half) && t1 + t2 + t3 == turn;
            let cw = proper(half, turn) && t1 + t2 + t3 == 2 * turn;
            // Collinear: one point between the other two, where the path turns back (π)
            // twice and goes straight on (0) once. A turn of π with the other two splitting
            // π otherwise is *not* a triangle: interior angle 0 forces the others to 0 and π.
            let collinear = matches!(
                (
                    t1 == 0,
                    t2 == 0,
                    t3 == 0,
                    t1 == half,
                    t2 == half,
                    t3 == half
                ),
                (true, false, false, false, true, true)
                    | (false, true, false, true, false, true)
                    | (false, false, true, true, true, false)
            );
            if ccw || cw || collinear {
                out.push((t1, t2));
            }
        }
    }
    out
}

/// Parts the composition's directions are split into, each with its own bitset table.
pub(crate) const PARTS: usize = 4;

/// Converse and composition of `c` on a grid of `per_unit` ticks per unit.
pub(crate) fn derive_tables(c: &Relations, per_unit: usize) -> BinaryTables {
    BinaryTables {
        converse: derive_converse(c, per_unit),
        compose: derive_compose(c, per_unit),
    }
}

/// Grid steps of the composition derivation (for the cost estimate): directions of A→B ×
/// triangles × B's and C's headings, plus the coincidences.
pub(crate) fn compose_steps(c: &Relations, per_unit: usize) -> u64 {
    let turn = 2 * c.partition().m() * per_unit;
    let headings = if c.is_oriented() { turn as u64 } else { 1 };
    let half = (turn / 2) as u64;
    // Proper triangles: about half² per orientation; collinear ones are few.
    let triangles = half * half + 3;
    turn as u64 * (triangles + 3) * headings * headings
}

/// The composition of `c` on a grid of `per_unit` ticks per unit.
///
/// Headings: A's is 0 (rotation invariance); B's and C's run over the grid for OPRA and are
/// 0 for STAR (its reference direction is shared).
pub(crate) fn derive_compose(c: &Relations, per_unit: usize) -> ComposeTable {
    let n = c.n_states();
    let turn = 2 * c.partition().m() * per_unit;
    let half = turn / 2;
    let headings = if c.is_oriented() { turn } else { 1 };
    let tri = triangles(turn);
    let d = |dir: usize, hx: usize, hy: usize| c.relation_distinct(dir, hx, hy, per_unit);
    let same = |hx: usize, hy: usize| c.relation_same(hx, hy, per_unit);

    // One table per part of a fixed split of the directions of A→B (so memory, and the
    // estimate that may refuse the derivation, do not depend on the thread count), merged by
    // OR: the result does not either.
    let chunk = turn.div_ceil(PARTS);
    let alphas: Vec<usize> = (0..turn).collect();
    let mut table = alphas
        .par_chunks(chunk)
        .map(|chunk| {
            let mut t = BitTable::new(n);
            for &alpha in chunk {
                for &(t1, t2) in &tri {
                    let beta = alpha + t1; // B→C
                    let gamma = beta + t2; // C→A
                    for hb in 0..headings {
                        let r = d(alpha, 0, hb);
                        for hc in 0..headings {
                            t.set(r, d(beta, hb, hc), d(gamma + half, 0, hc));
                        }
                    }
                }
                // Coincidences with this direction: A = B ≠ C (alpha is A→C), B = C ≠ A
                // (alpha is A→B = A→C), A = C ≠ B (alpha is A→B).
                for hb in 0..headings {
                    for hc in 0..headings {
                        t.set(same(0, hb), d(alpha, hb, hc), d(alpha, 0, hc));
                        t.set(d(alpha, 0, hb), same(hb, hc), d(alpha, 0, hc));
                        t.set(d(alpha, 0, hb), d(alpha + half, hb, hc), same(0, hc));
                    }
                }
            }
            t
        })
        .reduce(|| BitTable::new(n), BitTable::merge);
    for hb in 0..headings {
        for hc in 0..headings {
            table.set(same(0, hb), same(hb, hc), same(0, hc));
        }
    }
    let rows: Vec<Vec<Vec<StateId>>> = (0..n)
        .map(|r| (0..n).map(|s| table.entry(r, s)).collect())
        .collect();
    ComposeTable::from_sorted_rows(rows)
}

/// The converse of `c`: every direction and heading of B on the grid, and coincidence.
pub(crate) fn derive_converse(c: &Relations, per_unit: usize) -> ConverseTable {
    let n = c.n_states();
    let turn = 2 * c.partition().m() * per_unit;
    let half = turn / 2;
    let headings = if c.is_oriented() { turn } else { 1 };
    let d = |dir: usize, hx: usize, hy: usize| c.relation_distinct(dir, hx, hy, per_unit);
    let mut converse = vec![Vec::new(); n];
    for alpha in 0..turn {
        for hb in 0..headings {
            converse[d(alpha, 0, hb)].push(state_id(d(alpha + half, hb, 0)));
        }
    }
    for hb in 0..headings {
        converse[c.relation_same(0, hb, per_unit)].push(state_id(c.relation_same(hb, 0, per_unit)));
    }
    for row in &mut converse {
        row.sort_unstable();
        row.dedup();
    }
    ConverseTable { rows: converse }
}

/// Conceptual neighbours: relations whose configurations touch under a continuous motion.
///
/// Distinct positions: the relation depends on two free angles, `a` (Y seen from X, against
/// X's heading) and `b` (X seen from Y, against Y's); one grid step in either or both moves
/// between relations whose closures meet. Moving Y onto X keeps `a`, `b` and leaves the
/// headings differing by `a − b + π`: the same-position relations at that difference (and a
/// step either side when the difference ranges over an open interval) are neighbours.
pub(crate) fn derive_neighbours(c: &Relations, per_unit: usize) -> NeighbourGraph {
    let n = c.n_states();
    let turn = 2 * c.partition().m() * per_unit;
    let half = turn / 2;
    let p = c.partition();
    let mut adj = vec![vec![false; n]; n];
    let mut link = |x: usize, y: usize| {
        if x != y {
            adj[x][y] = true;
            adj[y][x] = true;
        }
    };
    let steps = [turn - 1, 0, 1];
    if c.is_oriented() {
        // X's heading 0, direction X→Y = a, Y's heading chosen so that X is at b from it.
        let rel = |a: usize, b: usize| {
            c.relation_distinct(a, 0, (a + half + 2 * turn - b) % turn, per_unit)
        };
        for a in 0..turn {
            for b in 0..turn {
                let r = rel(a, b);
                for da in steps {
                    for db in steps {
                        link(r, rel(a + da, b + db));
                    }
                }
                let diff = (a + half + 2 * turn - b) % turn; // Y's heading − X's
                link(r, c.relation_same(0, diff, per_unit));
                let open = !(p.is_ray(p.sector_of_tick(a, per_unit))
                    && p.is_ray(p.sector_of_tick(b, per_unit)));
                if open {
                    link(r, c.relation_same(0, diff + 1, per_unit));
                    link(r, c.relation_same(0, diff + turn - 1, per_unit));
                }
            }
        }
        for h in 0..turn {
            link(
                c.relation_same(0, h, per_unit),
                c.relation_same(0, h + 1, per_unit),
            );
        }
    } else {
        for a in 0..turn {
            let r = c.relation_distinct(a, 0, 0, per_unit);
            link(r, c.relation_distinct(a + 1, 0, 0, per_unit));
            link(r, c.relation_same(0, 0, per_unit));
        }
    }
    NeighbourGraph::from_adjacency(n, &adj)
}
