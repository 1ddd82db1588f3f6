#!/usr/bin/env python3
"""qrm's binary reasoner against GQR itself: agreement and CPU time, network by network.

GQR (Gantner, Westphal, Wölfl 2008) is the standard C++ reasoner for binary qualitative
calculi. This script builds it from its source with g++ (``--gqr-source DIR``, a checkout of
m-westphal/gqr) or takes a built binary (``--gqr PATH``), and runs both reasoners on

* random networks in the standard model A(n, d, l) — n nodes, each pair constrained with
  probability d/(n-1) (average degree d), each constrained pair given a random set of base
  relations of mean size l — at degrees around each calculus's phase transition, and
* GQR's own example networks (``data/*/csp/*.csp``),

for path consistency (``gqr path-consistency`` / ``qrm reason close``; default) or consistency
(``--mode consistency``: ``gqr consistency`` / ``qrm reason scenario``). Both read the same
calculus files (GQR's ``.spec``) and the same ``.csp`` files. For every network it checks that
the verdicts agree and, for path consistency, that the closed networks are equal relation for
relation (consistency: the verdicts agree, and each solution qrm prints is atomic and refines
the input's constraints; that closure leaves a solution unchanged is checked by the reasoner's
own tests; with ``--split horn`` each set must be a member of the cover set, GQR's ``-c horn``).
A network qrm's search leaves undecided within ``--max-nodes`` is counted as "unknown", apart
from disagreements. Each reasoner is timed as a whole process (CPU = user +
system of the child, and wall clock), the two interleaved, best of ``--rounds``. The table
gives, per class, the median CPU time of each and their ratio (qrm ÷ GQR: below 1, qrm is
faster).

    python3 crates/qsr-core/benches/gqr_compare.py --gqr-source /path/to/gqr --quick

Exit status 1 when any verdict or closed network differs.
"""

from __future__ import annotations

import argparse
import os
import random
import re
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]

# Degrees around the phase transition (where about half the networks are path consistent), and
# the mean label size, per calculus: measured with this script at n = 100 and 200 (the share
# of consistent networks falls from ~0.8 to ~0.1 across each row's degrees). OPRA-2 networks
# with half of the 72 relations per label stay path consistent at any degree (its composition
# is weak), so its labels are smaller.
CLASSES = {
    "rcc8": {"l": 4.0, "d": [6.0, 8.0, 10.0]},
    "allen": {"l": 6.5, "d": [10.0, 12.0, 14.0]},
    "point": {"l": 1.5, "d": [1.5, 2.0, 2.5]},
    "opra2": {"l": 8.0, "d": [8.0, 12.0, 16.0]},
}

GQR_SOURCES = """utils/Timer.cpp utils/Logger.cpp Stringtools.cpp gqr.cpp PriorityQueue.cpp
Calculus.cpp CalculusReader.cpp CombinedCalculusReader.cpp CSPReader.cpp FileSplitter.cpp
RestartsFramework.cpp commands/SubcommandAbstract.cpp commands/SubcommandHelp.cpp
commands/SubcommandVersion.cpp commands/SubcommandCheck.cpp
commands/SubcommandPathConsistency.cpp commands/SubcommandConsistency.cpp""".split()


def build_gqr(source: Path, out: Path) -> Path:
    """GQR's own build is waf for Python 2; the same sources and flags (-O3 -DNDEBUG) by g++."""
    gqr = source / "gqr"
    (gqr / "config.h").write_text("")
    binary = out / "gqr"
    cmd = ["g++", "-O3", "-DNDEBUG", "-std=gnu++11", "-w", '-DGQR_VERSION="source"',
           f"-I{gqr}", f"-I{source}", *[str(gqr / s) for s in GQR_SOURCES], "-o", str(binary)]
    print("building GQR:", " ".join(cmd[:6]), "...", file=sys.stderr)
    subprocess.run(cmd, check=True)
    return binary


def read_calculus_labels(data: Path, name: str) -> list[str]:
    spec = (data / f"{name}.spec").read_text()
    conv = re.search(r"^converse_file\s+(\S+)", spec, re.M)
    labels = []
    for line in (data / conv.group(1)).read_text().splitlines():
        if "::" in line and not line.strip().startswith("#"):
            labels.append(line.split("::")[0].strip())
    return labels


