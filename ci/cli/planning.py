"""Commands about one scenario: plan, validate, promela, explain, shrink."""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import TYPE_CHECKING

import click
from rich.table import Table

from ci.cli.common import (
    MODEL,
    abbrev,
    cell_option,
    horizon_option,
    load,
    out,
    print_json,
    print_states,
    print_table,
    sound_options,
    strategy_option,
)
from ci.shared.options import MAX_STATES, SECONDS, out_file
from oracle.commit import CommitValidation
from oracle.conform import disagreements
from oracle.planner import plan as run_plan
from oracle.planner import validate_pipeline
from oracle.shrink import engines_disagree, to_toml
from oracle.shrink import shrink as shrink_scenario
from spec.actions import parse_action
from spec.answers import Answer, Commit, Limits, Status, Strategy, state_to_json
from spec.assumptions import Phantom
from spec.engines import check_strategy, get_engine, load_engines
from spec.errors import ActionError, ExitCode, OptionError
from spec.files import scenario_to_dict
from spec.models import ModelChoice, ModelKind, models_for
from spec.scenario import Problem, Scenario, problem_for
from spec.sound import Violation, sound_to_table

if TYPE_CHECKING:
    from oracle.why import SoundExplanation, Suspect


@click.command()
@click.argument("file")
@strategy_option()
@click.option("--model", type=MODEL, default=None, help="Default: the scenario's (auto).")
@horizon_option()
@cell_option()
@click.option("--engine", default="interpreter", show_default=True,
              help="An engine name (see `overtake engines`), or all: every engine that answers the strategy.")
@click.option("--max-states", type=MAX_STATES, default=Limits().max_states, show_default=True,
              help="Stored states before the search gives up (answer: incomplete).")
@click.option("--timeout", type=SECONDS, default=None, help="Seconds before giving up (incomplete).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object.")
@sound_options
def plan(file: str, strategy: Strategy, model: str | None, horizon: int | None, cell_m: float | None, engine: str,
         max_states: int, timeout: float | None, as_json: bool, sound: Callable[[Scenario], Scenario]) -> None:
    """Plan an overtake for a scenario FILE (.json/.toml) or a built-in scenario name."""
    scenario = sound(load(file, cell_m))
    choice, limits = ModelChoice(model) if model else None, Limits(max_states, timeout)
    if engine == "all":
        sys.exit(_plan_all(scenario, strategy, choice, horizon, limits, as_json))
    answer = run_plan(scenario, strategy, choice, horizon, engine, limits)
    if as_json:
        print_json({**answer.to_json(), **_sound_json(scenario)})
    else:
        _print_answer(scenario, answer)
    sys.exit(answer.status.exit_code)


def _plan_all(scenario: Scenario, strategy: Strategy, model: ModelChoice | None, horizon: int | None, limits: Limits,
              as_json: bool) -> int:
    """Run every engine that answers ``strategy``, side by side, and say whether they agree."""
    committed = scenario.sound is not None and scenario.sound.commitment is not None
    engines = [e for e in load_engines().values() if strategy in e.strategies and (e.sound or scenario.sound is None)
               and (e.commit or not committed)]
    answers = [run_plan(scenario, strategy, model, horizon, e, limits) for e in engines]
    problems = disagreements(answers)
    if as_json:
        print_json({"strategy": strategy.value, "answers": [a.to_json() for a in answers], "agree": not problems,
                    "disagreements": problems})
    else:
        table = Table(title=f"every engine, strategy {strategy.value}")
        for col in ("engine", "status", "model", "length", "plan", "ms"):
            table.add_column(col, overflow="fold")
        for a in answers:
            table.add_row(a.engine, a.status.value, a.model.value if a.model else "-", str(len(a.actions)),
                          abbrev(a), f"{a.elapsed_ms:.1f}")
        print_table(table)
        out.print(f"agreement: all {len(answers)} engines agree" if not problems
                  else "DISAGREEMENT: " + "; ".join(problems))
    return ExitCode.DISAGREE if problems else answers[0].status.exit_code


def _sound_json(scenario: Scenario) -> dict[str, object]:
    """The sound model's bounds beside an answer (nothing under the paper's rules)."""
    if scenario.sound is None:
        return {}
    return {"sound": {**sound_to_table(scenario.sound), "bounds": scenario.sound.bounds.name,
                      "source": scenario.sound.bounds.source}}


