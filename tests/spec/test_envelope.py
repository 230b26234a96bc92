"""The AV's envelope: its reference is the executor's (``spec.motion``), and centred ramps never overlap."""

from __future__ import annotations

import itertools
from dataclasses import replace

import pytest
from hypothesis import given
from hypothesis import strategies as st

from spec.actions import ACTION_RULES, Action
from spec.assumptions import profile
from spec.envelope import MINIMAL_RISK, TRACKING, Reference
from spec.grid import PAPER_GRID, STANDARD_CELLS_M, Grid
from spec.lanes import Lane
from spec.motion import action_speed_mps, plan_profiles, ramp_s
from spec.physical import CAR
from spec.safety import SAFETY
from spec.sound import Sound, SoundRules, SoundState

SPEEDS = sorted({action_speed_mps(a, PAPER_GRID) for a in Action})


def _half(v_from: float, v_to: float) -> float:
    return ramp_s(v_from, v_to) / 2 if v_from != v_to else 0.0


@pytest.mark.parametrize("before,middle,after", list(itertools.product(Action, repeat=3)))
def test_centred_ramps_never_overlap_within_an_action(before: Action, middle: Action, after: Action) -> None:
    """The ramp into an action ends before the ramp out of it starts: a step's window has one centred ramp."""
    v0, v1, v2 = (action_speed_mps(a, PAPER_GRID) for a in (before, middle, after))
    assert _half(v0, v1) + _half(v1, v2) <= float(ACTION_RULES[middle].duration_s)


@pytest.mark.parametrize("before,after", list(itertools.product(Action, repeat=2)))
def test_a_ramp_after_a_lane_change_is_checked_in_both_lanes_while_the_move_runs(before: Action, after: Action) -> None:
    """The half ramp before a boundary can start while the previous action's sideways move still runs (a lane change
    then accelerate: 1.30 s of ramp, 1 s left of the action after its 2 s move): that stretch is a both-lanes
    segment of the step's window, entering the left lane when the move does."""
    grid = PAPER_GRID
    rules = SoundRules(Sound(profile("default")), Lane.RIGHT, (), (), grid, ())
    state = rules.after(rules.after(SoundState(Lane.RIGHT, 0, 0, 0, 0, None, None), Action.DRIVE), before)
    segments = rules._segments(state.lane, rules.reference(state, after), after, state.moved)
    v0, v1 = action_speed_mps(before, grid), action_speed_mps(after, grid)
    boundary = state.t_units * float(grid.time_unit_s)
    move_end = boundary - float(ACTION_RULES[before].duration_s) + TRACKING.lateral_s
    early = [s for s in segments if s.t1_s <= boundary]
    assert sum(s.t1_s - s.t0_s for s in early) == pytest.approx(_half(v0, v1))
    both = [s for s in early if len(s.lanes) == 2]
    if ACTION_RULES[before].changes_lane and boundary - _half(v0, v1) < move_end:
        assert both and both[0].t1_s == pytest.approx(move_end)
        assert both[0].entering_left is (ACTION_RULES[before].to_lane is Lane.LEFT)
    else:
        assert not both


@given(st.lists(st.sampled_from(list(Action)), min_size=1, max_size=8), st.sampled_from(STANDARD_CELLS_M),
       st.floats(0.0, 20.0))
def test_reference_is_the_executors_speed_profile(actions: list[Action], cell_m: object, start_mps: float) -> None:
    """From every boundary, the envelope's reference is where ``spec.motion.plan_profiles`` (the executor's rule)
    puts the AV, up to where the ramp out of the action starts (the next step's window covers the rest)."""
    grid = Grid(cell_m)  # type: ignore[arg-type]
    rules = SoundRules(Sound(profile("default"), start_mps=start_mps), Lane.LEFT, (), (), grid, ())
    profiles = plan_profiles(tuple(actions), start_mps, grid)
    state = SoundState(Lane.LEFT, 0, 0, 0, 0, None, None)
    for k, action in enumerate(actions):
        ref: Reference = rules.reference(state, action)
        duration = float(ACTION_RULES[action].duration_s)
        nxt = actions[k + 1] if k + 1 < len(actions) else None
        v_here = action_speed_mps(action, grid)
        stop = duration - (_half(v_here, action_speed_mps(nxt, grid)) if nxt is not None else duration / 2)
        for i in range(21):
            s = stop * i / 20
            t = ref.boundary_s + s
            assert ref.position_m(t) == pytest.approx(profiles[k].distance_m(s), abs=1e-6)
            assert ref.speed_mps(t) == pytest.approx(profiles[k].at(s), abs=1e-9)
        state = rules.after(state, action)  # guards are not the envelope's business


