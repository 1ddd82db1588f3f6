#!/usr/bin/env python3
"""The shared-error model read per set, its frames grouped by robot (issue 35; a candidate
that was measured and not built — docs/calibration.md).

Each recording is mapped once per group of frames (a robot, or a robot and a time block of
`--block` seconds) under eq. 2.10 (`evidence="independent"`), with the noise `qrm map
--noise auto` fits; a set's log-likelihood sums add over the groups. Its belief is then read
three ways and scored against the survey (error, ECE over qrm's P(ML) bins, largest gap over
bins of ≥ 30 sets, log loss):
- eq. 2.10 (τ = 1);
- the shared model at constant N (τ = 1/√(n(1 + n/N)), `crates/pqrm/src/evidence.rs`);
- grouped: τ = √n_eff / n with n_eff = Σ_g 1/(ρ + (1 − ρ)/n_g), n_g the set's frames in group
  g — frames within a group share a fraction ρ of their error, groups none;
- with `--two-level`: each group's frames capped as the shared model caps a set's
  (n_g/(1 + n_g/N_r)), the groups added, and the sum capped again by an error every group
  shares (n_eff = 1/(1/Σ_g … + 1/N_c)), over a grid of N_r and N_c.

`--gate` reads the recording as `qrm map` does (noise fitted, gross outliers gated); without it
the fitted noise is used and every detection kept (the reading of 2026-11-28).

    python3 scripts/shared_error_groups.py --qrm target/release/qrm ../shared/data/mrclam-dataset2 \\
        ../shared/data/mrclam-dataset5 ../shared/data/mrclam-dataset7

Needs numpy, the qrm wheel and a built `qrm` (for the fitted noise).
"""

import argparse
import collections
import json
import pathlib
import subprocess
import tempfile

import numpy as np

import qrm

EDGES = [0.0, 0.5, 0.7, 0.8, 0.9, 0.95, 0.99, 0.999, 1.0]  # pqrm::calibration::EDGES


def score(p: np.ndarray, truth: np.ndarray):
    p_ml, ml = p.max(1), p.argmax(1)
    right = ml == truth
    log_loss = -np.log(np.maximum(p[np.arange(len(p)), truth], 1e-300)).mean()
    bins = np.clip(np.searchsorted(EDGES, p_ml, side="right") - 1, 0, len(EDGES) - 2)
    ece = gap = 0.0
    for k in range(len(EDGES) - 1):
        m = bins == k
        if m.any():
            g = abs(right[m].mean() - p_ml[m].mean())
            ece += m.sum() / len(p) * g
            if m.sum() >= 30:
                gap = max(gap, g)
    return 1 - right.mean(), ece, gap, log_loss


def fitted_noise(qrm_bin: str, recording: pathlib.Path):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([qrm_bin, "map", "--format", "mrclam", "--input", str(recording), "--noise", "auto",
                        "--calculus", "left-right", "--out", out], check=True, capture_output=True)
        fit = json.load(open(pathlib.Path(out) / "summary.json"))["noise_fit"]
    return fit["sigma_range"], fit["sigma_bearing"]


def grouped_sums(recording: pathlib.Path, calculus: str, block: float, noise, gate: bool):
    if gate:
        frames, truth = qrm.read_observations(str(recording), "mrclam", noise="auto")
    else:
        frames, truth = qrm.read_observations(str(recording), "mrclam", sigma_range=noise[0],
                                              sigma_bearing=noise[1])
    maps = {}
    for f in frames:
        if len(f["ids"]) < 3:
            continue
        g = (f["robot"], int(f["t"] // block) if block else 0)
        if g not in maps:
            maps[g] = qrm.Pqrm(qrm.Calculus.builtin(calculus), evidence="independent", seed=len(maps))
        maps[g].update(f["t"], f["ids"], f["xy"], f["cov"], robot=f["robot"])
    sums = collections.defaultdict(float)
    frames_per_group = collections.defaultdict(list)
    for m in maps.values():
        updates = m.columns()["updates"]
        for i, s in enumerate(m.sets()):
            b = m.belief(s)
            assert b is not None
            sums[s] = sums[s] + np.log(np.maximum(b, 1e-300))
            frames_per_group[s].append(int(updates[i]))
    assert truth is not None, "the recording has no survey"
    sets = [s for s in sums if all(x in truth for x in s)]
    points = np.array([[*truth[a], *truth[b], *truth[c]] for a, b, c in sets])
    return (np.array([sums[s] for s in sets]), [frames_per_group[s] for s in sets],
            qrm.Calculus.builtin(calculus).classify(points))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--qrm", default="target/release/qrm")
    ap.add_argument("--calculus", default="edc")
    ap.add_argument("--block", type=float, default=0.0, help="time block (s); 0: one group per robot")
    ap.add_argument("--gate", action="store_true", help="read as qrm map does: gross outliers gated")
    ap.add_argument("--two-level", action="store_true", help="also the two-level readings (N_r, N_c)")
    ap.add_argument("recordings", nargs="+", type=pathlib.Path)
    a = ap.parse_args()
    print("| recording | reading | error | ECE | largest gap | log loss |")
    print("|---|---|---|---|---|---|")
    for rec in a.recordings:
        noise = None if a.gate else fitted_noise(a.qrm, rec)
        sums, groups, truth = grouped_sums(rec, a.calculus, a.block, noise, a.gate)
        n = np.array([sum(g) for g in groups], dtype=float)

        def read(tau: np.ndarray) -> np.ndarray:
            x = sums * tau[:, None]
            x -= x.max(1, keepdims=True)
            e = np.exp(x)
            return e / e.sum(1, keepdims=True)

        readings = [("eq. 2.10", np.ones(len(n)))]
        readings += [(f"shared:{big}", 1 / np.sqrt(n * (1 + n / big))) for big in (2, 4, 32)]
        for rho in (0.1, 0.5, 0.9):
            n_eff = np.array([sum(1 / (rho + (1 - rho) / k) for k in g) for g in groups])
            readings.append((f"grouped ρ = {rho}", np.sqrt(n_eff) / n))
        if a.two_level:
            for n_r in (1, 2, 4, 8):
                pooled = np.array([sum(k / (1 + k / n_r) for k in g) for g in groups])
                for n_c in (2, 4, 8, 16, 32, 64, np.inf):
                    n_eff = 1 / (1 / pooled + 1 / n_c)
                    readings.append((f"two-level N_r = {n_r}, N_c = {n_c:g}", np.sqrt(n_eff) / n))
        for name, tau in readings:
            err, ece, gap, ll = score(read(tau), truth)
            print(f"| {rec.name} | {name} | {err:.3f} | {ece:.3f} | {gap:.3f} | {ll:.3f} |")


if __name__ == "__main__":
    main()
