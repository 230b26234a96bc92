"""The verifier cache heals itself: a truncated, altered or non-executable cached pan is rebuilt, a verifier that
answers nonsense is rebuilt once and then reported with the cache to clear, and a "no plan" that the interpreter
contradicts is an engine error, never an answer."""

from __future__ import annotations

import os
import shutil
from pathlib import Path

import pytest

from oracle.planner import plan
from promela import runner
from spec.answers import SearchResult, Status, Strategy
from spec.engines import Engine
from spec.errors import EngineError
from spec.library import builtin
from spec.models import ModelKind
from spec.scenario import Scenario, problem_for

pytestmark = [pytest.mark.requires_spin, pytest.mark.xdist_group("verifier-cache")]  # one worker compiles once


def _scenario() -> Scenario:
    return builtin("one_target").load()  # type: ignore[union-attr]


@pytest.fixture(scope="module")
def compiled(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A cache holding the one verifier these tests damage, compiled once for the module (each test gets a copy)."""
    cache = tmp_path_factory.mktemp("cache")
    with pytest.MonkeyPatch.context() as patch:
        patch.setenv("OVERTAKE_CACHE", str(cache))
        runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    runner.close_servers()
    return cache


@pytest.fixture
def cached(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, compiled: Path) -> tuple[Path, SearchResult]:
    """A cache of this test's own (a copy of ``compiled``) and the plan its verifier gives: the damage a test does
    is what a later process finds."""
    shutil.copytree(compiled, tmp_path, dirs_exist_ok=True)
    monkeypatch.setenv("OVERTAKE_CACHE", str(tmp_path))
    first = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert first.extra["verifier_cached"] is True
    (pan,) = tmp_path.glob("pan-*/pan")
    runner.close_servers()  # the damage below is what a later process finds
    return pan, first


@pytest.mark.parametrize("damage", ["truncated", "altered", "not executable", "no checksum", "removed"])
def test_a_damaged_cached_verifier_is_rebuilt(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        cached: tuple[Path, SearchResult], damage: str) -> None:
    pan, first = cached
    if damage == "truncated":
        pan.write_bytes(pan.read_bytes()[:1000])
    elif damage == "altered":
        data = bytearray(pan.read_bytes())
        data[len(data) // 2] ^= 0xFF
        pan.write_bytes(bytes(data))
    elif damage == "not executable":
        pan.chmod(0o644)
    elif damage == "no checksum":
        (pan.parent / runner.CHECKSUM_FILE).unlink()
    else:
        pan.unlink()
    again = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert again.actions == first.actions and again.extra["verifier_cached"] is False
    assert os.access(pan, os.X_OK) and (pan.parent / runner.CHECKSUM_FILE).read_text() == runner._sha256(pan)


def test_a_verifier_that_answers_nonsense_is_rebuilt_once_then_reported_with_the_cache(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        cached: tuple[Path, SearchResult]) -> None:
    assert cached
    calls = {"n": 0}

    def nonsense(*args: object, **kw: object) -> SearchResult:
        calls["n"] += 1
        raise EngineError("pan failed (exit 0): nonsense")

    monkeypatch.setattr(runner, "_pan", nonsense)
    with pytest.raises(EngineError, match="rm -rf") as caught:
        runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert calls["n"] == 2 and str(tmp_path) in str(caught.value)


def _hanging(pan: Path) -> None:
    """Replace a cached verifier with one that hangs but passes its checksum."""
    pan.write_text("#!/bin/sh\nsleep 30\n")
    (pan.parent / runner.CHECKSUM_FILE).write_text(runner._sha256(pan))
    pan.chmod(0o755)
    runner._VERIFIED.clear()


def test_a_hung_pan_process_is_incomplete_within_the_default_limit(tmp_path: Path,
                                                                   monkeypatch: pytest.MonkeyPatch,
        cached: tuple[Path, SearchResult]) -> None:
    pan, _ = cached
    monkeypatch.setattr(runner, "DEFAULT_TIMEOUT_S", 0.5)
    _hanging(pan)
    result = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE, serve=False)
    assert result.status is Status.INCOMPLETE and "time limit" in result.detail


def test_a_hung_run_of_a_server_is_killed_and_incomplete_within_the_default_limit(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        cached: tuple[Path, SearchResult]) -> None:
    pan, first = cached
    server = runner._server(pan)
    output = server.folder / "out.txt"
    output.unlink(missing_ok=True)
    os.mkfifo(output)  # the forked pan blocks opening its output: a real hang, inside the server
    monkeypatch.setattr(runner, "DEFAULT_TIMEOUT_S", 0.5)
    result = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert result.status is Status.INCOMPLETE and "time limit" in result.detail
    output.unlink()
    again = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert again.actions == first.actions and runner._server(pan) is server  # the server lives on


def test_a_server_that_will_not_start_is_rebuilt(tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        cached: tuple[Path, SearchResult]) -> None:
    pan, first = cached
    monkeypatch.setattr(runner, "SERVER_START_S", 0.5)
    _hanging(pan)
    again = runner.search(problem_for(_scenario(), ModelKind.FINAL), Strategy.SENSIBLE)
    assert again.actions == first.actions and again.extra["verifier_cached"] is False


def test_a_no_plan_the_interpreter_contradicts_is_an_engine_error() -> None:
    liar = Engine("liar", (Strategy.SENSIBLE,), lambda problem, strategy, limits: SearchResult(
        Status.NO_PLAN_WITHIN_HORIZON, (), 0, "search complete, no error"), "says no plan to everything")
    with pytest.raises(EngineError, match="interpreter finds a plan"):
        plan(_scenario(), Strategy.SENSIBLE, engine=liar)
    assert plan(builtin("no_plan_within_horizon").load(), engine=liar).status is Status.NO_PLAN_WITHIN_HORIZON  # type: ignore[union-attr]
