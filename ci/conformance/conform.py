"""Conformance campaign: registered engines must agree on generated scenarios, plan for plan.

Usage: python -m ci.conformance.conform --engines interpreter,spin --strategy sensible --count 500 --seed 7
       --out out/conform [--cell-m 10.5]

Every scenario's verdict is appended to ``OUT/results.jsonl`` as it is decided, so an
interrupted campaign resumes where it stopped (same seed, same scenarios). Each
disagreement is shrunk to a minimal reproducer ``OUT/repro-N.toml``. Exit 0 when all
agree, 6 on any disagreement, 2 on bad arguments, 130 on Ctrl-C, 143 on SIGTERM.
"""

from __future__ import annotations

import argparse
import itertools
import signal
import sys
from pathlib import Path
from typing import NoReturn

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

from ci.shared.gen import random_scenarios
from ci.shared.options import CELL_M, HORIZON, SECONDS, SEED, Whole, convert, names, out_dir
from ci.shared.records import append, campaign_lock, open_for_append, read_records
from ci.shared.signals import handled, received
from oracle.conform import disagreements
from oracle.planner import plan
from oracle.shrink import engines_disagree, shrink, to_toml
from spec.answers import Limits, Strategy
from spec.constants import DEFAULT_HORIZON
from spec.engines import Engine, check_strategy, get_engine, parse_strategy
from spec.errors import EngineError, ExitCode, OptionError, SuiteError
from spec.files import scenario_to_dict
from spec.grid import PAPER_GRID, Grid, grid_for

COUNT = Whole(0, 10_000_000)  # scenarios: ten million is weeks of Spin runs, more is a typo


class _Parser(argparse.ArgumentParser):
    """argparse whose own errors (an unknown option, a missing value) are one line and exit 2, as everywhere else."""

    def error(self, message: str) -> NoReturn:
        self.exit(ExitCode.BAD_INPUT, f"conform: error: {message} (see --help)\n")


class _Terminated(BaseException):
    """SIGTERM, raised where the campaign is, so that it ends like Ctrl-C: one line, what was decided kept (a
    BaseException, as KeyboardInterrupt is: no ``except Exception`` on the way may take it for a finding)."""


def _signalled(signum: int, _frame: object) -> None:
    if signum == signal.SIGTERM:
        raise _Terminated
    raise KeyboardInterrupt


def main(argv: list[str] | None = None) -> int:
    parser = _Parser(description=__doc__.splitlines()[0])
    parser.add_argument("--engines", default="interpreter,spin", help="comma-separated; the first is the reference")
    parser.add_argument("--strategy", default="sensible")
    parser.add_argument("--count", default="500")
    parser.add_argument("--seed", default="7")
    parser.add_argument("--horizon", default=str(DEFAULT_HORIZON))
    parser.add_argument("--timeout", default=None, help="seconds per scenario and engine")
    parser.add_argument("--out", default="out/conform")
    parser.add_argument("--cell-m", default=None,
                        help=f"cell length in metres (default: the paper's {float(PAPER_GRID.cell_m):g})")
    console = Console(stderr=True)
    try:
        with handled(_signalled):
            return _main(parser, argv, console)
    except (KeyboardInterrupt, _Terminated, Exception) as stopped:
        # a signal raises where the campaign is; inside a native call (ctypes) it arrives wrapped in another
        # exception, and a cancelled check raises KeyboardInterrupt: whatever comes after a signal is the signal
        signum = received()
        if signum is None and not isinstance(stopped, KeyboardInterrupt):
            raise
        if signum == signal.SIGTERM:
            console.print("conform: terminated (SIGTERM; what was decided is in results.jsonl; run again to resume)",
                          soft_wrap=True)
            return ExitCode.TERMINATED
        console.print("conform: interrupted (what was decided is in results.jsonl; run again to resume)",
                      soft_wrap=True)
        return ExitCode.INTERRUPTED


