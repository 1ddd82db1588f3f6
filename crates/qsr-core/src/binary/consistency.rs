//! [`solve_binary`]: consistency of a binary network by backtracking search over its base
//! relations with path consistency at every node — GQR's `consistency` mode — within a node
//! budget.
//!
//! Each node picks the edge with the fewest relations left (ties: the lower pair), tries its
//! relations in order of weight (GQR's: lighter first) and propagates that choice alone
//! (an undo trail restores the matrix on backtracking). An atomic, path-consistent network is
//! reported as a solution: for calculi where path consistency decides atomic networks (the
//! point algebra, Allen's interval algebra, RCC-8) that is consistency; for others (OPRA,
//! cardinal directions of regions) it is what GQR reports too, "algebraically closed".

use super::closure::{Propagator, words_error};
use super::network::BinaryNetwork;
use super::set_ops::SetOps;

/// Options of [`solve_binary`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SolveOptions {
    /// The most search nodes (relations tried) before the answer is [`SolveOutcome::Unknown`].
    pub max_nodes: u64,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            max_nodes: 1_000_000,
        }
    }
}

/// The answer of [`solve_binary`].
#[derive(Debug, Clone)]
pub enum SolveOutcome {
    /// An atomic, path-consistent refinement of the network.
    Consistent(BinaryNetwork),
    /// No refinement is path-consistent: the network is inconsistent.
    Inconsistent,
    /// The budget ran out before an answer.
    Unknown,
}

/// The answer and the work it took.
#[derive(Debug, Clone)]
pub struct BinarySolution {
    /// The answer.
    pub outcome: SolveOutcome,
    /// Search nodes (relations tried on an edge).
    pub nodes: u64,
}

/// Searches for an atomic path-consistent refinement (see the module docs).
///
/// ```
/// use qsr_core::binary::{BinaryAlgebra, BinaryNetwork, SolveOptions, SolveOutcome, solve_binary};
/// let pa = BinaryAlgebra::from_gqr_tables(
///     "point",
///     "< :: >\n= :: =\n> :: <\n",
///     "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n\
///      = : < :: ( < )\n= : = :: ( = )\n= : > :: ( > )\n\
///      > : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n",
///     "=",
///     None,
/// )?;
/// let net = BinaryNetwork::from_sparq_str(&pa, "((a (< =) b) (b (< =) c) (c (< >) a))")?;
/// let found = solve_binary(net, &SolveOptions::default())?;
/// let SolveOutcome::Consistent(s) = found.outcome else { panic!("consistent") };
/// assert!(s.is_atomic());
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
///
/// # Errors
/// As [`super::close_binary`].
pub fn solve_binary(
    network: BinaryNetwork,
    options: &SolveOptions,
) -> crate::Result<BinarySolution> {
    let algebra = network.algebra().clone();
    let ops = algebra.ops()?;
    macro_rules! run {
        ($($w:literal)*) => {
            match ops.words() {
                $($w => solve_with::<$w>(network, ops, options),)*
                _ => Err(words_error(&algebra)),
            }
        };
    }
    run!(1 2 3 4 5 6 8 12 16 24 32)
}

/// One level of the search: the edge, its relations still to try, the trail before it.
struct Level {
    i: usize,
    j: usize,
    candidates: Vec<usize>,
    mark: usize,
}

fn solve_with<const W: usize>(
    mut network: BinaryNetwork,
    ops: &SetOps,
    options: &SolveOptions,
) -> crate::Result<BinarySolution> {
    let Some(view) = ops.view::<W>() else {
        return Err(words_error(network.algebra()));
    };
    let mut prop = Propagator::<W>::new(&network, view);
    let done = |outcome, nodes| Ok(BinarySolution { outcome, nodes });
    if prop.start(ops.universal_closed()).is_err() {
        return done(SolveOutcome::Inconsistent, 0);
    }
    prop.trail = Some(Vec::new());
    let mut stack: Vec<Level> = Vec::new();
    let mut nodes = 0u64;
    let mut descend = true;
    loop {
        if descend {
            let Some((i, j)) = choose_edge(&prop) else {
                prop.write_back(&mut network);
                return done(SolveOutcome::Consistent(network), nodes);
            };
            let mut candidates: Vec<usize> = crate::reason::iter_bits(&prop.m[i * prop.n + j])
                .map(crate::calculus::StateId::index)
                .collect();
            // Tried from the back: heaviest first in the list, so the lightest is popped first.
            candidates.sort_by_key(|&r| (std::cmp::Reverse(view.weights[r]), std::cmp::Reverse(r)));
            let mark = prop.trail.as_ref().map_or(0, Vec::len);
            stack.push(Level {
                i,
                j,
                candidates,
                mark,
            });
        }
        let Some(level) = stack.last_mut() else {
            return done(SolveOutcome::Inconsistent, nodes);
        };
        let (i, j, mark) = (level.i, level.j, level.mark);
        prop.undo_to(mark);
        let Some(r) = level.candidates.pop() else {
            stack.pop();
            descend = false;
            continue;
        };
        nodes += 1;
        if nodes > options.max_nodes {
            return done(SolveOutcome::Unknown, nodes);
        }
        let mut single = [0u64; W];
        single[r / 64] |= 1 << (r % 64);
        prop.put(i, j, single);
        prop.enqueue(i, j);
        descend = prop.run().is_ok();
    }
}

/// The edge `i < j` with the fewest relations among those with two or more.
fn choose_edge<const W: usize>(prop: &Propagator<'_, W>) -> Option<(usize, usize)> {
    let n = prop.n;
    let mut best: Option<(u32, usize, usize)> = None;
    for i in 0..n {
        for j in i + 1..n {
            let size: u32 = prop.m[i * n + j].iter().map(|w| w.count_ones()).sum();
            if size > 1 && best.is_none_or(|(b, _, _)| size < b) {
                best = Some((size, i, j));
                if size == 2 {
                    return Some((i, j));
                }
            }
        }
    }
    best.map(|(_, i, j)| (i, j))
}
