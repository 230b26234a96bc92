"""The sound model beside the paper's rules: planning latency and answers on the conformance example sweep, per cell.

Usage: python -m ci.bench.sound [--count 300] [--seed 2026] [--space left=2@8..20,right=1@12..30,lanes=both]
                                [--strategies sensible,shortest]

A seeded sample of the sweep's scenarios (paper grid), the same traffic cut finer for 10.5, 7 and
5.25 m cells (``ci.shared.gen.refined``); each planned by the interpreter with each strategy asked (the
default, sensible, and shortest), whole pipeline (final model, then preparations), under the
paper's rules, the sound model with the ``paper`` profile and with the ``default`` profile, in
one run. The table quotes median and p99 latency and the share of each answer, and the sound
model's plans are checked by the exact reachable-set check (a breach would be printed; there has
been none).
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
from oracle import reach
from oracle.planner import plan
from spec.answers import Status, Strategy
from spec.assumptions import profile
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.scenario import Scenario, refined
from spec.sound import Sound

DEFAULT_SPACE = "left=2@8..20,right=1@12..30,lanes=both"
MODELS = {"paper rules": None, "sound, paper profile": "paper", "sound, default profile": "default"}


def run(scenarios: list[Scenario], bounds: str | None, strategy: Strategy) -> tuple[np.ndarray, dict[Status, int], int]:
    """Milliseconds per scenario, the answers, and the exact check's breaches among the plans."""
    ms, answers, breaches = [], dict.fromkeys(Status, 0), 0
    for base in scenarios:
        scenario = base if bounds is None else replace(base, sound=Sound(profile(bounds)))
        started = time.perf_counter()
        answer = plan(scenario, strategy)
        ms.append((time.perf_counter() - started) * 1000)
        answers[answer.status] += 1
        if bounds is not None and answer.status is Status.PLAN and reach.exact_check(scenario, answer.actions):
            breaches += 1
    return np.array(ms), answers, breaches


def _strategies(text: str) -> tuple[Strategy, ...]:
    try:
        return tuple(Strategy(part.strip()) for part in text.split(",") if part.strip())
    except ValueError as err:
        raise argparse.ArgumentTypeError(f"{text!r}: {err}") from None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=300, help="scenarios drawn from the sweep")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--space", default=DEFAULT_SPACE)
    parser.add_argument("--strategies", type=_strategies, default=(Strategy.SENSIBLE, Strategy.SHORTEST),
                        help="comma-separated, from " + ", ".join(s.value for s in Strategy))
    args = parser.parse_args()
    console = Console(width=150)
    everything = list(parse_space(args.space, PAPER_GRID).scenarios(PAPER_GRID, None))
    sample = random.Random(args.seed).sample(everything, min(args.count, len(everything)))
    console.print(f"seed {args.seed}; {len(sample)} of the {len(everything)} scenarios of {args.space}; interpreter, "
                  f"whole pipeline; {machine()}")
    table = Table(title="sound model beside the paper's rules: latency (ms) and answers")
    for col in ("cell", "model", "strategy", "median", "p99", "max", "plan", "within horizon", "no plan", "incomplete",
                "breaches"):
        table.add_column(col, justify="left" if col in ("cell", "model", "strategy") else "right")
    for cell_m in STANDARD_CELLS_M:
        grid = Grid(cell_m)
        scenarios = [refined(s, grid) for s in sample] if grid != PAPER_GRID else sample
        for name, bounds in MODELS.items():
            for strategy in args.strategies:
                ms, answers, breaches = run(scenarios, bounds, strategy)
                n = len(scenarios)
                table.add_row(f"{float(cell_m):g} m", name, strategy.value, f"{np.median(ms):.2f}",
                              f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}", f"{answers[Status.PLAN] / n:.0%}",
                              f"{answers[Status.NO_PLAN_WITHIN_HORIZON] / n:.0%}", f"{answers[Status.NO_PLAN] / n:.0%}",
                              f"{answers[Status.INCOMPLETE] / n:.0%}", "-" if bounds is None else str(breaches))
                console.print(f"  {float(cell_m):g} m, {name}, {strategy.value}: done", style="dim")
    console.print(table)


if __name__ == "__main__":
    main()