def _main(parser: argparse.ArgumentParser, argv: list[str] | None, console: Console) -> int:
    try:
        args = parser.parse_args(argv)
        strategy = parse_strategy(args.strategy)
        # an engine may be named twice: compared with itself, it must be deterministic
        engines = [get_engine(name) for name in names("--engines", args.engines, get_engine, distinct=False)]
        if len(engines) < 2:
            raise OptionError("--engines", args.engines, "name at least two engines: a campaign compares them")
        for engine in engines:
            check_strategy(engine, strategy)
            engine.ready()
        args.count = convert("--count", COUNT, args.count)
        args.seed = convert("--seed", SEED, args.seed)
        args.horizon = convert("--horizon", HORIZON, args.horizon)
        args.timeout = None if args.timeout is None else convert("--timeout", SECONDS, args.timeout)
        args.cell_m = None if args.cell_m is None else convert("--cell-m", CELL_M, args.cell_m)
        grid = grid_for(args.cell_m)
        out = out_dir("--out", args.out)
        with campaign_lock(out):
            return _campaign(args, console, strategy, grid, engines, out)
    except SuiteError as err:
        console.print(f"conform: error: {err}", soft_wrap=True)
        return err.exit_code


def _campaign(args: argparse.Namespace, console: Console, strategy: Strategy, grid: Grid, engines: list[Engine],
              out: Path) -> int:
    results = out / "results.jsonl"
    done = _done(results, args)
    heading = (f"seed {args.seed}; {args.count} scenarios on {grid.describe()}; engines {args.engines}; "
               f"strategy {strategy.value}")
    console.print(f"{heading}; resuming after {len(done)}" if done else heading)
    limits = Limits(timeout_s=args.timeout)
    scenarios = itertools.islice(random_scenarios(args.seed, horizon=args.horizon, grid=grid), args.count)
    bad = sum(1 for r in done.values() if r["disagreements"])
    columns = (TextColumn("conform"), BarColumn(), MofNCompleteColumn(), TextColumn("{task.fields[bad]} disagree"),
               TimeRemainingColumn())
    with Progress(*columns, console=console) as progress, open_for_append(results) as log:
        task = progress.add_task("conform", total=args.count, completed=len(done), bad=bad)
        for index, scenario in enumerate(scenarios):
            if index in done:
                continue
            try:
                answers = [plan(scenario, strategy, engine=e, limits=limits) for e in engines]
                problems = disagreements(answers)
                statuses = [a.status.value for a in answers]
            except EngineError as error:  # a finding, not the end of the campaign
                problems, statuses = [f"engine error: {error}"], ["error"]
            record = {"index": index, "seed": args.seed, "strategy": args.strategy, "engines": args.engines,
                      "cell_m": args.cell_m,
                      "scenario": scenario_to_dict(scenario), "statuses": statuses,
                      "disagreements": problems}
            if problems:
                bad += 1
                small, _ = shrink(scenario, engines_disagree(engines, strategy, limits))
                repro = out / f"repro-{index}.toml"
                repro.write_text(to_toml(small, f"seed {args.seed}, scenario {index}: " + "; ".join(problems)))
                record["reproducer"] = str(repro)
            append(log, record)
            progress.update(task, advance=1, bad=bad)
    records = _done(results, args)
    recorded_statuses = [r.get("statuses") for r in records.values()]
    incomplete = sum(isinstance(st, list) and "incomplete" in st for st in recorded_statuses)
    console.print(f"conform: {args.count} scenarios, {bad} disagreement(s), {incomplete} with an incomplete answer "
                  f"(a limit was hit; compared with nothing); results in {results}")
    print(f"{args.count - bad} passed, {bad} failed")
    return ExitCode.DISAGREE if bad else ExitCode.OK


def _done(results: Path, args: argparse.Namespace) -> dict[int, dict[str, object]]:
    """Verdicts already recorded by an earlier run of the same campaign (same seed, engines, strategy)."""
    key = (args.seed, args.engines, args.strategy, args.cell_m)
    return {record["index"]: record for record in read_records(results)
            if (record.get("seed"), record.get("engines"), record.get("strategy"), record.get("cell_m")) == key
            and isinstance(record.get("index"), int)}


if __name__ == "__main__":
    sys.exit(main())
