"""What every command shares: the consoles, reading a scenario, option types, printing plans."""

from __future__ import annotations

import enum
import json
import os
import sys
from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any

import click
from rich import box
from rich.console import Console
from rich.markup import escape
from rich.measure import Measurement
from rich.table import Table

from oracle.render import FRAME_CHARS, LEGEND, PRECEDENCE, cells_per_char, draw
from spec.actions import Action
from spec.answers import Answer, Status, Strategy
from spec.constants import DEFAULT_HORIZON
from spec.envelope import TRACKING
from spec.errors import ScenarioError
from spec.files import load_scenario
from spec.library import builtin
from spec.models import ModelChoice
from spec.physical import LOOP
from spec.scenario import Scenario
from spec.sound import sound_from
from spec.state import State
from spec.tracking import VEHICLE_SPEED_CHANGE


def _pipe_width() -> int | None:
    """A terminal tells its width; a pipe does not: $COLUMNS if set, else the classic 80 columns."""
    if sys.stdout.isatty():
        return None
    columns = os.environ.get("COLUMNS", "")
    return int(columns) if columns.isdigit() and int(columns) >= 40 else 80


out = Console(highlight=False, width=_pipe_width())
err = Console(stderr=True, highlight=False)


def print_paths(heading: str, paths: Sequence[object]) -> None:
    """``heading``, then each path on a line of its own, never folded (a folded path cannot be copied)."""
    out.print(heading)
    for path in paths:
        out.print(f"  {path}", soft_wrap=True)


def print_header(console: Console, text: str, results: object) -> None:
    """A campaign's header: ``text``, then where its results go, on a line of its own, never folded."""
    console.print(f"{text}; results in:")
    console.print(f"  {results}", soft_wrap=True)

MODEL = click.Choice([m.value for m in ModelChoice])


def strategy_option(default: Strategy = Strategy.SENSIBLE, choices: tuple[Strategy, ...] = tuple(Strategy)) -> Any:
    """``--strategy``, handed to the command as a ``Strategy``."""
    return click.option("--strategy", type=click.Choice([s.value for s in choices]), default=default.value,
                        show_default=True, callback=lambda _ctx, _param, value: Strategy(value))


def faults_options(command: Any) -> Any:
    """``--faults KIND=RATE[/SWEEPS],...`` and ``--steering-offset-deg``: the fault injectors of every drive
    (``spec.faults``), checked when the campaign's configuration is made."""
    from ci.shared.options import DEGREES
    from spec.faults import DEFAULT_STEERING_OFFSET_DEG, FaultKind

    kinds = ", ".join(k.value for k in FaultKind)
    command = click.option("--steering-offset-deg", type=DEGREES, default=DEFAULT_STEERING_OFFSET_DEG,
                           show_default=True,
                           help="The steering fault's offset (the default spins the car at 14 m/s).")(command)
    command = click.option("--tracking", type=click.Choice(["on", "off"]), default="off", show_default=True,
                           callback=lambda _ctx, _param, value: value == "on",
                           help="The tracking layer between the sensors and the planner (docs/faults.md).")(command)
    return click.option("--faults", "faults", default="", show_default=False,
                        help=f"Faults injected, KIND=RATE[/SWEEPS],... : a rate per sensor sweep (10 Hz) and how "
                             f"many sweeps one lasts (default 30; steering 20); or 'paper', the rates calibrated "
                             f"against the paper's failures (docs/faults.md). Kinds: {kinds}.")(command)


def _enum_option(name: str, choices: type[enum.Enum], default: enum.Enum, help_text: str) -> Any:
    """An option of one of ``choices``' values, handed to the command as the member."""
    return click.option(name, type=click.Choice([v.value for v in choices]), default=default.value, show_default=True,
                        callback=lambda _ctx, _param, value: choices(value), help=help_text)


def vehicle_speeds_option(command: Any) -> Any:
    """``--vehicle-speeds lane|measured``, handed to the command as a ``VehicleSpeeds``."""
    from spec.dynamics import VehicleSpeeds

    return _enum_option("--vehicle-speeds", VehicleSpeeds, VehicleSpeeds.LANE,
                        "Where the sound model's drives take each vehicle's speed from: its lane's bounds, or its "
                        "track's measured interval (needs --tracking on; each vehicle may then brake to a "
                        "standstill: docs/sound.md).")(command)


