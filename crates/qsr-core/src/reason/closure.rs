//! Algebraic closure ([`close`]): refine every constraint of a [`Network`] with the
//! permutation operations and with composition until nothing changes.
//!
//! The rules, for distinct points `a, b, c, d`:
//! - permutation: `{π(a,b,c)} ⊆ op({a,b:c})` for each of the five operations;
//! - composition: `{a,b:d} ⊆ {a,b:c} ∘ {b,c:d}` (SparQ's ternary composition).
//!
//! Work is organised by unordered triplet. When any ordering of `{x, y, z}` changes, the
//! triplet is queued; processing it first makes its six orderings agree through the
//! permutation tables, then re-runs every composition rule in which one of its orderings is an
//! input: with `(p, q, r)` an ordering and `w` any fourth point, `{p,q:w} ⊆ {p,q:r} ∘ {q,r:w}`
//! and `{w,p:r} ⊆ {w,p:q} ∘ {p,q:r}`. Each rule is run again only when one of its inputs
//! changed (AC-3 style), so the fixpoint is reached with each refinement done once; a triplet
//! that changes while it is still to be processed in the current round is not queued again.
//!
//! Queued triplets are processed in rounds, in fixed-size chunks: the permutations and then the
//! compositions of a chunk are evaluated in parallel against the network as it stands, then
//! applied in queue order. The first round of a full closure takes the triplets something is
//! known of first, with the left-input rule only (every rule instance has one such input),
//! and then the triplets nothing is known of, with both rules: by the time these run, the
//! compositions of the known ones have inferred most of what they will hold, so a half-known
//! network closes in about one pass over its rule instances rather than two. The closed
//! network (the greatest fixpoint of the rules) is unique, and the order of application is
//! fixed, so the result, the point of a contradiction and its explanation do not depend on the
//! thread count.
//!
//! Algebraic closure is sound: a configuration of distinct points satisfying the input
//! satisfies the closed network, *provided the tables are complete* (see
//! [`TableScope`](crate::reason::TableScope)). It is not complete: for ternary point calculi a
//! closed network need not be realisable (deciding that is NP-hard), so "consistent" here means
//! "not refuted by closure", as in SparQ and GQR.

use rayon::prelude::*;

use crate::binary::set_ops::SetView;
use crate::error::QsrError;
use crate::permute::{Permutation, all_orderings};
use crate::reason::algebra::Algebra;
use crate::reason::network::Network;
use crate::reason::state_set::{StateSet, count};

/// Options of [`close_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClosureOptions {
    /// Keep, for every constraint, the rule that last refined it, so a contradiction comes with
    /// the chain of refinements that produced it (12 bytes per ordered triplet).
    pub explain: bool,
    /// The most steps an explanation lists.
    pub max_explanation_steps: usize,
}

impl Default for ClosureOptions {
    fn default() -> Self {
        Self {
            explain: true,
            max_explanation_steps: 24,
        }
    }
}

impl ClosureOptions {
    /// No provenance kept (faster, less memory); a contradiction still names the constraint
    /// that became empty and the rule that emptied it.
    #[must_use]
    pub fn without_explanation() -> Self {
        Self {
            explain: false,
            ..Self::default()
        }
    }
}

/// Why a constraint holds the set it holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Rule {
    /// As given (never refined).
    Given,
    /// Refined by a permutation of another ordering of the same points.
    Permutation {
        /// The operation.
        op: Permutation,
        /// The ordering it was applied to, `(a, b, c)` for `{a,b:c}`.
        from: [usize; 3],
    },
    /// Refined by composing two constraints: `{a,b:d} ⊆ {a,b:c} ∘ {b,c:d}`.
    Composition {
        /// `{a,b:c}`.
        left: [usize; 3],
        /// `{b,c:d}`.
        right: [usize; 3],
    },
    /// Not recorded ([`ClosureOptions::explain`] was off).
    Unrecorded,
}

/// One line of an explanation: a constraint, its set, and the rule behind it.
#[derive(Debug, Clone, PartialEq)]
pub struct Step {
    /// `(a, b, c)` for `{a,b:c}`.
    pub triplet: [usize; 3],
    /// Its set when the contradiction arose.
    pub states: StateSet,
    /// The rule that last refined it.
    pub rule: Rule,
}

/// A constraint that became empty, and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Contradiction {
    /// The constraint that became empty.
    pub triplet: [usize; 3],
    /// Its set just before.
    pub before: StateSet,
    /// The set the emptying rule allows (disjoint from `before`).
    pub allowed: StateSet,
    /// The emptying rule.
    pub rule: Rule,
    /// The constraints the rule used and, recursively, theirs, down to given ones.
    pub steps: Vec<Step>,
    /// Whether `steps` was cut at [`ClosureOptions::max_explanation_steps`].
    pub truncated: bool,
}

