"""One controller per action: it follows the action's physical mapping from spec/ for its duration, applying the
controller's law (``sim.driver.control``) to the car step by step.

Longitudinal: a position reference advancing along a speed profile (``spec.motion``: the action's speed, speed factor
x the common speed, with feasible ramps to its neighbours' speeds). Lateral: a reference that stays on the lane
centre, or for a lane change moves one lane width (a smooth cosine profile) within the first
``LOOP.lane_change_lateral_s`` of the action's time, since the model puts the AV in its new lane before any oncoming
vehicle moves. The car's wheel motors limit acceleration and braking.
"""

from __future__ import annotations

from collections.abc import Callable

from sim.driver.control import CarState, Command, Sideways, Steps, control_law, cosine_move, lane_of, perform
from sim.scene import Scene
from sim.vehicle import WheeledCar
from spec.actions import ACTION_RULES, Action
from spec.errors import EngineError
from spec.grid import Grid
from spec.lanes import Lane
from spec.motion import SpeedProfile, action_speed_mps
from spec.physical import LOOP


class Executor:
    """The AV's controller: the control steps of an action, a hold or a move sent back (``Steps``, which the world
    applies one at a time: ``control``); ``perform`` applies them all with a ``tick`` after each (traffic,
    contacts)."""

    def __init__(self, scene: Scene, car: WheeledCar, lane: Lane, grid: Grid) -> None:
        self.scene, self.car, self.lane, self.grid = scene, car, lane, grid
        self.x_ref_m = car.pose().x_m
        self.v_ref_mps = 0.0  # the reference speed of the control step under way
        self.lane_due: Lane | None = lane  # the lane the car must be wholly in now (None: a sideways move under way)
        self.dt_s = scene.dt_s * LOOP.control_every_steps
        self.steer_offset_rad = 0.0  # a steering fault's offset on every command (``sim.faults.SteeringFault``)
        #: a sideways move a decision took over mid-way: every control step's lateral reference until it is over
        #: (``hand_over``); a lane change begun meanwhile starts where it stands
        self.sideways: Sideways | None = None
        self._speed_before_mps = car.pose().speed_mps

    def reset_reference(self, ahead_m: float = 0.0) -> None:
        """Start the position reference ``ahead_m`` in front of the car: where the new plan's frame puts it."""
        self.x_ref_m = self.car.pose().x_m + ahead_m

    def run(self, action: Action, tick: Callable[[float], bool], profile: SpeedProfile | None = None,
            stop: Callable[[], bool] | None = None, skip_s: float = 0.0,
            reverse: Callable[[Lane, float, float], bool] | None = None,
            hand_over: Callable[[Lane, float, float], Lane | None] | None = None) -> bool:
        """``perform`` the ``action``'s control steps (``acting``)."""
        return self.perform(self.acting(action, profile, stop, skip_s, reverse, hand_over), tick)

    def acting(self, action: Action, profile: SpeedProfile | None = None, stop: Callable[[], bool] | None = None,
               skip_s: float = 0.0, reverse: Callable[[Lane, float, float], bool] | None = None,
               hand_over: Callable[[Lane, float, float], Lane | None] | None = None) -> Steps:
        """Execute ``action`` for its duration along ``profile`` (default: its speed throughout); False as soon
        as a step does not go on. ``stop`` is asked after every control step once any sideways move is over
        (an action in lane has none: from its first step); when it says so the action ends there, the AV in the
        action's lane. After every control step of a sideways move (seconds of it done and left):
        ``hand_over(to_lane, done_s, left_s)`` first, whose lane (the one the move goes to, or the one it left) ends
        the action there with the rest of the move, finished or undone, under the next decision (``sideways``);
        then ``reverse(to_lane, done_s, left_s)``: when it says so the move goes back (``reverse_move``) and the
        action ends there, the AV in the lane it started in. ``skip_s``: the action's first seconds have gone by
        already (its reference goes on from there, on the action's clock)."""
        rule = ACTION_RULES[action]
        if rule.from_lane is not None and rule.from_lane is not self.lane:
            raise EngineError(f"simulator: {action.value} asked of an AV in the {self.lane.value} lane "
                              f"(its guard needs the {rule.from_lane.value} lane)")
        speed = action_speed_mps(action, self.grid)
        profile = profile or SpeedProfile(speed, ())
        y_from = self.scene.lane_y(self.lane)
        if self.sideways is not None and rule.to_lane is not None:  # a lane change starts where the move stands
            y_from, self.sideways = self.sideways.now()[0], None
        to_lane = rule.to_lane or self.lane
        y_to = self.scene.lane_y(to_lane)
        duration_s = float(rule.duration_s)
        steps = max(1, round(duration_s / self.dt_s))
        lateral_s = min(duration_s, LOOP.lane_change_lateral_s)
        for k in range(min(steps, round(skip_s / self.dt_s)), steps):
            phase = min(1.0, (k + 1) * self.dt_s / lateral_s)
            y_ref, vy_ref = cosine_move(y_from, y_to, phase, lateral_s)
            self.lane_due = to_lane if phase >= 1 else None
            if not (yield profile.at(k * self.dt_s), y_ref, vy_ref):
                return False
            done_s = (k + 1) * self.dt_s
            moving = phase < 1 and to_lane is not self.lane
            handed = hand_over(to_lane, done_s, lateral_s - done_s) if hand_over is not None and moving else None
            if handed is not None:
                self.sideways = Sideways(y_from, y_to, lateral_s, done_s) if handed is to_lane else \
                    Sideways(y_ref, y_from, done_s, 0.0)
                self.lane, self.lane_due = handed, None
                return True
            if reverse is not None and moving and reverse(to_lane, done_s, lateral_s - done_s):
                return (yield from self.reverse_move(y_ref, y_from, done_s, profile, k + 1))
            if stop is not None and (phase >= 1 or to_lane is self.lane) and stop():
                break
        self.lane = to_lane
        return True

    def reverse_move(self, y_at_m: float, y_back_m: float, done_s: float, profile: SpeedProfile, k: int) -> Steps:
        """Take a sideways move back from the lateral reference ``y_at_m`` to the lane centre ``y_back_m`` it left,
        on a cosine of the time the move had taken (``MinimalRisk``'s cut-short move), the speed reference going on
        along the action's ``profile`` from its step ``k``; the AV stays in its lane. False on a collision."""
        self.lane_due = None
        steps = max(1, round(done_s / self.dt_s))
        for j in range(steps):
            y_ref, vy_ref = cosine_move(y_at_m, y_back_m, (j + 1) / steps, steps * self.dt_s)
            if not (yield profile.at((k + j) * self.dt_s), y_ref, vy_ref):
                return False
        self.lane_due = self.lane
        return True

    def hold(self, seconds: float, speed_mps: float, tick: Callable[[float], bool]) -> bool:
        """``perform`` a ``holding``."""
        return self.perform(self.holding(seconds, speed_mps), tick)

    def holding(self, seconds: float, speed_mps: float) -> Steps:
        """Keep the lane at ``speed_mps`` for ``seconds`` (start-up, or waiting without a plan)."""
        y_ref = self.scene.lane_y(self.lane)
        self.lane_due = self.lane
        for _ in range(max(1, round(seconds / self.dt_s))):
            if not (yield speed_mps, y_ref, 0.0):
                return False
        return True

    def perform(self, steps: Steps, tick: Callable[[float], bool]) -> bool:
        """Apply ``steps`` one control step at a time (``control``), each followed by ``tick``, whose answer (whether
        the world went on) the steps are told."""
        def step(command: Command) -> bool:
            self.control(*command)
            return tick(self.dt_s)

        return perform(steps, step)

    def control(self, speed_mps: float, y_ref: float, vy_ref: float) -> None:
        """One control step towards the references (the position reference advances at ``speed_mps``): the
        controller's commands (``sim.driver.control.control_law``) applied to the car through the physics steps."""
        if self.sideways is not None:  # a move handed over goes on whatever the step asks sideways
            y_ref, vy_ref, self.sideways = self.sideways.step(self.dt_s)
            self.lane_due = None if self.sideways is not None else self.lane
        pose = self.car.pose()
        self.x_ref_m += speed_mps * self.dt_s
        self.v_ref_mps = speed_mps
        state = CarState(pose.x_m, pose.y_m, pose.yaw_rad, pose.speed_mps, self._speed_before_mps)
        self._speed_before_mps = pose.speed_mps
        speed, steer = control_law(state, self.x_ref_m, speed_mps, y_ref, vy_ref, self.dt_s, self.grid.speed,
                                   self.car.spec.wheelbase_m, self.steer_offset_rad)
        for _ in range(LOOP.control_every_steps):
            self.car.command(speed, steer, self.scene.dt_s)
            self.scene.step()

    lane_of = staticmethod(lane_of)  # the lane a lateral position is in (``sim.driver.control.lane_of``)

