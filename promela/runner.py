"""Run Spin: render, compile (once, cached), search with pan, replay the trail into actions and states.

A cached verifier is pan compiled together with ``serve.c``: run plainly it is pan; run
with ``--serve`` it stays up and answers many searches, each in a forked copy of itself,
so a campaign pays for starting a process once per verifier, not twice per scenario
(``search(..., serve=False)`` starts pan for every run, for comparison). Each server, and
each run of the compile-every-time pipeline, works in its own temporary directory, so
concurrent runs never share a ``pan.c`` or a trail; a server removes the last trail before
every search, so no trail from an earlier run can be replayed by mistake.
pan's own words decide the answer, and only after a clean exit (0) with pan's closing summary
("errors: N"), for pan ends every search that way, plan or none, truncated or not:

- "max search depth too small" or the memory bound ("reached -DMEMLIM bound", "out of memory"):
  "incomplete", even with a trail (a truncated search claims nothing);
- the goal's assertion violated ("assertion violated  !(reached)") and a trail written: a plan;
- "errors: 0" in pan's clean report of a complete search (its banner first, a full state-space
  search, no warning, no line of pan's own but its timing): "no plan within the horizon", the
  only way to it;
- the time limit (pan killed by the runner or the server): "incomplete";
- anything else is an engine error naming pan's exit code or signal and its first line, never
  "no plan": a signal (even after a trail or "errors: 0"), any other exit code, no output, no
  summary, a line it does not know (before, inside or after the report), another assertion (an
  array bound), a goal violation without its trail, an interrupted search ("Interrupted":
  "Search not completed" with no limit named).

A replay (``pan -r``, ``spin -t``) that times out or does not exit cleanly is an engine error too.
"""

from __future__ import annotations

import atexit
import fcntl
import hashlib
import multiprocessing.util
import os
import re
import select
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache, lru_cache
from pathlib import Path
from typing import IO

from promela import sound as sound_model
from promela.render import ENV_VAR, SEARCH, Probe, Query, Shape, render, render_for, scenario_values, shape_of
from spec.actions import Action
from spec.answers import SearchResult, Status, Strategy
from spec.errors import EngineError, ToolMissing
from spec.grid import Grid
from spec.lanes import Lane
from spec.scenario import Problem
from spec.sound import Sound, hold_floor_mps
from spec.state import State

MODEL_FILE = "model.pml"
#: gcc flags: SAFETY (no cycle detection needed), a memory bound pan reports, and -O1, for both modes: it compiles a
#: sound verifier ~1.6x faster than -O2 and its searches run as fast (docs/engines.md), and a campaign that draws
#: bounds compiles a verifier per draw.
CFLAGS = ("-O1", "-DSAFETY", "-DMEMLIM=2048", "-w")
HASH_BITS = 16  # pan's default table (-w24) costs ~130 ms to clear; these models are small
#: pan's depth bound is the horizon plus this: the start takes two transitions, each action one.
DEPTH_MARGIN = 10
COMPILE_TIMEOUT_S = 300.0
#: pan's time limit when the caller sets none: a hung verifier answers "incomplete", never hangs a plan.
DEFAULT_TIMEOUT_S = 60.0
CHECKSUM_FILE = "pan.sha256"  # written after a successful build; a verifier that fails it is rebuilt
SERVER_SOURCE = Path(__file__).with_name("serve.c")  # pan's main renamed, and the --serve loop
SERVER_GRACE_S = 30.0  # a server that has not answered this long after a run's own time limit is hung
SERVER_START_S = 10.0  # a server that has not said "ready" by then will not start: the verifier is rebuilt
REPLAY_TIMEOUT_S = 60.0  # replaying a trail of at most MAX_HORIZON steps takes milliseconds
#: The goal's assertion (``assert(!reached)``, promela.render) as pan reports it violated: the one error that is a plan.
GOAL_VIOLATED = re.compile(r"assertion violated\s+!\(reached\)")
SUMMARY = re.compile(r"errors: (\d+)")  # pan's closing summary: it ran to its end
#: A batch probe's sequence held (``promela.render.Probe.BATCH``), printed by the verifier during its search.
HELD = re.compile(r"^HELD (\d+)\n", re.MULTILINE)
INSTALL_HINT = {"spin": "apt-get install spin", "gcc": "apt-get install gcc"}


