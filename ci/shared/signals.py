"""Ctrl-C and SIGTERM reach a command at once, even while an engine runs native code.

Python runs a signal handler between bytecodes only, so while Z3 solves (native code, for as long as a check
takes: without --timeout, unbounded) SIGTERM waited for the check to end; and during a check Z3 takes SIGINT for
itself (its ``ctrl_c`` parameter): it cancels the check and answers "unknown", so Ctrl-C became an "incomplete"
answer (exit 3), or in a campaign an incomplete verdict or a planner failure recorded as a finding while the
campaign went on. Within ``handled``, Z3 leaves SIGINT alone, and a thread that hears every signal through Python's
wakeup descriptor cancels a running check (``Z3_interrupt``): the main thread returns to Python and runs the
handler at once.

Python drops an exception raised inside a ``__del__`` (Z3 frees terms in one on almost every line, through ctypes,
which wraps the handler's exception in an ``ArgumentError`` of its own), so a handler that raised there would be
lost and the command would run on: while a signal has not yet ended the block, ``handled`` takes any dropped
exception (``sys.unraisablehook``) as that loss and sends the signal again from another thread, so the handler
raises once more, outside.
``received`` says which signal came, for code that sees only the KeyboardInterrupt of a cancelled check or the
``ctypes.ArgumentError`` that wraps a handler's exception raised inside a native call.
"""

from __future__ import annotations

import contextlib
import os
import signal
import socket
import sys
import threading
from collections.abc import Callable, Iterator
from typing import Any

SIGNALS = (signal.SIGINT, signal.SIGTERM)
_RECEIVED: list[int] = []  # the signals heard within ``handled``
_PENDING = threading.Event()  # a signal came and has not yet ended the ``handled`` block


def received() -> int | None:
    """The first signal heard within ``handled``, if any."""
    return _RECEIVED[0] if _RECEIVED else None


@contextlib.contextmanager
def handled(handler: Callable[[int, Any], None]) -> Iterator[None]:
    """Within the block, ``handler`` handles SIGINT and SIGTERM in the main thread, promptly; after it, as before
    (after a signal: ignored, since the command is ending on it)."""
    if threading.current_thread() is not threading.main_thread():  # signals reach the main thread only
        yield
        return
    z3_ctrl_c = _z3_ctrl_c("false")
    _RECEIVED.clear()
    _PENDING.clear()

    def on_signal(signum: int, frame: Any) -> None:
        _RECEIVED.append(signum)
        _PENDING.set()
        handler(signum, frame)

    previous_hook = sys.unraisablehook

    def on_dropped(dropped: Any) -> None:
        if _PENDING.is_set():
            # the handler's exception (or ctypes' wrapping of it) raised inside a __del__ and dropped there: the
            # signal again, from another thread, so that the handler runs at the main thread's next line, outside
            # (run from here, it would raise inside this hook)
            threading.Timer(0.01, _resend, (_RECEIVED[-1],)).start()
        elif not _RECEIVED:
            previous_hook(dropped)
        # else: debris of the work the signal broke off (a Z3 term half made when it came): the command is ending

    sys.unraisablehook = on_dropped
    previous = {sig: signal.signal(sig, on_signal) for sig in SIGNALS}
    heard, wakeup = socket.socketpair()
    wakeup.setblocking(False)
    previous_fd = signal.set_wakeup_fd(wakeup.fileno(), warn_on_full_buffer=False)
    watcher = threading.Thread(target=_cancel_native_work, args=(heard,), name="signals", daemon=True)
    watcher.start()
    try:
        yield
    finally:
        _PENDING.clear()  # the block is over: what ends it is the signal's, no more resending
        signal.set_wakeup_fd(previous_fd)
        for sig, old in previous.items():
            if _RECEIVED:  # the command is ending on a signal: a late re-sent one, or a second, changes nothing
                signal.signal(sig, signal.SIG_IGN)
            elif old is not None:
                signal.signal(sig, old)
        wakeup.close()  # the watcher hears the end of the stream and stops
        watcher.join(timeout=1)
        heard.close()
        if not _RECEIVED:  # after a signal the hook stays, for the debris the interpreter's exit collects
            sys.unraisablehook = previous_hook
        _z3_ctrl_c(z3_ctrl_c)


def _resend(signum: int) -> None:
    """The signal again, unless the block it is meant to end has ended (after it the signal is ignored)."""
    if _PENDING.is_set():
        os.kill(os.getpid(), signum)


def _cancel_native_work(heard: socket.socket) -> None:
    """For each SIGINT or SIGTERM: cancel a running Z3 check, so that the main thread gets back to its handler."""
    with contextlib.suppress(OSError):
        while data := heard.recv(64):
            z3 = sys.modules.get("z3")
            if z3 is not None and any(number in SIGNALS for number in data):
                with contextlib.suppress(Exception):
                    z3.main_ctx().interrupt()


def _z3_ctrl_c(value: str | None) -> str | None:
    """Set Z3's ``ctrl_c`` parameter (its own SIGINT handler, installed for each check, takes Ctrl-C from Python);
    the value it had."""
    try:
        import z3
    except ImportError:
        return None
    before = str(z3.get_param("ctrl_c"))
    if value is not None:
        z3.set_param("ctrl_c", value == "true")
    return before
