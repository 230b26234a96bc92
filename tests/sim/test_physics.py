"""The AV's dynamics, its controllers, and contact detection, in a real PyBullet world."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from sim.driver.control import Sideways
from sim.executor import Executor
from sim.scene import Scene
from sim.vehicle import KinematicCar, WheeledCar, first_contact
from spec.actions import ACTION_RULES, Action
from spec.envelope import MINIMAL_RISK, TRACKING
from spec.errors import EngineError
from spec.faults import lost_control
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.motion import (
    RAMP_SHARE,
    SpeedProfile,
    action_speed_mps,
    plan_profiles,
    ramp_gain_m,
    ramp_s,
    reference_offset_m,
)
from spec.physical import CAR, LOOP, ROAD
from spec.safety import SAFETY

COMMON_MPS = PAPER_GRID.speed  # the common speed of the paper's grid


def no_traffic(_dt: float) -> bool:
    return True


@pytest.fixture
def world():
    scene = Scene()
    car = WheeledCar(scene, 0.0, scene.lane_y(Lane.LEFT))
    yield scene, car, Executor(scene, car, Lane.LEFT, PAPER_GRID)
    scene.close()


def settle(executor: Executor, speed_mps: float) -> None:
    """Reach ``speed_mps`` from rest and stay there: the position reference restarts once the speed is reached."""
    executor.hold(8.0, speed_mps, no_traffic)
    executor.reset_reference()
    executor.hold(6.0, speed_mps, no_traffic)
    executor.reset_reference()


def speeds_while(scene: Scene, car: WheeledCar, target_mps: float, seconds: float) -> np.ndarray:
    out = []
    for _ in range(round(seconds / scene.dt_s)):
        car.command(target_mps, 0.0, scene.dt_s)
        scene.step()
        out.append(car.pose().speed_mps)
    return np.array(out)


def test_acceleration_and_braking_stay_within_their_limits(world) -> None:
    scene, car, _ = world
    up = speeds_while(scene, car, 2 * COMMON_MPS, 6.0)
    down = speeds_while(scene, car, 0.0, 4.0)
    window = round(0.5 / scene.dt_s)  # rates over half a second, so contact jitter does not count
    rate = lambda v: np.diff(v[::window]) / 0.5  # noqa: E731
    assert rate(up).max() <= CAR.max_accel_mps2 * 1.05
    assert -rate(down).min() <= CAR.max_brake_mps2 * 1.05
    assert up[-1] == pytest.approx(2 * COMMON_MPS, abs=0.3) and down[-1] < 0.2


def test_lane_keeping_holds_the_lane_centre(world) -> None:
    scene, car, executor = world
    assert executor.hold(12.0, COMMON_MPS, no_traffic)
    pose = car.pose()
    assert abs(pose.y_m - scene.lane_y(Lane.LEFT)) < 0.15 and abs(pose.yaw_rad) < 0.05


@pytest.mark.parametrize("action", [Action.DRIVE, Action.ACCELERATE, Action.BRAKE])
def test_each_speed_controller_realises_its_mapping_once_at_speed(world, action: Action) -> None:
    _scene, car, executor = world
    rule = ACTION_RULES[action]
    target = float(rule.speed_factor) * COMMON_MPS
    settle(executor, target)  # already at the action's speed: the mapping is exact
    assert car.pose().speed_mps == pytest.approx(target, abs=0.1)
    start = car.pose().x_m
    assert executor.run(action, no_traffic)
    expected_m = target * rule.duration_s
    assert car.pose().x_m - start == pytest.approx(expected_m, rel=0.08)


def test_accelerating_from_the_common_speed_falls_short_of_the_model(world) -> None:
    """The grid's accelerate needs 42 m in 3 s from 7 m/s; with 3 m/s^2 at most 34.5 m are possible."""
    _scene, car, executor = world
    settle(executor, COMMON_MPS)
    assert car.pose().speed_mps == pytest.approx(COMMON_MPS, abs=0.1)
    start = car.pose().x_m
    executor.run(Action.ACCELERATE, no_traffic)
    covered = car.pose().x_m - start
    assert 30.0 < covered <= COMMON_MPS * 3 + 0.5 * CAR.max_accel_mps2 * 9 + 1.0