def overtaken_option(command: Any) -> Any:
    """``--overtaken physics|no-acceleration`` for the closed loop, handed to the command as an ``Overtaken``."""
    from spec.dynamics import Overtaken

    return _enum_option("--overtaken", Overtaken, Overtaken.PHYSICS,
                        "What a same-direction vehicle whose speed was measured may do while the AV is in the "
                        "passing lane: speed up as physics allows, or (a stated profile, StVO section 5(6), monitored "
                        "as 'accelerated while overtaken') not at all. Needs --vehicle-speeds measured.")(command)


def loop_semantics_option(command: Any) -> Any:
    """``--semantics commit|whole`` for the closed loop's sound model, handed to the command as a ``Semantics`` (None:
    not given, the model's own: ``sim.parts.loop_semantics``)."""
    from spec.escapes import Semantics

    return click.option("--semantics", type=click.Choice([v.value for v in Semantics]), default=None,
                        callback=lambda _ctx, _param, value: None if value is None else Semantics(value),
                        help="How the sound model decides in the loop: commit (the default: a committed part with a "
                             "proved escape, executed until the next decision; when a decision proves nothing, the "
                             "rest of the last one and its escape) or whole (plans proved to their end). "
                             "docs/closed-loop.md. Needs --model sound.")(command)


def horizon_option() -> Any:
    from ci.shared.options import HORIZON

    return click.option("--horizon", type=HORIZON, default=None,
                        help=f"Maximum plan length (default: the scenario's, else {DEFAULT_HORIZON}).")


def cell_option() -> Any:
    from ci.shared.options import CELL_M

    return click.option("--cell-m", "cell_m", type=CELL_M, default=None,
                        help="Cell length in metres (21, 10.5, 7, 5.25; default: the file's, else 21).")


def load(file: str, cell_m: float | None = None) -> Scenario:
    """A scenario from a file path or the name of a built-in scenario; ``cell_m`` is the grid of a file that names
    none (every built-in scenario names the paper's)."""
    path = Path(file)
    entry = builtin(file)
    if not path.exists() and entry is not None:
        path = entry.path
    elif not path.exists():
        raise ScenarioError("file", file, "no such file (nor a built-in scenario: see `overtake scenarios`)")
    return load_scenario(path, cell_m)


def print_table(table: Table, keep: int = 1, full: str = "--json") -> None:
    """``table`` at the console's width, every word whole: first the lines between columns go, then the rightmost
    columns (never the first ``keep``) until the rest fit, and one line names them and ``full``, where every column
    is; each column gets at least its longest word and the room left in proportion to what it would take more (rich
    alone shrinks the widest columns below their longest word). A pipe is 80 columns wide unless $COLUMNS says
    otherwise; a terminal, its own."""
    wide = out.options.update_width(10_000)

    def narrowest() -> int:  # every column as narrow as its longest word (rich clamps a measure to the width asked)
        return Measurement.get(out, wide, table).minimum

    left_out: list[str] = []
    if narrowest() > out.width:
        table.box, table.show_edge, table.pad_edge = box.SIMPLE_HEAD, False, False
    while narrowest() > out.width and len(table.columns) > keep:
        left_out.append(" ".join(str(table.columns.pop().header).split()))
    ranges = [[Measurement.get(out, wide, cell) for cell in (column.header, *column.cells)] for column in table.columns]
    least = [max(m.minimum for m in r) for r in ranges]
    most = [max(m.maximum for m in r) for r in ranges]
    room = out.width - (narrowest() - sum(least))  # what the columns' contents may take together
    if sum(most) > room >= sum(least):
        spare, wanted = room - sum(least), sum(most) - sum(least)
        for column, low, high in zip(table.columns, least, most):
            column.width = low + spare * (high - low) // wanted
    out.print(table)
    if left_out:
        out.print(escape(f"(not shown at {out.width} columns: {'; '.join(reversed(left_out))}; {full} has every "
                         "column)"), style="dim")


def print_json(obj: Any) -> None:
    click.echo(json.dumps(obj, indent=2))


def print_states(scenario: Scenario, actions: tuple[Action, ...], states: tuple[State, ...]) -> None:
    """Both lanes after every step, with a legend for the marks."""
    labels = ["start", *(a.value for a in actions)]
    room = out.width - 2 - FRAME_CHARS  # the indent, and each line's frame
    for n, (label, state) in enumerate(zip(labels, states)):
        out.print(f"step {n}: {label}")
        for line in draw(state, scenario.grid, scenario.target_indices, room):
            out.print(f"  {line}", overflow="ignore", crop=False)
    step = cells_per_char(scenario.grid, room)
    scale = "" if step == 1 else (f"; one character is {step} cells of {scenario.grid.cell:g} m, showing the first of "
                                  f"{', '.join(PRECEDENCE[:-1])} among them")
    out.print(f"  ({LEGEND}{scale})")