def _print_answer(scenario: Scenario, answer: Answer) -> None:
    if scenario.sound is not None:
        out.print(scenario.sound.describe())
    model = answer.model.value if answer.model else "-"
    out.print(f"{answer.status.value} ({answer.engine}, {answer.strategy.value}, model {model}, "
              f"{answer.states_explored} states, {answer.elapsed_ms:.2f} ms)")
    if answer.detail:
        out.print(answer.detail)
    if answer.commit is not None:
        _print_commit(answer.commit)
    elif answer.actions or answer.states:
        out.print("actions: " + (", ".join(a.value for a in answer.actions) or "(none: the goal already holds)"))
    if answer.actions or answer.states:
        print_states(scenario, answer.actions, answer.states)


def _print_commit(parts: Commit) -> None:
    """The commitment semantics' three parts, each labelled with what is proved of it."""
    if parts.committed or parts.escape is None:
        out.print("committed: " + (", ".join(a.value for a in parts.committed) or "(none: the goal already holds)")
                  + " (proved: safe at every instant for every motion inside the assumptions"
                  + (", to the goal and for ever after)" if parts.escape is None else ")"))
    if parts.escape is not None:
        out.print(f"escape: {parts.escape.describe()} "
                  + ("(proved with the committed actions, safe for ever after)" if parts.escape_proved else
                     "(to take at once; nothing is proved from this start)"))
    if parts.predicted:
        out.print("predicted: " + ", ".join(a.value for a in parts.predicted)
                  + " (the paper's rules from the snapshot's cells: nominal motion, no safety claim)")


@click.command(name="validate")
@click.argument("file")
@click.option("--actions", "actions_text", required=True, help="Comma-separated actions, e.g. accelerate,drive.")
@click.option("--model", type=MODEL, default=None, help="Default: the scenario's (auto: any model).")
@horizon_option()
@cell_option()
@click.option("--json", "as_json", is_flag=True)
@sound_options
def validate_cmd(file: str, actions_text: str, model: str | None, horizon: int | None, cell_m: float | None,
                 as_json: bool, sound: Callable[[Scenario], Scenario]) -> None:
    """Check that an action list is a plan for FILE: enabled, collision-free, goal first at the end (under the sound
    model: safe at every instant for every motion within the bounds, and safe for ever after)."""
    scenario = sound(load(file, cell_m))
    names = actions_text.split(",")
    if any(not name.strip() for name in names) and actions_text.strip():  # "" alone is the empty plan
        raise OptionError("--actions", actions_text, "an empty action between commas")
    try:
        actions = tuple(parse_action(a) for a in names if a.strip())
    except ActionError as error:
        raise OptionError("--actions", actions_text, str(error)) from None
    checked = validate_pipeline(scenario, actions, ModelChoice(model) if model else None, horizon)
    verdict = checked.verdict
    parts = verdict.commit if isinstance(verdict, CommitValidation) else None
    if as_json:
        print_json({"valid": verdict.valid, "reason": checked.reason, "model": checked.model.value,
                    "states": [state_to_json(s) for s in verdict.states], **({} if parts is None else parts.to_json())})
    else:
        out.print(f"{'valid' if verdict.valid else 'invalid'} (model {checked.model.value}): {checked.reason}")
        if parts is not None:
            _print_commit(parts)
        print_states(scenario, actions[: len(verdict.states) - 1], verdict.states)
    sys.exit(ExitCode.OK if verdict.valid else ExitCode.NO)


@click.command()
@click.argument("file")
@click.option("--model", type=click.Choice([m.value for m in ModelKind]), default=None,
              help="Default: the model `plan` answers with (the pipeline's first model that has a plan).")
@horizon_option()
@cell_option()
@click.option("--out", default=None, help="Write the model here instead of printing it.")
def promela(file: str, model: str | None, horizon: int | None, cell_m: float | None, out: str | None) -> None:
    """Write the Promela model of a scenario, runnable by hand: spin -a; gcc -DSAFETY -o pan pan.c; ./pan -E."""
    from promela.render import render_for  # Spin's renderer is only loaded when asked for

    target = out_file("--out", out) if out else None
    scenario = load(file, cell_m)
    if model:
        kind = ModelKind(model)
    else:  # the model `plan` would answer with: the first of the pipeline with a plan (the interpreter: milliseconds)
        answer = run_plan(scenario, horizon=horizon)
        kind = answer.model if answer.status is Status.PLAN and answer.model else models_for(scenario.model)[0]
    problem = problem_for(scenario, kind, horizon)
    text = render_for(problem) if scenario.sound is None else _sound_promela(problem)
    if target:
        target.write_text(text)
        click.echo(f"wrote {out} ({kind.value} model)")
    else:
        click.echo(text, nl=False)


