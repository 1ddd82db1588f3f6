#!/usr/bin/env python3
"""Where MRCLAM's shared error lives, seen against the survey (issue 35): does a landmark's
error depend on where it is seen from, and on how far?

For every scan that sees at least four surveyed landmarks, the survey is fitted to the scan by
a rotation and a translation (Procrustes, no scale); each detection's residual is taken in the
survey's frame, with the direction from the landmark to the robot. Scans with a residual over
1 m (a misidentified barcode) are left out. Printed per recording:

1. The covariance of one landmark's residuals between two detections at least 30 s apart, by
   the angle between their viewing directions, for the same robot and for different robots
   (cm²). An error tied to the landmark alone is the same from every side; one that depends
   on the viewpoint (a cylinder ranged at its near surface, a barcode off its centre) falls
   with the angle and turns negative for opposite views; one of the robot's own shows only
   in the same-robot column.
2. The relative error of the distance between two landmarks seen in one scan, by the mean
   range at which they were seen — a range-dependent bias the robots share.

With `--landmark L`: the distance from L to each other landmark as the robots see it in one
scan, against the survey. With `--triplet A,B,C`: where C is in the frame A → B (x: right of
AB, y: along it, in |AB|; the EDC's boundaries are x = 0, y = 0, ½, 1 and the unit circles
about A and B) in the survey and in every scan that saw all three, per robot.

No qrm needed, only NumPy:
    python3 scripts/shared_error_views.py ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7
    python3 scripts/shared_error_views.py ../shared/data/mrclam-dataset5 --triplet 17,14,20 --landmark 20
"""
from __future__ import annotations

import argparse
import collections
from pathlib import Path
from typing import Dict, List, Tuple

import numpy as np

Scans = Dict[Tuple[int, float], Dict[int, Tuple[float, float]]]


def numbers(path: Path) -> List[List[float]]:
    return [[float(v) for v in line.split()] for line in path.read_text().splitlines() if line.strip() and not line.startswith("#")]


def load(d: Path) -> Tuple[Dict[int, np.ndarray], Scans]:
    survey = {int(r[0]): np.array(r[1:3]) for r in numbers(d / "Landmark_Groundtruth.dat")}
    subject = {int(r[1]): int(r[0]) for r in numbers(d / "Barcodes.dat")}
    scans: Scans = collections.defaultdict(dict)
    for robot in range(1, 6):
        path = d / f"Robot{robot}_Measurement.dat"
        if not path.exists():
            continue
        for t, code, rng, bearing in numbers(path):
            s = subject.get(int(code))
            if s in survey:
                scans[(robot, t)].setdefault(s, (rng, bearing))  # a repeat in one scan: the first
    return survey, scans


