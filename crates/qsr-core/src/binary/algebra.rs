//! [`BinaryAlgebra`]: what path consistency needs of a binary calculus — relation names, the
//! identity, converse and composition tables, and weights — whether qsr-core derived them
//! (OPRA-m, STAR-m) or they were read from GQR's or SparQ's files (RCC-8, Allen's interval
//! algebra, the point algebra, cardinal directions, …).
//!
//! ## Why one type for both
//! A reasoning user brings the calculi of the literature as tables; qrm's own binary calculi
//! have tables derived by angle arithmetic. Networks, closure, consistency and the file
//! formats need only the tables, so they take a `BinaryAlgebra` and never ask where it came
//! from. A derived calculus composes lazily (its table is derived on the first closure, as
//! before); a loaded one carries its table.
//!
//! ## What loading checks
//! Structure is refused with a typed error naming the file and line (a relation not in the
//! base relations, a missing or repeated table entry, an identity that is not a relation).
//! Algebraic properties are *reported*, not enforced, by [`BinaryAlgebra::check`]: published
//! tables are often weak compositions, where associativity fails by design (OPRA's does;
//! RCC-8's, Allen's and the point algebra's hold: `qrm reason laws`).

use std::sync::{Arc, OnceLock};

use super::calculus::BinaryCalculus;
use super::set_ops::SetOps;
use crate::calculus::StateId;
use crate::compose::ComposeTable;
use crate::error::{QsrError, Result};

/// The most base relations a loaded calculus may have (a relation id is 16 bits; path
/// consistency keeps sets of up to 2,048 relations in fixed-size words).
pub const MAX_LOADED_RELATIONS: usize = 2048;

/// A binary calculus's tables for reasoning; cheap to clone (shared).
///
/// ```
/// use qsr_core::binary::BinaryAlgebra;
/// // The point algebra, as GQR writes it (`r : s :: ( t ... )` and `r :: converse`).
/// let pa = BinaryAlgebra::from_gqr_tables(
///     "point",
///     "< :: >\n= :: =\n> :: <\n",
///     "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n\
///      = : < :: ( < )\n= : = :: ( = )\n= : > :: ( > )\n\
///      > : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n",
///     "=",
///     None,
/// )?;
/// assert_eq!(pa.n_states(), 3);
/// assert!(pa.check()?.is_relation_algebra());
/// # Ok::<(), qsr_core::QsrError>(())
/// ```
#[derive(Debug, Clone)]
pub struct BinaryAlgebra {
    inner: Arc<Inner>,
}

#[derive(Debug)]
struct Inner {
    name: String,
    labels: Vec<String>,
    /// Label → id, for reading networks of 10⁵ constraints.
    index: std::collections::HashMap<String, usize>,
    identity: Option<StateId>,
    /// `converse[r]`: the converses of `r` (one relation for every calculus GQR reads).
    converse: Vec<Vec<StateId>>,
    weights: Vec<u32>,
    source: Source,
    ops: OnceLock<SetOps>,
}

#[derive(Debug)]
enum Source {
    /// qsr-core derives the composition on first use.
    Derived(BinaryCalculus),
    /// Read from files.
    Tables(ComposeTable),
}

impl PartialEq for BinaryAlgebra {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.inner, &other.inner)
            || (self.inner.name == other.inner.name && self.inner.labels == other.inner.labels)
    }
}

impl BinaryAlgebra {
    /// The algebra of a derived calculus (OPRA-m, STAR-m): converse now, composition on the
    /// first closure. Every relation weighs 1; the identity is `s_0` (OPRA) or `eq` (STAR).
    #[must_use]
    pub fn of(calculus: &BinaryCalculus) -> Self {
        let converse = calculus.converse().rows().to_vec();
        let identity = ["s_0", "eq"].iter().find_map(|l| calculus.state(l).ok());
        Self {
            inner: Arc::new(Inner {
                name: calculus.name().to_owned(),
                index: index_of(calculus.labels()),
                labels: calculus.labels().to_vec(),
                identity,
                converse,
                weights: vec![1; calculus.n_states()],
                source: Source::Derived(calculus.clone()),
                ops: OnceLock::new(),
            }),
        }
    }

