"""The ``overtake`` command: plan, validate, list and demonstrate built-in scenarios.

Every error reaches the user as one line on stderr with a documented exit code:
0 plan / valid, 1 no plan / invalid (simulate: a run failed), 2 bad input,
3 search incomplete, 4 a tool is missing, 5 an engine failed, 6 engines disagree, 130 interrupted.
"""

from __future__ import annotations

import json
import os
import sys
import threading
from pathlib import Path
from typing import Any

import click
from rich.console import Console
from rich.table import Table

from oracle.answer import Answer, Limits, Status, state_to_json
from oracle.conform import disagreements
from oracle.engines import check_strategy, get_engine, load_engines
from oracle.interpreter import Validation, validate
from oracle.planner import plan as run_plan
from oracle.render import draw
from oracle.shrink import engines_disagree, to_toml
from oracle.shrink import shrink as shrink_scenario
from spec.actions import Action, parse_action
from spec.constants import DEFAULT_HORIZON, MAX_HORIZON
from spec.errors import ScenarioError, SuiteError
from spec.files import load_scenario, scenario_to_dict
from spec.library import BUILTINS, builtin
from spec.models import ModelChoice, ModelKind, models_for
from spec.scenario import Scenario, problem_for

STRATEGIES = ("sensible", "shortest", "optimal")
#: Exit code when engines asked side by side (``--engine all``) disagree.
DISAGREE_EXIT = 6
MODELS = [m.value for m in ModelChoice]

out = Console(highlight=False, width=None if sys.stdout.isatty() else 120)


def _scenario(file: str) -> Scenario:
    """A scenario from a file path or the name of a built-in scenario."""
    path = Path(file)
    if not path.exists() and builtin(file) is not None:
        return builtin(file).load()  # type: ignore[union-attr]
    if not path.exists():
        raise ScenarioError("file", file, "no such file (nor a built-in scenario: see `overtake scenarios`)")
    return load_scenario(path)


def _horizon(horizon: int | None) -> int | None:
    if horizon is not None and not 0 <= horizon <= MAX_HORIZON:
        raise ScenarioError("--horizon", horizon, f"must be between 0 and {MAX_HORIZON}")
    return horizon


def _print_json(obj: Any) -> None:
    click.echo(json.dumps(obj, indent=2))


def _print_states(scenario: Scenario, actions: tuple[Action, ...], states: tuple) -> None:
    targets = scenario.target_indices
    out.print("step 0: start")
    for line in draw(states[0], targets):
        out.print(f"  {line}")
    for n, (action, state) in enumerate(zip(actions, states[1:]), start=1):
        out.print(f"step {n}: {action.value}")
        for line in draw(state, targets):
            out.print(f"  {line}")


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="overtake-mc")
def cli() -> None:
    """Plan overtaking manoeuvres by model checking, with cross-validated engines."""


@cli.command()
@click.argument("file")
@click.option("--strategy", type=click.Choice(STRATEGIES), default="sensible", show_default=True)
@click.option("--model", type=click.Choice(MODELS), default=None, help="Default: the scenario's (auto).")
@click.option("--horizon", type=int, default=None,
              help=f"Maximum plan length (default: the scenario's, else {DEFAULT_HORIZON}).")
@click.option("--engine", default="interpreter", show_default=True, help="An engine name (see `overtake engines`).")
@click.option("--max-states", type=click.IntRange(min=1), default=Limits().max_states, show_default=True,
              help="Stored states before the search gives up (answer: incomplete).")
