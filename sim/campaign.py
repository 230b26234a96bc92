"""Several drives, on several cores: the unit later campaigns reuse. Each run's seed is printed.

Runs go to a process pool (one simulator, one physics client and one generator per run);
each leaves ``trace-seedS.jsonl`` and ``spacetime-seedS.png`` in the output folder.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

from sim.report import plot_trace
from sim.simulator import RunSummary, run_drive


def simulate(runs: int, km: float, seed: int, until_failure: bool = False, engine: str = "interpreter",
             strategy: str = "sensible", workers: int = 1, out_dir: str | None = None,
             replan_on_violation: bool = True,
             on_done: Callable[[RunSummary], None] | None = None) -> list[RunSummary]:
    """Run ``runs`` drives with seeds ``seed .. seed + runs - 1``; results in seed order."""
    jobs = [(seed + i, km, until_failure, engine, strategy, out_dir, replan_on_violation) for i in range(runs)]
    results: list[RunSummary] = []
    if workers <= 1:
        for job in jobs:
            results.append(run_drive(*job))
            _finish(results[-1], out_dir, on_done)
    else:
        with ProcessPoolExecutor(max_workers=workers) as pool:
            for future in as_completed([pool.submit(run_drive, *job) for job in jobs]):
                results.append(future.result())
                _finish(results[-1], out_dir, on_done)
    return sorted(results, key=lambda r: r.seed)


def _finish(summary: RunSummary, out_dir: str | None, on_done: Callable[[RunSummary], None] | None) -> None:
    if out_dir:
        trace = Path(out_dir) / f"trace-seed{summary.seed}.jsonl"
        if trace.exists() and trace.stat().st_size:
            plot_trace(trace, Path(out_dir) / f"spacetime-seed{summary.seed}.png")
    if on_done:
        on_done(summary)