@pytest.mark.parametrize(("action", "to_lane"), [(Action.RIGHT_LANE_CHANGE, Lane.RIGHT)])
def test_lane_change_moves_one_lane_width_in_the_actions_time(world, action: Action, to_lane: Lane) -> None:
    scene, car, executor = world
    executor.hold(4.0, COMMON_MPS, no_traffic)
    assert executor.run(action, no_traffic)
    assert abs(car.pose().y_m - scene.lane_y(to_lane)) < 0.4 and executor.lane is to_lane
    assert executor.run(Action.LEFT_LANE_CHANGE, no_traffic)
    assert abs(car.pose().y_m - scene.lane_y(Lane.LEFT)) < 0.4


def test_a_staged_crash_is_detected_as_a_contact(world) -> None:
    scene, car, executor = world
    parked = KinematicCar(scene, 25.0, scene.lane_y(Lane.LEFT), 0.0)

    def contact(_dt: float) -> bool:
        return not scene.client.getContactPoints(car.body, parked.body)

    assert not executor.hold(12.0, COMMON_MPS, contact)


def feasible(speeds: list[float], dt: float) -> bool:
    """Every speed change within the car's acceleration (up) or braking (down) limit."""
    return all(-CAR.max_brake_mps2 * dt * 1.001 <= b - a <= CAR.max_accel_mps2 * dt * 1.001
               for a, b in itertools.pairwise(speeds))


@pytest.mark.parametrize(("start_mps", "plan"), [(3.5, (Action.ACCELERATE, Action.DRIVE)),
                                                 (14.0, (Action.BRAKE, Action.ACCELERATE)),
                                                 (10.5, (Action.DRIVE, Action.ACCELERATE))])
def test_a_plans_first_ramp_starts_at_the_cars_speed_and_stays_feasible(start_mps: float,
                                                                       plan: tuple[Action, ...]) -> None:
    dt = 0.01
    profiles = plan_profiles(plan, start_mps, PAPER_GRID)
    speeds = [p.at(i * dt) for a, p in zip(plan, profiles) for i in range(round(ACTION_RULES[a].duration_s / dt))]
    assert speeds[0] == pytest.approx(start_mps) and feasible(speeds, dt)


def test_ramp_gain_is_what_a_ramp_gains_or_loses_on_a_car_at_the_target_speed() -> None:
    assert ramp_gain_m(COMMON_MPS, COMMON_MPS) == 0.0
    assert ramp_gain_m(14.0, 7.0) == pytest.approx(7.0**2 / (2 * RAMP_SHARE * CAR.max_brake_mps2))
    assert ramp_gain_m(7.0, 14.0) == pytest.approx(-(7.0**2) / (2 * RAMP_SHARE * CAR.max_accel_mps2))
    profile = plan_profiles((Action.ACCELERATE,), 7.0, PAPER_GRID)[0]  # a plan's first ramp starts at the car's speed
    dt, duration_s = 0.001, float(ACTION_RULES[Action.ACCELERATE].duration_s)
    covered_m = sum(profile.at(i * dt) for i in range(round(duration_s / dt))) * dt
    assert covered_m == pytest.approx(14.0 * duration_s + ramp_gain_m(7.0, 14.0)
                                      - ramp_gain_m(14.0, 7.0) / 4, abs=0.05)  # - half the centred ramp out
    speeds = [profile.at(i * dt) for i in range(round(duration_s / dt))]
    assert max(abs(b - a) for a, b in itertools.pairwise(speeds)) < 0.01  # continuous where the ramps overlap


@pytest.mark.parametrize("plan", [(Action.DRIVE, Action.ACCELERATE, Action.ACCELERATE, Action.DRIVE),
                                  (Action.DRIVE, Action.ACCELERATE, Action.BRAKE, Action.ACCELERATE),
                                  (Action.DRIVE, Action.BRAKE, Action.DRIVE, Action.BRAKE)])
