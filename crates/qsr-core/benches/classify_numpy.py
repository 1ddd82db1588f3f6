#!/usr/bin/env python3
"""EDC classification: a vectorised NumPy implementation of the same rule as qsr-core,
timed on 10^7 random triplets, side by side with the criterion bench `classify`.

Usage (from the workspace root, with numpy installed):
    python crates/qsr-core/benches/classify_numpy.py [--skip-cargo]

Runs `cargo bench -p qsr-core --bench classify` (unless --skip-cargo), reads criterion's
estimates and prints ns/triplet for NumPy and qrm and the ratio. The NumPy side is pinned to
one thread through the BLAS env vars (it uses no BLAS here anyway).
"""
import argparse
import json
import os
import pathlib
import subprocess
import sys
import time

import numpy as np

N = 10_000_000
ROOT = pathlib.Path(__file__).resolve().parents[3]


def edc_numpy(t: np.ndarray) -> np.ndarray:
    """Labels 1..20 for an (n, 6) array, the same conventions as calculi/edc.toml."""
    ax, ay, bx, by, cx, cy = (t[:, i] for i in range(6))
    dx, dy = bx - ax, by - ay
    inv = 1.0 / (dx * dx + dy * dy)
    vx, vy = cx - ax, cy - ay
    x = -(dx * vy - dy * vx) * inv
    y = (dx * vx + dy * vy) * inv
    right = x >= 0
    near_a = x * x + y * y <= 1.0
    near_b = x * x + (y - 1.0) ** 2 <= 1.0
    lab = np.empty(len(t), dtype=np.int16)
    top = y >= 1.0
    upper = (y >= 0.5) & ~top
    lower = (y >= 0.0) & (y < 0.5)
    below = y < 0.0
    # y >= 1: 1 L far-B, 2 R far-B, 3 L near-B, 4 R near-B
    lab[top] = np.where(near_b[top], 3, 1)[...] + right[top]
    # 0.5 <= y < 1: L 5 far, 6 near-B only, 7 lune; R 8 lune, 9 near-B only, 10 far
    lune = near_a & near_b
    left_u = np.where(lune, 7, np.where(near_b, 6, 5))
    right_u = np.where(lune, 8, np.where(near_b, 9, 10))
    lab[upper] = np.where(right[upper], right_u[upper], left_u[upper])
    left_l = np.where(lune, 13, np.where(near_a, 12, 11))
    right_l = np.where(lune, 14, np.where(near_a, 15, 16))
    lab[lower] = np.where(right[lower], right_l[lower], left_l[lower])
    # y < 0: 17 L near-A, 18 R near-A, 19 L far-A, 20 R far-A
    lab[below] = np.where(near_a[below], 17, 19) + right[below]
    return lab


def check_against_qrm(t: np.ndarray) -> None:
    """Both sides must compute the same thing: compare labels with `qrm calculus classify`."""
    exe = ROOT / "target" / "release" / "qrm"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--release", "-q"], cwd=ROOT, check=True)
    text = "\n".join(" ".join(f"{v:.17g}" for v in row) for row in t)
    out = subprocess.run([str(exe), "calculus", "classify", "edc"], input=text, text=True,
                         capture_output=True, check=True).stdout.split()
    ours = np.array([int(x) for x in out])
    agree = np.mean(ours == edc_numpy(t))
    print(f"numpy and qrm agree on {agree:.4%} of {len(t)} triplets")
    if agree < 1.0:
        sys.exit("the NumPy rule and qrm disagree: the comparison would be meaningless")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--skip-cargo", action="store_true", help="reuse the last criterion result")
    ap.add_argument("--n", type=int, default=N)
    args = ap.parse_args()
    rng = np.random.default_rng(7)
    t = rng.uniform(0.0, 100.0, size=(args.n, 6))
    check_against_qrm(t[:20000])
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        edc_numpy(t)
        best = min(best, time.perf_counter() - t0)
    np_ns = best / args.n * 1e9
    if not args.skip_cargo:
        subprocess.run(
            ["cargo", "bench", "-p", "qsr-core", "--bench", "classify", "--", "--noplot"],
            cwd=ROOT, check=True,
        )
    res = {}
    for name in ("qrm_1_thread", "qrm_2_threads"):
        est = ROOT / "target" / "criterion" / "edc_classify_1e7" / name / "new" / "estimates.json"
        if est.exists():
            mean_ns = json.loads(est.read_text())["mean"]["point_estimate"]
            res[name] = mean_ns / N
    print(f"numpy (1 thread)   {np_ns:7.2f} ns/triplet")
    for name, ns in res.items():
        print(f"{name:<18} {ns:7.2f} ns/triplet   {np_ns / ns:6.1f}x numpy")
    if not res:
        sys.exit("no criterion results found; run without --skip-cargo")


if __name__ == "__main__":
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    main()
