"""The sound model with each vehicle's own measured speed (``Scenario.left_mps``, ``spec.dynamics``): every plan, and
every committed part with its escape, survives every motion that keeps to each vehicle's own interval and
acceleration bounds, braking to a standstill at any instant included; the lane-wide model's plans and the paper's do
not; a vehicle standing ahead is planned for (a committed step and its escape, or the minimal-risk manoeuvre proved
from the start), never left to the fallback."""

from __future__ import annotations

import random
from collections.abc import Callable
from dataclasses import replace

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ci.conformance.hypo import with_speeds
from oracle import commit, reach
from oracle.planner import plan
from spec.actions import Action
from spec.answers import Status, Strategy
from spec.cells import left_extent_m
from spec.dynamics import Overtaken
from spec.escapes import COMMIT
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.models import ModelKind
from spec.physical import LOOP
from spec.safety import Conflict
from spec.scenario import Scenario, make_scenario, measured_speeds, problem_for, sensed
from spec.sound import sound_from
from tests.conftest import CI_PROFILE
from tests.oracle.test_commit import _check as check_committed
from tests.oracle.test_sound import _check as check_whole
from tests.oracle.test_sound import sound_scenarios


@st.composite
def measured_scenarios(draw: st.DrawFn) -> Scenario:
    """A sound scenario on a standard grid whose same-direction vehicles' speeds were measured, and, half the time,
    the oncoming ones' too (the crossval source's ``with_speeds``)."""
    scenario = draw(st.sampled_from(STANDARD_CELLS_M).flatmap(lambda c: sound_scenarios(Grid(c))))
    return draw(with_speeds(scenario))


@settings(max_examples=100 if CI_PROFILE else 25)
@given(measured_scenarios(), st.sampled_from(list(Strategy)), st.booleans(), st.integers(0, 2**32 - 1),
       st.sampled_from(list(Overtaken)))
def test_every_answer_with_measured_speeds_survives_every_motion_that_may_brake_to_a_standstill(
        scenario: Scenario, strategy: Strategy, committed: bool, seed: int, overtaken: Overtaken) -> None:
    """Under either profile of vehicles overtaken (``no-acceleration``: the motions do not speed up while the AV is
    in the passing lane, ``oracle.reach``)."""
    assert scenario.sound is not None
    scenario = replace(scenario, sound=replace(scenario.sound, overtaken=overtaken))
    if committed:
        check_committed(replace(scenario, sound=replace(scenario.sound, commitment=COMMIT)), strategy, 4,
                        random.Random(seed))
    else:
        check_whole(scenario, strategy, 4, random.Random(seed))


def _standing_ahead(cell: int, start_mps: float | None = None) -> Scenario:
    """The AV in the left lane at the default bounds, one vehicle standing in its lane at ``cell`` (21 m cells)."""
    scenario = measured_speeds(make_scenario("left", [cell], [], 1, cell_m=21), [(0.0, 0.0)])
    return replace(scenario, sound=replace(sound_from(None, "default"), start_mps=start_mps))


@pytest.mark.parametrize("cell", [14, 16])
def test_the_lane_wide_models_and_the_papers_plans_break_against_a_vehicle_standing_ahead(cell: int) -> None:
    """Planned as if the vehicle ahead drove at its lane's slowest (4.9 m/s) or at the common speed, the AV closes in
    on it faster than the specification allows once it stands: the standstill corners find it."""
    standing = _standing_ahead(cell)
    lane_wide = replace(standing, left_mps=None)
    answer = plan(lane_wide, Strategy.SENSIBLE)
    assert answer.status is Status.PLAN and answer.commit is not None
    assert reach.exact_check(lane_wide, answer.actions) is None
    assert reach.exact_check(standing, answer.actions) is not None
    paper = plan(make_scenario("left", [cell], [], 1, cell_m=21), Strategy.SENSIBLE)
    assert paper.status is Status.PLAN
    found = reach.exact_check(standing, paper.actions)
    assert found is not None and found.vehicle.startswith("left_lane[0]")


@pytest.mark.parametrize("start_mps", [None, 3.5, 12.0])
@pytest.mark.parametrize("cell", range(11, 19))
def test_a_vehicle_standing_ahead_is_planned_for(cell: int, start_mps: float | None) -> None:
    """From every start that does not already break the specification: a committed step with its escape that
    survives the standstill, or no committed step with the minimal-risk manoeuvre (braking to a stop behind it)
    proved from the start; a start too near is an answer of its own."""
    scenario = _standing_ahead(cell, start_mps)
    problem = problem_for(scenario, ModelKind.FINAL)
    rules, first = commit._sound_rules(problem), commit.start(problem)
    answer = plan(scenario, Strategy.SENSIBLE)
    if rules.start_violation(first) is not None:
        assert answer.status is Status.UNSAFE_START
        return
    assert rules.continuation_violation(first) is None  # the minimal-risk manoeuvre: a stop behind it
    assert reach.exact_check(scenario, ()) is None
    assert answer.status in (Status.PLAN, Status.NO_PLAN)
    if answer.status is Status.PLAN:
        assert check_committed(scenario, Strategy.SENSIBLE, 8, random.Random(cell)) > 0


def _least_accepted_m(scenario_at: Callable[[float], Scenario], lo_m: float, hi_m: float) -> float:
    """The nearest reading of the vehicle (bisected within ``lo_m .. hi_m``) from which the model proves the start
    and its minimal-risk manoeuvre (the empty answer)."""
    def accepted(dx_m: float) -> bool:
        problem = problem_for(scenario_at(dx_m), ModelKind.FINAL)
        rules, first = commit._sound_rules(problem), commit.start(problem)
        return rules.start_violation(first) is None and rules.continuation_violation(first) is None

    assert accepted(hi_m)
    for _ in range(50):
        mid = (lo_m + hi_m) / 2
        lo_m, hi_m = (lo_m, mid) if accepted(mid) else (mid, hi_m)
    return hi_m + 1e-6


