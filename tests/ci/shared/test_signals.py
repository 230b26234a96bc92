"""Signals and locks: Ctrl-C and SIGTERM end a campaign with one line and their exit codes, its workers die with it
(even when it is killed outright), and a second campaign on the same folder is refused, naming the first."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from spec.errors import ExitCode


def _children(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid and fields[0] != "Z":
                found.append(int(entry.name))
    return found


def _campaign(out: Path) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "ci.cli.main", "simulate", "--km", "20", "--runs", "2",
                             "--workers", "2", "--out", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True)


def _wait_for_workers(process: subprocess.Popen[str], count: int = 2, timeout_s: float = 60) -> list[int]:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        workers = [c for c in _children(process.pid) if len(_children(c)) == 0]
        if len(_children(process.pid)) >= count:
            return workers
        time.sleep(0.2)
    raise AssertionError("the campaign started no workers")


@pytest.mark.parametrize(("sig", "code", "word"), [(signal.SIGINT, ExitCode.INTERRUPTED, "interrupted"),
                                                   (signal.SIGTERM, ExitCode.TERMINATED, "terminated")])
def test_a_signal_ends_a_campaign_with_one_line_and_stops_its_workers(tmp_path: Path, sig: int, code: int,
                                                                       word: str) -> None:
    process = _campaign(tmp_path)
    _wait_for_workers(process)
    time.sleep(1.0)
    process.send_signal(sig)
    _, stderr = process.communicate(timeout=60)
    assert process.returncode == code, stderr
    assert "Traceback" not in stderr and word in stderr.strip().splitlines()[-1]
    time.sleep(0.5)
    assert _children(process.pid) == []


def test_workers_die_with_a_campaign_killed_outright(tmp_path: Path) -> None:
    process = _campaign(tmp_path)
    _wait_for_workers(process)
    workers = _children(process.pid)
    os.kill(process.pid, signal.SIGKILL)
    process.wait(timeout=10)
    deadline = time.monotonic() + 10
    while time.monotonic() < deadline and any(Path(f"/proc/{w}").exists() and _alive(w) for w in workers):
        time.sleep(0.2)
    assert not any(Path(f"/proc/{w}").exists() and _alive(w) for w in workers)


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


def test_a_second_campaign_on_the_same_folder_is_refused_naming_the_first(tmp_path: Path) -> None:
    first = _campaign(tmp_path)
    try:
        _wait_for_workers(first)
        second = subprocess.run([sys.executable, "-m", "ci.cli.main", "simulate", "--km", "1", "--out",
                                 str(tmp_path)], capture_output=True, text=True, timeout=60)
        assert second.returncode == 2 and f"pid {first.pid}" in second.stderr, second.stderr
        assert len(second.stderr.strip().splitlines()) == 1
    finally:
        first.send_signal(signal.SIGTERM)
        first.communicate(timeout=60)


@pytest.mark.parametrize(("sig", "code", "word"), [(signal.SIGINT, ExitCode.INTERRUPTED, "interrupted"),
                                                   (signal.SIGTERM, ExitCode.TERMINATED, "terminated")])
def test_a_signal_ends_the_older_conformance_campaign_with_one_line(tmp_path: Path, sig: int, code: int,
                                                                   word: str) -> None:
    """``python -m ci.conformance.conform`` as well: its exit code, one last line, no traceback, and what it decided
    kept."""
    results = tmp_path / "results.jsonl"
    process = subprocess.Popen([sys.executable, "-m", "ci.conformance.conform", "--engines", "interpreter,z3",
                                "--strategy", "shortest", "--count", "2000", "--out", str(tmp_path)],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, start_new_session=True)
    try:
        deadline = time.monotonic() + 60
        while (not results.exists() or not results.read_text().count("\n")) and time.monotonic() < deadline:
            time.sleep(0.05)
        if sig == signal.SIGINT:
            os.killpg(process.pid, sig)  # Ctrl-C reaches the whole foreground process group
        else:
            process.send_signal(sig)
        _, stderr = process.communicate(timeout=60)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == code, stderr
    assert "Traceback" not in stderr and word in stderr.strip().splitlines()[-1], stderr
    kept = results.read_text().count("\n")
    assert 0 < kept < 2000


# Three targets to pass and oncoming traffic at horizon 200: Z3's optimal plan is a check of minutes.
LONG_CHECK = 'lane = "left"\nleft_lane = [12, 14, 16]\nright_lane = [40, 45]\ntargets = 3\nmodel = "final"\n' \
             'horizon = 200\ncell_m = 21\n'


@pytest.mark.parametrize(("sig", "code", "word"), [(signal.SIGINT, ExitCode.INTERRUPTED, "interrupted"),
                                                   (signal.SIGTERM, ExitCode.TERMINATED, "terminated")])
def test_a_signal_during_a_long_z3_check_ends_the_command_at_once(tmp_path: Path, sig: int, code: int,
                                                                  word: str) -> None:
    """Z3 took Ctrl-C for itself (the check answered "incomplete", exit 3) and SIGTERM waited for the check."""
    scenario = tmp_path / "long.toml"
    scenario.write_text(LONG_CHECK)
    process = subprocess.Popen([sys.executable, "-m", "ci.cli.main", "plan", str(scenario), "--engine", "z3",
                                "--strategy", "optimal"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        time.sleep(3)  # well into the check
        assert process.poll() is None, process.communicate()
        process.send_signal(sig)
        signalled = time.monotonic()
        out, stderr = process.communicate(timeout=20)
    finally:
        if process.poll() is None:
            process.kill()
            process.communicate()
    assert process.returncode == code and time.monotonic() - signalled < 5, (out, stderr)
    assert out == "" and "Traceback" not in stderr and word in stderr.strip().splitlines()[-1], stderr