@dataclass(frozen=True, slots=True)
class Verifier:
    """A compiled pan binary and whether it came from the cache."""

    path: Path
    cached: bool


def check_tools() -> None:
    """Raise ToolMissing, with the install command, when spin or gcc is not on PATH (looked up once per PATH: every
    search asks, and a lookup walks the whole PATH)."""
    tools_on(os.environ.get("PATH"))


@lru_cache(maxsize=8)
def tools_on(path: str | None) -> None:
    """``check_tools`` on the PATH ``path``; only a lookup that found both is remembered (a test that changes how tools
    are looked up clears it: ``tools_on.cache_clear()``)."""
    for tool in ("spin", "gcc"):
        if shutil.which(tool) is None:
            raise ToolMissing(f"{tool} not found on PATH: install it with `{INSTALL_HINT[tool]}` "
                              f"(Spin needs gcc as its preprocessor and compiler)")


@cache
def tool_versions() -> str:
    """Spin's and gcc's version lines: part of the cache key and of every answer."""
    check_tools()
    spin = _run(["spin", "-V"], timeout=30).stdout.strip().splitlines()
    gcc = _run(["gcc", "--version"], timeout=30).stdout.strip().splitlines()
    return f"{spin[0] if spin else 'spin ?'}; {gcc[0] if gcc else 'gcc ?'}"


