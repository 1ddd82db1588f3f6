#!/usr/bin/env python3
"""Chooses the shared-error model's N (`pqrm::evidence`) by leaving one recording out.

For every N of the grid, `qrm pqrm real` maps every recording given (one run, `--input`
repeated) and writes `recordings.csv`: per recording and calculus the error, the majority
vote, ECE, the largest bin gap, the map's log loss and the smoothed vote's. Then, for each
recording held out, N is the grid value with the lowest log loss on the *other* recordings
(summed over every calculus), and the held-out recording is scored at that N. Printed as
Markdown: the choice per fold, and the held-out scores beside eq. 2.10 and the smoothed vote.

    python3 scripts/evidence_loro.py --qrm target/release/qrm \\
        ../shared/data/mrclam-dataset2 ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Needs only the standard library and a built `qrm`. Takes about 10 s per grid value and gate
setting for the three MRCLAM recordings on 2 cores.
"""

import argparse
import csv
import pathlib
import statistics
import subprocess
import sys
import tempfile

GRID = ["0.5", "1", "2", "4", "8", "16", "32", "64", "128", "inf"]


def run(qrm, inputs, evidence, gate, out):
    cmd = [qrm, "pqrm", "real", "--gate", gate, "--evidence", evidence, "--out", str(out)]
    for i in inputs:
        cmd += ["--input", str(i)]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    rows = {}
    for r in csv.DictReader(open(out / "recordings.csv")):
        rows[(r["recording"], r["calculus"])] = r
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qrm", default="target/release/qrm")
    ap.add_argument("--gate", choices=["true", "false", "both"], default="both")
    ap.add_argument("--calculi", default="edc,double-cross,left-right",
                    help="calculi shown in the held-out table (all are summed for the choice)")
    ap.add_argument("inputs", nargs="+", type=pathlib.Path)
    a = ap.parse_args()
    if len(a.inputs) < 2:
        sys.exit("leave-one-out needs two or more recordings")
    shown = a.calculi.split(",")
    gates = ["true", "false"] if a.gate == "both" else [a.gate]
    with tempfile.TemporaryDirectory() as tmp:
        for gate in gates:
            runs = {}
            for n in GRID + ["independent"]:
                evidence = n if n == "independent" else f"shared:{n}"
                print(f"gate {gate}, {evidence} …", file=sys.stderr, flush=True)
                runs[n] = run(a.qrm, a.inputs, evidence, gate,
                              pathlib.Path(tmp) / f"{gate}-{n}")
            recs = sorted({k[0] for k in runs["1"]})
            calculi = sorted({k[1] for k in runs["1"]})
            print(f"\n### gate {gate}\n")
            print("| held out | N chosen on the others | calculus | error / vote | ECE | "
                  "largest gap | log loss: model / eq. 2.10 / smoothed vote |")
            print("|---|---|---|---|---|---|---|")
            chosen = []
            for held in recs:
                others = [r for r in recs if r != held]
                loss = {n: sum(float(runs[n][(r, c)]["log_loss"]) for r in others for c in calculi)
                        for n in GRID}
                best = min(GRID, key=lambda n: loss[n])
                chosen.append(best)
                for c in shown:
                    if (held, c) not in runs[best]:
                        continue
                    m, p = runs[best][(held, c)], runs["independent"][(held, c)]
                    f = lambda k, r=m: float(r[k])
                    print(f"| {held} | {best} | {c} | {f('error_rate'):.3f} / "
                          f"{f('majority_error_rate'):.3f} | {f('ece'):.3f} | {f('max_gap'):.3f} | "
                          f"{f('log_loss'):.3f} / {float(p['log_loss']):.3f} / "
                          f"{f('vote_log_loss'):.3f} |")
            finite = [float(n) for n in chosen if n != "inf"]
            if finite:
                print(f"\nchosen per fold: {', '.join(chosen)}; median of the finite ones "
                      f"{statistics.median(finite):g}")


if __name__ == "__main__":
    main()
