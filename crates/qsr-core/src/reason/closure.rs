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
//! changed (AC-3 style), so the fixpoint is reached with each refinement done once.
//!
//! Queued triplets are processed in rounds: the compositions of one round are evaluated in
//! parallel against the network as it stands, then applied in triplet order. The closed
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
    mut network: Network,
    algebra: &Algebra,
    frontier: Vec<usize>,
    options: &ClosureOptions,
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
        let mut queued = vec![false; n * n * n];
        // Every composition rule instance `{a,b:d} ⊆ {a,b:c} ∘ {b,c:d}` has a left input, so
        // a first round over every triplet evaluates each instance once from its left input
        // (rule 1 below) and skips the right-input copies (rule 2), which read the network a
        // column at a time. A triplet whose sets change after an instance read them is queued,
        // and later rounds run both rules, as does a triplet its own permutations refined.
        let mut left_only = frontier.len() == n * n.saturating_sub(1) * n.saturating_sub(2) / 6;
        if left_only && alg.one_word().is_some() && n <= MAX_TRANSPOSED_POINTS {
            let sets = net.one_word_sets();
            let mut t = vec![0u64; n * n * n];
            for (i, &set) in sets.iter().enumerate().take(n * n * n) {
                t[(i % (n * n)) * n + i / (n * n)] = set;
            }
            self.transposed = Some(t);
        }
        while !frontier.is_empty() {
            frontier.sort_unstable();
            frontier.dedup();
            self.stats.rounds += 1;
            self.stats.triplets_processed += frontier.len();
            for &t in &frontier {
                queued[t] = false;
            }
            let mut next = Vec::new();
            // Fixed-size chunks (never thread-count dependent): each chunk's compositions are
            // evaluated in parallel against the network as the chunks before it left it, then
            // applied in order. Bounded memory (a round over all triplets of 200 points would
            // otherwise hold ~10^9 proposals), and later chunks see earlier refinements.
            for chunk in frontier.chunks(CHUNK) {
                let mut both = Vec::with_capacity(chunk.len());
                for &t in chunk {
                    both.push(self.sync_permutations(net, alg, t)? || !left_only);
                }
                let snapshot: &Network = net;
                let transposed = self.transposed.as_deref();
                let proposals: Vec<Vec<Proposal>> = chunk
                    .par_iter()
                    .zip(&both)
                    .map(|(&t, &both)| compositions(snapshot, transposed, alg, t, both))
                    .collect();
                for p in proposals.into_iter().flatten() {
                    let target = p.target as usize;
                    if self.refine(
                        net,
                        target,
                        p.allowed.words(),
                        Reason::Composition(p.left, p.right),
                    )? {
                        let canon = canonical(net, target);
                        if !queued[canon] {
                            queued[canon] = true;
                            next.push(canon);
                        }
                    }
                }
            }
            frontier = next;
            left_only = false;
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
            let n = net.n_points();
            t[(target % (n * n)) * n + target / (n * n)] = net.words_at(target)[0];
        }
        if let Some(r) = &mut self.reasons {
            r[target] = reason;
        }
        Ok(true)
    }

    /// Makes the six orderings of one unordered triplet agree through the permutation tables;
    /// whether that changed any.
    fn sync_permutations(
        &mut self,
        net: &mut Network,
        alg: &Algebra,
        canon: usize,
    ) -> Result<bool, Emptied> {
        let [a, b, c] = net.triplet(canon);
        let mut any = false;
        let mut permuted = vec![0u64; alg.words()];
        loop {
            let mut changed = false;
            for (x, y, z) in processing_order(a, b, c) {
                let from = net.index(x, y, z);
                for op in Permutation::ALL {
                    let (p, q, r) = op.apply(x, y, z);
                    let to = net.index(p, q, r);
                    alg.permute_into(op, net.words_at(from), &mut permuted);
                    changed |=
                        self.refine(net, to, &permuted, Reason::Permutation(op, from as u32))?;
                }
            }
            if !changed {
                return Ok(any);
            }
            any = true;
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
                    left: left as u32,
                    right: pqr as u32,
                    allowed: Allowed::Many(out.as_slice().into()),
                });
            }
        }
    }
    proposals
}

/// The most relations a fixed right input is gathered for ([`SetView::fixed_right`]: a
/// pass over the block entries each; past it, each composition reads the block table).
const FIXED_RIGHT_MAX: usize = 4;

