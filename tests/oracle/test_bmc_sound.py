"""The Z3 engine's sound model (``oracle.bmc_sound``) agrees with the interpreter's (``oracle.sound``): plan or no plan
alike through the pipeline, "no plan of any length" proved wherever the interpreter proves it, every plan valid with
the validation's states, equal shortest lengths, equal least costs; the encoding's vehicles are ``spec.sound``'s; the
identity check refused; time-outs incomplete.

The seeded sample (``SAMPLE``: lanes both, 0-2 left-lane vehicles in paper cells 8..20, 0-1 oncoming in 12..30,
targets 0..len, horizon 30) runs whole in CI's profile and its first third by default (``dev``: the same draws);
``OVERTAKE_SOUND_SAMPLE=N`` multiplies it by N (another seed per round) for a larger one.
"""

from __future__ import annotations

import math
import os
import random
import statistics
import sys
import time
from dataclasses import replace

import pytest

from ci.conformance.hypo import VIEWS_M
from oracle import bmc, bmc_sound, planner, sound, z3_engine
from spec.answers import Limits, SearchResult, Status, Strategy
from spec.assumptions import Bounds, SpeedBounds, profile
from spec.cost import COST_TERMS, total_cost
from spec.errors import EngineError
from spec.grid import PAPER_GRID, Grid, grid_for
from spec.lanes import Lane
from spec.models import ModelKind
from spec.scenario import Scenario, make_scenario, problem_for
from spec.sound import Checks, Sound, vehicles
from tests.conftest import AGED_SHORTEST_LENGTH, CI_PROFILE, check_aged_witness, measured_like, measured_pinned

