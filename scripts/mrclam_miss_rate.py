#!/usr/bin/env python3
"""Measures how often a real landmark detector misses a landmark it can see: the default
miss rate of Q-Link's erring robot (`qlink::robot::MISS_RATE`).

MRCLAM's robots detect barcoded landmarks with a camera at about 4 frames a second (frames
0.24 s apart: the median gap between consecutive measurement times). A landmark detected on
one frame and again two frames later was in view in between (the robots move a few
centimetres a frame) and was missed on the middle frame. So, over every pair of successive
detections of one subject by one robot, with gaps of one frame (n1) or two (n2):

    miss rate ≈ n2 / (n1 + n2)

Gaps of three frames and more are left out (they mix misses with leaving the view). Printed
per recording and pooled.

    python3 scripts/mrclam_miss_rate.py ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Standard library only.
"""

import argparse
import collections
import pathlib
import statistics
import sys


def detections(path):
    """(time, subject) per line of a MRCLAM measurement file."""
    out = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            if line.startswith("#") or not line.strip():
                continue
            parts = line.split()
            try:
                out.append((float(parts[0]), int(parts[1])))
            except (IndexError, ValueError) as e:
                sys.exit(f"{path}:{number}: expected `time subject range bearing`: {e}")
    return out


def gaps(recording):
    """The frame period (the median gap between a robot's successive measurement times) and
    the one-frame and two-frame gaps between successive detections of a subject, over every
    robot of a recording."""
    files = sorted(pathlib.Path(recording).glob("Robot*_Measurement.dat"))
    if not files:
        sys.exit(f"{recording}: no Robot*_Measurement.dat")
    per_robot = [detections(f) for f in files]
    frames = []
    for rows in per_robot:
        times = sorted({t for t, _ in rows})
        frames += [b - a for a, b in zip(times, times[1:])]
    if not frames:
        sys.exit(f"{recording}: fewer than two measurement times")
    frame = statistics.median(frames)
    n1 = n2 = 0
    for rows in per_robot:
        seen = collections.defaultdict(list)
        for t, s in rows:
            seen[s].append(t)
        for ts in seen.values():
            ts.sort()
            for a, b in zip(ts, ts[1:]):
                k = round((b - a) / frame)
                n1 += k == 1
                n2 += k == 2
    return frame, n1, n2


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("recordings", nargs="+")
    args = ap.parse_args()
    print("| recording | frame (s) | one-frame gaps | two-frame gaps | miss rate |")
    print("|---|---|---|---|---|")
    total1 = total2 = 0
    for r in args.recordings:
        frame, n1, n2 = gaps(r)
        total1, total2 = total1 + n1, total2 + n2
        print(f"| {pathlib.Path(r).name} | {frame:.3f} | {n1} | {n2} | {n2 / (n1 + n2):.3f} |")
    print(f"| pooled | | {total1} | {total2} | {total2 / (total1 + total2):.3f} |")


if __name__ == "__main__":
    main()
