//! [`Network`]: a ternary constraint network — for every ordered triplet of distinct named
//! points, the set of states its relation may take.

use std::collections::HashMap;

use nalgebra::Point2;

use crate::calculus::{Calculus, StateId};
use crate::cost::{Budget, Cost};
use crate::error::QsrError;
use crate::frame::FrameKind;
use crate::reason::state_set::{StateSet, count, fill_universal, resolve_label, words_for};

/// Core-seconds of closure per ordered triplet × fourth point × word of a set: measured on
/// the half-known EDC networks of `cargo bench -p qsr-core --bench closure` (inferred sets of
/// several states — the slowest case measured; a scenario closes 2–3x faster): n = 140 took
/// 2.13 s on two threads, at most 4.3 core-seconds over 140⁴ units (n = 200: 7.5 s, 9.3e-9
/// per unit). The fitted exponent is 3.4 (n = 30 … 200), so n⁴ errs high for larger
/// networks: an upper bound there (networks of a few dozen points, which take milliseconds,
/// cost more per unit).
pub const CLOSURE_SECONDS_PER_UNIT: f64 = 1.2e-8;

/// What building and closing a network of `n` points takes, before anything is allocated.
///
/// Memory, per ordered triplet: its set, closure's transposed copy of it (one-word calculi)
/// and a provenance record — measured peak at 200 points (double-cross, `qrm reason close`):
/// 238 MB against this 224 MB; the output is streamed, not held (issue 39: the whole JSON
/// value of a 100-point result took 1.3 GB where this said 20 MB). Work: each of the n³
/// ordered triplets is revised against every fourth point, at
/// [`CLOSURE_SECONDS_PER_UNIT`] per word of its set.
pub fn closure_cost(n: usize, n_states: usize) -> Cost {
    let n = n as f64;
    let words = words_for(n_states) as f64;
    Cost::new(
        n.powi(3) * (16.0 * words + 12.0),
        n.powi(4) * words * CLOSURE_SECONDS_PER_UNIT,
    )
}

/// A ternary constraint network over named points.
///
/// Every ordered triplet `(a, b, c)` of distinct points carries a [`StateSet`] of the
/// calculus: the relation `{a,b:c}` is one of those states. A triplet nothing constrains is
/// universal. The six orderings of one unordered triplet are stored separately, as SparQ
/// does; [`close`](crate::reason::close) makes them agree through the permutation tables.
///
/// ```
/// use qsr_core::{Calculus, reason::Network};
/// let dc = Calculus::builtin("double-cross")?;
/// let mut net = Network::universal(&dc, ["A", "B", "C"])?;
/// net.constrain_labels("A", "B", "C", &["left-front"])?;
/// assert_eq!(net.labels_of(0, 1, 2), ["left-front"]);
/// assert_eq!(net.get(1, 0, 2).len(), dc.n_states()); // not yet closed
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone)]
pub struct Network {
    calculus: Calculus,
    names: Vec<String>,
    words: usize,
    /// `sets[index(a, b, c) * words ..][..words]`; the entries with repeated points are unused.
    sets: Vec<u64>,
}

/// Equal when over the same calculus (by name and states), the same points and the same sets.
impl PartialEq for Network {
    fn eq(&self, other: &Self) -> bool {
        self.calculus.name() == other.calculus.name()
            && self.calculus.labels() == other.calculus.labels()
            && self.names == other.names
            && self.sets == other.sets
    }
}

