"""qrm.serge from Python: same map as `qrm serge run`, learned calculi, errors."""
import json
import subprocess

import numpy as np
import pytest

import qrm

BELIEFS = [
    {"mean": [0.0, 0.0], "cov": [[0.05, 0.0], [0.0, 0.05]]},
    {"mean": [6.0, 0.0], "cov": np.array([[0.05, 0.01], [0.01, 0.05]])},
    {"samples": np.array([[6.2, 0.3], [6.1, 0.2], [5.9, 0.4], [6.3, 0.1]])},
    {"mean": [0.0, 6.0], "cov": [[0.1, 0.0], [0.0, 0.1]]},
]


def test_python_and_cli_give_the_same_map(qrm_bin, tmp_path):
    m = qrm.serge(BELIEFS, 3, sigma=0.0, trials=40, grid=80, seed=4)
    assert m.n_regions == 3
    assert m.assignment[1] == m.assignment[2] != m.assignment[0]
    doc = {"beliefs": [{k: (v.tolist() if hasattr(v, "tolist") else v) for k, v in b.items()} for b in BELIEFS]}
    (tmp_path / "b.json").write_text(json.dumps(doc))
    subprocess.run([qrm_bin, "serge", "run", "--beliefs", str(tmp_path / "b.json"), "--mu", "3", "--sigma", "0",
                    "--trials", "40", "--grid", "80", "--seed", "4", "--out", str(tmp_path / "o")],
                   check=True, capture_output=True)
    cli = json.loads((tmp_path / "o" / "map.json").read_text())
    assert cli["assignment"] == m.assignment
    assert cli["log_saliency"] == pytest.approx(m.log_saliency, abs=1e-12)
    cells = m.cells()
    assert cells.shape == (80, 80)
    assert set(np.unique(cells)) == {0, 1, 2}
    # the region of each belief's mean is its assigned region
    means = np.array([[0.0, 0.0], [6.0, 0.0], [6.1, 0.25], [0.0, 6.0]])
    assert m.region_of(means).tolist() == m.assignment
    assert all(0.0 <= s <= 1.0 for s in m.saliency)
    assert m.polygons(0) and m.adjacency()


def test_a_learned_calculus_classifies_and_composes():
    rng = np.random.default_rng(1)
    # beliefs of F in a normalised frame: left, right and far ahead
    beliefs = [{"samples": rng.normal(c, 0.15, size=(500, 2))} for c in ([-1.0, 0.5], [1.0, 0.5], [0.0, 2.5])]
    m = qrm.serge(beliefs, 3, sigma=0.0, trials=30, grid=24, window=(-2.0, 2.0, -1.0, 3.0), seed=2)
    calc = m.to_calculus("toy")
    assert calc.n_states == 3
    pts = np.array([[0, 0, 0, 1, -1.0, 0.5], [0, 0, 0, 1, 1.0, 0.5], [0, 0, 0, 1, 0.0, 2.5]])
    assert calc.classify(pts).tolist() == [m.assignment[0], m.assignment[1], m.assignment[2]]
    cells = qrm.compose_cells(calc)
    sampled = calc.compose()
    for r in sampled:
        for s in sampled[r]:
            assert set(sampled[r][s]) <= set(cells[r][s])


def test_cross_validation_records():
    recs = qrm.serge_cross_validate("well-separated", quick=True, seed=0)
    assert recs and all(r["n_regions"] == r["mu"] for r in recs)
    assert all(r["errors"] == 0 for r in recs)


@pytest.mark.parametrize(
    "beliefs,mu,kw",
    [
        ([], 1, {}),
        ([{"mean": [0, 0], "cov": [[1, 1], [1, 1]]}], 1, {}),
        ([{"mean": [0, 0], "cov": [[1, 0], [0, 1]]}], 2, {}),
        ([{"mean": [0, 0], "cov": [[1, 0], [0, 1]]}], 1, {"sigma": -1.0}),
        ([{"mean": [float("nan"), 0], "cov": [[1, 0], [0, 1]]}], 1, {}),
        ([{"mean": [0, 0], "covariance": [[1, 0], [0, 1]]}], 1, {}),
    ],
)
def test_bad_input_raises_invalid_input(beliefs, mu, kw):
    with pytest.raises(qrm.InvalidInput):
        qrm.serge(beliefs, mu, **kw)


def test_malformed_json_is_a_format_error():
    with pytest.raises(qrm.FormatError):
        qrm.serge('{"beliefs": [', 1)
    with pytest.raises(qrm.InvalidInput):
        qrm.compose_cells(qrm.Calculus.builtin("edc"))