def _sound_promela(problem: Problem) -> str:
    """The sound model's Promela for ``problem``: its verifier reads the scenario and the sound model's table (written
    into the verifier cache) when it starts (the line to run it with heads the file)."""
    from promela.render import ENV_VAR
    from promela.runner import injected
    from promela.sound import render, shape_of

    run = f'{ENV_VAR}="{injected(problem)}" ./pan -E'
    return f"/* the sound model: spin -a FILE; gcc -DSAFETY -o pan pan.c; {run} */\n" + render(shape_of(problem))


@click.command()
@click.argument("file")
@cell_option()
@click.option("--json", "as_json", is_flag=True)
@sound_options
def explain(file: str, cell_m: float | None, as_json: bool, sound: Callable[[Scenario], Scenario]) -> None:
    """Name a minimal set of vehicles that makes the overtake impossible (Z3 unsat core, minimised); under the sound
    model (the interpreter), also the phantoms and the assumption to blame."""
    scenario = sound(load(file, cell_m))
    if scenario.sound is not None:
        _explain_sound(file, scenario, as_json)
        return
    from oracle.explain import explain as explain_scenario  # loads Z3 only when asked for

    result = explain_scenario(scenario)
    if as_json:
        print_json({
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


def _explain_sound(file: str, scenario: Scenario, as_json: bool) -> None:
    """``explain`` under the sound model: which answer, the start's violation, the blocking vehicles and phantoms,
    and the assumptions narrowed to the paper's world."""
    from oracle.why import explain_sound, narrow, stated  # loads Z3 (oracle.explain's keep_only) only when asked for

    result = explain_sound(scenario)
    if as_json:
        print_json(_sound_explanation_json(result))
        sys.exit(ExitCode.INCOMPLETE if result.status is Status.INCOMPLETE else ExitCode.OK)
    assert scenario.sound is not None
    out.print(scenario.sound.describe())
    if result.status is Status.INCOMPLETE:
        out.print(f"{file}: the search hit its limit ({result.answer.detail}): nothing is explained.")
        sys.exit(ExitCode.INCOMPLETE)
    if result.has_plan:
        out.print(f"{file} has a plan under the sound model: nothing to explain (`overtake plan` with the same "
                  "options shows it).")
        return
    if result.violation is not None:
        out.print(f"no plan for {file} ({result.status.value}): the start already breaks the safety specification: "
                  f"{result.violation.describe()}.")
        if result.answer.commit is not None and result.answer.commit.escape is not None:
            out.print(f"The escape to take at once: {result.answer.commit.escape.describe()}.")
    elif result.status is Status.NO_PLAN:
        out.print(f"no plan for {file} (no_plan): {result.answer.detail}.")
    else:
        out.print(f"no plan within {scenario.horizon} actions for {file} (no_plan_within_horizon: a longer plan may "
                  "exist).")
    if result.blocking:
        out.print(f"These {len(result.blocking)} vehicle(s) alone leave no plan, and removing any one of them gives "
                  "one:")
        for suspect, answer in result.removals:
            out.print(f"  {result.name(suspect)}: without it, {_answer_text(answer)}")
    else:
        out.print(f"No vehicle or phantom is to blame: without any there is still no plan within the horizon of "
                  f"{scenario.horizon}.")
    for widened in result.parameters:
        out.print(f"The {widened.what} changed alone: {widened.stated} -> {widened.changed}: "
                  f"{_answer_text(widened.answer)}")
    if result.everything is None:
        return
    base = scenario.sound
    out.print("Each assumption narrowed to the paper's world alone, everything else as stated:")
    for narrowed in result.narrowings:
        (a,) = narrowed.assumptions
        out.print(f"  {a.label}: {stated(base, a)} -> {stated(narrow(base, a), a)}: {_answer_text(narrowed.answer)}")
    out.print(f"  all of them: {_answer_text(result.everything.answer)}")
    singles = [n.assumptions[0].label for n in result.narrowings if n.has_plan]
    if singles:
        out.print(f"The bound to blame: {', '.join(singles)} (narrowing {'it' if len(singles) == 1 else 'any one'} "
                  "alone gives a plan).")
    elif result.enough is not None:
        out.print(f"The bounds to blame, together: {', '.join(a.label for a in result.enough.assumptions)} "
                  f"(narrowing them gives a plan, no one alone does): {_answer_text(result.enough.answer)}")
    else:
        out.print("No assumption is to blame: even the paper's world leaves no plan.")


def _answer_text(answer: Answer) -> str:
    """An answer in a line: the plan and its model, or the status."""
    if answer.status is not Status.PLAN:
        return answer.status.value
    return f"{answer.model.value if answer.model else '-'} model: " + (
        ", ".join(a.value for a in answer.actions) or "(the empty plan)")


def _answer_json(answer: Answer) -> dict[str, object]:
    return {"status": answer.status.value, "model": answer.model.value if answer.model else None,
            "plan": [a.value for a in answer.actions]}


def _sound_explanation_json(result: SoundExplanation) -> dict[str, object]:
    """``explain --json`` under the sound model."""
    from oracle.why import narrow, stated

    scenario = result.scenario
    assert scenario.sound is not None
    v = result.violation
    return {
        "has_plan": result.has_plan,
        "status": result.status.value,
        "detail": result.answer.detail,
        "violation": None if v is None else {"text": v.describe(), **(
            {"conflict": v.conflict.value, "vehicle": v.vehicle.name, "time_s": v.time_s, "gap_m": v.gap_m,
             "required_m": v.required_m} if isinstance(v, Violation) else {"conflict": "collision"})},
        "blocking": [_suspect_json(result, s) for s in result.blocking],
        "reduced": scenario_to_dict(result.reduced) if result.reduced else None,  # its phantoms: reduced_phantoms
        "reduced_phantoms": [result.name(s) for s in result.blocking if isinstance(s, Phantom)],
        "removals": [{"removed": result.name(s), **_answer_json(a)} for s, a in result.removals],
        "narrowings": [{"assumption": n.assumptions[0].value, "stated": stated(scenario.sound, n.assumptions[0]),
                        "narrowed": stated(narrow(scenario.sound, n.assumptions[0]), n.assumptions[0]),
                        **_answer_json(n.answer)} for n in result.narrowings],
        "all_narrowed": None if result.everything is None else {
            "assumptions": [a.value for a in result.everything.assumptions], **_answer_json(result.everything.answer)},
        "enough": None if result.enough is None else {
            "assumptions": [a.value for a in result.enough.assumptions], **_answer_json(result.enough.answer)},
        "parameters": [{"parameter": w.what, "stated": w.stated, "changed": w.changed, **_answer_json(w.answer)}
                       for w in result.parameters],
        **({} if result.answer.commit is None else {"answer": result.answer.commit.to_json()}),
        **_sound_json(scenario),
    }


def _suspect_json(result: SoundExplanation, suspect: Suspect) -> dict[str, object]:
    if isinstance(suspect, Phantom):
        return {"kind": "phantom", "lane": suspect.lane.value, "index": None, "dx_m": suspect.dx_m,
                "name": result.name(suspect)}
    lane, i = suspect
    return {"kind": "sensed", "lane": lane.value, "index": i, "dx_m": None, "name": result.name(suspect)}


@click.command()
@click.argument("file")
@click.option("--engine", "engine_names", multiple=True, required=True,
              help="Two or more engines to compare (repeat the option).")
@strategy_option()
@cell_option()
@click.option("--out", default=None, help="Write the reproducer here (TOML) instead of printing it.")
def shrink(file: str, engine_names: tuple[str, ...], strategy: Strategy, cell_m: float | None,
           out: str | None) -> None:
    """Shrink a scenario on which engines disagree to a minimal reproducer."""
    target = out_file("--out", out) if out else None
    scenario = load(file, cell_m)
    engines = [get_engine(n) for n in engine_names]
    if len(engines) < 2:
        raise OptionError("--engine", engine_names, "name at least two engines to compare")
    for engine in engines:
        check_strategy(engine, strategy)
    fails = engines_disagree(engines, strategy)
    if not fails(scenario):
        click.echo(f"engines {', '.join(engine_names)} agree on {file}: nothing to shrink")
        sys.exit(ExitCode.OK)
    small, checks = shrink_scenario(scenario, fails)
    answers = [run_plan(small, strategy, engine=e) for e in engines]
    why = "; ".join(disagreements(answers))
    text = to_toml(small, f"minimal reproducer from {file} ({checks} checks), strategy {strategy.value}:\n{why}")
    if target:
        target.write_text(text)
        click.echo(f"wrote {out}: {why}")
    else:
        click.echo(text, nl=False)
    sys.exit(ExitCode.DISAGREE)


COMMANDS = (plan, validate_cmd, promela, explain, shrink)
