"""Hostile input, command by command: every case is exit 2 with one line naming the option or file, never a
traceback, a hang or a run that starts."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import run_cli

CASES = [
    (("plan", "one_target", "--timeout", "inf"), "--timeout"),
    (("plan", "one_target", "--timeout", "nan"), "--timeout"),
    (("plan", "one_target", "--engine", "z3", "--timeout", "1e308"), "--timeout"),
    (("plan", "one_target", "--timeout", "-1"), "--timeout"),
    (("plan", "one_target", "--cell-m", "nan"), "--cell-m"),
    (("validate", "one_target", "--actions", ",,"), "--actions"),
    (("simulate", "--km", "nan"), "--km"),
    (("simulate", "--km", "inf"), "--km"),
    (("simulate", "--seed", "-1"), "--seed"),
    (("simulate", "--step-tolerance", "nan"), "--step-tolerance"),
    (("simulate", "--out", "/proc/overtake"), "--out"),
    (("promela", "prep_case_b", "--out", "/nonexistent/dir/model.pml"), "--out"),
    (("promela", "prep_case_b", "--out", "/tmp"), "--out"),
    (("shrink", "one_target", "--engine", "interpreter", "--engine", "spin", "--out", "/proc/x.toml"), "--out"),
    (("audit", "--km", "inf"), "--km"),
    (("audit", "--seed", "99999999999"), "--seed"),
    (("audit", "--out", "/proc/audit"), "--out"),
    (("crossval", "--timeout", "inf"), "--timeout"),
]


@pytest.mark.parametrize(("args", "option"), CASES, ids=lambda v: " ".join(v) if isinstance(v, tuple) else v)
def test_a_bad_option_is_one_line_exit_two(args: tuple[str, ...], option: str) -> None:
    done = run_cli(*args, timeout_s=60)
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1 and "Traceback" not in done.stderr, done.stderr
    assert option in lines[0], lines[0]


def test_an_output_that_names_a_file_is_refused_as_a_directory(tmp_path: Path) -> None:
    existing = tmp_path / "runs"
    existing.write_text("")
    done = run_cli("simulate", "--out", str(existing))
    assert done.returncode == 2 and "names a file" in done.stderr


@pytest.mark.parametrize("kind", ["fifo", "device", "duplicate", "huge"])
def test_a_scenario_file_that_is_no_scenario_is_refused_without_reading_it_whole(tmp_path: Path, kind: str) -> None:
    path = tmp_path / "scenario.json"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "device":
        path.symlink_to("/dev/zero")
    elif kind == "duplicate":
        path.write_text('{"lane": "left", "lane": "right", "left_lane": [], "right_lane": []}')
    else:
        path.write_text('{"lane": "' + "x" * 400_000 + '"}')
    done = run_cli("plan", str(path), timeout_s=30)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "scenario.json" in done.stderr


@pytest.mark.parametrize("args", [("--seed", "-5"), ("--timeout", "inf"), ("--horizon", "1000000000"),
                                  ("--out", "/proc/conform"), ("--engines", "interpreter")])
def test_the_older_conformance_campaign_refuses_bad_input_in_one_line(args: tuple[str, ...]) -> None:
    done = subprocess.run([sys.executable, "-m", "ci.conform", "--count", "2", *args], capture_output=True,
                          text=True, timeout=60)
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert args[0] in done.stderr and "Traceback" not in done.stderr
