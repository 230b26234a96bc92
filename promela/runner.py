"""Run Spin: render, compile (once, cached), search with pan, replay the trail into actions and states.

Every run works in its own temporary directory, so concurrent runs never share a
``pan.c`` or a trail, and no trail from an earlier run can be replayed by mistake.
pan's own words decide the answer: an assertion violation with a trail is a plan;
"errors: 0" with a complete search is "no plan within the horizon"; a depth or memory
limit or a time-out is "incomplete"; anything else is an engine error.
"""

from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import tempfile
import time
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from promela.render import ENV_VAR, Shape, render, render_for, scenario_values, shape_of
from spec.actions import Action
from spec.answers import SearchResult, Status, Strategy
from spec.errors import EngineError, ToolMissing
from spec.lanes import Lane
from spec.scenario import Problem
from spec.state import State

MODEL_FILE = "model.pml"
#: gcc flags: SAFETY (no cycle detection needed), a memory bound pan reports, no optimisation
#: for the compile-every-time pipeline would be unfair to it, so both modes use -O2.
CFLAGS = ("-O2", "-DSAFETY", "-DMEMLIM=2048", "-w")
HASH_BITS = 16  # pan's default table (-w24) costs ~130 ms to clear; these models are small
#: pan's depth bound is the horizon plus this: the start takes two transitions, each action one.
DEPTH_MARGIN = 10
COMPILE_TIMEOUT_S = 300.0
#: pan's time limit when the caller sets none: a hung verifier answers "incomplete", never hangs a plan.
DEFAULT_TIMEOUT_S = 60.0
CHECKSUM_FILE = "pan.sha256"  # written after a successful build; a verifier that fails it is rebuilt
INSTALL_HINT = {"spin": "apt-get install spin", "gcc": "apt-get install gcc"}


@dataclass(frozen=True, slots=True)
class Verifier:
    """A compiled pan binary and whether it came from the cache."""

    path: Path
    cached: bool


def check_tools() -> None:
    """Raise ToolMissing, with the install command, when spin or gcc is not on PATH."""
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


def verifier(shape: Shape, strategy: Strategy) -> Verifier:
    """The compiled verifier for ``shape``: from the cache, or compiled once and cached.

    The key hashes the rendered template (which holds every rule and number of the shape's
    model, goal and grid), the grid itself, the compiler flags and the tool versions."""
    source = render(shape)
    flags = _flags(strategy)
    key_text = [source, f"cell_m={shape.grid.cell_m}", " ".join(flags), tool_versions()]
    key = hashlib.sha256("\n".join(key_text).encode()).hexdigest()[:24]
    target = cache_dir() / f"pan-{shape.name}-{strategy.value}-{key}"
    if _healthy(target):
        return Verifier(target / "pan", True)
    if target.exists():
        discard(target)  # damaged (truncated, altered, not executable, no checksum): built again below
    target.parent.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=target.parent, prefix=".build-") as build:
        _compile(Path(build), source, flags)
        (Path(build) / CHECKSUM_FILE).write_text(_sha256(Path(build) / "pan"))
        try:
            os.rename(build, target)  # atomic: a concurrent build of the same key wins or loses whole
            os.mkdir(build)  # for TemporaryDirectory's clean-up
        except OSError:
            if not (target / "pan").exists():
                raise
    return Verifier(target / "pan", False)


_VERIFIED: dict[Path, tuple[int, int]] = {}  # pan -> (size, mtime) when its checksum last matched


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
    """Remove a cached verifier (it is built again on next use)."""
    _VERIFIED.pop(folder / "pan", None)
    shutil.rmtree(folder, ignore_errors=True)


def _flags(strategy: Strategy) -> list[str]:
    return [*CFLAGS, "-DBFS"] if strategy is Strategy.SHORTEST else list(CFLAGS)


def _compile(folder: Path, source: str, flags: list[str]) -> None:
    (folder / MODEL_FILE).write_text(source)
    spin = _run(["spin", "-a", MODEL_FILE], cwd=folder, timeout=COMPILE_TIMEOUT_S)
    if spin.returncode != 0 or not (folder / "pan.c").exists():
        raise EngineError(f"spin -a failed on the rendered model: {_last_line(spin)}")
    gcc = _run(["gcc", *flags, "-o", "pan", "pan.c"], cwd=folder, timeout=COMPILE_TIMEOUT_S)
    if gcc.returncode != 0:
        raise EngineError(f"gcc failed on pan.c: {_last_line(gcc)}")


