#!/usr/bin/env python3
"""Can a recording say how much error its frames share, without truth? (issue 35)

The shared-error model (`crates/pqrm/src/evidence.rs`) reads a set's frames with
N = σ² / σ_b²: how many independent frames the shared error is worth. Leaving one MRCLAM
recording out (docs/calibration.md) the recordings want different N (Dataset 7 near 32,
Dataset 5 near 2), so a per-recording estimate would beat any constant — if the recording
itself can give one.

The distance between two landmarks seen in one frame does not depend on the robot's pose.
This script splits its spread across frames, one landmark pair at a time, into a part within
groups of frames and a part between groups (one-way random effects, method of moments:
E[(group mean − pair mean)²] ≈ σ_b² + σ_w²/n_g), with groups = the robot (block 0) or the
robot and a time block of `--blocks` seconds; residuals over 1 m are dropped as gross
outliers. It prints σ_w, σ_b, their N = σ_w²/σ_b², and the rms distance of the group means
from the surveyed distance (which uses the truth, as a check).

    python3 scripts/shared_error_anova.py ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Standard library only. Measured 2026-11-28 (robot groups): N = 1.7, 1.1, 1.0 for Datasets 2,
5 and 7 — the same on all three, so this decomposition does not tell Dataset 7 from Dataset 5.
"""

import argparse
import collections
import math
import pathlib
import statistics


def load(d: pathlib.Path):
    barcodes = {}
    for line in open(d / "Barcodes.dat"):
        if not line.startswith("#"):
            subject, code = line.split()
            barcodes[int(code)] = int(subject)
    truth = {}
    for line in open(d / "Landmark_Groundtruth.dat"):
        if not line.startswith("#"):
            p = line.split()
            truth[int(p[0])] = (float(p[1]), float(p[2]))
    frames = []
    for robot in range(1, 6):
        by_time = collections.defaultdict(dict)
        for line in open(d / f"Robot{robot}_Measurement.dat"):
            if line.startswith("#"):
                continue
            t, code, rng, bearing = line.split()
            subject = barcodes.get(int(code))
            if subject is None or subject < 6:  # robots are subjects 1-5
                continue
            r, b = float(rng), float(bearing)
            by_time[t][subject] = (r * math.cos(b), r * math.sin(b))
        frames += [(robot, float(t), obs) for t, obs in by_time.items() if len(obs) >= 2]
    return truth, frames


def components(d: pathlib.Path, block: float):
    truth, frames = load(d)
    per_pair = collections.defaultdict(lambda: collections.defaultdict(list))
    for robot, t, obs in frames:
        ids = sorted(obs)
        for i, a in enumerate(ids):
            for b in ids[i + 1:]:
                (px, py), (qx, qy) = obs[a], obs[b]
                group = (robot, int(t // block)) if block else robot
                per_pair[(a, b)][group].append(math.hypot(px - qx, py - qy))
    within, df, between, sq_truth, n_truth = 0.0, 0, [], 0.0, 0
    for (a, b), groups in per_pair.items():
        everything = [x for g in groups.values() for x in g]
        if len(everything) < 5:
            continue
        median = statistics.median(everything)
        true = math.dist(truth[a], truth[b])
        means = []
        for values in groups.values():
            values = [x for x in values if abs(x - median) < 1.0]
            if len(values) >= 2:
                m = sum(values) / len(values)
                within += sum((x - m) ** 2 for x in values)
                df += len(values) - 1
                means.append((m, len(values)))
        if len(means) >= 2:
            grand = sum(m * n for m, n in means) / sum(n for _, n in means)
            between += [((m - grand) ** 2, n) for m, n in means]
            sq_truth += sum((m - true) ** 2 for m, _ in means)
            n_truth += len(means)
    sw2 = within / df
    sb2 = sum(e - sw2 / n for e, n in between) / len(between)
    return sw2, sb2, sq_truth / n_truth


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("recordings", nargs="+", type=pathlib.Path)
    ap.add_argument("--blocks", default="0,60,10", help="time blocks in s (0: one group per robot)")
    a = ap.parse_args()
    print("| recording | groups | σ_w (m) | σ_b (m) | N = σ_w²/σ_b² | rms group mean − survey (m) |")
    print("|---|---|---|---|---|---|")
    for d in a.recordings:
        for block in (float(b) for b in a.blocks.split(",")):
            sw2, sb2, rms2 = components(d, block)
            groups = "robot" if block == 0 else f"robot × {block:g} s"
            n = f"{sw2 / sb2:.1f}" if sb2 > 0 else "∞"
            print(f"| {d.name} | {groups} | {math.sqrt(sw2):.3f} | {math.sqrt(max(sb2, 0.0)):.3f} | {n} "
                  f"| {math.sqrt(rms2):.3f} |")


if __name__ == "__main__":
    main()
