"""Served verifiers' folders: a campaign's live in one folder it removes, on a normal end and on SIGTERM (its workers
too); what a worker or a campaign killed outright leaves, the campaign or the next one removes. Folders are counted
in a temporary folder of the test's own (TMPDIR), before and after."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from ci.shared.executors import CAMPAIGN_PREFIX
from promela.runner import SERVED_PREFIX

pytestmark = pytest.mark.requires_spin

SWEEP = "left=2@8..20,right=1@12..30,lanes=both"  # minutes of work: the signals arrive while it runs
WAIT_S = 60.0


def _ours(tmp: Path) -> list[Path]:
    """Every campaign and served-verifier folder in ``tmp``, and in the campaign folders."""
    found = [p for p in tmp.iterdir() if p.name.startswith((CAMPAIGN_PREFIX, SERVED_PREFIX))]
    return found + [p for c in found if c.name.startswith(CAMPAIGN_PREFIX) for p in c.iterdir()
                    if p.name.startswith(SERVED_PREFIX)]


def _served_pids(tmp: Path) -> set[int]:
    served = [p.name.removeprefix(SERVED_PREFIX) for p in _ours(tmp) if p.name.startswith(SERVED_PREFIX)]
    return {int(name.split("-")[0]) for name in served}


def _campaign(tmp: Path, out: Path, *args: str) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-m", "ci.cli.main", "crossval", "--out", str(out), "--fresh", *args],
                            env={**os.environ, "TMPDIR": str(tmp)}, stdout=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)


def _until(condition: object, what: str) -> None:
    deadline = time.monotonic() + WAIT_S
    while not condition():  # type: ignore[operator]
        if time.monotonic() > deadline:
            raise AssertionError(f"not within {WAIT_S:g} s: {what}")
        time.sleep(0.2)


def _sweep_serving(tmp: Path, out: Path) -> subprocess.Popen[str]:
    """The example sweep on 2 workers, once both workers serve a verifier."""
    campaign = _campaign(tmp, out, "--source", "exhaustive", "--space", SWEEP, "--workers", "2",
                         "--max-reproducers", "0")
    _until(lambda: len(_served_pids(tmp) - {campaign.pid}) >= 2 or campaign.poll() is not None,
           "two workers serving verifiers")
    assert campaign.poll() is None, campaign.stderr.read() if campaign.stderr else ""
    return campaign


@pytest.fixture
def tmp(tmp_path: Path) -> Path:
    folder = tmp_path / "tmp"
    folder.mkdir()
    return folder


def test_a_campaign_on_two_workers_leaves_no_folder(tmp: Path, tmp_path: Path) -> None:
    campaign = _campaign(tmp, tmp_path / "out", "--source", "library", "--workers", "2")
    assert campaign.wait(timeout=600) == 0
    assert _ours(tmp) == []


def test_sigterm_to_a_campaign_removes_its_folders_and_its_workers(tmp: Path, tmp_path: Path) -> None:
    campaign = _sweep_serving(tmp, tmp_path / "out")
    before = _ours(tmp)
    assert len(before) >= 3  # the campaign's folder, a served folder per worker
    campaign.send_signal(signal.SIGTERM)
    assert campaign.wait(timeout=WAIT_S) == 143
    _until(lambda: _ours(tmp) == [], "every folder removed after SIGTERM")


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
def test_a_worker_ended_by_a_signal_leaves_nothing_once_its_campaign_ends(tmp: Path, tmp_path: Path,
                                                                          signum: int) -> None:
    campaign = _sweep_serving(tmp, tmp_path / "out")
    worker = min(_served_pids(tmp) - {campaign.pid})
    os.kill(worker, signum)
    code = campaign.wait(timeout=WAIT_S)
    assert code != 0 and "Traceback" not in (campaign.stderr.read() if campaign.stderr else "")
    _until(lambda: _ours(tmp) == [], "every folder removed when the campaign ended")


def test_folders_of_a_campaign_killed_outright_are_removed_by_the_next(tmp: Path, tmp_path: Path) -> None:
    campaign = _sweep_serving(tmp, tmp_path / "out")
    workers = _served_pids(tmp) - {campaign.pid}
    for pid in (*workers, campaign.pid):  # the workers first: a campaign's death sends them SIGTERM (PDEATHSIG)
        os.kill(pid, signal.SIGKILL)
    campaign.wait(timeout=WAIT_S)
    _until(lambda: not any(_alive(pid) for pid in workers), "the killed workers gone")
    left = _ours(tmp)
    assert len(left) >= 3  # nothing ran to remove them
    after = _campaign(tmp, tmp_path / "next", "--source", "library", "--engines", "interpreter")
    assert after.wait(timeout=600) == 0
    assert _ours(tmp) == []


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return Path(f"/proc/{pid}").exists() and "zombie" not in Path(f"/proc/{pid}/status").read_text().lower()