def test_minimal_risk_brakes_to_the_slowest_vehicle_ahead() -> None:
    """The hold speed is the slowest same-direction speed (the envelope's position bound covers the car's speed
    error), never above the speed the AV has, never below a standstill; only a reference that ends faster than the
    slowest vehicle ahead closes in; the ramp brakes at the stated deceleration."""
    assert MINIMAL_RISK.hold_mps(14.0, 4.9) == 4.9
    assert MINIMAL_RISK.hold_mps(3.0, 4.9) == 3.0
    assert MINIMAL_RISK.hold_mps(7.0, 0.0) == 0.0
    assert not MINIMAL_RISK.closes_in(MINIMAL_RISK.hold_mps(14.0, 4.9), 4.9)
    assert not MINIMAL_RISK.closes_in(4.9 + 1e-12, 4.9)  # a rounding above is the same speed
    assert MINIMAL_RISK.closes_in(4.95, 4.9)
    ramp = MINIMAL_RISK.ramp(10.0, 14.0, 3.4)
    assert ramp is not None and ramp.start_s == 10.0
    assert ramp.dv_mps / ramp.duration_s == pytest.approx(-MINIMAL_RISK.decel_mps2)
    assert MINIMAL_RISK.ramp(0.0, 3.0, 3.0) is None


def test_a_slot_between_two_vehicles_is_a_car_and_a_least_gap_each_side_of_the_av() -> None:
    """Centres ``beside_m`` from the AV's on both sides leave a slot; a millimetre less does not."""
    both = 2 * (CAR.length_m + SAFETY.min_gap_m)
    assert MINIMAL_RISK.leaves_slot(both) and MINIMAL_RISK.leaves_slot(both + 30.0)
    assert not MINIMAL_RISK.leaves_slot(both - 0.001) and not MINIMAL_RISK.leaves_slot(-both)


def test_the_fallback_brakes_for_the_closing_speed_it_measured_and_comes_back_up_to_the_hold_speed() -> None:
    """Measured closing speeds count within [0, the AV's speed]; not measured, the vehicle ahead may stand (the
    AV's whole speed); the fallback's hold speed is the slowest speed ahead itself, from below as from above."""
    assert MINIMAL_RISK.fallback_closing_mps(7.0, None) == 7.0
    assert MINIMAL_RISK.fallback_closing_mps(7.0, 0.3) == 0.3
    assert MINIMAL_RISK.fallback_closing_mps(7.0, -2.0) == 0.0  # moving away: nothing to brake for
    assert MINIMAL_RISK.fallback_closing_mps(7.0, 9.0) == 7.0  # more than the AV's speed: a reading jumped
    assert MINIMAL_RISK.fallback_hold_mps(7.0) == 7.0 and MINIMAL_RISK.hold_mps(6.2, 7.0) == 6.2
    assert 0 < MINIMAL_RISK.accel_mps2 < MINIMAL_RISK.emergency_decel_mps2


def test_a_returns_predicted_gap_takes_the_cars_envelope_and_a_measured_gap_is_taken_as_it_is() -> None:
    """Seed 7 of the paper's world (km 21.8): 29.9 m ahead closing at 6.6 m/s, a 3 s return ends inside the
    specification for a car exactly on its reference, not for one within its stated envelope."""
    mr = MINIMAL_RISK
    assert not SAFETY.violated(29.92 - 6.59 * 3.0, 6.59)  # what the return's check said before
    assert mr.too_near_after(29.92, 6.59, 3.0)
    exact = replace(TRACKING, position_m=0.0, speed_mps=0.0)
    assert not mr.too_near_after(29.92, 6.59, 3.0, exact)
    for gap_m, closing_mps in ((10.0, 7.0), (10.6, 7.0), (2.5, -1.0), (1.9, -1.0)):  # now: the gap as measured
        assert mr.too_near_after(gap_m, closing_mps, 0.0) == SAFETY.violated(gap_m, closing_mps)
    # the envelope is the car's, once: a longer prediction closes only by the reference's closing speed
    margin_m = SAFETY.required_gap_m(7.0 + TRACKING.speed_mps) + TRACKING.position_m
    assert not mr.too_near_after(margin_m + 7.0 * 5.0 + 0.01, 7.0, 5.0)
    assert mr.too_near_after(margin_m + 7.0 * 5.0 - 0.01, 7.0, 5.0)


def test_the_emergency_brake_cancels_every_closing_speed_the_car_can_have_before_contact() -> None:
    """The fallback brakes at the car's limit only once the gap ahead breaks the specification, and a sweep and a
    control step late: from there, at every closing speed up to the fastest the car may have on a standing vehicle,
    the gap left exceeds what braking closes (stepped here, not from the closed form), and the stated bound is where
    that ends."""
    mr = MINIMAL_RISK
    fastest = mr.fastest_closing_mps()
    assert fastest == 2 * 7.0 + TRACKING.speed_mps and mr.reaction_s == pytest.approx(0.1 + 1 / 30)
    assert fastest < mr.emergency_cancels_mps()
    dt_s = 1e-3

    def left_at_stop_m(closing_mps: float) -> float:
        gap_m = SAFETY.required_gap_m(closing_mps) - closing_mps * mr.reaction_s
        while closing_mps > 0.0:
            closing_mps = max(0.0, closing_mps - mr.emergency_decel_mps2 * dt_s)
            gap_m -= closing_mps * dt_s
        return gap_m

    for k in range(1, 157):
        assert left_at_stop_m(k * fastest / 156) > 0.0
    bound = mr.emergency_cancels_mps()
    assert left_at_stop_m(bound - 0.05) > 0.0 > left_at_stop_m(bound + 0.05)
