"""Any study beyond one machine: its shards fan out over a backend and merge into exactly the
result of a local run.

A study splits its work into shards (Table 4.1: one per world it maps) that depend on the
config and their index alone, so they can run on any machine in any order;
`aggregate` merges them, refusing a missing or duplicated shard, into the same output — byte
for byte — as `qrm.studies.run` on one machine.

    import ray, qrm
    ray.init(address="auto")                        # or ray.init(num_cpus=2) on one machine
    run = qrm.distributed.run("table-4-1", qrm.studies.config("table-4-1", full=True))
    print(run["report"]["claims"][0])

Backends: `"ray"` (a `ray.remote` task per shard; Ray is not a dependency of the wheel — `pip
install ray`), `"processes"` (a local process pool), `"local"` (one after another, here).
Shards cross process boundaries as JSON text.
"""

from __future__ import annotations

from typing import Any, Iterable, List, Mapping, Optional, Tuple

from . import _qrm, types
from .studies import _as_run, _config_json
from .studies import config as _config

__all__ = ["aggregate", "run", "run_shard", "shards"]


def _text(config: Mapping[str, Any]) -> str:
    return _config_json(config)


def shards(name: str, config: Mapping[str, Any]) -> int:
    """How many shards study `name`'s work under `config` splits into."""
    return int(_qrm.studies_shards(name, _text(config)))


def run_shard(name: str, config: Mapping[str, Any], index: int) -> str:
    """Runs shard `index` (0-based) and returns it as JSON text, to hand to `aggregate`."""
    return str(_qrm.studies_run_shard(name, _text(config), index))


def _task(name: str, config_text: str, index: int) -> Tuple[int, str]:
    """What a worker runs: shard `index`, tagged with its index."""
    return index, str(_qrm.studies_run_shard(name, config_text, index))


def aggregate(name: str, config: Mapping[str, Any], parts: Iterable[Tuple[int, str]]) -> types.StudyRun:
    """Merges `(index, shard)` pairs, in any order, into the run (config, output, report).
    A missing or duplicated shard raises `InvalidInput` naming it."""
    return _as_run(_qrm.studies_aggregate(name, _text(config), list(parts)))


def run(
    name: str,
    config: Optional[Mapping[str, Any]] = None,
    *,
    quick: bool = False,
    seed: Optional[int] = None,
    backend: str = "ray",
    max_workers: Optional[int] = None,
) -> types.StudyRun:
    """Runs study `name` shard by shard on `backend` ("ray", "processes" or "local") and
    merges the shards. `config` None: the built-in quick (`quick=True`) or full config.
    With "ray", Ray is started on this machine (`ray.init()`) unless the caller already
    connected it to a cluster (`ray.init(address=...)`)."""
    cfg = dict(config) if config is not None else _config(name, full=not quick, seed=seed)
    text = _text(cfg)
    n = int(_qrm.studies_shards(name, text))
    parts: List[Tuple[int, str]]
    if backend == "ray":
        import ray  # type: ignore[import-untyped,import-not-found,unused-ignore]  # only when asked

        if not ray.is_initialized():
            ray.init()
        task = ray.remote(_task)
        parts = list(ray.get([task.remote(name, text, i) for i in range(n)]))
    elif backend == "processes":
        import concurrent.futures as cf

        with cf.ProcessPoolExecutor(max_workers=max_workers) as pool:
            parts = list(pool.map(_task, [name] * n, [text] * n, range(n)))
    elif backend == "local":
        parts = [_task(name, text, i) for i in range(n)]
    else:
        raise ValueError(f"backend {backend!r}: one of 'ray', 'processes', 'local'")
    return _as_run(_qrm.studies_aggregate(name, text, parts))
