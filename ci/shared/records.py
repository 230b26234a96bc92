"""A campaign's resumable record: one JSON object per line, appended as each unit of work finishes.

An interruption can cut the last line short: reading skips it (that unit is done again), and
re-opening for append first removes it, so the file holds whole records only. One
campaign works in a folder at a time (``campaign_lock``: a lock the kernel drops when its
holder dies, so a killed campaign never leaves a stale lock).
"""

from __future__ import annotations

import contextlib
import datetime
import fcntl
import json
import os
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from spec.errors import OptionError

LOCK_FILE = ".campaign.lock"


def read_records(path: Path) -> Iterator[dict[str, Any]]:
    """Every whole record in ``path`` (none if it does not exist)."""
    if not path.exists():
        return
    for line in path.read_text().splitlines():
        try:
            record = json.loads(line)
        except json.JSONDecodeError:
            continue  # cut short by an interruption
        if isinstance(record, dict):
            yield record


def open_for_append(path: Path) -> IO[str]:
    """``path`` opened to append records, after removing a last line an interruption left half-written (its unit of
    work was not recorded, and is done again)."""
    if path.exists():
        data = path.read_bytes()
        if data and not data.endswith(b"\n"):
            with path.open("r+b") as handle:
                handle.truncate(data.rfind(b"\n") + 1)
    return path.open("a")


def append(log: IO[str], record: dict[str, Any]) -> None:
    """Write one record and make it durable before the next unit of work starts."""
    log.write(json.dumps(record) + "\n")
    log.flush()


_HELD: set[Path] = set()  # folders this process holds (a command locks before its heading, its campaign again)


@contextlib.contextmanager
def campaign_lock(folder: Path) -> Iterator[None]:
    """Hold ``folder`` for this campaign; another campaign there is bad input naming the holder."""
    folder.mkdir(parents=True, exist_ok=True)
    key = folder.resolve()
    if key in _HELD:
        yield
        return
    path = folder / LOCK_FILE
    handle = path.open("a+")
    try:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            handle.seek(0)
            holder = handle.read().strip() or "another process"
            raise OptionError("--out", str(folder), f"in use by {holder}: one campaign per folder at a time") from None
        handle.seek(0)
        handle.truncate()
        since = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
        handle.write(f"pid {os.getpid()} ({' '.join(os.path.basename(a) for a in sys.argv[:2])}, since {since})\n")
        handle.flush()
        _HELD.add(key)
        try:
            yield
        finally:
            _HELD.discard(key)
    finally:
        handle.close()  # closing drops the lock
