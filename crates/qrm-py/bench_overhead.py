#!/usr/bin/env python3
"""Python-call overhead of the qrm wheel: the same batch work called from Python and from Rust.

- classify: `Calculus.classify` on 10^7 random EDC triplets vs the criterion bench
  `edc_classify_1e7/qrm_1_thread` (crates/qsr-core/benches/classify.rs);
- update: `Pqrm.update` with 10 landmarks and s = 1000 vs `pqrm_update_m10_s1000/qrm_1_thread`
  (crates/pqrm/benches/sampling.rs).

Both sides on one thread (RAYON_NUM_THREADS=1). Run from the workspace root with the wheel
installed: python crates/qrm-py/bench_overhead.py [--skip-cargo]
"""
import argparse
import json
import os
import pathlib
import subprocess
import time

os.environ["RAYON_NUM_THREADS"] = "1"

import numpy as np  # noqa: E402

import qrm  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


def best(f, n=5):
    times = []
    for _ in range(n):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return min(times)


def criterion(group, name):
    est = ROOT / "target" / "criterion" / group / name / "new" / "estimates.json"
    return json.loads(est.read_text())["mean"]["point_estimate"] * 1e-9 if est.exists() else None


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-cargo", action="store_true")
    args = ap.parse_args()
    if not args.skip_cargo:
        env = dict(os.environ, RAYON_NUM_THREADS="1")
        subprocess.run(["cargo", "bench", "-p", "qsr-core", "--bench", "classify", "--", "--noplot", "qrm_1_thread"], cwd=ROOT, check=True, env=env)
        subprocess.run(["cargo", "bench", "-p", "pqrm", "--bench", "sampling", "--", "--noplot", "pqrm_update"], cwd=ROOT, check=True, env=env)
    rng = np.random.default_rng(7)
    t = rng.uniform(0.0, 100.0, size=(10_000_000, 6))
    edc = qrm.Calculus.builtin("edc")
    py_classify_alloc = best(lambda: edc.classify(t), 3)
    buf = np.empty(len(t), dtype=np.int64)
    edc.classify(t, out=buf)
    py_classify = best(lambda: edc.classify(t, out=buf), 5)
    rs_classify = criterion("edc_classify_1e7", "qrm_1_thread")
    means = rng.uniform(0, 100, size=(10, 2))
    ids = np.arange(10, dtype=np.int64)
    cov = np.tile([100.0, 0.0, 100.0], (10, 1))
    m = qrm.Pqrm(edc, samples=1000)
    py_update = best(lambda: m.update(0.0, ids, means, cov), 40)
    rs_update = criterion("pqrm_update_m10_s1000", "qrm_1_thread")
    for name, py, rs in [("classify 1e7 (out=)", py_classify, rs_classify), ("classify 1e7 (new array)", py_classify_alloc, rs_classify), ("update m=10 s=1000", py_update, rs_update)]:
        if rs is None:
            print(f"{name}: python {py * 1e3:.2f} ms (no criterion result; run without --skip-cargo)")
        else:
            print(f"{name}: python {py * 1e3:.2f} ms, rust {rs * 1e3:.2f} ms, overhead {100 * (py / rs - 1):+.1f}%")


if __name__ == "__main__":
    main()
