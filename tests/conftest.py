"""Shared test settings and helpers: hypothesis profiles picked by HYPOTHESIS_PROFILE, the requires_spin
marker, and the hypothesis strategy for valid scenarios that tests import from here."""

from __future__ import annotations

import os
import random
import shutil
import subprocess
import sys
from dataclasses import replace

import pytest
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from spec.assumptions import profile
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.library import builtin
from spec.physical import LOOP
from spec.scenario import Scenario, make_scenario, sensed
from spec.sound import Sound, sensed_extents

settings.register_profile("dev", max_examples=60, deadline=None)
settings.register_profile("ci", max_examples=200, deadline=None, suppress_health_check=[HealthCheck.too_slow],
                          print_blob=True, derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "dev"))
#: Whether the tests run in CI's profile: sweeps and samples sized by it run whole there (.ci/run), a part by default.
CI_PROFILE = os.environ.get("HYPOTHESIS_PROFILE", "dev") == "ci"


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """The slow tests first (each takes minutes: started last, one of them would keep a core busy long after the
    other is idle; ``ci/test.sh`` hands tests to its workers in this order), the rest in their own order; skip tests
    marked requires_spin when spin or gcc is missing (CI installs both)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)  # stable: each part keeps its order
    missing = [tool for tool in ("spin", "gcc") if shutil.which(tool) is None]
    if not missing:
        return
    skip = pytest.mark.skip(reason=f"requires {' and '.join(missing)} (apt-get install spin gcc)")
    for item in items:
        if "requires_spin" in item.keywords:
            item.add_marker(skip)


@st.composite
def scenarios(draw: st.DrawFn, max_left: int = 5, max_right: int = 2, horizon: int | None = None,
              span: int | None = None, grid: Grid = PAPER_GRID) -> Scenario:
    """A valid scenario on ``grid``: cells drawn in ``0 .. span`` (default the whole window) so that plans and
    dead ends both occur."""
    lane = draw(st.sampled_from(list(Lane)))
    cells = st.integers(0, grid.road_cells if span is None else span)
    left = draw(st.lists(cells, max_size=max_left, unique=True))
    right = draw(st.lists(cells, max_size=max_right, unique=True))
    if lane is Lane.LEFT:
        left = [c for c in left if c != grid.av_cell]
    else:
        right = [c for c in right if c != grid.av_cell]
    ahead = sum(1 for c in left if c >= grid.av_cell)
    targets = draw(st.integers(0, min(ahead, 3)))
    h = horizon if horizon is not None else draw(st.integers(0, 12))
    return make_scenario(lane, left, right, targets, horizon=h, grid=grid)


#: The paper's grid and the finer ones every engine must handle alike.
GRIDS = tuple(Grid(c) for c in STANDARD_CELLS_M)


def scenarios_on_grids(span: int | None = None, **kw: object) -> st.SearchStrategy[Scenario]:
    """``scenarios(**kw)`` on any standard grid; ``span`` (cells of the paper's grid) scales with the grid."""
    def on(grid: Grid) -> st.SearchStrategy[Scenario]:
        scaled = None if span is None else round(span * PAPER_GRID.cell / grid.cell)
        return scenarios(span=scaled, grid=grid, **kw)  # type: ignore[arg-type]

    return st.sampled_from(GRIDS).flatmap(on)


def run_cli(*args: str, timeout_s: float = 120) -> subprocess.CompletedProcess[str]:
    """The ``overtake`` command in a fresh process, as a user runs it."""
    return subprocess.run([sys.executable, "-m", "ci.cli.main", *args], capture_output=True, text=True,
                          timeout=timeout_s)


# -- what a snapshot measured (``spec.scenario.sensed``), for the engines' agreement tests -------------------------
#: The AV at 21 m cells between the vehicle it passed and the next one, each sensed 21 m away: their cells reach the
#: AV (no start is provable), the readings do not.
MEASURED = ("left", (9, 11), (20,), 1, ((-21.0, -21.0), (21.0, 21.0)), ((215.0, 216.0),))


def measured_pinned(sound: Sound) -> Scenario:
    lane, left, right, targets, left_m, right_m = MEASURED
    return sensed(replace(make_scenario(lane, list(left), list(right), targets), sound=sound), left_m, right_m)


def measured_like(rng: random.Random, scenario: Scenario) -> Scenario:
    """``scenario`` with each vehicle sensed at a reading or within a short interval of its cell."""
    same, oncoming = sensed_extents(scenario.lane, scenario.left_lane, scenario.right_lane, scenario.grid)
    pick = [(lo + a * (hi - lo), lo + a * (hi - lo) + b * (hi - lo) * (1 - a))
            for lo, hi in (*same, *oncoming) for a, b in [(rng.random(), rng.choice((0.0, 0.3)))]]
    return sensed(scenario, tuple(pick[:len(same)]), tuple(pick[len(same):]))


#: The shortest plan's length where a snapshot's age decides it (``aged_witness``): acting at the snapshot's instant,
#: and one control step later (the closed loop's planning budget).
AGED_SHORTEST_LENGTH = {0.0: 3, LOOP.plan_budget_s: 4}


def aged_witness(latency_s: float) -> Scenario:
    """One vehicle ahead, measured at exactly 9.62 m, under the paper profile with ``latency_s``: acting at once the
    shortest overtake is three actions, one control step later (the loop's budget; ``Sound.age_m`` of the left lane:
    0.1 m either way, the AV at the common speed within twice its envelope's speed error) four. Found by scanning the
    measured position over 0..60 m by 0.05 m, then 9.4..9.7 m by 0.01 m, with the interpreter: 9.57..9.66 m do."""
    return replace(builtin("one_target").load(), left_m=((9.62, 9.62),),
                   sound=Sound(replace(profile("paper"), latency_s=latency_s)))


def check_aged_witness(engine: str, latency_s: float) -> None:
    """``engine`` answers ``aged_witness(latency_s)`` as the interpreter does, with the shortest plan's length there."""
    from oracle.planner import plan
    from spec.answers import Status, Strategy

    scenario = aged_witness(latency_s)
    answer = plan(scenario, Strategy.SHORTEST, engine=engine)
    assert answer.status is Status.PLAN and len(answer.actions) == AGED_SHORTEST_LENGTH[latency_s], answer
    assert answer.actions == plan(scenario, Strategy.SHORTEST).actions


#: The built-ins the engines' commitments are compared on (each with a plan under the paper's rules).
COMMITTED_BUILT_INS = ("paper_example", "one_target", "two_targets", "oncoming_forces_wait", "prep_case_b")


def committed_answers(name: str, bounds: str, strategy: object, engine: str) -> tuple[object, object]:
    """The interpreter's and ``engine``'s answers (unchecked) for a built-in under ``bounds`` and the commitment
    semantics, their statuses the same ("no plan" and "no plan within the horizon" alike: only the interpreter
    proves the former of the prediction)."""
    from oracle.planner import solve
    from spec.answers import Status
    from spec.escapes import COMMIT

    found = builtin(name)
    assert found is not None
    scenario = replace(found.load(), sound=Sound(profile(bounds), commitment=COMMIT))
    ours, theirs = solve(scenario, strategy), solve(scenario, strategy, engine=engine)  # type: ignore[arg-type]
    assert theirs.status is ours.status or {ours.status, theirs.status} == {
        Status.NO_PLAN, Status.NO_PLAN_WITHIN_HORIZON}, (theirs.detail, ours.detail)
    return ours, theirs


def paper_start_collision() -> Scenario:
    """The AV in the right lane with an oncoming vehicle one cell behind it: a collision under the paper's rules (its
    danger zone is symmetric), safe under the sound model (the vehicle is past): the commitment semantics' prediction
    starts there unchecked, and the whole plan is the move back (``spec.commitment``)."""
    from spec.escapes import COMMIT

    return replace(make_scenario("right", [], [9], 0, horizon=1), sound=Sound(profile("paper"), commitment=COMMIT))
