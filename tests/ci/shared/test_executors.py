"""ci/shared/executors.py: every executor runs every job once and hands back the same results."""

from __future__ import annotations

import operator
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

import ci.shared.executors
from ci.shared.executors import ExecutorChoice, ExecutorKind, check_executor, run_jobs
from spec.errors import OptionError, ToolMissing

JOBS = [(i, i * i) for i in range(6)]
EXPECTED = {i: i + i * i for i in range(6)}


PROCESSES, DASK = ExecutorKind.PROCESSES, ExecutorKind.DASK


@pytest.mark.parametrize("choice", [ExecutorChoice(), ExecutorChoice(PROCESSES, 2), ExecutorChoice(DASK, 2)],
                         ids=["in-process", "processes", "dask-local"])
def test_every_executor_runs_each_job_once_with_the_same_results(choice: ExecutorChoice) -> None:
    results = list(run_jobs(operator.add, JOBS, choice))
    assert sorted(i for i, _ in results) == list(range(len(JOBS)))
    assert dict(results) == EXPECTED


def test_dask_runs_on_a_scheduler_given_by_its_address() -> None:
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        choice = ExecutorChoice(ExecutorKind.DASK, scheduler=cluster.scheduler_address)
        assert dict(run_jobs(operator.add, JOBS, choice)) == EXPECTED


def test_an_unreachable_scheduler_is_a_missing_tool_not_a_traceback(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(ci.shared.executors, "CONNECT_TIMEOUT_S", 1)
    with pytest.raises(ToolMissing, match=r"no dask scheduler answered at tcp://127\.0\.0\.1:9"):
        list(run_jobs(operator.add, JOBS, ExecutorChoice(ExecutorKind.DASK, scheduler="tcp://127.0.0.1:9")))


@pytest.mark.parametrize(("choice", "key"), [
    (ExecutorChoice("threads"), "--executor"),  # type: ignore[arg-type]
    (ExecutorChoice(ExecutorKind.PROCESSES, scheduler="tcp://x:1"), "--scheduler"),
    (ExecutorChoice(ExecutorKind.PROCESSES, 0), "--workers")])
def test_a_choice_that_cannot_run_is_bad_input_naming_the_option(choice: ExecutorChoice, key: str) -> None:
    with pytest.raises(OptionError, match=key):
        check_executor(choice)


def report_twice(a: int, b: int, report=None) -> int:  # type: ignore[no-untyped-def]
    report((a, 1))
    report((a, 2))
    return a + b


@pytest.mark.parametrize("choice", [ExecutorChoice(), ExecutorChoice(PROCESSES, 2)], ids=["in-process", "processes"])
def test_progress_reported_by_a_job_reaches_this_process_while_it_runs(choice: ExecutorChoice) -> None:
    heard: list[tuple[int, int]] = []
    assert dict(run_jobs(report_twice, JOBS, choice, heard.append)) == EXPECTED
    assert sorted(heard) == sorted((i, k) for i in range(len(JOBS)) for k in (1, 2))


PROGRESS_ON_TWO_WORKERS = """
from ci.shared.executors import ExecutorChoice, ExecutorKind, run_jobs
from tests.ci.shared.test_executors import report_twice
heard = []
done = dict(run_jobs(report_twice, [(1, 2), (3, 4)], ExecutorChoice(ExecutorKind.PROCESSES, 2), heard.append))
print(done == {0: 3, 1: 7} and sorted(heard) == [(1, 1), (1, 2), (3, 1), (3, 2)])
"""


def test_progress_on_two_workers_runs_under_a_temporary_folder_too_long_for_a_unix_socket(tmp_path: Path) -> None:
    """A Unix socket's path has at most 107 bytes; the progress queue's server must not need one under TMPDIR (a
    fresh process: multiprocessing keeps its first temporary folder for the life of the process)."""
    long = tmp_path / ("t" * 110)
    long.mkdir()
    done = subprocess.run([sys.executable, "-c", PROGRESS_ON_TWO_WORKERS], env={**os.environ, "TMPDIR": str(long)},
                          capture_output=True, text=True, timeout=120, check=False)
    assert done.returncode == 0 and done.stdout.strip() == "True", done.stderr


def mark_and_wait(folder: str, index: int) -> int:
    (Path(folder) / str(index)).touch()  # this job started
    time.sleep(0.5)
    return index


def test_a_campaign_stopped_early_starts_none_of_its_queued_jobs(tmp_path: Path) -> None:
    """Ctrl-C (or any error) while runs are queued must not go on to run, and throw away, every queued run."""
    results = run_jobs(mark_and_wait, [(str(tmp_path), i) for i in range(12)], ExecutorChoice(PROCESSES, 2))
    next(results)
    results.close()  # the consumer stops, as the CLI does on an interrupt
    started = len(list(tmp_path.iterdir()))
    time.sleep(1.0)
    assert started == len(list(tmp_path.iterdir())) < 12
