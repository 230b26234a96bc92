"""The exact continuous-motion check's vectorised sweep against its one-instant-at-a-time walk (``oracle.reach``)."""

from __future__ import annotations

import itertools
import math
from dataclasses import replace
from unittest import mock

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from ci.conformance.crossval import DRAWN
from ci.conformance.hypo import scenarios
from oracle import reach
from spec.actions import Action
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.scenario import Scenario
from spec.sound import held_vehicle, reach_m, sound_from
from tests.conftest import CI_PROFILE

#: Any scenario of the hypothesis source under drawn bounds (measured speeds, either profile, either semantics),
#: with any short path: plans, and mostly sequences that break the specification somewhere.
drawn = st.tuples(st.booleans().flatmap(lambda commit: scenarios(PAPER_GRID, None, DRAWN, measured=True,
                                                                  profiles=True, commit=commit)),
                  st.lists(st.sampled_from(list(Action)), max_size=6).map(tuple))
#: Every property over drawn cases: more of them in CI.
DRAWN_SETTINGS = settings(max_examples=300 if CI_PROFILE else 60, deadline=None)


def _followers(walk: reach._Walk, times: list[float]) -> list[set[int]]:
    """The vehicles that follow the AV at each sample, accumulated one sample at a time: none while the AV is out of
    the left lane or moving into it; in it, the first ones and every one found certainly behind since."""
    tr, length = walk.sound.tracking, walk.sound.safety.vehicle_length_m
    behind, out = set(walk.first), []
    for t in times:
        lanes, entering = walk.path.occupancy(t)
        if Lane.LEFT not in lanes or entering:
            behind = set()
        else:
            x = walk.path.position(t)
            behind |= {i for i, c in enumerate(walk.cars) if c.lane is Lane.LEFT
                       and reach_m(held_vehicle(c, walk.windows, t), walk.sound.bounds, t)[1] + length
                       <= x - tr.position_m}
        out.append(set(behind))
    return out


@DRAWN_SETTINGS
@given(drawn)
def test_the_sweep_takes_every_instants_followers_and_margins_as_the_walk_does(case: tuple[Scenario,
                                                                                        tuple[Action, ...]]) -> None:
    scenario, actions = case
    walk = reach._Walk(scenario, actions)
    times = walk.path.times(reach.MAX_DT_S)
    swept = reach._Sweep(walk, np.asarray(times))
    for k, (t, behind) in enumerate(zip(times, _followers(walk, times), strict=True)):
        assert swept.behind(k) == behind, f"followers at t = {t}"
        each = walk.worst(t, *walk.path.occupancy(t), behind)[2]
        assert np.allclose(swept.margins[:, k], each, rtol=0.0, atol=1e-9), f"margins at t = {t}"


@DRAWN_SETTINGS
@given(drawn)
def test_the_exact_check_answers_as_its_walk_over_every_instant_and_interval(case: tuple[Scenario,
                                                                                      tuple[Action, ...]]) -> None:
    scenario, actions = case
    found = reach.exact_check(scenario, actions)
    with mock.patch.object(reach, "CLEAR_M", math.inf):  # nothing cleared by the sweep: the walk decides everything
        walked = reach.exact_check(scenario, actions)
    assert (found is None) == (walked is None)
    assert found is None or walked is None or found.describe() == walked.describe()


@DRAWN_SETTINGS
@given(drawn, st.none() | st.floats(0.0, 12.0))
def test_the_reference_speed_is_monotone_between_two_samples(case: tuple[Scenario, tuple[Action, ...]],
                                                             start_mps: float | None) -> None:
    """So a conflict that holds while the reference is slower than a follower may be (``BEHIND``) holds at one end of
    any interval it holds in, where the interval's bound sees it."""
    scenario, actions = case
    assert scenario.sound is not None
    scenario = replace(scenario, sound=replace(scenario.sound, start_mps=start_mps))
    path = reach.scenario_path(scenario, actions)
    times = path.times(reach.MAX_DT_S)
    for t0, t1 in itertools.pairwise(times):
        v0, v1 = path.speed(t0), path.speed(t1)
        for t in (t0 + (t1 - t0) / 3, t0 + 2 * (t1 - t0) / 3):
            assert min(v0, v1) - 1e-9 <= path.speed(t) <= max(v0, v1) + 1e-9, f"between {t0} and {t1}"


@DRAWN_SETTINGS
@given(drawn)
def test_the_samples_cover_the_plan_and_its_continuation_at_most_dt_apart(case: tuple[Scenario,
                                                                                    tuple[Action, ...]]) -> None:
    scenario, actions = case
    path = reach.scenario_path(scenario, actions)
    times = path.times(reach.MAX_DT_S)
    assert times[0] == 0.0 and times[-1] >= path.end_s + reach.CONTINUATION_S
    assert max(b - a for a, b in itertools.pairwise(times)) <= reach.MAX_DT_S + 1e-12


def test_an_oncoming_vehicle_already_behind_adds_no_time_and_takes_none_away() -> None:
    """Oncoming vehicles that have all passed the AV leave the right lane's continuation at its least, not less."""
    sound = sound_from(None, "default")
    path = reach.Path((Action.RIGHT_LANE_CHANGE,), sound, PAPER_GRID, Lane.LEFT, oncoming_far_m=-189.0)
    assert path.continuation_s == reach.CONTINUATION_S
