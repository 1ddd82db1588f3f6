//! Binary reasoning over calculi read from tables: loading GQR's and SparQ's files, the
//! algebra check, path consistency against a reference fixpoint, GQR's `.csp` in and out, and
//! consistency by search.
//!
//! The calculi are built here rather than copied: the point algebra by hand, Allen's interval
//! algebra by enumerating intervals on a grid (every relation triple is realised by endpoints
//! among 0..6), OPRA-2 derived by qsr-core; GQR's own OPRA-1 files from `shared/oracles`.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

use std::collections::BTreeSet;
use std::fmt::Write as _;

use proptest::prelude::*;
use qsr_core::QsrError;
use qsr_core::binary::{
    AlgebraLaw, BinaryAlgebra, BinaryCalculus, BinaryNetwork, SolveOptions, SolveOutcome, SplitSet,
    close_binary, from_gqr_csp_str, solve_binary,
};
use qsr_core::reason::StateSet;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

const POINT_CONV: &str = "< :: >\n= :: =\n> :: <\n";
const POINT_COMP: &str = "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n\
                          = : < :: ( < )\n= : = :: ( = )\n= : > :: ( > )\n\
                          > : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n";

fn point_algebra() -> BinaryAlgebra {
    BinaryAlgebra::from_gqr_tables("point", POINT_CONV, POINT_COMP, "=", None).unwrap()
}

/// Allen's relation of interval `a` to interval `b` (GQR's names).
fn allen(a: (i32, i32), b: (i32, i32)) -> &'static str {
    use std::cmp::Ordering::{Equal as E, Greater as G, Less as L};
    match (a.0.cmp(&b.0), a.1.cmp(&b.1), a.1.cmp(&b.0), a.0.cmp(&b.1)) {
        (_, _, L, _) => "<",
        (_, _, _, G) => ">",
        (_, _, E, _) => "m",
        (_, _, _, E) => "mi",
        (E, E, _, _) => "=",
        (E, L, _, _) => "s",
        (E, G, _, _) => "si",
        (G, E, _, _) => "f",
        (L, E, _, _) => "fi",
        (G, L, _, _) => "d",
        (L, G, _, _) => "di",
        (L, L, _, _) => "o",
        (G, G, _, _) => "oi",
    }
}

/// Allen's algebra in GQR's text form, composition by enumeration.
fn allen_tables() -> (String, String) {
    let intervals: Vec<(i32, i32)> = (0..7)
        .flat_map(|a| (a + 1..7).map(move |b| (a, b)))
        .collect();
    let mut comp: std::collections::BTreeMap<(&str, &str), BTreeSet<&str>> = Default::default();
    let mut conv = std::collections::BTreeMap::new();
    for &a in &intervals {
        for &b in &intervals {
            conv.insert(allen(a, b), allen(b, a));
            for &c in &intervals {
                comp.entry((allen(a, b), allen(b, c)))
                    .or_default()
                    .insert(allen(a, c));
            }
        }
    }
    assert_eq!(
        comp.len(),
        169,
        "every pair of Allen relations is realised on the grid"
    );
    let mut conv_text = String::new();
    for (r, t) in conv {
        writeln!(conv_text, "{r} :: {t}").unwrap();
    }
    let mut comp_text = String::new();
    for ((r, s), ts) in comp {
        let ts: Vec<&str> = ts.into_iter().collect();
        writeln!(comp_text, "{r} : {s} :: ( {} )", ts.join(" ")).unwrap();
    }
    (conv_text, comp_text)
}

fn allen_algebra() -> BinaryAlgebra {
    let (conv, comp) = allen_tables();
    BinaryAlgebra::from_gqr_tables("allen", &conv, &comp, "=", None).unwrap()
}