def cache_dir() -> Path:
    """Where compiled verifiers live: $OVERTAKE_CACHE, else $XDG_CACHE_HOME/overtake, else ~/.cache/overtake."""
    if os.environ.get("OVERTAKE_CACHE"):
        return Path(os.environ["OVERTAKE_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "overtake"


def verifier(shape: Shape | sound_model.SoundShape, strategy: Strategy) -> Verifier:
    """The compiled verifier for ``shape``: from the cache, or compiled once and cached.

    The key hashes the rendered template (which holds every rule and number of the shape's
    model, goal and grid), the grid itself, the compiler flags, the tool versions, the server's and this
    module's source; for the sound model also its shape in full (``SoundShape.key_text``: rules, goal, grid, the
    phantoms' lanes, the followers' words). The sound model's numbers are not compiled in: each search names its
    table (``table_file``)."""
    target = cache_dir() / _cached_name(shape, strategy, tool_versions())
    if _healthy(target):
        return Verifier(target / "pan", True)
    if target.exists():
        discard(target)  # damaged (truncated, altered, not executable, no checksum): built again below
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".build-") as build:
        _compile(Path(build), _source(shape), _flags(strategy), serve=True)
        (Path(build) / CHECKSUM_FILE).write_text(_sha256(Path(build) / "pan"))
        try:
            os.rename(build, target)  # atomic: a concurrent build of the same key wins or loses whole
            os.mkdir(build)  # for TemporaryDirectory's clean-up
        except OSError:
            if not (target / "pan").exists():
                raise
    return Verifier(target / "pan", False)


@lru_cache(maxsize=256)
def _cached_name(shape: Shape | sound_model.SoundShape, strategy: Strategy, versions: str) -> str:
    """The cache folder's name of ``shape``'s verifier for ``strategy`` under the tools ``versions`` (``verifier``'s
    key), made once per process: hashing the rendered model on every search cost more than a served search's own
    start."""
    key_text = [_source(shape), f"cell_m={shape.grid.cell_m}", " ".join(_flags(strategy)), versions, _server_source(),
                _own_source()]
    if isinstance(shape, sound_model.SoundShape):
        key_text.append(shape.key_text())
    key = hashlib.sha256("\n".join(key_text).encode()).hexdigest()[:24]
    return f"pan-{shape.name}-{strategy.value}-{key}"


def _source(shape: Shape | sound_model.SoundShape) -> str:
    """The Promela model a verifier of ``shape`` is compiled from: the sound model's or the paper model's."""
    return sound_model.render(shape) if isinstance(shape, sound_model.SoundShape) else render(shape)


_VERIFIED: dict[Path, tuple[int, int]] = {}  # pan -> (size, mtime) when its checksum last matched
_WRITTEN: set[Path] = set()  # the sound models' tables this process wrote or found whole (table_file)


def _healthy(folder: Path) -> bool:
    """Whether a cached verifier is whole: present, executable, and matching the checksum its build wrote."""
    pan, checksum = folder / "pan", folder / CHECKSUM_FILE
    try:
        info = pan.stat()
        if not os.access(pan, os.X_OK) or not checksum.is_file():
            return False
        if _VERIFIED.get(pan) == (info.st_size, info.st_mtime_ns):
            return True
        if checksum.read_text().strip() != _sha256(pan):
            return False
    except OSError:
        return False
    _VERIFIED[pan] = (info.st_size, info.st_mtime_ns)
    return True


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def discard(folder: Path) -> None:
    """Remove a cached verifier (it is built again on next use), and stop its servers; every table is looked at
    again on next use."""
    _VERIFIED.pop(folder / "pan", None)
    _WRITTEN.clear()
    for key in [k for k in _SERVERS if k[0] == folder / "pan"]:
        _SERVERS.pop(key).close()
    shutil.rmtree(folder, ignore_errors=True)


@cache
def _server_source() -> str:
    return SERVER_SOURCE.read_text()


@cache
def _own_source() -> str:
    """This module's text, part of every key: how a verifier is compiled and served lives here."""
    return Path(__file__).read_text()


def _flags(strategy: Strategy) -> list[str]:
    return [*CFLAGS, "-DBFS"] if strategy is Strategy.SHORTEST else list(CFLAGS)


def _compile(folder: Path, source: str, flags: list[str], serve: bool = False) -> None:
    """spin -a, then gcc: pan.c alone (the paper's pipeline) or with the server (``serve``: the cached verifiers)."""
    (folder / MODEL_FILE).write_text(source)
    spin = _run(["spin", "-a", MODEL_FILE], cwd=folder, timeout=COMPILE_TIMEOUT_S)
    if spin.returncode != 0 or not (folder / "pan.c").exists():
        raise EngineError(f"spin -a failed on the rendered model: {_said(spin)}")
    main = "pan.c"
    if serve:
        main = SERVER_SOURCE.name
        (folder / main).write_text(_server_source())
    gcc = _run(["gcc", *flags, "-o", "pan", main], cwd=folder, timeout=COMPILE_TIMEOUT_S)
    if gcc.returncode != 0:
        raise EngineError(f"gcc failed on pan.c: {_said(gcc)}")


def search(problem: Problem, strategy: Strategy, timeout_s: float | None = None,
           serve: bool = True, query: Query = SEARCH) -> SearchResult:
    """Compile-once planning: the cached verifier, the scenario injected through the environment; by its server
    (``serve``), else a pan process per run. A scenario with a sound model is searched in the sound model's
    verifier (``promela.sound``), the others in the paper model's.

    A cached verifier that will not start or answers nonsense is rebuilt once; if the rebuilt one
    fails too, the engine error names the cache to clear. Without a time limit pan gets
    ``DEFAULT_TIMEOUT_S``, counted from when the verifier is built: a compile (once per shape, on a busy machine
    seconds) is not the search's time, and counting it made a first search ``incomplete`` by load alone."""
    check_tools()
    limit = DEFAULT_TIMEOUT_S if timeout_s is None else timeout_s
    shape = shape_of(problem) if problem.scenario.sound is None else sound_model.shape_of(problem)
    for attempt in (1, 2):
        built = verifier(shape, strategy)
        started = time.perf_counter()
        try:
            return _search_with(built, problem, limit, started, serve, query)
        except (EngineError, OSError) as err:
            reason = str(err) if isinstance(err, EngineError) else f"the verifier would not start ({err})"
            if attempt == 1 and built.cached:
                discard(built.path.parent)
                continue
            raise EngineError(f"{reason} [verifier {built.path.parent}; if it persists, clear the cache: "
                              f"rm -rf {cache_dir()}]") from None
    raise AssertionError("unreachable")


def table_file(problem: Problem) -> Path:
    """The sound model's table for ``problem`` (``promela.sound.table_text``), in the cache and named by the hash of
    its text: written once (atomically: a concurrent writer of the same text wins or loses whole), found whole
    after, rewritten when damaged. Its path goes to the verifier with the scenario."""
    sound, scenario = sound_model.table_sound(problem), problem.scenario
    data, name = _table_data(sound, problem.grid, hold_floor_mps(scenario), scenario.lane if sound.sideways_s else None)
    path = cache_dir() / "sound-tables" / name
    if path in _WRITTEN:
        return path
    if any(c in str(path) for c in "\t\n\r"):
        raise EngineError(f"the verifier cache's path {str(cache_dir())!r} holds a tab or a line break (the served "
                          "verifiers read one request per line, tab separated): set OVERTAKE_CACHE to another")
    try:
        whole = path.read_bytes() == data
    except OSError:
        whole = False
    if not whole:
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=".table-", delete=False) as out:
            out.write(data)
        os.replace(out.name, path)
    _WRITTEN.add(path)
    return path


