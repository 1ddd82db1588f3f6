//! Which landmark triplets a calculus is learned from (thesis §3.3.2), chosen one way for
//! every caller — the SERGE study's hallway, `qrm serge learn` and the demo.
//!
//! **The rule.** A landmark *set* `{a, b, c}` is a candidate when the three are seen together
//! in at least [`TripletSelection::min_frames`] frames (enough observations for a belief). Up
//! to [`TripletSelection::max_triplets`] candidates are drawn at random, each set at most
//! once, and each drawn set gets a random ordering — which landmark is located (F) and which
//! two make the frame (D, E). A random ordering matters: the sets a robot sees are not
//! ordered, and taking, say, ascending ids would put every F on the side its id happens to
//! lie, so the learned partition would describe the numbering rather than space. Everything
//! random comes from [`TripletSelection::seed`].
//!
//! An observation of a chosen triplet is kept from every frame that sees all three with D
//! and E apart (F has a normalised position).

use std::collections::BTreeMap;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Result, SergeError};
use crate::learn::{TripletObservation, normalise};

/// A landmark seen in a frame: its id, position and covariance (in the frame's coordinates).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sighting {
    /// Landmark id.
    pub id: u32,
    /// Position.
    pub xy: [f64; 2],
    /// Covariance `[[a, b], [b, c]]`.
    pub cov: [[f64; 2]; 2],
}

/// How many triplets to learn from, and which (see the module's rule).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[must_use]
pub struct TripletSelection {
    /// Frames a set must be seen together in.
    pub min_frames: usize,
    /// Most triplets drawn.
    pub max_triplets: usize,
    /// Seed of the draw and the orderings.
    pub seed: u64,
}

/// The triplets chosen and their observations.
#[derive(Debug, Clone, PartialEq)]
pub struct Selected {
    /// Ordered triplets `[D, E, F]`, in the order they were drawn (belief `k` is `triplets[k]`).
    pub triplets: Vec<[u32; 3]>,
    /// How many sets were candidates.
    pub candidates: usize,
    /// Every observation of a chosen triplet, frame by frame.
    pub observations: Vec<TripletObservation>,
}

impl TripletSelection {
    /// Selects from `frames` (each the landmarks one frame saw; an id seen twice in a frame
    /// counts once, its first sighting).
    ///
    /// # Errors
    /// [`SergeError::Empty`] when no set is seen together in `min_frames` frames or
    /// `max_triplets` is 0.
    pub fn select(&self, frames: &[Vec<Sighting>]) -> Result<Selected> {
        let candidates = self.candidates(frames);
        if candidates.is_empty() || self.max_triplets == 0 {
            return Err(SergeError::Empty(format!(
                "no landmark triplet is seen together in {} frames (of {})",
                self.min_frames,
                frames.len()
            )));
        }
        let n = self.max_triplets.min(candidates.len());
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        let mut drawn: Vec<[u32; 3]> = Vec::with_capacity(n);
        let mut triplets: Vec<[u32; 3]> = Vec::with_capacity(n);
        while triplets.len() < n {
            let set = candidates[rng.random_range(0..candidates.len())];
            if drawn.contains(&set) {
                continue;
            }
            drawn.push(set);
            let mut t = set;
            for i in (1..3).rev() {
                t.swap(i, rng.random_range(0..=i));
            }
            triplets.push(t);
        }
        let observations = observations(frames, &triplets);
        Ok(Selected {
            triplets,
            candidates: candidates.len(),
            observations,
        })
    }

    /// The landmark sets (ids ascending) seen together in `min_frames` frames, ascending.
    fn candidates(&self, frames: &[Vec<Sighting>]) -> Vec<[u32; 3]> {
        let mut seen: BTreeMap<[u32; 3], usize> = BTreeMap::new();
        for f in frames {
            let mut ids: Vec<u32> = f.iter().map(|s| s.id).collect();
            ids.sort_unstable();
            ids.dedup();
            for a in 0..ids.len() {
                for b in a + 1..ids.len() {
                    for c in b + 1..ids.len() {
                        *seen.entry([ids[a], ids[b], ids[c]]).or_insert(0) += 1;
                    }
                }
            }
        }
        seen.into_iter()
            .filter(|&(_, n)| n >= self.min_frames)
            .map(|(t, _)| t)
            .collect()
    }
}