impl Contradiction {
    /// A text a user can read, with point names and labels.
    #[must_use]
    pub fn describe(&self, network: &Network) -> String {
        let c = network.calculus();
        let name = |t: &[usize; 3]| {
            let n = network.names();
            format!("{{{},{}:{}}}", n[t[0]], n[t[1]], n[t[2]])
        };
        let set = |s: &StateSet| format!("{{{}}}", s.labels(c).join(", "));
        let rule = |r: &Rule| match r {
            Rule::Given => "given".to_owned(),
            Rule::Permutation { op, from } => format!("{op} of {}", name(from)),
            Rule::Composition { left, right } => format!("{} ∘ {}", name(left), name(right)),
            Rule::Unrecorded => "refined (provenance not kept)".to_owned(),
        };
        let mut out = if self.rule == Rule::Given {
            format!(
                "{} is empty as given: the constraints on it exclude each other",
                name(&self.triplet)
            )
        } else {
            format!(
                "{} became empty: it was {} and {} allows only {}",
                name(&self.triplet),
                set(&self.before),
                rule(&self.rule),
                set(&self.allowed)
            )
        };
        if !self.steps.is_empty() {
            out.push_str("\nbecause:");
            for s in &self.steps {
                out.push_str(&format!(
                    "\n  {} = {}  ({})",
                    name(&s.triplet),
                    set(&s.states),
                    rule(&s.rule)
                ));
            }
            if self.truncated {
                out.push_str("\n  …");
            }
        }
        out
    }
}

/// Counters of one closure.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ClosureStats {
    /// Rounds of the queue.
    pub rounds: usize,
    /// Unordered triplets processed (a triplet counts once per round it was queued in).
    pub triplets_processed: usize,
    /// Constraints that were strictly refined.
    pub refinements: usize,
}

/// The result of [`close`]: the network at the fixpoint, or at the moment a constraint
/// became empty.
#[derive(Debug, Clone)]
pub struct Closure {
    /// The closed network (or the network when the contradiction arose).
    pub network: Network,
    /// `None` when closure found no contradiction.
    pub contradiction: Option<Contradiction>,
    /// Work done.
    pub stats: ClosureStats,
}

impl Closure {
    /// Whether closure found no contradiction ("algebraically closed").
    #[must_use]
    pub fn is_consistent(&self) -> bool {
        self.contradiction.is_none()
    }
}

/// Algebraic closure with the default options (explanations kept).
///
/// ```
/// use qsr_core::{Calculus, reason::{Algebra, Network, TableScope, close}};
/// let lr = Calculus::builtin("left-right")?;
/// let alg = Algebra::of(&lr, TableScope::Sound)?;
/// let mut net = Network::universal(&lr, ["A", "B", "C"])?;
/// net.constrain_labels("A", "B", "C", &["left"])?;
/// net.constrain_labels("B", "A", "C", &["left"])?; // the inverse says: right
/// let closed = close(net, &alg)?;
/// assert!(!closed.is_consistent());
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
///
/// # Errors
/// [`QsrError::Arity`] when the algebra belongs to another calculus than the network.
pub fn close(network: Network, algebra: &Algebra) -> crate::Result<Closure> {
    close_with(network, algebra, &ClosureOptions::default())
}

/// Algebraic closure with explicit options.
///
/// # Errors
/// As [`close`].
pub fn close_with(
    network: Network,
    algebra: &Algebra,
    options: &ClosureOptions,
) -> crate::Result<Closure> {
    let n = network.n_points();
    let all = (0..n)
        .flat_map(|a| (a + 1..n).flat_map(move |b| (b + 1..n).map(move |c| [a, b, c])))
        .map(|t| network.index(t[0], t[1], t[2]))
        .collect();
    close_from(network, algebra, all, options)
}

/// Closure of a network that was closed before `frontier` (canonical indices of unordered
/// triplets) changed: only their consequences are propagated.
pub(crate) fn close_from(
    network: Network,
    algebra: &Algebra,
    frontier: Vec<usize>,
    options: &ClosureOptions,
) -> crate::Result<Closure> {
    close_chunked(network, algebra, frontier, options, CHUNK)
}

/// [`close_from`] with `chunk` triplets evaluated together (the result does not depend on it;
/// a test runs chunks of one, where every triplet sees the refinements of all before it).
fn close_chunked(
    mut network: Network,
    algebra: &Algebra,
    frontier: Vec<usize>,
    options: &ClosureOptions,
    chunk: usize,
) -> crate::Result<Closure> {
    if algebra.n_states() != network.calculus().n_states()
        || algebra.calculus().name() != network.calculus().name()
    {
        return Err(QsrError::Arity(format!(
            "the tables are of calculus `{}` ({} states), the network of `{}` ({} states)",
            algebra.calculus().name(),
            algebra.n_states(),
            network.calculus().name(),
            network.calculus().n_states()
        )));
    }
    let mut state = Propagation {
        reasons: options
            .explain
            .then(|| vec![Reason::Given; network.n_points().pow(3)]),
        stats: ClosureStats::default(),
        transposed: None,
        chunk: chunk.max(1),
    };
    let outcome = state.run(&mut network, algebra, frontier);
    let contradiction = outcome.err().map(|empty| {
        let mut c = empty.into_contradiction(&network, algebra);
        if let Some(reasons) = &state.reasons {
            explain(&mut c, &network, reasons, options.max_explanation_steps);
        }
        c
    });
    Ok(Closure {
        network,
        contradiction,
        stats: state.stats,
    })
}

