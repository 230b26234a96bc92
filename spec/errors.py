"""One small hierarchy of typed errors, each with the exit code the CLI returns for it."""

from __future__ import annotations


class SuiteError(Exception):
    """Base of every error the suite reports to a user as one line."""

    exit_code = 5


class ScenarioError(SuiteError):
    """Bad input: a scenario file or value that cannot be planned for."""

    exit_code = 2

    def __init__(self, key: str, value: object, reason: str, source: str = "") -> None:
        self.source, self.key, self.value, self.reason = source, key, value, reason
        where = f"{source}: " if source else ""
        super().__init__(f"{where}{key}={value!r}: {reason}")

    def with_source(self, source: str) -> ScenarioError:
        """The same error, naming the file it came from."""
        return ScenarioError(self.key, self.value, self.reason, source)


class ActionError(SuiteError):
    """Bad input: an action list that names an unknown action."""

    exit_code = 2


class ToolMissing(SuiteError):
    """An external tool (spin, gcc) is not installed; the message says how to install it."""

    exit_code = 4


class EngineError(SuiteError):
    """An engine failed (crash, unreadable output): never reported as "no plan"."""

    exit_code = 5
