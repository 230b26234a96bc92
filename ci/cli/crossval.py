"""The crossval command: every registered property on scenarios from a source, as CI runs it."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
from rich.progress import BarColumn, MofNCompleteColumn, Progress, ProgressColumn, Task, TextColumn, TimeRemainingColumn
from rich.table import Table
from rich.text import Text

from ci.cli.common import (
    cell_option,
    err,
    horizon_option,
    out,
    print_header,
    print_json,
    print_paths,
    print_table,
    whole_sound_options,
)
from ci.shared.executors import ExecutorChoice, ExecutorKind, check_executor
from ci.shared.options import CHECK_COUNT, MAX_WORKERS, REPRODUCERS, SCHEDULER, SECONDS, SEED, WORKERS, names
from ci.shared.options import out_dir as checked_out_dir
from ci.shared.records import campaign_lock
from oracle.coverage import CoverageTarget
from spec.assumptions import DEFAULT_PROFILE, profile
from spec.errors import ExitCode, OptionError
from spec.escapes import Semantics
from spec.lanes import Lane
from spec.scenario import Scenario
from spec.sound import Checks, Sound

if TYPE_CHECKING:
    from ci.conformance.properties import PropertyName

SOURCES = ("library", "hypothesis", "exhaustive")
MODELS = ("paper", "sound")
DEFAULT_SPACE = "left=2@8..20,right=1@12..30,lanes=both"


class RateColumn(ProgressColumn):
    """Scenarios per second."""

    def render(self, task: Task) -> Text:
        return Text(f"{task.speed:.1f}/s" if task.speed else "-/s")


@click.command()
@click.option("--source", type=click.Choice(SOURCES), default="library", show_default=True)
@click.option("--space", default=DEFAULT_SPACE, show_default=True,
              help="With --source exhaustive: left=N@A..B,right=M@C..D[,lanes=left|right|both] (cells).")
@click.option("--properties", "property_text", default="all", show_default=True,
              help="Comma-separated property names, or all (see --list).")
@click.option("--engines", "engine_text", default="interpreter,spin,z3", show_default=True)
@click.option("--workers", type=WORKERS, default=None, help=f"Default: every core (at most {MAX_WORKERS}).")
@click.option("--executor", "executor_kind", type=click.Choice([k.value for k in ExecutorKind]),
              default=ExecutorKind.PROCESSES.value, show_default=True)
@click.option("--scheduler", type=SCHEDULER, default=None, help="With --executor dask: a running scheduler's address.")
@click.option("--timeout", "timeout_s", type=SECONDS, default=10.0, show_default=True,
              help="Seconds per engine run (past it: incomplete).")
@click.option("--coverage-target", "coverage_text", type=click.Choice([t.value for t in CoverageTarget]),
              default=CoverageTarget.NONE.value, show_default=True,
              help="Rules every campaign must exercise (exit 7 otherwise): 'grid', those the cell size decides "
                   "differently from the paper's 21 m; 'all', every rule that can occur there.")
@click.option("--seed", type=SEED, default=None,
              help="With --source hypothesis (default: drawn, and printed).")
@click.option("--count", type=CHECK_COUNT, default=None,
              help="At most this many scenarios: with --source hypothesis, examples per property (instead of the "
                   "profile's); otherwise that many spread evenly through the library or the space, in its order.")
@click.option("--max-reproducers", type=REPRODUCERS, default=3, show_default=True,
              help="Failures shrunk per property.")
@cell_option()
@horizon_option()
@click.option("--out", "out_dir", default="out/crossval", show_default=True)
@click.option("--fresh", is_flag=True, help="Forget the verdicts already recorded in --out instead of resuming.")
@click.option("--list", "list_only", is_flag=True, help="List the registered properties and exit.")
@click.option("--json", "as_json", is_flag=True)
@click.option("--model", "model_name", type=click.Choice(MODELS), default="paper", show_default=True,
              help="The paper's rules, or the sound model (under --bounds and the options below; with --source "
                   "hypothesis the bounds are drawn with each scenario unless given).")
@click.option("--semantics", "semantics_text", type=click.Choice([s.value for s in Semantics]),
              default=Semantics.WHOLE.value, show_default=True,
              help="With --model sound: whole plans, or the commitment semantics (committed actions, a proved escape, "
                   "a predicted continuation; each engine must answer it). See docs/sound.md.")
@whole_sound_options
def crossval(source: str, space: str, property_text: str, engine_text: str, workers: int | None, executor_kind: str,
             scheduler: str | None, timeout_s: float, coverage_text: str, seed: int | None, count: int | None,
             max_reproducers: int,
             cell_m: float | None, horizon: int | None, out_dir: str, fresh: bool, list_only: bool, as_json: bool,
             model_name: str, semantics_text: str, sound: Callable[[Scenario], Scenario]) -> None:
    """Check every property on scenarios from a source; exit 0 when all hold, 6 on any failure, 3 when none failed
    but one could not be decided, 7 when every property held but the coverage target was missed."""
    from ci.conformance.crossval import (
        VERDICTS_FILE,
        Campaign,
        Summary,
        check_resumable,
        library_scenarios,
        parse_space,
        spread,
        write_reports,
    )
    from ci.conformance.properties import PROPERTIES
    from spec.grid import grid_for

    if list_only:
        for prop in PROPERTIES.values():
            out.print(f"{prop.name.value}: {prop.doc} (runs: {', '.join(k.label for k in prop.runs)})")
        sys.exit(ExitCode.OK)
    grid = grid_for(cell_m)
    properties = _properties(property_text)
    engines = _engines(engine_text)
    model = _model(model_name, sound, grid, source, engines)
    commit = _commit(Semantics(semantics_text), model, engines)
    if model is not None and coverage_text != CoverageTarget.NONE.value:
        raise OptionError("--coverage-target", coverage_text, "names the paper model's rules; a --model sound campaign "
                                                              "has no rule coverage yet")
    executor = ExecutorChoice(ExecutorKind(executor_kind), workers or min(os.cpu_count() or 1, MAX_WORKERS), scheduler)
    check_executor(executor)
    chosen = [p for p in properties if PROPERTIES[p].applies(engines)]
    if not chosen:
        raise OptionError("--engines", engine_text, "no selected property applies to these engines")
    skipped = [p.value for p in properties if p not in chosen]
    out_path = checked_out_dir("--out", out_dir)
    click.get_current_context().with_resource(campaign_lock(Path(out_dir)))  # before any line: one campaign per folder
    scenarios: list[Any] = []
    the_space = None
    if source == "library":
        scenarios = library_scenarios(grid)
        if horizon is not None:
            from dataclasses import replace

            scenarios = [replace(s, horizon=horizon) for s in scenarios]
    elif source == "exhaustive":
        the_space = parse_space(space, grid)
    if source == "hypothesis" and seed is None:
        seed = int.from_bytes(os.urandom(4), "little")
    campaign = Campaign(source, tuple(chosen), engines, float(grid.cell_m), horizon, timeout_s,
                        the_space.describe() if the_space else None, seed if source == "hypothesis" else None, model,
                        count, commit)
    if fresh:
        (out_path / VERDICTS_FILE).unlink(missing_ok=True)
    check_resumable(out_path / VERDICTS_FILE, campaign)  # before any line: one model and bounds per folder
    print_header(err, f"crossval: source {source}; properties {', '.join(p.value for p in chosen)}"
              + (f" (not applicable to these engines: {', '.join(skipped)})" if skipped else "")
              + f"; engines {', '.join(engines)}; {_describe(model)}"
              + ("; the commitment semantics" if commit else "") + f"; on {executor.describe()}"
              + (f"; seed {seed}" if source == "hypothesis" else ""), out_dir)
    summary = Summary(CoverageTarget(coverage_text), float(grid.cell_m), paper=model is None)
    started = time.perf_counter()
    if source == "hypothesis":
        from ci.conformance.hypo import run_hypothesis

        results, reproducers = run_hypothesis(campaign, out_path, executor, max_reproducers, err)
        for result in results:
            summary.add(result)
    else:
        if the_space is not None:
            err.print(f"crossval: space {the_space.describe()}: {the_space.candidates()} candidates ...")
            scenarios = list(the_space.scenarios(grid, horizon))
            err.print(f"crossval: {len(scenarios)} valid scenarios in the space ("
                      + ("every one is checked)" if count is None or count >= len(scenarios) else
                         f"{count} spread through it are checked: --count)"))
        elif count is not None and count < len(scenarios):
            err.print(f"crossval: {count} of the library's {len(scenarios)} scenarios, spread through it (--count)")
        scenarios = spread(scenarios, count)
        _sweep(campaign, scenarios, out_path, executor, summary)
        reproducers = _reproduce(summary, campaign, out_path, max_reproducers)
    data = summary.to_json(campaign, reproducers)
    paths = write_reports(data, summary, campaign, out_path)
    wall_s = time.perf_counter() - started
    if as_json:
        print_json(data)
    else:
        _print(data, wall_s)
        print_paths("written:", paths)
    if not summary.all_held:  # a failure is a disagreement; a verdict not reached alone claims nothing
        sys.exit(ExitCode.DISAGREE if summary.any_failed else ExitCode.INCOMPLETE)
    sys.exit(ExitCode.COVERAGE_MISSED if summary.missed() else ExitCode.OK)


def _properties(text: str) -> tuple[PropertyName, ...]:
    """Registered property names, or "all"."""
    from ci.conformance.properties import PROPERTIES, PropertyName

    if text.strip() == "all":
        return tuple(PROPERTIES)
    known = ", ".join(p.value for p in PROPERTIES)

    def check(name: str) -> None:
        if name not in {p.value for p in PROPERTIES}:
            raise OptionError("--properties", name, f"unknown property (known: {known}, or all)")

    return tuple(PropertyName(name) for name in names("--properties", text, check))


def _model(name: str, sound: Callable[[Scenario], Scenario], grid: Any, source: str,
           engines: tuple[str, ...]) -> Sound | str | None:
    """The campaign's model: None (the paper's rules), the sound model the options choose, or drawn with each
    scenario (the hypothesis source without bounds options); bad input names the option, the value and why."""
    from ci.conformance.crossval import DRAWN
    from spec.engines import get_engine, load_engines
    from spec.scenario import make_scenario

    probe = sound(make_scenario(Lane.RIGHT, [], [], 0, grid=grid))  # the options on an empty road: their model
    if name == "paper":
        if probe.sound is not None:
            raise OptionError("--bounds", probe.sound.bounds.name, "the bounds options choose the sound model: add "
                                                                   "--model sound")
        return None
    for engine in engines:
        if not get_engine(engine).sound:
            able = ", ".join(e.name for e in load_engines().values() if e.sound) or "none"
            raise OptionError("--engines", engine, f"engine {engine} answers the paper model only, not --model sound "
                                                   f"(the sound model is answered by: {able})")
    if probe.sound is not None:
        if probe.sound.checks is not Checks.PHYSICAL:
            raise OptionError("--model", name, "the identity check's cell rules are not a campaign's model")
        return probe.sound
    return DRAWN if source == "hypothesis" else Sound(profile(DEFAULT_PROFILE))


def _commit(semantics: Semantics, model: Sound | str | None, engines: tuple[str, ...]) -> bool:
    """Whether the campaign holds the engines to the commitment semantics; bad input names the option and why."""
    from spec.engines import get_engine, load_engines

    if semantics is Semantics.WHOLE:
        return False
    if model is None:
        raise OptionError("--semantics", semantics.value, "the commitment semantics is the sound model's: add "
                                                          "--model sound")
    for engine in engines:
        if not get_engine(engine).commit:
            able = ", ".join(e.name for e in load_engines().values() if e.commit) or "none"
            raise OptionError("--engines", engine, f"engine {engine} answers the sound model's whole plans only, not "
                                                   f"--semantics commit (answered by: {able})")
    return True


def _describe(model: Sound | str | None) -> str:
    if model is None:
        return "the paper's rules"
    return f"the sound model, bounds {model}" if isinstance(model, str) else model.describe()


def _engines(text: str) -> tuple[str, ...]:
    from spec.engines import get_engine

    found = names("--engines", text, get_engine)
    for name in found:
        get_engine(name).ready()  # exit 4 with the install command, before any work
    return found


def _sweep(campaign: Any, scenarios: list[Any], out_path: Path, executor: ExecutorChoice, summary: Any) -> list[Any]:
    from ci.conformance.crossval import run_sweep

    columns = (TextColumn("crossval"), BarColumn(), MofNCompleteColumn(), RateColumn(),
               TextColumn("{task.fields[failed]} failing"), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task("crossval", total=len(scenarios), failed=0)

        def on_result(result: dict[str, Any], resumed: bool) -> None:
            summary.add(result)
            failing = sum(1 for v in result["verdicts"].values() if v[0] != "held")
            progress.update(task, advance=1 if resumed or executor.kind is ExecutorKind.DASK else 0,
                            failed=progress.tasks[0].fields["failed"] + (1 if failing else 0))

        def on_checked(_n: int) -> None:
            progress.update(task, advance=1)

        results = run_sweep(campaign, scenarios, out_path, executor, on_result, on_checked)
    return results


def _reproduce(summary: Any, campaign: Any, out_path: Path, max_reproducers: int) -> list[dict[str, Any]]:
    from ci.conformance.properties import PropertyName
    from ci.conformance.repro import reproduce
    from spec.files import scenario_from_dict

    written = []
    for name, failures in summary.failures.items():
        real = [r for r in failures if r["verdicts"][name][0] == "failed"][:max_reproducers]
        for n, result in enumerate(real, start=1):
            err.print(f"crossval: shrinking a {name} failure ({n} of {len(real)}) ...")
            written.append(reproduce(PropertyName(name), scenario_from_dict(result["scenario"]), campaign.engines,
                                     campaign.timeout_s, out_path, n, result["key"]))
    return written


def _print(data: dict[str, Any], wall_s: float) -> None:
    table = Table(title=f"crossval: {data['scenarios']} scenarios in {wall_s:.1f} s")
    for col in ("property", "checked", "held", "failed", "incomplete"):
        table.add_column(col, justify="right")
    for name, v in data["properties"].items():
        table.add_row(name, str(v["checked"]), str(v["held"]), str(v["failed"]), str(v["incomplete"]))
    print_table(table, 1, "summary.md")
    latency = Table(title="latency per run (engine/strategy)")
    for col in ("run", "n", "median ms", "p99 ms"):
        latency.add_column(col, justify="right")
    for label, v in data["latency"].items():
        latency.add_row(label, str(v["n"]), str(v["median_ms"]), str(v["p99_ms"]))
    print_table(latency, 1, "summary.md")
    for cell, rules in data["rule_coverage"].items():
        coverage = Table(title=f"rule coverage at {cell}: scenarios that exercised each rule")
        coverage.add_column("rule")
        coverage.add_column("scenarios", justify="right")
        for rule, n in rules.items():
            coverage.add_row(rule, str(n))
        print_table(coverage, 1, "summary.md")
    target = data["coverage_target"]
    if target["missed"]:
        out.print(f"coverage target {target['target']} missed: no scenario exercised {'; '.join(target['missed'])}")
    elif target["target"] != "none":
        out.print(f"coverage target {target['target']} met")
    for r in data["reproducers"]:
        out.print(f"reproducer ({r['property']}, {r['vehicles']} vehicle(s), horizon {r['horizon']}): "
                  f"{r['scenario_file']} — {r['detail']}")


COMMANDS = (crossval,)