impl Network {
    /// The network over `names` in which nothing is known.
    ///
    /// # Errors
    /// [`QsrError::Arity`] for a calculus that is not ternary; [`QsrError::Network`] for a
    /// repeated or empty name, or a network too large for memory (the estimate is in the
    /// message).
    pub fn universal<S: Into<String>>(
        calculus: &Calculus,
        names: impl IntoIterator<Item = S>,
    ) -> crate::Result<Self> {
        if calculus.frame() != FrameKind::Ternary {
            return Err(QsrError::Unsupported {
                operation: "constraint network".into(),
                calculus: calculus.name().into(),
                reason: format!(
                    "networks of {} relations are not supported yet; ternary point calculi are",
                    calculus.frame().as_str()
                ),
            });
        }
        let names: Vec<String> = names.into_iter().map(Into::into).collect();
        let mut seen = HashMap::new();
        for (i, name) in names.iter().enumerate() {
            if name.is_empty() {
                return Err(network_error(
                    "points",
                    format!("point {i} has an empty name"),
                ));
            }
            if let Some(j) = seen.insert(name.as_str(), i) {
                return Err(network_error(
                    "points",
                    format!("point `{name}` is named twice (points {j} and {i})"),
                ));
            }
        }
        let n = names.len();
        let words = words_for(calculus.n_states());
        closure_cost(n, calculus.n_states())
            .check(
                &Budget::RUN,
                format!("{n} points (n³ ordered triplets, each closed against n fourth points)"),
            )
            .map_err(|e| network_error("points", e.hint("fewer points").to_string()))?;
        let mut sets = vec![0u64; n * n * n * words];
        let mut universal = vec![0u64; words];
        fill_universal(&mut universal, calculus.n_states());
        for (a, b, c) in ordered_triplets(n) {
            let at = ((a * n + b) * n + c) * words;
            sets[at..at + words].copy_from_slice(&universal);
        }
        Ok(Self {
            calculus: calculus.clone(),
            names,
            words,
            sets,
        })
    }

    /// The exact network of a configuration: every ordered triplet holds the one state its
    /// points are in (a *scenario*).
    ///
    /// # Errors
    /// As [`Network::universal`]; [`QsrError::Arity`] when `points` and `names` differ in
    /// length; [`QsrError::DegenerateFrame`] naming the two points that coincide;
    /// [`QsrError::NonFinite`].
    pub fn from_points<S: Into<String>>(
        calculus: &Calculus,
        names: impl IntoIterator<Item = S>,
        points: &[Point2<f64>],
    ) -> crate::Result<Self> {
        let mut net = Self::universal(calculus, names)?;
        if points.len() != net.n_points() {
            return Err(QsrError::Arity(format!(
                "{} points but {} names",
                points.len(),
                net.n_points()
            )));
        }
        let n = net.n_points();
        for (a, b, c) in ordered_triplets(n) {
            let state = calculus
                .classify_triplet(points[a], points[b], points[c])
                .map_err(|e| match e {
                    QsrError::DegenerateFrame { reason } => QsrError::DegenerateFrame {
                        reason: format!(
                            "points `{}` and `{}` coincide ({reason})",
                            net.names[a], net.names[b]
                        ),
                    },
                    other => other,
                })?;
            let set = StateSet::single(calculus.n_states(), state);
            net.set(a, b, c, &set);
        }
        Ok(net)
    }

    /// The calculus.
    #[must_use]
    pub fn calculus(&self) -> &Calculus {
        &self.calculus
    }