/// Every observation of `triplets` in `frames`, frame by frame, triplet by triplet.
fn observations(frames: &[Vec<Sighting>], triplets: &[[u32; 3]]) -> Vec<TripletObservation> {
    let mut out = Vec::new();
    for f in frames {
        let get = |id: u32| f.iter().find(|s| s.id == id);
        for (k, t) in triplets.iter().enumerate() {
            if let (Some(d), Some(e), Some(g)) = (get(t[0]), get(t[1]), get(t[2]))
                && normalise(d.xy, e.xy, g.xy).is_some()
            {
                out.push(TripletObservation {
                    triplet: k,
                    points: [d.xy, e.xy, g.xy],
                    cov: [d.cov, e.cov, g.cov],
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn frame(ids: &[u32]) -> Vec<Sighting> {
        ids.iter()
            .map(|&id| Sighting {
                id,
                xy: [f64::from(id), f64::from(id * id % 7)],
                cov: [[0.1, 0.0], [0.0, 0.1]],
            })
            .collect()
    }

    #[test]
    fn sets_count_whatever_the_order_ids_come_in() {
        let frames = vec![frame(&[3, 1, 2]), frame(&[2, 3, 1]), frame(&[1, 2, 3, 4])];
        let sel = TripletSelection {
            min_frames: 3,
            max_triplets: 10,
            seed: 1,
        };
        let s = sel.select(&frames).unwrap();
        assert_eq!(s.candidates, 1, "{{1, 2, 3}} in three frames; no other set");
        let mut t = s.triplets[0];
        t.sort_unstable();
        assert_eq!(t, [1, 2, 3]);
        assert_eq!(s.observations.len(), 3);
    }

    #[test]
    fn each_set_once_with_orderings_of_every_kind() {
        let frames: Vec<Vec<Sighting>> = (0..4).map(|_| frame(&[1, 2, 3, 4, 5, 6, 7])).collect();
        let sel = TripletSelection {
            min_frames: 4,
            max_triplets: 35,
            seed: 9,
        };
        let s = sel.select(&frames).unwrap();
        assert_eq!(s.candidates, 35);
        assert_eq!(s.triplets.len(), 35, "all 35 sets of 7");
        let mut sets: Vec<[u32; 3]> = s
            .triplets
            .iter()
            .map(|t| {
                let mut t = *t;
                t.sort_unstable();
                t
            })
            .collect();
        sets.sort_unstable();
        sets.dedup();
        assert_eq!(sets.len(), 35, "no set twice");
        // random orderings: F is not always the largest id (ascending order would make it so)
        let largest_last = s.triplets.iter().filter(|t| t[2] > t[0] && t[2] > t[1]);
        assert!(largest_last.count() < 30);
        // the same seed draws the same; another draws otherwise
        assert_eq!(sel.select(&frames).unwrap(), s);
        let other = TripletSelection { seed: 10, ..sel };
        assert_ne!(other.select(&frames).unwrap().triplets, s.triplets);
    }

    #[test]
    fn nothing_seen_often_enough_is_an_error() {
        let frames = vec![frame(&[1, 2, 3])];
        let sel = TripletSelection {
            min_frames: 2,
            max_triplets: 5,
            seed: 0,
        };
        let e = sel.select(&frames).unwrap_err().to_string();
        assert!(e.contains("seen together in 2 frames"), "{e}");
        let none = TripletSelection {
            min_frames: 1,
            max_triplets: 0,
            seed: 0,
        };
        assert!(none.select(&frames).is_err());
    }
}
