#!/usr/bin/env python3
"""One PQRM step — 10 landmarks, s = 1000 Gaussian samples each, every ordered triplet (720)
normalised, classified in the EDC and histogrammed: 720,000 triplet-samples — in qrm and in
the best a Python user would write.

Baselines, each timed from drawing the samples (NumPy's generator, the same for all) to the
(720, 20) count table, and checked to give identical tables from the same samples:
- `numpy-naive`: everything at once with nested `np.where` (the repository's old baseline);
- `numpy-lut`: blocks of 8 triplets × 1000 samples (temporaries in cache), a 5-bit key per
  triplet-sample (right of A→B, inside the circle about A, about B, band of y) and one lookup
  table, `np.bincount` with per-triplet offsets;
- `numba`: an `@njit` loop computing the same key, counting into four sub-histograms in turn
  (no wait on the previous increment) and folding them through the table at the end; `numba-parallel`: `parallel=True`, one triplet per `prange`
  step (each writes its own row, so the counts do not depend on the threads).
qrm draws its own samples (a seeded generator of its own), so it is checked in distribution:
for a few triplets `qrm.single_observation` and the baselines' histograms agree within
sampling noise. qrm is timed by the criterion bench `crates/pqrm/benches/sampling.rs`
(`pqrm_step_m10_s1000`: draw + counts, 1 and 2 threads), run from here in the same session.

Usage (workspace root; a venv with numpy, numba and the qrm wheel):
    python crates/qrm-py/benches/sampling_numpy.py [--skip-cargo] [--repeat 5]
This script lives with the wheel it imports (qrm-py), above the kernel crates.
"""
from __future__ import annotations

import argparse
import itertools
import json
import pathlib
import subprocess
import sys
import time
from typing import Callable, Dict

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]
M, S, SIGMA = 10, 1000, 10.0
TRIPLETS = np.array(list(itertools.permutations(range(M), 3)), dtype=np.int64)
Q = 20


def _state(right: int, near_a: int, near_b: int, band: int) -> int:
    """The EDC's rule (calculi/edc.toml order) for one combination of answers."""
    lune = near_a and near_b
    if band == 3:
        return (2 if near_b else 0) + right
    if band == 2:
        return (7 if lune else 8 if near_b else 9) if right else (6 if lune else 5 if near_b else 4)
    if band == 1:
        return (13 if lune else 14 if near_a else 15) if right else (12 if lune else 11 if near_a else 10)
    return (16 if near_a else 18) + right


LUT = np.array([_state(k & 1, (k >> 1) & 1, (k >> 2) & 1, k >> 3) for k in range(32)], dtype=np.int64)


def draw(rng: np.random.Generator, means: np.ndarray) -> np.ndarray:
    return means[:, None, :] + SIGMA * rng.standard_normal((M, S, 2))


def counts_naive(samples: np.ndarray) -> np.ndarray:
    i, j, k = TRIPLETS.T
    a, b, c = samples[i], samples[j], samples[k]
    d = b - a
    v = c - a
    inv = 1.0 / (d[..., 0] ** 2 + d[..., 1] ** 2)
    x = -(d[..., 0] * v[..., 1] - d[..., 1] * v[..., 0]) * inv
    y = (d[..., 0] * v[..., 0] + d[..., 1] * v[..., 1]) * inv
    right = x >= 0
    near_a = x * x + y * y <= 1.0
    near_b = x * x + (y - 1.0) ** 2 <= 1.0
    lune = near_a & near_b
    top = np.where(near_b, 2, 0) + right
    upper = np.where(right, np.where(lune, 7, np.where(near_b, 8, 9)), np.where(lune, 6, np.where(near_b, 5, 4)))
    lower = np.where(right, np.where(lune, 13, np.where(near_a, 14, 15)), np.where(lune, 12, np.where(near_a, 11, 10)))
    below = np.where(near_a, 16, 18) + right
    lab = np.where(y >= 1.0, top, np.where(y >= 0.5, upper, np.where(y >= 0.0, lower, below)))
    lab = lab + Q * np.arange(len(TRIPLETS))[:, None]
    return np.bincount(lab.ravel(), minlength=Q * len(TRIPLETS)).reshape(-1, Q)


def counts_lut(samples: np.ndarray, trips: np.ndarray = TRIPLETS, block: int = 8) -> np.ndarray:
    out = np.empty((len(trips), Q), dtype=np.int64)
    offsets = (Q * np.arange(block))[:, None]
    for s in range(0, len(trips), block):
        i, j, k = trips[s : s + block].T
        a, b, c = samples[i], samples[j], samples[k]
        dx = b[..., 0] - a[..., 0]
        dy = b[..., 1] - a[..., 1]
        vx = c[..., 0] - a[..., 0]
        vy = c[..., 1] - a[..., 1]
        inv = 1.0 / (dx * dx + dy * dy)
        x = -(dx * vy - dy * vx) * inv
        y = (dx * vx + dy * vy) * inv
        x2 = x * x
        key = (x >= 0).view(np.uint8).copy()
        key |= (x2 + y * y <= 1.0).view(np.uint8) << 1
        key |= (x2 + (y - 1.0) ** 2 <= 1.0).view(np.uint8) << 2
        key += ((y >= 0.0).view(np.uint8) + (y >= 0.5).view(np.uint8) + (y >= 1.0).view(np.uint8)) << 3
        n = len(i)
        lab = LUT[key] + offsets[:n]
        out[s : s + n] = np.bincount(lab.ravel(), minlength=Q * n).reshape(n, Q)
    return out


