//! [`BinaryNetwork`]: a set of relations for every ordered pair of named points, and its
//! algebraic closure ([`close_binary`]) — path consistency as SparQ and GQR run it.

use std::collections::HashMap;

use nalgebra::Point2;

use super::calculus::BinaryCalculus;
use crate::calculus::StateId;
use crate::error::QsrError;
use crate::reason::StateSet;
use crate::reason::network::{network_error, sexpr};

/// The most points a binary network may have (n² sets; closure is O(n³) set compositions).
pub const MAX_BINARY_POINTS: usize = 4096;

/// A binary constraint network over named points: `get(i, j)` is the set of relations
/// possible between point `i` and point `j`; `(j, i)` always holds the converse.
///
/// ```
/// use qsr_core::binary::{BinaryCalculus, BinaryNetwork, close_binary};
/// let opra = BinaryCalculus::builtin("opra-1")?;
/// // A and B face each other; B also faces C, and C faces B.
/// let net = BinaryNetwork::from_sparq_str(&opra, "((A 0_0 B) (B 0_0 C))")?;
/// let closed = close_binary(net)?;
/// assert!(closed.is_consistent());
/// // B faces both, so C lies on the ray from B through A: between A and B (C straight
/// // ahead of A, A straight behind C), beyond A, or at A with A's heading.
/// assert_eq!(closed.network.labels_of(0, 2), ["0_2", "2_0", "s_0"]);
/// // Saying C is on A's left contradicts that.
/// let bad = BinaryNetwork::from_sparq_str(&opra, "((A 0_0 B) (B 0_0 C) (A 1_1 C))")?;
/// assert!(!close_binary(bad)?.is_consistent());
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct BinaryNetwork {
    calculus: BinaryCalculus,
    names: Vec<String>,
    words: usize,
    sets: Vec<u64>,
}

