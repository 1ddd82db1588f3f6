//! [`AlgebraCheck`]: which of a relation algebra's laws a binary calculus's tables obey.
//!
//! Checked on base relations (the laws extend to sets by union): the converse is an
//! involution; the identity is its own converse and neutral on both sides; the converse of a
//! composition is the composition of the converses in reverse order; composition is
//! associative. Path consistency as GQR runs it (and [`super::close_binary`]) relies on the
//! converse laws; weak compositions (RCC-8's, OPRA's) are not associative, which makes
//! closure weaker, not wrong.

use super::algebra::BinaryAlgebra;
use crate::calculus::StateId;

/// The most relations for which associativity (`n³` set compositions) is checked.
pub const MAX_ASSOCIATIVITY_CHECK: usize = 300;

/// One law of a relation algebra.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AlgebraLaw {
    /// `r˘˘ = r`.
    ConverseInvolution,
    /// `id˘ = id`, `id ∘ r = r ∘ id = r`.
    Identity,
    /// `(r ∘ s)˘ = s˘ ∘ r˘`.
    ConverseOfComposition,
    /// `(r ∘ s) ∘ t = r ∘ (s ∘ t)`.
    Associativity,
}

impl AlgebraLaw {
    /// The law in words.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            Self::ConverseInvolution => "converse is an involution (r˘˘ = r)",
            Self::Identity => "identity is neutral (id ∘ r = r ∘ id = r, id˘ = id)",
            Self::ConverseOfComposition => "converse reverses composition ((r∘s)˘ = s˘∘r˘)",
            Self::Associativity => "composition is associative ((r∘s)∘t = r∘(s∘t))",
        }
    }
}

/// The verdict on one law.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LawVerdict {
    /// The law.
    pub law: AlgebraLaw,
    /// `Some(true)`: holds for every base relation; `Some(false)`: fails (see `witness`);
    /// `None`: not checked (no identity, or too many relations for associativity).
    pub holds: Option<bool>,
    /// The first relations for which it fails, or why it was not checked.
    pub witness: Option<String>,
}

/// The laws a calculus's tables obey.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AlgebraCheck {
    /// One verdict per law, in [`AlgebraLaw`] order.
    pub laws: Vec<LawVerdict>,
}

impl AlgebraCheck {
    /// Whether every law was checked and holds.
    #[must_use]
    pub fn is_relation_algebra(&self) -> bool {
        self.laws.iter().all(|l| l.holds == Some(true))
    }

    /// Whether the converse laws closure relies on hold.
    #[must_use]
    pub fn converse_laws_hold(&self) -> bool {
        self.laws.iter().all(|l| {
            !matches!(
                l.law,
                AlgebraLaw::ConverseInvolution | AlgebraLaw::ConverseOfComposition
            ) || l.holds == Some(true)
        })
    }

    /// One line per law: `holds`, `FAILS (witness)` or `not checked (why)`.
    #[must_use]
    pub fn to_text(&self) -> String {
        self.laws
            .iter()
            .map(|l| {
                let verdict = match (l.holds, &l.witness) {
                    (Some(true), _) => "holds".to_owned(),
                    (Some(false), Some(w)) => format!("FAILS: {w}"),
                    (Some(false), None) => "FAILS".to_owned(),
                    (None, w) => format!("not checked: {}", w.as_deref().unwrap_or("")),
                };
                format!("{}: {verdict}", l.law.describe())
            })
            .collect::<Vec<_>>()
            .join("\n")
    }
}

type Set = Vec<u64>;

struct Tables<'a> {
    alg: &'a BinaryAlgebra,
    words: usize,
    compose: Vec<u64>,
}

impl Tables<'_> {
    fn base(&self, r: usize, s: usize) -> &[u64] {
        let n = self.alg.n_states();
        &self.compose[(r * n + s) * self.words..][..self.words]
    }

    fn single(&self, r: usize) -> Set {
        let mut s = vec![0; self.words];
        s[r / 64] |= 1 << (r % 64);
        s
    }

    fn members(set: &[u64]) -> impl Iterator<Item = usize> + '_ {
        crate::reason::iter_bits(set).map(StateId::index)
    }

    fn compose(&self, a: &[u64], b: &[u64]) -> Set {
        let mut out = vec![0; self.words];
        for r in Self::members(a) {
            for s in Self::members(b) {
                for (o, x) in out.iter_mut().zip(self.base(r, s)) {
                    *o |= x;
                }
            }
        }
        out
    }

    fn converse(&self, a: &[u64]) -> Set {
        let mut out = vec![0; self.words];
        for r in Self::members(a) {
            for t in self
                .alg
                .converse(StateId(u16::try_from(r).unwrap_or(u16::MAX)))
            {
                out[t.index() / 64] |= 1 << (t.index() % 64);
            }
        }
        out
    }

    fn show(&self, set: &[u64]) -> String {
        let labels: Vec<&str> = Self::members(set)
            .map(|r| self.alg.labels()[r].as_str())
            .collect();
        format!("{{{}}}", labels.join(" "))
    }
}