def random_network(rng: random.Random, labels: list[str], n: int, d: float, l: float) -> str:
    """A(n, d, l): each pair constrained with probability d/(n-1); each base relation in a
    constrained pair's set with probability l/|B| (an empty draw is drawn again)."""
    p_edge = min(1.0, d / (n - 1))
    p_rel = min(1.0, l / len(labels))
    lines = [f"{n - 1} #A({n},{d},{l})"]
    for i in range(n):
        for j in range(i + 1, n):
            if rng.random() < p_edge:
                rels = []
                while not rels:
                    rels = [r for r in labels if rng.random() < p_rel]
                lines.append(f"{i} {j} ( {' '.join(rels)} )")
    lines.append(".")
    return "\n".join(lines) + "\n"


def timed(cmd: list[str], env: dict[str, str], cwd: Path) -> tuple[float, float, str]:
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, env=env, cwd=cwd)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    if proc.returncode not in (0, 1):
        raise SystemExit(
            f"{Path(cmd[0]).name} failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stderr.decode()[:2000]}")
    return cpu, wall, proc.stdout.decode()


def parse_gqr(out: str) -> list[tuple[bool, dict[tuple[int, int], frozenset[str]] | None]]:
    """GQR's output with -S: a verdict line per network (`#name: 0|1`), each followed, when
    the network is consistent, by the network in .csp form."""
    results = []
    current = None
    for line in out.splitlines():
        line = line.strip()
        if not line or line.startswith("["):
            continue
        m = re.match(r"^(.*): ([01])$", line)
        if m and not re.match(r"^\d+ \d+ \(", line):
            current = {} if m.group(2) == "1" else None
            results.append((m.group(2) == "1", current))
            continue
        m = re.match(r"^(\d+) (\d+) \((.*)\)$", line)
        if m and results and results[-1][1] is not None:
            results[-1][1][(int(m.group(1)), int(m.group(2)))] = frozenset(m.group(3).split())
    return results


def parse_qrm(out: str) -> list[tuple[bool, dict[tuple[int, int], frozenset[str]] | None]]:
    """qrm's `--output gqr`: per network `N #name status` and its .csp lines, then `.`."""
    results = []
    for block in out.split("\n.\n"):
        lines = [l for l in block.strip().splitlines() if l and not l.startswith("# points")]
        if not lines:
            continue
        header = lines[0]
        ok = header.endswith(" consistent") and not header.endswith("inconsistent")
        if header.endswith("unknown"):
            ok = None
        net = {}
        for line in lines[1:]:
            m = re.match(r"^(\d+) (\d+) \((.*)\)$", line.strip())
            if m:
                net[(int(m.group(1)), int(m.group(2)))] = frozenset(m.group(3).split())
        results.append((ok, net if ok else None))
    return results


def input_networks(csp: Path) -> list[dict[tuple[int, int], frozenset[str]]]:
    """Each network's constraints `i < j` as given (a pair given twice: the intersection;
    lines `j i` with j > i are left out: comparing them needs the converse)."""
    nets, cur, header = [], {}, True
    for line in csp.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if header:
            header, cur = False, {}
            nets.append(cur)
            continue
        if line.startswith("."):
            header = True
            continue
        m = re.match(r"^(\d+)\s+(\d+)\s*\((.*)\)", line)
        if m and int(m.group(1)) < int(m.group(2)):
            key, rels = (int(m.group(1)), int(m.group(2))), frozenset(m.group(3).split())
            cur[key] = cur.get(key, rels) & rels
    return nets


def self_constrained(csp: Path) -> set[int]:
    """Indices of the networks of a .csp file with a constraint `i i (...)`."""
    found, k, header = set(), 0, True
    for line in csp.read_text().splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if header:
            header = False
            continue
        if line.startswith("."):
            k, header = k + 1, True
            continue
        m = re.match(r"^(\d+)\s+(\d+)", line)
        if m and m.group(1) == m.group(2):
            found.add(k)
    return found


def same_network(a: dict, b: dict, universal: frozenset[str]) -> bool:
    keys = set(a) | set(b)
    return all(a.get(k, universal) == b.get(k, universal) for k in keys)


