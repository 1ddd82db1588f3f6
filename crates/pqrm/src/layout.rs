//! [`Layout`]: the landmark positions every frame of a recording agrees with best, the error
//! its frames share beyond it ([`SharedError`]), and a landmark set's belief read from the two.
//!
//! ## Why
//! Eq. 2.10 multiplies a set's frames as independent evidence; the frames share the true
//! geometry and much of their error, so the filter is sure where it should not be, and how
//! much the frames share differs between recordings: on MRCLAM Dataset 7 the filter's map
//! wants a shared error of `N ≈ 32` frames, on Dataset 5 `N ≈ 2` (`docs/calibration.md`). No
//! constant serves both, and a set's own frames cannot say how much they share. The whole
//! recording can. Every frame is a rigid view of the same landmarks; the positions that fit
//! all frames best (generalised Procrustes analysis: each frame rotated and translated onto the
//! current layout, each landmark then the mean of its aligned sightings, until nothing moves)
//! pool every frame of every landmark — a pair seen together a hundred times and a triplet seen
//! twice alike. What the frames share *beyond* any one layout shows as landmark pairs whose
//! distance the frames see, in their median, longer or shorter than the layout's: a cylinder
//! ranged at its near surface, a robot's range scale, a camera's bearing distortion. Their
//! spread over the recording's pairs is the shared error, measured without ground truth, in
//! metres, on each recording anew.
//!
//! ## A set's belief
//! Each landmark's true position is read as the layout's, give or take an isotropic normal
//! error of variance `σ_shared,i²/2 + σ_frame²/(2·n_i)` per axis — its shared error (a pair's
//! distance error is the difference of two landmarks', hence the halves) and the standard
//! error of the mean of its `n_i` sightings. The set's belief is the share of draws of the three
//! positions that fall in each state, with one pseudo-draw spread over the states so no state
//! is impossible. The six orderings of one triplet read the same draws, so their beliefs are
//! each other's permutations.
//!
//! ## The shared error's estimate
//! For each landmark pair seen together in at least [`MIN_PAIR_FRAMES`] frames, the median
//! over those frames of the distance seen minus the layout's distance (the median: a gross
//! outlier now and then moves it little), and the frames' spread about it (`1.4826 · MAD`).
//! `σ_shared = 1.4826 · median |pair median|` over the pairs, `σ_frame` the median spread —
//! both robust, as a normal's standard deviation; the variance the pair medians have from the
//! frames' own noise (`π/2 · σ²/n`) is taken off, and a landmark with [`MIN_LANDMARK_PAIRS`]
//! pairs gets a shared error of its own. On MRCLAM (`docs/calibration.md`, "The layout"):
//! Datasets 2, 5, 7 give σ_shared 0.063, 0.060, 0.022 m (σ_frame 0.153, 0.125, 0.088 m), and
//! the layout lies 0.253, 0.072, 0.017 m (median) from the survey — Dataset 2's pulled by the
//! pairs its frames and its survey disagree on.
//!
//! A landmark offset the same in every frame (one moved after the survey, a world-fixed
//! mounting error) moves the layout with it and is invisible without the survey — to this
//! estimate as to any other made from the frames alone.

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::progress::Progress;
use qsr_core::{Calculus, Point2};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{PqrmError, Result};
use crate::likelihood::{LandmarkSet, Orderings};
use crate::map::{Pqrm, PqrmConfig};
use crate::observation::{LandmarkId, Scan};
use crate::survey::median;

/// Frames a landmark pair needs before its median distance error counts towards the shared
/// error (as [`crate::survey::MIN_FRAMES`]).
pub const MIN_PAIR_FRAMES: usize = 5;

/// Draws of a set's three positions behind its belief: one state's probability is then known
/// to ±0.011 at worst (binomial, p = ½), well inside a reliability bin.
pub const DEFAULT_DRAWS: usize = 2000;

/// The fit stops when no landmark moves by more than this between two rounds (m).
pub const TOLERANCE_M: f64 = 1e-6;

/// Rounds the fit may take; it stops there, converged or not ([`Layout::converged`]).
pub const MAX_ROUNDS: usize = 20_000;

/// Pairs a landmark needs (each seen in [`MIN_PAIR_FRAMES`] frames) for a shared error of its
/// own: a median of fewer than three values is not a robust one. With fewer it takes the
/// recording's ([`SharedError::sigma_shared`]).
pub const MIN_LANDMARK_PAIRS: usize = 3;

/// One set of a layout map: the set, the frames that saw it, its belief.
pub type SetBelief = (LandmarkSet, u32, Vec<f64>);

/// Scales a median absolute deviation to a normal's standard deviation.
const MAD_TO_SIGMA: f64 = 1.4826;

