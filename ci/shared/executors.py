"""Where a campaign's independent jobs run: this process, a pool of local processes, or a dask.distributed cluster.

Campaigns hand ``run_jobs`` a picklable function and its argument tuples and get each
``(index, result)`` back as soon as that job finishes, whatever runs it. For dask,
``scheduler`` is the address of a running scheduler (``dask scheduler`` prints it; every
worker needs this package installed) or None for a local cluster of ``workers`` processes.

Every campaign's served verifiers work in one folder of its own (``served_scope``), which it removes when it ends,
however it ends short of being killed outright (its workers' folders are in it); a folder whose owner was killed
outright is removed by the next campaign.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import enum
import functools
import logging
import os
import secrets
import shutil
import signal
import sys
import tempfile
import threading
from collections.abc import Callable, Generator, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from multiprocessing.managers import SyncManager
from pathlib import Path
from typing import Any, TypeVar

from promela.runner import SERVED_DIR_ENV, SERVED_PREFIX, close_servers, hold, remove_stale
from spec.errors import OptionError, ToolMissing

R = TypeVar("R")
CONNECT_TIMEOUT_S = 10
PR_SET_PDEATHSIG = 1  # prctl(2)
CAMPAIGN_PREFIX = "overtake-campaign-"  # + the campaign's pid: its served verifiers' folder (``served_scope``)


class ExecutorKind(enum.Enum):
    """Where a campaign's jobs run."""

    PROCESSES = "processes"  # this process (one worker) or a pool of local processes
    DASK = "dask"  # a dask.distributed cluster: a local one, or a running scheduler


@dataclass(frozen=True, slots=True)
class ExecutorChoice:
    """How to run a campaign's jobs."""

    kind: ExecutorKind = ExecutorKind.PROCESSES
    workers: int = 1  # local processes (for dask without a scheduler: the local cluster's workers)
    scheduler: str | None = None  # dask only: a running scheduler's address

    def describe(self, jobs: int | None = None) -> str:
        """Where the jobs run, as many workers as will actually start (no more than ``jobs``)."""
        if self.kind is ExecutorKind.DASK and self.scheduler:
            return f"dask scheduler {self.scheduler}"
        used = self.workers if jobs is None else max(1, min(self.workers, jobs))
        if self.kind is ExecutorKind.DASK:
            return f"local dask cluster, {used} worker(s)"
        return "this process" if used <= 1 else f"{used} processes"


IN_PROCESS = ExecutorChoice()


def check_executor(choice: ExecutorChoice) -> None:
    """Reject a choice that cannot run, before any job starts."""
    if not isinstance(choice.kind, ExecutorKind):
        known = ", ".join(k.value for k in ExecutorKind)
        raise OptionError("--executor", choice.kind, f"unknown executor (known: {known})")
    if choice.scheduler and choice.kind is not ExecutorKind.DASK:
        raise OptionError("--scheduler", choice.scheduler, "a scheduler address goes with --executor dask")
    if choice.workers < 1:
        raise OptionError("--workers", choice.workers, "at least one worker is needed")


def run_jobs(fn: Callable[..., R], jobs: Sequence[tuple[Any, ...]], choice: ExecutorChoice,
             progress: Callable[[Any], None] | None = None) -> Generator[tuple[int, R], None, None]:
    """Run ``fn(*job)`` for every job; yield ``(index, result)`` in the order they finish.

    With ``progress``, each job also gets ``report=``: a function whose every call reaches
    ``progress`` in this process while the job runs (in this process or local ones; on dask,
    ``report`` is None and progress is per finished job). Jobs must not report None.
    """
    check_executor(choice)
    with served_scope():
        yield from _run_jobs(fn, jobs, choice, progress)  # callers close this generator (contextlib.closing)


_SCOPE: list[Path] = []  # this process's open scope (at most one; nested scopes share it)


@contextlib.contextmanager
def served_scope() -> Iterator[Path]:
    """A folder for this campaign's served verifiers (``promela.runner.SERVED_DIR_ENV``, inherited by its workers),
    held by its owner lock while the block runs and removed when it ends; first, the campaign and server folders
    whose owner is gone (killed outright). Within a scope already open in this process, that one."""
    if _SCOPE:
        yield _SCOPE[-1]
        return
    temporary = Path(tempfile.gettempdir())
    for prefix in (CAMPAIGN_PREFIX, SERVED_PREFIX):
        remove_stale(temporary, prefix)
    folder = Path(tempfile.mkdtemp(prefix=f"{CAMPAIGN_PREFIX}{os.getpid()}-"))
    owner = hold(folder)
    before = os.environ.get(SERVED_DIR_ENV)
    os.environ[SERVED_DIR_ENV] = str(folder)
    _SCOPE.append(folder)
    try:
        yield folder
    finally:
        _SCOPE.pop()
        close_servers(within=folder)  # this process's servers in it (its workers' die with them: PDEATHSIG)
        if before is None:
            os.environ.pop(SERVED_DIR_ENV, None)
        else:
            os.environ[SERVED_DIR_ENV] = before
        owner.close()
        shutil.rmtree(folder, ignore_errors=True)


