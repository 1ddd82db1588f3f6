"""What notebook, data-frame, multiprocessing and Ray users need (issue 19): objects that
pickle, pictures in a notebook, data frames."""
import multiprocessing
import pickle

import numpy as np
import pytest

import qrm

ROWS = np.array([[0.0, 0.0, 0.0, 10.0, -1.0, 5.0], [0.0, 0.0, 10.0, 0.0, 5.0, 0.5]])


def small_map(calculus="edc"):
    m = qrm.Pqrm(qrm.Calculus.builtin(calculus), samples=100, seed=3)
    for f in qrm.sim.run("hallway", 1)[:20]:
        m.update(f["t"], f["ids"], f["xy"], f["cov"])
    return m


@pytest.mark.parametrize("name", ["edc", "double-cross", "left-right"])
def test_a_calculus_pickles_to_an_equal_one(name):
    c = qrm.Calculus.builtin(name)
    d = pickle.loads(pickle.dumps(c))
    assert d.name == c.name and d.labels == c.labels
    assert list(d.classify(ROWS)) == list(c.classify(ROWS))
    assert d.compose() == c.compose()


def test_a_spec_calculus_pickles_too():
    spec = qrm.Calculus.builtin("quadrant").spec_toml().replace('name = "quadrant"', 'name = "my-quadrant"')
    c = qrm.Calculus.from_spec_text(spec)
    d = pickle.loads(pickle.dumps(c))
    assert d.name == "my-quadrant" and list(d.classify(ROWS)) == list(c.classify(ROWS))


def test_a_binary_calculus_pickles():
    b = qrm.BinaryCalculus.builtin("opra-2")
    assert pickle.loads(pickle.dumps(b)).converse() == b.converse()


def test_a_map_pickles_with_every_belief():
    m = small_map()
    n = pickle.loads(pickle.dumps(m))
    assert len(n) == len(m) > 0 and n.sets() == m.sets()
    for s in m.sets()[:50]:
        assert np.allclose(n.belief(s), m.belief(s), atol=1e-12)
    # the copy goes on mapping like the original
    f = qrm.sim.run("hallway", 1)[20]
    m.update(f["t"], f["ids"], f["xy"], f["cov"])
    n.update(f["t"], f["ids"], f["xy"], f["cov"])
    assert all(np.allclose(n.belief(s), m.belief(s), atol=1e-12) for s in m.sets()[:50])


def test_a_map_in_the_binary_format_is_the_same_map(tmp_path):
    m = small_map()
    data = m.to_bytes()
    assert data[:8] == b"QRM-PQRM"
    n = qrm.Pqrm.from_bytes(data)
    assert n.sets() == m.sets()
    m.save(str(tmp_path / "map.pqrm"))
    m.save(str(tmp_path / "map.json"))
    b, j = qrm.Pqrm.load(str(tmp_path / "map.pqrm")), qrm.Pqrm.load(str(tmp_path / "map.json"))
    assert (tmp_path / "map.pqrm").read_bytes()[:8] == b"QRM-PQRM"
    assert (tmp_path / "map.pqrm").stat().st_size < (tmp_path / "map.json").stat().st_size
    for s in m.sets():
        assert np.array_equal(n.belief(s), m.belief(s))
        assert np.array_equal(b.belief(s), j.belief(s))
        assert abs(m.belief(s).sum() - 1.0) < 1e-12
    # a damaged map is refused with the field named, never half-read
    broken = bytearray(data)
    broken[len(broken) // 2] ^= 0x10
    with pytest.raises(qrm.FormatError, match="checksum|CRC"):
        qrm.Pqrm.from_bytes(bytes(broken))
    with pytest.raises(qrm.FormatError):
        qrm.Pqrm.from_bytes(data[: len(data) - 3])


def test_a_salient_region_map_pickles():
    beliefs = [{"mean": [float(i % 3), float(i // 3)], "cov": [[0.05, 0.0], [0.0, 0.05]]} for i in range(6)]
    m = qrm.serge(beliefs, 3, sigma=0.0, trials=20, grid=24, seed=1)
    n = pickle.loads(pickle.dumps(m))
    assert (n.n_regions, n.assignment, n.initial_regions, n.window) == (m.n_regions, m.assignment, m.initial_regions, m.window)
    assert np.array_equal(n.cells(), m.cells())
    pts = np.array([[0.1, 0.2], [1.9, 1.1]])
    assert list(n.region_of(pts)) == list(m.region_of(pts))


def _entropy_in_a_child(m):
    return m.entropy()


def test_maps_and_calculi_cross_process_boundaries():
    """A spawn pool pickles arguments and results (as Ray does)."""
    m = small_map("double-cross")
    with multiprocessing.get_context("spawn").Pool(1) as pool:
        assert pool.apply(_entropy_in_a_child, (m,)) == pytest.approx(m.entropy(), abs=1e-12)
        back = pool.apply(pickle.loads, (pickle.dumps(qrm.Calculus.builtin("edc")),))
    assert back.n_states == 20


def test_notebooks_draw_calculi_and_maps():
    for obj in (qrm.Calculus.builtin("edc"), qrm.BinaryCalculus.builtin("opra-1"), small_map()):
        svg = obj._repr_svg_()
        assert svg.lstrip().startswith("<svg") and svg.rstrip().endswith("</svg>"), type(obj)
    assert "sets" in small_map()._repr_svg_()


def test_columns_describe_every_set():
    m = small_map()
    cols = m.columns()
    assert set(cols) == {"a", "b", "c", "ml_state", "p_ml", "entropy", "updates"}
    assert all(len(v) == len(m) for v in cols.values())
    s = (int(cols["a"][0]), int(cols["b"][0]), int(cols["c"][0]))
    p = m.belief(s)
    assert int(cols["ml_state"][0]) == int(np.argmax(p)) and cols["p_ml"][0] == pytest.approx(p.max())
    assert ((cols["p_ml"] > 0) & (cols["p_ml"] <= 1)).all() and (cols["updates"] >= 1).all()


def test_to_pandas_makes_data_frames_or_says_how():
    try:
        import pandas  # noqa: F401
    except ImportError:
        with pytest.raises(ImportError, match="pip install pandas"):
            qrm.to_pandas([{"a": 1}])
        return
    m = small_map()
    df = m.to_pandas()
    assert len(df) == len(m) and list(df.columns)[:3] == ["a", "b", "c"]
    assert qrm.to_pandas(m).equals(df)
    records = [{"trial": 0, "err": 0.1}, {"trial": 1, "err": 0.2}]
    assert qrm.to_pandas(records)["err"].tolist() == [0.1, 0.2]
    assert qrm.to_pandas({"x": [1, 2]})["x"].tolist() == [1, 2]
