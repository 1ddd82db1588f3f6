//! The composition table `{A,B:C} ∘ {B,C:D} → {A,B:D}` (thesis §3.3.2, Algorithm 3; SparQ's
//! composition with its A, B, C, D).
//!
//! Algorithm 3 maps every cell of `{DE:F}` and every cell of `{EF:G}` into frame DE. We do
//! the same with points instead of cells: for every pair of states `(r, s)` we draw `C` from
//! a pool of probe points of `r` and `P` from a pool of `s` (both pools come from the
//! boundary-, vertex- and log-radially-biased probe stream of [`crate::coverage`], so thin
//! and unbounded states are represented), place `D` at `P` in the frame of `(B, C)`, and
//! record the state of `D` in the frame of `(A, B)`. Every `(r, s)` pair gets the same number
//! of draws however small `r` and `s` are. Configurations in which two of A, B, C, D
//! coincide are left out (SparQ's `dou`/`tri`-like relations; distinct landmarks never
//! produce them); collinear configurations are kept, since boundaries belong to states.
//!
//! Two kinds of configuration are used. Sampled ones are dropped when C, P or D lies within
//! [`crate::ROUNDING_MARGIN`] (relative) of a circle or a raster edge: there f64 rounding,
//! not geometry, decides the side, and keeping them adds entries no exact configuration has
//! (and makes the table grow without end as the samples grow). Configurations exactly *on*
//! boundaries are added from a dyadic lattice (multiples of 1/8 for C and P) on which the
//! placement arithmetic is exact.
//!
//! **Guarantee.** Every entry is witnessed by a real configuration (no entry is invented),
//! and the table is complete for every configuration whose `C` and `P` lie within the probe
//! pools' reach. Completeness is checked, not assumed: the test suite draws 10^6 independent
//! configurations per built-in calculus (uniform, log-radial and on-boundary) and finds no
//! `{A,B:D}` missing from the table, and the double cross and flip-flop tables agree with
//! SparQ's published ones on planar relations. Rows are computed in parallel with one seeded
//! generator per row, so the table does not depend on the thread count.

use nalgebra::Point2;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

use crate::permute::coincident;
use crate::sampled::{DERIVED_SEED, Sampled};
use crate::state::StateId;

/// Sampling options for [`ComposeTable`] and [`crate::PermutationTable`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ComposeOptions {
    /// Configurations drawn per `(r, s)` pair.
    pub samples_per_pair: usize,
    /// Seed of the draws.
    pub seed: u64,
    /// Include configurations with a point exactly on a boundary (the default, so the table
    /// is sound for *every* configuration). Without them the table describes configurations
    /// in general position only — what noisy measurements produce with probability 1, and
    /// what SparQ's tables give for planar relations.
    pub boundaries: bool,
}

impl Default for ComposeOptions {
    fn default() -> Self {
        Self {
            samples_per_pair: 20_000,
            seed: DERIVED_SEED ^ 0xc0de,
            boundaries: true,
        }
    }
}

impl ComposeOptions {
    /// The defaults, restricted to configurations in general position.
    #[must_use]
    pub fn generic() -> Self {
        Self {
            boundaries: false,
            ..Self::default()
        }
    }
}

/// The states whose flag is set, in id order.
fn states_hit(hit: &[bool]) -> Vec<StateId> {
    hit.iter()
        .enumerate()
        .filter(|(_, h)| **h)
        .map(|(i, _)| StateId(i as u16))
        .collect()
}

/// One configuration placed: C in the AB frame, P the position of D in the BC frame, whether
/// exact (on the lattice) → the states `(r, s, t)` of `{AB:C}`, `{BC:D}`, `{AB:D}`, or
/// `None` for a configuration skipped (coincident points, near a boundary).
trait Place: Fn(Point2<f64>, Point2<f64>, bool) -> Option<(usize, usize, usize)> {}

impl<F: Fn(Point2<f64>, Point2<f64>, bool) -> Option<(usize, usize, usize)>> Place for F {}

/// What `place` gives for C and P on the dyadic lattice `(i/8, j/8)`, `i` in −24..=24 and
/// `j` in −16..=24, each C's placements sorted and deduplicated: C and P on it make every
/// product and sum of the placement exact.
fn exact_placements(place: &(dyn Place + Sync)) -> Vec<Vec<(usize, usize, usize)>> {
    let lattice: Vec<Point2<f64>> = (-24..=24)
        .flat_map(|i| (-16..=24).map(move |j| Point2::new(f64::from(i) / 8.0, f64::from(j) / 8.0)))
        .collect();
    lattice
        .par_iter()
        .map(|c| {
            let mut found = Vec::new();
            for p in &lattice {
                if let Some(rst) = place(*c, *p, true) {
                    found.push(rst);
                }
            }
            found.sort_unstable();
            found.dedup();
            found
        })
        .collect()
}

