//! Path consistency of binary networks ([`close_binary`]) and the propagator that the
//! consistency search ([`super::solve_binary`]) runs at every node.
//!
//! The algorithm is PC-2 as GQR runs it: a queue of edges `(i, j)`, `i < j`, lightest set
//! first ([`super::edge_queue`]); popping one
//! revises `R(i,k) ← R(i,k) ∩ R(i,j) ∘ R(j,k)` and `R(k,j) ← R(k,j) ∩ R(k,i) ∘ R(i,j)` for
//! every other `k`, and queues what changed. The matrix keeps both directions (`R(j,i)` is the
//! converse of `R(i,j)`), so each revision reads two sets and the other three revisions of a
//! triangle follow by converse (`(R ∘ S)˘ = S˘ ∘ R˘`, which [`super::BinaryAlgebra::check`]
//! reports). Sets are `[u64; W]` with `W` fixed at compile time, composed by
//! [`super::set_ops`]'s block tables; for one-word sets of at most 16 relations (RCC-8, Allen,
//! the point algebra) the loop is instantiated per layout of the compact table, so a
//! composition is one lookup (≤ 8 relations) or four with constant shifts and no bounds check
//! (on Allen's 320-node networks split into ORD-Horn, a third of the time of the general
//! loop). An edge nothing constrains starts outside the queue
//! when `U ∘ U = U`: each revision runs when either of its two inputs is popped, so one with
//! two universal inputs can refine nothing.
//!
//! The fixpoint (the largest path-consistent refinement) is unique, so the result does not
//! depend on the order of the queue; the contradiction reported is the first one met in the
//! fixed order, single-threaded.

use super::edge_queue::EdgeQueue;
use super::network::BinaryNetwork;
use super::set_ops::{SetOps, SetView, compose_compact};

/// Why a binary network is inconsistent.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryContradiction {
    /// The relation of `(a, b)` was empty as given (e.g. two disjoint sets for one pair).
    Given {
        /// First point.
        a: usize,
        /// Second point.
        b: usize,
    },
    /// `R(a,b) ∩ R(a,via) ∘ R(via,b)` emptied during closure.
    Composed {
        /// First point.
        a: usize,
        /// The point in between.
        via: usize,
        /// Last point.
        b: usize,
    },
}

/// The outcome of [`close_binary`].
#[derive(Debug, Clone)]
pub struct BinaryClosure {
    /// The closed network (on a contradiction: as it stood when a set emptied).
    pub network: BinaryNetwork,
    /// Set when the network is inconsistent.
    pub contradiction: Option<BinaryContradiction>,
    /// Sets narrowed.
    pub revisions: usize,
}

impl BinaryClosure {
    /// Whether closure found no contradiction.
    #[must_use]
    pub fn is_consistent(&self) -> bool {
        self.contradiction.is_none()
    }

    /// The contradiction in words, naming the points.
    #[must_use]
    pub fn describe(&self) -> Option<String> {
        let n = self.network.names();
        self.contradiction.map(|c| match c {
            BinaryContradiction::Given { a, b } => format!(
                "the constraints given for {} and {} leave no relation (disjoint sets?)",
                n[a], n[b]
            ),
            BinaryContradiction::Composed { a, via, b } => format!(
                "no relation between {} and {} agrees with {}–{} and {}–{}",
                n[a], n[b], n[a], n[via], n[via], n[b]
            ),
        })
    }
}

/// Algebraic closure (path consistency): `R(i,k) ← R(i,k) ∩ R(i,j) ∘ R(j,k)` over every
/// triple until nothing changes.
///
/// # Errors
/// As [`super::BinaryAlgebra::compose_table`] (a derived calculus too fine to derive its
/// table).
pub fn close_binary(network: BinaryNetwork) -> crate::Result<BinaryClosure> {
    let algebra = network.algebra().clone();
    let ops = algebra.ops()?;
    macro_rules! run {
        ($($w:literal)*) => {
            match ops.words() {
                $($w => close_with::<$w>(network, ops),)*
                _ => Err(words_error(&algebra)),
            }
        };
    }
    run!(1 2 3 4 5 6 8 12 16 24 32)
}