/// Compact provenance of one ordered triplet.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reason {
    Given,
    Permutation(Permutation, u32),
    Composition(u32, u32),
}

/// The moment a constraint became empty.
struct Emptied {
    target: usize,
    before: Vec<u64>,
    allowed: Vec<u64>,
    reason: Reason,
}

impl Emptied {
    fn into_contradiction(self, net: &Network, alg: &Algebra) -> Contradiction {
        let n_states = alg.n_states();
        Contradiction {
            triplet: net.triplet(self.target),
            before: StateSet::from_words(n_states, &self.before),
            allowed: StateSet::from_words(n_states, &self.allowed),
            rule: rule_of(net, self.reason),
            steps: Vec::new(),
            truncated: false,
        }
    }
}

fn rule_of(net: &Network, r: Reason) -> Rule {
    match r {
        Reason::Given => Rule::Given,
        Reason::Permutation(op, from) => Rule::Permutation {
            op,
            from: net.triplet(from as usize),
        },
        Reason::Composition(l, r) => Rule::Composition {
            left: net.triplet(l as usize),
            right: net.triplet(r as usize),
        },
    }
}

/// Walks the provenance back from the emptying rule's inputs, breadth first.
fn explain(c: &mut Contradiction, net: &Network, reasons: &[Reason], max_steps: usize) {
    let index = |t: [usize; 3]| net.index(t[0], t[1], t[2]);
    let inputs = |r: &Rule| match r {
        Rule::Permutation { from, .. } => vec![index(*from)],
        Rule::Composition { left, right } => vec![index(*left), index(*right)],
        Rule::Given | Rule::Unrecorded => vec![],
    };
    let mut queue: std::collections::VecDeque<usize> = inputs(&c.rule).into();
    let mut seen = std::collections::HashSet::new();
    while let Some(i) = queue.pop_front() {
        if !seen.insert(i) {
            continue;
        }
        if c.steps.len() == max_steps {
            c.truncated = true;
            break;
        }
        let rule = rule_of(net, reasons[i]);
        queue.extend(inputs(&rule));
        let t = net.triplet(i);
        c.steps.push(Step {
            triplet: t,
            states: net.get(t[0], t[1], t[2]),
            rule,
        });
    }
}

/// Unordered triplets whose compositions are evaluated together (in parallel) before being
/// applied.
const CHUNK: usize = 512;

/// A refinement proposed by one triplet's compositions: `target ∩= allowed`.
struct Proposal {
    target: u32,
    /// The target's index in [`Propagation::transposed`] (computed with the proposal: the
    /// applying loop would divide by `n` twice per refinement).
    transposed: u32,
    /// The canonical index of the target's unordered triplet (the one to queue), computed
    /// with the proposal rather than by the applying loop, which runs on one thread.
    canon: u32,
    left: u32,
    right: u32,
    allowed: Allowed,
}

/// A proposal's set: one word inline (EDC and every built-in calculus — a first round over a
/// half-known network proposes millions, and a heap allocation each cost more than the
/// compositions), wider sets on the heap.
enum Allowed {
    One([u64; 1]),
    Many(Box<[u64]>),
}

impl Allowed {
    fn words(&self) -> &[u64] {
        match self {
            Self::One(w) => w,
            Self::Many(w) => w,
        }
    }
}

struct Propagation {
    reasons: Option<Vec<Reason>>,
    stats: ClosureStats,
    /// For one-word sets in a full closure: every set again, at `(x·n + y)·n + w` for
    /// `{w,x:y}`, so the right-input rule reads `{w,p:q}` and `{w,p:r}` over all `w` in order
    /// instead of a column of the n³ array. Kept equal to the network by [`Self::refine`].
    transposed: Option<Vec<u64>>,
    /// Triplets per chunk ([`CHUNK`]).
    chunk: usize,
}

/// The most points for which a full closure keeps [`Propagation::transposed`] (its n³ words
/// double the network's memory).
const MAX_TRANSPOSED_POINTS: usize = 400;