/// `table[r][s]` = the states `{A,B:D}` can take given `{A,B:C} = r` and `{B,C:D} = s`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ComposeTable {
    table: Vec<Vec<Vec<StateId>>>,
}

impl ComposeTable {
    pub(crate) fn compute(calculus: &impl Sampled, options: &ComposeOptions) -> Self {
        let n = calculus.n_states();
        let pools = calculus.pools();
        let partition = calculus.partition();
        let a = Point2::new(0.0, 0.0);
        let b = Point2::new(0.0, 1.0);
        // One configuration: C in the AB frame, P the position of D in the BC frame.
        let place =
            |c: Point2<f64>, p: Point2<f64>, exact: bool| -> Option<(usize, usize, usize)> {
                if coincident(&c, &a) || coincident(&c, &b) {
                    return None;
                }
                let e = c - b;
                // D = B + y·e + x·(e_y, −e_x): P placed in the frame (B, C), no division.
                let d = Point2::new(b.x + p.y * e.x + p.x * e.y, b.y + p.y * e.y - p.x * e.x);
                if coincident(&d, &a) || coincident(&d, &b) || coincident(&d, &c) {
                    return None;
                }
                if !exact || !options.boundaries {
                    let scale_d = d.coords.norm() + e.norm() * p.coords.norm() + 1.0;
                    let lines = !options.boundaries;
                    if partition.near_boundary(&c, c.coords.norm(), lines)
                        || partition.near_boundary(&p, p.coords.norm(), lines)
                        || partition.near_boundary(&d, scale_d, lines)
                    {
                        return None;
                    }
                }
                Some((
                    calculus.classify_normalised(&c).index(),
                    calculus.classify_normalised(&p).index(),
                    calculus.classify_normalised(&d).index(),
                ))
            };
        let mut hits: Vec<Vec<Vec<bool>>> = (0..n)
            .into_par_iter()
            .map(|r| {
                let mut rng =
                    ChaCha8Rng::seed_from_u64(options.seed ^ (r as u64).wrapping_mul(0x9e37_79b9));
                let pool_r = &pools[r];
                let mut row = vec![vec![false; n]; n];
                for (s, hit) in row.iter_mut().enumerate() {
                    let pool_s = &pools[s];
                    if pool_r.is_empty() || pool_s.is_empty() {
                        continue;
                    }
                    for _ in 0..options.samples_per_pair {
                        let (c, p) = (pool_r.draw(&mut rng), pool_s.draw(&mut rng));
                        if let Some((_, _, t)) = place(c, p, false) {
                            hit[t] = true;
                        }
                    }
                }
                row
            })
            .collect();
        // Exact configurations on boundaries: dyadic C and P (multiples of 1/8) make every
        // product and sum above exact, so points exactly on lines, on the unit circles' dyadic
        // points and on vertices count with the spec's zero-set rule.
        let exact = exact_placements(&place);
        for (r, s, t) in exact.into_iter().flatten() {
            hits[r][s][t] = true;
        }
        let table = hits
            .into_iter()
            .map(|row| row.into_iter().map(|hit| states_hit(&hit)).collect())
            .collect();
        Self { table }
    }

    /// A table computed elsewhere (e.g. SERGE's cell-by-cell Algorithm 3 for a learned
    /// calculus): `rows[r][s]` lists the possible `{A,B:D}`. Each list is sorted and
    /// deduplicated here.
    ///
    /// # Errors
    /// [`crate::QsrError::Arity`] when the table is not `n × n` or names a state `≥ n`.
    pub fn from_rows(mut rows: Vec<Vec<Vec<StateId>>>) -> crate::Result<Self> {
        let n = rows.len();
        for (r, row) in rows.iter_mut().enumerate() {
            if row.len() != n {
                return Err(crate::QsrError::Arity(format!(
                    "compose table row {r} has {} columns, expected {n}",
                    row.len()
                )));
            }
            for entry in row.iter_mut() {
                if let Some(bad) = entry.iter().find(|t| t.index() >= n) {
                    return Err(crate::QsrError::Arity(format!(
                        "compose table entry names state {bad}, the table has {n} states"
                    )));
                }
                entry.sort_unstable();
                entry.dedup();
            }
        }
        Ok(Self { table: rows })
    }

    /// A table whose entries are already sorted, deduplicated and in range (built by this
    /// crate's own derivations).
    pub(crate) fn from_sorted_rows(rows: Vec<Vec<Vec<StateId>>>) -> Self {
        Self { table: rows }
    }

    /// The possible `{A,B:D}` for `{A,B:C} = r`, `{B,C:D} = s` (sorted).
    #[must_use]
    pub fn get(&self, r: StateId, s: StateId) -> &[StateId] {
        &self.table[r.index()][s.index()]
    }

    /// Number of states.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.table.len()
    }

    /// Total number of `(r, s, t)` entries.
    #[must_use]
    pub fn n_entries(&self) -> usize {
        self.table.iter().flatten().map(Vec::len).sum()
    }
}
