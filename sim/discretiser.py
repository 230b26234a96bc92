"""Readings in metres to the Scenario the planner sees, by the discretisation rules of ``spec.cells``.

Cells outside the sensed window ``0 .. ROAD_CELLS`` are dropped; what remains must be a
valid scenario (two vehicles in one cell, or a snapshot that is already a collision, is a
sensing failure: ``ScenarioError``).
"""

from __future__ import annotations

from sim.sensors import Reading
from spec.cells import first_platoon, left_cell, oncoming_cell
from spec.constants import DEFAULT_HORIZON, ROAD_CELLS
from spec.lanes import Lane
from spec.scenario import Scenario, make_scenario


def reading_cell(reading: Reading, av_lane: Lane) -> int:
    """The cell of one reading, by its lane's rule."""
    return left_cell(reading.dx_m, av_lane) if reading.lane is Lane.LEFT else oncoming_cell(reading.dx_m)


def discretise(readings: tuple[Reading, ...], av_lane: Lane, horizon: int = DEFAULT_HORIZON) -> Scenario:
    """The scenario the planner sees; raises ScenarioError when the readings are inconsistent."""
    cells = {lane: sorted(c for r in readings if r.lane is lane and 0 <= (c := reading_cell(r, av_lane)) <= ROAD_CELLS)
             for lane in Lane}
    left = cells[Lane.LEFT]
    return make_scenario(av_lane, left, cells[Lane.RIGHT], first_platoon(left, av_lane), horizon=horizon)