    /// An algebra from tables given as data: labels, converses, composition, identity and
    /// weights (`None`: all 1).
    ///
    /// # Errors
    /// [`QsrError::Spec`] when the tables' sizes disagree, a converse row is empty, the
    /// identity is out of range, a weight is 0, or there are more than
    /// [`MAX_LOADED_RELATIONS`] relations.
    pub fn from_tables(
        name: &str,
        labels: Vec<String>,
        converse: Vec<Vec<StateId>>,
        compose: ComposeTable,
        identity: Option<StateId>,
        weights: Option<Vec<u32>>,
    ) -> Result<Self> {
        let n = labels.len();
        let bad = |reason: String| QsrError::Spec {
            calculus: name.to_owned(),
            reason,
        };
        if n == 0 || n > MAX_LOADED_RELATIONS {
            return Err(bad(format!(
                "{n} base relations; a binary calculus has 1 to {MAX_LOADED_RELATIONS}"
            )));
        }
        if converse.len() != n || compose.n_states() != n {
            return Err(bad(format!(
                "{n} relations, but the converse table has {} rows and the composition {}",
                converse.len(),
                compose.n_states()
            )));
        }
        if let Some(r) = converse.iter().position(Vec::is_empty) {
            return Err(bad(format!("relation `{}` has no converse", labels[r])));
        }
        if converse.iter().flatten().any(|t| t.index() >= n) {
            return Err(bad("a converse names a relation out of range".into()));
        }
        if identity.is_some_and(|i| i.index() >= n) {
            return Err(bad("the identity is out of range".into()));
        }
        let weights = weights.unwrap_or_else(|| vec![1; n]);
        if weights.len() != n || weights.contains(&0) {
            return Err(bad(format!(
                "weights: {} given for {n} relations, each ≥ 1",
                weights.len()
            )));
        }
        Ok(Self {
            inner: Arc::new(Inner {
                name: name.to_owned(),
                index: index_of(&labels),
                labels,
                identity,
                converse,
                weights,
                source: Source::Tables(compose),
                ops: OnceLock::new(),
            }),
        })
    }

    /// Name (`rcc8`, `opra-2`).
    #[must_use]
    pub fn name(&self) -> &str {
        &self.inner.name
    }

    /// Number of base relations.
    #[must_use]
    pub fn n_states(&self) -> usize {
        self.inner.labels.len()
    }

    /// Relation labels in id order.
    #[must_use]
    pub fn labels(&self) -> &[String] {
        &self.inner.labels
    }

    /// The label of a relation.
    ///
    /// # Panics
    /// If `s` is not a relation of this algebra.
    #[must_use]
    pub fn label(&self, s: StateId) -> &str {
        &self.inner.labels[s.index()]
    }

    /// A relation by label: exact, else ignoring ASCII case when that is unambiguous (SparQ
    /// writes `S_0` for `s_0`; Allen's `d` and `D` are different relations).
    ///
    /// # Errors
    /// [`QsrError::UnknownState`].
    pub fn state(&self, label: &str) -> Result<StateId> {
        let id = |i: usize| StateId(u16::try_from(i).unwrap_or(u16::MAX));
        if let Some(&i) = self.inner.index.get(label) {
            return Ok(id(i));
        }
        let mut folded = self
            .inner
            .labels
            .iter()
            .enumerate()
            .filter(|(_, l)| l.eq_ignore_ascii_case(label));
        match (folded.next(), folded.next()) {
            (Some((i, _)), None) => Ok(id(i)),
            _ => Err(QsrError::UnknownState {
                calculus: self.inner.name.clone(),
                state: crate::text_file::shorten(label),
            }),
        }
    }