impl Propagation {
    fn run(
        &mut self,
        net: &mut Network,
        alg: &Algebra,
        mut frontier: Vec<usize>,
    ) -> Result<(), Emptied> {
        let n = net.n_points();
        // Given empty sets are contradictions of their own.
        for &t in &frontier {
            for o in orderings(net, t) {
                if count(net.words_at(o)) == 0 {
                    return Err(Emptied {
                        target: o,
                        before: net.words_at(o).to_vec(),
                        allowed: net.words_at(o).to_vec(),
                        reason: Reason::Given,
                    });
                }
            }
        }
        frontier.sort_unstable();
        frontier.dedup();
        let full = frontier.len() == n * n.saturating_sub(1) * n.saturating_sub(2) / 6;
        // Every composition rule instance `{a,b:d} ⊆ {a,b:c} ∘ {b,c:d}` has a left input, so
        // the first round of a full closure evaluates each instance from its left input
        // (rule 1 below) and skips the right-input copies (rule 2), which read the network a
        // column at a time — for the triplets something is known of. The triplets nothing is
        // known of come last: by then those instances have inferred most of what they will
        // hold, and they run both rules, so the instances they take part in are evaluated
        // once with that rather than again in a second round over every inferred triplet.
        let mut left_only_until = 0;
        if full {
            let universal = alg.universal_words();
            let (known, unknown): (Vec<usize>, Vec<usize>) = frontier.iter().partition(|&&t| {
                orderings(net, t)
                    .iter()
                    .any(|&o| net.words_at(o) != universal)
            });
            left_only_until = known.len();
            frontier = known;
            frontier.extend(unknown);
        }
        let transposable = full && alg.one_word().is_some() && n <= MAX_TRANSPOSED_POINTS;
        let mut state = vec![0u8; n * n * n];
        while !frontier.is_empty() {
            self.stats.rounds += 1;
            self.stats.triplets_processed += frontier.len();
            for (i, &t) in frontier.iter().enumerate() {
                state[t] = if i < left_only_until {
                    PENDING_LEFT
                } else {
                    PENDING_BOTH
                };
            }
            let mut next = Vec::new();
            let (left_part, both_part) = frontier.split_at(left_only_until);
            // Fixed-size chunks (never thread-count dependent): each chunk's compositions are
            // evaluated in parallel against the network as the chunks before it left it, then
            // applied in order. Bounded memory (a round over all triplets of 200 points would
            // otherwise hold ~10^9 proposals), and later chunks see earlier refinements.
            let chunks = left_part
                .chunks(self.chunk)
                .map(|c| (c, false))
                .chain(both_part.chunks(self.chunk).map(|c| (c, true)));
            for (chunk, both) in chunks {
                if both && transposable && self.transposed.is_none() {
                    self.transposed = Some(transpose(net.one_word_sets(), n));
                }
                for &t in chunk {
                    state[t] &= !(PENDING_LEFT | PENDING_BOTH);
                }
                let snapshot: &Network = net;
                let synced: Vec<Vec<Refinement>> = chunk
                    .par_iter()
                    .map(|&t| permutation_refinements(snapshot, alg, t))
                    .collect();
                for (&t, refinements) in chunk.iter().zip(synced) {
                    let mut changed = false;
                    for r in refinements {
                        changed |=
                            self.refine(net, r.target as usize, r.allowed.words(), r.reason)?;
                    }
                    // Run with the left rule only, a triplet its permutations refined is
                    // queued for the right one (instances before it read its old sets).
                    if changed && !both {
                        queue(&mut state, &mut next, t);
                    }
                }
                let snapshot: &Network = net;
                let transposed = self.transposed.as_deref();
                let proposals: Vec<Vec<Proposal>> = chunk
                    .par_iter()
                    .map(|&t| compositions(snapshot, transposed, alg, t, both))
                    .collect();
                for p in proposals.into_iter().flatten() {
                    let target = p.target as usize;
                    if self.refine_at(
                        net,
                        target,
                        p.transposed as usize,
                        p.allowed.words(),
                        Reason::Composition(p.left, p.right),
                    )? {
                        queue(&mut state, &mut next, p.canon as usize);
                    }
                }
            }
            next.sort_unstable();
            frontier = next;
            left_only_until = 0;
        }
        Ok(())
    }

    /// `target ∩= allowed`; whether it changed. An empty result stops the closure.
    fn refine(
        &mut self,
        net: &mut Network,
        target: usize,
        allowed: &[u64],
        reason: Reason,
    ) -> Result<bool, Emptied> {
        let transposed = transposed_index(net.n_points(), target);
        self.refine_at(net, target, transposed, allowed, reason)
    }

    /// [`Self::refine`] with the target's index in the transposed copy given.
    fn refine_at(
        &mut self,
        net: &mut Network,
        target: usize,
        transposed: usize,
        allowed: &[u64],
        reason: Reason,
    ) -> Result<bool, Emptied> {
        let cur = net.words_at(target);
        if cur.iter().zip(allowed).all(|(c, a)| c & !a == 0) {
            return Ok(false);
        }
        // Only a contradiction needs the set as it was (no allocation per refinement).
        if cur.iter().zip(allowed).all(|(c, a)| c & a == 0) {
            let before = cur.to_vec();
            net.words_at_mut(target).fill(0);
            self.stats.refinements += 1;
            if let Some(r) = &mut self.reasons {
                r[target] = reason;
            }
            return Err(Emptied {
                target,
                before,
                allowed: allowed.to_vec(),
                reason,
            });
        }
        for (c, a) in net.words_at_mut(target).iter_mut().zip(allowed) {
            *c &= a;
        }
        self.stats.refinements += 1;
        if let Some(t) = &mut self.transposed {
            t[transposed] = net.words_at(target)[0];
        }
        if let Some(r) = &mut self.reasons {
            r[target] = reason;
        }
        Ok(true)
    }
}

