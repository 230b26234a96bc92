"""One set of option types for every command: each bad value is exit 2 with one line naming the option, the value
and the reason, before any work starts.

- ``Number(low, high, positive)``: a finite number in ``low .. high`` (NaN, infinity, 1e308 and text are refused);
- ``Whole(low, high)``: a whole number in ``low .. high``; ``SEED``: one a generator takes (0 .. 2**32 - 1);
- ``HORIZON``, ``WORKERS``, ``RUNS``, ``MAX_STATES``, ``PER_RUN``, ``REPRODUCERS``: whole numbers with stated bounds;
- ``names``: a comma-separated list of distinct names, each one checked (bad input names the list's option);
- ``SCHEDULER``: a dask scheduler's address;
- ``convert``: any of these types outside click's own parsing (a list's items,
  ``python -m ci.conformance.conform``'s argparse);
- ``out_dir`` / ``out_file``: an output that can be written (a directory that is not a file, in a place this user
  may write; a file whose folder exists and is writable, and which is not a directory).
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

import click

from spec.assumptions import MAX_LATENCY_S
from spec.constants import MAX_HORIZON
from spec.envelope import TRACKING
from spec.errors import OptionError, check_number
from spec.physical import MAX_STOP_RATE_PER_H


class Whole(click.IntRange):
    """A whole number in ``low .. high`` (click's IntRange, which calls itself an "integer range" in messages)."""

    name = "integer"


SEED = Whole(0, 2**32 - 1)
MAX_SECONDS = 7 * 24 * 3600.0  # a week: more is a typo, and timers overflow long before infinity
MAX_KM = 100_000.0
# Local workers are processes of ~150 MB each (a simulator, a verifier): 256 is beyond any one machine's memory, so
# more is a typo; a dask cluster behind --scheduler has its own workers. Shared by every command with --workers.
MAX_WORKERS = 256
WORKERS = Whole(1, MAX_WORKERS)
# Runs in one campaign: its seeds are listed before the first starts; 100 000 runs of the smallest drive are days of
# work, so more is a typo (and a list of 2**32 seeds would exhaust memory before anything ran).
RUNS = Whole(1, 100_000)
HORIZON = Whole(0, MAX_HORIZON)  # actions in a plan
MAX_STATES = Whole(1, 10**9)  # stored states: a billion does not fit in any machine's memory
PER_RUN = Whole(0, 10_000)  # scenarios kept, decisions replayed per run: a run makes a few thousand
FRAMED = Whole(0, 20)  # closest calls drawn per folder: each replays a drive from its start
CHECK_COUNT = Whole(1, 10**7)  # scenarios or examples a campaign checks: the largest exhaustive space is a million
REPRODUCERS = Whole(0, 1000)  # failures shrunk per property: each shrink is minutes of engine runs


def _name(param: click.Parameter | None) -> str:
    return param.opts[0] if param is not None and param.opts else "option"


class Number(click.ParamType):
    """A finite number in ``low .. high`` (``positive``: above ``low``, not at it)."""

    name = "number"

    def __init__(self, low: float = 0.0, high: float = math.inf, positive: bool = False) -> None:
        self.low, self.high, self.positive = low, high, positive

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> float:
        if isinstance(value, float | int) and not isinstance(value, bool):
            number = float(value)
        else:
            try:
                number = float(str(value).strip())
            except ValueError:
                raise OptionError(_name(param), value, "must be a number") from None
        return check_number(_name(param), number, self.high, self.low, positive=self.positive)


class Address(click.ParamType):
    """A dask scheduler's address as dask reads it (``tcp://host:port``, ``host:port``): a malformed one is bad input
    before the campaign starts; whether a scheduler answers there is known only when the campaign connects."""

    name = "address"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        text = str(value).strip()
        try:
            from distributed.comm.addressing import get_address_host_port
        except ImportError:  # the executor says how to install it (exit 4)
            return text
        try:
            get_address_host_port(text)
        except ValueError as error:
            raise OptionError(_name(param), value, f"not a scheduler address ({error})") from None
        return text


SCHEDULER = Address()


def names(option: str, text: str, check: Callable[[str], object] | None = None,
          distinct: bool = True) -> tuple[str, ...]:
    """A comma-separated list of names (``distinct``: each once), each passed to ``check`` (which raises on one it
    does not know)."""
    found = tuple(n.strip() for n in text.split(",") if n.strip())
    if not found:
        raise OptionError(option, text, "name at least one")
    if distinct and len(set(found)) < len(found):
        raise OptionError(option, text, "a name given twice")
    for name in found:
        if check is None:
            continue
        try:
            check(name)
        except OptionError as error:  # a check shared with a one-name option (get_engine: --engine) names that one
            if error.key == option:
                raise
            raise OptionError(option, name, error.reason) from None
    return found


def convert(option: str, kind: click.ParamType, value: Any) -> Any:
    """``value`` as ``kind`` (``SEED``, ``SECONDS``, ...) outside click's own parsing: bad input is an OptionError
    naming ``option``, the value and the reason."""
    try:
        return kind.convert(value, click.Option([option]), None)
    except click.BadParameter as error:
        raise OptionError(option, value, error.message) from None


SECONDS = Number(0.0, MAX_SECONDS, positive=True)
KM = Number(0.01, MAX_KM)
TOLERANCE = Number(0.0, 100.0, positive=True)
CELL_M = Number(0.0, 1000.0, positive=True)
PER_HOUR = Number(0.0, MAX_STOP_RATE_PER_H)  # events per vehicle-hour: at most one start per control step
METRES = Number(0.0, 1000.0)  # a gap or a noise in metres: the sensed window is a kilometre
FRACTION = Number(0.0, 1.0)  # a probability
SPEED = Number(0.0, 100.0)  # m/s: no car on this road goes faster than 360 km/h
DEGREES = Number(0.0, 90.0)  # a steering offset: past a right angle the wheels point backwards
SCALE = Number(0.0, 100.0)  # a factor on the bounds' widths: 0 is the rule's middle speed alone
ACCEL = Number(0.0, 100.0, positive=True)  # m/s^2: an acceleration bound above 0 (about 10 g at the most)
LATENCY = Number(0.0, MAX_LATENCY_S)  # seconds a snapshot ages before the plan acts (spec.assumptions.MAX_LATENCY_S)
SIDEWAYS = Number(0.0, TRACKING.lateral_s)  # seconds a sideways move under way may still take (spec.envelope)
#: metres the sensors stood ahead of the plan's reference: within the envelope's position error either way
AHEAD = Number(-TRACKING.position_m, TRACKING.position_m)


def out_dir(option: str, path: str | Path) -> Path:
    """A directory outputs can be written to, made if missing; anything else is bad input."""
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise OptionError(option, str(path), "names a file, not a directory")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise OptionError(option, str(path), f"cannot be made ({error.strerror or error})") from None
    if not os.access(folder, os.W_OK | os.X_OK) or str(folder.resolve()).startswith(("/proc", "/sys")):
        raise OptionError(option, str(path), "cannot be written to")
    return folder


def out_file(option: str, path: str | Path) -> Path:
    """A file that can be written: its folder exists and is writable, and it is not a directory."""
    file = Path(path)
    if file.is_dir():
        raise OptionError(option, str(path), "names a directory, not a file")
    folder = file.parent if str(file.parent) else Path(".")
    if not folder.is_dir():
        raise OptionError(option, str(path), f"its folder {folder} does not exist")
    if not os.access(folder, os.W_OK) or (file.exists() and not os.access(file, os.W_OK)) \
            or str(folder.resolve()).startswith(("/proc", "/sys")):
        raise OptionError(option, str(path), "cannot be written to")
    return file