@pytest.mark.parametrize("latency_s", [0.0, LOOP.plan_budget_s])
def test_a_vehicle_still_braking_when_the_av_stands_is_held_to_its_gap_until_it_stands_too(latency_s: float) -> None:
    """The AV at 1.08 m/s stops within 0.2 s; a vehicle ahead at 2.3 m/s brakes for 0.26 s: the closing speed on it
    rises to the AV's speed error after the AV stands, and the gap must hold it (found by review: the model checked
    the manoeuvre only to the AV's stop, and accepted a start the exact check breaks 0.06 m short). One control step
    of age later (the loop's budget) the vehicle may have slowed by b x the age before the plan starts: the motions
    age its speed themselves (``oracle.reach``)."""
    def at(dx_m: float) -> Scenario:
        base = sensed(make_scenario("left", [11], [], 1, cell_m=21), [(dx_m, dx_m)])
        sound = replace(sound_from(None, "default", latency_s=latency_s), start_mps=1.08)
        return replace(measured_speeds(base, [(2.3, 2.3)]), sound=sound)

    lo_m, hi_m = left_extent_m(11, Lane.LEFT, PAPER_GRID)
    least_m = _least_accepted_m(at, lo_m, hi_m)
    nearest = at(least_m)
    assert reach.exact_check(nearest, ()) is None
    # a millimetre nearer, the exact check breaks it (ahead, as the vehicle still brakes): the model is that tight
    short = reach.exact_check(at(least_m - 0.001), ())
    assert short is not None and short.conflict is Conflict.AHEAD
    assert all(reach.run_motion(nearest, (), m) is None for m in reach.motions(nearest, (), random.Random(3), 8))


def test_a_measured_follower_faster_than_its_lanes_top_is_held_behind() -> None:
    """Where followers keep their speed (the paper's profile, 7 m/s), one measured at 10 m/s 12 m behind the AV
    closes in while the AV drives 7 m/s: every step in its lane is refused for it, and the checks break a plan that
    ignored it (found by review: BEHIND bound only below the lane's top speed)."""
    base = measured_speeds(sensed(make_scenario("left", [9], [], 0, cell_m=21), [(-12.0, -12.0)]), [(10.0, 10.0)])
    scenario = replace(base, sound=sound_from(None, "paper", phantoms=False))
    problem = problem_for(scenario, ModelKind.FINAL)
    rules, first = commit._sound_rules(problem), commit.start(problem)
    for action in (Action.DRIVE, Action.RIGHT_LANE_CHANGE, Action.ACCELERATE):
        found = rules.step_violation(first, action)
        assert found is not None and found.conflict is Conflict.BEHIND, action
    assert reach.exact_check(scenario, (Action.DRIVE, Action.RIGHT_LANE_CHANGE)) is not None


def _overtaking(overtaken: Overtaken) -> Scenario:
    """The AV in the passing lane beside a vehicle measured at 3.5..6.5 m/s (its target, cell 10), another at 5..8
    m/s ahead (cell 18), an oncoming one at cell 19 (21 m cells, default bounds)."""
    base = measured_speeds(make_scenario("right", [10, 18], [19], 1, cell_m=21), [(3.5, 6.5), (5.0, 8.0)])
    return replace(base, sound=sound_from(None, "default", overtaken=overtaken.value))


def test_the_no_acceleration_profile_returns_ahead_of_a_vehicle_that_could_speed_up_under_physics() -> None:
    """Under ``no-acceleration`` the AV completes the pass (drive, accelerate, back into the left lane): every motion
    that does not speed up while the AV is out survives it. Under ``physics`` the model finds no plan, and the same
    actions break: the target speeding up at a_max while the AV passes it is where the AV cuts in."""
    held = _overtaking(Overtaken.NO_ACCELERATION)
    answer = plan(held, Strategy.SENSIBLE)
    assert answer.status is Status.PLAN
    actions = answer.actions
    assert actions == (Action.DRIVE, Action.ACCELERATE, Action.LEFT_LANE_CHANGE)
    assert reach.exact_check(held, actions) is None
    assert all(reach.run_motion(held, actions, m) is None for m in reach.motions(held, actions, random.Random(5), 30))
    physics = _overtaking(Overtaken.PHYSICS)
    assert plan(physics, Strategy.SENSIBLE).status is Status.NO_PLAN
    breach = reach.exact_check(physics, actions)
    assert breach is not None and breach.conflict is Conflict.CUT_IN and breach.vehicle.startswith("left_lane[0]")
    corners = reach.motions(physics, actions, random.Random(5), 0)
    fastest = next(m for m in corners if "fastest, readings high" in m.name)
    assert reach.run_motion(physics, actions, fastest) is not None



def test_the_exact_checks_bound_on_the_avs_acceleration_adds_up_ramps_under_way_together() -> None:
    """Measured at 22 m/s, the AV brakes to the common 7 m/s over 2.78 s, and the ramp into ``brake`` starts at 2.68 s:
    for 0.1 s both brake at 5.4 m/s^2, 10.8 together; the check's bound between samples takes their sum (found by
    review: it took the steepest single ramp)."""
    path = reach.Path((Action.DRIVE, Action.BRAKE), replace(sound_from(None, "default"), start_mps=22.0), PAPER_GRID,
                      Lane.LEFT)
    assert path.max_accel == pytest.approx(10.8)
    assert path.rates(2.7, 2.75)[1] == pytest.approx(10.8)
    assert path.rates(1.0, 1.1)[1] == pytest.approx(5.4)
