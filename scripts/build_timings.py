#!/usr/bin/env python3
"""Where a clean `cargo build --release` spends its time, from cargo's own timings report.

    CARGO_TARGET_DIR=/tmp/qrm-clean cargo build --release --timings
    python3 scripts/build_timings.py /tmp/qrm-clean/cargo-timings/cargo-timing.html

prints the build's wall time, the CPU summed over compilation units, and the units that take
longest (a build script's run counts as the unit that compiles its C sources). Given a second
report (``--vs BEFORE.html``), it prints each unit's time beside the other's, for a before/after
table (docs/build-time.md).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path


def units(report: Path) -> tuple[float, dict[str, float]]:
    """(wall seconds, {unit: seconds}) of one cargo timings report."""
    text = report.read_text()
    m = re.search(r"const UNIT_DATA = (\[.*?\]);\n", text, re.S)
    if m is None:
        sys.exit(f"{report}: no UNIT_DATA (not a `cargo build --timings` report?)")
    data = json.loads(m.group(1))
    out: dict[str, float] = {}
    for u in data:
        name = u["name"] + (" (build script run)" if u.get("mode") == "run-custom-build" else "")
        out[name] = out.get(name, 0.0) + u["duration"]
    wall = max(u["start"] + u["duration"] for u in data)
    return wall, out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("report", type=Path, help="cargo-timing.html of the build to show")
    ap.add_argument("--vs", type=Path, help="the report of the build to compare with (before)")
    ap.add_argument("--top", type=int, default=20, help="units shown (default 20)")
    args = ap.parse_args()
    wall, now = units(args.report)
    if args.vs is None:
        print(f"wall {wall:.0f} s, CPU summed over units {sum(now.values()):.0f} s")
        print("| unit | s |\n|---|---|")
        for name, s in sorted(now.items(), key=lambda kv: -kv[1])[: args.top]:
            print(f"| {name} | {s:.1f} |")
        return 0
    wall0, before = units(args.vs)
    print(f"wall {wall0:.0f} s → {wall:.0f} s; CPU summed over units {sum(before.values()):.0f} s → {sum(now.values()):.0f} s")
    print("| unit | before (s) | after (s) |\n|---|---|---|")
    for name in sorted(set(now) | set(before), key=lambda n: -max(now.get(n, 0), before.get(n, 0)))[: args.top]:
        print(f"| {name} | {before.get(name, 0):.1f} | {now.get(name, 0):.1f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