/// Sets wider than closure is compiled for (SetOps pads to one of its word sizes, so only a
/// calculus of more than 2,048 relations gets here).
pub(crate) fn words_error(algebra: &super::BinaryAlgebra) -> crate::QsrError {
    crate::QsrError::TooLarge {
        operation: "closure".into(),
        calculus: algebra.name().to_owned(),
        reason: format!(
            "{} relations; closure runs on calculi of up to {} relations",
            algebra.n_states(),
            super::MAX_LOADED_RELATIONS
        ),
    }
}

fn close_with<const W: usize>(
    mut network: BinaryNetwork,
    ops: &SetOps,
) -> crate::Result<BinaryClosure> {
    let Some(view) = ops.view::<W>() else {
        return Err(words_error(network.algebra()));
    };
    let mut prop = Propagator::<W>::new(&network, view);
    let outcome = prop.start(ops.universal_closed());
    let revisions = prop.revisions;
    prop.write_back(&mut network);
    Ok(BinaryClosure {
        network,
        contradiction: outcome.err(),
        revisions,
    })
}

/// The network as a matrix of `[u64; W]` sets, a queue of edges, and (for the search) a
/// trail of overwritten sets to undo.
pub(crate) struct Propagator<'a, const W: usize> {
    pub(crate) n: usize,
    pub(crate) m: Vec<[u64; W]>,
    pub(crate) view: SetView<'a, W>,
    queue: EdgeQueue,
    /// `(index, old set)` of every overwrite, when recording.
    pub(crate) trail: Option<Vec<(u32, [u64; W])>>,
    pub(crate) revisions: usize,
}

impl<'a, const W: usize> Propagator<'a, W> {
    pub(crate) fn new(network: &BinaryNetwork, view: SetView<'a, W>) -> Self {
        let n = network.n_points();
        let words = network.words_per_set();
        let m = if words == W {
            network.raw_sets().as_chunks::<W>().0.to_vec()
        } else {
            let mut m = vec![[0u64; W]; n * n];
            for (slot, set) in m.iter_mut().zip(network.raw_sets().chunks_exact(words)) {
                slot[..words].copy_from_slice(set);
            }
            m
        };
        Self {
            n,
            m,
            view,
            queue: EdgeQueue::new(n * n),
            trail: None,
            revisions: 0,
        }
    }

    /// Queues every edge (those nothing constrains only when `U ∘ U ≠ U`) and runs; an empty
    /// set as given is a contradiction of its own.
    pub(crate) fn start(&mut self, universal_closed: bool) -> Result<(), BinaryContradiction> {
        let n = self.n;
        for i in 0..n {
            for j in i + 1..n {
                let set = &self.m[i * n + j];
                if set.iter().all(|w| *w == 0) {
                    return Err(BinaryContradiction::Given { a: i, b: j });
                }
                if !(universal_closed && *set == self.view.universal) {
                    self.enqueue(i, j);
                }
            }
        }
        self.run()
    }

    pub(crate) fn enqueue(&mut self, i: usize, j: usize) {
        let (i, j) = if i < j { (i, j) } else { (j, i) };
        let at = i * self.n + j;
        let key = self.view.weight(&self.m[at]);
        self.queue.push(at, key);
    }

    /// Sets `R(i,j)` and its converse, recording the old sets when a trail is kept.
    pub(crate) fn put(&mut self, i: usize, j: usize, set: [u64; W]) {
        let n = self.n;
        if let Some(trail) = &mut self.trail {
            trail.push(((i * n + j) as u32, self.m[i * n + j]));
            trail.push(((j * n + i) as u32, self.m[j * n + i]));
        }
        self.m[j * n + i] = self.view.converse(&set);
        self.m[i * n + j] = set;
    }

    /// Restores the sets overwritten since the trail had `mark` entries.
    pub(crate) fn undo_to(&mut self, mark: usize) {
        if let Some(trail) = &mut self.trail {
            while trail.len() > mark {
                if let Some((at, old)) = trail.pop() {
                    self.m[at as usize] = old;
                }
            }
        }
    }

    /// Empties the queue without running it (after a contradiction, before backtracking).
    pub(crate) fn clear_queue(&mut self) {
        self.queue.clear();
    }

