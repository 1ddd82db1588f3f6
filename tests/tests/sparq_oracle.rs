//! Composition and permutations of the double cross and the flip-flop against SparQ's
//! published tables (`shared/oracles/sparq/`, read at run time, skipped with a message when
//! absent).
//!
//! SparQ's relations are mapped onto our states point by point: its `:algebraic-specification`
//! gives each relation as polynomial (in)equalities over `ax ay bx by cx cy`, which this test
//! evaluates on random configurations. Only *planar* relations (no equality in their
//! specification) are compared; SparQ's on-line and coincidence relations have no state of
//! their own here, because our partitions merge each line into a neighbouring state.
//!
//! Checked:
//! - the map SparQ planar relation → our state is a bijection;
//! - in general position (`ComposeOptions::generic`, `permutation_with(op, false)`) our tables
//!   equal SparQ's planar results exactly;
//! - our default tables (sound for every configuration, boundaries included) contain SparQ's
//!   planar results, and every extra state is a neighbour of one of them: the extras come
//!   from configurations exactly on a line that our partition merges into a state.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::{BTreeMap, BTreeSet};

use qsr_core::{Calculus, ComposeOptions, Permutation, StateId};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

#[derive(Debug, Clone)]
enum Sexp {
    Atom(String),
    List(Vec<Sexp>),
}

impl Sexp {
    fn atom(&self) -> Option<&str> {
        match self {
            Self::Atom(a) => Some(a),
            Self::List(_) => None,
        }
    }
    fn list(&self) -> &[Sexp] {
        match self {
            Self::List(l) => l,
            Self::Atom(_) => &[],
        }
    }
}

fn parse(text: &str) -> Vec<Sexp> {
    let mut tokens = Vec::new();
    let mut cur = String::new();
    let mut chars = text.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            ';' => {
                for d in chars.by_ref() {
                    if d == '\n' {
                        break;
                    }
                }
            }
            '(' | ')' => {
                if !cur.is_empty() {
                    tokens.push(std::mem::take(&mut cur));
                }
                tokens.push(c.to_string());
            }
            c if c.is_whitespace() => {
                if !cur.is_empty() {
                    tokens.push(std::mem::take(&mut cur));
                }
            }
            c => cur.push(c),
        }
    }
    let mut stack: Vec<Vec<Sexp>> = vec![Vec::new()];
    for t in tokens {
        match t.as_str() {
            "(" => stack.push(Vec::new()),
            ")" => {
                let done = stack.pop().unwrap();
                stack.last_mut().unwrap().push(Sexp::List(done));
            }
            _ => stack.last_mut().unwrap().push(Sexp::Atom(t.to_lowercase())),
        }
    }
    stack.pop().unwrap()
}

/// The value following `key` in the `def-calculus` form.
fn keyword<'a>(form: &'a [Sexp], key: &str) -> &'a Sexp {
    let i = form.iter().position(|s| s.atom() == Some(key)).unwrap();
    &form[i + 1]
}

struct Sparq {
    planar: Vec<String>,
    spec: BTreeMap<String, Vec<Sexp>>,
    composition: BTreeMap<(String, String), BTreeSet<String>>,
    unary: BTreeMap<&'static str, BTreeMap<String, BTreeSet<String>>>,
}