def numba_kernels() -> Dict[str, Callable[[np.ndarray], np.ndarray]]:
    try:
        import numba  # type: ignore[import-untyped]
    except ImportError:
        return {}

    lut = LUT.copy()

    # Branch-free (a key and the table, as numpy-lut), and four sub-histograms taken in turn:
    # with one, consecutive samples that land in the same state wait on each other's
    # increment (21 ns per triplet-sample when tried here, 6.8 with four).
    @numba.njit
    def one(samples: np.ndarray, trip: np.ndarray, t: int, out: np.ndarray) -> None:
        ia, ib, ic = trip[t, 0], trip[t, 1], trip[t, 2]
        h = np.zeros((4, 32), np.int64)
        for s in range(samples.shape[1]):
            ax, ay = samples[ia, s, 0], samples[ia, s, 1]
            dx = samples[ib, s, 0] - ax
            dy = samples[ib, s, 1] - ay
            vx = samples[ic, s, 0] - ax
            vy = samples[ic, s, 1] - ay
            inv = 1.0 / (dx * dx + dy * dy)
            x = -(dx * vy - dy * vx) * inv
            y = (dx * vx + dy * vy) * inv
            key = (x >= 0.0) | ((x * x + y * y <= 1.0) << 1) | ((x * x + (y - 1.0) * (y - 1.0) <= 1.0) << 2)
            h[s & 3, key | (((y >= 0.0) + (y >= 0.5) + (y >= 1.0)) << 3)] += 1
        for k in range(32):
            out[t, lut[k]] += h[0, k] + h[1, k] + h[2, k] + h[3, k]

    @numba.njit
    def serial(samples: np.ndarray, trip: np.ndarray) -> np.ndarray:
        out = np.zeros((trip.shape[0], 20), dtype=np.int64)
        for t in range(trip.shape[0]):
            one(samples, trip, t, out)
        return out

    @numba.njit(parallel=True)
    def parallel(samples: np.ndarray, trip: np.ndarray) -> np.ndarray:
        out = np.zeros((trip.shape[0], 20), dtype=np.int64)
        for t in numba.prange(trip.shape[0]):
            one(samples, trip, t, out)
        return out

    return {
        "numba": lambda smp: serial(smp, TRIPLETS),
        "numba-parallel": lambda smp: parallel(smp, TRIPLETS),
    }


def best_of(f: Callable[[], object], repeat: int) -> float:
    f()  # warm-up (and numba's compile)
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def check_qrm_in_distribution(means: np.ndarray) -> None:
    """qrm's single-observation belief and the baselines' histogram of one ordered triplet
    agree within sampling noise (total variation < 0.03 at 20,000 samples each)."""
    try:
        import qrm
    except ImportError:
        sys.exit("install the qrm wheel into this venv: the baselines are checked against it")
    edc = qrm.Calculus.builtin("edc")
    rng = np.random.default_rng(3)
    n = 20_000
    for trip in ([0, 1, 2], [3, 7, 5], [9, 4, 8]):
        pts = means[trip]
        cov = np.array([[SIGMA**2, 0.0, SIGMA**2]] * 3)
        p = qrm.single_observation(edc, pts, cov, samples=n, floor=0.0, seed=11)
        smp = pts[:, None, :] + SIGMA * rng.standard_normal((3, n, 2))
        h = counts_lut(smp, np.array([[0, 1, 2]]))[0] / n
        tv = 0.5 * float(np.abs(p - h).sum())
        if tv >= 0.03:
            sys.exit(f"triplet {trip}: qrm and NumPy differ by total variation {tv:.3f}")
    print("qrm and the baselines agree in distribution (3 triplets, total variation < 0.03)")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--skip-cargo", action="store_true", help="reuse the last criterion result")
    ap.add_argument("--repeat", type=int, default=5)
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    means = rng.uniform(0, 100, size=(M, 2))
    check_qrm_in_distribution(means)

    kernels: Dict[str, Callable[[np.ndarray], np.ndarray]] = {
        "numpy-naive": counts_naive,
        "numpy-lut": counts_lut,
    }
    kernels.update(numba_kernels())
    fixed = draw(np.random.default_rng(5), means)
    ref = counts_naive(fixed)
    for name, k in kernels.items():
        if not np.array_equal(k(fixed), ref):
            sys.exit(f"{name} counts differ from numpy-naive on the same samples: no comparison")
    print(f"all {len(kernels)} baselines give identical count tables from the same samples")

    n = len(TRIPLETS) * S
    ns = {name: best_of(lambda k=k: k(draw(rng, means)), args.repeat) / n * 1e9 for name, k in kernels.items()}
    if not args.skip_cargo:
        subprocess.run(["cargo", "bench", "-p", "pqrm", "--bench", "sampling", "--", "--noplot",
                        "pqrm_step_m10_s1000"], cwd=ROOT, check=True)
    for name in ("qrm_1_thread", "qrm_2_thread"):
        est = ROOT / "target" / "criterion" / "pqrm_step_m10_s1000" / name / "new" / "estimates.json"
        if est.exists():
            ns[name.replace("_", " ")] = json.loads(est.read_text())["mean"]["point_estimate"] / n
    q1 = ns.get("qrm 1 thread")
    print(f"\n{'implementation':<18} {'ns/triplet-sample':>18} {'÷ qrm 1 thread':>15}")
    for name, v in ns.items():
        print(f"{name:<18} {v:18.2f} {(f'{v / q1:.2f}' if q1 else '-'):>15}")
    print(f"\nbest of {args.repeat} (criterion's mean for qrm); numba-parallel uses every core.")


if __name__ == "__main__":
    main()