def test_centred_ramps_put_the_reference_where_the_model_is_at_every_boundary(plan: tuple[Action, ...]) -> None:
    """Each speed change inside a plan is a feasible ramp centred on its boundary, so at every boundary the
    reference is off the model by at most one half ramp's area (dv * ramp / 8), and the offsets do not add up."""
    dt = 0.01
    speeds_mps = [action_speed_mps(a, PAPER_GRID) for a in plan]
    bound_m = max(abs(b - a) * ramp_s(a, b) / 8 for a, b in zip(speeds_mps, [*speeds_mps[1:], COMMON_MPS]))
    model_m = reference_m = 0.0
    for action, profile in zip(plan, plan_profiles(plan, COMMON_MPS, PAPER_GRID)):
        duration_s = float(ACTION_RULES[action].duration_s)
        speeds = [profile.at(i * dt) for i in range(round(duration_s / dt))]
        assert feasible(speeds, dt)
        reference_m += sum(speeds) * dt
        model_m += action_speed_mps(action, PAPER_GRID) * duration_s
        assert abs(reference_m - model_m) <= bound_m + 0.05


def test_the_lateral_move_of_a_lane_change_is_done_early(world) -> None:
    """The model puts the AV in its new lane before any oncoming tick: the car is there well before the end."""
    scene, car, executor = world
    executor.hold(4.0, COMMON_MPS, no_traffic)
    ys: list[float] = []

    def record(_dt: float) -> bool:
        ys.append(car.pose().y_m)
        return True

    assert executor.run(Action.RIGHT_LANE_CHANGE, record)
    past_centre = next(i for i, y in enumerate(ys) if y < 0) * executor.dt_s
    assert past_centre <= LOOP.lane_change_lateral_s * 0.75  # out of its old lane by 3/4 of the lateral time
    assert abs(ys[-1] - scene.lane_y(Lane.RIGHT)) < 0.3


@pytest.mark.parametrize("start_mps", [3.5, 14.0])
@pytest.mark.parametrize("share", [0.2, 1.0])
@pytest.mark.parametrize("action", [Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE])
def test_a_sideways_move_cut_short_goes_back_wholly_into_the_lane_it_started_in(world, start_mps: float,
                                                                               share: float,
                                                                               action: Action) -> None:
    """``MinimalRisk``'s cut-short move, up to ``reverse_within_s`` into the move, at a speed held throughout: the car
    goes back on a cosine of the time the move had taken, the action ends there with the AV in the lane it started in,
    its centre never left that lane, its body is wholly in it from the move back's end on (containment's check of the
    AV asks that), and it is within 0.2 m of the lane's centre 3 s later."""
    scene, car, executor = world
    if action is Action.LEFT_LANE_CHANGE:
        executor.hold(1.0, COMMON_MPS, no_traffic)
        assert executor.run(Action.RIGHT_LANE_CHANGE, no_traffic)
    settle(executor, start_mps)
    start_lane, centre = executor.lane, scene.lane_y(executor.lane)
    done_s = share * MINIMAL_RISK.reverse_within_s
    asked: list[tuple[Lane, float, float]] = []
    ys: list[float] = []

    def record(_dt: float) -> bool:
        ys.append(car.pose().y_m)
        return True

    def reverse(to_lane: Lane, done: float, left: float) -> bool:
        asked.append((to_lane, done, left))
        return done >= done_s - 1e-9

    assert executor.run(action, record, SpeedProfile(start_mps, ()), reverse=reverse)
    moved = len(ys)
    assert moved == 2 * round(done_s / executor.dt_s)  # the move, then as long back
    assert all(to is ACTION_RULES[action].to_lane for to, _, _ in asked)
    assert all(abs(d + left - LOOP.lane_change_lateral_s) < 1e-9 for _, d, left in asked)
    assert executor.lane is start_lane and executor.lane_due is start_lane
    executor.hold(3.0, start_mps, record)
    assert all(Executor.lane_of(y) is start_lane for y in ys)
    assert all(abs(y - centre) <= (ROAD.lane_width_m - CAR.width_m) / 2 for y in ys[moved - 1:])
    assert abs(ys[-1] - centre) < 0.2


