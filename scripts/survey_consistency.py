#!/usr/bin/env python3
"""Does the survey agree with what every robot sees? (issue 35; a measurement, docs/calibration.md
"The survey against the robots")

A map is scored against the recording's survey, so a landmark pair whose distance *every* robot
sees differently from the survey — a landmark moved after the survey, a survey slip, an error
every robot's sensor makes alike — shows up as the map's error, and no model of the robots'
noise can hedge for it without the survey. This script measures how much of a map's
miscalibration sits there:

1. For every landmark pair seen together in at least `--min-frames` frames (the recording read
   as `qrm map` reads it: noise fitted, gross outliers gated), the median over frames of the
   distance seen minus the surveyed one. A pair is *off the survey* when that median is beyond
   `--off` metres (default 0.1 m, 3–5 % of the recordings' inter-cluster distances) and beyond
   three standard errors of the median (1.2533 · 1.4826 · MAD / √n): `qrm.survey_agreement`
   (`pqrm::survey`, what `qrm pqrm real` reports in `survey.csv`).
2. Each recording mapped with `qrm map` under each `--evidence` model, and its beliefs scored
   against the survey separately for the sets with no pair off the survey and the sets with
   one: accuracy, mean P(ML), ECE over ten equal P(ML) bins, log loss.

    python3 scripts/survey_consistency.py --qrm target/release/qrm ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Needs numpy, the qrm wheel (to read recordings and maps, and to classify the survey) and a built
`qrm`.
"""

import argparse
import itertools
import pathlib
import subprocess
import tempfile
from typing import Dict, Tuple

import numpy as np

import qrm

def ece(p_ml: np.ndarray, right: np.ndarray) -> float:
    bins = np.minimum((p_ml * 10).astype(int), 9)
    return float(sum(abs(right[bins == k].mean() - p_ml[bins == k].mean()) * (bins == k).sum()
                     for k in range(10) if (bins == k).any()) / len(p_ml))


def scored(qrm_bin: str, recording: pathlib.Path, calculus: str, evidence: str,
           survey: Dict[int, Tuple[float, float]], off: set) -> Dict[bool, np.ndarray]:
    """(P(ML), right, −ln P(truth)) per set with a surveyed state, split by 'has a pair off'."""
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run([qrm_bin, "map", "--format", "mrclam", "--input", str(recording),
                        "--calculus", calculus, "--evidence", evidence, "--out", tmp],
                       check=True, capture_output=True)
        m = qrm.Pqrm.load(str(pathlib.Path(tmp) / "map.json"))
    cal = qrm.Calculus.builtin(calculus)
    c = m.columns()
    sets = [(int(a), int(b), int(d)) for a, b, d in zip(c["a"], c["b"], c["c"])]
    sets = [s for s in sets if all(x in survey for x in s)]
    truth = cal.classify(np.array([[*survey[a], *survey[b], *survey[d]] for a, b, d in sets]))
    split: Dict[bool, list] = {False: [], True: []}
    for s, t in zip(sets, truth):
        p = np.asarray(m.belief(s))
        has_off = any(tuple(sorted(pr)) in off for pr in itertools.combinations(s, 2))
        split[has_off].append((p.max(), float(int(p.argmax()) == int(t)),
                               -np.log(max(float(p[int(t)]), 1e-300))))
    return {k: np.array(v) for k, v in split.items() if v}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qrm", default="target/release/qrm")
    ap.add_argument("--calculus", default="edc")
    ap.add_argument("--off", type=float, default=0.1, help="metres; a pair's median offset beyond it is off")
    ap.add_argument("--min-frames", type=int, default=5)
    ap.add_argument("--evidence", default="shared:2,shared:4,shared:8,shared:64,shared:inf")
    ap.add_argument("recordings", nargs="+", type=pathlib.Path)
    a = ap.parse_args()
    for rec in a.recordings:
        frames, survey = qrm.read_observations(str(rec), "mrclam")
        if survey is None:
            raise SystemExit(f"{rec} has no survey")
        agreement = qrm.survey_agreement(frames, survey, off=a.off, min_frames=a.min_frames)
        off = {(p, q): med for p, q, med, _ in agreement["off"]}
        print(f"## {rec.name}: {len(off)} of {agreement['pairs_seen']} landmark pairs off the survey by "
              f"more than {a.off} m (median over ≥ {a.min_frames} frames)\n")
        if off:
            print(", ".join(f"{p[0]}–{p[1]} {med:+.2f}" for p, med in sorted(off.items())) + "\n")
        print("| evidence | sets: no pair off / a pair off | accuracy | mean P(ML) | ECE | log loss |")
        print("|---|---|---|---|---|---|")
        for ev in a.evidence.split(","):
            parts = scored(a.qrm, rec, a.calculus, ev, survey, off)
            cells = []
            for stat in (lambda g: f"{len(g)}", lambda g: f"{g[:, 1].mean():.3f}",
                         lambda g: f"{g[:, 0].mean():.3f}", lambda g: f"{ece(g[:, 0], g[:, 1]):.3f}",
                         lambda g: f"{g[:, 2].mean():.3f}"):
                cells.append(" / ".join(stat(parts[k]) if k in parts else "—" for k in (False, True)))
            print(f"| {ev} | " + " | ".join(cells) + " |")
        print()


if __name__ == "__main__":
    main()
