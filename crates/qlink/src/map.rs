//! Map elements `M_i = {L_i, Q_i}` (thesis §4.2): a landmark set and, for each ordering, the
//! qualitative state — a distribution when the map is a PQRM.
//!
//! A [`QualitativeMap`] stacks *layers*, each a set of elements of one calculus: a
//! probabilistic layer is a [`pqrm::Pqrm`], an exact layer records one state per ordering
//! (a deterministic QRM, e.g. from surveyed positions). Several layers of different calculi
//! make a hybrid map (§4.4.2). Elements are numbered across layers in layer order, then by
//! landmark set.

use std::collections::BTreeMap;

use pqrm::{LandmarkSet, Pqrm};
use qsr_core::{Calculus, Point2, StateId};

use crate::error::{QlinkError, Result};

/// One layer of a qualitative map.
#[derive(Debug, Clone)]
pub enum Layer {
    /// A probabilistic map: beliefs per ordering.
    Probabilistic(Pqrm),
    /// A deterministic map: one state per ordered triplet.
    Exact {
        /// Its calculus.
        calculus: Calculus,
        /// State of each ordered triplet `[a, b, c]` = `{a, b : c}`.
        states: BTreeMap<[u32; 3], StateId>,
    },
}

impl Layer {
    /// The calculus.
    #[must_use]
    pub fn calculus(&self) -> &Calculus {
        match self {
            Self::Probabilistic(m) => m.calculus(),
            Self::Exact { calculus, .. } => calculus,
        }
    }

    /// An exact layer of every triplet of `positions` whose three landmarks lie within a disc
    /// of radius `range` (what a mapping robot with that range could have recorded; §4.3.4
    /// Assumption 1 (i)), classified from the true positions.
    ///
    /// # Errors
    /// Frame errors for coincident landmarks.
    pub fn exact_from_positions(
        calculus: Calculus,
        positions: &BTreeMap<u32, [f64; 2]>,
        range: f64,
    ) -> Result<Self> {
        Self::exact_where(calculus, positions, |p| within_disc(p, range))
    }

    /// An exact layer of the triplets whose landmarks are pairwise at most `range` apart —
    /// the restricted maps of §4.3.4 Assumption 3 (i), for which the direct controller and
    /// Proposition 4's bound apply.
    ///
    /// # Errors
    /// Frame errors for coincident landmarks.
    pub fn exact_pairwise(
        calculus: Calculus,
        positions: &BTreeMap<u32, [f64; 2]>,
        range: f64,
    ) -> Result<Self> {
        Self::exact_where(calculus, positions, |p| {
            (p[0] - p[1]).norm() <= range
                && (p[1] - p[2]).norm() <= range
                && (p[2] - p[0]).norm() <= range
        })
    }

    fn exact_where(
        calculus: Calculus,
        positions: &BTreeMap<u32, [f64; 2]>,
        keep: impl Fn(&[Point2<f64>; 3]) -> bool,
    ) -> Result<Self> {
        let ids: Vec<u32> = positions.keys().copied().collect();
        let mut states = BTreeMap::new();
        let p = |id: u32| {
            let q = positions[&id];
            Point2::new(q[0], q[1])
        };
        for (i, &a) in ids.iter().enumerate() {
            for (j, &b) in ids.iter().enumerate().skip(i + 1) {
                for &c in &ids[j + 1..] {
                    if !keep(&[p(a), p(b), p(c)]) {
                        continue;
                    }
                    for [x, y, z] in orderings([a, b, c]) {
                        let s = calculus.classify_triplet(p(x), p(y), p(z))?;
                        states.insert([x, y, z], s);
                    }
                }
            }
        }
        Ok(Self::Exact { calculus, states })
    }

    /// Unordered landmark sets of the layer (sorted ids), sorted.
    fn sets(&self) -> Vec<[u32; 3]> {
        let mut out: Vec<[u32; 3]> = match self {
            Self::Probabilistic(m) => m
                .iter()
                .map(|(s, _)| {
                    let mut ids = s.ids();
                    ids.sort_unstable();
                    ids
                })
                .collect(),
            Self::Exact { states, .. } => states
                .keys()
                .map(|k| {
                    let mut ids = *k;
                    ids.sort_unstable();
                    ids
                })
                .collect(),
        };
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Distribution over the states of `{a, b : c}` (`None` if not in the layer).
    #[must_use]
    pub fn belief(&self, ordered: [u32; 3]) -> Option<Vec<f64>> {
        match self {
            Self::Probabilistic(m) => {
                m.belief(LandmarkSet::new(ordered[0], ordered[1], ordered[2]))
            }
            Self::Exact { calculus, states } => states.get(&ordered).map(|s| {
                let mut v = vec![0.0; calculus.n_states()];
                v[s.index()] = 1.0;
                v
            }),
        }
    }
}

/// The six orderings of a triplet.
#[must_use]
pub fn orderings([a, b, c]: [u32; 3]) -> [[u32; 3]; 6] {
    [
        [a, b, c],
        [a, c, b],
        [b, a, c],
        [b, c, a],
        [c, a, b],
        [c, b, a],
    ]
}

/// Whether points fit in a disc of radius `r` (the smallest enclosing circle of ≤ 3 points).
fn within_disc(p: &[Point2<f64>; 3], r: f64) -> bool {
    let d = |a: &Point2<f64>, b: &Point2<f64>| (a - b).norm();
    let (ab, bc, ca) = (d(&p[0], &p[1]), d(&p[1], &p[2]), d(&p[2], &p[0]));
    let longest = ab.max(bc).max(ca);
    // obtuse or right triangle: the longest side is the diameter
    let sq = |x: f64| x * x;
    let sum = sq(ab) + sq(bc) + sq(ca);
    if 2.0 * sq(longest) >= sum {
        return longest / 2.0 <= r;
    }
    // acute: circumradius abc / 4K
    let area = ((p[1] - p[0]).perp(&(p[2] - p[0]))).abs() / 2.0;
    area > 0.0 && ab * bc * ca / (4.0 * area) <= r
}

/// One map element.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapElement {
    /// Its landmarks, sorted.
    pub landmarks: [u32; 3],
    /// The layer it belongs to.
    pub layer: usize,
}

