"""Binary calculi from Python: exact OPRA tables, classification, closure of pair networks."""
import math
import pickle

import numpy as np
import pytest

import qrm


def test_opra_sizes_and_converse():
    for m in (1, 2, 3, 4):
        c = qrm.BinaryCalculus.builtin(f"opra-{m}")
        assert c.n_states == 16 * m * m + 4 * m
    c = qrm.BinaryCalculus.builtin("opra-1")
    conv = c.converse()
    assert conv["1_3"] == ["3_1"]
    assert all(conv[conv[r][0]] == [r] for r in c.labels)


def test_composition_of_a_convoy_is_a_convoy():
    c = qrm.BinaryCalculus.builtin("opra-2")
    table = c.compose()
    assert table["0_4"]["0_4"] == ["0_4"]
    assert set(table["s_0"]["1_5"]) == {"1_5"}


def test_classify_agrees_with_the_composition_table():
    rng = np.random.default_rng(2)
    c = qrm.BinaryCalculus.builtin("opra-1")
    table = c.compose()
    labels = c.labels
    for _ in range(200):
        p = rng.uniform(-3, 3, size=(3, 2))
        h = rng.uniform(0, 2 * math.pi, size=3)

        def rel(i, j):
            row = np.array([[p[i, 0], p[i, 1], h[i], p[j, 0], p[j, 1], h[j]]])
            return labels[int(c.classify(row)[0])]

        assert rel(0, 2) in table[rel(0, 1)][rel(1, 2)]


def test_bad_rows_are_value_errors():
    c = qrm.BinaryCalculus.builtin("opra-1")
    with pytest.raises(ValueError):
        c.classify(np.zeros((2, 5)))
    with pytest.raises(ValueError, match="row 1"):
        c.classify(np.array([[0, 0, 0, 1, 0, 0], [0, 0, math.nan, 1, 0, 0]], dtype=float))
    with pytest.raises(qrm.SpecError):
        qrm.BinaryCalculus.builtin("opra-0")


def test_close_binary_infers_and_detects():
    c = qrm.BinaryCalculus.builtin("opra-1")
    r = qrm.reason.close_binary(c, [("A", "B", ["0_0"]), ("B", "C", ["0_0"])])
    assert r.consistent
    assert r.constraints[("A", "C")] == ["0_2", "2_0", "s_0"]
    bad = qrm.reason.close_binary(
        c, [("A", "B", ["0_0"]), ("B", "C", ["0_0"]), ("A", "C", ["1_1", "1_3"])]
    )
    assert not bad.consistent
    assert "A" in bad.explanation
    with pytest.raises(ValueError, match="no relation `9_9`"):
        qrm.reason.close_binary(c, [("A", "B", ["9_9"])])


def test_star_render_is_svg():
    svg = qrm.BinaryCalculus.builtin("star-8").render_svg(width=200)
    assert svg.startswith("<svg") and "front" in svg


POINT_CONV = "< :: >\n= :: =\n> :: <\n"
POINT_COMP = (
    "< : < :: ( < )\n< : = :: ( < )\n< : > :: ( < = > )\n"
    "= : < :: ( < )\n= : = :: ( = )\n= : > :: ( > )\n"
    "> : < :: ( < = > )\n> : = :: ( > )\n> : > :: ( > )\n"
)


def _gqr_point_dir(tmp_path):
    (tmp_path / "point" / "calculus").mkdir(parents=True)
    (tmp_path / "point" / "calculus" / "point.conv").write_text(POINT_CONV)
    (tmp_path / "point" / "calculus" / "point.comp").write_text(POINT_COMP)
    spec = tmp_path / "point.spec"
    spec.write_text(
        "comp_table_file point/calculus/point.comp\nconverse_file point/calculus/point.conv\n"
        "identity =\ncalculus_size 3\n"
    )
    return spec