SHORT = {Action.LEFT_LANE_CHANGE: "L", Action.ACCELERATE: "A", Action.RIGHT_LANE_CHANGE: "R", Action.DRIVE: "D",
         Action.BRAKE: "B"}


#: Answers without a plan, short enough for a narrow table (``STATUS_LEGEND`` says what each is).
SHORT_STATUS = {Status.NO_PLAN: "no-plan", Status.NO_PLAN_WITHIN_HORIZON: "no-plan-h", Status.INCOMPLETE: "incomplete",
                Status.PLAN: "plan"}
STATUS_LEGEND = ("no-plan: proved, no plan of any length; no-plan-h: no plan within the horizon; incomplete: the "
                 "search hit its limit")


def abbrev(answer: Answer, compact: bool = False) -> str:
    """A plan as letters (``compact``: without spaces), or the status when there is none (``compact``: short)."""
    if answer.status is not Status.PLAN:
        return SHORT_STATUS.get(answer.status, answer.status.value) if compact else answer.status.value
    return ("" if compact else " ").join(SHORT[a] for a in answer.actions) or "(empty)"


#: The commitment semantics' options (the last of ``SOUND_OPTIONS``).
COMMIT_OPTIONS = ("semantics", "commit_max", "escapes")
SOUND_OPTIONS = ("bounds", "same_mps", "oncoming_mps", "sensing_error_m", "phantoms", "av_speed_mps", "followers_react",
                 "oncoming_view_m", "latency_s", "accel_mps2", "brake_mps2", "overtaken", "sideways_s",
                 "sensors_ahead_m", "sensed_sets", "from_reference", *COMMIT_OPTIONS)


def sound_options(command: Any) -> Any:
    """The sound model's options, handed to the command as one ``sound`` argument: a function that puts the chosen
    model on a scenario (unchanged when none of them is given and the file has no ``bounds`` table)."""
    return _sound_options(command, commitment=True)


def whole_sound_options(command: Any) -> Any:
    """``sound_options`` without the commitment semantics' (a campaign, which names its semantics itself:
    ``crossval --semantics``): the model is the sound model's whole plans."""
    return _sound_options(command, commitment=False)


