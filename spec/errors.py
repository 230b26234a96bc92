"""One hierarchy of typed errors; every exit code the suite uses is declared once, here (``ExitCode``)."""

from __future__ import annotations

import enum
import math
from typing import TypeVar


class ExitCode(enum.IntEnum):
    """The documented exit codes of every command (README, "exit codes")."""

    OK = 0  # a plan, a valid action list, every property held
    NO = 1  # no plan, an invalid action list, a drive that failed
    BAD_INPUT = 2  # one line naming the file or option, the value and the reason
    INCOMPLETE = 3  # a search limit was hit: nothing is claimed
    TOOL_MISSING = 4  # spin, gcc, dask.distributed, an unreachable scheduler
    ENGINE_FAILED = 5  # an engine crashed or answered nonsense: never "no plan"
    DISAGREE = 6  # engines disagree
    COVERAGE_MISSED = 7  # every property held, but the campaign never exercised a rule it was asked to cover
    INTERRUPTED = 130  # Ctrl-C: what a campaign finished is kept
    TERMINATED = 143  # SIGTERM: likewise


class SuiteError(Exception):
    """Base of every error the suite reports to a user as one line."""

    exit_code = ExitCode.ENGINE_FAILED


class BadInput(SuiteError):
    """Bad input of any kind: a file, a value, an option."""

    exit_code = ExitCode.BAD_INPUT

    def __init__(self, key: str, value: object, reason: str, source: str = "") -> None:
        self.source, self.key, self.value, self.reason = source, key, value, reason
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{_short(str(key))}={_short(repr(value))}: {reason}")


def _short(text: str, limit: int = 100) -> str:
    """``text``, or its start when it is long (a file's 200 kB string is not shown whole in a one-line message)."""
    return text if len(text) <= limit else f"{text[:limit - 20]}... ({len(text)} characters)"


class ScenarioError(BadInput):
    """Bad input: a scenario file or value that cannot be planned for."""

    def with_source(self, source: str) -> ScenarioError:
        """The same error, naming the file it came from."""
        return ScenarioError(self.key, self.value, self.reason, source)


class OptionError(BadInput):
    """Bad input: a command-line option (or the same setting given to the library) with an unusable value."""


class ActionError(SuiteError):
    """Bad input: an action list that names an unknown action."""

    exit_code = ExitCode.BAD_INPUT


class ToolMissing(SuiteError):
    """An external tool (spin, gcc, dask.distributed) is not installed; the message says how to install it."""

    exit_code = ExitCode.TOOL_MISSING


class EngineError(SuiteError):
    """An engine failed (crash, unreadable output): never reported as "no plan"."""

    exit_code = ExitCode.ENGINE_FAILED


class EnginesDisagree(SuiteError):
    """Engines asked the same question gave different answers; the message says how."""

    exit_code = ExitCode.DISAGREE


def check_number(option: str, value: object, high: float = math.inf, low: float = 0.0,
                 positive: bool = False) -> float:
    """A finite number in ``low .. high`` (``positive``: above ``low``, not at it); anything else (NaN, infinity, a
    negative rate, text) is bad input. The one check behind every numeric option."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise OptionError(option, value, "must be a number")
    if not math.isfinite(value):
        raise OptionError(option, value, "must be a finite number")
    if not low <= value <= high or (positive and value == low):
        if positive:
            bound = f"above {low:g}" + ("" if math.isinf(high) else f" and at most {high:g}")
        else:
            bound = f"between {low:g} and {high:g}" if math.isfinite(high) else f"at least {low:g}"
        raise OptionError(option, value, f"must be {bound}")
    return float(value)


Choice = TypeVar("Choice", bound=enum.Enum)


def parse_choice(kind: type[Choice], value: object, where: str) -> Choice:
    """One of ``kind``'s members, given as itself or by its value; anything else is bad input naming ``where``."""
    if isinstance(value, kind):
        return value
    allowed = [str(m.value) for m in kind]
    if not isinstance(value, str) or value not in allowed:
        raise OptionError(where, value, f"must be one of {', '.join(allowed)}")
    return kind(value)