def _run_jobs(fn: Callable[..., R], jobs: Sequence[tuple[Any, ...]], choice: ExecutorChoice,
              progress: Callable[[Any], None] | None) -> Iterator[tuple[int, R]]:
    if choice.kind is ExecutorKind.DASK:
        extra: dict[str, Any] = {"report": None} if progress else {}
        yield from _dask(functools.partial(fn, **extra), jobs, choice)
    elif choice.workers <= 1 or len(jobs) <= 1:
        call = functools.partial(fn, report=progress) if progress else fn
        for index, job in enumerate(jobs):
            yield index, call(*job)
    else:
        with contextlib.ExitStack() as stack:
            call = fn
            if progress:
                manager = SyncManager(address=_progress_address())
                manager.start(worker_setup)  # the progress queue's server process dies with the campaign too
                stack.callback(manager.shutdown)
                queue = manager.Queue()
                stack.enter_context(_drained(queue, progress))
                call = functools.partial(fn, report=queue.put)
            pool = stack.enter_context(ProcessPoolExecutor(max_workers=min(choice.workers, len(jobs)),
                                                           initializer=worker_setup))
            try:
                futures = {pool.submit(call, *job): index for index, job in enumerate(jobs)}
                for future in as_completed(futures):
                    yield futures[future], future.result()
            except BaseException:  # an interrupt, a failed job, or a consumer that stopped: nothing queued starts
                _stop(pool)
                raise


def _progress_address() -> str | None:
    """Where the progress queue's server listens: on Linux, a socket in the abstract namespace, which has no file and
    so no length limit from TMPDIR (multiprocessing's default is a file under TMPDIR, and a Unix socket's path may
    not exceed 107 bytes: a long TMPDIR made every campaign on 2 workers fail); elsewhere multiprocessing's default."""
    if not sys.platform.startswith("linux"):
        return None
    return f"\0overtake-progress-{os.getpid()}-{secrets.token_hex(8)}"


def worker_setup() -> None:
    """In each local worker: leave Ctrl-C to the campaign (which stops the workers and says so in one line), and die
    with the campaign, even when it is killed outright (Linux's parent-death signal), so no worker is orphaned."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # not the campaign's handler, inherited through fork: end at
    # once, even inside a long native call (a Z3 check); its served folder is in the campaign's, removed with it
    with contextlib.suppress(OSError, AttributeError):
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6", use_errno=True)
        libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM)
    if os.getppid() == 1:  # the campaign died before the signal was asked for
        os._exit(1)


def _stop(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and end the workers still running: an interrupted campaign stops now
    (what it finished is already recorded), instead of running every queued job and discarding it."""
    workers = list((getattr(pool, "_processes", None) or {}).values())  # the executor's own handles
    pool.shutdown(wait=False, cancel_futures=True)
    for worker in workers:
        if worker.is_alive():
            worker.terminate()


@contextlib.contextmanager
def _drained(queue: Any, progress: Callable[[Any], None]) -> Iterator[None]:
    """Hand every item the jobs put on ``queue`` to ``progress``, from a thread, until the block ends."""
    def drain() -> None:
        while (item := queue.get()) is not None:  # None ends it: a sentinel object would not survive pickling
            progress(item)

    thread = threading.Thread(target=drain, daemon=True)
    thread.start()
    try:
        yield
    finally:
        queue.put(None)
        thread.join()


def _local_cluster(make: Callable[..., Any], workers: int) -> Any:
    """A local dask cluster whose worker processes ignore Ctrl-C (the campaign's process decides what it means;
    they inherit the disposition when they start, and otherwise print a traceback each)."""
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        return make(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None,
                    silence_logs=logging.ERROR)
    finally:
        signal.signal(signal.SIGINT, before)


def _dask(fn: Callable[..., R], jobs: Sequence[tuple[Any, ...]], choice: ExecutorChoice) -> Iterator[tuple[int, R]]:
    try:
        from distributed import Client, LocalCluster
        from distributed import as_completed as dask_completed
    except ImportError:
        raise ToolMissing("dask.distributed is not installed: pip install 'distributed>=2024.1'") from None
    cluster = None
    try:
        if choice.scheduler:
            client = Client(choice.scheduler, timeout=CONNECT_TIMEOUT_S)
        else:
            cluster = _local_cluster(LocalCluster, choice.workers)
            client = Client(cluster)
    except ValueError as err:
        if not choice.scheduler:
            raise
        raise OptionError("--scheduler", choice.scheduler, f"not a scheduler address ({err})") from None
    except (OSError, TimeoutError) as err:
        raise ToolMissing(f"no dask scheduler answered at {choice.scheduler} within {CONNECT_TIMEOUT_S} s "
                          f"({type(err).__name__}); start one with `dask scheduler` and workers with "
                          f"`dask worker ADDRESS`") from None
    try:
        futures = {client.submit(fn, *job, pure=False): index for index, job in enumerate(jobs)}
        for future in dask_completed(list(futures)):
            yield futures[future], future.result()
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
