"""Q-Link from Python: navigation on exact and probabilistic maps, the study, errors."""
import numpy as np
import pytest

import qrm

POSTS = {1: (0.0, 0.0), 2: (6.0, 3.0), 3: (3.0, 8.0), 4: (11.0, 7.0), 5: (14.0, 1.0),
         6: (18.0, 9.0), 7: (23.0, 4.0), 8: (26.0, 11.0), 9: (30.0, 2.0)}


@pytest.mark.parametrize("controller", ["arc", "closest-point", "safe-search", "direct"])
def test_navigation_on_an_exact_map_reaches_the_goal(controller):
    out = qrm.navigate(POSTS, 1, 9, calculus="quadrant", range=12.0, controller=controller)
    assert out["success"], out["failure"]
    assert out["plan_len"] >= 1
    assert out["transit_length"] <= out["bound"]
    assert len(out["trajectory"]) > 1


def test_navigation_on_a_pqrm_built_from_python():
    calc = qrm.Calculus.builtin("quadrant")
    m = qrm.Pqrm(calc, samples=200, seed=1)
    rng = np.random.default_rng(0)
    ids = np.array(sorted(POSTS))
    xy = np.array([POSTS[i] for i in ids])
    # a robot at a few places sees the posts within 12 m (world frame, small noise)
    for t, (px, py) in enumerate([(2, 2), (8, 5), (14, 4), (20, 6), (27, 5)]):
        near = np.hypot(xy[:, 0] - px, xy[:, 1] - py) <= 12.0
        if near.sum() < 3:
            continue
        obs = xy[near] - [px, py] + rng.normal(0, 0.1, size=(near.sum(), 2))
        m.update(float(t), ids[near], obs, np.tile([0.01, 0.0, 0.01], (near.sum(), 1)))
    out = qrm.navigate(POSTS, 1, 9, pqrm=m, range=12.0)
    assert out["success"], out


def test_the_quick_study_keeps_proposition_1():
    # Proposition 1 is about a robot that sees and drives exactly
    res = qrm.qlink_study("sensor-range", quick=True, pairs=30, seed=3, exact_robot=True)
    rows = {r["value"]: r for r in res["table"]}
    assert rows[1.0]["failures"] == 0
    assert len(res["records"]) == 30 * 5


def test_the_erring_robot_is_the_default_and_its_seed_matters():
    a = qrm.navigate(POSTS, 1, 9, calculus="quadrant", range=12.0)
    b = qrm.navigate(POSTS, 1, 9, calculus="quadrant", range=12.0, seed=1)
    x = qrm.navigate(POSTS, 1, 9, calculus="quadrant", range=12.0, exact_robot=True)
    assert a == qrm.navigate(POSTS, 1, 9, calculus="quadrant", range=12.0)
    assert a["trajectory"] != b["trajectory"] and a["trajectory"] != x["trajectory"]


def test_bad_input():
    with pytest.raises(qrm.InvalidInput):
        qrm.navigate(POSTS, 1, 1, calculus="quadrant")
    with pytest.raises(qrm.InvalidInput):
        qrm.navigate(POSTS, 1, 99, calculus="quadrant", range=12.0)
    with pytest.raises(qrm.InvalidInput):
        qrm.navigate(POSTS, 1, 9)
    with pytest.raises(qrm.InvalidInput):
        qrm.navigate(POSTS, 1, 9, calculus="quadrant", controller="teleport")
    with pytest.raises(qrm.UnsupportedError):
        qrm.navigate(POSTS, 1, 9, calculus="edc", range=12.0, controller="closest-point")
    with pytest.raises(qrm.InvalidInput):
        qrm.qlink_study("nope", quick=True)


def test_field_experiment_in_one_world():
    res = qrm.qlink_field(quick=True, trials=3, seed=1)
    assert res["mapping"]["wall_elements"] > 0
    assert res["draws"]["kept"] == 3
    names = [v["variant"] for v in res["variants"]]
    assert names == ["thesis", "safe-search", "visibility-costs", "safe-search+visibility-costs"]
    for v in res["variants"]:
        assert 0.0 <= v["success_rate"] <= 1.0
        assert v["trials"] == 3
    assert len(res["trials"]) == 4 * 3
    # the JSON names, as qrm.types.FieldResult declares them (files write "+aliasing")
    assert {t["result"] for t in res["trials"]} <= {
        "success", "perceptual-aliasing", "insufficient-features",
        "insufficient-features-and-aliasing", "no-path",
    }
    # issue 18: both distance bounds per run, at the lidar's and the effective range
    for t in res["trials"]:
        lidar, effective = t["bounds"]
        assert lidar["range"] > effective["range"] > 0
        assert lidar["length"] == t["transit_length"]
        assert set(lidar["assumptions"]) == {"disc", "circle", "pairwise", "sight_lines", "straight"}
        assert lidar["assumptions"]["straight"] is False
    with pytest.raises(qrm.InvalidInput):
        qrm.qlink_field(trials=0)