/// A triplet's state in the queue of [`Propagation::run`]: to be run this round with both rules.
const PENDING_BOTH: u8 = 1;
/// To be run this round with the left rule only (the first round of a full closure).
const PENDING_LEFT: u8 = 2;
/// In the next round's queue.
const IN_NEXT: u8 = 4;

/// Queues the unordered triplet `t`, whose sets changed, for the next round — unless it is
/// still to run this round with both rules: then every instance it takes part in is evaluated
/// with its new sets anyway.
fn queue(state: &mut [u8], next: &mut Vec<usize>, t: usize) {
    if state[t] & (PENDING_BOTH | IN_NEXT) == 0 {
        state[t] |= IN_NEXT;
        next.push(t);
    }
}

/// The network's sets again, at `(x·n + y)·n + w` for `{w,x:y}` (a row per pair, gathered
/// in parallel).
fn transpose(sets: &[u64], n: usize) -> Vec<u64> {
    let nn = n * n;
    let mut t = vec![0u64; nn * n];
    t.par_chunks_mut(n.max(1))
        .enumerate()
        .for_each(|(xy, row)| {
            for (w, out) in row.iter_mut().enumerate() {
                *out = sets[w * nn + xy];
            }
        });
    t
}

/// A refinement found by a read-only pass, applied later by [`Propagation::refine`].
struct Refinement {
    target: u32,
    allowed: Allowed,
    reason: Reason,
}

/// The refinements that make the six orderings of one unordered triplet agree through the
/// permutation tables, in the order a pass over them applies them (to the fixpoint, or up to
/// the one that empties a set). Read-only, so the triplets of a chunk are synchronised in
/// parallel (they share no ordering); applying the list in order gives what the pass gave.
fn permutation_refinements(net: &Network, alg: &Algebra, canon: usize) -> Vec<Refinement> {
    if alg.words() == 1 {
        return permutation_refinements_one_word(net, alg, canon);
    }
    let [a, b, c] = net.triplet(canon);
    let words = alg.words();
    let order = processing_order(a, b, c);
    let slot = |x: usize, y: usize, z: usize| {
        order
            .iter()
            .position(|&o| o == (x, y, z))
            .unwrap_or_default()
    };
    let mut local: Vec<u64> = order
        .iter()
        .flat_map(|&(x, y, z)| net.words_at(net.index(x, y, z)).iter().copied())
        .collect();
    let mut permuted = vec![0u64; words];
    let mut out = Vec::new();
    loop {
        let mut changed = false;
        for (from_slot, &(x, y, z)) in order.iter().enumerate() {
            let from = net.index(x, y, z);
            for op in Permutation::ALL {
                let (p, q, r) = op.apply(x, y, z);
                let to_slot = slot(p, q, r);
                alg.permute_into(op, &local[from_slot * words..][..words], &mut permuted);
                let cur = &mut local[to_slot * words..][..words];
                if cur.iter().zip(&permuted).all(|(c, p)| c & !p == 0) {
                    continue;
                }
                let emptied = cur.iter().zip(&permuted).all(|(c, p)| c & p == 0);
                for (c, p) in cur.iter_mut().zip(&permuted) {
                    *c &= p;
                }
                out.push(Refinement {
                    target: net.index(p, q, r) as u32,
                    allowed: if words == 1 {
                        Allowed::One([permuted[0]])
                    } else {
                        Allowed::Many(permuted.as_slice().into())
                    },
                    reason: Reason::Permutation(op, from as u32),
                });
                if emptied {
                    return out;
                }
                changed = true;
            }
        }
        if !changed {
            return out;
        }
    }
}

