//! [`BeliefStore`]: the map's beliefs in flat arrays, so that a map of a million landmark
//! sets costs about a hundred bytes per set instead of a kilobyte.
//!
//! **Why flat.** A `BTreeMap<LandmarkSet, TripletBelief>` spends per set a tree slot, a
//! `Vec` header and a heap block for `Q` doubles (≈ 1 KB per EDC set once the filter's
//! temporaries are counted). Here a set is a 12-byte key in an insertion-ordered hash index
//! (its *slot*), `Q` log-probabilities in one `f32` table and one `u32` update count:
//! ≈ 35 + 4·Q + 4 bytes (EDC, Q = 20: ≈ 120 bytes).
//!
//! **Why `f32` is enough.** The filter adds and renormalises in `f64` and rounds only what it
//! keeps. A stored log-probability `l` is off by at most `|l|·2⁻²⁴`: for the states that carry
//! the probability (`|l|` small) that is ~1e-8 in relative probability, and states with
//! `|l| > 20` weigh less than 2e-9. ML states and entropies stay within 1e-6 of a filter kept
//! in `f64` (`tests/map_scale.rs` checks it over a study's worth of steps). `-inf` (a state
//! ruled out with `floor = 0`) is kept exactly.
//!
//! Slots are in insertion order, which is deterministic (the order of the steps and of
//! [`crate::likelihood::step_counts`]); anything that shows sets to a user sorts them.

use foldhash::fast::FixedState;
use indexmap::IndexSet;

use crate::likelihood::LandmarkSet;

/// Beliefs of landmark sets: slot `i` holds the `i`-th set recorded.
#[derive(Debug, Clone, Default)]
pub(crate) struct BeliefStore {
    n_states: usize,
    index: IndexSet<LandmarkSet, FixedState>,
    /// `n_states` log-probabilities per slot.
    log_p: Vec<f32>,
    /// Steps that observed each slot's set.
    updates: Vec<u32>,
}

impl BeliefStore {
    /// An empty store for beliefs over `n_states` states.
    pub(crate) fn new(n_states: usize) -> Self {
        Self {
            n_states,
            ..Self::default()
        }
    }

    /// Sets recorded.
    pub(crate) fn len(&self) -> usize {
        self.index.len()
    }

    /// The slot of a set.
    pub(crate) fn slot(&self, set: &LandmarkSet) -> Option<usize> {
        self.index.get_index_of(set)
    }

    /// The set in a slot.
    pub(crate) fn set(&self, slot: usize) -> &LandmarkSet {
        &self.index[slot]
    }

    /// Room for `additional` more sets without reallocating (the filter knows a step's new
    /// sets before it records them, so the tables grow once per step and never double past
    /// what they hold).
    pub(crate) fn reserve_exact(&mut self, additional: usize) {
        self.index.reserve_exact(additional);
        self.log_p.reserve_exact(additional * self.n_states);
        self.updates.reserve_exact(additional);
    }

    /// Records a new set (the caller checked it is not recorded) and returns its slot.
    pub(crate) fn push(&mut self, set: LandmarkSet, log_p: &[f64], updates: u32) -> usize {
        self.slot_or_push(set, log_p, updates).0
    }

    /// The slot of a set, recording it with `log_p` and `updates` if it is new (one hash
    /// lookup either way); true when it was new.
    pub(crate) fn slot_or_push(
        &mut self,
        set: LandmarkSet,
        log_p: &[f64],
        updates: u32,
    ) -> (usize, bool) {
        let (slot, new) = self.index.insert_full(set);
        if new {
            self.log_p.extend(log_p.iter().map(|&v| to_stored(v)));
            self.updates.push(updates);
        }
        (slot, new)
    }

    /// The stored log-probabilities of a slot.
    pub(crate) fn row(&self, slot: usize) -> &[f32] {
        &self.log_p[slot * self.n_states..(slot + 1) * self.n_states]
    }

    /// Overwrites a slot's belief.
    pub(crate) fn set_row(&mut self, slot: usize, log_p: &[f64], updates: u32) {
        let q = self.n_states;
        for (d, &v) in self.log_p[slot * q..(slot + 1) * q].iter_mut().zip(log_p) {
            *d = to_stored(v);
        }
        self.updates[slot] = updates;
    }

    /// Overwrites a slot's belief with rows already rounded (as [`Self::row`] gives them).
    pub(crate) fn set_stored_row(&mut self, slot: usize, log_p: &[f32], updates: u32) {
        let q = self.n_states;
        self.log_p[slot * q..(slot + 1) * q].copy_from_slice(log_p);
        self.updates[slot] = updates;
    }

    /// Update count of a slot.
    pub(crate) fn updates(&self, slot: usize) -> u32 {
        self.updates[slot]
    }

    /// Slots ordered by their sets (what users and files see).
    pub(crate) fn sorted_slots(&self) -> Vec<usize> {
        // sorted as packed keys beside their slots, not slots compared through the index:
        // each comparison then reads the two elements it compares instead of two random
        // entries of a 24-byte-per-set table (the sort was 4 % of mapping 10⁶ sets)
        let mut keyed: Vec<(u128, usize)> = self
            .index
            .iter()
            .enumerate()
            .map(|(slot, set)| {
                let [a, b, c] = set.ids();
                (
                    u128::from(a) << 64 | u128::from(b) << 32 | u128::from(c),
                    slot,
                )
            })
            .collect();
        // keys are distinct (a set is recorded once), so an unstable sort is deterministic
        keyed.sort_unstable_by_key(|&(key, _)| key);
        keyed.into_iter().map(|(_, slot)| slot).collect()
    }

    /// Keeps the sets for which `keep` is true (slots stay in insertion order).
    pub(crate) fn retain(&mut self, mut keep: impl FnMut(&LandmarkSet) -> bool) {
        let q = self.n_states;
        let kept: Vec<bool> = self.index.iter().map(&mut keep).collect();
        let mut next = 0;
        for (slot, k) in kept.iter().enumerate() {
            if *k {
                self.log_p.copy_within(slot * q..(slot + 1) * q, next * q);
                self.updates[next] = self.updates[slot];
                next += 1;
            }
        }
        self.log_p.truncate(next * q);
        self.updates.truncate(next);
        let mut flags = kept.into_iter();
        self.index.retain(|_| flags.next().unwrap_or(false));
    }

    /// Bytes held by the tables (capacity, not just length): what a map costs in memory.
    pub(crate) fn heap_bytes(&self) -> usize {
        // an index entry: the key with its cached hash in the entries vector, plus a slot
        // index and a control byte in the hash table
        let entry = std::mem::size_of::<LandmarkSet>() + 8;
        self.index.capacity() * (entry + std::mem::size_of::<usize>() + 1)
            + self.log_p.capacity() * std::mem::size_of::<f32>()
            + self.updates.capacity() * std::mem::size_of::<u32>()
    }
}

/// A log-probability as stored: rounded to `f32` (below `f32::MIN` it is `-inf`: a
/// probability under e^-3.4e38 is zero in either precision).
pub(crate) fn to_stored(v: f64) -> f32 {
    v as f32
}