/// A qualitative relational map: elements of one or more calculi.
#[derive(Debug, Clone)]
pub struct QualitativeMap {
    layers: Vec<Layer>,
    elements: Vec<MapElement>,
    by_landmark: BTreeMap<u32, Vec<usize>>,
}

impl QualitativeMap {
    /// A map of the given layers.
    ///
    /// # Errors
    /// [`QlinkError::EmptyMap`] when no layer has an element; [`QlinkError::Unsupported`]
    /// for a layer whose calculus is not ternary.
    pub fn new(layers: Vec<Layer>) -> Result<Self> {
        let mut elements = Vec::new();
        for (li, layer) in layers.iter().enumerate() {
            if layer.calculus().frame() != qsr_core::FrameKind::Ternary {
                return Err(QlinkError::Unsupported(format!(
                    "layer {li}: calculus `{}` is not ternary; point-triplet elements need a \
                     ternary calculus",
                    layer.calculus().name()
                )));
            }
            for set in layer.sets() {
                elements.push(MapElement {
                    landmarks: set,
                    layer: li,
                });
            }
        }
        if elements.is_empty() {
            return Err(QlinkError::EmptyMap);
        }
        let mut by_landmark: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        for (i, e) in elements.iter().enumerate() {
            for &l in &e.landmarks {
                by_landmark.entry(l).or_default().push(i);
            }
        }
        Ok(Self {
            layers,
            elements,
            by_landmark,
        })
    }

    /// A one-layer map of a PQRM.
    ///
    /// # Errors
    /// As [`QualitativeMap::new`].
    pub fn from_pqrm(map: Pqrm) -> Result<Self> {
        Self::new(vec![Layer::Probabilistic(map)])
    }

    /// The elements.
    #[must_use]
    pub fn elements(&self) -> &[MapElement] {
        &self.elements
    }
    /// One search POMDP per layer, on the layer's calculus, with the settings `configure`
    /// sets on the builder's defaults (what the Link Graph's costs and the navigator need).
    ///
    /// # Errors
    /// As [`crate::SearchPomdpBuilder::build`].
    pub fn search_pomdps(
        &self,
        configure: impl for<'c> Fn(crate::SearchPomdpBuilder<'c>) -> crate::SearchPomdpBuilder<'c>,
    ) -> Result<Vec<crate::SearchPomdp>> {
        self.layers
            .iter()
            .map(|l| configure(crate::SearchPomdp::builder(l.calculus())).build())
            .collect()
    }

    /// The layers.
    #[must_use]
    pub fn layers(&self) -> &[Layer] {
        &self.layers
    }

    /// The calculus of element `i`.
    #[must_use]
    pub fn calculus(&self, i: usize) -> &Calculus {
        self.layers[self.elements[i].layer].calculus()
    }

    /// Elements containing a landmark (empty when none).
    #[must_use]
    pub fn elements_with(&self, landmark: u32) -> &[usize] {
        self.by_landmark.get(&landmark).map_or(&[], Vec::as_slice)
    }

    /// All landmark ids in the map, sorted.
    #[must_use]
    pub fn landmarks(&self) -> Vec<u32> {
        self.by_landmark.keys().copied().collect()
    }

    /// Distribution over `{a, b : c}` for element `i` (`None` if that ordering is unknown).
    #[must_use]
    pub fn belief(&self, i: usize, ordered: [u32; 3]) -> Option<Vec<f64>> {
        self.layers[self.elements[i].layer].belief(ordered)
    }

    /// Elements whose reference landmarks (any two of its three) are all in `visible`.
    #[must_use]
    pub fn elements_in_view(&self, visible: &[u32]) -> Vec<usize> {
        let mut out: Vec<usize> = Vec::new();
        for &l in visible {
            for &e in self.elements_with(l) {
                let seen = self.elements[e]
                    .landmarks
                    .iter()
                    .filter(|x| visible.contains(x))
                    .count();
                if seen >= 2 {
                    out.push(e);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }
}
