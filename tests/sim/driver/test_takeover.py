"""The fallback's take-over as control steps (``sim.driver.takeover``), driven with constructed readings and speeds
and a scripted world that says whether each step went on: no physics engine."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import pytest

from sim.driver.control import Command, Steps, perform
from sim.driver.fallback import Around
from sim.driver.readings import Reading
from sim.driver.takeover import Cockpit, awaiting_room, braking_in_lane
from spec.assumptions import PROFILES
from spec.envelope import MINIMAL_RISK
from spec.lanes import Lane

DT = 1 / 15
RIGHT_Y = -3.5
EMPTY = Around(None, None, None, True, PROFILES["paper"])


@dataclass
class World:
    """A scripted world: the car's speed, what the AV senses, how many restarts, and the step that fails (if any)."""

    speed_mps: float = 7.0
    readings: tuple[Reading, ...] = ()
    around: Around = EMPTY
    restarts: int = 0
    fails_at: int | None = None  # the step (from 0) the world does not go on after
    commands: list[Command] = field(default_factory=list)

    def cockpit(self) -> Cockpit:
        def restart() -> None:
            self.restarts += 1
        return Cockpit(lambda: self.speed_mps, lambda: self.around, lambda: self.readings, restart)

    def step(self, command: Command) -> bool:
        self.commands.append(command)
        return len(self.commands) - 1 != self.fails_at

    def perform(self, steps: Steps) -> bool:
        return perform(steps, self.step)


ALONGSIDE = (Reading(Lane.LEFT, 1, -2.0),)


def test_the_wait_returns_at_once_when_the_left_lane_leaves_room() -> None:
    world = World()
    assert world.perform(awaiting_room(world.cockpit(), RIGHT_Y, DT)) and world.commands == []


def test_the_wait_beside_a_vehicle_holds_the_right_lane_at_the_car_until_its_longest_wait_is_over() -> None:
    world = World(readings=ALONGSIDE)
    assert world.perform(awaiting_room(world.cockpit(), RIGHT_Y, DT))
    # the last step held is the one whose next would be past the longest wait
    assert len(world.commands) == math.floor(MINIMAL_RISK.return_wait_s / DT + 1e-9)
    assert all(y == RIGHT_Y and vy == 0.0 for _, y, vy in world.commands)
    assert world.restarts == len(world.commands)  # the speed alone is commanded: the reference at the car


def test_a_wait_whose_step_does_not_go_on_ends_there() -> None:
    world = World(readings=ALONGSIDE, fails_at=3)
    assert not world.perform(awaiting_room(world.cockpit(), RIGHT_Y, DT)) and len(world.commands) == 4


def test_the_fallbacks_brake_lasts_a_take_over_at_the_car_braking_to_the_hold_speed() -> None:
    world = World(speed_mps=7.0)
    assert world.perform(braking_in_lane(world.cockpit(), 5.0, 0.0, DT, True, lambda _: False, lambda: True))
    assert len(world.commands) == round(MINIMAL_RISK.takeover_s / DT) and world.restarts == len(world.commands)
    speeds = [c for c, _, _ in world.commands]
    assert speeds[0] == pytest.approx(7.0 - MINIMAL_RISK.decel_mps2 * DT) and speeds[-1] == pytest.approx(5.0)
    assert speeds == sorted(speeds, reverse=True)


def test_a_proved_continuation_keeps_its_reference_and_ends_when_a_breach_stops_it() -> None:
    world = World(speed_mps=7.0)
    asked = []

    def stop() -> bool:
        asked.append(True)
        return len(asked) == 5

    assert world.perform(braking_in_lane(world.cockpit(), 5.0, 0.0, DT, False, lambda _: False, stop))
    assert len(world.commands) == 5 and world.restarts == 0


def test_a_brake_whose_step_does_not_go_on_ends_there() -> None:
    world = World(fails_at=0)
    assert not world.perform(braking_in_lane(world.cockpit(), 5.0, 0.0, DT, True, lambda _: False, lambda: False))
    assert len(world.commands) == 1
