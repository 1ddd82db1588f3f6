#!/usr/bin/env python3
"""One PQRM step — 10 landmarks, s = 1000 Gaussian samples each, every ordered triplet (720)
classified in the EDC and histogrammed: 720,000 ordered triplet-samples — in qrm and in the
best a Python user would write.

Baselines, each timed from drawing the samples (NumPy's generator, the same for all) to the
(720, 20) count table, and checked to give identical tables from the same samples:
- `numpy-naive`: everything at once with nested `np.where` (the repository's old baseline);
- `numpy-lut`: blocks of 8 triplets × 1000 samples (temporaries in cache), a 5-bit key per
  triplet-sample (right of A→B, inside the circle about A, about B, band of y) and one lookup
  table, `np.bincount` with per-triplet offsets;
- `numpy-frames`: the fair algorithm below (one frame per unordered triplet, a 7-bit key, a
  128 × 6 table) in blocks of NumPy arrays;
- `numba-720`: an `@njit` loop over the 720 ordered triplets, one frame each, the same 5-bit
  key, four sub-histograms counted in turn (the bench's baseline before issue 37);
- `numba-frames`: **the fair one** — what a performance-minded numba user writes with the
  algebra qrm itself uses (`SixForms`, `crates/pqrm/src/likelihood.rs`): one frame per
  *unordered* triplet (120), the signs of the EDC's seven base-frame quantities (x, y, y − ½,
  y − 1, n − 1, n − y, n − 2y with n = x² + y²) as a 7-bit key, four interleaved
  sub-histograms of 128 keys, and a 128 × 6 table from key to the state of each of the six
  orderings applied once per triplet;
- `-parallel` forms of the numba loops: `parallel=True`, one triplet per `prange` step (each
  writes its own rows, so the counts do not depend on the threads).
qrm is timed through the wheel, doing more than the baselines: `Pqrm.update` draws its own
samples, counts every ordering *and* runs the Bayes filter over the 720 sets. It draws with its
own generator, so it is checked in distribution (for a few triplets `qrm.single_observation`
and the baselines' histograms agree within sampling noise).

Timing, the same for every implementation: one process per thread count (qrm's pool and
numba's are pinned by RAYON_NUM_THREADS / NUMBA_NUM_THREADS when the process starts), the
implementations of that count run in interleaved rounds (round r runs each once, in turn),
and each keeps its best wall time and its best CPU time (`time.process_time`, every thread of
the process) over --repeat rounds; a timing is a batch of calls lasting about 50 ms, divided
by the number of calls (the CPU time of worker threads is only accounted at the scheduler's
ticks, so one short call would miss it), after 50 ms of quiet (`SETTLE`: numba's OpenMP
workers spin on after a parallel loop and would slow whatever is timed next). The table gives both; every ratio is against the
**strongest baseline** of the same thread count (the fastest by wall time), named in the
output. `numba-frames, drawn before` times the fair kernel on samples drawn outside the clock
(what the kernel alone costs; not a baseline, since qrm's figure includes its draws).

Usage (workspace root; a venv with numpy, numba and the qrm wheel):
    python crates/qrm-py/benches/sampling_numpy.py [--repeat 40] [--threads 1,2] [--json OUT]
This script lives with the wheel it imports (qrm-py), above the kernel crates.
"""
from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import time
from typing import Callable, Dict, List, Optional

import numpy as np

M, S, SIGMA = 10, 1000, 10.0
BATCH = 0.05  # seconds per timed batch of calls
# Seconds of quiet before each timed batch: numba's OpenMP workers spin for milliseconds after
# a parallel loop, and on two cores they took 7 % from whichever job was timed next (qrm's
# step: 0.252 ms alone and after a pause, 0.271 ms right after numba-frames-parallel).
SETTLE = 0.05
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

# The six orderings of an unordered triplet (i, j, k), i < j < k, as positions of the located
# point C in each ordering's frame, written in the base frame (x, y) of (i, j, k) with
# n = x² + y² and m = x² + (1 − y)²: (x, y); (−x, 1 − y); (−x/n, y/n); (x/n, 1 − y/n);
# (x/m, (1 − y)/m); (−x/m, (n − y)/m) — SixForms's table. Multiplying each EDC constraint by
# the positive 1, n or m turns it into the sign of one of seven base-frame quantities:
# bit 0 x > 0, 1 y > 0, 2 y > ½, 3 y > 1, 4 n > 1, 5 n > y, 6 n > 2y.
ORDERINGS = [(0, 1, 2), (1, 0, 2), (0, 2, 1), (2, 0, 1), (1, 2, 0), (2, 1, 0)]


