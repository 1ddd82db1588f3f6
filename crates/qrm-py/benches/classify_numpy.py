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
The bound: a numba loop that reads every input value once and computes and writes nothing,
on the thread count being measured — no kernel can classify faster — and whether 1.5x the
strongest baseline (issue 37's goal) lies above it.
qrm is timed through the wheel (`Calculus.classify` with `out=`, rows; `classify_columns`,
six contiguous columns) in the same process as the baselines of its thread count: one process
per thread count (its pools pinned by RAYON_NUM_THREADS / NUMBA_NUM_THREADS), interleaved
rounds (each call after 50 ms of quiet), best wall and best CPU time each (the way
`sampling_numpy.py` times the PQRM step).
Every ratio is against the strongest baseline of the same layout and thread count.

Usage (workspace root; a venv with numpy, numba and the qrm wheel):
    python crates/qrm-py/benches/classify_numpy.py [--n 10000000] [--repeat 5] [--threads 1,2]
The criterion bench `crates/qsr-core/benches/classify.rs` times the Rust kernel without
Python. This script lives with the wheel it imports (qrm-py), above the kernel crates.
"""
from __future__ import annotations

import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import time
from typing import Callable, Dict

import numpy as np

BLOCK = 1 << 16
# Seconds of quiet before each timed call: numba's OpenMP workers spin for milliseconds after
# a parallel loop and would take CPU from whichever implementation is timed next.
SETTLE = 0.05


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
        import numba  # type: ignore[import-untyped,import-not-found,unused-ignore]
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

    def column_body(ax, ay, bx, by, cx, cy, out, i):  # type: ignore[no-untyped-def]
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

    column = numba.njit(column_body)

    @numba.njit
    def columns(ax, ay, bx, by, cx, cy, out):  # type: ignore[no-untyped-def]
        for i in range(ax.shape[0]):
            column(ax, ay, bx, by, cx, cy, out, i)

    @numba.njit(parallel=True)
    def columns_parallel(ax, ay, bx, by, cx, cy, out):  # type: ignore[no-untyped-def]
        for i in numba.prange(ax.shape[0]):
            column(ax, ay, bx, by, cx, cy, out, i)

    # The bound: reading every input value once, nothing computed, nothing written — no
    # kernel can take less. Eight independent xors of the raw words (LLVM vectorises them);
    # on k threads, k contiguous parts read at once from a thread pool (`nogil`), which
    # numba's `prange` reduction ran at a quarter of the speed. Until 2026-11-30 the bound was
    # `t.sum()` (about 55 % of this speed), then briefly a loop that also wrote an int64 per
    # row, which qrm's columns beat on one thread: neither was a bound.
    @numba.njit(nogil=True)
    def read(words: np.ndarray) -> np.ndarray:
        acc = np.zeros(8, np.uint64)
        for i in range(0, words.size - 7, 8):
            for k in range(8):
                acc[k] ^= words[i + k]
        return acc

    return {"numba": serial, "numba-parallel": parallel, "numba columns": columns,
            "numba-parallel columns": columns_parallel, "read": read}


def triplets(n: int) -> np.ndarray:
    return np.random.default_rng(7).uniform(0.0, 100.0, size=(n, 6))


def measure(threads: int, n: int, repeat: int) -> Dict[str, Dict[str, float]]:
    """Runs in a process whose pools are pinned to `threads`: every implementation of that
    thread count checked against qrm's labels, then interleaved rounds, best wall and best
    CPU seconds each."""
    try:
        import qrm
    except ImportError:
        sys.exit("install the qrm wheel into this venv: the baselines are checked against it")
    if qrm.worker_threads() != threads:
        sys.exit(f"qrm's pool has {qrm.worker_threads()} threads, not {threads}")
    nb = numba_kernels()
    if not nb:
        sys.exit("numba is not installed in this venv: the fair baseline is numba")
    t = triplets(n)
    cols = [np.ascontiguousarray(t[:, j]) for j in range(6)]
    out = np.empty(n, dtype=np.int64)
    edc = qrm.Calculus.builtin("edc")
    truth = edc.classify(t)
    jobs: Dict[str, Callable[[], object]] = {}
    if threads == 1:
        jobs["numpy-naive"] = lambda: edc_naive(t)
        jobs["numpy-lut"] = lambda: edc_lut(t, out)
    read = nb.pop("read")
    for name, k in nb.items():
        if name.startswith("numba-parallel") != (threads > 1):
            continue
        if name.endswith("columns"):
            jobs[name] = lambda k=k: k(*cols, out)  # type: ignore[misc]
        else:
            jobs[name] = lambda k=k: k(t, out)  # type: ignore[misc]
    for name, job in jobs.items():
        got = job()
        got = out if got is None else got
        wrong = int(np.count_nonzero(got != truth))
        if wrong:
            sys.exit(f"{name} disagrees with qrm on {wrong} of {n} triplets: no comparison")
    plural = "s" if threads > 1 else ""
    jobs[f"qrm rows, {threads} thread{plural}"] = lambda: edc.classify(t, out=out)
    jobs[f"qrm columns, {threads} thread{plural}"] = lambda: edc.classify_columns(*cols, out=out)
    parts = np.array_split(t.view(np.uint64).reshape(-1), threads)
    pool = concurrent.futures.ThreadPoolExecutor(threads)
    jobs[BOUND] = lambda: list(pool.map(read, parts))
    best = {name: {"wall": float("inf"), "cpu": float("inf")} for name in jobs}
    for f in jobs.values():
        f()  # warm-up (numba's compile, qrm's pool)
    for _ in range(repeat):
        for name, f in jobs.items():
            time.sleep(SETTLE)
            w0, c0 = time.perf_counter(), time.process_time()
            f()
            c1, w1 = time.process_time(), time.perf_counter()
            best[name]["wall"] = min(best[name]["wall"], w1 - w0)
            best[name]["cpu"] = min(best[name]["cpu"], c1 - c0)
    return best


BOUND = "read the input (bound)"
GOAL = 1.5  # issue 37: qrm ≥ 1.5x its strongest baseline


def strongest(best: Dict[str, Dict[str, float]], columns: bool) -> str:
    """The fastest baseline of one layout by wall time (the NumPy ones read rows)."""
    baselines = [k for k in best if not k.startswith("qrm") and k != BOUND
                 and k.endswith("columns") == columns]
    return min(baselines, key=lambda k: best[k]["wall"])


def report(threads: int, n: int, best: Dict[str, Dict[str, float]]) -> str:
    plural = "s" if threads > 1 else ""
    lines = [f"\n{threads} thread{plural} (best of the rounds; ns per triplet)",
             f"{'implementation':<26} {'wall':>8} {'CPU':>8}"]
    for name, t in best.items():
        lines.append(f"{name:<26} {t['wall'] / n * 1e9:8.2f} {t['cpu'] / n * 1e9:8.2f}")
    for layout, columns in (("rows", False), ("columns", True)):
        ours = f"qrm {layout}, {threads} thread{plural}"
        top = strongest(best, columns)
        lines.append(f"qrm {layout} against the strongest baseline of its layout ({top}): "
                     f"{best[top]['wall'] / best[ours]['wall']:.2f}x by wall time, "
                     f"{best[top]['cpu'] / best[ours]['cpu']:.2f}x by CPU time")
    lines.append(reachable(best, n))
    return "\n".join(lines)


def reachable(best: Dict[str, Dict[str, float]], n: int) -> str:
    """Whether the goal is within what the machine can stream: GOAL x the strongest baseline
    of a layout needs a time per triplet, and no kernel runs faster than its input is read."""
    need = {layout: best[strongest(best, columns)]["wall"] / GOAL / n * 1e9
            for layout, columns in (("rows", False), ("columns", True))}
    bound = best[BOUND]["wall"] / n * 1e9
    below = [layout for layout, t in need.items() if t < bound]
    if below:
        verdict = f"below the bound on {' and '.join(below)}: no kernel can meet it there on this machine"
    else:
        verdict = (f"above the bound by {min(need.values()) / bound:.2f}x at the tightest: the "
                   "classification's arithmetic has to hide behind the memory traffic")
    shown = ", ".join(f"{layout} {t:.2f} ns" for layout, t in need.items())
    return (f"{GOAL}x the strongest baseline needs ({shown}); reading the input alone takes "
            f"{bound:.2f} ns: {verdict}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10_000_000)
    ap.add_argument("--repeat", type=int, default=5, help="interleaved rounds (best of)")
    ap.add_argument("--threads", default=f"1,{os.cpu_count() or 1}", help="thread counts, one process each")
    ap.add_argument("--json", help="also write the best times (seconds) here")
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.repeat < 1 or args.n < 1:
        sys.exit("--repeat and --n must be at least 1")
    if args.child is not None:
        print(json.dumps(measure(args.child, args.n, args.repeat)))
        return
    try:
        counts = sorted({int(v) for v in args.threads.split(",")})
    except ValueError:
        sys.exit(f"--threads: comma-separated thread counts, got {args.threads!r}")
    if any(t < 1 for t in counts):
        sys.exit("--threads: counts of at least 1")
    print(f"every baseline gives qrm's state on each of {args.n:,} triplets (checked before timing); "
          f"{args.repeat} interleaved rounds")
    res: Dict[str, Dict[str, Dict[str, float]]] = {}
    for t in counts:
        env = dict(os.environ, RAYON_NUM_THREADS=str(t), NUMBA_NUM_THREADS=str(t), OMP_NUM_THREADS="1",
                   OPENBLAS_NUM_THREADS="1")
        run = subprocess.run([sys.executable, __file__, "--child", str(t), "--n", str(args.n),
                              "--repeat", str(args.repeat)], env=env, capture_output=True, text=True)
        if run.returncode != 0:
            sys.exit(f"{t} thread(s): {run.stderr.strip() or run.stdout.strip()}")
        best = json.loads(run.stdout.strip().splitlines()[-1])
        res[str(t)] = best
        print(report(t, args.n, best))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(res, f, indent=1)


if __name__ == "__main__":
    main()
