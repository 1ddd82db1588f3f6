"""Fan the PQRM Monte Carlo study out over a Ray cluster with the qrm wheel.

Each Ray task runs one shard (a range of trial indices of every noise level); trial t of level
l is seeded by (seed, l, t) alone, so the shards can run on any machine in any order and their
records aggregate into exactly the result of one local run.

    pip install qrm_robotics-*.whl "ray[default]"
    python examples/python/ray_sweep.py --shards 64 --trials 1000

Without Ray installed (or with --no-ray) the same shards run one after another locally, which
is what the test suite checks.
"""
from __future__ import annotations

import argparse
import json
from typing import Any, Dict

import qrm


def sweep(config: Dict[str, Any], shards: int, use_ray: bool = True) -> Dict[str, Any]:
    trials = int(config["trials"])
    size = -(-trials // shards)  # ceil
    starts = list(range(0, trials, size))
    if use_ray:
        import ray  # imported only when used: the wheel does not depend on Ray

        ray.init(ignore_reinit_error=True)
        run = ray.remote(qrm.monte_carlo_shard)
        futures = [run.remote(config, s, size) for s in starts]
        records = ray.get(futures)
    else:
        records = [qrm.monte_carlo_shard(config, s, size) for s in starts]
    return qrm.monte_carlo_aggregate(config, records)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--shards", type=int, default=16)
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-ray", action="store_true")
    ap.add_argument("--out", default="study.json")
    args = ap.parse_args()
    config = qrm.monte_carlo_config(trials=args.trials, seed=args.seed)
    result = sweep(config, args.shards, use_ray=not args.no_ray)
    with open(args.out, "w") as f:
        json.dump(result, f)
    for level in result["levels"]:
        if level["calculus"] == "edc":
            print(f"σ_R {level['sigma_r']:6.1f}  entropy {level['mean_entropy']['mean']:.3f}  error {level['error_rate']['mean']:.3f}")


if __name__ == "__main__":
    main()