def procrustes(p: np.ndarray, q: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """R, t minimising |R p + t − q| (rotation only, no reflection, no scale)."""
    pc, qc = p.mean(0), q.mean(0)
    u, _, vt = np.linalg.svd((p - pc).T @ (q - qc))
    r = vt.T @ u.T
    if np.linalg.det(r) < 0:
        vt[-1] *= -1
        r = vt.T @ u.T
    return r, qc - r @ pc


def residuals(survey: Dict[int, np.ndarray], scans: Scans) -> np.ndarray:
    """Rows: robot, landmark, time, residual x, y (survey frame), view direction x, y."""
    rows = []
    for (robot, t), obs in scans.items():
        if len(obs) < 4:
            continue
        ids = sorted(obs)
        p = np.array([survey[i] for i in ids])
        q = np.array([[obs[i][0] * np.cos(obs[i][1]), obs[i][0] * np.sin(obs[i][1])] for i in ids])
        r, t_ = procrustes(p, q)
        res = q - (p @ r.T + t_)
        if np.abs(res).max() > 1.0:
            continue
        robot_at = r.T @ (-t_)
        for k, i in enumerate(ids):
            view = robot_at - survey[i]
            view /= np.linalg.norm(view)
            g = r.T @ res[k]
            rows.append((robot, i, t, g[0], g[1], view[0], view[1]))
    return np.array(rows)


def view_covariance(a: np.ndarray, rng: np.random.Generator) -> None:
    edges = np.radians([0, 30, 60, 90, 120, 150, 180])
    same: Dict[int, List[float]] = collections.defaultdict(list)
    diff: Dict[int, List[float]] = collections.defaultdict(list)
    for lm in np.unique(a[:, 1]):
        m = a[a[:, 1] == lm]
        n = len(m)
        if n < 10:
            continue
        idx = rng.integers(0, n, size=(min(20000, n * n), 2))
        x, y = m[idx[:, 0]], m[idx[:, 1]]
        keep = np.abs(x[:, 2] - y[:, 2]) > 30
        x, y = x[keep], y[keep]
        dot = x[:, 3] * y[:, 3] + x[:, 4] * y[:, 4]
        angle = np.arccos(np.clip(x[:, 5] * y[:, 5] + x[:, 6] * y[:, 6], -1, 1))
        b = np.minimum(np.digitize(angle, edges) - 1, 5)
        one = x[:, 0] == y[:, 0]
        for k in range(6):
            same[k].extend(dot[(b == k) & one])
            diff[k].extend(dot[(b == k) & ~one])
    print("  angle between views | same robot: cov (cm²) [pairs] | different robots: cov (cm²) [pairs]")
    for k in range(6):
        s, d = np.array(same[k]), np.array(diff[k])
        fmt = lambda v: f"{1e4 * v.mean():7.1f} [{len(v)}]" if len(v) else "      – [0]"
        print(f"  {np.degrees(edges[k]):4.0f}–{np.degrees(edges[k + 1]):3.0f}° | {fmt(s)} | {fmt(d)}")


def distance_bias(survey: Dict[int, np.ndarray], scans: Scans) -> None:
    rel, mean_range = [], []
    for obs in scans.values():
        ids = sorted(obs)
        at = {i: np.array([obs[i][0] * np.cos(obs[i][1]), obs[i][0] * np.sin(obs[i][1])]) for i in ids}
        for x in range(len(ids)):
            for y in range(x + 1, len(ids)):
                i, j = ids[x], ids[y]
                true = np.linalg.norm(survey[i] - survey[j])
                rel.append((np.linalg.norm(at[i] - at[j]) - true) / true)
                mean_range.append((obs[i][0] + obs[j][0]) / 2)
    rel_a, r_a = np.array(rel), np.array(mean_range)
    print("  mean range (m) | pair sightings | (seen − surveyed)/surveyed distance: median, mean")
    for lo, hi in [(0, 2), (2, 3), (3, 4), (4, 5), (5, 9)]:
        m = (r_a >= lo) & (r_a < hi)
        if m.sum() > 20:
            print(f"  {lo}–{hi} | {m.sum():6d} | {np.median(rel_a[m]):+.3f}, {rel_a[m].mean():+.3f}")


def point(obs: Dict[int, Tuple[float, float]], i: int) -> np.ndarray:
    return np.array([obs[i][0] * np.cos(obs[i][1]), obs[i][0] * np.sin(obs[i][1])])


def pair_distances(survey: Dict[int, np.ndarray], scans: Scans, lm: int) -> None:
    seen: Dict[int, List[float]] = collections.defaultdict(list)
    for obs in scans.values():
        if lm in obs:
            for j in obs:
                if j != lm:
                    seen[j].append(float(np.linalg.norm(point(obs, j) - point(obs, lm))))
    print(f"  landmark {lm}: other | surveyed distance (m) | seen − surveyed, median (m) | scans")
    for j in sorted(seen):
        true = np.linalg.norm(survey[j] - survey[lm])
        print(f"  {j} | {true:.2f} | {np.median(seen[j]) - true:+.3f} | {len(seen[j])}")


def frame(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> Tuple[float, float]:
    """C in the frame A → B as qrm computes it: x = −cross/|AB|², y = dot/|AB|²."""
    d, v = b - a, c - a
    den = float(d @ d)
    return (d[1] * v[0] - d[0] * v[1]) / den, float(d @ v) / den


def triplet_frames(survey: Dict[int, np.ndarray], scans: Scans, abc: Tuple[int, int, int]) -> None:
    a, b, c = abc
    x, y = frame(survey[a], survey[b], survey[c])
    print(f"  triplet {a},{b},{c}: surveyed x {x:+.3f}, y {y:+.3f}, |AB| {np.linalg.norm(survey[b] - survey[a]):.2f} m")
    per: Dict[int, List[Tuple[float, float, float]]] = collections.defaultdict(list)
    for (robot, t), obs in scans.items():
        if all(i in obs for i in abc):
            per[robot].append((t, *frame(point(obs, a), point(obs, b), point(obs, c))))
    if not per:
        print("  no scan saw all three")
        return
    t0 = min(v[0] for rows in per.values() for v in rows)
    for robot in sorted(per):
        r = np.array(per[robot])
        print(
            f"  robot {robot}: {len(r)} scans, x {r[:, 1].mean():+.3f} ± {r[:, 1].std():.3f}, "
            f"y {r[:, 2].mean():+.3f} ± {r[:, 2].std():.3f}, seen {r[:, 0].min() - t0:.0f}–{r[:, 0].max() - t0:.0f} s"
        )


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("recordings", nargs="+", type=Path)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--landmark", type=int, help="also: the distances from this landmark, seen and surveyed")
    ap.add_argument("--triplet", help="also: where C is in the frame A → B, surveyed and seen (A,B,C)")
    args = ap.parse_args()
    triplet = tuple(int(v) for v in args.triplet.split(",")) if args.triplet else None
    if triplet is not None and len(triplet) != 3:
        ap.error("--triplet takes three landmark ids, A,B,C")
    for d in args.recordings:
        survey, scans = load(d)
        a = residuals(survey, scans)
        print(f"== {d.name}: {len(a)} detections in scans of four or more surveyed landmarks")
        view_covariance(a, np.random.default_rng(args.seed))
        distance_bias(survey, scans)
        for lm in [args.landmark] if args.landmark is not None else []:
            if lm not in survey:
                ap.error(f"{d}: landmark {lm} is not surveyed")
            pair_distances(survey, scans, lm)
        if triplet is not None:
            missing = [i for i in triplet if i not in survey]
            if missing:
                ap.error(f"{d}: landmarks {missing} are not surveyed")
            triplet_frames(survey, scans, triplet)  # type: ignore[arg-type]


if __name__ == "__main__":
    main()
