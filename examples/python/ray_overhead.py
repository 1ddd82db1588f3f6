"""What a shard costs on Ray beyond its own work, measured on this machine.

    python examples/python/ray_overhead.py [--address auto]

Prints (1) the round trip of an empty Ray task, (2) for the Monte Carlo study cut into one
shard per trial, the wall time per shard run here in a loop and run as Ray tasks one at a
time (so the difference is Ray's: scheduling, arguments, the result back as JSON text), and
(3) a whole quick study locally and on Ray with every core.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

import ray

import qrm
from qrm.distributed import _task


@ray.remote
def _empty() -> int:
    return 0


def best_of(f, n: int = 5) -> float:
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--address", default=None)
    ap.add_argument("--shards", type=int, default=16)
    args = ap.parse_args()
    ray.init(address=args.address, include_dashboard=False, log_to_driver=False)
    ray.get(_empty.remote())  # workers up
    n = 200
    t_empty = best_of(lambda: ray.get([_empty.remote() for _ in range(n)]), 3) / n
    print(f"empty task, {n} in flight: {1e3 * t_empty:.2f} ms per task")
    lat = statistics.median([best_of(lambda: ray.get(_empty.remote()), 1) for _ in range(50)])
    print(f"empty task, one at a time: {1e3 * lat:.2f} ms round trip")

    cfg = qrm.studies.config("monte-carlo")
    cfg.update(trials=args.shards)  # one trial per shard, every level in each
    text = json.dumps(cfg)
    shards = qrm.distributed.shards("monte-carlo", cfg)
    task = ray.remote(_task)
    ray.get(task.remote("monte-carlo", text, 0))  # the worker imports qrm once
    local = best_of(lambda: [_task("monte-carlo", text, i) for i in range(shards)], 3) / shards
    remote = best_of(lambda: [ray.get(task.remote("monte-carlo", text, i)) for i in range(shards)], 3) / shards
    size = len(_task("monte-carlo", text, 0)[1])
    print(
        f"monte-carlo shard ({size / 1024:.0f} KiB of JSON back): here {1e3 * local:.1f} ms, "
        f"as a Ray task {1e3 * remote:.1f} ms: overhead {1e3 * (remote - local):.1f} ms per shard"
    )
    for name in ("monte-carlo", "table-4-1"):
        c = qrm.studies.config(name)
        t_local = best_of(lambda: qrm.studies.run(name, c), 1)
        t_ray = best_of(lambda: qrm.distributed.run(name, c, backend="ray"), 1)
        print(
            f"{name} quick, {qrm.distributed.shards(name, c)} shards: here {t_local:.2f} s, "
            f"on Ray {t_ray:.2f} s ({ray.cluster_resources().get('CPU', 0):.0f} CPUs)"
        )
    ray.shutdown()


if __name__ == "__main__":
    main()
