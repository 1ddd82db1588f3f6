"""Qualitative reasoning from Python: closure, scenarios, map inference and the map check."""
import numpy as np
import pytest

import qrm


def test_close_narrows_and_keeps_every_ordered_triplet():
    dc = qrm.Calculus.builtin("double-cross")
    r = qrm.reason.close(dc, [("A", "B", "C", ["left-front"]), ("B", "C", "D", ["left-front"])])
    assert r.consistent and r.explanation is None
    assert len(r.constraints) == 24
    assert r.constraints[("A", "B", "D")] == ["left-front", "left-middle", "left-back"]


def test_close_explains_a_contradiction():
    lr = qrm.Calculus.builtin("left-right")
    r = qrm.reason.close(lr, [("A", "B", "C", ["left"]), ("B", "A", "C", ["left"])])
    assert not r.consistent
    assert r.explanation is not None and "became empty" in r.explanation
    s = qrm.reason.scenario(lr, [("A", "B", "C", ["left"]), ("B", "A", "C", ["left"])])
    assert not s.consistent and s.constraints == {}


def test_scenario_is_atomic_and_refines_the_input():
    dc = qrm.Calculus.builtin("double-cross")
    net = [("A", "B", "C", ["left-front", "right-back"]), ("A", "B", "D", ["left-back"])]
    s = qrm.reason.scenario(dc, net)
    assert s.consistent
    assert all(len(v) == 1 for v in s.constraints.values())
    assert s.constraints[("A", "B", "C")][0] in ("left-front", "right-back")


def test_bad_networks_raise_catchable_errors():
    dc = qrm.Calculus.builtin("double-cross")
    with pytest.raises(qrm.FormatError, match="sideways"):
        qrm.reason.close(dc, [("A", "B", "C", ["sideways"])])
    with pytest.raises(ValueError):
        qrm.reason.close(dc, [("A", "A", "C", ["left-front"])])
    with pytest.raises(qrm.UnsupportedError):
        qrm.reason.close(qrm.Calculus.builtin("star-4"), [])


def _two_views_map() -> qrm.Pqrm:
    """Eight landmarks; two stops see overlapping halves, so {1,2,8} is never seen."""
    # No triplet within 1 % (relative) of a double-cross line: the ML states are the truth.
    pts = {1: (-0.22, -0.44), 2: (3.35, 1.49), 3: (0.59, 4.3), 4: (4.91, 4.65),
           5: (7.79, 2.27), 6: (9.37, 5.54), 7: (12.11, 0.54), 8: (13.22, 4.83)}
    m = qrm.Pqrm(qrm.Calculus.builtin("double-cross"), samples=200, seed=2)
    for t, ids in enumerate([[1, 2, 3, 4, 5], [3, 4, 5, 6, 7, 8]] * 2):
        xy = np.array([pts[i] for i in ids])
        m.update(float(t), np.array(ids), xy, np.array([[1e-6, 0.0, 1e-6]] * len(ids)))
    return m


def test_infer_predicts_a_set_never_seen_together():
    m = _two_views_map()
    assert m.belief((1, 2, 8)) is None
    r = m.infer((1, 2, 8), rounds=3)
    p = r["p"]
    assert isinstance(p, np.ndarray) and abs(p.sum() - 1.0) < 1e-9
    assert r["round"] >= 1 and r["paths"] >= 1
    # 8 is right of 1→2 and ahead of 2.
    assert m.calculus.labels[int(np.argmax(p))] == "right-front"
    with pytest.raises(ValueError):
        m.infer((1, 2, 8), fusion="averaging")
    # the composition shares: learned (default) and uniform both distributions; a typo refused
    u = m.infer((1, 2, 8), rounds=3, composition="uniform")
    assert abs(u["p"].sum() - 1.0) < 1e-9
    assert u["composition"] == "uniform" and u["base_rate"] is False
    assert r["composition"] == "learned" and isinstance(r["base_rate"], bool)
    with pytest.raises(ValueError, match="composition"):
        m.infer((1, 2, 8), composition="even")


def test_check_of_a_clean_map_flags_nothing():
    c = _two_views_map().check()
    assert c["consistent"] is True
    assert c["flagged"] == []
