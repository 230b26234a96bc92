"""The fallback's take-over as control steps (``spec.envelope.MinimalRisk``): the wait in the right lane for room to
return, and the brake in lane. Each step's command comes from ``sim.driver.fallback``'s pure rules on what the AV
senses at that step (``Cockpit``); the world applies the steps (``sim.executor.Executor.perform``)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from sim.driver.control import Steps
from sim.driver.fallback import Around, alongside, brake_command, wait_command
from sim.driver.readings import Reading
from spec.envelope import MINIMAL_RISK


@dataclass(frozen=True, slots=True)
class Cockpit:
    """What a take-over reads and moves at each control step: the car's speed along the road (its odometry), what the
    fallback knows at the last sweep and that sweep's readings, and a restart of the position reference at the car."""

    speed_mps: Callable[[], float]
    around: Callable[[], Around]
    readings: Callable[[], tuple[Reading, ...]]
    restart: Callable[[], None]


def awaiting_room(c: Cockpit, y_ref_m: float, dt_s: float) -> Steps:
    """The fallback in the right lane (its centre at ``y_ref_m``): hold the lane at the speeds ``wait_command`` says,
    each step from the car's speed with the position reference at the car, until it says return (the sensed left
    lane leaves room, or the wait ends)."""
    command = c.speed_mps()
    held = 0
    while True:
        after = wait_command(c.around(), c.speed_mps(), alongside(c.readings()), command, (held + 1) * dt_s, dt_s)
        if after is None:
            return True
        held, command = held + 1, after
        c.restart()
        if not (yield command, y_ref_m, 0.0):
            return False


def braking_in_lane(c: Cockpit, hold_mps: float, y_ref_m: float, dt_s: float, emergency: bool,
                    room_needed: Callable[[float], bool], stop: Callable[[], bool]) -> Steps:
    """The minimal-risk manoeuvre for ``MINIMAL_RISK.takeover_s`` in the lane centred at ``y_ref_m``: brake towards
    ``hold_mps``, each step's command from ``brake_command``. With ``emergency`` (the fallback) no position is kept:
    the reference restarts at the car every step. Without it (a proved continuation) the position reference runs on
    from the plan's (the envelope the proof assumed bounds the car's position about it; a speed command alone would
    let the car drift for as long as the manoeuvre lasts), and the manoeuvre ends once ``stop`` says so (a breach,
    on a sweep)."""
    command = c.speed_mps()
    for _ in range(max(1, round(MINIMAL_RISK.takeover_s / dt_s))):
        command = brake_command(c.around(), c.speed_mps(), command, hold_mps, emergency, room_needed, dt_s)
        if emergency:
            c.restart()
        if not (yield command, y_ref_m, 0.0):
            return False
        if not emergency and stop():
            break
    return True
