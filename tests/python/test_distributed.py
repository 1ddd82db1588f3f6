"""`qrm.distributed`: any study fans out shard by shard and merges into exactly the local run
(issue 14 §3) — on a process pool always, and on a local Ray cluster (`ray.init(num_cpus=2)`)
where Ray is installed (scripts/test installs it and sets QRM_REQUIRE_RAY=1, so there a
missing Ray fails instead of skipping)."""
from __future__ import annotations

import json
import os

import pytest

import qrm


def mc_config() -> dict:
    cfg = qrm.studies.config("monte-carlo", seed=3)  # the quick config
    cfg.update(trials=6, samples=60)
    return cfg


def t41_config() -> dict:
    cfg = qrm.studies.config("table-4-1", seed=1)
    cfg.update(pairs=20, schedule_pairs=20, samples=30, range_factors=[1.0, 0.8], sizes=[0.5])
    return cfg


def field_config() -> dict:
    cfg = qrm.studies.config("field", seed=2)
    cfg.update(trials=2, worlds=2)  # a shard per world
    return cfg


def serge_config() -> dict:
    cfg = qrm.studies.config("serge-cv", seed=1)
    cfg.update(datasets=["well-separated", "hallway"], folds=2, grid=30, mus=[1, 5],
               sigmas=[2.0], trials_per_belief=2, samples=300)
    return cfg


def real_config() -> dict:
    cfg = qrm.studies.config("real-data", seed=2)
    d = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "mrclam-dataset7")
    if not os.path.isdir(d):
        pytest.skip("shared/data/mrclam-dataset7 not found beside the checkout")
    cfg.update(input=os.path.abspath(d), max_frames=50, samples=30,
               variants=cfg["variants"][:2])  # the main run and two variants: three shards
    return cfg


def reason_config() -> dict:
    cfg = qrm.studies.config("reason", seed=2)
    d = os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "data", "mrclam-dataset7")
    if not os.path.isdir(d):
        pytest.skip("shared/data/mrclam-dataset7 not found beside the checkout")
    cfg.update(input=os.path.abspath(d), max_frames=40)
    cfg["study"].update(calculi=["left-right", "double-cross"], worlds_b=1)  # a shard each
    return cfg


def demo_config() -> dict:
    return qrm.studies.config("demo", seed=1)  # one shard: the pipeline is one run


CASES = [("monte-carlo", mc_config), ("real-data", real_config), ("table-4-1", t41_config),
         ("field", field_config), ("serge-cv", serge_config), ("reason", reason_config),
         ("demo", demo_config)]
QUICK = [("monte-carlo", 3), ("table-4-1", 1)]  # the quick configs, with their seeds


def same(a: qrm.types.StudyRun, b: qrm.types.StudyRun) -> None:
    assert json.dumps(a["output"], sort_keys=True) == json.dumps(b["output"], sort_keys=True)
    assert a["report"] == b["report"]
    assert a["config"] == b["config"]


@pytest.mark.parametrize("name,make", CASES)
def test_shards_on_a_process_pool_merge_into_the_local_run(name, make):
    cfg = make()  # skips the real-data case without the recording
    run = qrm.distributed.run(name, cfg, backend="processes", max_workers=2)
    same(run, qrm.studies.run(name, cfg))


def test_a_missing_or_repeated_shard_is_refused():
    cfg = mc_config()
    n = qrm.distributed.shards("monte-carlo", cfg)
    assert n == 6  # one range of trials each
    parts = [(i, qrm.distributed.run_shard("monte-carlo", cfg, i)) for i in range(n)]
    qrm.distributed.aggregate("monte-carlo", cfg, reversed(parts))  # any order
    with pytest.raises(qrm.InvalidInput, match="missing \\[2\\]"):
        qrm.distributed.aggregate("monte-carlo", cfg, parts[:2] + parts[3:])
    with pytest.raises(qrm.InvalidInput, match="more than once \\[0\\]"):
        qrm.distributed.aggregate("monte-carlo", cfg, parts + parts[:1])
    with pytest.raises(ValueError, match="backend"):
        qrm.distributed.run("monte-carlo", cfg, backend="slurm")


@pytest.fixture(scope="module")
def ray_cluster():
    if os.environ.get("QRM_REQUIRE_RAY") == "1":
        import ray  # must be there: scripts/test installed it
    else:
        ray = pytest.importorskip("ray")
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
    yield ray
    ray.shutdown()


@pytest.mark.parametrize("name,seed", QUICK)
def test_two_studies_on_a_local_ray_cluster_equal_the_local_run(name, seed, ray_cluster):
    config = qrm.studies.config(name, seed=seed)
    local = qrm.studies.run(name, config)
    run = qrm.distributed.run(name, config, backend="ray")
    assert qrm.distributed.shards(name, config) > 1
    same(run, local)