def _six_states(key: int) -> List[int]:
    b = [(key >> g) & 1 for g in range(7)]
    nb = [1 - v for v in b]
    # (right of the ordering's first → second, within the circle about its first, about its
    # second, band of its y: [Y ≥ 0] + [Y ≥ ½] + [Y ≥ 1]), derived from the maps above
    answers = [
        (b[0], nb[4], nb[6], b[1] + b[2] + b[3]),
        (nb[0], nb[6], nb[4], nb[3] + nb[2] + nb[1]),
        (nb[0], b[4], b[2], b[1] + nb[6] + nb[5]),
        (b[0], b[2], b[4], b[5] + b[6] + nb[1]),
        (b[0], b[6], nb[2], nb[3] + nb[4] + nb[5]),
        (nb[0], nb[2], b[6], b[5] + b[4] + b[3]),
    ]
    return [_state(*a) for a in answers]


SIX = np.array([_six_states(k) for k in range(128)], dtype=np.int64)
UNORDERED = np.array(list(itertools.combinations(range(M), 3)), dtype=np.int64)
_ROW = {tuple(t): r for r, t in enumerate(TRIPLETS.tolist())}
# the row of TRIPLETS each ordering of each unordered triplet counts into
ROWS = np.array([[_ROW[tuple(int(t[p]) for p in o)] for o in ORDERINGS] for t in UNORDERED], dtype=np.int64)


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


def counts_frames(samples: np.ndarray, block: int = 8) -> np.ndarray:
    """The fair algorithm in NumPy: one base frame per unordered triplet (blocks of `block`
    triplets), the 7-bit key of the seven quantities, `np.bincount` per triplet, and the
    128 × 6 table folding each key's count into the six orderings' rows."""
    out = np.zeros((len(TRIPLETS), Q), dtype=np.int64)
    for s in range(0, len(UNORDERED), block):
        i, j, k = UNORDERED[s : s + block].T
        a, b, c = samples[i], samples[j], samples[k]
        dx = b[..., 0] - a[..., 0]
        dy = b[..., 1] - a[..., 1]
        vx = c[..., 0] - a[..., 0]
        vy = c[..., 1] - a[..., 1]
        inv = 1.0 / (dx * dx + dy * dy)
        x = -(dx * vy - dy * vx) * inv
        y = (dx * vx + dy * vy) * inv
        n = x * x + y * y
        key = (x > 0.0).astype(np.int64)
        for bit, q in enumerate((y > 0.0, y > 0.5, y > 1.0, n > 1.0, n > y, n > 2.0 * y), start=1):
            key |= q.astype(np.int64) << bit
        m = len(i)
        hist = np.bincount((key + 128 * np.arange(m)[:, None]).ravel(), minlength=128 * m).reshape(m, 128)
        for t in range(m):
            for o in range(6):
                np.add.at(out[ROWS[s + t, o]], SIX[:, o], hist[t])
    return out