/// [`permutation_refinements`] for one-word sets: the six sets on the stack, and the slot
/// each operation takes each ordering to from a table (the same pass, the same list).
fn permutation_refinements_one_word(net: &Network, alg: &Algebra, canon: usize) -> Vec<Refinement> {
    static SLOTS: std::sync::OnceLock<[[usize; 5]; 6]> = std::sync::OnceLock::new();
    let slots = SLOTS.get_or_init(|| {
        let order = processing_order(0, 1, 2);
        std::array::from_fn(|from| {
            let (x, y, z) = order[from];
            std::array::from_fn(|k| {
                let image = Permutation::ALL[k].apply(x, y, z);
                order.iter().position(|&o| o == image).unwrap_or_default()
            })
        })
    });
    let [a, b, c] = net.triplet(canon);
    let sets = net.one_word_sets();
    let index = processing_order(a, b, c).map(|(x, y, z)| net.index(x, y, z));
    let mut local = index.map(|i| sets[i]);
    let mut out = Vec::new();
    loop {
        let mut changed = false;
        for (from, to_slots) in slots.iter().enumerate() {
            for (&op, &to) in Permutation::ALL.iter().zip(to_slots) {
                let permuted = alg.permute_word(op, local[from]);
                if local[to] & !permuted == 0 {
                    continue;
                }
                let emptied = local[to] & permuted == 0;
                local[to] &= permuted;
                out.push(Refinement {
                    target: index[to] as u32,
                    allowed: Allowed::One([permuted]),
                    reason: Reason::Permutation(op, index[from] as u32),
                });
                if emptied {
                    return out;
                }
                changed = true;
            }
        }
        if !changed {
            return out;
        }
    }
}

/// The six orderings of a triplet in the order closure processes them (fixed: the order of
/// refinements, and so the contradiction reported, depends on it).
fn processing_order(a: usize, b: usize, c: usize) -> [(usize, usize, usize); 6] {
    [
        (a, b, c),
        (b, a, c),
        (a, c, b),
        (c, a, b),
        (b, c, a),
        (c, b, a),
    ]
}

/// The compositions in which one ordering of the triplet is an input: as the left input
/// (rule 1), and as the right one (rule 2) when `both`.
fn compositions(
    net: &Network,
    transposed: Option<&[u64]>,
    alg: &Algebra,
    canon: usize,
    both: bool,
) -> Vec<Proposal> {
    if let Some(view) = alg.one_word() {
        return compositions_one_word(net, transposed, &view, canon, both);
    }
    let n = net.n_points();
    let [a, b, c] = net.triplet(canon);
    let mut out = vec![0u64; alg.words()];
    let mut proposals = Vec::new();
    for (p, q, r) in processing_order(a, b, c) {
        let pqr = net.index(p, q, r);
        let given = net.words_at(pqr);
        for w in (0..n).filter(|&w| w != a && w != b && w != c) {
            // {p,q:w} ⊆ {p,q:r} ∘ {q,r:w}
            let (target, right) = (net.index(p, q, w), net.index(q, r, w));
            if alg.compose_refines(given, net.words_at(right), net.words_at(target), &mut out) {
                proposals.push(Proposal {
                    target: target as u32,
                    transposed: transposed_index(n, target) as u32,
                    canon: canonical(net, target) as u32,
                    left: pqr as u32,
                    right: right as u32,
                    allowed: Allowed::Many(out.as_slice().into()),
                });
            }
            if !both {
                continue;
            }
            // {w,p:r} ⊆ {w,p:q} ∘ {p,q:r}
            let (target, left) = (net.index(w, p, r), net.index(w, p, q));
            if alg.compose_refines(net.words_at(left), given, net.words_at(target), &mut out) {
                proposals.push(Proposal {
                    target: target as u32,
                    transposed: transposed_index(n, target) as u32,
                    canon: canonical(net, target) as u32,
                    left: left as u32,
                    right: pqr as u32,
                    allowed: Allowed::Many(out.as_slice().into()),
                });
            }
        }
    }
    proposals
}

/// The fewest relations a fixed right input is always gathered for ([`SetView::fixed_right`]:
/// a pass over the block entries each); a larger set is gathered when the row is long enough
/// to repay it (one relation per [`GATHER_ROW_POINTS`] points), else each composition reads
/// the block table.
const FIXED_RIGHT_MAX: usize = 4;

/// Points of a row that repay gathering one more relation of a fixed right input.
const GATHER_ROW_POINTS: usize = 8;

/// [`compositions`] for sets of one word, composed by the block tables (EDC and every
/// built-in calculus): the same rules, so the same closed network.
///
/// The innermost loop of every closure, so written for its common case: one input of every
/// rule here is the triplet's own set, fixed over the fourth point `w`. Its block-table entries
/// are taken once ([`SetView::fixed_left`], [`SetView::fixed_right`]), so each composition
/// is one lookup per block of the other input, whatever that set holds — no branch on whether
/// it is single, universal or neither — and a row of the network (`{p,q:w}` over `w`) is one
/// pass of lookups and a test, instantiated per block count ([`scan_row`]). The three points of
/// the triplet itself are skipped only when their entry would refine (their sets repeat a point
/// and are never read), so the pass has no test per point either.
fn compositions_one_word(
    net: &Network,
    transposed: Option<&[u64]>,
    view: &SetView<'_, 1>,
    canon: usize,
    both: bool,
) -> Vec<Proposal> {
    match (view.n_blocks(), view.block()) {
        (1, _) => rows_one_word::<1, 0>(net, transposed, view, canon, both),
        (2, _) => rows_one_word::<2, 0>(net, transposed, view, canon, both),
        // Three bytes: calculi of 17 to 24 relations, EDC's 20 among them.
        (3, 8) => rows_one_word::<3, 8>(net, transposed, view, canon, both),
        (3, _) => rows_one_word::<3, 0>(net, transposed, view, canon, both),
        // More blocks have no gathered entries (`fixed_left` is `None`): any count serves.
        _ => rows_one_word::<0, 0>(net, transposed, view, canon, both),
    }
}