    /// The point names, in index order.
    #[must_use]
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The index of a point.
    #[must_use]
    pub fn point(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Number of points.
    #[must_use]
    pub fn n_points(&self) -> usize {
        self.names.len()
    }

    /// Number of ordered triplets of distinct points: `n (n − 1) (n − 2)`.
    #[must_use]
    pub fn n_triplets(&self) -> usize {
        let n = self.n_points();
        n * n.saturating_sub(1) * n.saturating_sub(2)
    }

    /// Every set by flat index (one word each for a calculus of at most 64 states, the only
    /// caller: closure's one-word kernel).
    pub(crate) fn one_word_sets(&self) -> &[u64] {
        &self.sets
    }

    /// The flat index of an ordered triplet.
    pub(crate) fn index(&self, a: usize, b: usize, c: usize) -> usize {
        let n = self.n_points();
        (a * n + b) * n + c
    }

    /// The points of a flat index.
    pub(crate) fn triplet(&self, index: usize) -> [usize; 3] {
        let n = self.n_points();
        [index / (n * n), (index / n) % n, index % n]
    }

    pub(crate) fn words_at(&self, index: usize) -> &[u64] {
        &self.sets[index * self.words..][..self.words]
    }

    pub(crate) fn words_at_mut(&mut self, index: usize) -> &mut [u64] {
        &mut self.sets[index * self.words..][..self.words]
    }

    /// The set of `{a,b:c}` (by point index).
    ///
    /// # Panics
    /// When an index is out of range or two indices are equal.
    #[must_use]
    pub fn get(&self, a: usize, b: usize, c: usize) -> StateSet {
        assert!(
            a != b && b != c && a != c,
            "a triplet needs three distinct points"
        );
        StateSet::from_words(self.calculus.n_states(), self.words_at(self.index(a, b, c)))
    }

    /// The labels of `{a,b:c}`.
    #[must_use]
    pub fn labels_of(&self, a: usize, b: usize, c: usize) -> Vec<String> {
        self.get(a, b, c).labels(&self.calculus)
    }

    /// Replaces the set of `{a,b:c}`.
    ///
    /// # Panics
    /// As [`Network::get`].
    pub fn set(&mut self, a: usize, b: usize, c: usize, set: &StateSet) {
        assert!(
            a != b && b != c && a != c,
            "a triplet needs three distinct points"
        );
        let i = self.index(a, b, c);
        self.words_at_mut(i).copy_from_slice(set.words());
    }

    /// Intersects `{a,b:c}` with `set` (a constraint added to what is known).
    ///
    /// # Panics
    /// As [`Network::get`].
    pub fn constrain(&mut self, a: usize, b: usize, c: usize, set: &StateSet) {
        assert!(
            a != b && b != c && a != c,
            "a triplet needs three distinct points"
        );
        let i = self.index(a, b, c);
        for (w, s) in self.words_at_mut(i).iter_mut().zip(set.words()) {
            *w &= s;
        }
    }

    /// Makes all six orderings of the unordered triplet `{a, b, c}` universal (forgets what
    /// is known about it).
    ///
    /// # Panics
    /// As [`Network::get`].
    pub fn relax(&mut self, a: usize, b: usize, c: usize) {
        let any = StateSet::universal(self.calculus.n_states());
        for (x, y, z) in crate::permute::all_orderings(a, b, c) {
            self.set(x, y, z, &any);
        }
    }

    /// Intersects `{a,b:c}`, given by names and labels, with the labels' set.
    ///
    /// # Errors
    /// [`QsrError::Network`] for an unknown or repeated point; [`QsrError::UnknownState`].
    pub fn constrain_labels(
        &mut self,
        a: &str,
        b: &str,
        c: &str,
        labels: &[impl AsRef<str>],
    ) -> crate::Result<()> {
        let [ia, ib, ic] = self.resolve_triplet(a, b, c, "constraint")?;
        let set = StateSet::from_labels(&self.calculus, labels)?;
        self.constrain(ia, ib, ic, &set);
        Ok(())
    }

    fn resolve_triplet(&self, a: &str, b: &str, c: &str, at: &str) -> crate::Result<[usize; 3]> {
        let find = |name: &str| {
            self.point(name)
                .ok_or_else(|| network_error(at, format!("unknown point `{name}`")))
        };
        let t = [find(a)?, find(b)?, find(c)?];
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(network_error(
                at,
                format!(
                    "({a} {b} {c}) repeats a point; relations with coincident points are not \
                     modelled (the calculus's states are for distinct points)"
                ),
            ));
        }
        Ok(t)
    }

    /// Whether every triplet holds exactly one state (a scenario).
    #[must_use]
    pub fn is_atomic(&self) -> bool {
        let n = self.n_points();
        ordered_triplets(n).all(|(a, b, c)| count(self.words_at(self.index(a, b, c))) == 1)
    }

    /// Whether some triplet's set is empty.
    #[must_use]
    pub fn has_empty(&self) -> bool {
        let n = self.n_points();
        ordered_triplets(n).any(|(a, b, c)| count(self.words_at(self.index(a, b, c))) == 0)
    }

    /// Total number of states over every ordered triplet (a measure of what is unknown).
    #[must_use]
    pub fn total_states(&self) -> usize {
        let n = self.n_points();
        ordered_triplets(n)
            .map(|(a, b, c)| count(self.words_at(self.index(a, b, c))))
            .sum()
    }

    /// Every ordered triplet with its labels, in index order: the interchange form.
    #[must_use]
    pub fn constraints(&self) -> Vec<(String, String, String, Vec<String>)> {
        ordered_triplets(self.n_points())
            .map(|(a, b, c)| {
                (
                    self.names[a].clone(),
                    self.names[b].clone(),
                    self.names[c].clone(),
                    self.labels_of(a, b, c),
                )
            })
            .collect()
    }

