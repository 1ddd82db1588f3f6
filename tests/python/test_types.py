"""Study results are typed (issue 19: every study result was `Dict[str, Any]`), and the types
say what the dicts really hold: each result is checked, key by key and recursively, against
its `qrm.types` TypedDict, and `mypy --strict` rejects a misspelt key."""
from __future__ import annotations

import subprocess
import sys
import typing
from typing import Any, Dict, List, Literal, Union

import numpy as np
import pytest

import qrm
from qrm import types as qt


def conforms(value: Any, tp: Any, path: str = "result") -> None:
    """Raises AssertionError naming the first place where `value` is not a `tp`."""
    origin = typing.get_origin(tp)
    args = typing.get_args(tp)
    if tp is Any:
        return
    if typing.is_typeddict(tp):
        assert isinstance(value, dict), f"{path}: {type(value).__name__}, not a dict"
        hints = typing.get_type_hints(tp)
        missing = tp.__required_keys__ - value.keys()
        extra = value.keys() - hints.keys()
        assert not missing, f"{path}: keys {sorted(missing)} missing"
        assert not extra, f"{path}: keys {sorted(extra)} not in {tp.__name__}"
        for k, v in value.items():
            conforms(v, hints[k], f"{path}[{k!r}]")
    elif origin is Union:
        errors = []
        for a in args:
            try:
                conforms(value, a, path)
                return
            except AssertionError as e:
                errors.append(str(e))
        raise AssertionError(" / ".join(errors))
    elif origin is Literal:
        assert value in args, f"{path}: {value!r} not one of {args}"
    elif origin in (list, List):
        assert isinstance(value, list), f"{path}: {type(value).__name__}, not a list"
        for i, v in enumerate(value):
            conforms(v, args[0], f"{path}[{i}]")
    elif origin is np.ndarray:
        assert isinstance(value, np.ndarray), f"{path}: {type(value).__name__}, not an ndarray"
    elif origin is tuple:
        assert isinstance(value, tuple), f"{path}: {type(value).__name__}, not a tuple"
        assert len(value) == len(args), f"{path}: {len(value)} items, not {len(args)}"
        for i, (v, a) in enumerate(zip(value, args)):
            conforms(v, a, f"{path}[{i}]")
    elif origin in (dict, Dict):
        assert isinstance(value, dict), f"{path}: {type(value).__name__}, not a dict"
        for k, v in value.items():
            conforms(k, args[0], f"{path} key")
            conforms(v, args[1], f"{path}[{k!r}]")
    elif tp is type(None):
        assert value is None, f"{path}: {value!r}, not None"
    elif tp is float:
        assert isinstance(value, (int, float)) and not isinstance(value, bool), f"{path}: {value!r}"
    elif tp is int:
        assert isinstance(value, int) and not isinstance(value, bool), f"{path}: {value!r}"
    else:
        assert isinstance(value, tp), f"{path}: {value!r} is not {tp}"


def test_the_checker_itself_catches_a_wrong_shape():
    with pytest.raises(AssertionError, match="missing"):
        conforms({"mean": 1.0}, qt.MeanStd)
    with pytest.raises(AssertionError, match="not in"):
        conforms({"mean": 1.0, "std": 0.0, "n": 3}, qt.MeanStd)
    with pytest.raises(AssertionError, match="not one of"):
        conforms("lost", qt.NavFailure)


def test_the_q_link_study_is_a_qlink_study():
    res = qrm.qlink_study("sensor-range", quick=True, pairs=20, seed=3)
    conforms(res, qt.QlinkStudy)
    # a failure among the records, so the Literal is exercised beside None
    assert any(r["failure"] for r in res["records"])


def test_the_field_experiment_is_a_field_experiment():
    conforms(qrm.qlink_field(quick=True, trials=3, seed=1), qt.FieldExperiment)


def test_a_navigation_is_a_nav_outcome():
    pos = {10 * i + j: (6.0 * i + 0.7 * j * j, 6.0 * j + 0.5 * i * i) for i in range(5) for j in range(5)}
    out = qrm.navigate(pos, 0, 44, calculus="edc", range=10.0)
    conforms(out, qt.NavOutcome)
    assert out["transitions"], "a navigation with transitions, so their shape is checked"


def test_the_monte_carlo_study_is_typed_through_shards_and_aggregate():
    cfg = qrm.monte_carlo_config(quick=True, trials=2)
    conforms(cfg, qt.MonteCarloConfig)
    shard = qrm.monte_carlo_shard(cfg, 0, 2)
    conforms(shard, List[qt.MonteCarloRecord])
    conforms(qrm.monte_carlo_aggregate(cfg, [shard]), qt.MonteCarloResult)


def test_the_cross_validation_records_are_cv_records():
    conforms(qrm.serge_cross_validate("well-separated", quick=True, seed=0), List[qt.CvRecord])


def test_neighbours_inference_and_the_consistency_check_are_typed():
    edc = qrm.Calculus.builtin("edc")
    conforms(edc.neighbours(), qt.Neighbours)
    conforms(qrm.BinaryCalculus.builtin("opra-2").neighbours(), qt.Neighbours)
    m = qrm.Pqrm(edc, samples=200, seed=1)
    for f in qrm.sim.run("hallway", 1)[:30]:
        m.update(f["t"], f["ids"], f["xy"], f["cov"])
    check = m.check()
    conforms(check, qt.ConsistencyCheck)
    assert check["flagged"], "flagged entries, so their shape is checked"
    conforms(m.infer(m.sets()[0]), qt.Inference)


def test_mypy_strict_rejects_a_misspelt_result_key(tmp_path):
    good = tmp_path / "good.py"
    good.write_text(
        "import qrm\n"
        "res = qrm.qlink_study('sensor-range', pairs=3)\n"
        "rate: float = res['table'][0]['failure_rate']\n"
        "out = qrm.navigate({1: (0.0, 0.0)}, 1, 1, calculus='edc')\n"
        "first: int = out['transitions'][0]['from']\n"
        "cfg = qrm.monte_carlo_config(quick=True)\n"
        "sigmas: list[float] = cfg['sigmas']\n"
    )
    bad = tmp_path / "bad.py"
    bad.write_text("import qrm\nres = qrm.qlink_study('sensor-range', pairs=3)\nrate = res['table'][0]['failure_rat']\n")
    run = lambda f: subprocess.run(  # noqa: E731
        [sys.executable, "-m", "mypy", "--strict", "--no-incremental", str(f)], capture_output=True, text=True
    )
    ok = run(good)
    assert ok.returncode == 0, ok.stdout + ok.stderr
    ko = run(bad)
    assert ko.returncode != 0 and "failure_rat" in ko.stdout, ko.stdout
