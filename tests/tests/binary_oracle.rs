//! Binary calculi against published tables: OPRA-1 composition and converse against GQR's
//! `opra1` (exported from SparQ; compared as text, relation names as GQR writes them), and
//! STAR-8 against SparQ's revised star calculus (relations mapped by SparQ's own qualifier).
//! The tables are read from `shared/oracles/` at run time; a test without them says SKIPPED.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::{BTreeMap, BTreeSet};
use std::f64::consts::PI;

use qrm_tests::sexp::{Sexp, keyword, parse};
use qsr_core::Point2;
use qsr_core::binary::BinaryCalculus;

fn oracle(path: &str) -> Option<String> {
    std::fs::read_to_string(qrm_tests::shared_dir()?.join("oracles").join(path)).ok()
}

fn set(items: &[&str]) -> BTreeSet<String> {
    items.iter().map(|s| s.to_lowercase()).collect()
}

/// GQR's `r : s :: ( t1 t2 ... )` lines.
fn gqr_composition(text: &str) -> BTreeMap<(String, String), BTreeSet<String>> {
    let mut out = BTreeMap::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let (lhs, rhs) = line.split_once("::").expect("r : s :: (...)");
        let (r, s) = lhs.split_once(':').expect("r : s");
        let ts: Vec<&str> = rhs
            .trim()
            .trim_start_matches('(')
            .trim_end_matches(')')
            .split_whitespace()
            .collect();
        let key = (r.trim().to_lowercase(), s.trim().to_lowercase());
        assert!(
            out.insert(key, set(&ts)).is_none(),
            "entry given twice: {line}"
        );
    }
    out
}

fn ours_compose(c: &BinaryCalculus, r: &str, s: &str) -> BTreeSet<String> {
    let t = c.compose_table().unwrap();
    t.get(c.state(r).unwrap(), c.state(s).unwrap())
        .iter()
        .map(|x| c.label(*x).to_lowercase())
        .collect()
}

#[test]
fn opra1_composition_and_converse_equal_gqr() {
    let (Some(comp), Some(conv), Some(spec)) = (
        oracle("gqr/opra1.comp"),
        oracle("gqr/opra1.conv"),
        oracle("gqr/opra1.spec"),
    ) else {
        eprintln!("SKIPPED: shared/oracles/gqr/opra1.* not found beside the checkout");
        return;
    };
    let c = BinaryCalculus::builtin("opra-1").unwrap();
    let size: usize = spec
        .lines()
        .find_map(|l| l.strip_prefix("calculus_size "))
        .unwrap()
        .trim()
        .parse()
        .unwrap();
    assert_eq!(c.n_states(), size);
    let identity = spec
        .lines()
        .find_map(|l| l.strip_prefix("identity "))
        .unwrap()
        .trim();
    let id = c.state(identity).unwrap();
    for r in c.states() {
        assert_eq!(
            c.compose_table().unwrap().get(r, id),
            &[r],
            "{identity} is the identity"
        );
    }

    let gqr = gqr_composition(&comp);
    assert_eq!(gqr.len(), size * size, "GQR lists every pair");
    let mut differ = Vec::new();
    for ((r, s), theirs) in &gqr {
        let ours = ours_compose(&c, r, s);
        if &ours != theirs {
            differ.push(format!(
                "{r} ∘ {s}: ours {ours:?}, GQR {theirs:?} (missing {:?}, extra {:?})",
                theirs.difference(&ours).collect::<Vec<_>>(),
                ours.difference(theirs).collect::<Vec<_>>()
            ));
        }
    }
    assert!(
        differ.is_empty(),
        "{} of {} entries differ:\n{}",
        differ.len(),
        gqr.len(),
        differ.join("\n")
    );

    let mut n_conv = 0;
    for line in conv.lines().filter(|l| !l.trim().is_empty()) {
        let (r, t) = line.split_once("::").unwrap();
        let ours: Vec<&str> = c
            .converse()
            .get(c.state(r.trim()).unwrap())
            .iter()
            .map(|x| c.label(*x))
            .collect();
        assert_eq!(ours, [t.trim()], "converse of {r}");
        n_conv += 1;
    }
    assert_eq!(n_conv, size);
}