impl BinaryNetwork {
    /// The network where nothing is known: every pair may be in any relation.
    ///
    /// # Errors
    /// [`QsrError::Network`] for an empty or repeated name or more than
    /// [`MAX_BINARY_POINTS`] points.
    pub fn universal<S: Into<String>>(
        calculus: &BinaryCalculus,
        names: impl IntoIterator<Item = S>,
    ) -> crate::Result<Self> {
        let names: Vec<String> = names.into_iter().map(Into::into).collect();
        if names.len() > MAX_BINARY_POINTS {
            return Err(network_error(
                "points",
                format!("{} points; at most {MAX_BINARY_POINTS}", names.len()),
            ));
        }
        let mut seen = HashMap::new();
        for (i, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(network_error(
                    "points",
                    format!("point {i} has an empty name"),
                ));
            }
            if let Some(first) = seen.insert(name.clone(), i) {
                return Err(network_error(
                    "points",
                    format!("point `{name}` is named twice (positions {first} and {i})"),
                ));
            }
        }
        let n = names.len();
        let words = calculus.n_states().div_ceil(64);
        let universal = StateSet::universal(calculus.n_states());
        let mut sets = Vec::with_capacity(n * n * words);
        for _ in 0..n * n {
            sets.extend_from_slice(universal.words());
        }
        Ok(Self {
            calculus: calculus.clone(),
            names,
            words,
            sets,
        })
    }

    /// The exact network of points with headings (radians; STAR ignores them).
    ///
    /// # Errors
    /// As [`BinaryNetwork::universal`], [`QsrError::Arity`] when names and points differ in
    /// number, [`QsrError::NonFinite`].
    pub fn from_points<S: Into<String>>(
        calculus: &BinaryCalculus,
        names: impl IntoIterator<Item = S>,
        points: &[(Point2<f64>, f64)],
    ) -> crate::Result<Self> {
        let mut net = Self::universal(calculus, names)?;
        if points.len() != net.n_points() {
            return Err(QsrError::Arity(format!(
                "{} names but {} points",
                net.n_points(),
                points.len()
            )));
        }
        let n_states = calculus.n_states();
        for (i, (p, h)) in points.iter().enumerate() {
            for (j, (q, g)) in points.iter().enumerate() {
                if i != j {
                    let r = calculus.classify(*p, *h, *q, *g)?;
                    net.set_one(i, j, &StateSet::single(n_states, r));
                }
            }
        }
        Ok(net)
    }

    /// A network in SparQ's text form: `((A r B) (A (r1 r2) B) ...)`, relations matched
    /// ignoring case; a pair given twice gets the intersection.
    ///
    /// # Errors
    /// [`QsrError::Network`] with the line and column of the offending token.
    pub fn from_sparq_str(calculus: &BinaryCalculus, text: &str) -> crate::Result<Self> {
        let expr = sexpr::parse(text)?;
        let list = expr.as_list().ok_or_else(|| {
            network_error("line 1", "expected a list of constraints ((A r B) ...)")
        })?;
        let mut parsed = Vec::with_capacity(list.len());
        for c in list {
            let at = format!("line {}, column {}", c.line, c.column);
            let items = c.as_list().filter(|l| l.len() == 3).ok_or_else(|| {
                network_error(&at, "a constraint is (A r B) or (A (r1 r2 ...) B)")
            })?;
            let name = |e: &sexpr::Expr| {
                e.as_atom()
                    .map(str::to_owned)
                    .ok_or_else(|| network_error(&at, "a point name is a symbol"))
            };
            let (a, b) = (name(&items[0])?, name(&items[2])?);
            let labels: Vec<String> = match &items[1].kind {
                sexpr::Kind::Atom(r) => vec![r.clone()],
                sexpr::Kind::List(rs) => rs
                    .iter()
                    .map(|r| r.as_atom().map(str::to_owned))
                    .collect::<Option<_>>()
                    .ok_or_else(|| network_error(&at, "relations are symbols"))?,
            };
            parsed.push((at, a, b, labels));
        }
        Self::assemble(calculus, parsed)
    }

    /// A network from JSON: `{"calculus": NAME?, "constraints": [["A", "B", ["label", ...]],
    /// ...]}` (a single label may stand as a string).
    ///
    /// # Errors
    /// [`QsrError::Network`] naming the constraint by position and what is wrong with it.
    pub fn from_json_str(calculus: &BinaryCalculus, text: &str) -> crate::Result<Self> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
            network_error(
                &format!("line {}, column {}", e.line(), e.column()),
                format!("not JSON: {e}"),
            )
        })?;
        if let Some(named) = value.get("calculus").and_then(serde_json::Value::as_str)
            && named != calculus.name()
        {
            return Err(network_error(
                "calculus",
                format!(
                    "the network is over calculus `{named}`, but `{}` was given",
                    calculus.name()
                ),
            ));
        }
        let list = value
            .get("constraints")
            .and_then(serde_json::Value::as_array)
            .ok_or_else(|| network_error("top level", "expected {\"constraints\": [...]}"))?;
        let mut parsed = Vec::with_capacity(list.len());
        for (i, c) in list.iter().enumerate() {
            let at = format!("constraints[{i}]");
            let shape = || network_error(&at, "expected [\"A\", \"B\", [\"label\", ...]]");
            let items = c.as_array().filter(|a| a.len() == 3).ok_or_else(shape)?;
            let name = |v: &serde_json::Value| {
                v.as_str()
                    .filter(|s| !s.is_empty())
                    .map(str::to_owned)
                    .ok_or_else(|| network_error(&at, "point names are non-empty strings"))
            };
            let labels: Vec<String> = match &items[2] {
                serde_json::Value::String(l) => vec![l.clone()],
                serde_json::Value::Array(ls) => ls
                    .iter()
                    .map(|l| l.as_str().map(str::to_owned))
                    .collect::<Option<_>>()
                    .ok_or_else(|| network_error(&at, "labels are strings"))?,
                _ => return Err(shape()),
            };
            parsed.push((at.clone(), name(&items[0])?, name(&items[1])?, labels));
        }
        Self::assemble(calculus, parsed)
    }

    /// A network from constraints `(A, B, [labels])`: the points in order of first
    /// appearance; a pair given twice gets the intersection.
    ///
    /// # Errors
    /// [`QsrError::Network`] naming the constraint by position (`constraints[i]`).
    pub fn from_constraints(
        calculus: &BinaryCalculus,
        constraints: &[(String, String, Vec<String>)],
    ) -> crate::Result<Self> {
        let parsed = constraints
            .iter()
            .enumerate()
            .map(|(i, (a, b, l))| (format!("constraints[{i}]"), a.clone(), b.clone(), l.clone()))
            .collect();
        Self::assemble(calculus, parsed)
    }

    fn assemble(
        calculus: &BinaryCalculus,
        parsed: Vec<(String, String, String, Vec<String>)>,
    ) -> crate::Result<Self> {
        let mut names: Vec<String> = Vec::new();
        for (_, a, b, _) in &parsed {
            for p in [a, b] {
                if !names.contains(p) {
                    names.push(p.clone());
                }
            }
        }
        let mut net = Self::universal(calculus, names)?;
        for (at, a, b, labels) in parsed {
            if a == b {
                return Err(network_error(&at, format!("`{a}` is related to itself")));
            }
            let (i, j) = (net.point(&a).unwrap_or(0), net.point(&b).unwrap_or(0));
            let mut set = StateSet::empty(calculus.n_states());
            for l in &labels {
                let s = calculus.state(l).map_err(|_| {
                    network_error(
                        &at,
                        format!("calculus `{}` has no relation `{l}`", calculus.name()),
                    )
                })?;
                set.insert(s);
            }
            net.constrain(i, j, &set);
        }
        Ok(net)
    }

    /// The calculus.
    #[must_use]
    pub fn calculus(&self) -> &BinaryCalculus {
        &self.calculus
    }

    /// Point names in index order.
    #[must_use]
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The index of a named point.
    #[must_use]
    pub fn point(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Number of points.
    #[must_use]
    pub fn n_points(&self) -> usize {
        self.names.len()
    }

    fn slot(&self, i: usize, j: usize) -> std::ops::Range<usize> {
        let at = (i * self.names.len() + j) * self.words;
        at..at + self.words
    }

    pub(crate) fn words_of(&self, i: usize, j: usize) -> &[u64] {
        &self.sets[self.slot(i, j)]
    }

    /// The relations possible between `i` and `j`.
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> StateSet {
        StateSet::from_words(self.calculus.n_states(), self.words_of(i, j))
    }

    /// The labels of `get(i, j)`.
    #[must_use]
    pub fn labels_of(&self, i: usize, j: usize) -> Vec<String> {
        self.get(i, j)
            .iter()
            .map(|s| self.calculus.label(s).to_owned())
            .collect()
    }

    fn set_one(&mut self, i: usize, j: usize, set: &StateSet) {
        let conv = self.converse_of(set.words());
        let slot = self.slot(i, j);
        self.sets[slot].copy_from_slice(set.words());
        let slot = self.slot(j, i);
        self.sets[slot].copy_from_slice(&conv);
    }

    /// Replaces the relation of `(i, j)` (and its converse at `(j, i)`).
    pub fn set(&mut self, i: usize, j: usize, set: &StateSet) {
        if i != j && i < self.n_points() && j < self.n_points() {
            self.set_one(i, j, set);
        }
    }

    /// Intersects the relation of `(i, j)` with `set` (and `(j, i)` with its converse).
    pub fn constrain(&mut self, i: usize, j: usize, set: &StateSet) {
        if i == j || i >= self.n_points() || j >= self.n_points() {
            return;
        }
        let mut words = self.words_of(i, j).to_vec();
        for (w, s) in words.iter_mut().zip(set.words()) {
            *w &= s;
        }
        self.set_one(
            i,
            j,
            &StateSet::from_words(self.calculus.n_states(), &words),
        );
    }

    /// The converse of a set of relations, as words.
    pub(crate) fn converse_of(&self, words: &[u64]) -> Vec<u64> {
        let conv = self.calculus.converse();
        let mut out = vec![0u64; self.words];
        for s in crate::reason::StateSet::from_words(self.calculus.n_states(), words).iter() {
            for t in conv.get(s) {
                out[t.index() / 64] |= 1 << (t.index() % 64);
            }
        }
        out
    }

    pub(crate) fn replace_words(&mut self, i: usize, j: usize, words: &[u64]) {
        let conv = self.converse_of(words);
        let slot = self.slot(i, j);
        self.sets[slot].copy_from_slice(words);
        let slot = self.slot(j, i);
        self.sets[slot].copy_from_slice(&conv);
    }

    /// Whether every pair holds exactly one relation.
    #[must_use]
    pub fn is_atomic(&self) -> bool {
        self.pairs().all(|(i, j)| self.get(i, j).len() == 1)
    }

    /// Ordered pairs of distinct points.
    pub fn pairs(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        let n = self.n_points();
        (0..n).flat_map(move |i| (0..n).filter(move |&j| j != i).map(move |j| (i, j)))
    }

    /// The network in SparQ's text form, listing the pairs `i < j` that are not universal.
    #[must_use]
    pub fn to_sparq(&self) -> String {
        let n_states = self.calculus.n_states();
        let parts: Vec<String> = self
            .pairs()
            .filter(|&(i, j)| i < j && self.get(i, j).len() < n_states)
            .map(|(i, j)| {
                format!(
                    "({} ({}) {})",
                    self.names[i],
                    self.labels_of(i, j).join(" "),
                    self.names[j]
                )
            })
            .collect();
        format!("({})", parts.join(" "))
    }

    /// The constraints as JSON `[[A, B, [labels]], ...]` for pairs `i < j` that are not
    /// universal.
    #[must_use]
    pub fn constraints_json(&self) -> serde_json::Value {
        let n_states = self.calculus.n_states();
        serde_json::Value::Array(
            self.pairs()
                .filter(|&(i, j)| i < j && self.get(i, j).len() < n_states)
                .map(|(i, j)| {
                    serde_json::json!([self.names[i], self.names[j], self.labels_of(i, j)])
                })
                .collect(),
        )
    }
}

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

