"""Progress of a simulation campaign in kilometres, fed from the worker processes' reports."""

from __future__ import annotations

import threading
from collections.abc import Iterator
from contextlib import contextmanager

from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

from sim.summary import RunSummary


class KmProgress:
    """A bar over every run's kilometres: runs report (key, km) while they drive, and once when they finish.

    Kilometres arrive from a thread draining the workers' reports, so every update is locked;
    a finished run fills its share of the bar, wherever it stopped.
    """

    def __init__(self, progress: Progress, runs: int, km: float, resumed_line: str) -> None:
        self.progress, self.km, self.resumed_line = progress, km, resumed_line
        self.task = progress.add_task("simulate", total=runs * km, km=0.0, failed=0)
        self.km_by_seed: dict[int, float] = {}
        self.finished: set[int] = set()
        self.failed = 0
        self.lock = threading.Lock()

    def _show(self) -> None:
        share = sum(self.km if s in self.finished else min(d, self.km) for s, d in self.km_by_seed.items())
        self.progress.update(self.task, completed=share, km=sum(self.km_by_seed.values()), failed=self.failed)

    def moved(self, update: tuple[int, float]) -> None:
        """A run (by its key: a seed, or a job's index) reports how far it has driven."""
        with self.lock:
            self.km_by_seed[update[0]] = update[1]
            self._show()

    def done(self, summary: RunSummary, resumed: bool, key: int | None = None, name: str = "") -> None:
        """A run finished (or was found finished in the record); ``key`` defaults to its seed."""
        key = summary.seed if key is None else key
        if resumed:
            self.progress.console.print(f"{name or f'seed {summary.seed}'}: {self.resumed_line}")
        with self.lock:
            self.km_by_seed[key] = summary.km
            self.finished.add(key)
            self.failed += bool(summary.failures)
            self._show()


@contextmanager
def km_progress(console: Console, runs: int, km: float, resumed_line: str) -> Iterator[KmProgress]:
    """A transient kilometre bar on ``console`` for the duration of a campaign."""
    columns = (TextColumn("simulate"), BarColumn(), TextColumn("{task.fields[km]:.1f} of {task.total:.0f} km"),
               TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=console, transient=True) as progress:
        yield KmProgress(progress, runs, km, resumed_line)
