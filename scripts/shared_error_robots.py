#!/usr/bin/env python3
"""Where a recording's shared error lives: within a robot, or common to every robot (issue 35;
a measurement, docs/calibration.md "Where the shared error lives").

Each recording is mapped with `qrm map` as a user maps it (noise fitted, gross outliers gated)
under eq. 2.10 (`--evidence independent`), once with every robot and once per robot. Each
map's beliefs are then read under the shared-error model at N on a grid
(τ(n) = 1/√(n(1 + n/N)), `crates/pqrm/src/evidence.rs`) and scored:
- against the survey (log loss, ECE over ten equal P(ML) bins): the N that the pooled map and
  the per-robot maps want;
- without truth, robot against robot: for every set two robots both saw, ln(Q · Σ_s p_i(s)
  p_j(s)) — how much robot i's belief predicts robot j's over chance. It is highest where the
  maps are as sharp as the robots' *disagreement* allows, so it sees the error a robot has
  alone and not the error every robot shares.

    python3 scripts/shared_error_robots.py --qrm target/release/qrm ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Needs numpy, the qrm wheel (to read the maps and classify the survey) and a built `qrm`.
"""

import argparse
import itertools
import json
import pathlib
import subprocess
import tempfile

import numpy as np

import qrm

GRID = [0.5, 1, 2, 4, 8, 16, 32, 64, 128, float("inf")]


def tau(n: float, big: float) -> float:
    return 1 / np.sqrt(n * (1 + n / big)) if np.isfinite(big) else 1 / np.sqrt(n)


def tempered(log_p: np.ndarray, t: float) -> np.ndarray:
    x = t * log_p
    e = np.exp(x - x.max())
    return e / e.sum()


def mapped(qrm_bin: str, recording: pathlib.Path, calculus: str, out: pathlib.Path, robot=None):
    """A set's log-belief under eq. 2.10 and its frame count, per ordered set."""
    cmd = [qrm_bin, "map", "--format", "mrclam", "--input", str(recording), "--calculus", calculus,
           "--evidence", "independent", "--out", str(out)]
    if robot is not None:
        cmd += ["--robots", str(robot)]
    subprocess.run(cmd, check=True, capture_output=True)
    m = qrm.Pqrm.load(str(out / "map.json"))
    c = m.columns()
    sets = {}
    for a, b, d, n in zip(c["a"], c["b"], c["c"], c["updates"]):
        s = (int(a), int(b), int(d))
        p = m.belief(s)
        assert p is not None
        sets[s] = (np.log(np.maximum(p, 1e-300)), int(n))
    return sets, json.load(open(out / "summary.json"))


def scores(beliefs: dict, truth: dict):
    """(log loss, ECE) over the sets with a surveyed state."""
    ll, p_ml, right = [], [], []
    for s, p in beliefs.items():
        if s in truth:
            ll.append(-np.log(max(p[truth[s]], 1e-300)))
            p_ml.append(p.max())
            right.append(int(p.argmax()) == truth[s])
    p_ml, right = np.array(p_ml), np.array(right)
    bins = np.minimum((p_ml * 10).astype(int), 9)
    ece = sum(abs(right[bins == k].mean() - p_ml[bins == k].mean()) * (bins == k).sum()
              for k in range(10) if (bins == k).any()) / len(p_ml)
    return float(np.mean(ll)), float(ece)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qrm", default="target/release/qrm")
    ap.add_argument("--calculus", default="edc")
    ap.add_argument("recordings", nargs="+", type=pathlib.Path)
    a = ap.parse_args()
    cal = qrm.Calculus.builtin(a.calculus)
    q = cal.n_states
    rows = []
    for rec in a.recordings:
        with tempfile.TemporaryDirectory() as tmp:
            tmp = pathlib.Path(tmp)
            pooled, summary = mapped(a.qrm, rec, a.calculus, tmp / "all")
            robots = sorted({int(r) for r in summary.get("robots", [])}) or [1, 2, 3, 4, 5]
            per_robot = [mapped(a.qrm, rec, a.calculus, tmp / f"r{r}", r)[0] for r in robots]
        _, survey = qrm.read_observations(str(rec), "mrclam")
        assert survey is not None, f"{rec} has no survey"
        known = [s for s in pooled if all(x in survey for x in s)]
        states = cal.classify(np.array([[*survey[a_], *survey[b], *survey[c]] for a_, b, c in known]))
        truth = dict(zip(known, (int(t) for t in states)))
        table = []
        for big in GRID:
            pooled_score = scores({s: tempered(lp, tau(n, big)) for s, (lp, n) in pooled.items()}, truth)
            read = [{s: tempered(lp, tau(n, big)) for s, (lp, n) in m.items()} for m in per_robot]
            robot_score = scores({(i, s): p for i, m in enumerate(read) for s, p in m.items()},
                                 {(i, s): t for i in range(len(read)) for s, t in truth.items()})
            agree = [np.log(q * max(float((mi[s] * mj[s]).sum()), 1e-300))
                     for mi, mj in itertools.combinations(read, 2) for s in mi.keys() & mj.keys()]
            table.append((big, pooled_score, robot_score, float(np.mean(agree)), len(agree)))
        best = lambda key: min(table, key=key)[0]  # noqa: E731
        rows.append((rec.name, best(lambda r: r[1][0]), best(lambda r: r[2][0]),
                     best(lambda r: -r[3]), table[0][4]))
        print(f"## {rec.name} ({a.calculus})\n")
        print("| N | pooled map: log loss / ECE | per-robot maps: log loss / ECE | robot against robot |")
        print("|---|---|---|---|")
        for big, ps, rs, agree, _ in table:
            print(f"| {big:g} | {ps[0]:.3f} / {ps[1]:.3f} | {rs[0]:.3f} / {rs[1]:.3f} | {agree:.3f} |")
        print()
    print("| recording | N the pooled map wants (survey) | N each robot's map wants (survey) | "
          "N robots agree best at (no survey) | pairs of robots' beliefs |")
    print("|---|---|---|---|---|")
    for name, pooled_n, robot_n, agree_n, pairs in rows:
        print(f"| {name} | {pooled_n:g} | {robot_n:g} | {agree_n:g} | {pairs} |")


if __name__ == "__main__":
    main()