@lru_cache(maxsize=64)
def _table_data(sound: Sound, grid: Grid, hold_floor_mps: float | None, lane: Lane | None) -> tuple[bytes, str]:
    """A sound model's table as bytes and its file's name (the hash of its text), made once per process: every
    search of the closed loop asks again. ``lane``: the start's, None unless a sideways move is under way there."""
    data = sound_model.table_text(sound, grid, hold_floor_mps, lane).encode()
    return data, f"{hashlib.sha256(data).hexdigest()[:24]}.txt"


def injected(problem: Problem, query: Query = SEARCH) -> str:
    """What a verifier reads when it starts (``OVERTAKE_SCENARIO``): the scenario's values and the query's; under the
    sound model then ``|`` and the path of its table."""
    values = scenario_values(problem, query)
    return values if problem.scenario.sound is None else f"{values} | {table_file(problem)}"


def _replay_args(problem: Problem) -> list[str]:
    """pan's own replay of its trail (the sound model's: ``spin -t`` cannot run its C code)."""
    return ["-r", f"-w{HASH_BITS}", f"-m{problem.horizon + DEPTH_MARGIN}", f"{MODEL_FILE}.trail"]


def _search_with(built: Verifier, problem: Problem, timeout_s: float, started: float, serve: bool,
                 query: Query = SEARCH) -> SearchResult:
    values = injected(problem, query)
    replay_args = _replay_args(problem)
    if serve:
        server = _server(built.path)
        (server.folder / f"{MODEL_FILE}.trail").unlink(missing_ok=True)  # the last search's
        outcome = _pan(server.folder, lambda args, limit: server.run(values, args, limit), problem, timeout_s,
                       started)
        if outcome.status is not Status.PLAN or query.probe in (Probe.ESCAPE, Probe.WHOLE, Probe.START, Probe.BATCH):
            return _with_extra(outcome, built.cached, "compile-once, served")
        found = _replay(lambda args, limit: server.run(values, args, limit), replay_args, problem,
                        outcome.states_explored)
        return _with_extra(found, built.cached, "compile-once, served")
    env = {**os.environ, ENV_VAR: values}
    with tempfile.TemporaryDirectory(prefix="overtake-spin-") as work:
        folder = Path(work)
        pan = _executing(str(built.path), folder, env)
        outcome = _pan(folder, pan, problem, timeout_s, started)
        if outcome.status is not Status.PLAN or query.probe in (Probe.ESCAPE, Probe.WHOLE, Probe.START, Probe.BATCH):
            return _with_extra(outcome, built.cached, "compile-once")
        found = _replay(pan, replay_args, problem, outcome.states_explored)
        return _with_extra(found, built.cached, "compile-once")