/// How far the frames of a recording disagree with its layout.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SharedError {
    /// The error the frames share beyond the layout, as a landmark pair's distance (m):
    /// `1.4826 · median |median over frames of (seen − layout distance)|` over the pairs.
    pub sigma_shared: f64,
    /// One frame's spread of a pair's distance about its median (m), the median over pairs.
    pub sigma_frame: f64,
    /// Landmark pairs seen together in at least [`MIN_PAIR_FRAMES`] frames.
    pub pairs: usize,
    /// Whether the frames measured it. With no pair seen in [`MIN_PAIR_FRAMES`] frames (a
    /// recording of a few frames) they cannot: `sigma_frame` is then the observations' own
    /// stated noise (`√2 ·` the median per-axis σ of their covariances, a pair's distance) and
    /// the shared error is taken as large as that — more than any MRCLAM recording measures
    /// (0.28–0.49 of it), so the map errs towards hedging.
    pub measured: bool,
}

impl SharedError {
    /// The `N` of the filter's shared-error model ([`crate::evidence`]) that this recording
    /// measures: `N = σ_frame² / σ_shared²`, the number of independent frames whose noise
    /// equals the error they all share (the model's own definition, `σ² / σ_b²`, read off
    /// the layout instead of chosen for every recording). `∞` with no shared error (or one
    /// too small to tell from it); `None` where the frames did not measure it or disagree
    /// with their layout by more than their own noise (`σ_shared > σ_frame`: ids that do not
    /// name one place, where the layout says nothing about the filter's sets).
    #[must_use]
    pub fn frames(&self) -> Option<f64> {
        // NaN compares false: a broken estimate says nothing either
        let agrees = matches!(
            self.sigma_shared.partial_cmp(&self.sigma_frame),
            Some(std::cmp::Ordering::Less | std::cmp::Ordering::Equal)
        );
        if !self.measured || !agrees {
            return None;
        }
        let n = (self.sigma_frame / self.sigma_shared).powi(2);
        Some(
            if n.is_finite() && n <= crate::evidence::MAX_SHARED_FRAMES {
                n
            } else {
                f64::INFINITY
            },
        )
    }
}

/// One landmark of the layout.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LayoutLandmark {
    /// Where the frames put it (m), in its component's frame.
    pub position: [f64; 2],
    /// Frames (of three or more landmarks) that saw it.
    pub sightings: u32,
    /// The error its frames share beyond the layout (m, as a pair's distance): `1.4826 ·
    /// median |median error|` over its own pairs, or the recording's with fewer than
    /// [`MIN_LANDMARK_PAIRS`] of them.
    pub sigma_shared: f64,
    /// Its connected component: landmarks linked by frames that saw them together. Positions
    /// of different components are in unrelated frames.
    pub component: u32,
}

/// The landmark positions every frame agrees with best, and the error the frames share beyond
/// them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Layout {
    landmarks: BTreeMap<LandmarkId, LayoutLandmark>,
    shared: SharedError,
    rounds: usize,
    converged: bool,
}

/// A frame the fit uses: its landmarks (indices into the fit's sorted ids) and where it saw
/// them.
struct View {
    idx: Vec<usize>,
    xy: Vec<[f64; 2]>,
    /// Each observation's stated noise, σ per axis.
    sigma: Vec<f64>,
}

impl Layout {
    /// The layout of the frames with three or more landmarks (the frames a map learns from;
    /// with none, an empty layout).
    ///
    /// # Errors
    /// [`PqrmError::Cancelled`] when `progress` asks to stop.
    pub fn fit(scans: &[Scan], progress: &dyn Progress) -> Result<Self> {
        let ids: Vec<LandmarkId> = scans
            .iter()
            .filter(|s| s.observations.len() >= 3)
            .flat_map(|s| s.observations.iter().map(|o| o.id))
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        if ids.is_empty() {
            // no frame relates three landmarks: an empty layout, as the filter's map is empty
            return Ok(Self {
                landmarks: BTreeMap::new(),
                shared: SharedError {
                    sigma_shared: 0.0,
                    sigma_frame: 0.0,
                    pairs: 0,
                    measured: false,
                },
                rounds: 0,
                converged: true,
            });
        }
        let index: BTreeMap<LandmarkId, usize> =
            ids.iter().enumerate().map(|(i, id)| (*id, i)).collect();
        let views: Vec<View> = scans
            .iter()
            .filter(|s| s.observations.len() >= 3)
            .map(|s| View {
                idx: s.observations.iter().map(|o| index[&o.id]).collect(),
                xy: s.observations.iter().map(|o| o.mean).collect(),
                sigma: s
                    .observations
                    .iter()
                    .map(|o| (0.5 * o.cov[0][0] + 0.5 * o.cov[1][1]).max(0.0).sqrt())
                    .collect(),
            })
            .collect();
        let n = ids.len();
        let component = components(n, &views);
        let mut x = initial_layout(n, &views);
        let mut sightings = vec![0u32; n];
        for v in &views {
            for &i in &v.idx {
                sightings[i] += 1;
            }
        }
        let (mut rounds, mut converged) = (0, false);
        while rounds < MAX_ROUNDS {
            progress.check()?;
            rounds += 1;
            let next = procrustes_round(&x, &views);
            let moved = next
                .iter()
                .zip(&x)
                .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                .fold(0.0, f64::max);
            x = next;
            if moved < TOLERANCE_M {
                converged = true;
                break;
            }
        }
        let (shared, own) = shared_error(&x, &views);
        let landmarks = ids
            .iter()
            .enumerate()
            .map(|(i, id)| {
                (
                    *id,
                    LayoutLandmark {
                        position: x[i],
                        sightings: sightings[i],
                        sigma_shared: own[i].unwrap_or(shared.sigma_shared),
                        component: component[i] as u32,
                    },
                )
            })
            .collect();
        Ok(Self {
            landmarks,
            shared,
            rounds,
            converged,
        })
    }

