#!/usr/bin/env python3
"""One PQRM step in NumPy, side by side with the criterion bench `sampling`.

10 landmarks, s = 1000 Gaussian samples each, every ordered triplet (720) normalised,
classified in the EDC and histogrammed per triplet: 720,000 triplet-samples. The NumPy
version is fully vectorised (all triplets at once, np.bincount with offsets).

Usage (workspace root, numpy installed): python crates/pqrm/benches/sampling_numpy.py [--skip-cargo]
"""
import argparse
import itertools
import json
import pathlib
import subprocess
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[3]
M, S = 10, 1000


def edc_labels(x, y):
    """0-based EDC state index (as calculi/edc.toml) for normalised points."""
    right = x >= 0
    near_a = x * x + y * y <= 1.0
    near_b = x * x + (y - 1.0) ** 2 <= 1.0
    lune = near_a & near_b
    top = np.where(near_b, 2, 0) + right
    upper = np.where(right, np.where(lune, 7, np.where(near_b, 8, 9)), np.where(lune, 6, np.where(near_b, 5, 4)))
    lower = np.where(right, np.where(lune, 13, np.where(near_a, 14, 15)), np.where(lune, 12, np.where(near_a, 11, 10)))
    below = np.where(near_a, 16, 18) + right
    return np.where(y >= 1.0, top, np.where(y >= 0.5, upper, np.where(y >= 0.0, lower, below)))


def step(rng, means, sigma, triplets):
    samples = means[:, None, :] + sigma * rng.standard_normal((M, S, 2))
    i, j, k = triplets.T
    a, b, c = samples[i], samples[j], samples[k]          # (720, S, 2) each
    d = b - a
    v = c - a
    inv = 1.0 / (d[..., 0] ** 2 + d[..., 1] ** 2)
    x = -(d[..., 0] * v[..., 1] - d[..., 1] * v[..., 0]) * inv
    y = (d[..., 0] * v[..., 0] + d[..., 1] * v[..., 1]) * inv
    lab = edc_labels(x, y) + 20 * np.arange(len(triplets))[:, None]
    return np.bincount(lab.ravel(), minlength=20 * len(triplets)).reshape(-1, 20)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-cargo", action="store_true")
    args = ap.parse_args()
    rng = np.random.default_rng(1)
    means = rng.uniform(0, 100, size=(M, 2))
    triplets = np.array([t for t in itertools.permutations(range(M), 3)])
    step(rng, means, 10.0, triplets)
    best = min(_timed(lambda: step(rng, means, 10.0, triplets)) for _ in range(5))
    n = len(triplets) * S
    np_ns = best / n * 1e9
    if not args.skip_cargo:
        subprocess.run(["cargo", "bench", "-p", "pqrm", "--bench", "sampling", "--", "--noplot"], cwd=ROOT, check=True)
    print(f"numpy (1 thread)   {np_ns:7.2f} ns/triplet-sample  ({1e3 / np_ns:7.1f} M/s)")
    for name in ("qrm_1_thread", "qrm_2_thread"):
        est = ROOT / "target" / "criterion" / "pqrm_step_m10_s1000" / name / "new" / "estimates.json"
        if est.exists():
            ns = json.loads(est.read_text())["mean"]["point_estimate"] / n
            print(f"{name:<18} {ns:7.2f} ns/triplet-sample  ({1e3 / ns:7.1f} M/s)  {np_ns / ns:6.1f}x numpy")


def _timed(f):
    t0 = time.perf_counter()
    f()
    return time.perf_counter() - t0


if __name__ == "__main__":
    main()
