"""The AV's own containment monitor at its boundaries (``sim.containment.Containment.sense``): a reading is explained
while its interval, widened by the sensing error (its own), meets where a vehicle the decision knew can be (the
snapshot's reading widened by the sensing error, grown by its lane's speed bounds since); a reading just beyond that
is a breach the AV senses, of the kind its side names, one just inside is not.

Every boundary is computed here from the declarations (the world's bounds), not read back from the monitor.
"""

from __future__ import annotations

from dataclasses import replace

import pytest

from sim.containment import BreachKind, Containment
from sim.discretiser import discretise
from sim.sensors import Reading
from spec.assumptions import world_bounds
from spec.grid import PAPER_GRID
from spec.lanes import Lane
from spec.sound import Sound

BOUNDS = world_bounds("spread", "noisy")  # 4.9..9.1 m/s both lanes, sensing error 1.5 m
E_M = BOUNDS.sensing_error_m
READ_M = {Lane.LEFT: 40.0, Lane.RIGHT: 150.0}  # where the snapshot read each lane's vehicle, ahead of the AV
ELAPSED_S = 1.0
AV_MOVED_M = 7.0  # the AV's own travel since the snapshot: a later reading is ahead of it, not of the snapshot
NUDGE_M = 1e-3  # just inside or just beyond (the monitor's own slack is 1e-6 m)


def _monitor() -> Containment:
    seen = (Reading(Lane.LEFT, 1, READ_M[Lane.LEFT]), Reading(Lane.RIGHT, 2, READ_M[Lane.RIGHT]))
    scenario = replace(discretise(seen, Lane.LEFT, PAPER_GRID, measured=True), sound=Sound(BOUNDS))
    assert scenario.sound is not None
    return Containment(0, scenario.sound, scenario, seen, PAPER_GRID, 0.0, 0.0, [])


def _edges_m(lane: Lane) -> tuple[float, float]:
    """The farthest a reading (road coordinates, the snapshot's frame) may lie behind and ahead and be explained: the
    vehicle's interval (its reading +- the error) grown by its lane's speeds, then the reading's own error."""
    speeds = BOUNDS.speeds(lane)
    read = READ_M[lane]
    if lane is Lane.LEFT:
        low, high = read - E_M + speeds.low_mps * ELAPSED_S, read + E_M + speeds.high_mps * ELAPSED_S
    else:
        low, high = read - E_M - speeds.high_mps * ELAPSED_S, read + E_M - speeds.low_mps * ELAPSED_S
    return low - E_M, high + E_M


@pytest.mark.parametrize("lane", list(Lane))
@pytest.mark.parametrize("side", ["behind", "ahead"])
@pytest.mark.parametrize("inside", [True, False])
def test_a_reading_just_beyond_its_allowance_is_a_sensed_breach_one_just_inside_is_not(
        lane: Lane, side: str, inside: bool) -> None:
    low, high = _edges_m(lane)
    nudge = -NUDGE_M if inside else NUDGE_M
    x_m = low - nudge if side == "behind" else high + nudge
    breach = _monitor().sense(ELAPSED_S, 0.0, AV_MOVED_M, (Reading(lane, 1, x_m - AV_MOVED_M),), "a test")
    if inside:
        assert breach is None
        return
    assert breach is not None and breach.sensed
    # behind its interval in the left lane is slower than its bounds; an oncoming vehicle nearer than its interval
    # (behind it in road coordinates) is faster
    slower = (side == "behind") == (lane is Lane.LEFT)
    assert breach.kind is (BreachKind.TOO_SLOW if slower else BreachKind.TOO_FAST)
    assert breach.by_m == pytest.approx(NUDGE_M, abs=1e-6)