#: (profile, cell length, scenarios): 150 scenarios in CI's profile, both strategies each; the first third by default.
SAMPLE = tuple((name, cell_m, count if CI_PROFILE else count // 3)
               for name, cell_m, count in (("default", 21.0, 60), ("default", 10.5, 60), ("paper", 21.0, 15),
                                           ("paper", 10.5, 15)))
ROUNDS = int(os.environ.get("OVERTAKE_SOUND_SAMPLE", "1"))
STRATEGIES = (Strategy.SHORTEST, Strategy.OPTIMAL)


def _draw(rng: random.Random, grid: Grid, sound_: Sound, horizon: int = 30) -> Scenario:
    """A scenario of the sample: paper cells scaled to the grid, none in the AV's cell in its own lane."""
    scale = round(PAPER_GRID.cell / grid.cell)
    lane = rng.choice(list(Lane))
    left = [c for c in rng.sample(range(8 * scale, 20 * scale + 1), rng.randint(0, 2))
            if not (lane is Lane.LEFT and c == grid.av_cell)]
    right = rng.sample(range(12 * scale, 30 * scale + 1), rng.randint(0, 1))
    ahead = sum(1 for c in left if c >= grid.av_cell)
    return replace(make_scenario(lane, left, right, rng.randint(0, ahead), horizon=horizon, grid=grid), sound=sound_)


def _cost(scenario: Scenario, model: ModelKind, actions: tuple) -> tuple[int, ...]:
    verdict = sound.validate(problem_for(scenario, model), actions)
    return total_cost(zip(actions, verdict.states[1:]))


def _agree(scenario: Scenario, strategy: Strategy) -> tuple[float, bool]:
    """Z3's pipeline answer against the interpreter's; Z3's time, and whether it is a plan."""
    started = time.perf_counter()
    z3 = planner.solve(scenario, strategy, engine="z3")
    took = time.perf_counter() - started
    ours = planner.solve(scenario, strategy, engine="interpreter")
    where = f"{scenario} {strategy.value}: z3 {z3.status.value} {z3.actions}, interpreter {ours.status.value} " \
            f"{ours.actions}"
    assert (z3.status is Status.PLAN) == (ours.status is Status.PLAN), where
    assert z3.status is not Status.INCOMPLETE, where
    if ours.status is Status.NO_PLAN and bmc_sound.PRUNE:  # every path ends within the horizon (the prune ends the
        # hopeless ones, in both): Z3's own proof finds it too
        assert z3.status is Status.NO_PLAN, where
    if z3.status is not Status.PLAN:
        return took, False
    assert z3.model is ours.model and z3.model is not None, where
    verdict = sound.validate(problem_for(scenario, z3.model), z3.actions)
    assert verdict.valid, f"{where}: {verdict.reason}"
    assert z3.states == verdict.states, where
    if strategy is Strategy.SHORTEST:
        assert len(z3.actions) == len(ours.actions), where
    else:
        cost = _cost(scenario, z3.model, z3.actions)
        assert cost == _cost(scenario, ours.model, ours.actions), where
        assert z3.extra["cost"] == dict(zip(COST_TERMS, cost, strict=True)), where
    return took, True


@pytest.mark.parametrize(("name", "cell_m", "count"), SAMPLE, ids=[f"{n}-{c:g}m" for n, c, _ in SAMPLE])
def test_the_pipeline_agrees_with_the_interpreter_on_a_seeded_sample(name: str, cell_m: float, count: int) -> None:
    grid, sound_ = grid_for(cell_m), Sound(profile(name))
    started, times, plans = time.perf_counter(), {s: list[float]() for s in STRATEGIES}, 0
    for round_ in range(ROUNDS):
        rng = random.Random(f"sound-z3-{name}-{cell_m}-{round_}")
        for _ in range(count):
            scenario = _draw(rng, grid, sound_)
            for strategy in STRATEGIES:
                took, plan = _agree(scenario, strategy)
                times[strategy].append(took)
                plans += plan
    print(f"\n[z3 sound {name} {cell_m:g} m] {ROUNDS * count} scenarios, {plans} plans, "
          + ", ".join(f"{s.value} median {statistics.median(t) * 1000:.1f} ms max {max(t) * 1000:.0f} ms"
                      for s, t in times.items())
          + f"; {time.perf_counter() - started:.1f} s in all", file=sys.stderr)


@pytest.mark.parametrize("cell_m", [21.0, 10.5])
def test_the_translation_without_the_prune_agrees_on_short_horizons(cell_m: float,
                                                                    monkeypatch: pytest.MonkeyPatch) -> None:
    """The prune of dead states (``SoundEncoding._hopeless``, the interpreter's) changes no answer, and the
    translation agrees without it: drawn bounds (phantoms or not), measured start speeds, a short horizon."""
    monkeypatch.setattr(bmc_sound, "PRUNE", False)
    rng, grid = random.Random(f"sound-z3-unpruned-{cell_m}"), grid_for(cell_m)
    for _ in range(12):
        spread, onc = rng.choice((0.0, 0.5, 2.1)), rng.choice((0.0, 1.0, 2.1))
        bounds = Bounds("drawn", SpeedBounds(7 - spread, 7 + spread), SpeedBounds(7 - onc, 7 + onc),
                        rng.choice((0.0, 0.5, 1.5)), rng.random() < 0.5, "drawn by the test")
        sound_ = Sound(bounds, start_mps=rng.choice((None, 3.0, 9.5)))
        scenario = _draw(rng, grid, sound_, horizon=6)
        for strategy in STRATEGIES:
            _agree(scenario, strategy)


def test_an_oncoming_view_ended_short_agrees_too() -> None:
    """The oncoming phantom where a left-lane vehicle hid the lane (``Sound.oncoming_view_m``, the hypothesis source's
    views): Z3's answers are the interpreter's, and the view changes some of them."""
    rng, changed = random.Random("sound-z3-view"), 0
    for _ in range(16):
        seen = _draw(rng, PAPER_GRID, Sound(profile("default"), start_mps=rng.choice((None, 3.0, 9.5))))
        assert seen.sound is not None
        hidden = replace(seen, sound=replace(seen.sound, oncoming_view_m=rng.choice(VIEWS_M)))
        _agree(hidden, Strategy.SHORTEST)
        changed += planner.solve(hidden, Strategy.SHORTEST).actions != planner.solve(seen, Strategy.SHORTEST).actions
    assert changed > 0


def test_the_encodings_vehicles_are_the_sound_models() -> None:
    """The intervals the engine computes itself (extents widened by the sensing error; phantoms) are
    ``spec.sound.vehicles``, in its order."""
    rng = random.Random("sound-z3-vehicles")
    for cell_m in (21.0, 10.5, 7.0, 5.25):
        grid = grid_for(cell_m)
        for name in ("default", "paper"):
            for _ in range(10):
                view = rng.choice((None, *VIEWS_M))
                scenario = _draw(rng, grid, Sound(profile(name), oncoming_view_m=view))
                problem = problem_for(scenario, ModelKind.FINAL)
                enc = bmc_sound.encoding(problem)
                values = dict(((p.get_id(), v) for p, v in enc.values(scenario)))
                ours = [(Lane.LEFT, v) for v in enc.same] + [(Lane.RIGHT, v) for v in enc.oncoming]
                theirs = vehicles(scenario.lane, scenario.left_lane, scenario.right_lane, grid, scenario.sound)
                ordered = sorted(theirs, key=lambda v: v.lane is Lane.RIGHT)  # stable: same-direction ones first
                assert len(ours) == len(ordered)
                for (lane, interval), vehicle in zip(ours, ordered, strict=True):
                    ends = [values[e.get_id()] if not isinstance(e, float) else e for e in (interval.lo, interval.hi)]
                    assert lane is vehicle.lane
                    assert all(a == b or (math.isinf(a) and a == b) for a, b in
                               zip(ends, (vehicle.lo_m, vehicle.hi_m), strict=True))


def test_a_refused_start_is_no_plan_as_the_interpreters() -> None:
    grid = PAPER_GRID
    scenario = replace(make_scenario("left", [grid.av_cell + 1], [], 1, horizon=30), sound=Sound(profile("default")))
    problem = problem_for(scenario, ModelKind.FINAL)
    assert sound.shortest(problem).status is Status.NO_PLAN
    for solve in bmc_sound.SOLVERS.values():
        found = solve(problem, None)
        assert found.status is Status.NO_PLAN and "initial state" in found.detail


def test_the_identity_check_is_refused() -> None:
    scenario = replace(make_scenario("right", [12], [], 1, horizon=10),
                       sound=Sound(Bounds("zero", SpeedBounds(7, 7), SpeedBounds(7, 7), 0.0, False, "test"),
                                   checks=Checks.PAPER_CELLS))
    with pytest.raises(EngineError, match="identity check"):
        planner.solve(scenario, Strategy.SHORTEST, engine="z3")


@pytest.mark.parametrize("strategy", STRATEGIES, ids=lambda s: s.value)
def test_a_time_out_is_incomplete_never_no_plan(strategy: Strategy) -> None:
    scenario = replace(make_scenario("right", [13, 17], [], 1, horizon=30), sound=Sound(profile("default")))
    problem = problem_for(scenario, ModelKind.FINAL)
    key = (bmc_sound.Optimal if strategy is Strategy.OPTIMAL else bmc_sound.Shortest, bmc_sound.shape(problem))
    found = z3_engine._solve(problem, strategy, Limits(timeout_s=1e-9))
    assert found.status is Status.INCOMPLETE
    assert key not in bmc._kept  # a solver that gave up is not kept


def test_answers_on_kept_solvers_equal_answers_on_fresh_ones() -> None:
    """Scenarios of one shape one cell apart, on the shape's kept solver and each on its own."""
    sound_ = Sound(profile("default"))
    scenarios = [replace(make_scenario("right", [left], [right], 1, horizon=30), sound=sound_)
                 for left, right in ((12, 24), (13, 24), (13, 25), (14, 25), (14, 26), (15, 27))]
    for strategy, solve in bmc_sound.SOLVERS.items():
        problems = [problem_for(s, ModelKind.FINAL) for s in scenarios]
        kept = [solve(p, None) for p in problems]
        with bmc.isolated():
            fresh = [solve(p, None) for p in problems]
        for p, k, f in zip(problems, kept, fresh, strict=True):
            assert (k.status, len(k.actions), k.extra.get("cost")) == (f.status, len(f.actions), f.extra.get("cost"))
            if k.status is Status.PLAN:
                assert sound.validate(p, k.actions).states == k.states, strategy


def _answer(found: object) -> tuple[object, ...]:
    assert isinstance(found, SearchResult)
    return found.status, len(found.actions), found.extra.get("cost")


def test_a_wrong_expectation_never_changes_the_answer() -> None:
    """Z3 guesses an expected length and cost first (``bmc.expecting``, a cross-check's reference): each guess, right
    or wrong, too short or too long, cheaper or dearer, gives the answer it gives without one; the right one asks
    no more checks."""
    sound_ = Sound(profile("default"))
    scenarios = [replace(make_scenario(lane, left, right, targets, horizon=30), sound=sound_)
                 for lane, left, right, targets in (("right", [13], [25], 1), ("right", [12, 16], [24], 2),
                                                    ("left", [14], [20], 1), ("right", [], [], 0))]
    for scenario in scenarios:
        problem = problem_for(scenario, ModelKind.FINAL)
        with bmc.isolated():
            plain = {strategy: solve(problem, None) for strategy, solve in bmc_sound.SOLVERS.items()}
        least = plain[Strategy.OPTIMAL].extra.get("cost")
        cost = tuple(least.values()) if isinstance(least, dict) else (1, 2, 0, 6)
        length = len(plain[Strategy.SHORTEST].actions)
        guesses = [bmc.Expected(n, tuple(max(0, c + d) for c in cost))
                   for n in (0, 1, length - 1, length, length + 1, 30) for d in (-1, 0, 1)]
        guesses += [bmc.Expected(length, tuple(c + (i == j) for j, c in enumerate(cost))) for i in range(len(cost))]
        for guess in guesses:
            with bmc.isolated(), bmc.expecting({problem: guess}):
                for strategy, solve in bmc_sound.SOLVERS.items():
                    found = solve(problem, None)
                    assert _answer(found) == _answer(plain[strategy]), (scenario, guess, strategy)
                    if found.status is Status.PLAN:
                        assert sound.validate(problem, found.actions).states == found.states, (scenario, guess)
        if plain[Strategy.OPTIMAL].status is Status.PLAN:
            with bmc.isolated(), bmc.expecting({problem: bmc.Expected(length, cost)}):
                bmc_sound.shortest(problem, None)
                right = bmc_sound.optimal(problem, None)
            assert right.states_explored <= plain[Strategy.OPTIMAL].states_explored, scenario  # its checks


#: Two scenarios whose answer the paper profile's followers (who keep their speed: ``Conflict.BEHIND``) change
#: (cell length, profile, measured start speed, lane, left, right, targets), as in Spin's pinned ones.
PINNED = ((21.0, "paper", 5.0, "left", (12, 13, 15, 17), (), 0), (21.0, "paper", 5.0, "right", (8, 12, 14, 16),
                                                                   (18, 23), 1))


@pytest.mark.parametrize("case", PINNED, ids=lambda c: f"{c[1]}-{c[0]:g}m-{c[2]:g}mps-{c[3]}")
def test_pinned_scenarios_agree(case: tuple[float, str, float, str, tuple[int, ...], tuple[int, ...], int]) -> None:
    cell_m, name, start_mps, lane, left, right, targets = case
    scenario = make_scenario(lane, list(left), list(right), targets, horizon=30, grid=grid_for(cell_m))
    for strategy in STRATEGIES:
        _agree(replace(scenario, sound=Sound(profile(name), start_mps=start_mps)), strategy)



@pytest.mark.parametrize("name", ["paper", "default"])
def test_measured_intervals_agree(name: str) -> None:
    """What a snapshot measured (``spec.scenario.sensed``): the engine reads each vehicle's interval from it (12 drawn
    scenarios in CI's profile, the first 4 of them by default)."""
    rng, sound_ = random.Random(f"measured-{name}"), Sound(profile(name))
    drawn = 12 if CI_PROFILE else 4
    for scenario in [measured_pinned(sound_),
                     *(measured_like(rng, _draw(rng, PAPER_GRID, sound_)) for _ in range(drawn))]:
        for strategy in STRATEGIES:
            _agree(scenario, strategy)


@pytest.mark.parametrize("latency_s", sorted(AGED_SHORTEST_LENGTH))
def test_z3_plans_for_the_snapshots_age_where_it_decides_the_plan(latency_s: float) -> None:
    """Z3 reads the snapshot's age (``Sound.start_error_m``, the aged phantoms) as the interpreter does: where one
    control step of age (the loop's budget) makes the shortest overtake one action longer, both answer that."""
    check_aged_witness("z3", latency_s)