fn load(file: &str) -> Option<Sparq> {
    let path = qrm_tests::shared_dir()?.join("oracles/sparq").join(file);
    let text = std::fs::read_to_string(&path).ok()?;
    let top = parse(&text);
    let form = top
        .iter()
        .find(|s| s.list().first().and_then(Sexp::atom) == Some("def-calculus"))?
        .list();
    let names: Vec<String> = keyword(form, ":base-relations")
        .list()
        .iter()
        .filter_map(|s| s.atom().map(str::to_owned))
        .collect();
    let mut spec: BTreeMap<String, Vec<Sexp>> = BTreeMap::new();
    for entry in keyword(form, ":algebraic-specification").list() {
        let l = entry.list();
        let pattern = l[0].atom().unwrap();
        for n in &names {
            let matches = pattern.len() == n.len()
                && pattern
                    .chars()
                    .zip(n.chars())
                    .all(|(p, c)| p == '?' || p == c);
            if matches {
                spec.entry(n.clone())
                    .or_default()
                    .extend(l[1..].iter().cloned());
            }
        }
    }
    let planar = names
        .iter()
        .filter(|n| {
            spec.get(*n).is_some_and(|conds| {
                conds
                    .iter()
                    .all(|c| !c.list().iter().any(|x| x.atom() == Some("=")))
            })
        })
        .cloned()
        .collect();
    let mut composition = BTreeMap::new();
    for row in keyword(form, ":composition-operation").list() {
        let l = row.list();
        let set = l[2]
            .list()
            .iter()
            .filter_map(|s| s.atom().map(str::to_owned))
            .filter(|s| s != "nil")
            .collect();
        composition.insert(
            (
                l[0].atom().unwrap().to_owned(),
                l[1].atom().unwrap().to_owned(),
            ),
            set,
        );
    }
    let mut unary = BTreeMap::new();
    for (key, name) in [
        (":inverse-operation", "inverse"),
        (":shortcut-operation", "shortcut"),
        (":homing-operation", "homing"),
    ] {
        let mut table = BTreeMap::new();
        for row in keyword(form, key).list() {
            let l = row.list();
            let set = l[1..]
                .iter()
                .filter_map(|s| s.atom().map(str::to_owned))
                .filter(|s| s != "nil")
                .collect();
            table.insert(l[0].atom().unwrap().to_owned(), set);
        }
        unary.insert(name, table);
    }
    Some(Sparq {
        planar,
        spec,
        composition,
        unary,
    })
}

/// Sum of the terms of one side of a condition.
fn side(terms: &[Sexp], v: &BTreeMap<&str, f64>) -> f64 {
    terms
        .iter()
        .map(|t| match t {
            Sexp::Atom(a) => a.parse::<f64>().unwrap(),
            Sexp::List(l) => {
                let coef: f64 = l[0].atom().unwrap().parse().unwrap();
                l[1].list().iter().fold(coef, |acc, m| {
                    let m = m.list();
                    let pow: i32 = m[1].atom().unwrap().parse().unwrap();
                    acc * v[m[0].atom().unwrap()].powi(pow)
                })
            }
        })
        .sum()
}

fn holds(conds: &[Sexp], v: &BTreeMap<&str, f64>) -> bool {
    conds.iter().all(|c| {
        let l = c.list();
        let op = l
            .iter()
            .position(|x| matches!(x.atom(), Some("<" | ">" | "=")))
            .unwrap();
        let (lhs, rhs) = (side(&l[..op], v), side(&l[op + 1..], v));
        match l[op].atom().unwrap() {
            "<" => lhs < rhs,
            ">" => lhs > rhs,
            _ => (lhs - rhs).abs() < 1e-12,
        }
    })
}

/// SparQ planar relation → our state, by evaluating both on random configurations.
fn relation_map(s: &Sparq, calc: &Calculus) -> BTreeMap<String, StateId> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut map: BTreeMap<String, BTreeSet<StateId>> = BTreeMap::new();
    for _ in 0..20_000 {
        let p: [f64; 6] = std::array::from_fn(|_| rng.random_range(-10.0..10.0));
        let v: BTreeMap<&str, f64> = ["ax", "ay", "bx", "by", "cx", "cy"]
            .into_iter()
            .zip(p)
            .collect();
        let rels: Vec<&String> = s.planar.iter().filter(|r| holds(&s.spec[*r], &v)).collect();
        assert_eq!(
            rels.len(),
            1,
            "exactly one SparQ planar relation holds at {p:?}: {rels:?}"
        );
        let ours = calc.classify_row(&p).unwrap();
        map.entry(rels[0].clone()).or_default().insert(ours);
    }
    let map: BTreeMap<String, StateId> = map
        .into_iter()
        .map(|(k, v)| {
            assert_eq!(v.len(), 1, "SparQ `{k}` spans our states {v:?}");
            (k, *v.iter().next().unwrap())
        })
        .collect();
    let targets: BTreeSet<_> = map.values().collect();
    assert_eq!(map.len(), s.planar.len(), "every planar relation was met");
    assert_eq!(
        targets.len(),
        calc.n_states(),
        "the map is a bijection onto our states"
    );
    map
}

