//! User calculi from spec files, validation errors, and learned (raster) calculi.
#![allow(clippy::unwrap_used)] // tests: a panic is the failure report

mod common;

use qsr_core::{BUILTIN_SPECS, Calculus, OutsideRule, Permutation, Point2, QsrError};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn random_points(n: usize, seed: u64) -> Vec<Point2<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| Point2::new(rng.random_range(-4.0..4.0), rng.random_range(-3.0..4.0)))
        .collect()
}

#[test]
fn a_user_calculus_from_a_file_behaves_exactly_like_the_builtin() {
    let dir = std::env::temp_dir().join(format!("qsr-core-spec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in BUILTIN_SPECS {
        let builtin = Calculus::builtin(name).unwrap();
        // Through a TOML file and through JSON.
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, text).unwrap();
        let from_toml = Calculus::resolve(path.to_str().unwrap()).unwrap();
        let json = builtin.spec().to_json_string().unwrap();
        let from_json = Calculus::from_json_str(&json).unwrap();
        for user in [&from_toml, &from_json] {
            assert_eq!(user.labels(), builtin.labels());
            for p in random_points(20_000, 3) {
                assert_eq!(
                    user.classify_normalised(&p),
                    builtin.classify_normalised(&p)
                );
            }
            assert_eq!(
                user.neighbours().edges(),
                builtin.neighbours().edges(),
                "{name}"
            );
            if builtin.frame() == qsr_core::FrameKind::Ternary {
                assert_eq!(
                    user.compose_table().unwrap(),
                    builtin.compose_table().unwrap(),
                    "{name}"
                );
                for op in Permutation::ALL {
                    assert_eq!(
                        user.permutation(op).unwrap(),
                        builtin.permutation(op).unwrap()
                    );
                }
            }
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_new_user_calculus_works_end_to_end() {
    // Distance rings about A (not a built-in): near / middle / far.
    let text = r#"
        name = "rings"
        frame = "ternary"
        [[constraint]]
        kind = "circle"
        center = [0.0, 0.0]
        radius = 1.0
        zero = "negative"
        [[constraint]]
        kind = "circle"
        center = [0.0, 0.0]
        radius = 2.0
        zero = "negative"
        [[state]]
        label = "near"
        cells = ["--"]
        [[state]]
        label = "middle"
        cells = ["+-"]
        [[state]]
        label = "far"
        cells = ["++"]
    "#;
    let c = Calculus::from_toml_str(text).unwrap();
    assert_eq!(c.neighbours().diameter(), Some(2));
    let s = |l: &str| c.state(l).unwrap();
    assert!(!c.neighbours().is_adjacent(s("near"), s("far")));
    // Inverse of "near" (|AC| ≤ |AB|) from B's side: |BC| ≤ 2|AB|, so never far.
    let inv = c.permutation(Permutation::Inverse).unwrap();
    assert_eq!(inv.get(s("near")), &[s("near"), s("middle")]);
}

fn spec_err(text: &str) -> String {
    match Calculus::from_toml_str(text) {
        Err(QsrError::Spec { reason, .. }) => reason,
        other => panic!("expected a spec error, got {other:?}"),
    }
}

const LINE: &str =
    "[[constraint]]\nkind = \"line\"\na = 1.0\nb = 0.0\nc = 0.0\nzero = \"positive\"\n";

#[test]
fn bad_specs_get_clear_errors() {
    let head = "name = \"x\"\nframe = \"ternary\"\n";
    let st = |l: &str, p: &str| format!("[[state]]\nlabel = \"{l}\"\ncells = [\"{p}\"]\n");
    assert!(
        spec_err(&format!("{head}{LINE}{}{}", st("a", "-"), st("a", "+")))
            .contains("duplicate state label")
    );
    assert!(spec_err(&format!("{head}{LINE}{}", st("left", "-"))).contains("no state claims"));
    assert!(
        spec_err(&format!("{head}{LINE}{}{}", st("a", "-"), st("b", "*")))
            .contains("claimed by states")
    );
    assert!(
        spec_err(&format!("{head}{LINE}{}{}", st("a", "-"), st("b", "+x"))).contains("characters")
    );
    // A state whose cells never occur: inside a unit circle *and* right of a line far away.
    let unreachable = format!(
        "{head}[[constraint]]\nkind = \"circle\"\ncenter = [0.0, 0.0]\nradius = 1.0\nzero = \"negative\"\n\
         [[constraint]]\nkind = \"line\"\na = 1.0\nb = 0.0\nc = -5.0\nzero = \"positive\"\n{}{}{}",
        st("in", "--"),
        st("out", "+-"),
        st("ghost", "-+")
    );
    let msg = format!(
        "{}",
        Calculus::from_toml_str(&unreachable.replace("[\"+-\"]", "[\"+-\", \"++\"]")).unwrap_err()
    );
    assert!(msg.contains("`ghost` is unreachable"), "{msg}");
    assert!(spec_err(&format!("{head}[[constraint]]\nkind = \"circle\"\ncenter = [0.0, 0.0]\nradius = -1.0\nzero = \"negative\"\n{}", st("a", "*"))).contains("radius must be > 0"));
    assert!(spec_err(&format!("{head}[[constraint]]\nkind = \"line\"\na = 0.0\nb = 0.0\nc = 1.0\nzero = \"negative\"\n{}", st("a", "*"))).contains("(a, b) != (0, 0)"));
    // Regression (issue 17): a circle centred at 1e308 made the sampler's probe window
    // infinite and `coverage.rs` panicked on load, in every command; a line that far too.
    assert!(spec_err(&format!("{head}[[constraint]]\nkind = \"circle\"\ncenter = [1e308, 0.0]\nradius = 1.0\nzero = \"negative\"\n{}{}", st("in", "-"), st("out", "+"))).contains("must lie within"));
    assert!(spec_err(&format!("{head}[[constraint]]\nkind = \"circle\"\ncenter = [0.0, 0.0]\nradius = 1e-300\nzero = \"negative\"\n{}{}", st("in", "-"), st("out", "+"))).contains("radius"));
    assert!(spec_err(&format!("{head}[[constraint]]\nkind = \"line\"\na = 1.0\nb = 0.0\nc = 1e300\nzero = \"negative\"\n{}{}", st("l", "-"), st("r", "+"))).contains("must lie within"));
    assert!(spec_err(&format!("{head}{}", st("a", ""))).contains("constraints or a raster"));
    assert!(spec_err("name = \"x\"\nframe = \"quaternary\"\n").contains("TOML"));
    assert!(
        spec_err(&format!(
            "name = \"\"\nframe = \"ternary\"\n{LINE}{}{}",
            st("a", "-"),
            st("b", "+")
        ))
        .contains("non-empty")
    );
    // Raster shape errors.
    let raster = |cells: &str| {
        format!(
            "{head}[[state]]\nlabel = \"a\"\n[raster]\nwindow = [0.0, 1.0, 0.0, 1.0]\nnx = 2\nny = 1\ncells = {cells}\noutside = {{ rule = \"clamp\" }}\n"
        )
    };
    assert!(spec_err(&raster("[0]")).contains("expected nx·ny = 2"));
    assert!(spec_err(&raster("[0, 3]")).contains("not a state index"));
    // Regression (issue 17): a subnormal window passed `show` and panicked permute/compose
    // ("cannot sample empty range").
    let tiny = raster("[0, 0]").replace("[0.0, 1.0, 0.0, 1.0]", "[0.0, 1e-310, 0.0, 1.0]");
    assert!(
        spec_err(&tiny).contains("wide and high"),
        "{}",
        spec_err(&tiny)
    );
    // Files.
    assert!(matches!(
        Calculus::from_path(std::path::Path::new("/nonexistent/x.toml")),
        Err(QsrError::Io { .. })
    ));
    assert!(matches!(
        Calculus::resolve("no-such-calculus"),
        Err(QsrError::UnknownCalculus { .. })
    ));
}

#[test]
fn bad_inputs_get_typed_errors() {
    let edc = Calculus::builtin("edc").unwrap();
    let a = Point2::new(1.0, 1.0);
    assert!(matches!(
        edc.classify_triplet(a, a, Point2::new(0.0, 0.0)),
        Err(QsrError::DegenerateFrame { .. })
    ));
    assert!(matches!(
        edc.classify_triplet(a, Point2::new(2.0, 2.0), Point2::new(f64::NAN, 0.0)),
        Err(QsrError::NonFinite { .. })
    ));
    assert!(matches!(
        edc.classify_row(&[1.0, 2.0, 3.0]),
        Err(QsrError::Arity(_))
    ));
    assert!(matches!(
        edc.classify_oriented(a, 0.0, a),
        Err(QsrError::Arity(_))
    ));
    assert!(matches!(
        edc.state("21"),
        Err(QsrError::UnknownState { .. })
    ));
    assert!(matches!(
        "rotate".parse::<Permutation>(),
        Err(QsrError::UnknownOperation { .. })
    ));
    let mut out = vec![qsr_core::StateId(0); 2];
    let rows = [
        [0.0, 0.0, 0.0, 1.0, 1.0, 1.0],
        [5.0, 5.0, 5.0, 5.0, 1.0, 1.0],
    ];
    let err = edc.classify_triplets(&rows, &mut out).unwrap_err();
    assert!(format!("{err}").contains("triplet 1"), "{err}");
    assert!(matches!(
        edc.classify_triplets(&rows, &mut out[..1]),
        Err(QsrError::Arity(_))
    ));
    let star = Calculus::builtin("star-4").unwrap();
    assert!(matches!(
        star.permutation(Permutation::Inverse),
        Err(QsrError::Unsupported { .. })
    ));
    assert!(matches!(edc.merge_map(&star), Err(QsrError::Arity(_))));
    assert!(matches!(
        Calculus::builtin("star-5"),
        Err(QsrError::UnknownCalculus { .. })
    ));
}

#[test]
fn a_rasterised_edc_is_a_learned_calculus_that_matches_the_original() {
    let edc = Calculus::builtin("edc").unwrap();
    let cell = 0.01;
    let raster = edc
        .rasterise([-3.0, 3.0, -2.0, 3.0], 600, 500, OutsideRule::Clamp)
        .unwrap();
    assert_eq!(raster.labels(), edc.labels());
    // Classification: equal everywhere except within one cell diagonal of an EDC boundary,
    // including far outside the window (the clamp rule continues unbounded states).
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let mut disagree = 0;
    for _ in 0..200_000 {
        let p = if rng.random::<bool>() {
            Point2::new(rng.random_range(-3.0..3.0), rng.random_range(-2.0..3.0))
        } else {
            Point2::new(rng.random_range(-1e4..1e4), rng.random_range(-1e4..1e4))
        };
        if raster.classify_normalised(&p) != edc.classify_normalised(&p) {
            disagree += 1;
            let d = common::boundary_distance(&edc, &p);
            assert!(
                d <= cell * std::f64::consts::SQRT_2,
                "{p:?} is {d} from a boundary"
            );
        }
    }
    assert!(disagree < 2_000, "{disagree} disagreements");
    // Neighbours: the same graph.
    assert_eq!(raster.neighbours().edges(), edc.neighbours().edges());
    // The same through a JSON round trip (how SERGE will hand calculi over).
    let back = Calculus::from_json_str(&raster.spec().to_json_string().unwrap()).unwrap();
    assert_eq!(back.neighbours().edges(), edc.neighbours().edges());
}

/// `(missing, extra)`: entries of the original `a` absent from the raster's `b`, and entries
/// of `b` absent from `a`. Panics if an extra entry is not adjacent to an original one (a
/// raster may only blur boundaries).
fn table_difference(
    c: &Calculus,
    rows_a: &[Vec<qsr_core::StateId>],
    rows_b: &[Vec<qsr_core::StateId>],
    what: &str,
) -> (usize, usize) {
    let g = c.neighbours();
    let (mut missing, mut extra) = (0, 0);
    for (ra, rb) in rows_a.iter().zip(rows_b) {
        missing += ra.iter().filter(|t| !rb.contains(t)).count();
        for t in rb.iter().filter(|t| !ra.contains(t)) {
            extra += 1;
            assert!(
                ra.iter().any(|u| g.is_adjacent(*u, *t)),
                "{what}: {} is not next to {:?}",
                c.label(*t),
                ra
            );
        }
    }
    (missing, extra)
}

#[test]
fn a_rasterised_calculus_composes_and_permutes_like_the_original() {
    // A raster cannot reproduce a line's exact zero-set rule, so compare configurations in
    // general position. The double cross is exact on a raster whose grid lines fall on its
    // lines: every table must be equal. The EDC's circles become staircases of 0.01 cells,
    // which blurs the metric coincidences (|BC| = |AB|) its composition depends on: the
    // raster may add entries next to the original ones but must not lose any.
    let generic = qsr_core::ComposeOptions::generic();
    for (name, window, nx, ny, exact) in [
        ("double-cross", [-2.0, 2.0, -1.0, 2.0], 400, 300, true),
        ("edc", [-3.0, 3.0, -2.0, 3.0], 600, 500, false),
    ] {
        let orig = Calculus::builtin(name).unwrap();
        let raster = orig.rasterise(window, nx, ny, OutsideRule::Clamp).unwrap();
        let (a, b) = (
            &orig.compose_table_with(&generic).unwrap(),
            &raster.compose_table_with(&generic).unwrap(),
        );
        let rows = |t: &qsr_core::ComposeTable| -> Vec<Vec<qsr_core::StateId>> {
            orig.states()
                .flat_map(|r| orig.states().map(move |s| (r, s)))
                .map(|(r, s)| t.get(r, s).to_vec())
                .collect()
        };
        let (missing, extra) = table_difference(&orig, &rows(a), &rows(b), name);
        eprintln!(
            "{name}: compose {} vs {} entries: {missing} missing, {extra} extra",
            a.n_entries(),
            b.n_entries()
        );
        assert_eq!(
            missing, 0,
            "{name}: the raster's compose table lost entries"
        );
        assert!(!exact || extra == 0, "{name}: {extra} extra entries");
        for op in Permutation::ALL {
            let (pa, pb) = (
                orig.permutation_with(op, false).unwrap(),
                raster.permutation_with(op, false).unwrap(),
            );
            let (missing, extra) = table_difference(&orig, pa.rows(), pb.rows(), op.name());
            let total: usize = pa.rows().iter().map(Vec::len).sum();
            eprintln!("{name}: {op} {total} entries: {missing} missing, {extra} extra");
            assert_eq!(missing, 0, "{name} {op}");
            assert!(
                !exact || extra == 0,
                "{name} {op}: {extra} extra of {total}"
            );
        }
    }
}

/// TPCC's states are SparQ's sectors (Moratz & Ragni; SparQ's `qualify_tpcc`): the angle of
/// C about B measured from the direction A→B, counter-clockwise, in sectors of 45°, named by
/// side and nearer axis, and close/distant by |BC| against |AB|. Checked by geometry on random
/// configurations away from the boundaries, not by reading our spec back.
#[test]
fn tpcc_states_are_sparqs_sectors() {
    let tpcc = Calculus::builtin("tpcc").unwrap();
    assert_eq!(tpcc.n_states(), 16);
    let mut rng = ChaCha8Rng::seed_from_u64(12);
    let sectors = ["lf", "fl", "bl", "lb", "rb", "br", "fr", "rf"];
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..20_000 {
        let p: [f64; 6] = std::array::from_fn(|_| rng.random_range(-10.0..10.0));
        let (ex, ey) = (p[2] - p[0], p[3] - p[1]);
        let (dx, dy) = (p[4] - p[2], p[5] - p[3]);
        let theta = (ex * dy - ey * dx).atan2(ex * dx + ey * dy); // (−π, π], left positive
        let eighth = theta / std::f64::consts::FRAC_PI_4;
        let ratio = (dx * dx + dy * dy).sqrt() / (ex * ex + ey * ey).sqrt();
        if (eighth - eighth.round()).abs() < 1e-6 || (ratio - 1.0).abs() < 1e-6 {
            continue; // on a sector boundary or the circle
        }
        let k = if eighth >= 0.0 {
            eighth.floor() as usize
        } else {
            (8.0 + eighth.floor()) as usize
        };
        let sector = sectors[k];
        let want = format!("{}{sector}", if ratio < 1.0 { 'c' } else { 'd' });
        let got = tpcc.label(tpcc.classify_row(&p).unwrap());
        assert_eq!(got, want, "at {p:?} (θ = {theta:.4})");
        seen.insert(want);
    }
    assert_eq!(seen.len(), 16, "every state met");
    // TPCC refines the single cross (same line AB and perpendicular at B).
    let scc = Calculus::builtin("single-cross").unwrap();
    let m = tpcc.merge_map(&scc).unwrap();
    assert_eq!(
        scc.label(m.as_slice()[tpcc.state("cfl").unwrap().index()]),
        "left-front"
    );
}
