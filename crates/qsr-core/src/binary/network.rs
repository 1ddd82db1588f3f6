//! [`BinaryNetwork`]: a set of relations for every ordered pair of named points, over a
//! [`BinaryAlgebra`]; read from SparQ's text, JSON or GQR's `.csp` ([`super::csp`]), closed
//! by [`super::close_binary`].

use std::collections::HashMap;

use nalgebra::Point2;

use super::algebra::{AsBinaryAlgebra, BinaryAlgebra};
use super::calculus::BinaryCalculus;
use crate::calculus::StateId;
use crate::cost::{Budget, Cost};
use crate::error::QsrError;
use crate::reason::StateSet;
use crate::reason::network::{network_error, sexpr};

/// The most points a binary network may have (n² sets; closure is O(n³) set compositions).
pub const MAX_BINARY_POINTS: usize = 4096;

/// A binary constraint network over named points: `get(i, j)` is the set of relations
/// possible between point `i` and point `j`; `(j, i)` always holds the converse.
///
/// Networks are over a [`BinaryAlgebra`]; every constructor takes a derived calculus or a
/// loaded algebra alike ([`AsBinaryAlgebra`]).
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
    algebra: BinaryAlgebra,
    names: Vec<String>,
    words: usize,
    sets: Vec<u64>,
}

impl BinaryNetwork {
    /// The network where nothing is known: every pair may be in any relation.
    ///
    /// # Errors
    /// [`QsrError::Network`] for an empty or repeated name, more than
    /// [`MAX_BINARY_POINTS`] points, or sets beyond [`Budget::RUN`]'s memory (the estimate is
    /// in the message).
    pub fn universal<S: Into<String>>(
        algebra: &impl AsBinaryAlgebra,
        names: impl IntoIterator<Item = S>,
    ) -> crate::Result<Self> {
        let algebra = algebra.binary_algebra();
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
        let words = algebra.n_states().div_ceil(64);
        // The sets, closure's copy of them (padded to its word size) and its edge queue: the
        // count alone does not bound it (4,096 points of OPRA-10's 1,640 relations are 7 GiB).
        Cost::memory((n * n) as f64 * (16.0 * words as f64 + 16.0))
            .check(
                &Budget::RUN,
                format!("{n} points (n² sets of {} relations)", algebra.n_states()),
            )
            .map_err(|e| network_error("points", e.hint("fewer points").to_string()))?;
        let universal = StateSet::universal(algebra.n_states());
        let sets = universal.words().repeat(n * n);
        Ok(Self {
            algebra,
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
    pub fn from_sparq_str(algebra: &impl AsBinaryAlgebra, text: &str) -> crate::Result<Self> {
        let calculus = &algebra.binary_algebra();
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
    pub fn from_json_str(algebra: &impl AsBinaryAlgebra, text: &str) -> crate::Result<Self> {
        let calculus = &algebra.binary_algebra();
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
        algebra: &impl AsBinaryAlgebra,
        constraints: &[(String, String, Vec<String>)],
    ) -> crate::Result<Self> {
        let calculus = &algebra.binary_algebra();
        let parsed = constraints
            .iter()
            .enumerate()
            .map(|(i, (a, b, l))| (format!("constraints[{i}]"), a.clone(), b.clone(), l.clone()))
            .collect();
        Self::assemble(calculus, parsed)
    }

    fn assemble(
        calculus: &BinaryAlgebra,
        parsed: Vec<(String, String, String, Vec<String>)>,
    ) -> crate::Result<Self> {
        let mut names: Vec<String> = Vec::new();
        let mut index: HashMap<&str, usize> = HashMap::new();
        for (_, a, b, _) in &parsed {
            for p in [a, b] {
                if !index.contains_key(p.as_str()) {
                    index.insert(p, names.len());
                    names.push(p.clone());
                }
            }
        }
        let mut net = Self::universal(calculus, names)?;
        for (at, a, b, labels) in &parsed {
            if a == b {
                return Err(network_error(at, format!("`{a}` is related to itself")));
            }
            let (i, j) = (
                index.get(a.as_str()).copied().unwrap_or(0),
                index.get(b.as_str()).copied().unwrap_or(0),
            );
            let mut set = StateSet::empty(calculus.n_states());
            for l in labels {
                let s = calculus.state(l).map_err(|_| {
                    network_error(
                        at,
                        format!(
                            "calculus `{}` has no relation `{}`",
                            calculus.name(),
                            crate::text_file::shorten(l)
                        ),
                    )
                })?;
                set.insert(s);
            }
            net.constrain(i, j, &set);
        }
        Ok(net)
    }

    /// The algebra the network is over.
    #[must_use]
    pub fn algebra(&self) -> &BinaryAlgebra {
        &self.algebra
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

    /// Words of 64 bits per set.
    pub(crate) fn words_per_set(&self) -> usize {
        self.words
    }

    /// Every set, row by row (`(i · n + j) · words ..`); the diagonal is unused.
    pub(crate) fn raw_sets(&self) -> &[u64] {
        &self.sets
    }

    pub(crate) fn raw_sets_mut(&mut self) -> &mut [u64] {
        &mut self.sets
    }

    /// The relations possible between `i` and `j`.
    #[must_use]
    pub fn get(&self, i: usize, j: usize) -> StateSet {
        StateSet::from_words(self.algebra.n_states(), self.words_of(i, j))
    }

    /// The labels of `get(i, j)`.
    #[must_use]
    pub fn labels_of(&self, i: usize, j: usize) -> Vec<String> {
        self.get(i, j)
            .iter()
            .map(|s| self.algebra.label(s).to_owned())
            .collect()
    }

    fn set_one(&mut self, i: usize, j: usize, set: &StateSet) {
        let slot = self.slot(i, j);
        self.sets[slot].copy_from_slice(set.words());
        self.update_converse(i, j);
    }

    /// Rewrites `(j, i)` as the converse of `(i, j)`, in place (networks of 10⁵ constraints
    /// are read without an allocation per constraint).
    fn update_converse(&mut self, i: usize, j: usize) {
        let (from, to) = (self.slot(i, j).start, self.slot(j, i).start);
        self.sets[to..to + self.words].fill(0);
        for k in 0..self.words {
            let mut word = self.sets[from + k];
            while word != 0 {
                let r = k * 64 + word.trailing_zeros() as usize;
                word &= word - 1;
                for t in self
                    .algebra
                    .converse(StateId(u16::try_from(r).unwrap_or(u16::MAX)))
                {
                    self.sets[to + t.index() / 64] |= 1 << (t.index() % 64);
                }
            }
        }
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
        let slot = self.slot(i, j);
        for (w, s) in self.sets[slot].iter_mut().zip(set.words()) {
            *w &= s;
        }
        self.update_converse(i, j);
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
        let n_states = self.algebra.n_states();
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
        let n_states = self.algebra.n_states();
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
        algebra: &impl AsBinaryAlgebra,
        text: &str,
        format: crate::reason::NetworkFormat,
    ) -> crate::Result<Self> {
        match format {
            crate::reason::NetworkFormat::Json => Self::from_json_str(algebra, text),
            crate::reason::NetworkFormat::Sparq => Self::from_sparq_str(algebra, text),
            crate::reason::NetworkFormat::Gqr => {
                let mut nets = super::csp::from_gqr_csp_str(algebra, text)?;
                match nets.len() {
                    1 => Ok(nets.remove(0).network),
                    k => Err(network_error(
                        "the file",
                        format!("{k} networks in one .csp; read them with `from_gqr_csp_str`"),
                    )),
                }
            }
        }
    }
}