    /// The network as JSON: `{"calculus", "points", "constraints": [[A, B, C, [labels]], …]}`
    /// over every ordered triplet (universal ones included, so the file is complete).
    #[must_use]
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "calculus": self.calculus.name(),
            "points": self.names,
            "constraints": self.constraints_json(),
        })
    }

    /// Writes [`Network::to_json`] as compact JSON, the same bytes, one triplet at a time:
    /// a 100-point network has 970,200 triplets, and building the whole value first took
    /// 1.3 GB where the network holds 8 MB (issue 39).
    ///
    /// # Errors
    /// The writer's.
    pub fn write_json(&self, w: &mut impl std::io::Write) -> std::io::Result<()> {
        w.write_all(b"{\"calculus\":")?;
        serde_json::to_writer(&mut *w, self.calculus.name())?;
        w.write_all(b",\"constraints\":")?;
        self.write_constraints_json(w)?;
        w.write_all(b",\"points\":")?;
        serde_json::to_writer(&mut *w, &self.names)?;
        w.write_all(b"}")
    }

    /// Writes the `constraints` array of [`Network::to_json`] as compact JSON (the bytes of
    /// [`Network::constraints_json`]), one triplet at a time.
    ///
    /// # Errors
    /// The writer's.
    pub fn write_constraints_json(&self, w: &mut impl std::io::Write) -> std::io::Result<()> {
        w.write_all(b"[")?;
        for (i, (a, b, c)) in ordered_triplets(self.n_points()).enumerate() {
            if i > 0 {
                w.write_all(b",")?;
            }
            let row = (
                &self.names[a],
                &self.names[b],
                &self.names[c],
                self.labels_of(a, b, c),
            );
            serde_json::to_writer(&mut *w, &row)?;
        }
        w.write_all(b"]")
    }

    /// The `constraints` array of [`Network::to_json`].
    #[must_use]
    pub fn constraints_json(&self) -> serde_json::Value {
        serde_json::Value::Array(
            self.constraints()
                .into_iter()
                .map(|(a, b, c, l)| serde_json::json!([a, b, c, l]))
                .collect(),
        )
    }

    /// The network in SparQ's text form, `((A B (r1 r2) C) …)`, leaving out universal
    /// triplets.
    #[must_use]
    pub fn to_sparq(&self) -> String {
        let n_states = self.calculus.n_states();
        let parts: Vec<String> = ordered_triplets(self.n_points())
            .filter_map(|(a, b, c)| {
                let set = self.get(a, b, c);
                (set.len() < n_states).then(|| {
                    format!(
                        "({} {} ({}) {})",
                        self.names[a],
                        self.names[b],
                        set.labels(&self.calculus).join(" "),
                        self.names[c]
                    )
                })
            })
            .collect();
        format!("({})", parts.join(" "))
    }

    /// A network from JSON: `{"calculus": NAME?, "points": [...]?, "constraints": [["A", "B",
    /// "C", ["label", ...]], ...]}` (a `calculus` key, as [`Network::to_json`] writes, must name
    /// `calculus`). Points are the listed ones, then those named by constraints in order of
    /// first appearance; a triplet given twice gets the intersection.
    ///
    /// # Errors
    /// [`QsrError::Network`] naming the constraint (by position) and what is wrong with it;
    /// [`QsrError::UnknownState`] for a label the calculus does not have.
    pub fn from_json_str(calculus: &Calculus, text: &str) -> crate::Result<Self> {
        let value: serde_json::Value = serde_json::from_str(text).map_err(|e| {
            network_error(
                &format!("line {}, column {}", e.line(), e.column()),
                format!("not JSON: {e}"),
            )
        })?;
        let object = value.as_object().ok_or_else(|| {
            network_error("top level", "expected an object {\"constraints\": [...]}")
        })?;
        if let Some(named) = object.get("calculus").and_then(serde_json::Value::as_str)
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
        let mut names: Vec<String> = Vec::new();
        if let Some(points) = object.get("points") {
            let points = points
                .as_array()
                .ok_or_else(|| network_error("points", "expected an array of names"))?;
            for (i, p) in points.iter().enumerate() {
                names.push(json_name(p).ok_or_else(|| {
                    network_error(&format!("points[{i}]"), "a point name is a string")
                })?);
            }
        }
        let constraints = object
            .get("constraints")
            .ok_or_else(|| network_error("top level", "no \"constraints\" array"))?
            .as_array()
            .ok_or_else(|| network_error("constraints", "expected an array"))?;
        let mut parsed = Vec::with_capacity(constraints.len());
        for (i, c) in constraints.iter().enumerate() {
            let at = format!("constraints[{i}]");
            let items = c.as_array().filter(|a| a.len() == 4).ok_or_else(|| {
                network_error(&at, "expected [\"A\", \"B\", \"C\", [\"label\", ...]]")
            })?;
            let mut pts = Vec::with_capacity(3);
            for item in &items[..3] {
                pts.push(
                    json_name(item).ok_or_else(|| network_error(&at, "point names are strings"))?,
                );
            }
            let labels: Vec<String> = match &items[3] {
                serde_json::Value::String(s) => vec![s.clone()],
                serde_json::Value::Array(ls) => ls
                    .iter()
                    .map(|l| l.as_str().map(str::to_owned))
                    .collect::<Option<_>>()
                    .ok_or_else(|| network_error(&at, "labels are strings"))?,
                _ => return Err(network_error(&at, "the fourth item is a list of labels")),
            };
            parsed.push((at, pts, labels));
        }
        Self::assemble(calculus, names, parsed)
    }

    /// A network in SparQ's text form: `((A B (r1 r2) C) (A B r C) ...)` (a single relation
    /// may stand without parentheses; names and relations are symbols, relations matched
    /// ignoring case as SparQ does).
    ///
    /// # Errors
    /// [`QsrError::Network`] with the line and column of the offending token.
    pub fn from_sparq_str(calculus: &Calculus, text: &str) -> crate::Result<Self> {
        let expr = sexpr::parse(text)?;
        let list = expr.as_list().ok_or_else(|| {
            network_error(
                "line 1",
                "expected a list of constraints ((A B (r ...) C) ...)",
            )
        })?;
        let names: Vec<String> = Vec::new();
        let mut parsed = Vec::with_capacity(list.len());
        for item in list {
            let at = format!("line {}, column {}", item.line, item.column);
            let parts = item
                .as_list()
                .filter(|p| p.len() == 4)
                .ok_or_else(|| network_error(&at, "a ternary constraint is (A B (r ...) C)"))?;
            let atom = |e: &sexpr::Expr| {
                e.as_atom().map(str::to_owned).ok_or_else(|| {
                    network_error(
                        &format!("line {}, column {}", e.line, e.column),
                        "expected a point name",
                    )
                })
            };
            let pts = vec![atom(&parts[0])?, atom(&parts[1])?, atom(&parts[3])?];
            let labels: Vec<String> = match parts[2].as_list() {
                Some(rs) => rs
                    .iter()
                    .map(|r| {
                        r.as_atom().map(str::to_owned).ok_or_else(|| {
                            network_error(
                                &format!("line {}, column {}", r.line, r.column),
                                "expected a relation name",
                            )
                        })
                    })
                    .collect::<crate::Result<_>>()?,
                None => vec![atom(&parts[2])?],
            };
            parsed.push((at, pts, labels));
        }
        Self::assemble(calculus, names, parsed)
    }
}

