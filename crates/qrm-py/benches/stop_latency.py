#!/usr/bin/env python3
"""How a study run through `qrm.studies.run` reports progress and how fast it stops.

Two measurements per study (issue 40):
- `progress`: a callback records every `(done, total)`; the report gives when the total was
  first known, every total seen (one is right: the bar's total never moves), the longest wait
  between two reports and the final count (it should equal the total).
- `stop`: a thread calls `_thread.interrupt_main()` — what Ctrl-C does — `--at` seconds into
  the run; the report gives how long the call took to raise `KeyboardInterrupt` after it. A
  watched call looks for the interrupt every 0.1 s, so the rest is the longest stretch of the
  study's work without a check.

Each measurement runs in a fresh interpreter (the first call of a process derives tables a
later call reuses). Run from the workspace root (the studies read ../shared/data):
    python crates/qrm-py/benches/stop_latency.py progress [--full] [STUDY ...]
    python crates/qrm-py/benches/stop_latency.py stop --at 2 6 15 [--full] [STUDY ...]
"""
from __future__ import annotations

import argparse
import subprocess
import sys

PROGRESS = r"""
import sys, time, qrm
name, full = sys.argv[1], sys.argv[2] == "1"
t0 = time.time(); log = []
qrm.studies.run(name, quick=not full, progress=lambda d, t: log.append((time.time() - t0, d, t)))
end = time.time() - t0
first = next((t for t, _, total in log if total), None)
totals = sorted({total for _, _, total in log})
gaps = [b - a for a, b in zip([0.0] + [t for t, _, _ in log], [t for t, _, _ in log] + [end])]
done, total = (log[-1][1], log[-1][2]) if log else (0, 0)
first_s = "never" if first is None else f"{first:.2f} s"
print(f"{name}: {end:.1f} s; total first known at {first_s}; totals seen {totals}; "
      f"longest wait {max(gaps):.2f} s; ended at {done} of {total}")
"""

STOP = r"""
import sys, time, threading, _thread, qrm
name, at, full = sys.argv[1], float(sys.argv[2]), sys.argv[3] == "1"
fired = []
def fire():
    time.sleep(at); fired.append(time.time()); _thread.interrupt_main()
threading.Thread(target=fire, daemon=True).start()
t0 = time.time()
try:
    qrm.studies.run(name, quick=not full)
    print(f"{name}: finished in {time.time() - t0:.1f} s, before the stop at {at:g} s")
except KeyboardInterrupt:
    print(f"{name}: stopped at {at:g} s, returned {time.time() - fired[0]:.2f} s later")
"""

STUDIES = ["monte-carlo", "real-data", "reason", "serge-cv", "table-4-1", "field", "demo"]


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("what", choices=["progress", "stop"])
    p.add_argument("studies", nargs="*", default=STUDIES)
    p.add_argument("--full", action="store_true", help="the thesis's configs (default: quick)")
    p.add_argument("--at", type=float, nargs="+", default=[2.0, 6.0, 15.0], help="stop times (s)")
    a = p.parse_args()
    full = "1" if a.full else "0"
    for name in a.studies:
        runs = [[PROGRESS, name, full]] if a.what == "progress" else [[STOP, name, str(t), full] for t in a.at]
        for script, *args in runs:
            out = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True)
            print(out.stdout.strip() or f"{name}: failed: {out.stderr.strip().splitlines()[-1:]}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
