"""A campaign's resumable record: one JSON object per line, appended as each unit of work finishes.

An interruption can cut the last line short: reading skips it (that unit is done again), and
re-opening for append first ends it, so the next record starts on a line of its own.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any


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
    """``path`` opened to append records, after ending a line an interruption left half-written."""
    log = path.open("a")
    if path.stat().st_size and not path.read_bytes().endswith(b"\n"):
        log.write("\n")
    return log


def append(log: IO[str], record: dict[str, Any]) -> None:
    """Write one record and make it durable before the next unit of work starts."""
    log.write(json.dumps(record) + "\n")
    log.flush()