@pytest.mark.parametrize("start_mps", [3.5, 7.0, 10.5])
@pytest.mark.parametrize("action", [Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE])
def test_a_lane_change_from_any_speed_keeps_the_car_within_its_envelope(world, start_mps: float,
                                                                         action: Action) -> None:
    """Turned sideways the car drives faster along its heading, so its speed along the road, which the reference
    is, keeps to it: from a slow queue a lane change's 2 s sideways move turns the car by up to about 35 degrees. The
    car speeds up to the action's speed meanwhile, and it stays on the road and ends wholly in its new lane (the
    steering takes off the sideways part of its speeding up: without that, from 3.5 m/s into the left lane, it ran
    1.75 m past the lane's centre, to the road's edge)."""
    scene, car, executor = world
    if action is Action.LEFT_LANE_CHANGE:
        executor.hold(1.0, COMMON_MPS, no_traffic)
        assert executor.run(Action.RIGHT_LANE_CHANGE, no_traffic)
    settle(executor, start_mps)
    errors: list[tuple[float, float]] = []
    sideways: list[float] = []  # off the new lane's centre, once the move is over
    centre = scene.lane_y(ACTION_RULES[action].to_lane or executor.lane)

    def record(_dt: float) -> bool:
        pose = car.pose()
        errors.append((abs(pose.x_m - executor.x_ref_m), abs(pose.along_mps - executor.v_ref_mps)))
        assert lost_control(pose.y_m, pose.yaw_rad) is None
        if executor.lane_due is not None:
            sideways.append(abs(pose.y_m - centre))
        return True

    profile = plan_profiles((action,), start_mps, PAPER_GRID, to_common=False)[0]
    assert executor.run(action, record, profile)
    assert executor.run(Action.DRIVE, record)
    assert max(e for e, _ in errors) <= TRACKING.position_m
    assert max(e for _, e in errors) <= TRACKING.speed_mps
    assert sideways and max(sideways) <= (ROAD.lane_width_m - CAR.width_m) / 2  # the body wholly in its new lane


@pytest.mark.parametrize(("speed_mps", "frame_mps", "plan"), [
    (7.0, 14.0, (Action.ACCELERATE, Action.ACCELERATE, Action.DRIVE)),  # the plan's own frame
    (7.0, 7.0, (Action.ACCELERATE, Action.DRIVE, Action.DRIVE)),  # made in the common-speed frame instead
    (14.0, 7.0, (Action.BRAKE, Action.DRIVE)),
    (3.5, 7.0, (Action.ACCELERATE, Action.ACCELERATE, Action.DRIVE)),
])
def test_the_reference_follows_the_frames_av_once_the_first_ramp_is_done(speed_mps: float, frame_mps: float,
                                                                       plan: tuple[Action, ...]) -> None:
    """The model's AV starts at the frame's offset and moves at each action's speed; the reference starts at the
    car's speed, from reference_offset_m, and meets it at every boundary after the first ramp (to within half
    a centred ramp's area)."""
    dt = 0.001
    speeds_mps = [action_speed_mps(a, PAPER_GRID) for a in plan]
    bound_m = max(abs(b - a) * ramp_s(a, b) / 8 for a, b in zip(speeds_mps, [*speeds_mps[1:], COMMON_MPS]))
    reference_m = reference_offset_m(speed_mps, frame_mps, speeds_mps[0])
    model_m = ramp_gain_m(speed_mps, frame_mps)
    elapsed_s, first_ramp_s = 0.0, ramp_s(speed_mps, speeds_mps[0])
    for action, profile in zip(plan, plan_profiles(plan, speed_mps, PAPER_GRID)):
        duration_s = float(ACTION_RULES[action].duration_s)
        reference_m += sum(profile.at(i * dt) for i in range(round(duration_s / dt))) * dt
        model_m += action_speed_mps(action, PAPER_GRID) * duration_s
        elapsed_s += duration_s
        if elapsed_s >= first_ramp_s:
            assert abs(reference_m - model_m) <= bound_m + 0.05
    assert plan_profiles(plan, speed_mps, PAPER_GRID)[0].at(0.0) == pytest.approx(speed_mps)