/// Algebraic closure (path consistency): repeat `R(i,k) ← R(i,k) ∩ R(i,j) ∘ R(j,k)` over
/// every triple until nothing changes. Sound for every calculus whose composition table is
/// sound — qsr-core's derived binary tables are exact.
///
/// # Errors
/// As [`BinaryCalculus::compose_table`] (a calculus too fine to derive its table).
pub fn close_binary(network: BinaryNetwork) -> crate::Result<BinaryClosure> {
    let c = network.calculus.clone();
    let n_states = c.n_states();
    let words = network.words;
    let table = c.compose_table()?;
    // compose[r][s] as words, and the compositions with a universal side.
    let mut bits = vec![0u64; n_states * n_states * words];
    for r in c.states() {
        for s in c.states() {
            let at = (r.index() * n_states + s.index()) * words;
            for t in table.get(r, s) {
                bits[at + t.index() / 64] |= 1 << (t.index() % 64);
            }
        }
    }
    let compose = |a: &[u64], b: &[u64]| -> Vec<u64> {
        let mut out = vec![0u64; words];
        for r in crate::reason::StateSet::from_words(n_states, a).iter() {
            for s in crate::reason::StateSet::from_words(n_states, b).iter() {
                let at = (r.index() * n_states + s.index()) * words;
                for (o, x) in out.iter_mut().zip(&bits[at..at + words]) {
                    *o |= x;
                }
            }
        }
        out
    };
    let mut net = network;
    let n = net.n_points();
    // A set empty as given is a contradiction even with no third point to compose through.
    let empty = net
        .pairs()
        .find(|&(i, j)| net.words_of(i, j).iter().all(|w| *w == 0));
    if let Some((a, b)) = empty {
        return Ok(BinaryClosure {
            network: net,
            contradiction: Some(BinaryContradiction::Given { a, b }),
            revisions: 0,
        });
    }
    let mut queue: std::collections::VecDeque<(usize, usize)> = net.pairs().collect();
    let mut queued = vec![true; n * n];
    let mut revisions = 0usize;
    while let Some((i, j)) = queue.pop_front() {
        queued[i * n + j] = false;
        for k in 0..n {
            if k == i || k == j {
                continue;
            }
            // R(i,k) ∩= R(i,j) ∘ R(j,k)  and  R(k,j) ∩= R(k,i) ∘ R(i,j)
            for (x, y, via) in [(i, k, j), (k, j, i)] {
                let composed = compose(net.words_of(x, via), net.words_of(via, y));
                let old = net.words_of(x, y);
                let new: Vec<u64> = old.iter().zip(&composed).map(|(a, b)| a & b).collect();
                if new != old {
                    revisions += 1;
                    net.replace_words(x, y, &new);
                    if new.iter().all(|w| *w == 0) {
                        return Ok(BinaryClosure {
                            network: net,
                            contradiction: Some(BinaryContradiction::Composed { a: x, via, b: y }),
                            revisions,
                        });
                    }
                    for (p, q) in [(x, y), (y, x)] {
                        if !queued[p * n + q] {
                            queued[p * n + q] = true;
                            queue.push_back((p, q));
                        }
                    }
                }
            }
        }
    }
    Ok(BinaryClosure {
        network: net,
        contradiction: None,
        revisions,
    })
}

/// The relation set of given ids (ids beyond the calculus are ignored).
#[must_use]
pub fn relation_set(calculus: &BinaryCalculus, ids: impl IntoIterator<Item = StateId>) -> StateSet {
    StateSet::from_states(calculus.n_states(), ids)
}

impl BinaryNetwork {
    /// Reads a network of `calculus` in `format`.
    ///
    /// # Errors
    /// As [`BinaryNetwork::from_json_str`] and [`BinaryNetwork::from_sparq_str`].
    pub fn parse(
        calculus: &BinaryCalculus,
        text: &str,
        format: crate::reason::NetworkFormat,
    ) -> crate::Result<Self> {
        match format {
            crate::reason::NetworkFormat::Json => Self::from_json_str(calculus, text),
            crate::reason::NetworkFormat::Sparq => Self::from_sparq_str(calculus, text),
        }
    }
}