pub(crate) fn check(alg: &BinaryAlgebra) -> crate::Result<AlgebraCheck> {
    let table = alg.compose_table()?;
    let n = alg.n_states();
    let words = n.div_ceil(64).max(1);
    let mut compose = vec![0u64; n * n * words];
    for r in alg.states() {
        for s in alg.states() {
            for t in table.get(r, s) {
                compose[(r.index() * n + s.index()) * words + t.index() / 64] |=
                    1 << (t.index() % 64);
            }
        }
    }
    let t = Tables {
        alg,
        words,
        compose,
    };
    let label = |r: usize| alg.labels()[r].as_str();
    let verdict = |law, failure: Option<String>| LawVerdict {
        law,
        holds: Some(failure.is_none()),
        witness: failure,
    };
    let involution = (0..n).find_map(|r| {
        let back = t.converse(&t.converse(&t.single(r)));
        (back != t.single(r)).then(|| format!("{}˘˘ = {}", label(r), t.show(&back)))
    });
    let identity = match alg.identity() {
        None => LawVerdict {
            law: AlgebraLaw::Identity,
            holds: None,
            witness: Some("the calculus names no identity".into()),
        },
        Some(id) => {
            let i = t.single(id.index());
            let fail = (t.converse(&i) != i)
                .then(|| format!("{}˘ = {}", label(id.index()), t.show(&t.converse(&i))))
                .or_else(|| {
                    (0..n).find_map(|r| {
                        let (left, right) =
                            (t.compose(&i, &t.single(r)), t.compose(&t.single(r), &i));
                        (left != t.single(r) || right != t.single(r)).then(|| {
                            format!(
                                "id ∘ {r_} = {}, {r_} ∘ id = {}",
                                t.show(&left),
                                t.show(&right),
                                r_ = label(r)
                            )
                        })
                    })
                });
            verdict(AlgebraLaw::Identity, fail)
        }
    };
    let conv_comp = (0..n).find_map(|r| {
        (0..n).find_map(|s| {
            let lhs = t.converse(t.base(r, s));
            let rhs = t.compose(&t.converse(&t.single(s)), &t.converse(&t.single(r)));
            (lhs != rhs).then(|| {
                format!(
                    "({} ∘ {})˘ = {} but {}˘ ∘ {}˘ = {}",
                    label(r),
                    label(s),
                    t.show(&lhs),
                    label(s),
                    label(r),
                    t.show(&rhs)
                )
            })
        })
    });
    let associativity = if n > MAX_ASSOCIATIVITY_CHECK {
        LawVerdict {
            law: AlgebraLaw::Associativity,
            holds: None,
            witness: Some(format!(
                "{n} relations: n³ compositions; checked up to {MAX_ASSOCIATIVITY_CHECK}"
            )),
        }
    } else {
        let fail = (0..n).find_map(|r| {
            (0..n).find_map(|s| {
                let rs = t.base(r, s).to_vec();
                (0..n).find_map(|u| {
                    let lhs = t.compose(&rs, &t.single(u));
                    let rhs = t.compose(&t.single(r), t.base(s, u));
                    (lhs != rhs).then(|| {
                        format!(
                            "({a} ∘ {b}) ∘ {c} = {} but {a} ∘ ({b} ∘ {c}) = {}",
                            t.show(&lhs),
                            t.show(&rhs),
                            a = label(r),
                            b = label(s),
                            c = label(u)
                        )
                    })
                })
            })
        });
        verdict(AlgebraLaw::Associativity, fail)
    };
    Ok(AlgebraCheck {
        laws: vec![
            verdict(AlgebraLaw::ConverseInvolution, involution),
            identity,
            verdict(AlgebraLaw::ConverseOfComposition, conv_comp),
            associativity,
        ],
    })
}