    /// All relation ids.
    pub fn states(&self) -> impl ExactSizeIterator<Item = StateId> + '_ {
        (0..self.n_states()).map(|i| StateId(u16::try_from(i).unwrap_or(u16::MAX)))
    }

    /// The identity relation, when the calculus has one.
    #[must_use]
    pub fn identity(&self) -> Option<StateId> {
        self.inner.identity
    }

    /// The converses of `r`.
    #[must_use]
    pub fn converse(&self, r: StateId) -> &[StateId] {
        &self.inner.converse[r.index()]
    }

    /// The weight of `r` (GQR's: smaller is more restrictive; orders the search).
    #[must_use]
    pub fn weight(&self, r: StateId) -> u32 {
        self.inner.weights[r.index()]
    }

    /// The derived calculus behind this algebra, if any (classification lives there).
    #[must_use]
    pub fn calculus(&self) -> Option<&BinaryCalculus> {
        match &self.inner.source {
            Source::Derived(c) => Some(c),
            Source::Tables(_) => None,
        }
    }

    /// The composition table `{A:B} ∘ {B:C} → {A:C}`.
    ///
    /// # Errors
    /// As [`BinaryCalculus::compose_table`] for a derived calculus too fine to derive.
    pub fn compose_table(&self) -> Result<&ComposeTable> {
        match &self.inner.source {
            Source::Derived(c) => c.compose_table(),
            Source::Tables(t) => Ok(t),
        }
    }

    /// The set operations closure runs on (built on first use).
    pub(crate) fn ops(&self) -> Result<&SetOps> {
        if let Some(ops) = self.inner.ops.get() {
            return Ok(ops);
        }
        let table = self.compose_table()?;
        Ok(crate::derived::get_or_derive(&self.inner.ops, || {
            SetOps::new(table, &self.inner.converse, &self.inner.weights)
        }))
    }

    /// Checks the tables' algebra: converse an involution, the identity neutral, composition
    /// associative and compatible with converse. Published weak compositions fail some of
    /// these by design; the report says which, with a witness.
    ///
    /// # Errors
    /// As [`BinaryAlgebra::compose_table`].
    pub fn check(&self) -> Result<super::algebra_check::AlgebraCheck> {
        super::algebra_check::check(self)
    }
}

fn index_of(labels: &[String]) -> std::collections::HashMap<String, usize> {
    labels
        .iter()
        .enumerate()
        .map(|(i, l)| (l.clone(), i))
        .collect()
}

/// What builds a [`BinaryAlgebra`]: the algebra itself, or a derived calculus (whose algebra
/// is made once and shared by its clones).
pub trait AsBinaryAlgebra {
    /// The algebra.
    fn binary_algebra(&self) -> BinaryAlgebra;
}

impl AsBinaryAlgebra for BinaryAlgebra {
    fn binary_algebra(&self) -> BinaryAlgebra {
        self.clone()
    }
}

impl AsBinaryAlgebra for BinaryCalculus {
    fn binary_algebra(&self) -> BinaryAlgebra {
        crate::derived::get_or_derive(&self.derived.algebra, || BinaryAlgebra::of(self)).clone()
    }
}

impl BinaryAlgebra {
    /// A binary calculus by what a user types: a built-in (`opra-M`, `star-m`), a GQR `.spec`
    /// file, a SparQ `.lisp` file, or the name of a calculus in GQR's data directory
    /// (`$GQR_DATA_DIR/NAME.spec`, then `data/NAME.spec`, as GQR searches). `None` when it
    /// names none of these, or a ternary built-in (which wins over a GQR file of that name).
    ///
    /// # Errors
    /// As [`BinaryAlgebra::from_gqr_spec`] and [`BinaryAlgebra::from_sparq_file`] for a file
    /// that is there but malformed.
    pub fn resolve(name: &str) -> Result<Option<Self>> {
        use std::path::{Path, PathBuf};
        if super::is_binary_name(name) {
            let calculus = BinaryCalculus::builtin(name)?;
            // The tables from the disk cache (derived and written on the first use).
            calculus.load_or_derive_cached()?;
            return Ok(Some(calculus.binary_algebra()));
        }
        let path = Path::new(name);
        let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        if ext.eq_ignore_ascii_case("spec") {
            return Self::from_gqr_spec(path).map(Some);
        }
        if ext.eq_ignore_ascii_case("lisp") {
            return Self::from_sparq_file(path).map(Some);
        }
        if name.is_empty()
            || name.contains(['/', '\\'])
            || ext.eq_ignore_ascii_case("toml")
            || ext.eq_ignore_ascii_case("json")
        {
            return Ok(None);
        }
        let dirs = std::env::var_os("GQR_DATA_DIR")
            .map(PathBuf::from)
            .into_iter()
            .chain([PathBuf::from("data")]);
        for dir in dirs {
            let spec = dir.join(format!("{name}.spec"));
            if spec.is_file() {
                return Self::from_gqr_spec(&spec).map(Some);
            }
        }
        Ok(None)
    }
}