impl Network {
    /// The network of parsed constraints `(where, [a, b, c], labels)`: the points are
    /// `names`, then the constraints' points in order of first appearance.
    fn assemble(
        calculus: &Calculus,
        mut names: Vec<String>,
        parsed: Vec<(String, Vec<String>, Vec<String>)>,
    ) -> crate::Result<Self> {
        // A set beside the list: a linear `contains` per point made reading quadratic, and
        // 100,000 points took 39 s before the size check could refuse them (issue 39).
        let mut seen: std::collections::HashSet<String> = names.iter().cloned().collect();
        for (_, pts, _) in &parsed {
            for p in pts {
                if seen.insert(p.clone()) {
                    names.push(p.clone());
                }
            }
        }
        let mut net = Self::universal(calculus, names)?;
        for (at, pts, labels) in parsed {
            let [a, b, c] = net.resolve_triplet(&pts[0], &pts[1], &pts[2], &at)?;
            let set = labels_set(calculus, &labels, &at)?;
            net.constrain(a, b, c, &set);
        }
        Ok(net)
    }
}

fn labels_set(calculus: &Calculus, labels: &[String], at: &str) -> crate::Result<StateSet> {
    let mut set = StateSet::empty(calculus.n_states());
    for l in labels {
        let s: StateId = resolve_label(calculus, l).map_err(|_| {
            network_error(
                at,
                format!(
                    "calculus `{}` has no relation `{}` (its relations: {})",
                    calculus.name(),
                    crate::text_file::shorten(l),
                    calculus.labels().join(", ")
                ),
            )
        })?;
        set.insert(s);
    }
    Ok(set)
}