def test_an_action_whose_lane_guard_fails_is_an_error_not_a_straight_drive(world) -> None:
    _scene, _car, executor = world
    with pytest.raises(EngineError, match="left_lane_change asked of an AV in the left lane"):
        executor.run(Action.LEFT_LANE_CHANGE, no_traffic)


def test_the_emergency_brake_from_the_trigger_gap_stops_short_of_a_standing_vehicle_at_the_fastest_closing_speed(
        world) -> None:
    """``MinimalRisk.emergency_cancels_mps`` in physics: the car as fast as it goes (asked for the fastest
    closing speed it may have, ``fastest_closing_mps``) meets a standing vehicle where the gap first breaks the
    specification, drives on for the fallback's ``reaction_s``, then steps its command down at
    ``emergency_decel_mps2`` per control step as the fallback does; it stops with no contact, the gap the bound's
    kinematics predict left."""
    scene, car, _ = world
    mr = MINIMAL_RISK
    fastest_mps = mr.fastest_closing_mps()
    speeds_while(scene, car, fastest_mps, 12.0)
    speed_mps = car.pose().speed_mps  # the car tops out a little below 15.5 m/s: as fast as it goes
    assert speed_mps >= 2 * COMMON_MPS
    trigger_gap_m = SAFETY.required_gap_m(speed_mps)
    standing = KinematicCar(scene, car.pose().x_m + CAR.length_m + trigger_gap_m, car.pose().y_m, 0.0)
    speeds_while(scene, car, speed_mps, mr.reaction_s)
    command_mps, contacts = speed_mps, 0
    for _ in range(round(10.0 / LOOP.control_dt_s)):  # braking from 15.5 m/s takes 2.6 s
        if car.pose().speed_mps <= 0.05 and command_mps == 0.0:
            break
        command_mps = max(0.0, command_mps - mr.emergency_decel_mps2 * LOOP.control_dt_s)
        for _ in range(LOOP.control_every_steps):
            car.command(command_mps, 0.0, scene.dt_s)
            scene.step()
            contacts += first_contact(scene, car.body, [standing]) is not None
    assert contacts == 0 and car.pose().speed_mps <= 0.05
    left_m = standing.x_m - car.pose().x_m - CAR.length_m
    predicted_m = trigger_gap_m - speed_mps * mr.reaction_s - speed_mps**2 / (2 * mr.emergency_decel_mps2)
    assert left_m > 0.0 and left_m == pytest.approx(predicted_m, abs=0.5)  # 1.66 m measured, 1.56 m predicted