/// SparQ's revised-star qualifier, exactly: the number of π/4 rotations `i` after which the
/// vector has `x > 0` and one more rotation gives `x ≤ 0`. Evaluated in integers for
/// integer vectors (`cos`, `sin` of multiples of π/4 are 0, ±1 or ±1/√2, and the positive
/// factor 1/√2 does not change a sign), so boundary rays are decided as the definition says.
fn sparq_star(dx: i64, dy: i64) -> String {
    if dx == 0 && dy == 0 {
        return "id".into();
    }
    // x-coordinate of (dx, dy) rotated by k·π/4, up to a positive factor.
    let rotated_x = |k: i64| -> i64 {
        match k.rem_euclid(8) {
            0 => dx,
            1 => dx - dy,
            2 => -dy,
            3 => -dx - dy,
            4 => -dx,
            5 => -dx + dy,
            6 => dy,
            _ => dx + dy,
        }
    };
    (0..8)
        .find(|&i| rotated_x(i) > 0 && rotated_x(i + 1) <= 0)
        .map(|i| i.to_string())
        .expect("some rotation")
}

#[test]
fn star8_agrees_with_sparq_revised_star() {
    let Some(text) = oracle("sparq/revised-star-calculus.lisp") else {
        eprintln!("SKIPPED: shared/oracles/sparq/revised-star-calculus.lisp not found");
        return;
    };
    let top = parse(&text);
    let form = top
        .iter()
        .find(|s| s.list().first().and_then(Sexp::atom) == Some("def-calculus"))
        .unwrap()
        .list();
    let c = BinaryCalculus::builtin("star-8").unwrap();

    // Our reference direction at π/8 puts our sector k on [k·π/4, (k+1)·π/4): map each of
    // our relations to SparQ's by the qualifier on the ray it owns and on its bisector — both
    // must agree, which also checks that the boundary rays are owned alike.
    let dirs: [(i64, i64); 8] = [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ];
    let reference = PI / 8.0;
    let mut to_sparq: BTreeMap<String, String> = BTreeMap::new();
    for k in 0..8 {
        let (bx, by) = dirs[k];
        let (nx, ny) = dirs[(k + 1) % 8];
        let mut seen = BTreeSet::new();
        let mut ours = BTreeSet::new();
        for (x, y) in [(bx, by), (bx + nx, by + ny)] {
            seen.insert(sparq_star(x, y));
            let p = Point2::new(x as f64, y as f64);
            ours.insert(
                c.label(c.classify(Point2::origin(), reference, p, 0.0).unwrap())
                    .to_owned(),
            );
        }
        assert_eq!(seen.len(), 1, "sector {k} meets SparQ relations {seen:?}");
        assert_eq!(ours.len(), 1, "sector {k} classified as {ours:?}");
        to_sparq.insert(ours.pop_first().unwrap(), seen.pop_first().unwrap());
    }
    let eq = c.label(
        c.classify(Point2::origin(), reference, Point2::origin(), 0.0)
            .unwrap(),
    );
    to_sparq.insert(eq.to_owned(), sparq_star(0, 0));
    let names: BTreeSet<&String> = to_sparq.values().collect();
    assert_eq!(names.len(), 9, "the map is one to one: {to_sparq:?}");
    let from_sparq: BTreeMap<&String, &String> = to_sparq.iter().map(|(a, b)| (b, a)).collect();

    let atoms = |e: &Sexp| -> BTreeSet<String> {
        match e {
            Sexp::Atom(a) => [a.clone()].into(),
            Sexp::List(l) => l
                .iter()
                .filter_map(|x| x.atom().map(str::to_owned))
                .collect(),
        }
    };
    let mut checked = 0;
    for row in keyword(form, ":composition-operation").list() {
        let l = row.list();
        let (r, s) = (l[0].atom().unwrap(), l[1].atom().unwrap());
        let theirs = atoms(&l[2]);
        let ours: BTreeSet<String> =
            ours_compose(&c, from_sparq[&r.to_owned()], from_sparq[&s.to_owned()])
                .iter()
                .map(|t| to_sparq[t].clone())
                .collect();
        assert_eq!(ours, theirs, "{r} ∘ {s}");
        checked += 1;
    }
    assert_eq!(checked, 81, "SparQ lists all 9 × 9 compositions");
    for row in keyword(form, ":converse-operation").list() {
        let l = row.list();
        let r = l[0].atom().unwrap();
        let ours: BTreeSet<String> = c
            .converse()
            .get(c.state(from_sparq[&r.to_owned()]).unwrap())
            .iter()
            .map(|t| to_sparq[c.label(*t)].clone())
            .collect();
        assert_eq!(ours, atoms(&l[1]), "converse of {r}");
    }
}