    /// The error the frames share beyond the layout.
    #[must_use]
    pub fn shared_error(&self) -> SharedError {
        self.shared
    }

    /// Every landmark of the layout.
    #[must_use]
    pub fn landmarks(&self) -> &BTreeMap<LandmarkId, LayoutLandmark> {
        &self.landmarks
    }

    /// Rounds of alignment the fit took.
    #[must_use]
    pub fn rounds(&self) -> usize {
        self.rounds
    }

    /// Whether the fit stopped because nothing moved (not at [`MAX_ROUNDS`]).
    #[must_use]
    pub fn converged(&self) -> bool {
        self.converged
    }

    /// The standard deviation per axis of a landmark's true position about the layout's (m).
    #[must_use]
    pub fn position_sigma(&self, landmark: &LayoutLandmark) -> f64 {
        let s = self.shared;
        let n = f64::from(landmark.sightings.max(1));
        let own = landmark.sigma_shared;
        (0.5 * own * own + 0.5 * s.sigma_frame * s.sigma_frame / n).sqrt()
    }

    /// The beliefs of the six orderings of one triplet (`{a, b : c}` with `a < b < c`, then
    /// the orderings in [`Orderings::All`]'s order), from `draws` draws of the three positions.
    /// The draws depend on `seed` and the three ids only.
    ///
    /// # Errors
    /// [`PqrmError::Mismatch`] when a landmark is not in the layout or the three are in
    /// different components; [`PqrmError::CoincidentLandmarks`] when no draw gives a valid
    /// frame; calculus errors for a calculus that is not ternary.
    pub fn triplet_beliefs(
        &self,
        calculus: &Calculus,
        ids: [LandmarkId; 3],
        draws: usize,
        seed: u64,
    ) -> Result<[Vec<f64>; 6]> {
        let mut sorted = ids;
        sorted.sort();
        let marks = sorted
            .iter()
            .map(|id| {
                self.landmarks.get(id).copied().ok_or_else(|| {
                    PqrmError::Mismatch(format!("landmark {} is not in the layout", id.0))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        if marks.iter().any(|m| m.component != marks[0].component) {
            return Err(PqrmError::Mismatch(format!(
                "landmarks {:?} are in different components of the layout (no frame links them)",
                sorted.map(|i| i.0)
            )));
        }
        let sigma: Vec<f64> = marks.iter().map(|m| self.position_sigma(m)).collect();
        let mut rng = ChaCha8Rng::seed_from_u64(triplet_seed(seed, sorted));
        let q = calculus.n_states();
        let mut counts = [(); 6].map(|()| vec![0u32; q]);
        let mut valid = [0u32; 6];
        for _ in 0..draws {
            let p: Vec<Point2<f64>> = marks
                .iter()
                .zip(&sigma)
                .map(|(m, s)| {
                    let dx: f64 = StandardNormal.sample(&mut rng);
                    let dy: f64 = StandardNormal.sample(&mut rng);
                    Point2::new(m.position[0] + s * dx, m.position[1] + s * dy)
                })
                .collect();
            for (o, [i, j, k]) in SIX.iter().enumerate() {
                // a draw with two landmarks on one spot has no state; it is left out
                if let Ok(state) = calculus.classify_triplet(p[*i], p[*j], p[*k]) {
                    counts[o][state.index()] += 1;
                    valid[o] += 1;
                }
            }
        }
        let mut out = [(); 6].map(|()| Vec::new());
        for o in 0..6 {
            if valid[o] == 0 {
                return Err(PqrmError::CoincidentLandmarks {
                    set: sorted.map(|i| i.0),
                    reason: "every draw of the layout's positions coincides".into(),
                });
            }
            let total = f64::from(valid[o]) + 1.0;
            out[o] = counts[o]
                .iter()
                .map(|&c| (f64::from(c) + 1.0 / q as f64) / total)
                .collect();
        }
        Ok(out)
    }

    /// Beliefs of every set the frames saw (the sets a map of them has, in `orderings`), with
    /// how many frames saw each: in the order of the sets' sorted ids, then ordering.
    ///
    /// # Errors
    /// As [`Layout::triplet_beliefs`]; [`PqrmError::Cancelled`].
    pub fn beliefs(
        &self,
        calculus: &Calculus,
        scans: &[Scan],
        orderings: Orderings,
        draws: usize,
        seed: u64,
        progress: &dyn Progress,
    ) -> Result<Vec<SetBelief>> {
        let mut seen: BTreeMap<[LandmarkId; 3], u32> = BTreeMap::new();
        for s in scans.iter().filter(|s| s.observations.len() >= 3) {
            let ids: Vec<LandmarkId> = s.observations.iter().map(|o| o.id).collect();
            for i in 0..ids.len() {
                for j in i + 1..ids.len() {
                    for k in j + 1..ids.len() {
                        *seen.entry([ids[i], ids[j], ids[k]]).or_insert(0) += 1;
                    }
                }
            }
        }
        let triplets: Vec<([LandmarkId; 3], u32)> = seen.into_iter().collect();
        progress.add_total(triplets.len());
        let n_orders = match orderings {
            Orderings::All => 6,
            Orderings::Canonical => 1,
        };
        let per: Vec<Result<Vec<SetBelief>>> = triplets
            .par_iter()
            .map(|(ids, frames)| {
                progress.check()?;
                let six = self.triplet_beliefs(calculus, *ids, draws, seed)?;
                progress.tick();
                Ok(SIX
                    .iter()
                    .zip(six)
                    .take(n_orders)
                    .map(|([i, j, k], b)| (LandmarkSet([ids[*i], ids[*j], ids[*k]]), *frames, b))
                    .collect())
            })
            .collect();
        let mut out = Vec::with_capacity(triplets.len() * n_orders);
        for p in per {
            out.extend(p?);
        }
        Ok(out)
    }
}

impl Layout {
    /// The map of `scans` read from this layout (fitted on them): every set they saw, in
    /// `config.orderings`, its belief from [`DEFAULT_DRAWS`] draws seeded by `config.seed`
    /// ([`crate::EvidenceModel::Layout`]; the rows' update counts are the frames that saw each set).
    ///
    /// ```
    /// use pqrm::layout::Layout;
    /// use pqrm::{LandmarkId, LandmarkSet, Observation, PqrmConfig, Scan};
    /// use qsr_core::Calculus;
    ///
    /// // four landmarks seen from six places, each frame in the robot's own coordinates
    /// let world = [[0.0, 0.0], [2.0, 0.0], [1.0, 1.5], [1.0, -1.0]];
    /// let scans: Vec<Scan> = (0..6)
    ///     .map(|f| {
    ///         let (yaw, shift) = (0.5 * f64::from(f), f64::from(f));
    ///         let (c, s) = (yaw.cos(), yaw.sin());
    ///         let obs = world
    ///             .iter()
    ///             .enumerate()
    ///             .map(|(i, p)| {
    ///                 let wobble = 0.02 * f64::from((f * 7 + i as u32 * 3) % 5) - 0.04;
    ///                 let xy = [c * p[0] - s * p[1] + shift + wobble, s * p[0] + c * p[1]];
    ///                 Observation::isotropic(LandmarkId(i as u32), xy, 0.05).unwrap()
    ///             })
    ///             .collect();
    ///         Scan::new(f64::from(f), 1, obs).unwrap()
    ///     })
    ///     .collect();
    /// let layout = Layout::fit(&scans, &|| {})?;
    /// let map = layout.map(Calculus::builtin("left-right")?, &scans, PqrmConfig::default(), &|| {})?;
    /// // landmark 2 is left of 0 → 1, landmark 3 right of it
    /// let left = map.belief(LandmarkSet::new(0, 1, 2)).unwrap();
    /// let right = map.belief(LandmarkSet::new(0, 1, 3)).unwrap();
    /// assert!(left[0] > 0.9 && right[1] > 0.9, "{left:?} {right:?}");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    ///
    /// # Errors
    /// As [`Layout::beliefs`]; [`PqrmError::InvalidConfig`] for a config the mapper refuses or
    /// a calculus that is not ternary.
    pub fn map(
        &self,
        calculus: Calculus,
        scans: &[Scan],
        config: PqrmConfig,
        progress: &dyn Progress,
    ) -> Result<Pqrm> {
        config.validate()?;
        let rows = self.beliefs(
            &calculus,
            scans,
            config.orderings,
            DEFAULT_DRAWS,
            config.seed,
            progress,
        )?;
        Pqrm::from_beliefs(calculus, config, scans.len() as u64, rows)
    }
}

/// The six orderings of a sorted triplet, as positions in it — [`Orderings::All`]'s order
/// (`crate::likelihood::step_counts`).
const SIX: [[usize; 3]; 6] = [
    [0, 1, 2],
    [1, 0, 2],
    [0, 2, 1],
    [2, 0, 1],
    [1, 2, 0],
    [2, 1, 0],
];

/// A triplet's own stream of draws: the same for any thread count or set order.
fn triplet_seed(seed: u64, ids: [LandmarkId; 3]) -> u64 {
    // splitmix64 over the seed and the ids
    let mut h = seed ^ 0x9E37_79B9_7F4A_7C15;
    for id in ids {
        h ^= u64::from(id.0);
        h = h.wrapping_add(0x9E37_79B9_7F4A_7C15);
        h = (h ^ (h >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        h = (h ^ (h >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        h ^= h >> 31;
    }
    h
}

/// Connected components of the landmarks, two linked when a frame saw both: a component id per
/// landmark, numbered by its smallest landmark.
fn components(n: usize, views: &[View]) -> Vec<usize> {
    let mut parent: Vec<usize> = (0..n).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for v in views {
        for w in v.idx.windows(2) {
            let (a, b) = (root(&mut parent, w[0]), root(&mut parent, w[1]));
            // the smaller index is the root, so a component is named by its smallest landmark
            parent[a.max(b)] = a.min(b);
        }
    }
    (0..n).map(|i| root(&mut parent, i)).collect()
}

/// The rotation and translation taking `src` onto `dst` best in least squares (no
/// reflection: a frame is a robot's view, its handedness is the world's).
fn rigid_fit(src: &[[f64; 2]], dst: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let n = src.len() as f64;
    let mean = |v: &[[f64; 2]]| {
        let s = v.iter().fold([0.0, 0.0], |a, p| [a[0] + p[0], a[1] + p[1]]);
        [s[0] / n, s[1] / n]
    };
    let (ms, md) = (mean(src), mean(dst));
    let (mut dot, mut cross) = (0.0, 0.0);
    for (s, d) in src.iter().zip(dst) {
        let (sx, sy) = (s[0] - ms[0], s[1] - ms[1]);
        let (dx, dy) = (d[0] - md[0], d[1] - md[1]);
        dot += sx * dx + sy * dy;
        cross += sx * dy - sy * dx;
    }
    let h = dot.hypot(cross);
    let (c, s) = if h > 0.0 {
        (dot / h, cross / h)
    } else {
        (1.0, 0.0)
    };
    let t = [
        md[0] - (c * ms[0] - s * ms[1]),
        md[1] - (s * ms[0] + c * ms[1]),
    ];
    ([c, s], t)
}

fn apply(([c, s], t): ([f64; 2], [f64; 2]), p: [f64; 2]) -> [f64; 2] {
    [c * p[0] - s * p[1] + t[0], s * p[0] + c * p[1] + t[1]]
}

/// A first layout: per component, the largest frame as seen, then frame by frame the one that
/// shares the most placed landmarks (two or more, so its rotation is known) places its others.
fn initial_layout(n: usize, views: &[View]) -> Vec<[f64; 2]> {
    let mut x: Vec<Option<[f64; 2]>> = vec![None; n];
    let mut order: Vec<usize> = (0..views.len()).collect();
    order.sort_by_key(|&v| std::cmp::Reverse(views[v].idx.len()));
    let mut used = vec![false; views.len()];
    loop {
        // the frame sharing the most placed landmarks that also has an unplaced one
        let best = order
            .iter()
            .filter(|&&v| !used[v])
            .map(|&v| {
                let placed = views[v].idx.iter().filter(|&&i| x[i].is_some()).count();
                (v, placed, placed < views[v].idx.len())
            })
            .filter(|&(_, placed, open)| open && placed >= 2)
            .max_by_key(|&(v, placed, _)| (placed, std::cmp::Reverse(v)));
        let v = match best {
            Some((v, _, _)) => v,
            None => {
                // a component not started yet: its largest frame as seen (a component's
                // frame is its own)
                let Some(&v) = order
                    .iter()
                    .find(|&&v| !used[v] && views[v].idx.iter().all(|&i| x[i].is_none()))
                else {
                    break;
                };
                for (&i, p) in views[v].idx.iter().zip(&views[v].xy) {
                    x[i] = Some(*p);
                }
                used[v] = true;
                continue;
            }
        };
        used[v] = true;
        let (src, dst): (Vec<[f64; 2]>, Vec<[f64; 2]>) = views[v]
            .idx
            .iter()
            .zip(&views[v].xy)
            .filter_map(|(&i, p)| x[i].map(|q| (*p, q)))
            .unzip();
        let fit = rigid_fit(&src, &dst);
        for (&i, p) in views[v].idx.iter().zip(&views[v].xy) {
            if x[i].is_none() {
                x[i] = Some(apply(fit, *p));
            }
        }
    }
    // a landmark only ever linked through frames sharing one placed landmark: placed by
    // translation alone from such a frame (the rounds then turn it into place)
    for v in views {
        if let Some(k) = v.idx.iter().position(|&i| x[i].is_some()) {
            let anchor = x[v.idx[k]].unwrap_or([0.0, 0.0]);
            for (&i, p) in v.idx.iter().zip(&v.xy) {
                if x[i].is_none() {
                    x[i] = Some([anchor[0] + p[0] - v.xy[k][0], anchor[1] + p[1] - v.xy[k][1]]);
                }
            }
        }
    }
    x.into_iter().map(|p| p.unwrap_or([0.0, 0.0])).collect()
}

/// One round of generalised Procrustes: every frame aligned onto `x`, each landmark the mean
/// of its aligned sightings. (Nothing turns or moves the layout as a whole: at a fixed point
/// every frame's alignment returns it unchanged.)
///
/// Least squares, not a robust fit: measured on MRCLAM, Cauchy weights on the sightings
/// (scale 2.385 σ of their spread) make Dataset 5's EDC map worse (error 0.133 → 0.170, ECE
/// 0.043 → 0.080) — what a robust fit discounts there is a shared error, not outliers.
fn procrustes_round(x: &[[f64; 2]], views: &[View]) -> Vec<[f64; 2]> {
    let mut sum = vec![[0.0, 0.0]; x.len()];
    let mut count = vec![0u32; x.len()];
    for v in views {
        let dst: Vec<[f64; 2]> = v.idx.iter().map(|&i| x[i]).collect();
        let fit = rigid_fit(&v.xy, &dst);
        for (&i, p) in v.idx.iter().zip(&v.xy) {
            let q = apply(fit, *p);
            sum[i][0] += q[0];
            sum[i][1] += q[1];
            count[i] += 1;
        }
    }
    sum.iter()
        .zip(&count)
        .zip(x)
        .map(|((s, &c), old)| {
            if c == 0 {
                *old
            } else {
                [s[0] / f64::from(c), s[1] / f64::from(c)]
            }
        })
        .collect()
}

/// The pairs' median distance errors against the layout and the frames' spread about them:
/// the recording's shared error, and each landmark's own (`None` with too few pairs).
fn shared_error(x: &[[f64; 2]], views: &[View]) -> (SharedError, Vec<Option<f64>>) {
    let mut pairs: BTreeMap<(usize, usize), Vec<f64>> = BTreeMap::new();
    for v in views {
        for a in 0..v.idx.len() {
            for b in a + 1..v.idx.len() {
                let (i, j) = (v.idx[a], v.idx[b]);
                let seen = (v.xy[a][0] - v.xy[b][0]).hypot(v.xy[a][1] - v.xy[b][1]);
                let layout = (x[i][0] - x[j][0]).hypot(x[i][1] - x[j][1]);
                pairs
                    .entry((i.min(j), i.max(j)))
                    .or_default()
                    .push(seen - layout);
            }
        }
    }
    // per pair: |median error|, and the variance its median has from the frames' own noise
    // (π/2 · σ²/n for a normal's median), which is not shared error
    let (mut offsets, mut spreads, mut noise) = (Vec::new(), Vec::new(), Vec::new());
    let mut of_landmark: Vec<(Vec<f64>, Vec<f64>)> = vec![(Vec::new(), Vec::new()); x.len()];
    for ((i, j), mut r) in pairs
        .into_iter()
        .filter(|(_, r)| r.len() >= MIN_PAIR_FRAMES)
    {
        let m = median(&mut r);
        let mut dev: Vec<f64> = r.iter().map(|v| (v - m).abs()).collect();
        let spread = MAD_TO_SIGMA * median(&mut dev);
        let var = std::f64::consts::FRAC_PI_2 * spread * spread / r.len() as f64;
        spreads.push(spread);
        offsets.push(m.abs());
        noise.push(var);
        for k in [i, j] {
            of_landmark[k].0.push(m.abs());
            of_landmark[k].1.push(var);
        }
    }
    if offsets.is_empty() {
        let mut stated: Vec<f64> = views.iter().flat_map(|v| v.sigma.iter().copied()).collect();
        let frame = std::f64::consts::SQRT_2 * median(&mut stated);
        let shared = SharedError {
            sigma_shared: frame,
            sigma_frame: frame,
            pairs: 0,
            measured: false,
        };
        return (shared, vec![None; x.len()]);
    }
    let own = of_landmark
        .into_iter()
        .map(|(mut m, mut v)| (m.len() >= MIN_LANDMARK_PAIRS).then(|| beyond_noise(&mut m, &mut v)))
        .collect();
    let shared = SharedError {
        sigma_shared: beyond_noise(&mut offsets, &mut noise),
        sigma_frame: median(&mut spreads),
        pairs: offsets.len(),
        measured: true,
    };
    (shared, own)
}

/// The shared error of pairs with median errors `offsets` whose medians carry the noise
/// variances `noise`: `√max(0, (1.4826 · median |m|)² − median noise)`.
fn beyond_noise(offsets: &mut [f64], noise: &mut [f64]) -> f64 {
    let robust = MAD_TO_SIGMA * median(offsets);
    (robust * robust - median(noise)).max(0.0).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::observation::Observation;

    /// `world` seen exactly from pose (x, y, yaw): each landmark in the robot's frame.
    fn seen(world: &[(u32, [f64; 2])], pose: [f64; 3], t: f64) -> Scan {
        let (c, s) = (pose[2].cos(), pose[2].sin());
        let obs = world
            .iter()
            .map(|(id, p)| {
                let (dx, dy) = (p[0] - pose[0], p[1] - pose[1]);
                Observation::isotropic(LandmarkId(*id), [c * dx + s * dy, -s * dx + c * dy], 0.1)
                    .unwrap()
            })
            .collect();
        Scan::new(t, 1, obs).unwrap()
    }

    fn poses(n: usize) -> Vec<[f64; 3]> {
        (0..n)
            .map(|k| {
                let k = k as f64;
                [2.0 * (0.7 * k).sin(), 1.5 * (1.3 * k).cos(), 0.9 * k]
            })
            .collect()
    }

    #[test]
    fn exact_frames_give_the_world_up_to_a_rigid_motion_and_no_shared_error() {
        let world = [
            (3, [0.0, 0.0]),
            (5, [3.0, 0.5]),
            (8, [1.0, 2.5]),
            (9, [-1.5, 1.0]),
            (12, [2.2, -1.7]),
        ];
        // frames of three or four landmarks: no frame sees them all
        let scans: Vec<Scan> = poses(30)
            .into_iter()
            .enumerate()
            .map(|(k, pose)| {
                let skip = k % world.len();
                let some: Vec<(u32, [f64; 2])> = world
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| *i != skip && (k % 3 != 0 || *i != (skip + 2) % 5))
                    .map(|(_, w)| *w)
                    .collect();
                seen(&some, pose, k as f64)
            })
            .collect();
        let layout = Layout::fit(&scans, &|| {}).unwrap();
        assert!(layout.converged());
        let marks = layout.landmarks();
        for (a, pa) in &world {
            for (b, pb) in &world {
                let (la, lb) = (marks[&LandmarkId(*a)], marks[&LandmarkId(*b)]);
                let d = (la.position[0] - lb.position[0]).hypot(la.position[1] - lb.position[1]);
                let truth = (pa[0] - pb[0]).hypot(pa[1] - pb[1]);
                assert!((d - truth).abs() < 1e-5, "{a}-{b}: {d} vs {truth}");
            }
        }
        // handedness kept: 8 is left of 3 → 5 in the layout as in the world
        let (p3, p5, p8) = (
            marks[&LandmarkId(3)].position,
            marks[&LandmarkId(5)].position,
            marks[&LandmarkId(8)].position,
        );
        let cross = (p5[0] - p3[0]) * (p8[1] - p3[1]) - (p5[1] - p3[1]) * (p8[0] - p3[0]);
        assert!(cross > 0.0);
        let shared = layout.shared_error();
        assert!(
            shared.sigma_shared < 1e-6 && shared.sigma_frame < 1e-6,
            "{shared:?}"
        );
        assert_eq!(shared.pairs, 10);
        assert!(
            marks
                .values()
                .all(|m| m.component == marks[&LandmarkId(3)].component)
        );
        // no error left: every draw is the world, the belief all but certain
        let calc = Calculus::builtin("left-right").unwrap();
        let b = layout
            .triplet_beliefs(&calc, [LandmarkId(3), LandmarkId(5), LandmarkId(8)], 500, 1)
            .unwrap();
        assert!(b[0][0] > 0.99, "{:?}", b[0]);
        // the ordering {5, 3 : 8} sees 8 on the other side
        assert!(b[1][1] > 0.99, "{:?}", b[1]);
    }

    #[test]
    fn the_filters_frames_are_the_ratio_of_the_two_errors_squared() {
        let e = |sigma_shared: f64, sigma_frame: f64, measured: bool| SharedError {
            sigma_shared,
            sigma_frame,
            pairs: 10,
            measured,
        };
        let n = e(0.022, 0.088, true).frames().unwrap_or_default();
        assert!((n - 16.0).abs() < 1e-9, "{n}");
        assert_eq!(e(0.0, 0.088, true).frames(), Some(f64::INFINITY));
        assert_eq!(e(1e-12, 0.088, true).frames(), Some(f64::INFINITY));
        assert_eq!(e(0.05, 0.05, true).frames(), Some(1.0));
        // disagreeing with the layout, unmeasured or broken: nothing to say
        assert_eq!(e(0.2, 0.1, true).frames(), None);
        assert_eq!(e(0.02, 0.1, false).frames(), None);
        assert_eq!(e(f64::NAN, 0.1, true).frames(), None);
        assert_eq!(e(0.0, 0.0, true).frames(), Some(f64::INFINITY));
    }

    #[test]
    fn too_few_frames_to_measure_the_shared_error_take_the_stated_noise_for_it() {
        let world = [(1, [0.0, 0.0]), (2, [1.0, 0.0]), (3, [0.0, 1.0])];
        let pairs_only: Vec<Scan> = poses(10)
            .into_iter()
            .enumerate()
            .map(|(k, p)| seen(&world[..2], p, k as f64))
            .collect();
        let empty = Layout::fit(&pairs_only, &|| {}).unwrap();
        assert!(empty.landmarks().is_empty() && !empty.shared_error().measured);
        let calc = Calculus::builtin("left-right").unwrap();
        let map = empty
            .map(calc.clone(), &pairs_only, PqrmConfig::default(), &|| {})
            .unwrap();
        assert!(map.is_empty());
        // four frames: no pair in five of them; the observations say σ = 0.1 per axis
        let few: Vec<Scan> = poses(4)
            .into_iter()
            .enumerate()
            .map(|(k, p)| seen(&world, p, k as f64))
            .collect();
        let layout = Layout::fit(&few, &|| {}).unwrap();
        let s = layout.shared_error();
        assert!(!s.measured && s.pairs == 0);
        assert!(
            (s.sigma_frame - 0.1 * std::f64::consts::SQRT_2).abs() < 1e-12,
            "{s:?}"
        );
        assert!((s.sigma_shared - s.sigma_frame).abs() < 1e-12);
        let m = &layout.landmarks()[&LandmarkId(1)];
        assert!((m.sigma_shared - s.sigma_shared).abs() < 1e-12);
        // 3 sits 0.1 m · √(½ + ½/4) ≈ 0.08 m per axis from its place, 1 m off the line 1 → 2
        let b = layout
            .triplet_beliefs(&calc, [LandmarkId(1), LandmarkId(2), LandmarkId(3)], 400, 0)
            .unwrap();
        assert!(b[0][0] > 0.95 && b[0][0] < 1.0, "{:?}", b[0]);
    }

    #[test]
    fn landmarks_no_frame_links_are_in_different_components_and_not_related() {
        let a = [(1, [0.0, 0.0]), (2, [1.0, 0.0]), (3, [0.0, 1.0])];
        let b = [(7, [5.0, 5.0]), (8, [6.0, 5.0]), (9, [5.0, 6.5])];
        let scans: Vec<Scan> = poses(12)
            .into_iter()
            .enumerate()
            .map(|(k, p)| seen(if k % 2 == 0 { &a } else { &b }, p, k as f64))
            .collect();
        let layout = Layout::fit(&scans, &|| {}).unwrap();
        let m = layout.landmarks();
        assert_ne!(m[&LandmarkId(1)].component, m[&LandmarkId(7)].component);
        let calc = Calculus::builtin("left-right").unwrap();
        let e = layout
            .triplet_beliefs(&calc, [LandmarkId(1), LandmarkId(2), LandmarkId(7)], 10, 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("different components"), "{e}");
        let e = layout
            .triplet_beliefs(&calc, [LandmarkId(1), LandmarkId(2), LandmarkId(4)], 10, 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("landmark 4 is not in the layout"), "{e}");
    }

    #[test]
    fn coincident_landmarks_seen_exactly_are_a_typed_error() {
        let world = [(1, [0.0, 0.0]), (2, [0.0, 0.0]), (3, [0.0, 1.0])];
        let scans: Vec<Scan> = poses(8)
            .into_iter()
            .enumerate()
            .map(|(k, p)| seen(&world, p, k as f64))
            .collect();
        let layout = Layout::fit(&scans, &|| {}).unwrap();
        let calc = Calculus::builtin("left-right").unwrap();
        let e = layout
            .triplet_beliefs(&calc, [LandmarkId(1), LandmarkId(2), LandmarkId(3)], 50, 0)
            .unwrap_err();
        assert!(matches!(e, PqrmError::CoincidentLandmarks { .. }), "{e}");
    }
}