def search(problem: Problem, strategy: Strategy, timeout_s: float | None = None) -> SearchResult:
    """Compile-once planning: the cached verifier, the scenario injected through the environment.

    A cached verifier that will not start or answers nonsense is rebuilt once; if the rebuilt one
    fails too, the engine error names the cache to clear. Without a time limit pan gets
    ``DEFAULT_TIMEOUT_S``."""
    check_tools()
    started = time.perf_counter()
    limit = DEFAULT_TIMEOUT_S if timeout_s is None else timeout_s
    for attempt in (1, 2):
        built = verifier(shape_of(problem), strategy)
        try:
            return _search_with(built, problem, limit, started)
        except (EngineError, OSError) as err:
            reason = str(err) if isinstance(err, EngineError) else f"the verifier would not start ({err})"
            if attempt == 1 and built.cached:
                discard(built.path.parent)
                continue
            raise EngineError(f"{reason} [verifier {built.path.parent}; if it persists, clear the cache: "
                              f"rm -rf {cache_dir()}]") from None
    raise AssertionError("unreachable")


def _search_with(built: Verifier, problem: Problem, timeout_s: float, started: float) -> SearchResult:
    env = {**os.environ, ENV_VAR: scenario_values(problem)}
    with tempfile.TemporaryDirectory(prefix="overtake-spin-") as work:
        folder = Path(work)
        outcome = _pan(folder, [str(built.path)], problem, env, timeout_s, started)
        if outcome.status is not Status.PLAN:
            return _with_extra(outcome, built.cached, "compile-once")
        replay = _run([str(built.path), "-r", f"-w{HASH_BITS}", f"-m{problem.horizon + DEPTH_MARGIN}",
                       f"{MODEL_FILE}.trail"],
                      cwd=folder, env=env, timeout=60)
        found = _plan_from(replay.stdout, problem, outcome.states_explored)
        return _with_extra(found, built.cached, "compile-once")


def search_compiling(problem: Problem, strategy: Strategy, timeout_s: float | None = None) -> SearchResult:
    """The paper's pipeline: write the scenario into the model, spin -a, gcc, pan, replay with spin -t."""
    check_tools()
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="overtake-spin-") as work:
        folder = Path(work)
        _compile(folder, render_for(problem), _flags(strategy))
        outcome = _pan(folder, ["./pan"], problem, dict(os.environ), timeout_s, started)
        if outcome.status is not Status.PLAN:
            return _with_extra(outcome, False, "compile-every-time")
        replay = _run(["spin", "-t", MODEL_FILE], cwd=folder, timeout=60)
        return _with_extra(_plan_from(replay.stdout, problem, outcome.states_explored), False, "compile-every-time")


def _pan(folder: Path, command: list[str], problem: Problem, env: dict[str, str], timeout_s: float | None,
         started: float) -> SearchResult:
    """Run pan: its answer, or (status PLAN, no actions yet, the states it stored) when it left a trail to replay."""
    remaining = None if timeout_s is None else max(0.01, timeout_s - (time.perf_counter() - started))
    args = [*command, "-E", "-n", f"-m{problem.horizon + DEPTH_MARGIN}", f"-w{HASH_BITS}"]
    try:
        done = _run(args, cwd=folder, env=env, timeout=remaining)
    except subprocess.TimeoutExpired:
        return SearchResult(Status.INCOMPLETE, detail=f"pan: time limit {timeout_s} s reached")
    text = done.stdout + done.stderr
    explored = _explored(text)
    if "max search depth too small" in text:
        return SearchResult(Status.INCOMPLETE, (), explored, "pan: max search depth too small")
    if "-DMEMLIM" in text or "out of memory" in text:
        return SearchResult(Status.INCOMPLETE, (), explored, "pan: memory limit reached")
    if "assertion violated" in text and (folder / f"{MODEL_FILE}.trail").exists():
        return SearchResult(Status.PLAN, (), explored, "a trail to replay")
    if done.returncode == 0 and "errors: 0" in text:
        return SearchResult(Status.NO_PLAN_WITHIN_HORIZON, (), explored,
                            f"no plan within {problem.horizon} actions (search completed)")
    raise EngineError(f"pan failed (exit {done.returncode}): {_last_line(done)}")


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
    extra = {"spin_version": tool_versions(), "verifier_cached": cached, "spin_mode": mode}
    return SearchResult(result.status, result.actions, result.states_explored, result.detail, result.states, extra)


def _run(args: list[str], cwd: Path | None = None, env: dict[str, str] | None = None,
         timeout: float | None = None) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(args, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    except FileNotFoundError as err:
        if not os.path.isabs(args[0]):
            raise ToolMissing(f"{args[0]} could not be run: {err.strerror}") from None
        raise  # a verifier that vanished from the cache: the caller rebuilds it


def _last_line(done: subprocess.CompletedProcess[str]) -> str:
    lines = (done.stderr.strip() or done.stdout.strip()).splitlines()
    return lines[-1] if lines else f"exit code {done.returncode}"
