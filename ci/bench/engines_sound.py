"""Every engine on the sound model beside the paper's rules: latency per engine and strategy, per cell size, in one run.

Usage: python -m ci.bench.engines_sound [--count 100] [--seed 2026] [--space left=2@8..20,right=1@12..30,lanes=both]
                                        [--cells 21,10.5,7,5.25] [--runs interpreter/sensible,spin/sensible,...]
                                        [--timeout 10]

A seeded sample of the sweep's scenarios (paper grid), the same traffic cut finer for each finer
cell (``ci.shared.gen.refined``); each run (an engine with a strategy, the whole pipeline as the
conformance properties run it: ``oracle.planner.solve``) on every scenario under the paper's
rules and under the sound model with the ``default`` profile, one after the other in one
process (Spin's verifiers compiled before the clock starts; Z3's solvers kept per shape, as a
campaign keeps them). The table quotes median and p99 latency, the answers (plan / none within
the horizon / none at all / incomplete / engine error) and, for Spin, the median and largest
number of states pan stored per search. A run past ``--timeout`` seconds is counted incomplete (and its time
enters the latency), never dropped: the paper rules' Z3 ``optimal`` runs past a minute on finer cells.
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
from ci.conformance.properties import RUNS, RunKey
from ci.shared.machine import machine
from oracle.planner import solve
from spec.answers import Limits, Status, Strategy
from spec.assumptions import profile
from spec.errors import EngineError
from spec.grid import PAPER_GRID, grid_for
from spec.scenario import Scenario, refined
from spec.sound import Sound

DEFAULT_SPACE = "left=2@8..20,right=1@12..30,lanes=both"
MODELS = {"paper rules": None, "sound, default": "default"}
TIMEOUT_S = 10.0  # per run, by default: a run past it is counted incomplete, never dropped


def _runs(text: str) -> tuple[RunKey, ...]:
    """``engine/strategy`` pairs (default: the runs the conformance properties read)."""
    found = []
    for part in (p.strip() for p in text.split(",") if p.strip()):
        engine, _, strategy = part.partition("/")
        try:
            found.append(RunKey(engine, Strategy(strategy)))
        except ValueError:
            raise argparse.ArgumentTypeError(f"{part!r}: expected engine/strategy, a strategy of "
                                             f"{', '.join(s.value for s in Strategy)}") from None
    return tuple(found)


def _cells(text: str) -> tuple[float, ...]:
    try:
        return tuple(float(part) for part in text.split(",") if part.strip())
    except ValueError as err:
        raise argparse.ArgumentTypeError(str(err)) from None


def measure(scenarios: list[Scenario], key: RunKey, timeout_s: float = TIMEOUT_S) -> tuple[np.ndarray, dict[str, int],
                                                                                         list[int]]:
    """Milliseconds per scenario, the answers by kind, and the states each search stored (Spin's pan)."""
    ms, answers, stored = [], {s.value: 0 for s in Status} | {"error": 0}, []
    for scenario in scenarios:
        started = time.perf_counter()
        try:
            answer = solve(scenario, key.strategy, engine=key.engine, limits=Limits(timeout_s=timeout_s))
        except EngineError:
            answers["error"] += 1
            ms.append((time.perf_counter() - started) * 1000)
            continue
        ms.append((time.perf_counter() - started) * 1000)
        answers[answer.status.value] += 1
        stored.append(answer.states_explored)
    return np.array(ms), answers, stored


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=100, help="scenarios drawn from the sweep")
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--space", default=DEFAULT_SPACE)
    parser.add_argument("--cells", type=_cells, default=(21.0, 10.5, 7.0, 5.25))
    parser.add_argument("--runs", type=_runs, default=RUNS)
    parser.add_argument("--timeout", type=float, default=TIMEOUT_S, help="seconds per run (past it: incomplete)")
    args = parser.parse_args()
    console = Console(width=160)
    everything = list(parse_space(args.space, PAPER_GRID).scenarios(PAPER_GRID, None))
    sample = random.Random(args.seed).sample(everything, min(args.count, len(everything)))
    console.print(f"seed {args.seed}; {len(sample)} of the {len(everything)} scenarios of {args.space}; whole "
                  f"pipeline; {args.timeout:g} s per run; {machine()}")
    table = Table(title="every engine, sound model (default profile) beside the paper's rules: latency (ms), answers")
    for col in ("cell", "model", "run", "median", "p99", "max", "plan", "within h.", "none", "incompl.", "error",
                "stored median", "stored max"):
        table.add_column(col, justify="left" if col in ("cell", "model", "run") else "right")
    for cell_m in args.cells:
        grid = grid_for(cell_m)
        base = [refined(s, grid) for s in sample] if grid != PAPER_GRID else sample
        for name, bounds in MODELS.items():
            scenarios = base if bounds is None else [replace(s, sound=Sound(profile(bounds))) for s in base]
            for key in args.runs:
                measure(scenarios[:1], key)  # a verifier compiled, a solver built: not this bench's subject
                ms, answers, stored = measure(scenarios, key, args.timeout)
                n = len(scenarios)
                spin = key.engine == "spin" and stored
                table.add_row(f"{cell_m:g} m", name, key.label, f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}",
                              f"{ms.max():.2f}", f"{answers['plan'] / n:.0%}",
                              f"{answers['no_plan_within_horizon'] / n:.0%}", f"{answers['no_plan'] / n:.0%}",
                              f"{answers['incomplete'] / n:.0%}", str(answers["error"]),
                              f"{np.median(stored):.0f}" if spin else "-", f"{max(stored)}" if spin else "-")
                console.print(f"  {cell_m:g} m, {name}, {key.label}: median {np.median(ms):.2f} ms", style="dim")
    console.print(table)


if __name__ == "__main__":
    main()
