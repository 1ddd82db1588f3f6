#!/usr/bin/env python3
"""How `qrm map` scales with the number of landmarks in view (issue 16 §3).

For each n, a recording of 5 scans that each see all n landmarks (isotropic σ between 0.2 and
0.8 m, landmarks spread over 60 × 60 m) is written as our observation CSV and mapped with
`qrm map --samples 1000 --map-format binary`, once per `--orderings` asked for (all: the
n(n−1)(n−2) ordered sets; canonical: the n(n−1)(n−2)/6 unordered ones, which is what plain
`qrm map` records above 64 landmarks). The script measures the wall time and the peak resident memory of the process (`wait4`), reads
the map's size in memory and the save time from summary.json (loading is timed by the
criterion bench `map_file` beside this script), and fits the exponent of time
and memory against the number of sets by least squares on log–log (n ≥ 40, where the fixed
costs no longer dominate).

    python crates/pqrm/benches/map_scaling.py [--qrm target/release/qrm] [--n 10,20,40,80,101,160]
        [--orderings all,canonical]

Standard library only. Prints a markdown table (the one in docs/performance.md).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

SCANS = 5
SAMPLES = 1000
# issue 16 §3: 1e6 ordered triplets (101 landmarks all in view) in <= 3 s and <= 300 MB peak
# on 2 cores, <= 200 bytes per stored set
GOAL_LANDMARKS = 101
GOAL_SECONDS = 3.0
GOAL_PEAK_MB = 300
# issue 37 §4: the same 1e6 ordered sets in <= 2 s of CPU with canonical orderings, <= 4 s
# with all six (CPU: user + system time of the process, every thread)
GOAL_CPU_SECONDS = {"canonical": 2.0, "all": 4.0}
GOAL_BYTES_PER_SET = 200


def write_recording(path: Path, n: int, seed: int) -> None:
    rng = random.Random(seed)
    landmarks = [(rng.uniform(-30, 30), rng.uniform(-30, 30), rng.uniform(0.2, 0.8)) for _ in range(n)]
    with path.open("w") as f:
        f.write("t,robot,landmark,x,y,cxx,cxy,cyy\n")
        for t in range(SCANS):
            for i, (x, y, s) in enumerate(landmarks):
                # the robot's estimate moves a little between scans
                f.write(
                    f"{t},1,{i},{x + rng.gauss(0, s / 4):.4f},{y + rng.gauss(0, s / 4):.4f},"
                    f"{s * s:.5f},0,{s * s:.5f}\n"
                )


def timed(cmd: list[str]) -> tuple[float, float, int]:
    """Wall seconds, CPU seconds (user + system, every thread) and peak resident set (bytes)
    of one child process."""
    start = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    wall = time.perf_counter() - start
    err = proc.stderr.read().decode() if proc.stderr else ""
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{err}")
    return wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss * 1024  # Linux reports KiB


def fit_exponent(xs: list[float], ys: list[float]) -> float:
    lx = [math.log(x) for x in xs]
    ly = [math.log(y) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qrm", default="target/release/qrm")
    ap.add_argument("--n", default="10,20,40,80,101,160")
    ap.add_argument("--orderings", default="all,canonical")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    qrm = str(Path(args.qrm).resolve())
    ns = [int(v) for v in args.n.split(",")]
    orderings = args.orderings.split(",")
    rows = []
    work = Path(tempfile.mkdtemp(prefix="qrm-map-scaling-"))
    try:
        for order, n in [(o, n) for o in orderings for n in ns]:
            rec = work / f"n{n}.csv"
            write_recording(rec, n, args.seed + n)
            out = work / f"map{n}"
            wall, cpu, rss = timed(
                [qrm, "map", "--format", "csv", "--input", str(rec), "--samples", str(SAMPLES),
                 "--map-format", "binary", "--orderings", order, "--seed", "0", "--out", str(out)]
            )
            summary = json.loads((out / "summary.json").read_text())
            sets = summary["n_sets"]
            per_set = 6 if summary["orderings"] == "canonical" else 1
            assert sets * per_set == n * (n - 1) * (n - 2), (n, order, sets)
            map_file = out / summary["map_file"]
            rows.append({
                "n": n,
                "orderings": summary["orderings"],
                "sets": sets,
                "seconds": wall,
                "cpu": cpu,
                "peak_mb": rss / 1e6,
                "map_mb": summary["map_bytes_in_memory"] / 1e6,
                "bytes_per_set": summary["map_bytes_in_memory"] / sets,
                "file_mb": map_file.stat().st_size / 1e6,
                "save_s": summary["save_seconds"],
            })
            r = rows[-1]
            print(
                f"{r['orderings']:9s} n={n:4d} sets={sets:>9,} {wall:7.2f} s ({cpu:.2f} s CPU)  peak {r['peak_mb']:7.1f} MB  "
                f"map {r['map_mb']:6.1f} MB ({r['bytes_per_set']:.0f} B/set)  file {r['file_mb']:6.1f} MB  "
                f"save {r['save_s']:.2f} s",
                file=sys.stderr,
            )
            shutil.rmtree(out)
    finally:
        shutil.rmtree(work, ignore_errors=True)
    print(f"\n`qrm map`, {SCANS} scans, every landmark in every scan, s = {SAMPLES}, EDC, "
          f"binary map; {os.cpu_count()} cores\n")
    print("| landmarks | orderings | sets | time (s) | CPU (s) | peak memory (MB) | map in memory (B/set) | file (MB) | save (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['n']} | {r['orderings']} | {r['sets']:,} | {r['seconds']:.2f} | {r['cpu']:.2f} | {r['peak_mb']:.0f} | "
              f"{r['bytes_per_set']:.0f} | {r['file_mb']:.1f} | {r['save_s']:.2f} |")
    print()
    for order in sorted({r["orderings"] for r in rows}):
        big = [r for r in rows if r["n"] >= 40 and r["orderings"] == order]
        if len(big) >= 2:
            xs = [r["n"] ** 3 for r in big]
            print(f"fitted exponents against n³ (n >= 40), {order}: "
                  f"time {fit_exponent(xs, [r['seconds'] for r in big]):.2f}, "
                  f"peak memory {fit_exponent(xs, [r['peak_mb'] for r in big]):.2f}")
    # the goals (16 §3), judged on the measurements above
    for r in rows:
        if r["n"] == GOAL_LANDMARKS:
            cpu_goal = GOAL_CPU_SECONDS[r["orderings"]]
            checks = [
                (f"time {r['seconds']:.2f} s <= {GOAL_SECONDS} s (issue 16)", r["seconds"] <= GOAL_SECONDS),
                (f"CPU {r['cpu']:.2f} s <= {cpu_goal} s (issue 37)", r["cpu"] <= cpu_goal),
                (f"peak {r['peak_mb']:.0f} MB <= {GOAL_PEAK_MB} MB", r["peak_mb"] <= GOAL_PEAK_MB),
                (f"{r['bytes_per_set']:.0f} B/set <= {GOAL_BYTES_PER_SET} B/set",
                 r["bytes_per_set"] <= GOAL_BYTES_PER_SET),
            ]
            print(f"goals at n = {GOAL_LANDMARKS}, {r['orderings']}: "
                  + "; ".join(f"{text}: {'met' if ok else 'NOT met'}" for text, ok in checks))


if __name__ == "__main__":
    main()