/// The largest path-consistent refinement by the definition: every triangle revised, in
/// every direction, until nothing changes (no queue, no block tables, no converse shortcut).
fn reference_closure(net: &BinaryNetwork) -> Option<Vec<Vec<BTreeSet<String>>>> {
    let alg = net.algebra();
    let table = alg.compose_table().unwrap();
    let n = net.n_points();
    let mut m: Vec<Vec<BTreeSet<usize>>> = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if i == j {
                        BTreeSet::new()
                    } else {
                        net.get(i, j).iter().map(|s| s.index()).collect()
                    }
                })
                .collect()
        })
        .collect();
    let ids: Vec<_> = alg.states().collect();
    loop {
        let mut changed = false;
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    if i == j || j == k || i == k {
                        continue;
                    }
                    let mut allowed = BTreeSet::new();
                    for &r in &m[i][j] {
                        for &s in &m[j][k] {
                            allowed.extend(table.get(ids[r], ids[s]).iter().map(|t| t.index()));
                        }
                    }
                    let new: BTreeSet<usize> = m[i][k].intersection(&allowed).copied().collect();
                    if new != m[i][k] {
                        m[i][k] = new;
                        changed = true;
                    }
                }
            }
        }
        if m.iter()
            .enumerate()
            .any(|(i, row)| row.iter().enumerate().any(|(j, s)| i != j && s.is_empty()))
        {
            return None;
        }
        if !changed {
            break;
        }
    }
    Some(
        m.iter()
            .map(|row| {
                row.iter()
                    .map(|s| s.iter().map(|&r| alg.labels()[r].clone()).collect())
                    .collect()
            })
            .collect(),
    )
}

fn labels_matrix(net: &BinaryNetwork) -> Vec<Vec<BTreeSet<String>>> {
    let n = net.n_points();
    (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if i == j {
                        BTreeSet::new()
                    } else {
                        net.labels_of(i, j).into_iter().collect()
                    }
                })
                .collect()
        })
        .collect()
}

/// A random network in the standard model A(n, d, l), as constraints.
fn random_network(alg: &BinaryAlgebra, n: usize, d: f64, l: f64, seed: u64) -> BinaryNetwork {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut net = BinaryNetwork::universal(alg, (0..n).map(|i| i.to_string())).unwrap();
    let k = alg.n_states();
    for i in 0..n {
        for j in i + 1..n {
            if rng.random::<f64>() < d / (n - 1) as f64 {
                let mut set = StateSet::empty(k);
                while set.is_empty() {
                    for r in alg.states() {
                        if rng.random::<f64>() < l / k as f64 {
                            set.insert(r);
                        }
                    }
                }
                net.constrain(i, j, &set);
            }
        }
    }
    net
}

#[test]
fn closure_is_the_reference_fixpoint_for_loaded_and_derived_calculi() {
    let opra2 = BinaryCalculus::builtin("opra-2").unwrap();
    let cases: Vec<(BinaryAlgebra, f64, &[f64])> = vec![
        (point_algebra(), 1.5, &[2.0, 4.0, 6.0]),
        (allen_algebra(), 6.5, &[4.0, 8.0, 12.0]),
        (BinaryAlgebra::of(&opra2), 36.0, &[3.0, 6.0]),
    ];
    let (mut consistent, mut inconsistent) = (0, 0);
    for (alg, l, degrees) in cases {
        for &d in degrees {
            for seed in 0..6 {
                let net = random_network(&alg, 9, d, l, seed);
                let want = reference_closure(&net);
                let closed = close_binary(net).unwrap();
                match want {
                    None => {
                        inconsistent += 1;
                        assert!(!closed.is_consistent(), "{} d={d} seed {seed}", alg.name());
                    }
                    Some(m) => {
                        consistent += 1;
                        assert!(closed.is_consistent(), "{} d={d} seed {seed}", alg.name());
                        assert_eq!(
                            labels_matrix(&closed.network),
                            m,
                            "{} d={d} seed {seed}",
                            alg.name()
                        );
                    }
                }
            }
        }
    }
    // The cases straddle the phase transition: both verdicts are exercised.
    assert!(
        consistent >= 10 && inconsistent >= 10,
        "{consistent} / {inconsistent}"
    );
}

