//! The consistency check of a map's most likely states.

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::reason::{Algebra, ClosureOptions, Network, TableScope, close_with};
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::likelihood::LandmarkSet;
use crate::map::Pqrm;
use crate::observation::LandmarkId;
use crate::reason::network::{Selection, canonical, landmarks, observed_sets, select, to_network};

/// An observed set whose most likely state the check had to give up.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FlaggedEntry {
    /// The set in canonical (increasing-id) order.
    pub set: [u32; 3],
    /// Its most likely state (label).
    pub state: String,
    /// The probability of that state.
    pub p: f64,
}

/// The result of [`check`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapCheck {
    /// Observed (unordered) sets.
    pub sets: usize,
    /// Whether the most likely states as they are survive closure.
    pub consistent: bool,
    /// The first contradiction, described (when not consistent).
    pub contradiction: Option<String>,
    /// The entries relaxed to restore consistency, least probable first.
    pub flagged: Vec<FlaggedEntry>,
    /// Closures run.
    pub closures: usize,
}

/// A relaxed set with its most likely state and that state's probability.
fn flagged_entry(map: &Pqrm, s: LandmarkSet) -> FlaggedEntry {
    let p = map.belief(s).unwrap_or_default();
    let ml = select(&p, Selection::MostLikely)[0];
    FlaggedEntry {
        set: s.ids(),
        state: map.calculus().label(ml).to_owned(),
        p: p.get(ml.index()).copied().unwrap_or(0.0),
    }
}

/// How sure the map is of a set's most likely state: `−ln P(not ML)` in nats, computed in log
/// space from the stored belief, so beliefs whose P(ML) rounds to 1 in f64 still rank (a set
/// seen in 40 frames above one seen in 2).
fn confidence(map: &Pqrm, set: LandmarkSet) -> f64 {
    let log_p: Vec<f64> = match map.record(&set) {
        Some(r) => r.log_p.clone(),
        None => map
            .belief(set)
            .unwrap_or_default()
            .iter()
            .map(|p| p.ln())
            .collect(),
    };
    let Some(ml) = (0..log_p.len()).reduce(|b, i| if log_p[i] > log_p[b] { i } else { b }) else {
        return 0.0;
    };
    let rest: Vec<f64> = log_p
        .iter()
        .enumerate()
        .filter(|(i, _)| *i != ml)
        .map(|(_, l)| *l)
        .collect();
    let max = rest.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if max == f64::NEG_INFINITY {
        return f64::INFINITY;
    }
    -(max + rest.iter().map(|l| (l - max).exp()).sum::<f64>().ln())
}

/// Checks a map's most likely states against each other with algebraic closure (sound
/// tables). When closure refutes them, entries are relaxed greedily by belief: among the
/// observed sets the contradiction's explanation names, the one whose most likely state is
/// least certain (largest probability of the other states, in log space) is made universal, and closure runs again, until it no longer refutes the
/// network. A second pass restores each relaxed entry, most probable first, where that
/// keeps the network consistent, so every entry left flagged is needed. The result is
/// *irreducible*, not necessarily the smallest set (finding that is NP-hard).
///
/// # Errors
/// [`crate::PqrmError::Calculus`] for a calculus without ternary tables or a map too large.
pub fn check(map: &Pqrm) -> Result<MapCheck> {
    let algebra = Algebra::of(map.calculus(), TableScope::Sound)?;
    let ids = landmarks(map);
    let index: BTreeMap<LandmarkId, usize> = ids.iter().enumerate().map(|(i, l)| (*l, i)).collect();
    let base = to_network(map, Selection::MostLikely)?;
    let sets = observed_sets(map);
    // The confidence of each set's most likely state: the relaxation order (least first).
    let p_ml: BTreeMap<LandmarkSet, f64> = sets.iter().map(|s| (*s, confidence(map, *s))).collect();
    let options = ClosureOptions::default();
    let mut closures = 0;
    let relax = |net: &mut Network, s: LandmarkSet| {
        let [a, b, c] = s.0.map(|l| index[&l]);
        net.relax(a, b, c);
    };
    let consistent_with = |relaxed: &BTreeSet<LandmarkSet>, closures: &mut usize| {
        let mut net = base.clone();
        for s in relaxed {
            relax(&mut net, *s);
        }
        *closures += 1;
        close_with(net, &algebra, &options)
    };
    let mut relaxed: BTreeSet<LandmarkSet> = BTreeSet::new();
    let first = consistent_with(&relaxed, &mut closures)?;
    let first_text = first
        .contradiction
        .as_ref()
        .map(|c| c.describe(&first.network));
    let mut current = first;
    while let Some(c) = current.contradiction.clone() {
        let names = current.network.names().to_vec();
        let to_set = |t: [usize; 3]| -> Option<LandmarkSet> {
            let id = |i: usize| names[i].parse::<u32>().ok();
            let s = canonical(LandmarkSet::new(id(t[0])?, id(t[1])?, id(t[2])?));
            p_ml.contains_key(&s).then_some(s)
        };
        let named = std::iter::once(c.triplet)
            .chain(c.steps.iter().map(|s| s.triplet))
            .filter_map(to_set)
            .filter(|s| !relaxed.contains(s));
        let pick = named
            .min_by(|a, b| p_ml[a].total_cmp(&p_ml[b]).then(a.cmp(b)))
            .or_else(|| {
                // The explanation named nothing left to relax: the least probable entry.
                sets.iter()
                    .filter(|s| !relaxed.contains(s))
                    .min_by(|a, b| p_ml[a].total_cmp(&p_ml[b]).then(a.cmp(b)))
                    .copied()
            });
        let Some(pick) = pick else { break };
        relaxed.insert(pick);
        current = consistent_with(&relaxed, &mut closures)?;
    }
    // Restore what is not needed, most probable first.
    let mut order: Vec<LandmarkSet> = relaxed.iter().copied().collect();
    order.sort_by(|a, b| p_ml[b].total_cmp(&p_ml[a]).then(a.cmp(b)));
    for s in order {
        relaxed.remove(&s);
        if !consistent_with(&relaxed, &mut closures)?.is_consistent() {
            relaxed.insert(s);
        }
    }
    let mut flagged: Vec<FlaggedEntry> = relaxed.iter().map(|s| flagged_entry(map, *s)).collect();
    flagged.sort_by(|a, b| a.p.total_cmp(&b.p).then(a.set.cmp(&b.set)));
    Ok(MapCheck {
        sets: sets.len(),
        consistent: first_text.is_none(),
        contradiction: first_text,
        flagged,
        closures,
    })
}
