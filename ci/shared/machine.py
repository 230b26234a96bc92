"""Where and when a benchmark or study ran, for its header line."""

from __future__ import annotations

import platform
import time


def machine() -> str:
    """The processor, the Python version and today's date."""
    return f"{platform.machine()}, python {platform.python_version()}, {time.strftime('%Y-%m-%d')}"
