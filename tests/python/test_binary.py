"""Binary calculi from Python: exact OPRA tables, classification, closure of pair networks."""
import math

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
