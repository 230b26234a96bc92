"""Planning latency of the interpreter engine on the built-in library and on generated scenarios.

Usage: python -m ci.bench.latency [--count 1000] [--seed 2026] [--reference 200]

Times the ``shortest`` strategy (bitset BFS) through the whole pipeline (final model,
then preparations, then the "no plan" proof) with horizon 30, and, on the same
scenarios, the plain breadth-first search over states and the ``sensible`` DFS, so the
table quotes medians, 99th percentiles and ratios from one run.
"""

from __future__ import annotations

import argparse
import itertools
import platform
import time
from collections.abc import Callable

import numpy as np
from rich.console import Console
from rich.table import Table

from ci.shared.gen import balanced, random_scenarios
from oracle import search
from oracle.planner import plan
from spec.answers import Status, Strategy
from spec.constants import DEFAULT_HORIZON
from spec.engines import Engine, register
from spec.library import BUILTINS
from spec.scenario import Scenario

SENSIBLE, SHORTEST = Strategy.SENSIBLE, Strategy.SHORTEST
REFERENCE = Engine("reference", (SENSIBLE, SHORTEST),
                   lambda p, s, _limits: search.sensible(p) if s is SENSIBLE else search.shortest_reference(p),
                   "plain DFS and BFS over interpreter states (benchmark only)")


def timed(scenarios: list[Scenario], run: Callable[[Scenario], object]) -> np.ndarray:
    """Milliseconds per scenario (one warm-up call first)."""
    run(scenarios[0])
    out = []
    for scenario in scenarios:
        started = time.perf_counter()
        run(scenario)
        out.append((time.perf_counter() - started) * 1000)
    return np.array(out)


def library_and_generated(seed: int, count: int) -> list[Scenario]:
    """The built-in library followed by ``count`` generated scenarios."""
    return [b.load() for b in BUILTINS] + list(itertools.islice(random_scenarios(seed), count))


def latency_table(title: str, first: str, results: dict[str, np.ndarray], base: np.ndarray, ratio: str) -> Table:
    """Median, p99 and max per row, and each median as a multiple of ``base``'s."""
    table = Table(title=title)
    for col in (first, "n", "median", "p99", "max", ratio):
        table.add_column(col, justify="left" if col == first else "right")
    for name, ms in results.items():
        table.add_row(name, str(len(ms)), f"{np.median(ms):.2f}", f"{np.percentile(ms, 99):.2f}", f"{ms.max():.2f}",
                      f"{np.median(ms) / np.median(base):.2f}x")
    return table


def row(table: Table, name: str, ms: np.ndarray, base: np.ndarray | None) -> None:
    ratio = f"{np.median(ms) / np.median(base):.1f}x" if base is not None else "1.0x"
    table.add_row(name, str(len(ms)), f"{np.median(ms):.3f}", f"{np.percentile(ms, 99):.3f}",
                  f"{ms.max():.3f}", ratio)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--count", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=2026)
    parser.add_argument("--reference", type=int, default=200, help="scenarios also timed with the slow planners")
    args = parser.parse_args()
    console = Console(width=120)
    console.print(f"seed {args.seed}; {args.count} generated scenarios (<= 5 left, <= 2 oncoming), half without "
                  f"a plan; horizon {DEFAULT_HORIZON}; {platform.processor() or platform.machine()}, "
                  f"python {platform.python_version()}, {time.strftime('%Y-%m-%d')}")

    def has_plan(s: Scenario) -> bool:
        return plan(s, SHORTEST).status is Status.PLAN

    generated = balanced(args.seed, args.count, has_plan)
    builtins = [b.load() for b in BUILTINS]
    with_plan, without = generated[: args.count // 2], generated[args.count // 2:]
    ref_sample = with_plan[: args.reference // 2] + without[: args.reference // 2]
    register(REFERENCE)

    table = Table(title="planning latency per scenario (ms), whole pipeline")
    for col in ("planner / scenarios", "n", "median", "p99", "max", "median vs bitset"):
        table.add_column(col, justify="right" if col != "planner / scenarios" else "left")
    fast = timed(generated, lambda s: plan(s, SHORTEST))
    row(table, "shortest (bitset BFS): all generated", fast, None)
    row(table, "  ... with a plan", fast[: len(with_plan)], None)
    row(table, "  ... without a plan", fast[len(with_plan):], None)
    row(table, "shortest (bitset BFS): built-in library", timed(builtins, lambda s: plan(s, SHORTEST)), None)
    fast_ref = timed(ref_sample, lambda s: plan(s, SHORTEST))
    row(table, f"shortest (bitset BFS): {len(ref_sample)}-scenario sample", fast_ref, fast_ref)
    row(table, "shortest (plain BFS over states): same sample",
        timed(ref_sample, lambda s: plan(s, SHORTEST, engine="reference")), fast_ref)
    row(table, "sensible (DFS over offsets): same sample", timed(ref_sample, lambda s: plan(s, SENSIBLE)), fast_ref)
    row(table, "sensible (DFS over states): same sample",
        timed(ref_sample, lambda s: plan(s, SENSIBLE, engine="reference")), fast_ref)
    console.print(table)
    ok = np.median(fast) <= 1.0 and np.percentile(fast, 99) <= 10.0
    console.print(f"target (shortest, generated): median <= 1 ms and p99 <= 10 ms: {'met' if ok else 'NOT met'} "
                  f"(median {np.median(fast):.3f} ms, p99 {np.percentile(fast, 99):.3f} ms)")


if __name__ == "__main__":
    main()
