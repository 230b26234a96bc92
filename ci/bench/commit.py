"""The sound model's commitment semantics beside its whole plans and the paper's rules: answers and latency.

Usage: python -m ci.bench.commit [--count 123] [--seed 1] [--space left=2@8..20,right=1@12..30,lanes=both]

Two tables, one run. The built-in library under the ``default`` bounds: the paper's answer, the whole-plan sound
model's, and the commitment semantics' (its committed actions, escape and predicted continuation). Then a seeded
sample of the conformance space (scenarios with at least one left-lane vehicle), each vehicle read at its cell's
centre (``left_m``, ``right_m``), the same traffic cut finer for every cell size (``spec.scenario.refined``, the
readings where they were): per cell size how many the paper's rules plan, the whole plans, the commitments (a
committed part whose predicted continuation reaches the goal), the share of the paper-planned ones with a
commitment, and the interpreter's latency, whole pipeline, per strategy (sensible, the default, and shortest).
"""

from __future__ import annotations

import argparse
import random
import time
from dataclasses import replace

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.conformance.crossval import parse_space
from ci.shared.machine import machine
from oracle.planner import plan
from spec.answers import Answer, Status, Strategy
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.library import BUILTINS
from spec.scenario import Scenario, refined, sensed
from spec.sound import sensed_extents, sound_from

DEFAULT_SPACE = "left=2@8..20,right=1@12..30,lanes=both"


def read_at_centres(scenario: Scenario) -> Scenario:
    """``scenario`` with each vehicle read at its cell's centre (a reading where the cell alone would put it)."""
    same, oncoming = sensed_extents(scenario.lane, scenario.left_lane, scenario.right_lane, scenario.grid)
    return sensed(scenario, tuple(((lo + hi) / 2,) * 2 for lo, hi in same),
                  tuple(((lo + hi) / 2,) * 2 for lo, hi in oncoming))


def committed(answer: Answer) -> bool:
    """A commitment: a plan with a committed part (or the whole proved plan) whose prediction reaches the goal."""
    return answer.status is Status.PLAN and answer.commit is not None


def parts(answer: Answer) -> str:
    c = answer.commit
    if answer.status is not Status.PLAN or c is None:
        return answer.status.value
    escape = "none (a whole plan)" if c.escape is None else c.escape.kind.value
    return f"{len(c.committed)} committed, escape {escape}, {len(c.predicted)} predicted"


def library_table() -> Table:
    table = Table(title="the built-in library, default bounds, interpreter, sensible")
    for col in ("scenario", "paper's rules", "whole plans", "commitments"):
        table.add_column(col)
    for entry in BUILTINS:
        base = entry.load()
        paper = plan(base)
        whole = plan(replace(base, sound=sound_from(None, "default", semantics="whole")))
        answer = plan(replace(base, sound=sound_from(None, "default")))
        table.add_row(entry.name, f"{paper.status.value} ({len(paper.actions)})", whole.status.value, parts(answer))
    return table


def timed(scenario: Scenario, strategy: Strategy) -> tuple[Answer, float]:
    started = time.perf_counter()
    answer = plan(scenario, strategy)
    return answer, (time.perf_counter() - started) * 1000


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=123, help="scenarios drawn from the space")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--space", default=DEFAULT_SPACE)
    args = parser.parse_args()
    console = Console(width=160)
    everything = [s for s in parse_space(args.space, PAPER_GRID).scenarios(PAPER_GRID, None) if s.left_lane]
    sample = random.Random(args.seed).sample(everything, min(args.count, len(everything)))
    console.print(f"seed {args.seed}; {len(sample)} of the {len(everything)} scenarios of {args.space} with a "
                  f"left-lane vehicle, read at their cells' centres; default bounds; {machine()}")
    console.print(library_table())
    table = Table(title="answers and the interpreter's latency (ms), whole pipeline, default bounds")
    for col in ("cell", "paper plans", "whole plans", "commitments", "of the paper's", "commit sensible median",
                "p99", "max", "commit shortest median", "p99", "max", "whole sensible median", "p99"):
        table.add_column(col, justify="right")
    for cell_m in STANDARD_CELLS_M:
        grid = Grid(cell_m)
        scenarios = [read_at_centres(s if grid == PAPER_GRID else refined(s, grid)) for s in sample]
        counts = dict.fromkeys(("paper", "whole", "commit", "both"), 0)
        ms: dict[str, list[float]] = {"sensible": [], "shortest": [], "whole": []}
        for s in scenarios:
            paper = plan(replace(s, sound=None)).status is Status.PLAN
            whole, whole_ms = timed(replace(s, sound=sound_from(None, "default", semantics="whole")),
                                    Strategy.SENSIBLE)
            ours = replace(s, sound=sound_from(None, "default"))
            answer, sensible_ms = timed(ours, Strategy.SENSIBLE)
            _, shortest_ms = timed(ours, Strategy.SHORTEST)
            counts["paper"] += paper
            counts["whole"] += whole.status is Status.PLAN
            counts["commit"] += committed(answer)
            counts["both"] += paper and committed(answer)
            ms["sensible"].append(sensible_ms)
            ms["shortest"].append(shortest_ms)
            ms["whole"].append(whole_ms)
        q = {k: (np.median(v), np.percentile(v, 99), max(v)) for k, v in ms.items()}
        table.add_row(f"{float(cell_m):g} m", str(counts["paper"]), str(counts["whole"]), str(counts["commit"]),
                      f"{100 * counts['both'] / max(1, counts['paper']):.0f}%",
                      *(f"{x:.2f}" for x in q["sensible"]), *(f"{x:.2f}" for x in q["shortest"]),
                      *(f"{x:.2f}" for x in q["whole"][:2]))
    console.print(table)


if __name__ == "__main__":
    main()