def numba_kernels() -> Dict[str, Callable[[np.ndarray], np.ndarray]]:
    """The numba loops: `serial` / `parallel` forms of the 720-ordering loop and of the fair
    one-frame-per-unordered-triplet loop. Empty without numba."""
    try:
        import numba  # type: ignore[import-untyped]
    except ImportError:
        return {}

    lut, six = LUT.copy(), SIX.copy()

    # C's position in the frame of A → B for sample s (numba inlines it into both loops)
    @numba.njit(inline="always")
    def frame(samples: np.ndarray, ia: int, ib: int, ic: int, s: int) -> tuple:  # type: ignore[type-arg]
        ax, ay = samples[ia, s, 0], samples[ia, s, 1]
        dx = samples[ib, s, 0] - ax
        dy = samples[ib, s, 1] - ay
        vx = samples[ic, s, 0] - ax
        vy = samples[ic, s, 1] - ay
        inv = 1.0 / (dx * dx + dy * dy)
        return -(dx * vy - dy * vx) * inv, (dx * vx + dy * vy) * inv

    # Branch-free (a key and the table, as numpy-lut), and four sub-histograms taken in turn:
    # with one, consecutive samples that land in the same state wait on each other's
    # increment (21 ns per triplet-sample when tried here, 6.8 with four).
    @numba.njit
    def ordered(samples: np.ndarray, trip: np.ndarray, t: int, out: np.ndarray) -> None:
        ia, ib, ic = trip[t, 0], trip[t, 1], trip[t, 2]
        h = np.zeros((4, 32), np.int64)
        for s in range(samples.shape[1]):
            x, y = frame(samples, ia, ib, ic, s)
            key = (x >= 0.0) | ((x * x + y * y <= 1.0) << 1) | ((x * x + (y - 1.0) * (y - 1.0) <= 1.0) << 2)
            h[s & 3, key | (((y >= 0.0) + (y >= 0.5) + (y >= 1.0)) << 3)] += 1
        for k in range(32):
            out[t, lut[k]] += h[0, k] + h[1, k] + h[2, k] + h[3, k]

    # The fair loop: one base frame per unordered triplet gives all six orderings through the
    # signs of seven quantities (see ORDERINGS above) — SixForms's algebra, in numba.
    @numba.njit
    def frames(samples: np.ndarray, tri: np.ndarray, rows: np.ndarray, t: int, out: np.ndarray) -> None:
        ia, ib, ic = tri[t, 0], tri[t, 1], tri[t, 2]
        h = np.zeros((4, 128), np.int64)
        for s in range(samples.shape[1]):
            x, y = frame(samples, ia, ib, ic, s)
            n = x * x + y * y
            key = ((x > 0.0) | ((y > 0.0) << 1) | ((y > 0.5) << 2) | ((y > 1.0) << 3)
                   | ((n > 1.0) << 4) | ((n > y) << 5) | ((n > 2.0 * y) << 6))
            h[s & 3, key] += 1
        for k in range(128):
            c = h[0, k] + h[1, k] + h[2, k] + h[3, k]
            if c:
                for o in range(6):
                    out[rows[t, o], six[k, o]] += c

    @numba.njit
    def serial720(samples: np.ndarray, trip: np.ndarray) -> np.ndarray:
        out = np.zeros((trip.shape[0], 20), dtype=np.int64)
        for t in range(trip.shape[0]):
            ordered(samples, trip, t, out)
        return out

    @numba.njit(parallel=True)
    def parallel720(samples: np.ndarray, trip: np.ndarray) -> np.ndarray:
        out = np.zeros((trip.shape[0], 20), dtype=np.int64)
        for t in numba.prange(trip.shape[0]):
            ordered(samples, trip, t, out)
        return out

    @numba.njit
    def serial_frames(samples: np.ndarray, tri: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = np.zeros((rows.shape[0] * 6, 20), dtype=np.int64)
        for t in range(tri.shape[0]):
            frames(samples, tri, rows, t, out)
        return out

    @numba.njit(parallel=True)
    def parallel_frames(samples: np.ndarray, tri: np.ndarray, rows: np.ndarray) -> np.ndarray:
        out = np.zeros((rows.shape[0] * 6, 20), dtype=np.int64)
        for t in numba.prange(tri.shape[0]):
            frames(samples, tri, rows, t, out)
        return out

    return {
        "numba-720": lambda smp: serial720(smp, TRIPLETS),
        "numba-720-parallel": lambda smp: parallel720(smp, TRIPLETS),
        "numba-frames": lambda smp: serial_frames(smp, UNORDERED, ROWS),
        "numba-frames-parallel": lambda smp: parallel_frames(smp, UNORDERED, ROWS),
    }


def check_qrm_in_distribution(qrm, means: np.ndarray) -> None:  # type: ignore[no-untyped-def]
    """qrm's single-observation belief and the baselines' histogram of one ordered triplet
    agree within sampling noise (total variation < 0.03 at 20,000 samples each)."""
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


def qrm_step(qrm, means: np.ndarray) -> Callable[[], object]:  # type: ignore[no-untyped-def]
    """One `Pqrm.update` of a map that has seen every step before: draws, counts, filter."""
    edc = qrm.Calculus.builtin("edc")
    pq = qrm.Pqrm(edc, samples=S, orderings="all", seed=7)
    ids = np.arange(M, dtype=np.int64)
    cov = np.array([[SIGMA**2, 0.0, SIGMA**2]] * M)
    clock = itertools.count()

    def step() -> object:
        report = pq.update(float(next(clock)), ids, means, cov)
        if report["observed"] != len(TRIPLETS):
            sys.exit(f"qrm observed {report['observed']} sets, not {len(TRIPLETS)}")
        return report

    return step


def measure(threads: int, repeat: int) -> Dict[str, Dict[str, float]]:
    """Runs in a process whose pools are pinned to `threads`: every implementation of that
    thread count, interleaved rounds, best wall and best CPU seconds each."""
    try:
        import qrm
    except ImportError:
        sys.exit("install the qrm wheel into this venv: the baselines are checked against it")
    if qrm.worker_threads() != threads:
        sys.exit(f"qrm's pool has {qrm.worker_threads()} threads, not {threads}")
    rng = np.random.default_rng(1)
    means = rng.uniform(0, 100, size=(M, 2))
    check_qrm_in_distribution(qrm, means)
    nb = numba_kernels()
    if not nb:
        sys.exit("numba is not installed in this venv: the fair baseline is numba")
    kernels: Dict[str, Callable[[np.ndarray], np.ndarray]] = {}
    if threads == 1:
        kernels.update({"numpy-naive": counts_naive, "numpy-lut": counts_lut, "numpy-frames": counts_frames})
        kernels.update({k: v for k, v in nb.items() if not k.endswith("parallel")})
    else:
        kernels.update({k: v for k, v in nb.items() if k.endswith("parallel")})
    fixed = draw(np.random.default_rng(5), means)
    ref = counts_naive(fixed)
    for name, k in kernels.items():
        if not np.array_equal(k(fixed), ref):
            sys.exit(f"{name} counts differ from numpy-naive on the same samples: no comparison")
    jobs: Dict[str, Callable[[], object]] = {
        name: (lambda k=k: k(draw(rng, means))) for name, k in kernels.items()
    }
    fair = "numba-frames" + ("" if threads == 1 else "-parallel")
    pre = draw(np.random.default_rng(6), means)
    jobs[f"{fair}, drawn before"] = lambda: nb[fair](pre)
    jobs[f"qrm, {threads} thread{'s' if threads > 1 else ''}"] = qrm_step(qrm, means)
    best = {name: {"wall": float("inf"), "cpu": float("inf")} for name in jobs}
    # A batch of calls per timing, at least BATCH seconds: the CPU time of the process's
    # other threads is only brought up to date at the scheduler's ticks (a few ms), so a
    # single millisecond call would miss most of its workers' time.
    inner: Dict[str, int] = {}
    for name, f in jobs.items():
        f()  # warm-up (numba's compile, qrm's pool)
        w0 = time.perf_counter()
        f()
        inner[name] = max(1, int(BATCH / max(time.perf_counter() - w0, 1e-9)))
    for _ in range(repeat):
        for name, f in jobs.items():
            time.sleep(SETTLE)
            w0, c0 = time.perf_counter(), time.process_time()
            for _ in range(inner[name]):
                f()
            c1, w1 = time.process_time(), time.perf_counter()
            best[name]["wall"] = min(best[name]["wall"], (w1 - w0) / inner[name])
            best[name]["cpu"] = min(best[name]["cpu"], (c1 - c0) / inner[name])
    return best


def strongest(best: Dict[str, Dict[str, float]]) -> str:
    """The fastest baseline by wall time: not qrm, not a kernel timed without its draws."""
    baselines = [n for n in best if not n.startswith("qrm") and "drawn before" not in n]
    return min(baselines, key=lambda n: best[n]["wall"])


def report(threads: int, best: Dict[str, Dict[str, float]]) -> str:
    n = len(TRIPLETS) * S
    ours = next(name for name in best if name.startswith("qrm"))
    top = strongest(best)
    lines = [f"\n{threads} thread{'s' if threads > 1 else ''} (best of the rounds; ns per ordered triplet-sample)",
             f"{'implementation':<32} {'wall':>8} {'CPU':>8} {'÷ qrm (wall)':>13} {'÷ qrm (CPU)':>12}"]
    for name, t in best.items():
        mark = "  ← strongest baseline" if name == top else ""
        lines.append(f"{name:<32} {t['wall'] / n * 1e9:8.2f} {t['cpu'] / n * 1e9:8.2f} "
                     f"{t['wall'] / best[ours]['wall']:13.2f} {t['cpu'] / best[ours]['cpu']:12.2f}{mark}")
    lines.append(f"qrm against the strongest baseline ({top}): "
                 f"{best[top]['wall'] / best[ours]['wall']:.2f}x by wall time, "
                 f"{best[top]['cpu'] / best[ours]['cpu']:.2f}x by CPU time")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=40, help="interleaved rounds (best of)")
    ap.add_argument("--threads", default="1,2", help="thread counts, one process each")
    ap.add_argument("--json", help="also write the best times (seconds) here")
    ap.add_argument("--child", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.repeat < 1:
        sys.exit("--repeat must be at least 1")
    if args.child is not None:
        print(json.dumps(measure(args.child, args.repeat)))
        return
    try:
        counts = [int(v) for v in args.threads.split(",")]
    except ValueError:
        sys.exit(f"--threads: comma-separated thread counts, got {args.threads!r}")
    if any(t < 1 for t in counts):
        sys.exit("--threads: counts of at least 1")
    print(f"all baselines give count tables identical to numpy-naive's from the same samples; "
          f"qrm agrees with them in distribution (3 triplets, total variation < 0.03); "
          f"{args.repeat} interleaved rounds")
    out: Dict[str, Dict[str, Dict[str, float]]] = {}
    for t in counts:
        # BLAS threads pinned too: idle OpenBLAS servers spin and would count as CPU time
        env = dict(os.environ, RAYON_NUM_THREADS=str(t), NUMBA_NUM_THREADS=str(t), OMP_NUM_THREADS="1",
                   OPENBLAS_NUM_THREADS="1")
        run = subprocess.run([sys.executable, __file__, "--child", str(t), "--repeat", str(args.repeat)],
                             env=env, check=True, capture_output=True, text=True)
        best = json.loads(run.stdout.strip().splitlines()[-1])
        out[str(t)] = best
        print(report(t, best))
    if args.json:
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()
