"""Every command's output reads at 80 columns, on a terminal and in a pipe: no line longer, no "…", and no word split
(every word of the narrow output is a word of the same command's wide output)."""

from __future__ import annotations

import fcntl
import os
import pty
import re
import select
import shutil
import struct
import subprocess
import sys
import tempfile
import termios
from collections.abc import Iterator
from pathlib import Path

import pytest

from oracle.shrink import to_toml
from spec.grid import grid_for
from spec.library import builtin
from spec.scenario import refined

pytestmark = pytest.mark.xdist_group("terminal-width")  # on one worker: the campaign the report reads is run once

WIDTH = 80
ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]|\x1b\][^\x07\x1b]*(?:\x07|\x1b\\)")
#: Words only a narrow output has: the line that names the columns a narrow table leaves out and where they all are
#: (ci.cli.common.print_table), and the scale of a plan drawn with one character for several cells.
NOTE_WORDS = {"shown", "columns", "every", "column", "wider", "terminal", "jsonl", "json", "audit", "summary",
              "among", "cells", "character", "first", "showing", "them"}

COMMANDS: dict[str, list[str]] = {
    "demo": ["demo"],
    "scenarios": ["scenarios"],
    "engines": ["engines"],
    "plan": ["plan", "paper_example"],
    "plan-10.5m": ["plan", "{grid105}"],
    "plan-5.25m": ["plan", "{grid525}"],
    "plan-all": ["plan", "paper_example", "--engine", "all", "--strategy", "shortest"],
    "explain": ["explain", "no_plan_boxed_in"],
    "validate": ["validate", "paper_example", "--actions", "accelerate,right_lane_change"],
    "crossval": ["crossval", "--source", "library", "--engines", "interpreter,spin", "--out", "{out}", "--fresh"],
    "simulate": ["simulate", "--km", "0.1", "--out", "{out}", "--fresh"],
    "simulate-faults": ["simulate", "--until-failure", "--faults", "paper", "--km", "0.3", "--runs", "2", "--out",
                        "{out}", "--fresh"],
    "audit": ["audit", "--cells", "21", "--traffic", "paper", "--sensing", "exact", "--model", "paper,sound",
              "--faults", "paper", "--km", "0.3", "--runs", "1", "--engines", "interpreter", "--out", "{out}",
              "--fresh"],
    "report": ["report", "{campaigns}", "--out", "{campaigns}/report.html"],
}


@pytest.fixture(scope="module")
def files() -> Iterator[dict[str, str]]:
    root = Path(tempfile.mkdtemp(prefix="w", dir="/tmp"))
    paths = {}
    for name, cell_m in (("grid105", 10.5), ("grid525", 5.25)):
        path = root / f"{name}.toml"
        path.write_text(to_toml(refined(builtin("paper_example").load(), grid_for(cell_m)), f"{cell_m} m"))
        paths[name] = str(path)
    campaigns = root / "campaigns"
    done = _run(["simulate", "--km", "0.3", "--out", str(campaigns / "sim")], None)
    assert done[0] in (0, 1), done
    paths["campaigns"] = str(campaigns)
    yield paths
    shutil.rmtree(root, ignore_errors=True)


def _run(args: list[str], width: int | None, terminal: bool = False) -> tuple[int, str]:
    """(exit code, stdout) of ``overtake ARGS`` with $COLUMNS at ``width``, in a pipe or on a pseudo-terminal of that
    width."""
    env = {**os.environ, **({"COLUMNS": str(width)} if width else {})}
    command = [sys.executable, "-m", "ci.cli.main", *args]
    if not terminal:
        done = subprocess.run(command, capture_output=True, text=True, env=env, timeout=600)
        return done.returncode, done.stdout
    main, secondary = pty.openpty()
    fcntl.ioctl(secondary, termios.TIOCSWINSZ, struct.pack("HHHH", 50, width or WIDTH, 0, 0))
    process = subprocess.Popen(command, stdout=secondary, stderr=subprocess.DEVNULL, env=env)
    os.close(secondary)
    chunks = []
    while True:
        ready, _, _ = select.select([main], [], [], 600)
        if not ready:
            process.kill()
            raise AssertionError(f"no output within 600 s: {args}")
        try:
            chunk = os.read(main, 65536)
        except OSError:  # the terminal closed: the command ended
            break
        if not chunk:
            break
        chunks.append(chunk)
    os.close(main)
    text = ANSI.sub("", b"".join(chunks).decode(errors="replace")).replace("\r\n", "\n")
    return process.wait(timeout=60), text


def _words(text: str) -> set[str]:
    return set(re.findall(r"[A-Za-z]{4,}", text))


@pytest.fixture
def short_tmp() -> Iterator[Path]:
    """A folder with a short path: the paths a command prints are the user's, and a long one cannot fit 80 columns."""
    folder = Path(tempfile.mkdtemp(prefix="w", dir="/tmp"))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


#: Commands that drive whole campaigns (an audit of both models, drives until a fault): slow, .ci/run runs them.
CAMPAIGNS = {"simulate-faults", "audit"}


@pytest.mark.parametrize("name", [pytest.param(n, marks=pytest.mark.slow) if n in CAMPAIGNS else n for n in COMMANDS])
def test_every_command_reads_at_80_columns_on_a_terminal_and_in_a_pipe(name: str, files: dict[str, str],
                                                                       short_tmp: Path) -> None:
    def args(_tag: str) -> list[str]:  # the same folder each time (--fresh): the paths printed are the same
        return [a.format(out=str(short_tmp / "out"), **files) for a in COMMANDS[name]]

    code, wide = _run(args("wide"), 400)
    assert code in (0, 1), (name, code)
    for terminal in (False, True):
        tag = "terminal" if terminal else "pipe"
        narrow_code, narrow = _run(args(tag), WIDTH, terminal)
        assert narrow_code == code, (name, tag)
        assert narrow.strip(), (name, tag)
        long_lines = [line for line in narrow.splitlines() if len(line) > WIDTH]
        assert not long_lines, (name, tag, long_lines[:3])
        assert "…" not in narrow, (name, tag)
        split = _words(narrow) - _words(wide) - NOTE_WORDS
        assert not split, (name, tag, sorted(split)[:10])
