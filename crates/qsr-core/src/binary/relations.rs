//! The relation arithmetic of a binary calculus on the tick grid: which relation two points
//! with given direction and headings are in. It is all the derivations (converse,
//! composition, neighbours) need of a calculus, so they take it, below
//! [`super::BinaryCalculus`], which caches what they derive.

use super::direction::DirectionPartition;

/// Which published family a binary calculus belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BinaryFamily {
    /// Oriented Point Relation Algebra (Moratz 2006; SparQ `opra-m`, GQR `opra1`…): two
    /// oriented points, each one's own heading cutting the plane into `4m` sectors. Relation
    /// `i_j`: the other point in sector `i` of this one, this one in sector `j` of the
    /// other's; `s_k`: same position, the other's heading in sector `k`.
    Opra,
    /// STAR (Renz & Mitra 2004) as SparQ's revised star calculus: the direction from one
    /// point to the other in `m` half-open sectors about a reference direction *shared by all
    /// points*; `eq` for the same position.
    Star,
}

/// A binary calculus's family, partition of directions and number of relations.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Relations {
    pub(crate) family: BinaryFamily,
    pub(crate) partition: DirectionPartition,
    pub(crate) n_states: usize,
}

impl Relations {
    /// Number of relations.
    pub(crate) fn n_states(&self) -> usize {
        self.n_states
    }

    /// The partition of directions.
    pub(crate) fn partition(&self) -> DirectionPartition {
        self.partition
    }

    /// Whether each point has its own heading (OPRA) rather than a shared one (STAR).
    pub(crate) fn is_oriented(&self) -> bool {
        self.family == BinaryFamily::Opra
    }

    /// The relation of the distinct-position configuration where the direction from X to Y
    /// is `dir` ticks and the headings are `hx`, `hy` (ticks, `per_unit` ticks per unit).
    pub(crate) fn relation_distinct(
        &self,
        dir: usize,
        hx: usize,
        hy: usize,
        per_unit: usize,
    ) -> usize {
        let turn = 2 * self.partition.m() * per_unit;
        let half = turn / 2;
        let sec = |t: usize| self.partition.sector_of_tick(t, per_unit);
        match self.family {
            BinaryFamily::Opra => {
                let n = 4 * self.partition.m();
                sec(dir + turn - hx) * n + sec(dir + half + 2 * turn - hy)
            }
            BinaryFamily::Star => sec(dir + turn - hx),
        }
    }

    /// The relation of two points at the same position with headings `hx`, `hy` (ticks).
    pub(crate) fn relation_same(&self, hx: usize, hy: usize, per_unit: usize) -> usize {
        let turn = 2 * self.partition.m() * per_unit;
        match self.family {
            BinaryFamily::Opra => {
                let n = 4 * self.partition.m();
                n * n + self.partition.sector_of_tick(hy + turn - hx, per_unit)
            }
            BinaryFamily::Star => self.partition.m(),
        }
    }
}
