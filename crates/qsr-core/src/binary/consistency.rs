//! [`solve_binary`]: consistency of a binary network by backtracking search with path
//! consistency at every node — GQR's `consistency` mode — within a node budget.
//!
//! The search is GQR's (`gqrtl/RestartingDFS`): 2-way branching (narrow a constraint to its
//! first split; on failure, remove that split from it), the constraint chosen by its set's
//! weight divided by how often it took part in a failure (dom/wdeg, which moves the search to
//! where the network is hard), the constraint of the last dead end decided first again
//! (last-conflict reasoning), and geometric restarts that keep those weights. A failure's
//! weight is raised on the three constraints of the triangle that emptied. GQR also records
//! nogoods at restarts; qrm does not (the weights alone carry over).
//!
//! Constraints are split into base relations, or into the members of a [`SplitSet`] — a
//! tractable subclass such as RCC-8's Horn relations, where path consistency decides
//! consistency and the search can stop once every constraint is a member. A solution is a
//! path-consistent refinement whose every set is a split (atomic without a split set). For
//! calculi where path consistency decides such networks (the point algebra, Allen's interval
//! algebra, RCC-8; their Horn subclasses) that is consistency; for others (OPRA, cardinal
//! directions of regions) it is what GQR reports too, "algebraically closed".

use std::collections::HashSet;

use super::closure::{BinaryContradiction, Propagator, words_error};
use super::network::BinaryNetwork;
use super::set_ops::{SetOps, SetView};
use super::split_set::SplitSet;

/// Options of [`solve_binary`].
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SolveOptions {
    /// The most search nodes (decisions: a constraint narrowed to a split, or that split
    /// removed from it) before the answer is [`SolveOutcome::Unknown`].
    pub max_nodes: u64,
    /// The relations to split constraints into ([`SplitSet`], GQR's `-c`); `None`: base
    /// relations, and a solution is atomic.
    pub split: Option<SplitSet>,
    /// Restart the search after 10, 15, 22, … dead ends in all (GQR's default geometric
    /// schedule), keeping what the failures taught the choice of constraint; `false`: one
    /// depth-first search (GQR's `--2w`).
    pub restarts: bool,
}

