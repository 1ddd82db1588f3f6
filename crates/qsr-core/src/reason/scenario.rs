//! Scenario search ([`find_scenario`]): backtracking over base relations with algebraic
//! closure as forward checking — SparQ's `scenario-consistency first`.
//!
//! A *scenario* is a network in which every ordered triplet holds one state. The search
//! closes the network, picks the unordered triplet with the fewest remaining states (ties:
//! the lowest index), tries each of its canonical ordering's states in id order, closes only
//! the consequences of that choice, and recurses. The first algebraically closed scenario is
//! returned. For ternary point calculi algebraic closure is not complete, so a scenario found
//! is "not refuted by closure", not a proof of realisability; "none" is a proof that no
//! configuration realises the network (given complete tables).

use crate::reason::algebra::Algebra;
use crate::reason::closure::{ClosureOptions, close_from, close_with};
use crate::reason::network::Network;
use crate::reason::state_set::{StateSet, count, iter_bits};

/// Options of [`find_scenario`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ScenarioOptions {
    /// The most search nodes (closures after a choice) before giving up.
    pub max_nodes: usize,
}

impl Default for ScenarioOptions {
    fn default() -> Self {
        Self { max_nodes: 100_000 }
    }
}

/// What [`find_scenario`] found.
#[derive(Debug, Clone)]
pub enum ScenarioOutcome {
    /// An algebraically closed scenario refining the network.
    Found(Box<Network>),
    /// Every branch was refuted: no configuration satisfies the network.
    None,
    /// The node budget ran out first.
    GaveUp {
        /// Nodes searched.
        nodes: usize,
    },
}

/// Finds one algebraically closed scenario of `network`, or proves there is none.
///
/// ```
/// use qsr_core::{Calculus, reason::{Algebra, Network, ScenarioOptions, ScenarioOutcome,
///     TableScope, find_scenario}};
/// let lr = Calculus::builtin("left-right")?;
/// let alg = Algebra::of(&lr, TableScope::Sound)?;
/// let net = Network::universal(&lr, ["A", "B", "C", "D"])?;
/// match find_scenario(net, &alg, &ScenarioOptions::default())? {
///     ScenarioOutcome::Found(s) => assert!(s.is_atomic()),
///     other => panic!("expected a scenario, got {other:?}"),
/// }
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
///
/// # Errors
/// As [`crate::reason::close`].
pub fn find_scenario(
    network: Network,
    algebra: &Algebra,
    options: &ScenarioOptions,
) -> crate::Result<ScenarioOutcome> {
    let quiet = ClosureOptions::without_explanation();
    let closed = close_with(network, algebra, &quiet)?;
    if !closed.is_consistent() {
        return Ok(ScenarioOutcome::None);
    }
    let mut nodes = 0usize;
    search(closed.network, algebra, options, &quiet, &mut nodes)
}

fn search(
    net: Network,
    alg: &Algebra,
    options: &ScenarioOptions,
    quiet: &ClosureOptions,
    nodes: &mut usize,
) -> crate::Result<ScenarioOutcome> {
    // The ordered triplet with the fewest states above one.
    let n = net.n_points();
    let mut pick: Option<(usize, usize)> = None;
    for a in 0..n {
        for b in 0..n {
            for c in 0..n {
                if a == b || b == c || a == c {
                    continue;
                }
                let i = net.index(a, b, c);
                let k = count(net.words_at(i));
                if k > 1 && pick.is_none_or(|(_, best)| k < best) {
                    pick = Some((i, k));
                }
            }
        }
    }
    let Some((index, _)) = pick else {
        return Ok(ScenarioOutcome::Found(Box::new(net)));
    };
    let [a, b, c] = net.triplet(index);
    let states: Vec<_> = iter_bits(net.words_at(index)).collect();
    for s in states {
        if *nodes >= options.max_nodes {
            return Ok(ScenarioOutcome::GaveUp { nodes: *nodes });
        }
        *nodes += 1;
        let mut child = net.clone();
        child.set(a, b, c, &StateSet::single(alg.n_states(), s));
        let canon = crate::reason::closure::canonical(&child, index);
        let closed = close_from(child, alg, vec![canon], quiet)?;
        if !closed.is_consistent() {
            continue;
        }
        match search(closed.network, alg, options, quiet, nodes)? {
            ScenarioOutcome::None => {}
            found_or_gave_up => return Ok(found_or_gave_up),
        }
    }
    Ok(ScenarioOutcome::None)
}