def compare(args, gqr, qrm, data, env, csp: Path, calculus: str, universal) -> tuple[list, list, bool]:
    gqr_mode = "pc" if args.mode == "path-consistency" else "c"
    qrm_mode = "close" if args.mode == "path-consistency" else "scenario"
    g_cmd = [str(gqr), gqr_mode, "-S", "-C", calculus, str(csp)]
    q_cmd = [str(qrm), "reason", qrm_mode, "--calculus", str(data / f"{calculus}.spec"),
             "--input", str(csp), "--output", "gqr"]
    if args.mode == "consistency":
        q_cmd += ["--max-nodes", str(args.max_nodes)]  # the default: 10^6 search nodes
        if split_members(data, calculus, args.split) is not None:
            # GQR's -c NAME reads DATA/CALCULUS/calculus/NAMEalg; qrm's --split finds the same.
            g_cmd[3:3] = ["-c", args.split]
            q_cmd += ["--split", args.split]
    g_best, q_best = [float("inf")] * 2, [float("inf")] * 2
    g_out = q_out = ""
    for _ in range(args.rounds):
        c, w, g_out = timed(g_cmd, env, data.parent)
        g_best = [min(g_best[0], c), min(g_best[1], w)]
        c, w, q_out = timed(q_cmd, env, data.parent)
        q_best = [min(q_best[0], c), min(q_best[1], w)]
    g_res, q_res = parse_gqr(g_out), parse_qrm(q_out)
    agree = len(g_res) == len(q_res)
    self_loops = self_constrained(csp)
    inputs = input_networks(csp)
    unknown = 0
    for k, ((g_ok, g_net), (q_ok, q_net)) in enumerate(zip(g_res, q_res)):
        if q_ok is None:
            # qrm's search ran out of --max-nodes: no verdict, counted apart (not a conflict).
            unknown += 1
            continue
        if g_ok and q_ok is False and k in self_loops:
            # GQR drops a constraint `i i (r)` (its CSPSparse stores the pair and never reads
            # it: its own data/point/csp/ex1.csp calls `0 0 (<)` "inconsistent-test-9" and
            # answers 1); qrm intersects it with the identity. Counted as explained.
            print(f"explained: {csp.name} network {k + 1}: GQR ignores a self-constraint without the identity",
                  file=sys.stderr)
            continue
        agree &= g_ok == q_ok
        if args.mode == "path-consistency" and g_ok and q_ok:
            agree &= same_network(g_net, q_net, universal)
        if args.mode == "consistency" and q_ok:
            # A solution's every set is a split (atomic without --split) and refines what the
            # input says of every pair i < j.
            given = inputs[k] if k < len(inputs) else {}
            members = split_members(data, calculus, args.split)
            if members is None:
                agree &= all(len(rels) == 1 for rels in q_net.values())
            else:
                agree &= all(rels in members for rels in q_net.values())
            agree &= all(q_net.get(key, universal) <= rels for key, rels in given.items())
    return g_best, q_best, agree, [ok for ok, _ in g_res], unknown