fn json_name(v: &serde_json::Value) -> Option<String> {
    match v {
        serde_json::Value::String(s) if !s.is_empty() => Some(s.clone()),
        _ => None,
    }
}

pub(crate) fn network_error(at: &str, reason: impl Into<String>) -> QsrError {
    QsrError::Network {
        at: at.to_owned(),
        reason: reason.into(),
    }
}

/// Every ordered triplet of distinct indices below `n`, in index order.
pub(crate) fn ordered_triplets(n: usize) -> impl Iterator<Item = (usize, usize, usize)> {
    (0..n).flat_map(move |a| {
        (0..n).flat_map(move |b| {
            (0..n)
                .filter(move |&c| a != b && b != c && a != c)
                .map(move |c| (a, b, c))
        })
    })
}

/// A minimal s-expression reader for SparQ's network syntax (symbols and lists; `;`
/// comments).
pub(crate) mod sexpr {
    use super::network_error;

    #[derive(Debug)]
    pub(crate) struct Expr {
        pub(crate) line: usize,
        pub(crate) column: usize,
        pub(crate) kind: Kind,
    }

    #[derive(Debug)]
    pub(crate) enum Kind {
        Atom(String),
        List(Vec<Expr>),
    }

    impl Expr {
        pub(crate) fn as_list(&self) -> Option<&[Expr]> {
            match &self.kind {
                Kind::List(l) => Some(l),
                Kind::Atom(_) => None,
            }
        }

        pub(crate) fn as_atom(&self) -> Option<&str> {
            match &self.kind {
                Kind::Atom(a) => Some(a),
                Kind::List(_) => None,
            }
        }
    }

    /// The most nesting accepted (SparQ networks nest three deep).
    const MAX_DEPTH: usize = 64;

    /// An atom: `first` and the characters up to white space, a parenthesis or a comment.
    fn read_atom(first: char, chars: &mut std::iter::Peekable<std::str::Chars<'_>>) -> String {
        let mut atom = String::from(first);
        while let Some(&n) = chars.peek() {
            if n.is_whitespace() || n == '(' || n == ')' || n == ';' {
                break;
            }
            atom.push(n);
            chars.next();
        }
        atom
    }

    pub(crate) fn parse(text: &str) -> crate::Result<Expr> {
        let mut chars = text.chars().peekable();
        let (mut line, mut column) = (1usize, 1usize);
        let mut stack: Vec<(usize, usize, Vec<Expr>)> = Vec::new();
        let mut done: Option<Expr> = None;
        let here = |l: usize, c: usize| format!("line {l}, column {c}");
        while let Some(ch) = chars.next() {
            let (l, c) = (line, column);
            if ch == '\n' {
                line += 1;
                column = 1;
            } else {
                column += 1;
            }
            match ch {
                ';' => {
                    while let Some(&n) = chars.peek() {
                        if n == '\n' {
                            break;
                        }
                        chars.next();
                    }
                }
                '(' => {
                    if done.is_some() {
                        return Err(network_error(&here(l, c), "text after the network"));
                    }
                    if stack.len() >= MAX_DEPTH {
                        return Err(network_error(&here(l, c), "lists nested too deep"));
                    }
                    stack.push((l, c, Vec::new()));
                }
                ')' => {
                    let (sl, sc, items) = stack
                        .pop()
                        .ok_or_else(|| network_error(&here(l, c), "unbalanced `)`"))?;
                    let e = Expr {
                        line: sl,
                        column: sc,
                        kind: Kind::List(items),
                    };
                    match stack.last_mut() {
                        Some(top) => top.2.push(e),
                        None => done = Some(e),
                    }
                }
                c2 if c2.is_whitespace() => {}
                _ => {
                    let atom = read_atom(ch, &mut chars);
                    column += atom.chars().count() - 1;
                    let e = Expr {
                        line: l,
                        column: c,
                        kind: Kind::Atom(atom),
                    };
                    match stack.last_mut() {
                        Some(top) => top.2.push(e),
                        None => {
                            return Err(network_error(
                                &here(l, c),
                                "expected `(`: a network is a list ((A B (r) C) ...)",
                            ));
                        }
                    }
                }
            }
        }
        if let Some((l, c, _)) = stack.last() {
            return Err(network_error(
                &here(*l, *c),
                "this `(` is never closed (truncated input?)",
            ));
        }
        done.ok_or_else(|| network_error("line 1", "empty input: expected ((A B (r) C) ...)"))
    }
}