@click.option("--timeout", type=click.FloatRange(min=0), default=None, help="Seconds before giving up (incomplete).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
def plan(file: str, strategy: str, model: str | None, horizon: int | None, engine: str, max_states: int,
         timeout: float | None, as_json: bool) -> None:
    """Plan an overtake for a scenario FILE (.json/.toml) or a built-in scenario name."""
    scenario = _scenario(file)
    choice, limits = ModelChoice(model) if model else None, Limits(max_states, timeout)
    if engine == "all":
        sys.exit(_plan_all(scenario, strategy, choice, _horizon(horizon), limits, as_json))
    answer = run_plan(scenario, strategy, choice, _horizon(horizon), engine, limits)
    if as_json:
        _print_json(answer.to_json())
    else:
        _print_answer(scenario, answer)
    sys.exit(answer.status.exit_code)


def _plan_all(scenario: Scenario, strategy: str, model: ModelChoice | None, horizon: int | None, limits: Limits,
              as_json: bool) -> int:
    """Run every engine that answers ``strategy``, side by side, and say whether they agree."""
    engines = [e for e in load_engines().values() if strategy in e.strategies]
    answers = [run_plan(scenario, strategy, model, horizon, e, limits) for e in engines]
    problems = disagreements(answers)
    if as_json:
        _print_json({"strategy": strategy, "answers": [a.to_json() for a in answers], "agree": not problems,
                     "disagreements": problems})
    else:
        table = Table(title=f"every engine, strategy {strategy}")
        for col in ("engine", "status", "model", "length", "plan", "ms"):
            table.add_column(col, overflow="fold")
        for a in answers:
            table.add_row(a.engine, a.status.value, a.model.value if a.model else "-", str(len(a.actions)),
                          _abbrev(a), f"{a.elapsed_ms:.1f}")
        out.print(table)
        out.print(f"agreement: all {len(answers)} engines agree" if not problems
                  else "DISAGREEMENT: " + "; ".join(problems))
    return DISAGREE_EXIT if problems else answers[0].status.exit_code


def _print_answer(scenario: Scenario, answer: Answer) -> None:
    model = answer.model.value if answer.model else "-"
    out.print(f"{answer.status.value} ({answer.engine}, {answer.strategy}, model {model}, "
              f"{answer.states_explored} states, {answer.elapsed_ms:.2f} ms)")
    if answer.detail:
        out.print(answer.detail)
    if answer.actions or answer.states:
        out.print("actions: " + (", ".join(a.value for a in answer.actions) or "(none: the goal already holds)"))
        _print_states(scenario, answer.actions, answer.states)


@cli.command(name="validate")
@click.argument("file")
@click.option("--actions", "actions_text", required=True, help="Comma-separated actions, e.g. accelerate,drive.")
@click.option("--model", type=click.Choice(MODELS), default=None, help="Default: the scenario's (auto: any model).")
@click.option("--horizon", type=int, default=None)
@click.option("--json", "as_json", is_flag=True)
def validate_cmd(file: str, actions_text: str, model: str | None, horizon: int | None, as_json: bool) -> None:
    """Check that an action list is a plan for FILE: enabled, collision-free, goal first at the end."""
    scenario = _scenario(file)
    actions = tuple(parse_action(a) for a in actions_text.split(",") if a.strip())
    choice = ModelChoice(model) if model else scenario.model
    verdicts = []
    for kind in models_for(choice):
        verdict = validate(problem_for(scenario, kind, _horizon(horizon)), actions)
        verdicts.append((kind, verdict))
        if verdict.valid:
            break
    kind, verdict = next(((k, v) for k, v in verdicts if v.valid), verdicts[0])
    reason = verdict.reason if verdict.valid else "; ".join(f"{k.value}: {v.reason}" for k, v in verdicts)
    if as_json:
        _print_json({"valid": verdict.valid, "reason": reason, "model": kind.value,
                     "states": [state_to_json(s) for s in verdict.states]})
    else:
        _print_validation(scenario, actions, kind.value, verdict, reason)
    sys.exit(0 if verdict.valid else 1)


def _print_validation(scenario: Scenario, actions: tuple[Action, ...], model: str, verdict: Validation,
                      reason: str) -> None:
    out.print(f"{'valid' if verdict.valid else 'invalid'} (model {model}): {reason}")
    _print_states(scenario, actions[: len(verdict.states) - 1], verdict.states)


@cli.command()
@click.option("--json", "as_json", is_flag=True)
def scenarios(as_json: bool) -> None:
    """List the built-in scenarios and their expected outcomes."""
    if as_json:
        _print_json([{"name": b.name, "description": b.description, "path": str(b.path),
                      "expected": b.expected.status, "model": b.expected.model} for b in BUILTINS])
        return
    table = Table(title="built-in scenarios")
    for col in ("name", "description", "expected", "model"):
        table.add_column(col)
    for b in BUILTINS:
        table.add_row(b.name, b.description, b.expected.status, b.expected.model)
    out.print(table)


@cli.command()
@click.argument("file")
@click.option("--model", type=click.Choice([m.value for m in ModelKind]), default=None,
              help="Default: the scenario's model, or the final model for auto.")
@click.option("--horizon", type=int, default=None)
@click.option("--out", type=click.Path(dir_okay=False, writable=True), default=None,
              help="Write the model here instead of printing it.")
def promela(file: str, model: str | None, horizon: int | None, out: str | None) -> None:
    """Write the Promela model of a scenario, runnable by hand: spin -a; gcc -DSAFETY -o pan pan.c; ./pan -E."""
    from promela.render import render_for  # Spin's renderer is only loaded when asked for

    scenario = _scenario(file)
    kind = ModelKind(model) if model else models_for(scenario.model)[0]
    text = render_for(problem_for(scenario, kind, _horizon(horizon)))
    if out:
        Path(out).write_text(text)
        click.echo(f"wrote {out} ({kind.value} model)")
    else:
        click.echo(text, nl=False)


@cli.command()
@click.argument("file")
@click.option("--json", "as_json", is_flag=True)
def explain(file: str, as_json: bool) -> None:
    """Name a minimal set of vehicles that makes the overtake impossible (Z3 unsat core, minimised)."""
    from oracle.explain import explain as explain_scenario  # loads Z3 only when asked for

    scenario = _scenario(file)
    result = explain_scenario(scenario)
    if as_json:
        _print_json({
            "has_plan": result.has_plan,
            "blocking": [{"lane": lane.value, "index": i, "name": result.name((lane, i))}
                         for lane, i in result.blocking],
            "reduced": scenario_to_dict(result.reduced) if result.reduced else None,
            "removals": [{"removed": result.name(v), "status": a.status.value,
                          "model": a.model.value if a.model else None, "plan": [x.value for x in a.actions]}
                         for v, a in result.removals],
        })
        return
    if result.has_plan:
        out.print(f"{file} has a plan: nothing to explain (`overtake plan {file}` shows it). "
                  "Which vehicle forced each wait or brake of a plan is not explained yet.")
        return
    if not result.blocking:
        out.print(f"no plan for {file}, and no vehicle is to blame: the horizon of {scenario.horizon} is too short.")
        return
    out.print(f"no plan for {file}. These {len(result.blocking)} vehicle(s) alone make the overtake impossible, "
              "and removing any one of them gives a plan:")
    for vehicle, answer in result.removals:
        plan_text = ", ".join(a.value for a in answer.actions) or "(the empty plan)"
        out.print(f"  {result.name(vehicle)}: without it, {answer.model.value if answer.model else '-'} model: "
                  f"{plan_text}")


@cli.command()
@click.option("--km", type=click.FloatRange(min=0.01), default=5.0, show_default=True,
              help="Kilometres per run (with --until-failure: the cap).")
@click.option("--until-failure", is_flag=True, help="Stop each run at its first failure (capped by --km).")
@click.option("--seed", type=int, default=1, show_default=True, help="Run i uses seed + i.")
@click.option("--engine", default="interpreter", show_default=True)
@click.option("--strategy", type=click.Choice(["sensible", "shortest"]), default="sensible", show_default=True)
@click.option("--runs", type=click.IntRange(min=1), default=1, show_default=True)
@click.option("--workers", type=click.IntRange(min=1), default=1, show_default=True,
              help="Local processes (with --executor dask and no --scheduler: the local cluster's workers).")
@click.option("--executor", "executor_kind", type=click.Choice(["processes", "dask"]), default="processes",
              show_default=True, help="Where runs go: local processes or a dask.distributed cluster.")
@click.option("--scheduler", default=None, help="With --executor dask: a running scheduler's address.")
@click.option("--out", "out_dir", default="out/sim", show_default=True,
              help="Runs (runs.jsonl, resumable), traces (JSON lines) and plots.")
@click.option("--fresh", is_flag=True, help="Forget the runs already recorded in --out instead of resuming.")
@click.option("--step-tolerance", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Cells one action may add to a vehicle's deviation from the prediction [default: from spec/].")
@click.option("--plan-tolerance", type=click.FloatRange(min=0.0, min_open=True), default=None,
              help="Cells a vehicle may deviate over a plan [default: from spec/].")
@click.option("--paper-replanning", is_flag=True,
              help="Re-plan only as the paper did (not when a deviation exceeds the tolerance).")
@click.option("--json", "as_json", is_flag=True)
def simulate(km: float, until_failure: bool, seed: int, engine: str, strategy: str, runs: int, workers: int,
             executor_kind: str, scheduler: str | None, out_dir: str, fresh: bool, step_tolerance: float | None,
             plan_tolerance: float | None, paper_replanning: bool, as_json: bool) -> None:
    """Drive the PyBullet simulator closed-loop and check every action against the model's prediction."""
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

    from ci.executors import ExecutorChoice, check_executor
    from sim.campaign import RUNS_FILE, Campaign
    from sim.campaign import simulate as run_campaign
    from sim.tables import deviations_table, paper_table, runs_table, totals_table
    from spec.physical import LOOP

    check_strategy(get_engine(engine), strategy)
    executor = ExecutorChoice(executor_kind, workers, scheduler)
    check_executor(executor)
    campaign = Campaign(km, until_failure, engine, strategy, not paper_replanning,
                        step_tolerance or LOOP.step_tolerance_cells, plan_tolerance or LOOP.plan_tolerance_cells)
    err = Console(stderr=True)
    limit = f"{km:g} km" + (" or until failure" if until_failure else "")
    err.print(f"seeds {seed}..{seed + runs - 1}; {runs} run(s) of {limit}; engine {engine}, {strategy}; "
              f"on {executor.describe()}; results in {Path(out_dir) / RUNS_FILE}")
    columns = (TextColumn("simulate"), BarColumn(), TextColumn("{task.fields[km]:.1f} of {task.total:.0f} km"),
               TextColumn("{task.fields[failed]} failed"), TimeElapsedColumn(), TimeRemainingColumn())
    with Progress(*columns, console=err, transient=True) as progress:
        task = progress.add_task("simulate", total=runs * km, km=0.0, failed=0)
        km_by_seed: dict[int, float] = {}  # how far each run has driven
        finished: set[int] = set()  # a finished run fills its share of the bar, wherever it stopped
        failed = [0]
        lock = threading.Lock()  # kilometres arrive from a thread draining the workers' reports

        def show() -> None:
            share = sum(km if s in finished else min(d, km) for s, d in km_by_seed.items())
            progress.update(task, completed=share, km=sum(km_by_seed.values()), failed=failed[0])

        def moved(update: tuple[int, float]) -> None:
            with lock:
                km_by_seed[update[0]] = update[1]
                show()

        def done(summary: Any, resumed: bool) -> None:
            if resumed:
                err.print(f"seed {summary.seed}: already in {RUNS_FILE} (resumed; --fresh runs it again)")
            with lock:
                km_by_seed[summary.seed] = summary.km
                finished.add(summary.seed)
                failed[0] += bool(summary.failures)
                show()

        results = run_campaign(campaign, list(range(seed, seed + runs)), out_dir, executor, done, fresh, moved)
    if as_json:
        _print_json([r.to_json() for r in results])
    else:
        for table in (runs_table(results), totals_table(results), deviations_table(results)):
            out.print(table)
        if until_failure:
            out.print(paper_table(results, km))
    sys.exit(1 if any(r.failures for r in results) else 0)


@cli.command()
def engines() -> None:
    """List the registered engines and the strategies each answers."""
    table = Table(title="engines")
    for col in ("engine", "strategies", "description"):
        table.add_column(col)
    for engine in load_engines().values():
        table.add_row(engine.name, ", ".join(engine.strategies), engine.description)
    out.print(table)


@cli.command()
@click.option("--strategy", type=click.Choice(STRATEGIES), default="sensible", show_default=True)
@click.option("--engine", "engine_names", multiple=True, help="Engines to run (default: every registered one).")
def demo(strategy: str, engine_names: tuple[str, ...]) -> None:
    """Plan every built-in scenario with every engine, side by side; exit 1 on any unexpected answer."""
    registry = load_engines()
    for name in engine_names:
        if name not in registry:
            raise ScenarioError("--engine", name, f"unknown engine (known: {', '.join(registry)})")
    engines = [registry[n] for n in engine_names or registry if strategy in registry[n].strategies]
    table = Table(title=f"overtake demo: built-in scenarios, strategy {strategy}")
    table.add_column("scenario", no_wrap=True)
    table.add_column("expected")
    for engine in engines:
        table.add_column(f"{engine.name}: plan (length) ms", overflow="fold")
    table.add_column("agree")
    unexpected = 0
    for b in BUILTINS:
        answers = [run_plan(b.load(), strategy, engine=e) for e in engines]
        cells = []
        for a in answers:
            ok = _matches(a, b.expected, strategy)
            unexpected += not ok
            cells.append(f"{_abbrev(a)} ({len(a.actions)}) {a.elapsed_ms:.1f}" + ("" if ok else " UNEXPECTED"))
        expected = f"{b.expected.status}, {b.expected.model}"
        table.add_row(b.name, expected, *cells, "yes" if not disagreements(answers) else "NO")
    out.print(table)
    out.print("plans: L left_lane_change, A accelerate, R right_lane_change, D drive, B brake; "
              "(n) actions; ms per plan, whole pipeline")
    out.print("all answers as expected" if not unexpected else f"{unexpected} answer(s) differ from expectation")
    _demo_drive()
    sys.exit(1 if unexpected else 0)


def _demo_drive(km: float = 1.0, seed: int = 1) -> None:
    """A short closed-loop drive in the PyBullet simulator, summarised in two lines."""
    from sim.simulator import run_drive  # PyBullet loads only when asked for

    r = run_drive(seed, km)
    largest = ", ".join(f"{a} {d:.2f}" for a, d in sorted(r.tolerance.largest.items()))
    out.print(f"simulated drive (seed {seed}): {r.km:.2f} km in {r.sim_time_s / 60:.1f} simulated min "
              f"({r.wall_s:.1f} s wall), {r.overtakes} overtakes, {r.plans} plans, "
              f"{'no collision' if not r.collisions else r.collisions[0].cause + ', ' + r.collisions[0].detail}")
    out.print(f"  largest deviation from the model per action (cells): {largest}; "
              f"{len(r.tolerance.violations)} beyond tolerance (`overtake simulate` for more)")


def _abbrev(answer: Answer) -> str:
    """A plan as letters, or the status when there is none."""
    if answer.status is not Status.PLAN:
        return answer.status.value
    return " ".join(_short(a) for a in answer.actions) or "(empty)"


@cli.command()
@click.argument("file")
@click.option("--engine", "engine_names", multiple=True, required=True,
              help="Two or more engines to compare (repeat the option).")
@click.option("--strategy", type=click.Choice(STRATEGIES), default="sensible", show_default=True)
@click.option("--out", type=click.Path(dir_okay=False, writable=True), default=None,
              help="Write the reproducer here (TOML) instead of printing it.")
def shrink(file: str, engine_names: tuple[str, ...], strategy: str, out: str | None) -> None:
    """Shrink a scenario on which engines disagree to a minimal reproducer."""
    scenario = _scenario(file)
    engines = [get_engine(n) for n in engine_names]
    if len(engines) < 2:
        raise ScenarioError("--engine", engine_names, "name at least two engines to compare")
    for engine in engines:
        check_strategy(engine, strategy)
    fails = engines_disagree(engines, strategy)
    if not fails(scenario):
        click.echo(f"engines {', '.join(engine_names)} agree on {file}: nothing to shrink")
        sys.exit(0)
    small, checks = shrink_scenario(scenario, fails)
    answers = [run_plan(small, strategy, engine=e) for e in engines]
    why = "; ".join(disagreements(answers))
    text = to_toml(small, f"minimal reproducer from {file} ({checks} checks), strategy {strategy}:\n{why}")
    if out:
        Path(out).write_text(text)
        click.echo(f"wrote {out}: {why}")
    else:
        click.echo(text, nl=False)
    sys.exit(DISAGREE_EXIT)


def _short(action: Action) -> str:
    return {"left_lane_change": "L", "right_lane_change": "R"}.get(action.value, action.value[0].upper())


def _matches(answer: Answer, expected: Any, strategy: str) -> bool:
    return matches_expectation(answer, expected, strategy, get_engine(answer.engine).prove_beyond is not None)


def matches_expectation(answer: Answer, expected: Any, strategy: str, proves_beyond: bool) -> bool:
    """Whether an answer is the built-in scenario's expected one.

    An engine that cannot prove "no plan of any length" may answer the weaker
    "no plan within the horizon" where the expectation is "no plan".
    """
    status = answer.status.value
    if expected.status == "no_plan" and not proves_beyond and status == "no_plan_within_horizon":
        status = "no_plan"
    if status != expected.status or (answer.model and answer.model.value != expected.model):
        return False
    if strategy == "sensible":
        return tuple(a.value for a in answer.actions) == expected.sensible
    return strategy != "shortest" or len(answer.actions) == expected.shortest_length


def main() -> None:
    """Entry point: run the CLI, turning every suite error into one line and its exit code."""
    try:
        cli.main(standalone_mode=False)
    except click.exceptions.Exit as done:
        sys.exit(done.exit_code)
    except click.UsageError as err:
        command = err.ctx.command_path if err.ctx else "overtake"
        click.echo(f"overtake: error: {err.format_message()} (see `{command} --help`)", err=True)
        sys.exit(2)
    except click.ClickException as err:
        click.echo(f"overtake: error: {err.format_message()}", err=True)
        sys.exit(err.exit_code)
    except click.exceptions.Abort:
        click.echo("overtake: interrupted", err=True)
        sys.exit(130)
    except SuiteError as err:
        click.echo(f"overtake: error: {err}", err=True)
        sys.exit(err.exit_code)
    except Exception as err:
        if os.environ.get("OVERTAKE_DEBUG"):
            raise
        click.echo(f"overtake: internal error: {type(err).__name__}: {err} (set OVERTAKE_DEBUG=1 for details)",
                   err=True)
        sys.exit(5)


if __name__ == "__main__":
    main()