def search_compiling(problem: Problem, strategy: Strategy, timeout_s: float | None = None) -> SearchResult:
    """The paper's pipeline: write the scenario into the model, spin -a, gcc, pan, replay with spin -t. Under the
    sound model (whose C code pan alone can replay: ``spin -t`` cannot) the verifier of the snapshot's shape is
    compiled afresh, the snapshot injected as the served verifiers take it, and pan replays its trail: what planning
    costs when every snapshot compiles its verifier (benchmarks only)."""
    check_tools()
    started = time.perf_counter()
    if problem.scenario.sound is not None:
        with tempfile.TemporaryDirectory(prefix="overtake-spin-") as work:
            folder = Path(work)
            _compile(folder, sound_model.render(sound_model.shape_of(problem)), _flags(strategy))
            pan = _executing("./pan", folder, {**os.environ, ENV_VAR: injected(problem)})
            outcome = _pan(folder, pan, problem, timeout_s, started)
            if outcome.status is not Status.PLAN:
                return _with_extra(outcome, False, "compile-every-time")
            return _with_extra(_replay(pan, _replay_args(problem), problem, outcome.states_explored), False,
                               "compile-every-time")
    with tempfile.TemporaryDirectory(prefix="overtake-spin-") as work:
        folder = Path(work)
        _compile(folder, render_for(problem), _flags(strategy))
        outcome = _pan(folder, _executing("./pan", folder, dict(os.environ)), problem, timeout_s, started)
        if outcome.status is not Status.PLAN:
            return _with_extra(outcome, False, "compile-every-time")
        found = _replay(_executing("spin", folder, dict(os.environ)), ["-t", MODEL_FILE], problem,
                        outcome.states_explored)
        return _with_extra(found, False, "compile-every-time")


#: How a pan run is made: its arguments and time limit in, (exit code, stdout and stderr) out; TimeoutExpired at the
#: limit.
Execute = Callable[[list[str], "float | None"], tuple[int, str]]


def _executing(tool: str, folder: Path, env: dict[str, str]) -> Execute:
    """Runs of ``tool`` (pan, or spin to replay) as processes of their own, in ``folder``."""
    def execute(args: list[str], limit: float | None) -> tuple[int, str]:
        done = _run([tool, *args], cwd=folder, env=env, timeout=limit)
        return done.returncode, done.stdout + done.stderr
    return execute


def _pan(folder: Path, execute: Execute, problem: Problem, timeout_s: float | None,
         started: float) -> SearchResult:
    """Run pan and read its ending by the module's list: the answer (PLAN: the goal's trail, to replay), else
    EngineError; no answer, not even "no plan", without a clean exit and pan's summary."""
    remaining = None if timeout_s is None else max(0.01, timeout_s - (time.perf_counter() - started))
    args = ["-E", "-n", f"-m{problem.horizon + DEPTH_MARGIN}", f"-w{HASH_BITS}"]
    try:
        returncode, text = execute(args, remaining)
    except subprocess.TimeoutExpired:
        return SearchResult(Status.INCOMPLETE, detail=f"pan: time limit {timeout_s} s reached")
    held = sorted({int(k) for k in HELD.findall(text)})
    text = HELD.sub("", text)
    explored, summary = _explored(text), SUMMARY.search(text)
    if returncode == 0 and summary is not None:  # pan ran to its end: a signal or an error exit never gets here
        errors = int(summary.group(1))
        if "max search depth too small" in text:
            return SearchResult(Status.INCOMPLETE, (), explored, "pan: max search depth too small")
        if "reached -DMEMLIM bound" in text or "out of memory" in text:
            return SearchResult(Status.INCOMPLETE, (), explored, "pan: memory limit reached")
        if errors > 0 and GOAL_VIOLATED.search(text) and (folder / f"{MODEL_FILE}.trail").exists():
            return SearchResult(Status.PLAN, (), explored, "a trail to replay")
        if errors == 0 and _clean_report(text):
            return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored,
                                f"no plan within {problem.horizon} actions (search completed)", extra={"held": held})
    raise EngineError(f"pan failed ({_ending(returncode)}): {_first_line(text)}")