fn rows_one_word<const NB: usize, const B: usize>(
    net: &Network,
    transposed: Option<&[u64]>,
    view: &SetView<'_, 1>,
    canon: usize,
    both: bool,
) -> Vec<Proposal> {
    let n = net.n_points();
    let nn = n * n;
    let [a, b, c] = net.triplet(canon);
    let sets = net.one_word_sets();
    let mut proposals = Vec::new();
    let (mut left_buf, mut right_buf) = (Vec::new(), Vec::new());
    // A universal set of the triplet's refines nothing as either input when `U` absorbs
    // (EDC's tables: `U ∘ s = s ∘ U = U`): half of a half-known network's rule instances.
    let universal = view.universal[0];
    let (absorbs_left, absorbs_right) = (
        view.universal_absorbs_from_left(),
        view.universal_absorbs_from_right(),
    );
    let own = |w: usize| w == a || w == b || w == c;
    // The canonical index of {x, y, w} for x, y of the triplet: what the applying loop queues.
    let canonical_with = |x: usize, y: usize, w: usize| {
        let (lo, hi) = (x.min(y), x.max(y));
        let t = if w < lo {
            [w, lo, hi]
        } else if w < hi {
            [lo, w, hi]
        } else {
            [lo, hi, w]
        };
        ((t[0] * n + t[1]) * n + t[2]) as u32
    };
    let max_right = FIXED_RIGHT_MAX.max(n / GATHER_ROW_POINTS);
    for (p, q, r) in processing_order(a, b, c) {
        let pqr = net.index(p, q, r);
        let given = sets[pqr];
        if !(given == universal && absorbs_left) {
            // {p,q:w} ⊆ {p,q:r} ∘ {q,r:w}, over w: a row of targets, a row of right inputs.
            let (pq, qr) = (net.index(p, q, 0), net.index(q, r, 0));
            let (targets, rights) = (&sets[pq..pq + n], &sets[qr..qr + n]);
            let mut found = |w: usize, acc: u64| {
                if !own(w) {
                    proposals.push(Proposal {
                        target: (pq + w) as u32,
                        transposed: ((q * n + w) * n + p) as u32,
                        canon: canonical_with(p, q, w),
                        left: pqr as u32,
                        right: (qr + w) as u32,
                        allowed: Allowed::One([acc]),
                    });
                }
            };
            match view.fixed_left(&[given], &mut left_buf) {
                Some(e) if NB > 0 && e.len() >= NB << B => scan_row(
                    rights.iter().copied(),
                    targets.iter().copied(),
                    |x| view.through_word::<NB, B>(e, x),
                    &mut found,
                ),
                _ => refine_row(
                    rights.iter().copied(),
                    targets.iter().copied(),
                    |x, t| {
                        view.composition_refining(&[given], &[x], &[t])
                            .map(|o| o[0])
                    },
                    &mut found,
                ),
            }
        }
        if both && !(given == universal && absorbs_right) {
            // {w,p:r} ⊆ {w,p:q} ∘ {p,q:r}, over w: a column of the network, read as a row of
            // the transposed copy when there is one.
            let (wpr, wpq) = (net.index(0, p, r), net.index(0, p, q));
            let mut found = |w: usize, acc: u64| {
                if !own(w) {
                    proposals.push(Proposal {
                        target: (w * nn + wpr) as u32,
                        transposed: (wpr * n + w) as u32,
                        canon: canonical_with(p, r, w),
                        left: (w * nn + wpq) as u32,
                        right: pqr as u32,
                        allowed: Allowed::One([acc]),
                    });
                }
            };
            let entries = view.fixed_right(&[given], max_right, &mut right_buf);
            let compose = |x: u64, t: u64| {
                view.composition_refining(&[x], &[given], &[t])
                    .map(|o| o[0])
            };
            match (transposed, entries) {
                (Some(tr), Some(e)) if NB > 0 && e.len() >= NB << B => scan_row(
                    tr[wpq * n..][..n].iter().copied(),
                    tr[wpr * n..][..n].iter().copied(),
                    |x| view.through_word::<NB, B>(e, x),
                    &mut found,
                ),
                (Some(tr), _) => refine_row(
                    tr[wpq * n..][..n].iter().copied(),
                    tr[wpr * n..][..n].iter().copied(),
                    compose,
                    &mut found,
                ),
                (None, Some(e)) if NB > 0 && e.len() >= NB << B => scan_row(
                    sets[wpq..].iter().step_by(nn).copied(),
                    sets[wpr..].iter().step_by(nn).copied(),
                    |x| view.through_word::<NB, B>(e, x),
                    &mut found,
                ),
                (None, _) => refine_row(
                    sets[wpq..].iter().step_by(nn).copied(),
                    sets[wpr..].iter().step_by(nn).copied(),
                    compose,
                    &mut found,
                ),
            }
        }
    }
    proposals
}

