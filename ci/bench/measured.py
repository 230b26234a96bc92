"""The sound model with each vehicle's own measured speed beside the lane-wide one: answers and latency.

Usage: python -m ci.bench.measured [--count 123] [--seed 1] [--width-mps 3.22] [--space ...]

The sample of ``ci.bench.commit`` (the conformance space's scenarios with a left-lane vehicle, each read at its cell's
centre, the same traffic cut finer for every cell size), planned under the default bounds twice: every vehicle at
its lane's speeds, and every vehicle with a measured speed interval (``Scenario.left_mps``, ``right_mps``): its true
speed drawn from its lane's bounds (seeded), the interval that wide around it (default: the tracker's median width
after 2 s of noisy sightings, ``python -m ci.bench.speeds``, docs/faults.md), and, for a share of the same-direction
vehicles (``--standing``), a vehicle standing. Per cell size: how many each commits to, the interpreter's latency
(whole pipeline) per strategy, and whether each commitment with measured speeds survives the exact check; then the
same measured scenarios under the no-acceleration profile of vehicles overtaken (``spec.dynamics.Overtaken``): how
many it commits to, how many of those commit to a move back from the passing lane, and the exact check.
"""

from __future__ import annotations

import argparse
import random
from dataclasses import replace

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.bench.commit import DEFAULT_SPACE, committed, read_at_centres, timed
from ci.conformance.crossval import parse_space
from ci.shared.machine import machine
from oracle import reach
from spec.actions import ACTION_RULES
from spec.answers import Answer, Status, Strategy
from spec.assumptions import SpeedBounds
from spec.dynamics import Overtaken
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.scenario import Scenario, measured_speeds, refined
from spec.sound import sound_from

#: The tracker's median speed-interval width after 2 s of noisy sightings (``python -m ci.bench.speeds``, seed 1,
#: docs/faults.md, 2026-12-04).
TRACKED_WIDTH_MPS = 3.22


def measured(scenario: Scenario, rng: random.Random, width_mps: float, standing: float) -> Scenario:
    """``scenario`` with every vehicle's speed measured: a true speed drawn from its lane's bounds, the interval
    ``width_mps`` wide around it (never below a standstill), a same-direction one standing with probability
    ``standing``."""
    assert scenario.sound is not None
    b = scenario.sound.bounds

    def one(lane: SpeedBounds, may_stand: bool) -> tuple[float, float]:
        if may_stand and rng.random() < standing:
            return 0.0, 0.0
        v = rng.uniform(lane.low_mps, lane.high_mps)
        return max(0.0, v - width_mps / 2), v + width_mps / 2

    return measured_speeds(scenario, [one(b.same_mps, True) for _ in scenario.left_lane],
                           [one(b.oncoming_mps, False) for _ in scenario.right_lane])


def survives(scenario: Scenario, answer: Answer) -> bool:
    """Whether ``answer``'s commitment and its escape survive the exact check (False: no commitment)."""
    if answer.status is not Status.PLAN or answer.commit is None:
        return False
    c = answer.commit
    return reach.exact_check(scenario, (*c.committed, *(c.escape.actions if c.escape else ()))) is None


def moves_back(answer: Answer) -> bool:
    """Whether ``answer`` commits to a move back into the left lane (a pass completed, or an abort)."""
    return answer.status is Status.PLAN and answer.commit is not None and any(
        ACTION_RULES[a].to_lane is Lane.LEFT for a in answer.commit.committed)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=123, help="scenarios drawn from the space")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--width-mps", type=float, default=TRACKED_WIDTH_MPS, help="each speed interval's width")
    parser.add_argument("--standing", type=float, default=0.1, help="share of same-direction vehicles standing")
    parser.add_argument("--space", default=DEFAULT_SPACE)
    args = parser.parse_args()
    if not (args.width_mps >= 0 and 0 <= args.standing <= 1 and args.count > 0):
        parser.error(f"--width-mps={args.width_mps}, --standing={args.standing}, --count={args.count}: a width of 0 "
                     "or more, a share within 0..1 and a count above 0")
    console = Console(width=160)
    everything = [s for s in parse_space(args.space, PAPER_GRID).scenarios(PAPER_GRID, None) if s.left_lane]
    sample = random.Random(args.seed).sample(everything, min(args.count, len(everything)))
    console.print(f"seed {args.seed}; {len(sample)} of the {len(everything)} scenarios of {args.space} with a "
                  f"left-lane vehicle, read at their cells' centres; default bounds; speed intervals "
                  f"{args.width_mps:g} m/s wide, {args.standing:.0%} of the same-direction vehicles standing; "
                  f"{machine()}")
    table = Table(title="commitments and the interpreter's latency (ms), whole pipeline, default bounds")
    for col in ("cell", "lane-wide commits", "measured commits", "survive exact check", "sensible median", "p99",
                "max", "shortest median", "p99", "max", "lane-wide sensible median", "p99",
                "no-acceleration commits", "moves back", "survive exact check"):
        table.add_column(col, justify="right")
    for cell_m in STANDARD_CELLS_M:
        grid = Grid(cell_m)
        rng = random.Random(args.seed)  # the same speeds at every cell size
        counts = dict.fromkeys(("lane", "measured", "exact", "held", "held back", "held exact", "back"), 0)
        ms: dict[str, list[float]] = {"sensible": [], "shortest": [], "lane": []}
        for s in sample:
            lane_wide = replace(read_at_centres(s if grid == PAPER_GRID else refined(s, grid)),
                                sound=sound_from(None, "default"))
            ours = measured(lane_wide, rng, args.width_mps, args.standing)
            before, lane_ms = timed(lane_wide, Strategy.SENSIBLE)
            answer, sensible_ms = timed(ours, Strategy.SENSIBLE)
            _, shortest_ms = timed(ours, Strategy.SHORTEST)
            counts["lane"] += committed(before)
            counts["measured"] += committed(answer)
            counts["exact"] += survives(ours, answer)
            counts["back"] += moves_back(answer)
            assert ours.sound is not None
            held = replace(ours, sound=replace(ours.sound, overtaken=Overtaken.NO_ACCELERATION))
            held_answer, _ = timed(held, Strategy.SENSIBLE)
            counts["held"] += committed(held_answer)
            counts["held back"] += moves_back(held_answer)
            counts["held exact"] += survives(held, held_answer)
            ms["sensible"].append(sensible_ms)
            ms["shortest"].append(shortest_ms)
            ms["lane"].append(lane_ms)
        q = {k: (np.median(v), np.percentile(v, 99), max(v)) for k, v in ms.items()}
        table.add_row(f"{float(cell_m):g} m", str(counts["lane"]), str(counts["measured"]),
                      f"{counts['exact']} of {counts['measured']}", *(f"{x:.2f}" for x in q["sensible"]),
                      *(f"{x:.2f}" for x in q["shortest"]), *(f"{x:.2f}" for x in q["lane"][:2]),
                      str(counts["held"]), f"{counts['held back']} (physics {counts['back']})",
                      f"{counts['held exact']} of {counts['held']}")
    console.print(table)


if __name__ == "__main__":
    main()
