"""The ``overtake`` command: parse, call the layer below, print. One module per command group.

Every error reaches the user as one line on stderr with its exit code, declared once in
``spec.errors.ExitCode``: 0 plan / valid, 1 no plan / invalid (simulate: a run failed),
2 bad input, 3 search incomplete, 4 a tool is missing, 5 an engine failed, 6 engines
disagree, 130 interrupted (Ctrl-C), 143 terminated (SIGTERM).
"""

from __future__ import annotations

import os
import signal
import sys
from typing import NoReturn

import click

from ci.cli import audit, crossval, library, planning, report, simulation
from ci.shared.signals import handled, received
from spec.errors import ExitCode, SuiteError


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="overtake-mc")
def cli() -> None:
    """Plan overtaking manoeuvres by model checking, with cross-validated engines."""


for command in (*planning.COMMANDS, *library.COMMANDS, *simulation.COMMANDS, *audit.COMMANDS,
                *crossval.COMMANDS, *report.COMMANDS):
    cli.add_command(command)


class Interrupted(BaseException):
    """Ctrl-C or SIGTERM, raised here rather than as KeyboardInterrupt (which click would turn into its own
    output): campaigns stop their workers and keep what they finished."""

    def __init__(self, signum: int) -> None:
        super().__init__(signum)
        self.signum = signum


def _interrupted(signum: int, _frame: object) -> None:
    raise Interrupted(signum)


def _stopped(signum: int | None) -> NoReturn:
    """End on a signal (None: Ctrl-C that no handler saw): one line, and 143 for SIGTERM, else 130."""
    if signum == signal.SIGTERM:
        click.echo("overtake: terminated (SIGTERM); what was finished is kept: run again to resume", err=True)
        sys.exit(ExitCode.TERMINATED)
    click.echo("overtake: interrupted; what was finished is kept: run again to resume", err=True)
    sys.exit(ExitCode.INTERRUPTED)


def main() -> None:
    """Entry point: run the CLI, turning every suite error into one line and its exit code."""
    try:
        with handled(_interrupted):
            cli.main(standalone_mode=False)
    except click.exceptions.Exit as done:
        sys.exit(done.exit_code)
    except click.UsageError as error:
        command = error.ctx.command_path if error.ctx else "overtake"
        click.echo(f"overtake: error: {error.format_message()} (see `{command} --help`)", err=True)
        sys.exit(ExitCode.BAD_INPUT)
    except click.ClickException as error:
        click.echo(f"overtake: error: {error.format_message()}", err=True)
        sys.exit(error.exit_code)
    except (Interrupted, click.exceptions.Abort, KeyboardInterrupt) as signalled:  # the latter: a cancelled check
        if isinstance(signalled.__cause__, EOFError) and received() is None:  # click makes any EOFError an Abort:
            _failed(signalled.__cause__)  # a pipe closed under us (a helper process died) is no Ctrl-C
        _stopped(signalled.signum if isinstance(signalled, Interrupted) else received())
    except SuiteError as error:
        click.echo(f"overtake: error: {error}", err=True)
        sys.exit(error.exit_code)
    except Exception as error:
        if received() is not None:  # a signal raised inside a native call arrives wrapped (ctypes.ArgumentError)
            _stopped(received())
        _failed(error)


def _failed(error: BaseException) -> NoReturn:
    """An error of ours, not of the input: one line and exit 5, or the traceback with OVERTAKE_DEBUG set."""
    if os.environ.get("OVERTAKE_DEBUG"):
        raise error
    click.echo(f"overtake: internal error: {type(error).__name__}: {error} (set OVERTAKE_DEBUG=1 for details)",
               err=True)
    sys.exit(ExitCode.ENGINE_FAILED)


if __name__ == "__main__":
    main()