@pytest.mark.parametrize("start_mps", [3.5, 14.0])
@pytest.mark.parametrize("done_share", [0.1, 0.25, 0.75])
@pytest.mark.parametrize("action", [Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE])
def test_a_move_handed_over_and_finished_keeps_the_original_moves_envelope(world, start_mps: float,
                                                                           done_share: float, action: Action) -> None:
    """A sideways move a decision takes over mid-way and finishes (``hand_over``; the next decision's action in lane
    speeds up on its ramp from the speed the AV has): the lateral reference goes on along the original cosine, the
    action ends there with the AV in the lane the move goes to, and by the move's original end
    (``TRACKING.lateral_s``: what the sound model's windows hold a move under way to) its body is clear of the lane it
    left, on the road, near its lane's centre after. Speeding up while turned from 3.5 m/s can carry the body past
    its lane's outer line (measured: 0.21 m, a move into the left lane handed over 0.5 s in), away from every lane."""
    scene, car, executor = world
    if action is Action.LEFT_LANE_CHANGE:
        executor.hold(1.0, COMMON_MPS, no_traffic)
        assert executor.run(Action.RIGHT_LANE_CHANGE, no_traffic)
    settle(executor, start_mps)
    to_lane = ACTION_RULES[action].to_lane
    done_s = done_share * LOOP.lane_change_lateral_s
    ys: list[float] = []

    def record(_dt: float) -> bool:
        ys.append(car.pose().y_m)
        return True

    def hand_over(to: Lane, done: float, left: float) -> Lane | None:
        return to if done >= done_s - 1e-9 else None

    [own] = plan_profiles((action,), start_mps, PAPER_GRID, to_common=False)
    assert executor.run(action, record, own, hand_over=hand_over)
    moved = len(ys)
    assert executor.lane is to_lane and executor.lane_due is None and executor.sideways is not None
    assert executor.sideways.left_s == pytest.approx(LOOP.lane_change_lateral_s - moved * executor.dt_s)
    # the rest of the move goes on under the next decision's action, on its ramp from the speed the AV has
    [profile] = plan_profiles((Action.ACCELERATE,), car.pose().along_mps, PAPER_GRID, to_common=False)
    assert executor.run(Action.ACCELERATE, record, profile)
    executor.hold(5.0, executor.v_ref_mps, record)
    end = round(TRACKING.lateral_s / executor.dt_s)
    assert executor.sideways is None and executor.lane_due is to_lane
    centre, side = scene.lane_y(to_lane), 1.0 if to_lane is Lane.LEFT else -1.0
    assert all(side * y >= CAR.width_m / 2 for y in ys[end:])  # clear of the lane it left (the centre line at 0)
    assert all(lost_control(y, 0.0) is None for y in ys) and abs(ys[-1] - centre) < 0.3


@pytest.mark.parametrize("start_mps", [3.5, 14.0])
@pytest.mark.parametrize("share", [0.2, 1.0])
@pytest.mark.parametrize("action", [Action.RIGHT_LANE_CHANGE, Action.LEFT_LANE_CHANGE])
def test_a_move_handed_over_and_undone_goes_back_wholly_into_its_lane_as_long_as_it_had_taken(
        world, start_mps: float, share: float, action: Action) -> None:
    """Undone within ``MinimalRisk.reverse_within_s`` (``hand_over`` answering the lane left): back on a cosine of
    the time the move had taken, under the next action, the car wholly in the lane it left from then on (what the
    sound model's windows hold an undone move to: both lanes for as long as the move had taken)."""
    scene, car, executor = world
    if action is Action.LEFT_LANE_CHANGE:
        executor.hold(1.0, COMMON_MPS, no_traffic)
        assert executor.run(Action.RIGHT_LANE_CHANGE, no_traffic)
    settle(executor, start_mps)
    start_lane = executor.lane
    done_s = share * MINIMAL_RISK.reverse_within_s
    ys: list[float] = []

    def record(_dt: float) -> bool:
        ys.append(car.pose().y_m)
        return True

    def hand_over(to: Lane, done: float, left: float) -> Lane | None:
        return start_lane if done >= done_s - 1e-9 else None

    assert executor.run(action, record, SpeedProfile(start_mps, ()), hand_over=hand_over)
    moved = len(ys)
    assert executor.lane is start_lane and executor.sideways is not None
    assert executor.run(Action.DRIVE, record)
    executor.hold(3.0, start_mps, record)
    assert executor.sideways is None and executor.lane_due is start_lane
    centre, half = scene.lane_y(start_lane), (ROAD.lane_width_m - CAR.width_m) / 2
    assert all(Executor.lane_of(y) is start_lane for y in ys)
    assert all(abs(y - centre) <= half for y in ys[2 * moved - 1:])
    assert abs(ys[-1] - centre) < 0.2


def test_a_lane_change_begun_over_a_move_handed_over_starts_where_the_move_stands(world) -> None:
    """No jump of the lateral reference: the lane change's cosine starts at the handed-over move's place."""
    _, _, executor = world
    settle(executor, COMMON_MPS)
    executor.sideways = Sideways(1.75, -1.75, 2.0, 1.0)
    executor.lane = Lane.RIGHT
    steps = executor.acting(Action.LEFT_LANE_CHANGE)
    _, y_ref, _ = next(steps)
    assert executor.sideways is None and abs(y_ref - 0.0) < 0.01