    /// PC-2 until the queue is empty or a set empties.
    pub(crate) fn run(&mut self) -> Result<(), BinaryContradiction> {
        if let Some((nb, block, table)) = self.view.compact_layout() {
            // One word of at most 16 relations (RCC-8, Allen, the point algebra, …): the loop
            // instantiated for the compact table's layout.
            macro_rules! layouts {
                ($(($nb:literal, $b:literal))*) => {
                    match (nb, block) {
                        $(($nb, $b) => return self.run_compact::<$nb, $b>(table),)*
                        _ => {}
                    }
                };
            }
            layouts!((1, 1)(1, 2)(1, 3)(1, 4)(1, 5)(1, 6)(1, 7)(1, 8)(2, 5)(2, 6)(2, 7)(2, 8));
        }
        self.run_general()
    }

    /// [`Self::run`] for one-word sets composed by the compact table of `NB` blocks of `B`
    /// bits ([`compose_compact`]): the same revisions in the same order.
    fn run_compact<const NB: usize, const B: usize>(
        &mut self,
        table: &[u16],
    ) -> Result<(), BinaryContradiction> {
        let Some(table) = table.get(..(NB << B) * (NB << B)) else {
            return self.run_general();
        };
        let n = self.n;
        let word = |set: u64| -> [u64; W] { std::array::from_fn(|_| set) };
        while let Some(edge) = self.queue.pop() {
            let (i, j) = (edge / n, edge % n);
            let (rij, rji) = (self.m[i * n + j][0], self.m[j * n + i][0]);
            for k in 0..n {
                if k == i || k == j {
                    continue;
                }
                // R(i,k) ∩= R(i,j) ∘ R(j,k)
                let mut rik = self.m[i * n + k][0];
                let acc = compose_compact::<NB, B>(table, rij, self.m[j * n + k][0]);
                if rik & !acc != 0 {
                    rik &= acc;
                    self.revisions += 1;
                    self.put(i, k, word(rik));
                    if rik == 0 {
                        self.clear_queue();
                        return Err(BinaryContradiction::Composed { a: i, via: j, b: k });
                    }
                    self.enqueue(i, k);
                }
                // R(j,k) ∩= R(j,i) ∘ R(i,k) (the converse of R(k,j) ∩= R(k,i) ∘ R(i,j))
                let rjk = self.m[j * n + k][0];
                let acc = compose_compact::<NB, B>(table, rji, rik);
                if rjk & !acc != 0 {
                    let new = rjk & acc;
                    self.revisions += 1;
                    self.put(j, k, word(new));
                    if new == 0 {
                        self.clear_queue();
                        return Err(BinaryContradiction::Composed { a: k, via: i, b: j });
                    }
                    self.enqueue(j, k);
                }
            }
        }
        Ok(())
    }

    /// [`Self::run`] for any layout, through [`SetView::refine`].
    fn run_general(&mut self) -> Result<(), BinaryContradiction> {
        let n = self.n;
        while let Some(edge) = self.queue.pop() {
            let (i, j) = (edge / n, edge % n);
            let rij = self.m[i * n + j];
            let rji = self.m[j * n + i];
            for k in 0..n {
                if k == i || k == j {
                    continue;
                }
                // R(i,k) ∩= R(i,j) ∘ R(j,k)
                let mut rik = self.m[i * n + k];
                if let Some(new) = self.view.refine(&rij, &self.m[j * n + k], &rik) {
                    self.revisions += 1;
                    self.put(i, k, new);
                    if new.iter().all(|w| *w == 0) {
                        self.clear_queue();
                        return Err(BinaryContradiction::Composed { a: i, via: j, b: k });
                    }
                    self.enqueue(i, k);
                    rik = new;
                }
                // R(k,j) ∩= R(k,i) ∘ R(i,j), as its converse R(j,k) ∩= R(j,i) ∘ R(i,k): rows
                // i and j are read in order, never a column.
                if let Some(new) = self.view.refine(&rji, &rik, &self.m[j * n + k]) {
                    self.revisions += 1;
                    self.put(j, k, new);
                    if new.iter().all(|w| *w == 0) {
                        self.clear_queue();
                        return Err(BinaryContradiction::Composed { a: k, via: i, b: j });
                    }
                    self.enqueue(j, k);
                }
            }
        }
        Ok(())
    }

    /// Copies the matrix back into the network.
    pub(crate) fn write_back(&self, network: &mut BinaryNetwork) {
        let words = network.words_per_set();
        for (set, slot) in network.raw_sets_mut().chunks_exact_mut(words).zip(&self.m) {
            set.copy_from_slice(&slot[..words]);
        }
    }
}
