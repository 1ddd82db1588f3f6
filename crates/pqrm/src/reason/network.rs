//! A PQRM as a constraint network, and the landmark sets it observed.

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::StateId;
use qsr_core::reason::{Network, StateSet};

use crate::error::Result;
use crate::likelihood::LandmarkSet;
use crate::map::Pqrm;
use crate::observation::LandmarkId;

/// Which states of a belief become a constraint.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Selection {
    /// The most likely state only.
    MostLikely,
    /// Every state with probability at least this (the most likely one if none reaches it).
    AboveProbability(f64),
}

/// The landmarks a map has beliefs about, in id order.
#[must_use]
pub fn landmarks(map: &Pqrm) -> Vec<LandmarkId> {
    let set: BTreeSet<LandmarkId> = map.iter().flat_map(|(s, _)| s.0).collect();
    set.into_iter().collect()
}

/// The unordered sets the map has beliefs about, as canonical (increasing-id) sets.
#[must_use]
pub fn observed_sets(map: &Pqrm) -> Vec<LandmarkSet> {
    let set: BTreeSet<LandmarkSet> = map.iter().map(|(s, _)| canonical(*s)).collect();
    set.into_iter().collect()
}

pub(crate) fn canonical(s: LandmarkSet) -> LandmarkSet {
    let mut ids = s.ids();
    ids.sort_unstable();
    LandmarkSet::new(ids[0], ids[1], ids[2])
}

/// The six orderings of a set, `(a,b,c)` first.
pub fn orderings(s: LandmarkSet) -> [LandmarkSet; 6] {
    let [a, b, c] = s.ids();
    qsr_core::all_orderings(a, b, c).map(|(x, y, z)| LandmarkSet::new(x, y, z))
}

/// The map as a constraint network over its landmarks (named by id): observed sets are
/// constrained by `selection`, the others universal.
///
/// # Errors
/// [`crate::PqrmError::Calculus`] when the network would not fit in memory.
pub fn to_network(map: &Pqrm, selection: Selection) -> Result<Network> {
    let ids = landmarks(map);
    let index: BTreeMap<LandmarkId, usize> = ids.iter().enumerate().map(|(i, l)| (*l, i)).collect();
    let calc = map.calculus();
    let mut net = Network::universal(calc, ids.iter().map(|l| l.0.to_string()))?;
    for set in observed_sets(map) {
        for o in orderings(set) {
            let Some(p) = map.belief(o) else { continue };
            let states = select(&p, selection);
            let [a, b, c] = o.0.map(|l| index[&l]);
            net.constrain(a, b, c, &StateSet::from_states(calc.n_states(), states));
        }
    }
    Ok(net)
}

pub(crate) fn select(p: &[f64], selection: Selection) -> Vec<StateId> {
    let ml = (0..p.len()).fold(0, |best, i| if p[i] > p[best] { i } else { best });
    let ml = StateId(ml as u16);
    match selection {
        Selection::MostLikely => vec![ml],
        Selection::AboveProbability(t) => {
            let v: Vec<StateId> = (0..p.len())
                .filter(|i| p[*i] >= t)
                .map(|i| StateId(i as u16))
                .collect();
            if v.is_empty() { vec![ml] } else { v }
        }
    }
}
