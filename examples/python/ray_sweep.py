"""Fan any qrm study out over a Ray cluster with the qrm wheel.

Each Ray task runs one shard of the study (Table 4.1: a world; the Monte Carlo study: a range
of trials); a shard depends on the config and its index alone, so the shards run on any
machine in any order and merge into exactly the result of one local run (a missing or
duplicated shard is refused).

    pip install qrm_robotics-*.whl ray
    python examples/python/ray_sweep.py --study table-4-1 --full            # Ray on this machine
    python examples/python/ray_sweep.py --study monte-carlo --address auto  # an existing cluster
    python examples/python/ray_sweep.py --study monte-carlo --backend local # no Ray: one by one

On a real cluster: start it (`ray start --head` on one node, `ray start --address HEAD:6379`
on the others, with the same venv and wheel on every node), then pass `--address auto` (or the
head's address) from a node of the cluster; every node needs the qrm wheel installed.
"""
from __future__ import annotations

import argparse
import json
import time
from typing import Any, Dict, Optional

import qrm


def sweep(
    study: str,
    config: Dict[str, Any],
    backend: str = "ray",
    address: Optional[str] = None,
) -> qrm.types.StudyRun:
    """Runs `study` with `config` shard by shard on `backend` and merges the shards."""
    if backend == "ray":
        import ray  # type: ignore[import-untyped,import-not-found,unused-ignore]  # only when used

        if not ray.is_initialized():
            ray.init(address=address)
    return qrm.distributed.run(study, config, backend=backend)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--study", default="monte-carlo", help="a name from qrm.studies.available()")
    ap.add_argument("--full", action="store_true", help="the thesis's config (default: quick)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=JSON", help="change a config field")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--backend", default="ray", choices=["ray", "processes", "local"])
    ap.add_argument("--address", default=None, help="a running Ray cluster (e.g. auto)")
    ap.add_argument("--out", default="run.json")
    args = ap.parse_args()
    config = qrm.studies.config(args.study, full=args.full, seed=args.seed)
    for s in args.set:
        key, value = s.split("=", 1)
        config[key] = json.loads(value)
    t0 = time.perf_counter()
    run = sweep(args.study, config, args.backend, args.address)
    took = time.perf_counter() - t0
    with open(args.out, "w") as f:
        json.dump(run, f)
    n = qrm.distributed.shards(args.study, config)
    print(f"{args.study}: {n} shards on {args.backend} in {took:.1f} s; wrote {args.out}")
    for c in run["report"]["claims"]:
        print(f"[{c['verdict']}] {c['what']}: thesis {c['thesis']}; ours {c['ours']}")


if __name__ == "__main__":
    main()