def split_members(data: Path, calculus: str, split: str | None) -> set[frozenset[str]] | None:
    """The members of GQR's cover set `split` (`DATA/CALCULUS/calculus/SPLITalg`), or None."""
    path = data / calculus / "calculus" / f"{split}alg"
    if not split or not path.is_file():
        return None  # no such cover set for this calculus: base relations
    text = (data / calculus / "calculus" / f"{split}alg").read_text(encoding="latin-1")
    return {frozenset(m.group(1).split()) for m in re.finditer(r"\(([^)]*)\)", text)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--gqr", type=Path, help="a built gqr binary")
    ap.add_argument("--gqr-source", type=Path, help="a GQR checkout to build (and its data/)")
    ap.add_argument("--data", type=Path, help="GQR's data directory (default: SOURCE/data)")
    ap.add_argument("--qrm", type=Path, default=ROOT / "target" / "release" / "qrm")
    ap.add_argument("--mode", choices=["path-consistency", "consistency"], default="path-consistency")
    ap.add_argument("--calculi", default="rcc8,allen,point,opra2")
    ap.add_argument("--sizes", default="50,100,200")
    ap.add_argument("--networks", type=int, default=10, help="networks per class")
    ap.add_argument("--rounds", type=int, default=3, help="interleaved timing rounds (best of)")
    ap.add_argument("--max-nodes", type=int, default=1_000_000)
    ap.add_argument("--split", help="consistency: split into this cover set (GQR's -c, e.g. horn)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quick", action="store_true", help="3 networks per class, sizes 50,100")
    ap.add_argument("--no-examples", action="store_true", help="skip GQR's example networks")
    args = ap.parse_args()
    if args.quick:
        args.networks, args.sizes = 3, "50,100"
    if not args.qrm.exists():
        ap.error(f"{args.qrm} not found: cargo build --release -p qrm-cli")
    work = Path(tempfile.mkdtemp(prefix="gqr-compare-"))
    try:
        if args.gqr:
            gqr = args.gqr.resolve()
        elif args.gqr_source:
            if not shutil.which("g++"):
                ap.error("no g++ to build GQR: pass --gqr PATH")
            gqr = build_gqr(args.gqr_source.resolve(), work)
        else:
            ap.error("give --gqr PATH or --gqr-source DIR")
        data = (args.data or (args.gqr_source / "data" if args.gqr_source else None))
        if data is None:
            ap.error("give --data DIR (GQR's data directory with the .spec files)")
        data = data.resolve()
        env = dict(os.environ, GQR_DATA_DIR=str(data), RAYON_NUM_THREADS="1")
        rng = random.Random(args.seed)
        failures = 0
        unknowns = 0
        rows = []
        for calculus in args.calculi.split(","):
            labels = read_calculus_labels(data, calculus)
            universal = frozenset(labels)
            cls = CLASSES.get(calculus, {"l": len(labels) / 2, "d": [8.0, 10.0, 12.0]})
            for n in map(int, args.sizes.split(",")):
                for d in cls["d"]:
                    g_cpu, q_cpu, g_wall, q_wall, cons, agree = [], [], [], [], 0, 0
                    for k in range(args.networks):
                        csp = work / f"{calculus}-{n}-{d}-{k}.csp"
                        csp.write_text(random_network(rng, labels, n, d, cls["l"]))
                        g, q, ok, verdicts, unk = compare(args, gqr, args.qrm, data, env, csp, calculus, universal)
                        unknowns += unk
                        g_cpu.append(g[0]); g_wall.append(g[1]); q_cpu.append(q[0]); q_wall.append(q[1])
                        cons += sum(bool(v) for v in verdicts)
                        agree += ok
                        if not ok:
                            failures += 1
                            kept = Path.cwd() / csp.name
                            shutil.copy(csp, kept)
                            print(f"DISAGREE: {calculus} n={n} d={d} #{k} (kept as {kept})", file=sys.stderr)
                    gm, qm = statistics.median(g_cpu), statistics.median(q_cpu)
                    rows.append((f"{calculus} A({n},{d:g},{cls['l']:g})", args.networks, cons, agree,
                                 gm, qm, statistics.median(g_wall), statistics.median(q_wall)))
                    print_row(rows[-1])
        if not args.no_examples:
            for calculus in args.calculi.split(","):
                labels = read_calculus_labels(data, calculus)
                for csp in sorted((data / calculus / "csp").glob("*.csp")):
                    g, q, ok, verdicts, unk = compare(args, gqr, args.qrm, data, env, csp, calculus, frozenset(labels))
                    unknowns += unk
                    failures += not ok
                    rows.append((f"{calculus} {csp.name}", len(verdicts), sum(bool(v) for v in verdicts),
                                 len(verdicts) if ok else 0, g[0], q[0], g[1], q[1]))
                    print_row(rows[-1])
        print()
        print("| class | networks | consistent | agree | GQR CPU (median) | qrm CPU (median) | qrm ÷ GQR CPU | qrm ÷ GQR wall |")
        print("|---|---|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4] * 1e3:.1f} ms | {r[5] * 1e3:.1f} ms "
                  f"| {r[5] / max(r[4], 1e-9):.2f} | {r[7] / max(r[6], 1e-9):.2f} |")
        worst = max((r[5] / max(r[4], 1e-9) for r in rows), default=0.0)
        print(f"\nmode {args.mode}; {len(rows)} classes; disagreements: {failures}; "
              f"unknown (qrm's node budget ran out): {unknowns}; "
              f"largest median CPU ratio qrm ÷ GQR: {worst:.2f}")
        return 1 if failures else 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


def print_row(r) -> None:
    print(f"{r[0]:32s} nets {r[1]:3d} consistent {r[2]:3d} agree {r[3]:3d}  "
          f"GQR {r[4] * 1e3:8.1f} ms  qrm {r[5] * 1e3:8.1f} ms  ratio {r[5] / max(r[4], 1e-9):.2f}",
          file=sys.stderr, flush=True)


if __name__ == "__main__":
    sys.exit(main())
