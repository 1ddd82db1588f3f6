#!/usr/bin/env python3
"""EDC classification of 10^7 random triplets: qrm against the best a Python user would write.

Baselines, all checked to give qrm's labels on every triplet before any is timed:
- `numpy-naive`: the rule written with masks and nested `np.where` (what the repository
  compared against before issue 16; kept to show what the lookup table buys);
- `numpy-lut`: what a performance-minded NumPy user writes — blocks of 64 Ki triplets (the
  temporaries stay in cache), the five yes/no questions the EDC asks (right of A→B, within
  the circle about A, about B, and the band of y) packed into a 5-bit key, one lookup table
  from key to state;
- `numba`: the same rule as a plain loop under `@njit` (one thread), and `numba-parallel`
  (`parallel=True`, `prange`, all cores).
qrm is timed in the same process through the wheel (`Calculus.classify` with `out=`, its pool
pinned by RAYON_NUM_THREADS) for one core and all cores, best of --repeat runs each.

The bound: reading a 48-byte triplet from memory, measured here as a NumPy sum over the same
array (one pass, no arithmetic to speak of). Classification cannot go faster than its input
arrives.

Usage (workspace root; a venv with numpy, numba and the qrm wheel):
    python crates/qrm-py/benches/classify_numpy.py [--n 10000000] [--repeat 3]
The criterion bench `crates/qsr-core/benches/classify.rs` times the Rust kernel without
Python. This script lives with the wheel it imports (qrm-py), above the kernel crates.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from typing import Callable, Dict

import numpy as np

BLOCK = 1 << 16


def edc_naive(t: np.ndarray) -> np.ndarray:
    """0-based EDC state index (calculi/edc.toml order) for an (n, 6) array, masks and where."""
    ax, ay, bx, by, cx, cy = (t[:, i] for i in range(6))
    dx, dy = bx - ax, by - ay
    inv = 1.0 / (dx * dx + dy * dy)
    vx, vy = cx - ax, cy - ay
    x = -(dx * vy - dy * vx) * inv
    y = (dx * vx + dy * vy) * inv
    right = x >= 0
    near_a = x * x + y * y <= 1.0
    near_b = x * x + (y - 1.0) ** 2 <= 1.0
    lune = near_a & near_b
    top = np.where(near_b, 2, 0) + right
    upper = np.where(right, np.where(lune, 7, np.where(near_b, 8, 9)), np.where(lune, 6, np.where(near_b, 5, 4)))
    lower = np.where(right, np.where(lune, 13, np.where(near_a, 14, 15)), np.where(lune, 12, np.where(near_a, 11, 10)))
    below = np.where(near_a, 16, 18) + right
    return np.where(y >= 1.0, top, np.where(y >= 0.5, upper, np.where(y >= 0.0, lower, below))).astype(np.int64)


def _state(right: int, near_a: int, near_b: int, band: int) -> int:
    """The EDC's rule for one combination of answers (band: 0 y < 0, 1 [0, ½), 2 [½, 1), 3 y ≥ 1)."""
    lune = near_a and near_b
    if band == 3:
        return (2 if near_b else 0) + right
    if band == 2:
        return (7 if lune else 8 if near_b else 9) if right else (6 if lune else 5 if near_b else 4)
    if band == 1:
        return (13 if lune else 14 if near_a else 15) if right else (12 if lune else 11 if near_a else 10)
    return (16 if near_a else 18) + right


LUT = np.array(
    [_state(k & 1, (k >> 1) & 1, (k >> 2) & 1, k >> 3) for k in range(32)], dtype=np.int64
)


def edc_lut(t: np.ndarray, out: np.ndarray) -> None:
    """Blocked, one 5-bit key per triplet, one table lookup."""
    for s in range(0, len(t), BLOCK):
        b = t[s : s + BLOCK]
        dx = b[:, 2] - b[:, 0]
        dy = b[:, 3] - b[:, 1]
        vx = b[:, 4] - b[:, 0]
        vy = b[:, 5] - b[:, 1]
        inv = 1.0 / (dx * dx + dy * dy)
        x = -(dx * vy - dy * vx) * inv
        y = (dx * vx + dy * vy) * inv
        x2 = x * x
        key = (x >= 0).view(np.uint8).copy()
        key |= (x2 + y * y <= 1.0).view(np.uint8) << 1
        key |= (x2 + (y - 1.0) ** 2 <= 1.0).view(np.uint8) << 2
        key += ((y >= 0.0).view(np.uint8) + (y >= 0.5).view(np.uint8) + (y >= 1.0).view(np.uint8)) << 3
        np.take(LUT, key, out=out[s : s + BLOCK])