impl Default for SolveOptions {
    fn default() -> Self {
        Self {
            max_nodes: 1_000_000,
            split: None,
            restarts: true,
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
    /// Search nodes (decisions: a split tried on a constraint, or removed from it).
    pub nodes: u64,
    /// Restarts made.
    pub restarts: u64,
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

/// A decision on the stack: the constraint `(i, j)`, the set it was narrowed to, whether that
/// was the split (positive) or the split's removal (negative), and the trail before it.
struct Decision<const W: usize> {
    edge: (usize, usize),
    value: [u64; W],
    positive: bool,
    mark: usize,
}

/// How constraints are split: into base relations, or into the members of a [`SplitSet`]
/// tried in GQR's value order (heavier, then larger, first: the least constraining choice).
struct Splitter<const W: usize> {
    /// Members in trial order; empty for base relations.
    members: Vec<[u64; W]>,
    lookup: Membership<W>,
}

/// Whether a set is a member: a bit per possible set when the calculus is small (the search
/// asks for every constraint at every decision), a hash set otherwise.
enum Membership<const W: usize> {
    Dense(Vec<u64>),
    Hashed(HashSet<[u64; W]>),
}

/// Calculi of up to this many relations get a dense membership table (2^20 bits, 128 KB).
const DENSE_MEMBERSHIP_RELATIONS: usize = 20;

impl<const W: usize> Splitter<W> {
    fn new(split: Option<&SplitSet>, view: &SetView<'_, W>) -> Self {
        let Some(split) = split else {
            return Self {
                members: Vec::new(),
                lookup: Membership::Hashed(HashSet::new()),
            };
        };
        let mut members: Vec<[u64; W]> = split
            .members()
            .iter()
            .map(|m| {
                let mut w = [0u64; W];
                for (slot, word) in w.iter_mut().zip(m.words()) {
                    *slot = *word;
                }
                w
            })
            .collect();
        let count = |s: &[u64; W]| s.iter().map(|w| w.count_ones()).sum::<u32>();
        members.sort_by(|a, b| {
            view.weight(b)
                .cmp(&view.weight(a))
                .then(count(b).cmp(&count(a)))
                // At the highest relation where they differ, the one without it first.
                .then_with(|| a.iter().rev().cmp(b.iter().rev()))
        });
        let lookup = if split
            .members()
            .first()
            .map_or(0, crate::reason::StateSet::n_states)
            <= DENSE_MEMBERSHIP_RELATIONS
        {
            let mut bits = vec![0u64; (1usize << DENSE_MEMBERSHIP_RELATIONS) / 64];
            for m in &members {
                let k = m[0] as usize;
                bits[k / 64] |= 1 << (k % 64);
            }
            Membership::Dense(bits)
        } else {
            Membership::Hashed(members.iter().copied().collect())
        };
        Self { members, lookup }
    }

    /// Whether `set` needs no more splitting.
    fn is_split(&self, set: &[u64; W]) -> bool {
        if self.members.is_empty() {
            set.iter().map(|w| w.count_ones()).sum::<u32>() <= 1
        } else {
            match &self.lookup {
                Membership::Dense(bits) => {
                    // Small calculi: one word, below 2^DENSE_MEMBERSHIP_RELATIONS.
                    let k = set[0] as usize;
                    bits[k / 64] >> (k % 64) & 1 == 1
                }
                Membership::Hashed(h) => h.contains(set),
            }
        }
    }

    /// The split to try first: the heaviest base relation (ties: the lower one), or the
    /// first member within `set` in trial order (one exists: every base relation is one).
    fn first(&self, set: &[u64; W], view: &SetView<'_, W>) -> [u64; W] {
        let mut out = [0u64; W];
        if self.members.is_empty() {
            let best = crate::reason::iter_bits(set)
                .map(crate::calculus::StateId::index)
                .min_by_key(|&r| (std::cmp::Reverse(view.weights[r]), r));
            if let Some(r) = best {
                out[r / 64] = 1 << (r % 64);
            }
            return out;
        }
        self.members
            .iter()
            .find(|m| m.iter().zip(set).all(|(m, s)| m & !s == 0))
            .copied()
            .unwrap_or(out)
    }
}

/// The search (see [`solve_binary`]): GQR's 2-way depth-first search — narrow a constraint to
/// its first split, and on failure remove that split from it — with its choice of constraint
/// (the lightest set relative to how often it took part in a failure, "dom/wdeg"), last-
/// conflict reasoning (after a dead end, decide the constraint that caused it first again) and
/// geometric restarts.
fn solve_with<const W: usize>(
    mut network: BinaryNetwork,
    ops: &SetOps,
    options: &SolveOptions,
) -> crate::Result<BinarySolution> {
    let Some(view) = ops.view::<W>() else {
        return Err(words_error(network.algebra()));
    };
    let splitter = Splitter::<W>::new(options.split.as_ref(), &view);
    let mut prop = Propagator::<W>::new(&network, view);
    let mut restarts = 0u64;
    let done = |outcome, nodes, restarts| {
        Ok(BinarySolution {
            outcome,
            nodes,
            restarts,
        })
    };
    if prop.start(ops.universal_closed()).is_err() {
        return done(SolveOutcome::Inconsistent, 0, 0);
    }
    prop.trail = Some(Vec::new());
    let n = prop.n;
    let mut failures = Failures::new(n);
    // The constraints the search may have to split: those not split once closed.
    let mut candidates: Vec<(usize, usize)> = unsplit(&prop, &splitter).collect();
    let mut decisions: Vec<Decision<W>> = Vec::new();
    let mut last_conflict: Option<(usize, usize)> = None;
    let (mut nodes, mut dead_ends) = (0u64, 0u64);
    let mut next_restart = if options.restarts { 10 } else { u64::MAX };
    let mut failed: Option<BinaryContradiction> = None;
    loop {
        if let Some(why) = failed.take() {
            failures.record(why, decisions.len());
            // Back to the latest positive decision; its alternative is the split's removal.
            let refuted = loop {
                let Some(d) = decisions.pop() else {
                    return done(SolveOutcome::Inconsistent, nodes, restarts);
                };
                prop.undo_to(d.mark);
                if d.positive {
                    break d;
                }
            };
            dead_ends += 1;
            if dead_ends >= next_restart {
                // The negative decisions below the first positive one follow from the network
                // itself (each refuted a choice made with nothing else assumed): a restart
                // keeps them (GQR keeps them as nogoods of one constraint).
                let kept = decisions.iter().take_while(|d| !d.positive).count();
                let mark = decisions
                    .get(kept)
                    .map_or_else(|| prop.trail.as_ref().map_or(0, Vec::len), |d| d.mark);
                prop.undo_to(mark);
                decisions.truncate(kept);
                last_conflict = None;
                next_restart += next_restart / 2;
                restarts += 1;
            } else {
                last_conflict.get_or_insert(refuted.edge);
                let (i, j) = refuted.edge;
                let rest: [u64; W] =
                    std::array::from_fn(|k| prop.m[i * n + j][k] & !refuted.value[k]);
                nodes += 1;
                if nodes > options.max_nodes {
                    return done(SolveOutcome::Unknown, nodes, restarts);
                }
                failed = decide(&mut prop, &mut decisions, (i, j), rest, false).err();
                continue;
            }
        }
        if let (Some(edge), Some(d)) = (last_conflict, decisions.last())
            && d.positive
            && d.edge == edge
        {
            last_conflict = None;
        }
        let conflict = last_conflict.filter(|&(i, j)| !splitter.is_split(&prop.m[i * n + j]));
        let Some((i, j)) = conflict.or_else(|| failures.choose(&prop, &splitter, &mut candidates))
        else {
            prop.write_back(&mut network);
            return done(SolveOutcome::Consistent(network), nodes, restarts);
        };
        let value = splitter.first(&prop.m[i * n + j], &prop.view);
        nodes += 1;
        if nodes > options.max_nodes {
            return done(SolveOutcome::Unknown, nodes, restarts);
        }
        failed = decide(&mut prop, &mut decisions, (i, j), value, true).err();
    }
}

/// Narrows `(i, j)` to `value`, records the decision and propagates.
fn decide<const W: usize>(
    prop: &mut Propagator<'_, W>,
    decisions: &mut Vec<Decision<W>>,
    (i, j): (usize, usize),
    value: [u64; W],
    positive: bool,
) -> Result<(), BinaryContradiction> {
    let mark = prop.trail.as_ref().map_or(0, Vec::len);
    decisions.push(Decision {
        edge: (i, j),
        value,
        positive,
        mark,
    });
    prop.put(i, j, value);
    prop.enqueue(i, j);
    prop.run()
}

/// What failures taught: a weight per constraint, raised each time it is one of the three
/// of a triangle that emptied (more for a failure near the root: GQR's weighting).
struct Failures {
    n: usize,
    learned: Vec<u64>,
    max_depth: usize,
}

impl Failures {
    fn new(n: usize) -> Self {
        Self {
            n,
            learned: vec![1; n * n],
            max_depth: 1,
        }
    }

    fn record(&mut self, why: BinaryContradiction, depth: usize) {
        self.max_depth = self.max_depth.max(depth);
        let raise = (self.max_depth - depth + 1) as u64;
        let edges = match why {
            BinaryContradiction::Given { a, b } => [(a, b), (a, b), (a, b)],
            BinaryContradiction::Composed { a, via, b } => [(a, b), (a, via), (via, b)],
        };
        let mut seen = [usize::MAX; 3];
        for (k, (a, b)) in edges.into_iter().enumerate() {
            let at = a.min(b) * self.n + a.max(b);
            if !seen.contains(&at) {
                seen[k] = at;
                self.learned[at] = self.learned[at].saturating_add(raise);
            }
        }
    }

    /// The constraint still to split, among `candidates`, whose set weighs least relative to
    /// its learned weight (ties: the earlier candidate). When no candidate is left, every
    /// constraint is looked at once more — a split set not closed under intersection and
    /// composition can turn a set split at the root into one that is not — and one found is
    /// added to the candidates.
    fn choose<const W: usize>(
        &self,
        prop: &Propagator<'_, W>,
        splitter: &Splitter<W>,
        candidates: &mut Vec<(usize, usize)>,
    ) -> Option<(usize, usize)> {
        let n = self.n;
        let mut best: Option<(f64, usize, usize)> = None;
        for &(i, j) in candidates.iter() {
            let set = &prop.m[i * n + j];
            if splitter.is_split(set) {
                continue;
            }
            let score = f64::from(prop.view.weight(set)) / self.learned[i * n + j] as f64;
            if best.is_none_or(|(b, _, _)| score < b) {
                best = Some((score, i, j));
            }
        }
        if best.is_none() {
            let found = unsplit(prop, splitter).next();
            candidates.extend(found);
            return found;
        }
        best.map(|(_, i, j)| (i, j))
    }
}

/// The constraints `i < j` whose sets are not splits, in order.
fn unsplit<'p, const W: usize>(
    prop: &'p Propagator<'_, W>,
    splitter: &'p Splitter<W>,
) -> impl Iterator<Item = (usize, usize)> + 'p {
    let n = prop.n;
    (0..n)
        .flat_map(move |i| (i + 1..n).map(move |j| (i, j)))
        .filter(move |&(i, j)| !splitter.is_split(&prop.m[i * n + j]))
}
