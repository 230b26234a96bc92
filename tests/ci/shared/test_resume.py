"""An interrupted or killed campaign, started again on the same folder, ends with the same totals, records and files as
one that ran through: for ``simulate`` and the conformance campaign (``crossval``), after Ctrl-C, SIGTERM and
SIGKILL. Each campaign is small (seconds), and is signalled as soon as its first record is on disk, while its
workers still have most of the work ahead of them; no process of the campaign may outlive it."""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any, NamedTuple

import pytest

from spec.errors import ExitCode

pytestmark = pytest.mark.xdist_group("resume")  # on one worker: each campaign's uninterrupted run is run once

ROOT = Path(__file__).resolve().parents[3]
TIMING = ("wall_s", "plan_ms", "plan_latency_ms", "ms", "latency")  # how long things took: no two runs agree


class Campaign(NamedTuple):
    args: tuple[str, ...]
    records: str  # the JSON-lines file a unit of work is appended to when it is finished
    key: Callable[[dict[str, Any]], object]  # what a record is about (a seed, a scenario)


CAMPAIGNS = {
    "simulate": Campaign(("simulate", "--km", "1", "--runs", "3", "--workers", "2", "--seed", "1", "--json"),
                         "runs.jsonl", lambda record: record["run"]["seed"]),
    "crossval": Campaign(("crossval", "--source", "exhaustive", "--space", "left=2@8..13,right=1@12..16,lanes=both",
                          "--engines", "interpreter", "--workers", "2", "--json"),
                         "verdicts.jsonl", lambda record: record["result"]["key"]),
}
SIGNALS = {signal.SIGINT: ExitCode.INTERRUPTED, signal.SIGTERM: ExitCode.TERMINATED, signal.SIGKILL: -signal.SIGKILL}


def _command(campaign: Campaign, out: Path) -> list[str]:
    return [sys.executable, "-m", "ci.cli.main", *campaign.args, "--out", str(out)]


def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": str(ROOT)}


def _run(campaign: Campaign, out: Path) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(_command(campaign, out), capture_output=True, text=True, timeout=300, env=_env())
    assert done.returncode == ExitCode.OK, done.stderr
    return done


def _lines(path: Path) -> list[str]:
    """The whole lines of a JSON-lines file (a torn last line left out)."""
    if not path.exists():
        return []
    return [line for line in path.read_text().split("\n")[:-1] if line]


def _without_timing(value: Any) -> Any:
    if isinstance(value, dict):
        return {k: _without_timing(v) for k, v in value.items() if k not in TIMING}
    if isinstance(value, list):
        return [_without_timing(v) for v in value]
    return value


def _outcome(campaign: Campaign, out: Path, printed: str) -> dict[str, Any]:
    """What a campaign leaves: its records by what they are about, the totals it printed, its files' names, and
    its runs' traces (a drive is deterministic given its seed)."""
    records = [json.loads(line) for line in _lines(out / campaign.records)]
    by_key = {campaign.key(r): _without_timing(r) for r in records}
    assert len(by_key) == len(records), "a unit of work recorded twice"
    files = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    traces = {name: (out / name).read_text() for name in files if name.startswith("trace-")}  # deterministic
    return {"records": by_key, "totals": _without_timing(json.loads(printed)), "files": files, "traces": traces}


@pytest.fixture(scope="module")
def uninterrupted(tmp_path_factory: pytest.TempPathFactory) -> Callable[[str], dict[str, Any]]:
    """Each campaign run through once, into a folder of its own (computed when first asked for)."""
    found: dict[str, dict[str, Any]] = {}

    def get(name: str) -> dict[str, Any]:
        if name not in found:
            out = tmp_path_factory.mktemp(f"{name}-uninterrupted")
            found[name] = _outcome(CAMPAIGNS[name], out, _run(CAMPAIGNS[name], out).stdout)
        return found[name]

    return get


def _group(pgid: int) -> list[int]:
    """The live processes of a process group."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split() if entry.name.isdigit() else []
        except OSError:
            continue
        if fields and int(fields[2]) == pgid and fields[0] != "Z":
            found.append(int(entry.name))
    return found


def _signalled(campaign: Campaign, out: Path, sig: int, log: Path) -> int:
    """Start the campaign in a session of its own, signal it once its first record is on disk (Ctrl-C: the whole
    process group, as a terminal does; SIGTERM and SIGKILL: the campaign alone, as `kill` does), and check that
    it ends with its exit code and leaves no process behind; the records it kept."""
    with (log / "stdout").open("w") as stdout, (log / "stderr").open("w") as stderr:
        process = subprocess.Popen(_command(campaign, out), stdout=stdout, stderr=stderr, text=True, env=_env(),
                                   start_new_session=True)
        try:
            deadline = time.monotonic() + 120
            while not _lines(out / campaign.records) and time.monotonic() < deadline and process.poll() is None:
                time.sleep(0.02)
            assert process.poll() is None, "the campaign ended before it could be signalled"
            if sig == signal.SIGINT:
                os.killpg(process.pid, sig)
            else:
                process.send_signal(sig)
            code = process.wait(timeout=60)
            deadline = time.monotonic() + 10
            while _group(process.pid) and time.monotonic() < deadline:
                time.sleep(0.1)
            assert _group(process.pid) == [], "a process of the campaign outlived it"
        finally:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    said = (log / "stderr").read_text()
    assert code == SIGNALS[sig] and "Traceback" not in said, said
    if sig != signal.SIGKILL:
        assert ("interrupted" if sig == signal.SIGINT else "terminated") in said.strip().splitlines()[-1], said
    return len(_lines(out / campaign.records))


#: Ctrl-C on the conformance campaign runs by default; the other signals, and every one on three drives of a
#: kilometre, are slow (.ci/run runs them).
CASES = [pytest.param(name, sig, marks=() if (name, sig) == ("crossval", signal.SIGINT) else pytest.mark.slow,
                      id=f"{name}-{signal.Signals(sig).name}") for name in CAMPAIGNS for sig in SIGNALS]


@pytest.mark.parametrize(("name", "sig"), CASES)
def test_a_signalled_campaign_resumed_ends_as_one_that_ran_through(name: str, sig: int, tmp_path: Path,
                                                                   uninterrupted: Callable[[str], dict[str, Any]]
                                                                   ) -> None:
    campaign, out, log = CAMPAIGNS[name], tmp_path / "out", tmp_path / "log"
    log.mkdir()
    kept = _signalled(campaign, out, sig, log)
    whole = uninterrupted(name)
    assert 0 < kept < len(whole["records"]), "the signal came too late to leave work for the resumed campaign"
    resumed = _outcome(campaign, out, _run(campaign, out).stdout)
    assert resumed["files"] == whole["files"]
    assert resumed["records"] == whole["records"]
    assert resumed["totals"] == whole["totals"]
    assert resumed["traces"] == whole["traces"]