def numba_kernels() -> Dict[str, Callable[[np.ndarray, np.ndarray], None]]:
    """`@njit` loops, one thread and `parallel=True`; empty if numba is not installed."""
    try:
        import numba  # type: ignore[import-untyped]
    except ImportError:
        return {}

    lut = LUT.copy()

    # Branch-free (a key and the table, as numpy-lut): LLVM vectorises it, where the nested
    # if/else of the rule ran about 3x slower when tried here.
    def body(t: np.ndarray, out: np.ndarray, i: int) -> None:
        dx = t[i, 2] - t[i, 0]
        dy = t[i, 3] - t[i, 1]
        vx = t[i, 4] - t[i, 0]
        vy = t[i, 5] - t[i, 1]
        inv = 1.0 / (dx * dx + dy * dy)
        x = -(dx * vy - dy * vx) * inv
        y = (dx * vx + dy * vy) * inv
        key = (x >= 0.0) | ((x * x + y * y <= 1.0) << 1) | ((x * x + (y - 1.0) * (y - 1.0) <= 1.0) << 2)
        out[i] = lut[key | (((y >= 0.0) + (y >= 0.5) + (y >= 1.0)) << 3)]

    one = numba.njit(body)

    @numba.njit
    def serial(t: np.ndarray, out: np.ndarray) -> None:
        for i in range(t.shape[0]):
            one(t, out, i)

    @numba.njit(parallel=True)
    def parallel(t: np.ndarray, out: np.ndarray) -> None:
        for i in numba.prange(t.shape[0]):
            one(t, out, i)

    @numba.njit
    def columns(ax, ay, bx, by, cx, cy, out):  # type: ignore[no-untyped-def]
        for i in range(ax.shape[0]):
            dx = bx[i] - ax[i]
            dy = by[i] - ay[i]
            vx = cx[i] - ax[i]
            vy = cy[i] - ay[i]
            inv = 1.0 / (dx * dx + dy * dy)
            x = -(dx * vy - dy * vx) * inv
            y = (dx * vx + dy * vy) * inv
            right = 1 if x >= 0.0 else 0
            near_a = x * x + y * y <= 1.0
            near_b = x * x + (y - 1.0) * (y - 1.0) <= 1.0
            out[i] = lut[right | (near_a << 1) | (near_b << 2) | (((y >= 0.0) + (y >= 0.5) + (y >= 1.0)) << 3)]

    return {"numba": serial, "numba-parallel": parallel, "numba columns": columns}


def best_of(f: Callable[[], object], repeat: int) -> float:
    f()  # warm-up (and numba's compile)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def qrm_times(n: int, repeat: int) -> Dict[str, float]:
    """qrm through the wheel, rows and columns, in child processes so each gets its own pool
    size."""
    res: Dict[str, float] = {}
    for threads in (1, os.cpu_count() or 1):
        env = dict(os.environ, RAYON_NUM_THREADS=str(threads))
        r = subprocess.run(
            [sys.executable, __file__, "--qrm-only", "--n", str(n), "--repeat", str(repeat)],
            env=env, capture_output=True, text=True,
        )
        if r.returncode != 0:
            print(f"qrm ({threads} thread(s)) not timed: {r.stderr.strip().splitlines()[-1:]}")
            continue
        plural = "s" if threads > 1 else ""
        for layout, seconds in json.loads(r.stdout).items():
            res[f"qrm {layout} ({threads} thread{plural})"] = seconds
    return res


def triplets(n: int) -> np.ndarray:
    return np.random.default_rng(7).uniform(0.0, 100.0, size=(n, 6))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--qrm-only", action="store_true", help=argparse.SUPPRESS)
    args = ap.parse_args()
    t = triplets(args.n)
    out = np.empty(args.n, dtype=np.int64)
    if args.qrm_only:
        import qrm

        edc = qrm.Calculus.builtin("edc")
        cols = [np.ascontiguousarray(t[:, j]) for j in range(6)]
        print(json.dumps({
            "rows": best_of(lambda: edc.classify(t, out=out), args.repeat),
            "columns": best_of(lambda: edc.classify_columns(*cols, out=out), args.repeat),
        }))
        return

    # Every baseline computes qrm's labels, checked on the whole input before timing.
    try:
        import qrm

        truth = qrm.Calculus.builtin("edc").classify(t)
    except ImportError:
        sys.exit("install the qrm wheel into this venv: the baselines are checked against it")
    kernels: Dict[str, Callable[[], object]] = {
        "numpy-naive": lambda: edc_naive(t),
        "numpy-lut": lambda: edc_lut(t, out),
    }
    cols = [np.ascontiguousarray(t[:, j]) for j in range(6)]
    for name, k in numba_kernels().items():
        if name.endswith("columns"):
            kernels[name] = lambda k=k: k(*cols, out)
        else:
            kernels[name] = lambda k=k: k(t, out)
    for name, k in kernels.items():
        got = k()
        got = out if got is None else got
        wrong = int(np.count_nonzero(got != truth))
        if wrong:
            sys.exit(f"{name} disagrees with qrm on {wrong} of {args.n} triplets: no comparison")
    print(f"all {len(kernels)} baselines give qrm's state on each of {args.n:,} triplets")

    times = {name: best_of(k, args.repeat) for name, k in kernels.items()}
    times.update(qrm_times(args.n, args.repeat))
    bound = best_of(lambda: t.sum(), args.repeat)
    ns = {name: s / args.n * 1e9 for name, s in times.items()}
    bound_ns = bound / args.n * 1e9
    q1 = ns.get("qrm rows (1 thread)")
    print(f"\n{'implementation':<22} {'ns/triplet':>10} {'÷ qrm 1 thread':>15}")
    for name, v in ns.items():
        print(f"{name:<22} {v:10.2f} {(f'{v / q1:.2f}' if q1 else '-'):>15}")
    print(f"{'memory read (bound)':<22} {bound_ns:10.2f} {(f'{bound_ns / q1:.2f}' if q1 else '-'):>15}")
    print(f"\nbest of {args.repeat} runs each; numpy and numba on one thread, numba-parallel and "
          f"the last qrm row on every core; qrm through the wheel (classify with out=).")


if __name__ == "__main__":
    main()