def test_algebra_from_gqr_closes_solves_and_reads_csp(tmp_path):
    pa = qrm.reason.Algebra.from_gqr(_gqr_point_dir(tmp_path))
    assert (pa.name, pa.labels, pa.identity) == ("point", ["<", "=", ">"], "=")
    assert all(holds for _, holds, _ in pa.laws())
    r = qrm.reason.close_binary(pa, [("a", "b", ["<"]), ("b", "c", ["<", "="])])
    assert r.consistent and r.constraints[("a", "c")] == ["<"]
    cyc = [("a", "b", ["<"]), ("b", "c", ["<"]), ("c", "a", ["<", "="])]
    assert not qrm.reason.close_binary(pa, cyc).consistent
    s = qrm.reason.consistency(pa, [("a", "b", ["<", "="]), ("b", "c", ["<", "="]), ("a", "c", ["=", ">"])])
    assert s.status == "consistent"
    assert s.constraints == {("a", "b"): ["="], ("a", "c"): ["="], ("b", "c"): ["="]}
    assert qrm.reason.consistency(pa, cyc).status == "inconsistent"
    nets = qrm.reason.read_csp(pa, "1 #one\n0 1 ( < = )\n.\n2 #two\n0 2 ( > )\n.\n")
    assert nets == [("one", [("0", "1", ["<", "="])]), ("two", [("0", "2", [">"])])]
    # A loaded algebra pickles as its tables.
    again = pickle.loads(pickle.dumps(pa))
    assert again.labels == pa.labels and again.to_gqr_tables() == pa.to_gqr_tables()


def test_consistency_splits_into_a_tractable_subclass_given_as_sets_or_gqrs_file(tmp_path):
    pa = qrm.reason.Algebra.from_gqr(_gqr_point_dir(tmp_path))
    convex = [["<"], ["="], [">"], ["<", "="], ["=", ">"], ["<", "=", ">"]]
    net = [("a", "b", ["<", ">"]), ("b", "c", ["<", "="])]
    s = qrm.reason.consistency(pa, net, split=convex)
    # `≠` is not convex: split into `<`; `≤` is, and stays as it is.
    assert s.status == "consistent"
    assert s.constraints == {("a", "b"): ["<"], ("a", "c"): ["<"], ("b", "c"): ["<", "="]}
    assert qrm.reason.consistency(pa, net).constraints[("b", "c")] in (["<"], ["="])
    # GQR's cover-set file (what `gqr consistency -c convex` would read), and without restarts.
    cover = tmp_path / "point" / "calculus" / "convexalg"
    cover.write_text("".join(f"( {' '.join(m)} )\n" for m in convex))
    t = qrm.reason.consistency(pa, net, split=cover, restarts=False)
    assert t.constraints == s.constraints
    cyc = [("a", "b", ["<"]), ("b", "c", ["<"]), ("c", "a", ["<", ">"])]
    assert qrm.reason.consistency(pa, cyc, split=convex).status == "consistent"
    assert qrm.reason.consistency(pa, cyc + [("c", "a", ["<"])], split=convex).status == "inconsistent"
    with pytest.raises(qrm.SpecError, match="base relation `=` is not a member on its own"):
        qrm.reason.consistency(pa, net, split=[["<"], [">"]])
    with pytest.raises(qrm.SpecError, match="line 1.*no relation `lt`"):
        qrm.reason.consistency(pa, net, split=[["lt"]])


def test_algebra_errors_are_typed_and_name_the_place(tmp_path):
    spec = _gqr_point_dir(tmp_path)
    (tmp_path / "point" / "calculus" / "point.comp").write_text(POINT_COMP.replace("( = )", "( == )"))
    with pytest.raises(qrm.SpecError, match="line 5.*`==` is not a base relation"):
        qrm.reason.Algebra.from_gqr(spec)
    with pytest.raises(qrm.IoError):
        qrm.reason.Algebra.from_gqr(tmp_path / "missing.spec")
    pa = qrm.reason.Algebra.from_gqr_tables("point", POINT_CONV, POINT_COMP, "=")
    with pytest.raises(qrm.FormatError, match="line 2"):
        qrm.reason.read_csp(pa, "1 #x\n0 5 ( < )\n")
    with pytest.raises(qrm.InvalidInput, match="BinaryCalculus or a BinaryAlgebra"):
        qrm.reason.close_binary("point", [])  # type: ignore[arg-type]


def test_a_derived_calculus_is_an_algebra_too():
    opra = qrm.BinaryCalculus.builtin("opra-1")
    alg = qrm.reason.Algebra.of(opra)
    laws = dict((law, holds) for law, holds, _ in alg.laws())
    assert laws["composition is associative ((r∘s)∘t = r∘(s∘t))"] is False
    conv, comp, weights, spec = alg.to_gqr_tables()
    assert "0_0 : 0_0 :: (" in comp and "identity s_0" in spec
    same = qrm.reason.close_binary(alg, [("A", "B", ["0_0"]), ("B", "C", ["0_0"])])
    assert same.constraints[("A", "C")] == ["0_2", "2_0", "s_0"]
    budget = qrm.reason.consistency(opra, [("A", "B", ["0_0", "1_1"]), ("B", "C", ["0_0", "1_3"])], max_nodes=1)
    assert budget.status == "unknown"