def _sound_options(command: Any, commitment: bool) -> Any:
    from ci.shared.options import ACCEL, AHEAD, LATENCY, METRES, SIDEWAYS, SPEED
    from spec.engines import under_semantics
    from spec.escapes import Semantics

    names = SOUND_OPTIONS if commitment else SOUND_OPTIONS[:-len(COMMIT_OPTIONS)]

    def wrapper(**kwargs: Any) -> Any:
        given = {k: kwargs.pop(k) for k in names}
        kwargs["sound"] = (lambda scenario: with_sound(scenario, **given)) if commitment else \
            (lambda scenario: under_semantics(with_sound(scenario, **given), Semantics.WHOLE))
        return command(**kwargs)

    wrapper.__name__, wrapper.__doc__ = command.__name__, command.__doc__
    for decorate in reversed((
        click.option("--bounds", default=None, help="Plan with the sound model under this bounds profile "
                     "(paper, default; see docs/sound.md). Default: the paper's rules, or the file's bounds."),
        click.option("--same-mps", default=None, help="Sound model: same-direction speeds LOW..HIGH, m/s."),
        click.option("--oncoming-mps", default=None, help="Sound model: oncoming speeds LOW..HIGH, m/s."),
        click.option("--sensing-error-m", type=METRES, default=None, help="Sound model: sensing error, metres."),
        click.option("--phantoms/--no-phantoms", default=None, help="Sound model: vehicles assumed beyond the "
                     "sensors' ranges (default: the profile's)."),
        click.option("--av-speed-mps", type=SPEED, default=None, help="Sound model: the AV's measured speed at "
                     "the snapshot (default: the common speed)."),
        click.option("--followers-react/--followers-keep-speed", "followers_react", default=None,
                     help="Sound model: whether vehicles behind the AV brake for it (default: the profile's; the "
                     "paper's keep their speed, and the AV must not drive slower than they may while near)."),
        click.option("--oncoming-view-m", type=METRES, default=None, help="Sound model: how far the snapshot saw "
                     "the oncoming lane (a left-lane vehicle hid it from there on; the oncoming phantom stands "
                     "there). Default: the front-right sensor's range."),
        click.option("--latency-s", type=LATENCY, default=None, help="Sound model: how long the snapshot ages "
                     f"before the plan acts (the planner's time; the closed loop's is one control step, "
                     f"{LOOP.plan_budget_s * 1000:.1f} ms). "
                     "Default: 0, the profile's."),
        click.option("--accel-mps2", type=ACCEL, default=None, help="Sound model: the most a vehicle whose speed "
                     "was measured (the file's left_mps, right_mps) speeds up, m/s^2 (default: "
                     f"{VEHICLE_SPEED_CHANGE.accel_mps2:g}, spec.tracking)."),
        click.option("--brake-mps2", type=ACCEL, default=None, help="Sound model: the most a vehicle whose speed "
                     "was measured brakes, m/s^2, to a standstill at the least (default: "
                     f"{VEHICLE_SPEED_CHANGE.brake_mps2:g}, spec.tracking)."),
        click.option("--overtaken", default=None, help="Sound model: what a same-direction vehicle whose speed was "
                     "measured may do while the AV is in the passing lane: physics (speed up at --accel-mps2, the "
                     "default) or no-acceleration (a stated profile: it does not speed up, as StVO section 5(6) "
                     "asks of a vehicle being overtaken). See docs/sound.md."),
        click.option("--sideways-s", type=SIDEWAYS, default=None, help="Sound model: a sideways move under way at "
                     "the snapshot, into the scenario's lane: the most time it may still keep the AV in both lanes, "
                     "s (0 to the move's whole 2 s; default 0, none). See docs/sound.md."),
        click.option("--sensors-ahead-m", type=AHEAD, default=None, help="Sound model: how far ahead of the AV's "
                     "reference, where the plan starts, the car and its sensors stood at the snapshot (negative: "
                     f"behind; within the envelope's {TRACKING.position_m:g} m; default 0, the plan starts at the "
                     "car): the phantoms stand that much farther ahead. See docs/sound.md."),
        click.option("--sensed-sets/--sensed-readings", "sensed_sets", default=None, help="Sound model: whether "
                     "the file's sensed extents (left_m, right_m) are sets each vehicle is known to be in, the "
                     "sensing error held (the closed loop's readings narrowed by the last proof), or readings, "
                     "each vehicle within the sensing error of its own (the default). See docs/sound.md."),
        click.option("--from-reference/--from-car", "from_reference", default=None, help="Sound model: whether "
                     "the plan's AV is the proved reference the car runs on, at exactly its speed while the snapshot "
                     "ages, or the car (the default), within twice the envelope's speed error of it. See "
                     "docs/sound.md."),
    ) + ((
        click.option("--semantics", default=None, help="Sound model: commit (committed actions with a proved "
                     "escape and a predicted continuation; the default) or whole (every plan proved to its end). "
                     "See docs/sound.md."),
        click.option("--commit-max", default=None, help="Sound model, commit: the most actions one answer commits "
                     "to (default: as many as are proved)."),
        click.option("--escapes", default=None, help="Sound model, commit: the escapes it may prove, comma-separated "
                     "(minimal_risk, abort, complete; default: all)."),
    ) if commitment else ())):
        wrapper = decorate(wrapper)
    return wrapper


def with_sound(scenario: Scenario, bounds: str | None, same_mps: str | None, oncoming_mps: str | None,
               sensing_error_m: float | None, phantoms: bool | None, av_speed_mps: float | None,
               followers_react: bool | None = None, oncoming_view_m: float | None = None,
               latency_s: float | None = None, semantics: str | None = None, commit_max: str | None = None,
               escapes: str | None = None, accel_mps2: float | None = None,
               brake_mps2: float | None = None, overtaken: str | None = None,
               sideways_s: float | None = None, sensors_ahead_m: float | None = None,
               sensed_sets: bool | None = None, from_reference: bool | None = None) -> Scenario:
    """``scenario`` under the sound model the options (over the file's ``bounds``) choose; unchanged without any."""
    if all(v is None for v in (bounds, same_mps, oncoming_mps, sensing_error_m, phantoms, av_speed_mps,
                               followers_react, oncoming_view_m, latency_s, semantics, commit_max, escapes,
                               accel_mps2, brake_mps2, overtaken, sideways_s, sensors_ahead_m, sensed_sets,
                               from_reference)):
        return scenario
    sound = sound_from(scenario.sound, bounds, same_mps, oncoming_mps, sensing_error_m, phantoms, av_speed_mps,
                       followers_react=followers_react, oncoming_view_m=oncoming_view_m, latency_s=latency_s,
                       semantics=semantics, commit_max=commit_max, escapes=escapes, accel_mps2=accel_mps2,
                       brake_mps2=brake_mps2, overtaken=overtaken, sideways_s=sideways_s,
                       sensors_ahead_m=sensors_ahead_m, sensed_sets=sensed_sets, from_reference=from_reference)
    return replace(scenario, sound=sound)