#[test]
fn the_algebra_check_finds_the_laws_that_fail() {
    assert!(point_algebra().check().unwrap().is_relation_algebra());
    assert!(allen_algebra().check().unwrap().is_relation_algebra());
    // OPRA's composition is weak: not associative, with a witness.
    let opra = BinaryAlgebra::of(&BinaryCalculus::builtin("opra-1").unwrap());
    let laws = opra.check().unwrap();
    let assoc = laws
        .laws
        .iter()
        .find(|l| l.law == AlgebraLaw::Associativity)
        .unwrap();
    assert_eq!(assoc.holds, Some(false));
    assert!(assoc.witness.as_ref().unwrap().contains(" but "));
    assert!(laws.converse_laws_hold());
    // A converse that is not an involution, and an identity that is not neutral.
    let bad = BinaryAlgebra::from_gqr_tables(
        "bad",
        "< :: >\n= :: =\n> :: >\n",
        &POINT_COMP.replace("= : < :: ( < )", "= : < :: ( < = )"),
        "=",
        None,
    )
    .unwrap();
    let text = bad.check().unwrap().to_text();
    assert!(text.contains("involution (r˘˘ = r): FAILS: <˘˘"), "{text}");
    assert!(
        text.contains("identity is neutral (id ∘ r = r ∘ id = r, id˘ = id): FAILS"),
        "{text}"
    );
}