/// One rule over a row: `others[w]` composed with the fixed set by `compose` (the gathered
/// block entries), reported to `found` where it does not cover `targets[w]`. Always inlined:
/// it is the body of the innermost loop (a call per instance cost a third of ternary closure).
#[inline(always)]
fn scan_row(
    others: impl Iterator<Item = u64>,
    targets: impl Iterator<Item = u64>,
    compose: impl Fn(u64) -> u64,
    found: &mut impl FnMut(usize, u64),
) {
    for (w, (x, t)) in others.zip(targets).enumerate() {
        let acc = compose(x);
        if t & !acc != 0 {
            found(w, acc);
        }
    }
}

/// [`scan_row`] when the fixed set's entries are not gathered: `refines(other, target)` is the
/// composition when it refines the target.
#[inline(always)]
fn refine_row(
    others: impl Iterator<Item = u64>,
    targets: impl Iterator<Item = u64>,
    refines: impl Fn(u64, u64) -> Option<u64>,
    found: &mut impl FnMut(usize, u64),
) {
    for (w, (x, t)) in others.zip(targets).enumerate() {
        if let Some(acc) = refines(x, t) {
            found(w, acc);
        }
    }
}

/// The flat indices of the six orderings of the triplet with canonical index `canon`.
fn orderings(net: &Network, canon: usize) -> [usize; 6] {
    let [a, b, c] = net.triplet(canon);
    all_orderings(a, b, c).map(|(x, y, z)| net.index(x, y, z))
}

/// The index in [`Propagation::transposed`] of the set at `index`.
fn transposed_index(n: usize, index: usize) -> usize {
    (index % (n * n)) * n + index / (n * n)
}

/// The canonical (sorted) index of the unordered triplet of an ordered one.
pub(crate) fn canonical(net: &Network, index: usize) -> usize {
    let mut t = net.triplet(index);
    t.sort_unstable();
    net.index(t[0], t[1], t[2])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Calculus;
    use crate::reason::{StateSet, TableScope};
    use nalgebra::Point2;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Chunks of one triplet: every triplet runs after the refinements of all before it are
    /// applied — triplets refined before their turn, the orders one chunk of a small network
    /// never produces. The closed network is the one a single chunk gives (the work is not).
    /// Fails when a chunk's triplets are not marked as run before its proposals are applied.
    #[test]
    fn closure_by_chunks_of_one_triplet_is_closure_in_one_chunk() {
        let calc = Calculus::builtin("edc").unwrap();
        let alg = Algebra::of(&calc, TableScope::Sound).unwrap();
        let k = calc.n_states();
        let mut rng = ChaCha8Rng::seed_from_u64(38);
        let mut next = move || rng.random::<f64>();
        let mut differ_in_work = 0;
        for trial in 0..12 {
            let n = 9;
            let pts: Vec<Point2<f64>> = (0..n)
                .map(|_| Point2::new(next() * 100.0 - 50.0, next() * 100.0 - 50.0))
                .collect();
            let names: Vec<String> = (0..n).map(|i| format!("P{i}")).collect();
            let mut net = Network::from_points(&calc, names, &pts).unwrap();
            for a in 0..n {
                for b in a + 1..n {
                    for c in b + 1..n {
                        let u = next();
                        if u < 0.7 {
                            let truth = net.get(a, b, c);
                            net.relax(a, b, c);
                            if u < 0.3 {
                                // Vaguely known: the true state among others.
                                let vague = StateSet::from_states(
                                    k,
                                    (0..k)
                                        .map(|s| calc.state(calc.labels()[s].as_str()).unwrap())
                                        .filter(|&s| truth.contains(s) || next() < 0.4),
                                );
                                net.set(a, b, c, &vague);
                            }
                        }
                    }
                }
            }
            let options = ClosureOptions::default();
            let all: Vec<usize> = (0..n)
                .flat_map(|a| (a + 1..n).flat_map(move |b| (b + 1..n).map(move |c| (a, b, c))))
                .map(|(a, b, c)| net.index(a, b, c))
                .collect();
            let whole = close_chunked(net.clone(), &alg, all.clone(), &options, CHUNK).unwrap();
            let single = close_chunked(net.clone(), &alg, all, &options, 1).unwrap();
            assert!(
                whole.is_consistent() && single.is_consistent(),
                "trial {trial}"
            );
            assert!(whole.network == single.network, "trial {trial}");
            differ_in_work += usize::from(whole.stats != single.stats);
        }
        assert!(differ_in_work > 0, "chunks of one ran as one chunk did");
    }
}