#: The only lines of pan's own (``pan...``) a clean report of a complete search may hold: its timing.
TIMING_LINES = ("pan: elapsed time", "pan: rate")
#: pan's progress line (``snapshot()`` in pan.c: every million states, and at each breadth-first level), anywhere.
PROGRESS = re.compile(r"Depth=\s*\d+\s+States=\s*\S+\s+Transitions=")


def _clean_report(text: str) -> bool:
    """Whether ``text`` is pan's report of a complete search and nothing else: its banner first (after any progress
    lines), a full state-space search, no warning ("Search not completed", an interrupt), and no line of pan's own
    but its timing."""
    lines = [line for line in (raw.strip() for raw in text.splitlines()) if line and not PROGRESS.match(line)]
    return (bool(lines) and lines[0].startswith("(Spin Version") and "Full statespace search for:" in lines
            and not any(line.startswith(("Warning", "Interrupted")) or (line.startswith("pan")
                                                                         and not line.startswith(TIMING_LINES))
                        for line in lines))


def _replay(execute: Execute, args: list[str], problem: Problem, explored: int) -> SearchResult:
    """The plan a replay of pan's trail prints; a replay that times out or exits unclean is an engine error."""
    try:
        returncode, printed = execute(args, REPLAY_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        raise EngineError(f"the replay of pan's trail took over {REPLAY_TIMEOUT_S:g} s") from None
    if returncode != 0:
        raise EngineError(f"the replay of pan's trail failed ({_ending(returncode)}): {_first_line(printed)}")
    return _plan_from(printed, problem, explored)


# -- servers: one per verifier, process and thread ---------------------------------------------------
#: The folder served verifiers' work folders are made in: a campaign sets it to a folder of its own, which it removes
#: (``ci.shared.executors.served_scope``); otherwise the system's temporary folder.
SERVED_DIR_ENV = "OVERTAKE_SERVED_DIR"
#: A server's work folder (``overtake-served-PID-...``, named for the process that made it, for people).
SERVED_PREFIX = "overtake-served-"
#: The file in a work folder its owner holds an exclusive lock on while it lives (the kernel releases it however the
#: owner ends, SIGKILL too): a folder whose lock can be taken has no owner left (``remove_stale``).
OWNER_LOCK = ".owner"
#: Work folders without an owner's lock file (older versions; a process killed between making the folder and locking
#: it) are removed once this old: none can still be in use.
UNLOCKED_STALE_S = 24 * 3600.0


def served_root() -> Path:
    """Where this process's servers make their work folders."""
    return Path(os.environ.get(SERVED_DIR_ENV) or tempfile.gettempdir())


def hold(folder: Path) -> IO[bytes]:
    """Take ``folder``'s owner lock (``OWNER_LOCK``); it is held while the returned file stays open."""
    handle = (folder / OWNER_LOCK).open("wb")
    fcntl.flock(handle, fcntl.LOCK_EX)
    return handle


def _owned(folder: Path) -> bool | None:
    """Whether a process still holds ``folder``'s owner lock; None when it has no lock file."""
    try:
        handle = (folder / OWNER_LOCK).open("rb")
    except FileNotFoundError:
        return None
    except OSError:
        return True  # cannot tell: leave it
    with handle:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        except OSError:
            return True
        return False


def remove_stale(root: Path, prefix: str) -> int:
    """Remove the folders in ``root`` named ``prefix...`` whose owner is gone (their lock can be taken), and those
    without a lock file older than ``UNLOCKED_STALE_S``; how many were removed."""
    removed = 0
    try:
        entries = [e for e in root.iterdir() if e.name.startswith(prefix)]
    except OSError:
        return 0
    for entry in entries:
        if entry.is_symlink() or not entry.is_dir():
            continue
        owned = _owned(entry)
        if owned is None:
            try:
                owned = time.time() - entry.stat().st_mtime <= UNLOCKED_STALE_S
            except OSError:
                continue
        if not owned:
            shutil.rmtree(entry, ignore_errors=True)
            removed += 1
    return removed


class Server:
    """A verifier started with ``--serve`` (see ``serve.c``): pan runs on many scenarios in one process."""

    def __init__(self, pan: Path) -> None:
        self.pan = pan
        _close_at_exit()
        root = served_root()
        root.mkdir(parents=True, exist_ok=True)
        self._work = tempfile.TemporaryDirectory(prefix=f"{SERVED_PREFIX}{os.getpid()}-", dir=root)
        self.folder = Path(self._work.name)
        self._owner = hold(self.folder)
        self.process = subprocess.Popen([str(pan), "--serve"], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                        stderr=subprocess.DEVNULL, cwd=self.folder, text=True, bufsize=1)
        if self._reply(SERVER_START_S) != "ready":
            self.close()
            raise EngineError("the verifier's server did not start")

    def run(self, scenario: str, args: list[str], limit_s: float | None) -> tuple[int, str]:
        """One pan run (``Execute``): the scenario's values, pan's arguments, a time limit (default: the module's)."""
        limit = DEFAULT_TIMEOUT_S if limit_s is None else limit_s
        request = "\t".join([str(self.folder), str(max(1, round(limit * 1000))), scenario, *args])
        if "\n" in request or self.process.stdin is None:
            raise EngineError("a request the verifier's server cannot read")
        try:
            self.process.stdin.write(request + "\n")
            self.process.stdin.flush()
        except OSError as err:
            self.close()
            raise EngineError(f"the verifier's server has stopped ({err.strerror or err})") from None
        reply = self._reply(limit + SERVER_GRACE_S)
        if reply == "timeout":
            raise subprocess.TimeoutExpired([str(self.pan), *args], limit)
        kind, _, number = reply.partition(" ")
        if number.isdigit() and (kind == "exit" or (kind == "signal" and int(number) > 0)):  # "signal 0" is nonsense
            out = self.folder / "out.txt"  # missing when the run could not open it: no output
            text = out.read_text(errors="replace") if out.exists() else ""
            return (int(number) if kind == "exit" else -int(number)), text
        self.close()
        raise EngineError(f"the verifier's server answered {reply!r}")

    def _reply(self, wait_s: float) -> str:
        stdout = self.process.stdout
        poller = select.poll()  # not select(): it cannot watch a descriptor past 1,023
        if stdout is not None:
            poller.register(stdout, select.POLLIN)
        if stdout is None or not poller.poll(max(0, round(wait_s * 1000))):
            self.close()
            raise EngineError(f"the verifier's server did not answer within {wait_s:g} s")
        line = stdout.readline()
        if not line:
            self.close()
            raise EngineError("the verifier's server has stopped")
        return line.strip()

    def alive(self) -> bool:
        return self.process.poll() is None

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                stream.close()
        self._owner.close()
        self._work.cleanup()


_SERVERS: dict[tuple[Path, int, int], Server] = {}  # (pan, process, thread) -> its server, least recently used first
#: Servers a process's thread keeps at most: starting another stops its least recently used one (a served verifier is a
#: process, its pipes and a lock; a campaign over many sets of bounds met hundreds, and CI's sound campaign at 144 sets
#: of bounds ran out of what select() could watch). Starting one again costs a process start: its build is cached.
MAX_SERVERS = 32


def _server(pan: Path) -> Server:
    """This process's and thread's server of ``pan``, started on first use and again when it has stopped; at most
    ``MAX_SERVERS`` of them, the least recently used stopped first."""
    key = (pan, os.getpid(), threading.get_ident())
    server = _SERVERS.pop(key, None)  # put back last: the most recently used
    if server is None or not server.alive():
        if server is not None:
            server.close()
        mine = [k for k in _SERVERS if k[1:] == key[1:]]
        while len(mine) >= MAX_SERVERS:
            _SERVERS.pop(mine.pop(0)).close()
        server = Server(pan)
    _SERVERS[key] = server
    return server


@atexit.register
def close_servers(within: Path | None = None) -> None:
    """Stop this process's servers (they would die with it anyway: PR_SET_PDEATHSIG) and remove their folders; with
    ``within``, only the servers whose folder is in it."""
    for key in [k for k in _SERVERS if k[1] == os.getpid()]:
        if within is None or _SERVERS[key].folder.parent == within:
            _SERVERS.pop(key).close()


_FINALIZED: set[int] = set()  # processes whose exit closes their servers


def _close_at_exit() -> None:
    """Close this process's servers when it ends normally: a worker process of a pool ends without running atexit
    handlers, but runs multiprocessing's finalizers (its SIGTERM is ``ci.shared.executors.worker_setup``'s)."""
    if os.getpid() not in _FINALIZED:
        _FINALIZED.add(os.getpid())
        multiprocessing.util.Finalize(None, close_servers, exitpriority=0)


def _plan_from(replay: str, problem: Problem, explored: int) -> SearchResult:
    """Actions and states from the replay's INIT/STEP lines."""
    actions: list[Action] = []
    states: list[State] = []
    for line in replay.splitlines():
        words = line.split()
        if not words or words[0] not in ("INIT", "STEP"):
            continue
        if words[0] == "STEP":
            actions.append(Action(words[1]))
            words = words[1:]
        states.append(_state(words[1:]))
    if not states:
        raise EngineError("spin replay printed no states: the trail could not be replayed")
    return SearchResult(Status.PLAN, tuple(actions), explored, "", tuple(states))


def _state(words: list[str]) -> State:
    """``lane lc steps | left... | right...`` as a State."""
    head, left, right = " ".join(words).split("|")
    lane, lc, steps = map(int, head.split())
    return State(Lane.RIGHT if lane else Lane.LEFT, tuple(map(int, left.split())), tuple(map(int, right.split())),
                 lc, steps)


def _explored(text: str) -> int:
    for line in text.splitlines():
        if "states, stored" in line:
            return int(line.split()[0])
    return 0


def _with_extra(result: SearchResult, cached: bool, mode: str) -> SearchResult:
    extra = {**result.extra, "spin_version": tool_versions(), "verifier_cached": cached, "spin_mode": mode}
    return SearchResult(result.status, result.actions, result.states_explored, result.detail, result.states, extra)


def _run(args: list[str], cwd: Path | None = None, env: dict[str, str] | None = None,
         timeout: float | None = None) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    except FileNotFoundError as err:
        if not os.path.isabs(args[0]):
            raise ToolMissing(f"{args[0]} could not be run: {err.strerror}") from None
        raise  # a verifier that vanished from the cache: the caller rebuilds it


def _last_line(text: str, returncode: int) -> str:
    """The last line a tool printed, or how it ended when it printed nothing."""
    lines = text.strip().splitlines()
    return lines[-1] if lines else f"no output, {_ending(returncode)}"


def _first_line(text: str) -> str:
    """The first line a run printed (what ended pan: an error, "Interrupted", a violation), or "no output"."""
    lines = text.strip().splitlines()
    return lines[0].strip() if lines else "no output"


def _ending(returncode: int) -> str:
    """How a process ended, in words: "exit 2", or "signal 11 (SIGSEGV)" for subprocess's negative return codes."""
    if returncode >= 0:
        return f"exit {returncode}"
    try:
        return f"signal {-returncode} ({signal.Signals(-returncode).name})"
    except ValueError:
        return f"signal {-returncode}"


def _said(done: subprocess.CompletedProcess[str]) -> str:
    """What a tool said last: its error output's last line, else its output's."""
    return _last_line(done.stderr.strip() or done.stdout, done.returncode)
