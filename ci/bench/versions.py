"""Per-plan latency of this checkout beside another git revision, on the same scenarios, interleaved in one run.

Usage: python -m ci.bench.versions [--rev ce09fa1] [--count 200] [--seed 2026] [--rounds 5]

The other revision is checked out into a temporary git worktree. Each round runs one timing
process per checkout, in turn (A B A B ...), each planning every scenario with every engine
and strategy through the whole pipeline (warm: one untimed pass first); a scenario's time is
its median over the rounds, and the table gives each engine's median and p99 for both
checkouts and the ratio of the medians. Use it to show that a change made nothing slower.
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.shared.gen import random_scenarios
from ci.shared.machine import machine
from spec.library import BUILTINS

#: (engine, strategy) pairs both revisions answer.
CASES = (("interpreter", "sensible"), ("interpreter", "shortest"), ("spin", "sensible"), ("spin", "shortest"),
         ("z3", "shortest"))

#: Runs inside each checkout: only API that both revisions have (strategy names or the Strategy enum).
TIMER = r"""
import json, sys, time
from oracle.planner import plan
from spec.scenario import make_scenario
try:
    from spec.answers import Strategy
except ImportError:
    Strategy = None
cases, scenarios = json.load(open(sys.argv[1]))
made = [make_scenario(s["lane"], s["left_lane"], s["right_lane"], s["targets"], horizon=s["horizon"])
        for s in scenarios]
out = {}
for engine, strategy in cases:
    how = Strategy(strategy) if Strategy else strategy
    for s in made:
        plan(s, how, engine=engine)  # warm: verifiers compiled, modules loaded
    times = []
    for s in made:
        t = time.perf_counter()
        plan(s, how, engine=engine)
        times.append((time.perf_counter() - t) * 1000)
    out[f"{engine} {strategy}"] = times
json.dump(out, sys.stdout)
"""


def scenario_list(seed: int, count: int) -> list[dict[str, object]]:
    scenarios = [b.load() for b in BUILTINS] + list(itertools.islice(random_scenarios(seed), count))
    return [{"lane": s.lane.value, "left_lane": list(s.left_lane), "right_lane": list(s.right_lane),
             "targets": s.targets, "horizon": s.horizon} for s in scenarios]


def time_in(checkout: Path, job: Path) -> dict[str, list[float]]:
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run([sys.executable, "-c", TIMER, str(job)], cwd=checkout, capture_output=True, text=True,
                          check=True, env=env)
    return json.loads(done.stdout)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rev", default="ce09fa1", help="the revision to compare with")
    parser.add_argument("--count", type=int, default=200, help="generated scenarios besides the library")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    here = Path(__file__).resolve().parents[2]
    console = Console(width=120)
    scenarios = scenario_list(args.seed, args.count)
    console.print(f"seed {args.seed}; {len(scenarios)} scenarios (library + generated, 21 m cells); {args.rounds} "
                  f"rounds, A/B interleaved; this checkout vs {args.rev}; {machine()}")
    with tempfile.TemporaryDirectory(prefix="overtake-bench-") as tmp:
        other = Path(tmp) / "other"
        subprocess.run(["git", "-C", str(here), "worktree", "add", "--detach", str(other), args.rev], check=True,
                       capture_output=True)
        try:
            job = Path(tmp) / "job.json"
            job.write_text(json.dumps([CASES, scenarios]))
            rounds: dict[str, list[dict[str, list[float]]]] = {"this": [], "other": []}
            for _ in range(args.rounds):
                rounds["other"].append(time_in(other, job))
                rounds["this"].append(time_in(here, job))
        finally:
            subprocess.run(["git", "-C", str(here), "worktree", "remove", "--force", str(other)], check=False,
                           capture_output=True)
    table = Table(title=f"per-plan latency (ms), whole pipeline, medians over {args.rounds} rounds per scenario")
    for col in ("engine, strategy", "n", f"{args.rev} median", f"{args.rev} p99", "this median", "this p99",
                "this / before (median)"):
        table.add_column(col, justify="left" if col.startswith("engine") else "right")
    for engine, strategy in CASES:
        key = f"{engine} {strategy}"
        per = {side: np.median(np.array([r[key] for r in rs]), axis=0) for side, rs in rounds.items()}
        before, after = per["other"], per["this"]
        table.add_row(key, str(len(after)), f"{np.median(before):.3f}", f"{np.percentile(before, 99):.3f}",
                      f"{np.median(after):.3f}", f"{np.percentile(after, 99):.3f}",
                      f"{np.median(after) / np.median(before):.2f}x")
    console.print(table)


if __name__ == "__main__":
    main()