/// [`compositions`] for sets of one word, composed by the block tables (EDC and every
/// built-in calculus): the same rules in the same order, so the same proposals.
///
/// The innermost loop of every closure, so written for its common case: one input of every
/// rule here is the triplet's own set, fixed over the fourth point `w`. Its block-table entries
/// are taken once ([`SetView::fixed_left`], [`SetView::fixed_right`]), so each composition
/// is one lookup per block of the other input; two single states read the base table. Rows of the
/// network (`{p,q:w}` over `w`) are read as slices, without a bounds check per point.
fn compositions_one_word(
    net: &Network,
    transposed: Option<&[u64]>,
    view: &SetView<'_, 1>,
    canon: usize,
    both: bool,
) -> Vec<Proposal> {
    let n = net.n_points();
    let [a, b, c] = net.triplet(canon);
    let sets = net.one_word_sets();
    let mut proposals = Vec::new();
    let (mut left_buf, mut right_buf) = (Vec::new(), Vec::new());
    let single = |x: u64| crate::binary::set_ops::single(&[x]);
    // A universal set of the triplet's refines nothing as either input when `U` absorbs
    // (EDC's tables: `U ∘ s = s ∘ U = U`): half of a half-known network's rule instances.
    let universal = view.universal[0];
    let (absorbs_left, absorbs_right) = (
        view.universal_absorbs_from_left(),
        view.universal_absorbs_from_right(),
    );
    for (p, q, r) in processing_order(a, b, c) {
        let pqr = net.index(p, q, r);
        let given = sets[pqr];
        let left_rule = !(given == universal && absorbs_left);
        let right_rule = both && !(given == universal && absorbs_right);
        if !left_rule && !right_rule {
            continue;
        }
        // Index strides: {p,q:w} = pq + w, {q,r:w} = qr + w, {w,p:r} = w·n² + pr,
        // {w,p:q} = w·n² + pq'.
        let (pq, qr) = (net.index(p, q, 0), net.index(q, r, 0));
        let (wpr, wpq) = (net.index(0, p, r), net.index(0, p, q));
        let nn = n * n;
        let (targets, rights) = (&sets[pq..pq + n], &sets[qr..qr + n]);
        let given_single = single(given);
        let row = if left_rule {
            view.fixed_left(&[given], &mut left_buf)
        } else {
            None
        };
        let col = if right_rule {
            view.fixed_right(&[given], FIXED_RIGHT_MAX, &mut right_buf)
        } else {
            None
        };
        for w in 0..n {
            if w == a || w == b || w == c {
                continue;
            }
            // {p,q:w} ⊆ {p,q:r} ∘ {q,r:w}
            if left_rule
                && let Some(acc) =
                    refining_one_word(view, row, given_single, rights[w], given, true, targets[w])
            {
                proposals.push(Proposal {
                    target: (pq + w) as u32,
                    left: pqr as u32,
                    right: (qr + w) as u32,
                    allowed: Allowed::One([acc]),
                });
            }
            if !right_rule {
                continue;
            }
            // {w,p:r} ⊆ {w,p:q} ∘ {p,q:r}
            let (target, left) = (w * nn + wpr, w * nn + wpq);
            let (left_set, target_set) = match transposed {
                Some(t) => (t[wpq * n + w], t[wpr * n + w]),
                None => (sets[left], sets[target]),
            };
            if let Some(acc) =
                refining_one_word(view, col, given_single, left_set, given, false, target_set)
            {
                proposals.push(Proposal {
                    target: target as u32,
                    left: left as u32,
                    right: pqr as u32,
                    allowed: Allowed::One([acc]),
                });
            }
        }
    }
    proposals
}

/// The composition of one rule instance when it refines `target` (see
/// [`compositions_one_word`]): two single states by the base table (a scenario's every
/// instance); the triplet's own set `fixed` by its block entries (`entries`), one lookup per
/// block of the other input; otherwise the blocks of both. Always inlined: it is the body of
/// the innermost loop, and a call per instance cost a third of ternary closure.
#[inline(always)]
fn refining_one_word(
    view: &SetView<'_, 1>,
    entries: Option<&[[u64; 1]]>,
    given_single: Option<usize>,
    other: u64,
    fixed: u64,
    fixed_left: bool,
    target: u64,
) -> Option<u64> {
    let acc = match (
        given_single.zip(crate::binary::set_ops::single(&[other])),
        entries,
    ) {
        (Some((g, o)), _) if fixed_left => view.base_at(g, o)[0],
        (Some((g, o)), _) => view.base_at(o, g)[0],
        (None, Some(e)) => view.through(e, &[other])[0],
        (None, None) if fixed_left => {
            return view
                .composition_refining(&[fixed], &[other], &[target])
                .map(|o| o[0]);
        }
        (None, None) => {
            return view
                .composition_refining(&[other], &[fixed], &[target])
                .map(|o| o[0]);
        }
    };
    (target & !acc != 0).then_some(acc)
}

/// The flat indices of the six orderings of the triplet with canonical index `canon`.
fn orderings(net: &Network, canon: usize) -> [usize; 6] {
    let [a, b, c] = net.triplet(canon);
    all_orderings(a, b, c).map(|(x, y, z)| net.index(x, y, z))
}

/// The canonical (sorted) index of the unordered triplet of an ordered one.
pub(crate) fn canonical(net: &Network, index: usize) -> usize {
    let mut t = net.triplet(index);
    t.sort_unstable();
    net.index(t[0], t[1], t[2])
}
