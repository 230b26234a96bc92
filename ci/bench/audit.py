"""The audit's closed-loop speed by worker count: km per wall minute, whole command, in one run.

Usage: python -m ci.bench.audit [--km 4] [--workers 1,2] [--default-km KM]

Runs ``overtake audit`` on the default grid (every cell size, traffic, sensing and planning model) with
``--km KM --runs 1 --engines interpreter --snapshots 0`` once per worker count, each as a whole
process into a fresh folder, and prints km driven, wall time, km per wall minute (in all and per
worker) and the speed-up over the first count; then what the default audit (``--default-km`` per
combination, by default the command's own ``--km`` x ``--runs``, before its planning-cost pass) takes at each
rate. Every count drives the same runs,
which the table checks (the same km, collisions and near misses).
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

from rich.console import Console
from rich.table import Table

from ci.audit.campaign import AuditPlan
from ci.cli.audit import audit as audit_command
from ci.shared.machine import machine
from ci.shared.options import names


def audit(km: float, workers: int, out: Path) -> tuple[float, float, tuple[int, int]]:
    """One whole ``overtake audit``: its wall seconds, km driven, and (collisions, near misses) over the grid."""
    command = [sys.executable, "-m", "ci.cli.main", "audit", "--km", str(km), "--runs", "1", "--engines",
               "interpreter", "--snapshots", "0", "--workers", str(workers), "--out", str(out), "--fresh"]
    started = time.perf_counter()
    done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    wall_s = time.perf_counter() - started
    if done.returncode != 0:
        sys.exit(f"bench_audit: the audit with --workers {workers} exited {done.returncode}: {done.stderr.strip()}")
    rows = json.loads((out / "audit.json").read_text())["combinations"]
    return wall_s, sum(r["km"] for r in rows), (sum(r["collisions"] for r in rows), sum(r["near_misses"] for r in rows))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--km", type=float, default=4.0, help="km per combination (one run each)")
    parser.add_argument("--workers", default="1,2", help="worker counts, comma-separated")
    defaults: dict[str | None, Any] = {param.name: param.default for param in audit_command.params}
    parser.add_argument("--default-km", type=float, default=float(defaults["km"]) * int(defaults["runs"]),
                        help="km per combination of the default audit (its --km x --runs)")
    args = parser.parse_args()
    counts = [int(w) for w in args.workers.split(",")]
    # the command's default models (every one it compares), split as the command splits them
    combinations = len(AuditPlan(models=names("--model", str(defaults["model_text"]))).configs())
    console = Console(width=140)
    console.print(f"overtake audit --km {args.km} --runs 1 --engines interpreter --snapshots 0 --workers N: "
                  f"{combinations} combinations; {machine()}")
    table = Table(title="audit speed by worker count (whole command)")
    for col in ("--workers", "km driven", "wall s", "km per wall minute", "per worker", "vs first",
                f"default audit ({args.default_km:g} km x {combinations}) min"):
        table.add_column(col, justify="right")
    first_rate, outcomes = None, set()
    with tempfile.TemporaryDirectory() as scratch:
        for workers in counts:
            wall_s, km, outcome = audit(args.km, workers, Path(scratch) / f"w{workers}")
            outcomes.add((round(km, 3), outcome))
            rate = km / (wall_s / 60)
            first_rate = first_rate or rate
            table.add_row(str(workers), f"{km:.1f}", f"{wall_s:.1f}", f"{rate:.1f}", f"{rate / workers:.1f}",
                          f"{rate / first_rate:.2f}x", f"{args.default_km * combinations / rate:.1f}")
    console.print(table)
    same = len(outcomes) == 1
    console.print("every worker count drove the same runs (km, collisions, near misses)" if same else
                  f"the worker counts drove different runs: {sorted(outcomes)}")
    if not same:
        sys.exit(1)


if __name__ == "__main__":
    main()