#[test]
fn gqr_files_load_from_a_spec_and_bad_ones_name_the_file_and_line() {
    let dir = std::env::temp_dir().join(format!("qrm-gqr-spec-{}", std::process::id()));
    std::fs::create_dir_all(dir.join("point/calculus")).unwrap();
    std::fs::write(dir.join("point/calculus/point.conv"), POINT_CONV).unwrap();
    std::fs::write(dir.join("point/calculus/point.comp"), POINT_COMP).unwrap();
    std::fs::write(dir.join("point/calculus/point.weights"), "< 2\n= 1\n> 2\n").unwrap();
    let spec = "# Point algebra\ncomp_table_file point/calculus/point.comp\n\
                converse_file point/calculus/point.conv\nweights point/calculus/point.weights\n\
                identity =\ncalculus_size 3\n";
    std::fs::write(dir.join("point.spec"), spec).unwrap();
    let alg = BinaryAlgebra::from_gqr_spec(&dir.join("point.spec")).unwrap();
    assert_eq!(alg.name(), "point");
    assert_eq!(alg.labels(), ["<", "=", ">"]);
    assert_eq!(alg.weight(alg.state("<").unwrap()), 2);
    assert_eq!(alg.identity(), Some(alg.state("=").unwrap()));

    let error = |spec: &str, comp: &str| {
        std::fs::write(dir.join("bad.spec"), spec).unwrap();
        std::fs::write(dir.join("point/calculus/bad.comp"), comp).unwrap();
        BinaryAlgebra::from_gqr_spec(&dir.join("bad.spec"))
            .unwrap_err()
            .to_string()
    };
    let with_comp = spec.replace("point.comp", "bad.comp");
    // A missing entry names the pair and the file.
    let e = error(&with_comp, &POINT_COMP.replace("> : > :: ( > )\n", ""));
    assert!(
        e.contains("bad.comp") && e.contains("no entry for `> : >`"),
        "{e}"
    );
    // A relation that is not a base relation names the line.
    let e = error(
        &with_comp,
        &POINT_COMP.replace("= : = :: ( = )", "= : = :: ( == )"),
    );
    assert!(
        e.contains("line 5") && e.contains("`==` is not a base relation"),
        "{e}"
    );
    // A malformed line.
    let e = error(
        &with_comp,
        &POINT_COMP.replace("< : < :: ( < )", "< < ( < )"),
    );
    assert!(
        e.contains("line 1") && e.contains("expected `r : s :: ( t1 t2 ... )`"),
        "{e}"
    );
    // A size that disagrees with the tables names the spec's line.
    let e = error(
        &with_comp.replace("calculus_size 3", "calculus_size 4"),
        POINT_COMP,
    );
    assert!(
        e.contains("bad.spec") && e.contains("calculus_size is 4"),
        "{e}"
    );
    // An identity that is not a relation; a file that is not there.
    let e = error(&with_comp.replace("identity =", "identity EQ"), POINT_COMP);
    assert!(e.contains("identity `EQ`"), "{e}");
    let e = error(&with_comp.replace("bad.comp", "missing.comp"), POINT_COMP);
    assert!(e.contains("missing.comp"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn gqr_opra1_files_agree_with_the_derived_opra1() {
    let Some(dir) = ["../../../shared/oracles/gqr", "../../shared/oracles/gqr"]
        .iter()
        .map(|d| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(d))
        .find(|d| d.join("opra1.spec").is_file())
    else {
        eprintln!("SKIPPED: shared/oracles/gqr/opra1.spec not found");
        return;
    };
    // The oracle's spec names its tables under `opra1/calculus/`; lay them out as GQR does.
    let tmp = std::env::temp_dir().join(format!("qrm-gqr-opra1-{}", std::process::id()));
    std::fs::create_dir_all(tmp.join("opra1/calculus")).unwrap();
    for f in ["opra1.comp", "opra1.conv"] {
        std::fs::copy(dir.join(f), tmp.join("opra1/calculus").join(f)).unwrap();
    }
    let spec = std::fs::read_to_string(dir.join("opra1.spec")).unwrap();
    let spec: String = spec
        .lines()
        .filter(|l| !l.starts_with("weights"))
        .map(|l| format!("{l}\n"))
        .collect();
    std::fs::write(tmp.join("opra1.spec"), spec).unwrap();
    let loaded = BinaryAlgebra::from_gqr_spec(&tmp.join("opra1.spec")).unwrap();
    let derived = BinaryAlgebra::of(&BinaryCalculus::builtin("opra-1").unwrap());
    let (lt, dt) = (
        loaded.compose_table().unwrap(),
        derived.compose_table().unwrap(),
    );
    for r in loaded.states() {
        assert_eq!(
            derived.state(loaded.label(loaded.converse(r)[0])).unwrap(),
            derived.converse(derived.state(loaded.label(r)).unwrap())[0]
        );
        for s in loaded.states() {
            let want: BTreeSet<&str> = lt.get(r, s).iter().map(|t| loaded.label(*t)).collect();
            let (dr, ds) = (
                derived.state(loaded.label(r)).unwrap(),
                derived.state(loaded.label(s)).unwrap(),
            );
            let got: BTreeSet<&str> = dt.get(dr, ds).iter().map(|t| derived.label(*t)).collect();
            assert_eq!(got, want, "{} ∘ {}", loaded.label(r), loaded.label(s));
        }
    }
    std::fs::remove_dir_all(&tmp).unwrap();
}

#[test]
fn sparq_definitions_load_and_agree_with_the_same_calculus_from_gqr() {
    let lisp = r#";;; point algebra
#| a block
   comment |#
(def-calculus "Point Algebra"
  :arity :binary
  :basis-entity :1d-point
  :identity-relation =
  :converse-operation ((< >) (= =) (> <))
  :base-relations (< = >)
  :composition-operation ((< < <) (< = <) (< > (< = >))
                          (= < <) (= = =) (= > >)
                          (> < (< = >)) (> = >) (> > >)))
"#;
    let sparq = BinaryAlgebra::from_sparq_str(lisp).unwrap();
    let gqr = point_algebra();
    assert_eq!(sparq.labels(), gqr.labels());
    for r in gqr.states() {
        for s in gqr.states() {
            assert_eq!(
                sparq.compose_table().unwrap().get(r, s),
                gqr.compose_table().unwrap().get(r, s)
            );
        }
    }
    let e =
        BinaryAlgebra::from_sparq_str(&lisp.replace("(> > >)))", "(> > >) (> x >)))")).unwrap_err();
    assert!(
        e.to_string().contains("`x` is not one of :base-relations"),
        "{e}"
    );
    let e = BinaryAlgebra::from_sparq_str(&lisp.replace(":binary", ":ternary")).unwrap_err();
    assert!(e.to_string().contains("only binary calculi"), "{e}");
    let e = BinaryAlgebra::from_sparq_str("(in-package :sparq)").unwrap_err();
    assert!(e.to_string().contains("no (def-calculus ...) form"), "{e}");
}

#[test]
fn csp_files_round_trip_and_bad_lines_are_named() {
    let alg = allen_algebra();
    let text = "# two networks\n3 #first\n0 1 ( < m )\n1 2 (<)\n2 3 ( d di = )\n0 1 ( < o )\n.\n\n\
                2 # second\n0 2 ( = )\n.\n";
    let nets = from_gqr_csp_str(&alg, text).unwrap();
    assert_eq!(nets.len(), 2);
    assert_eq!(
        (nets[0].name.as_str(), nets[1].name.as_str()),
        ("first", "second")
    );
    // A pair given twice gets the intersection; the reverse pair holds the converse.
    assert_eq!(nets[0].network.labels_of(0, 1), ["<"]);
    assert_eq!(nets[0].network.labels_of(1, 0), [">"]);
    let again = from_gqr_csp_str(&alg, &nets[0].network.to_gqr_csp("first")).unwrap();
    assert_eq!(again[0].network, nets[0].network);
    assert!(
        nets[0]
            .network
            .to_gqr_csp("first")
            .starts_with("3 #first\n0 1 ( < )\n")
    );

    let bad = |t: &str| from_gqr_csp_str(&alg, t).unwrap_err().to_string();
    let e = bad("2 #x\n0 1 ( < )\n0 3 ( < )\n.\n");
    assert!(
        e.contains("line 3") && e.contains("node 3 is past the header's largest index 2"),
        "{e}"
    );
    let e = bad("2 #x\n0 1 ( < \n.\n");
    assert!(
        e.contains("line 2") && e.contains("expected a constraint"),
        "{e}"
    );
    let e = bad("2 #x\n0 1 ( < zz )\n");
    assert!(
        e.contains("line 2") && e.contains("has no relation `zz`"),
        "{e}"
    );
    let e = bad("x #y\n");
    assert!(e.contains("line 1") && e.contains("header"), "{e}");
    let e = bad("99999999 #huge\n");
    assert!(e.contains("at most"), "{e}");
    assert!(bad("").contains("no network"));
    let long = format!("2 #x\n0 1 ( {} )\n", "q".repeat(100_000));
    assert!(bad(&long).len() < 300, "a long relation name is cut");
    // A self-constraint as GQR reads it: with the identity it says nothing, without it the
    // point relates to nothing.
    let ok = from_gqr_csp_str(&alg, "1 #a\n0 0 ( = < )\n0 1 ( < )\n").unwrap();
    assert!(close_binary(ok[0].network.clone()).unwrap().is_consistent());
    let none = from_gqr_csp_str(&alg, "1 #b\n0 0 ( < )\n0 1 ( < )\n").unwrap();
    assert!(
        !close_binary(none[0].network.clone())
            .unwrap()
            .is_consistent()
    );
}

/// Every atomic refinement of a small network, tried: is one path consistent?
fn brute_force_consistent(net: &BinaryNetwork) -> bool {
    let n = net.n_points();
    let pairs: Vec<(usize, usize)> = (0..n)
        .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
        .collect();
    fn go(net: &BinaryNetwork, pairs: &[(usize, usize)], k: usize) -> bool {
        let Some(&(i, j)) = pairs.get(k) else {
            return close_binary(net.clone()).unwrap().is_consistent();
        };
        net.get(i, j).iter().any(|r| {
            let mut next = net.clone();
            next.set(i, j, &StateSet::single(net.algebra().n_states(), r));
            close_binary(next.clone()).unwrap().is_consistent() && go(&next, pairs, k + 1)
        })
    }
    go(net, &pairs, 0)
}

#[test]
fn search_finds_a_scenario_exactly_when_one_exists_and_says_unknown_past_its_budget() {
    let alg = allen_algebra();
    let (mut found, mut none) = (0, 0);
    for seed in 0..40 {
        let net = random_network(&alg, 5, 3.5, 4.0, 100 + seed);
        let exists = brute_force_consistent(&net);
        let solved = solve_binary(net.clone(), &SolveOptions::default()).unwrap();
        match solved.outcome {
            SolveOutcome::Consistent(s) => {
                assert!(exists, "seed {seed}: a scenario reported where none exists");
                found += 1;
                assert!(s.is_atomic());
                for (i, j) in s.pairs() {
                    assert!(net.get(i, j).is_superset(&s.get(i, j)), "refines the input");
                }
                let closed = close_binary(s.clone()).unwrap();
                assert!(
                    closed.is_consistent() && closed.network == s,
                    "path consistent"
                );
            }
            SolveOutcome::Inconsistent => {
                assert!(!exists, "seed {seed}: a scenario exists");
                none += 1;
            }
            SolveOutcome::Unknown => panic!("the default budget suffices for 5 intervals"),
        }
    }
    assert!(found >= 5 && none >= 5, "{found} / {none}");
    // A budget of one node cannot decide a network that needs a choice.
    let net = random_network(&alg, 30, 6.0, 6.5, 7);
    let solved = solve_binary(
        net,
        &SolveOptions {
            max_nodes: 1,
            ..SolveOptions::default()
        },
    )
    .unwrap();
    assert!(
        matches!(solved.outcome, SolveOutcome::Unknown),
        "{:?}",
        solved.nodes
    );
}

/// The point algebra's convex relations: path consistency decides networks over them (all
/// but `≠`, `{<, >}`), so they are a split set for which search is consistency.
const POINT_CONVEX: &str = "# convex\n( < )\n( = )\n( > )\n( < = )\n( = > )\n( < = > )\n";

/// Checks a search's answer against brute force: a solution refines the input, every set is a
/// split (`members`, or atomic), and closure leaves it as it is.
fn check_solution(
    net: &BinaryNetwork,
    outcome: &SolveOutcome,
    exists: bool,
    members: Option<&[StateSet]>,
    what: &str,
) -> bool {
    match outcome {
        SolveOutcome::Consistent(s) => {
            assert!(exists, "{what}: a solution reported where none exists");
            for (i, j) in s.pairs() {
                let set = s.get(i, j);
                assert!(net.get(i, j).is_superset(&set), "{what}: refines the input");
                match members {
                    Some(m) => assert!(m.contains(&set), "{what}: {i}-{j} is not a split"),
                    None => assert_eq!(set.len(), 1, "{what}: atomic"),
                }
            }
            let closed = close_binary(s.clone()).unwrap();
            assert!(
                closed.is_consistent() && &closed.network == s,
                "{what}: closed"
            );
            !s.is_atomic()
        }
        SolveOutcome::Inconsistent => {
            assert!(!exists, "{what}: a solution exists");
            false
        }
        SolveOutcome::Unknown => panic!("{what}: the default budget suffices"),
    }
}

#[test]
fn search_split_into_a_tractable_subclass_decides_as_brute_force_with_and_without_restarts() {
    let pa = point_algebra();
    let convex = SplitSet::from_gqr_str(&pa, POINT_CONVEX, "pa-convex").unwrap();
    assert_eq!(convex.len(), 6);
    let (mut found, mut none, mut stopped_early) = (0, 0, 0);
    for seed in 0..80 {
        // Dense, with labels of about half the relations: many `≠` and `≤` constraints.
        let net = random_network(&pa, 7, 4.0, 1.6, 300 + seed);
        let exists = brute_force_consistent(&net);
        for restarts in [true, false] {
            for split in [None, Some(&convex)] {
                let options = SolveOptions {
                    split: split.cloned(),
                    restarts,
                    ..SolveOptions::default()
                };
                let solved = solve_binary(net.clone(), &options).unwrap();
                let what = format!(
                    "seed {seed}, restarts {restarts}, split {}",
                    split.is_some()
                );
                let members = split.map(SplitSet::members);
                stopped_early += usize::from(check_solution(
                    &net,
                    &solved.outcome,
                    exists,
                    members,
                    &what,
                ));
            }
        }
        if exists {
            found += 1;
        } else {
            none += 1;
        }
    }
    assert!(found >= 10 && none >= 10, "{found} consistent / {none} not");
    // The split search stops at convex sets: some solutions are not atomic.
    assert!(stopped_early >= 10, "{stopped_early} non-atomic solutions");
}

#[test]
fn search_with_restarts_and_without_agree_on_allen_networks_around_the_transition() {
    let alg = allen_algebra();
    let (mut yes, mut no, mut restarted) = (0, 0, 0);
    for seed in 0..24 {
        let net = random_network(&alg, 30, 8.5, 6.5, 900 + seed);
        let with = solve_binary(net.clone(), &SolveOptions::default()).unwrap();
        let without = solve_binary(
            net.clone(),
            &SolveOptions {
                restarts: false,
                ..SolveOptions::default()
            },
        )
        .unwrap();
        let verdict = |o: &SolveOutcome| match o {
            SolveOutcome::Consistent(s) => {
                assert!(s.is_atomic());
                for (i, j) in s.pairs() {
                    assert!(net.get(i, j).is_superset(&s.get(i, j)));
                }
                Some(true)
            }
            SolveOutcome::Inconsistent => Some(false),
            SolveOutcome::Unknown => None,
        };
        let v = verdict(&with.outcome);
        assert_eq!(v, verdict(&without.outcome), "seed {seed}");
        match v {
            Some(true) => yes += 1,
            Some(false) => no += 1,
            None => panic!("seed {seed}: undecided within the default budget"),
        }
        restarted += usize::from(with.restarts > 0);
        assert_eq!(without.restarts, 0);
    }
    assert!(yes >= 3 && no >= 3, "{yes} consistent / {no} not");
    assert!(
        restarted >= 1,
        "no network needed a restart: the test does not exercise them"
    );
}

#[test]
fn split_sets_load_as_gqr_finds_them_and_bad_ones_name_the_line_and_relation() {
    let pa = point_algebra();
    let err = |text: &str| {
        SplitSet::from_gqr_str(&pa, text, "my.alg")
            .unwrap_err()
            .to_string()
    };
    let e = err("( < )\n( = )\n( > )\n< =\n");
    assert!(
        e.contains("my.alg") && e.contains("line 4") && e.contains("< ="),
        "{e}"
    );
    let e = err("( < )\n( = )\n( > )\n( < lt )\n");
    assert!(e.contains("line 4") && e.contains("`lt`"), "{e}");
    let e = err("( < )\n( > )\n( < = )\n");
    assert!(
        e.contains("`=`") && e.contains("not a member on its own"),
        "{e}"
    );
    let e = err("( < )\n( = )\n( > ) x\n");
    assert!(e.contains("line 3"), "{e}");
    // GQR's -c NAME: DIR/CALCULUS/calculus/NAMEalg beside the .spec.
    let dir = std::env::temp_dir().join(format!("qrm-split-{}", std::process::id()));
    let at = dir.join("point").join("calculus");
    std::fs::create_dir_all(&at).unwrap();
    std::fs::write(at.join("convexalg"), POINT_CONVEX).unwrap();
    let found = SplitSet::resolve(&pa, "convex", Some(&dir)).unwrap();
    assert_eq!(found.len(), 6);
    assert!(found.origin().ends_with("convexalg"));
    let by_path = SplitSet::resolve(&pa, &at.join("convexalg").display().to_string(), None);
    assert_eq!(by_path.unwrap().members(), found.members());
    let e = SplitSet::resolve(&pa, "horn", Some(&dir))
        .unwrap_err()
        .to_string();
    assert!(e.contains("hornalg") && e.contains("no such file"), "{e}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn loaded_tables_with_a_bad_structure_are_typed_errors() {
    let e = BinaryAlgebra::from_gqr_tables("x", "< :: >\n< :: <\n> :: <\n", POINT_COMP, "=", None);
    assert!(matches!(e, Err(QsrError::Spec { .. })));
    let e =
        BinaryAlgebra::from_gqr_tables("x", POINT_CONV, POINT_COMP, "=", Some("< 1\n= 0\n> 1\n"))
            .unwrap_err()
            .to_string();
    assert!(e.contains("weight `0`"), "{e}");
    let e = BinaryAlgebra::from_gqr_tables("x", "", "", "=", None)
        .unwrap_err()
        .to_string();
    assert!(e.contains("0 base relations"), "{e}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    /// Closure and the reference agree on any random point-algebra network, including
    /// dense and empty ones.
    #[test]
    fn closure_matches_the_reference_on_random_point_networks(
        seed in 0u64..1_000_000, n in 2usize..9, d in 0.0f64..8.0,
    ) {
        let alg = point_algebra();
        let net = random_network(&alg, n, d, 1.5, seed);
        let want = reference_closure(&net);
        let closed = close_binary(net).unwrap();
        prop_assert_eq!(closed.is_consistent(), want.is_some());
        if let Some(m) = want {
            prop_assert_eq!(labels_matrix(&closed.network), m);
        }
    }
}

#[test]
fn regression_a_gqr_spec_with_a_latin1_comment_loads() {
    // GQR's data/occ.spec carries an ISO-8859-1 comment; it was refused as "not valid UTF-8".
    let dir = std::env::temp_dir().join(format!("qrm-gqr-latin1-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("p.conv"), POINT_CONV).unwrap();
    std::fs::write(dir.join("p.comp"), POINT_COMP).unwrap();
    let mut spec = b"# Punktalgebra (W\xf6lfl)\n".to_vec();
    spec.extend_from_slice(
        b"comp_table_file p.comp\nconverse_file p.conv\nidentity =\ncalculus_size 3\n",
    );
    std::fs::write(dir.join("p.spec"), spec).unwrap();
    let alg = BinaryAlgebra::from_gqr_spec(&dir.join("p.spec")).unwrap();
    assert_eq!(alg.labels(), ["<", "=", ">"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Issue 39: the binary point cap (4,096) bounded the sets' count, not their size — 4,096
/// points of OPRA-10 (1,640 relations, 26 words a set) ask for about 7 GiB. The estimate
/// counts the words: refused with it, naming the points, before anything is allocated; the
/// same points of OPRA-1 (one word) are built.
#[test]
fn a_binary_network_is_refused_by_its_sets_memory_not_only_by_its_point_count() {
    let names: Vec<String> = (0..4_000).map(|i| format!("p{i}")).collect();
    let fine = BinaryCalculus::builtin("opra-10").unwrap();
    let t0 = std::time::Instant::now();
    let err = BinaryNetwork::universal(&fine, names.clone())
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("4000 points") && err.contains("GiB") && err.contains("the limits are"),
        "{err}"
    );
    assert!(t0.elapsed().as_secs_f64() < 5.0, "{:?}", t0.elapsed());
    let coarse = BinaryCalculus::builtin("opra-1").unwrap();
    assert_eq!(
        BinaryNetwork::universal(&coarse, names).unwrap().n_points(),
        4_000
    );
}
