"""The simulation campaign: several drives, resumable, run wherever ``ci.shared.executors`` sends them.

Every finished run is appended to ``OUT/runs.jsonl`` with the campaign's parameters, so an
interrupted campaign started again with the same parameters and folder runs only the
seeds it has no line for (a half-written last line is run again). Each run leaves
``trace-seedS.jsonl`` and ``spacetime-seedS.png`` in the same folder, written before its line.
"""

from __future__ import annotations

import contextlib
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ci.shared.executors import IN_PROCESS, ExecutorChoice, run_jobs
from ci.shared.records import append, campaign_lock, open_for_append, read_records
from sim.parts import DriveConfig
from sim.report import plot_trace
from sim.simulator import run_drive
from sim.summary import RunSummary
from spec.errors import OptionError

RUNS_FILE = "runs.jsonl"


def simulate(campaign: DriveConfig, seeds: list[int], out_dir: str, executor: ExecutorChoice = IN_PROCESS,
             on_done: Callable[[RunSummary, bool], None] | None = None, fresh: bool = False,
             on_km: Callable[[tuple[int, float]], None] | None = None) -> list[RunSummary]:
    """Run every seed not already recorded in ``out_dir``; ``on_done(summary, resumed)`` after each, and
    ``on_km((seed, km))`` after each kilometre of a run (not on dask); results in seed order."""
    out = Path(out_dir)
    with campaign_lock(out):
        return _simulate(campaign, seeds, out, executor, on_done, fresh, on_km)


def _simulate(campaign: DriveConfig, seeds: list[int], out: Path, executor: ExecutorChoice,
              on_done: Callable[[RunSummary, bool], None] | None, fresh: bool,
              on_km: Callable[[tuple[int, float]], None] | None) -> list[RunSummary]:
    log = out / RUNS_FILE
    if fresh:
        log.unlink(missing_ok=True)
    check_same_campaign(log, campaign)
    done = {seed: run for seed, run in recorded(log, campaign).items() if seed in seeds}
    for summary in done.values():
        if on_done:
            on_done(summary, True)
    todo = [s for s in seeds if s not in done]
    jobs = [(s, campaign, str(out)) for s in todo]
    with open_for_append(log) as lines, contextlib.closing(run_jobs(drive_one, jobs, executor, on_km)) as finished:
        for _index, summary in finished:
            append(lines, {"campaign": campaign.to_json(), "run": summary.to_json()})  # after its files (drive_one)
            done[summary.seed] = summary
            if on_done:
                on_done(summary, False)
    return [done[s] for s in seeds]


def drive_one(seed: int, campaign: DriveConfig, out_dir: str,
              report: Callable[[tuple[int, float]], None] | None = None) -> RunSummary:
    """One run of the campaign (what a worker runs): the drive, its trace and its space-time plot, all on disk
    before the run is returned (and recorded): a record means every file of its run is there."""
    summary = run_drive(seed, campaign, out_dir, report)
    out = Path(out_dir)
    trace = out / f"trace-seed{seed}.jsonl"
    if trace.exists() and trace.stat().st_size:
        plot_trace(trace, out / f"spacetime-seed{seed}.png", campaign.grid)
    return summary


def campaign_key(config: DriveConfig | dict[str, Any]) -> str:
    """What a record's drive configuration is compared by."""
    return json.dumps(config.to_json() if isinstance(config, DriveConfig) else config, sort_keys=True)


def recorded_runs(log: Path) -> dict[tuple[str, int], RunSummary]:
    """Every run recorded in ``log``, by (campaign key, seed); a record of another version is left out (run again)."""
    runs = {}
    for record in read_records(log):
        with contextlib.suppress(KeyError, TypeError, ValueError):
            summary = RunSummary.from_json(record["run"])
            runs[(campaign_key(record["campaign"]), summary.seed)] = summary
    return runs


def check_same_campaign(log: Path, campaign: DriveConfig) -> None:
    """Refuse to go on in a folder whose recorded runs were driven with another configuration (faults, model, km
    ...), naming the first difference: their traces and plots would be overwritten, and their runs never mix."""
    asked = campaign.all_json()
    for record in read_records(log):
        try:
            recorded_config = DriveConfig.from_json(record["campaign"]).all_json()
        except (KeyError, TypeError, ValueError, OptionError):
            continue  # a record of another version: run again, never mixed
        for key, value in asked.items():
            if recorded_config.get(key) != value:
                raise OptionError("--out", str(log.parent), f"holds runs with {key} = {recorded_config.get(key)!r}, "
                                  f"this campaign asks {value!r}; --fresh starts again, or use another --out")


def recorded(log: Path, campaign: DriveConfig) -> dict[int, RunSummary]:
    """Runs an earlier start of the same campaign finished, by seed."""
    key = campaign_key(campaign)
    return {seed: run for (other, seed), run in recorded_runs(log).items() if other == key}