fn mapped(set: &BTreeSet<String>, map: &BTreeMap<String, StateId>) -> BTreeSet<StateId> {
    set.iter().filter_map(|r| map.get(r).copied()).collect()
}

/// Checks one table row: exact equality for the generic table; containment plus adjacent
/// extras for the default one. Returns the number of extras.
fn compare(
    calc: &Calculus,
    what: &str,
    sparq: &BTreeSet<StateId>,
    generic: &[StateId],
    full: &[StateId],
) -> usize {
    let generic: BTreeSet<StateId> = generic.iter().copied().collect();
    let full: BTreeSet<StateId> = full.iter().copied().collect();
    assert_eq!(
        &generic, sparq,
        "{what}: general-position table differs from SparQ's planar result"
    );
    assert!(
        full.is_superset(sparq),
        "{what}: a SparQ planar result is missing"
    );
    let g = calc.neighbours();
    for extra in full.difference(sparq) {
        assert!(
            sparq.iter().any(|s| g.is_adjacent(*s, *extra)),
            "{what}: extra state {} is not next to SparQ's {:?}",
            calc.label(*extra),
            sparq.iter().map(|s| calc.label(*s)).collect::<Vec<_>>()
        );
    }
    full.difference(sparq).count()
}

fn check_calculus(file: &str, name: &str) {
    let Some(s) = load(file) else {
        eprintln!("SKIPPED: shared/oracles/sparq/{file} not found beside the checkout");
        return;
    };
    let calc = Calculus::builtin(name).unwrap();
    let map = relation_map(&s, &calc);
    let generic = calc.compose_table_with(&ComposeOptions::generic()).unwrap();
    let full = calc.compose_table().unwrap();
    let mut extras = 0;
    for r in &s.planar {
        for t in &s.planar {
            let want = mapped(&s.composition[&(r.clone(), t.clone())], &map);
            let (a, b) = (map[r], map[t]);
            extras += compare(
                &calc,
                &format!("{name}: {r} ∘ {t}"),
                &want,
                generic.get(a, b),
                full.get(a, b),
            );
        }
    }
    eprintln!(
        "{name}: composition agrees with SparQ on {} planar pairs; {extras} boundary extras",
        s.planar.len().pow(2)
    );
    let inv = &s.unary["inverse"];
    let apply =
        |table: &BTreeMap<String, BTreeSet<String>>, rs: &BTreeSet<String>| -> BTreeSet<String> {
            rs.iter().flat_map(|r| table[r].iter().cloned()).collect()
        };
    for op in Permutation::ALL {
        let g = calc.permutation_with(op, false).unwrap();
        let f = calc.permutation(op).unwrap();
        for r in &s.planar {
            let one: BTreeSet<String> = [r.clone()].into();
            let sparq = match op {
                Permutation::Inverse => apply(inv, &one),
                Permutation::Shortcut => apply(&s.unary["shortcut"], &one),
                Permutation::Homing => apply(&s.unary["homing"], &one),
                // A,B r C ⇒ A,C sc(r) B ⇒ C,A inv(sc(r)) B; likewise for homing.
                Permutation::ShortcutInverse => apply(inv, &apply(&s.unary["shortcut"], &one)),
                Permutation::HomingInverse => apply(inv, &apply(&s.unary["homing"], &one)),
            };
            let want = mapped(&sparq, &map);
            compare(
                &calc,
                &format!("{name}: {op}({r})"),
                &want,
                g.get(map[r]),
                f.get(map[r]),
            );
        }
    }
}

#[test]
fn double_cross_agrees_with_sparq() {
    check_calculus("double-cross.lisp", "double-cross");
}

#[test]
fn flip_flop_agrees_with_sparq() {
    check_calculus("flipflop.lisp", "left-right");
}
