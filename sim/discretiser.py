"""Readings in metres to a Scenario in cells, by the rules of spec/.

A vehicle dx metres ahead of the AV is at cell AV_CELL + round(dx / SEGMENT_M) (half a
cell either way of a cell's centre belongs to it); cells outside the sensed window are
dropped. A vehicle in the AV's own lane is never put in the AV's cell: one that is not
touching the AV is at least one cell ahead or behind (its side of the AV), since the
model would read the shared cell as a collision. Targets: the first platoon ahead of the
AV (vehicles in consecutive cells, at most three), the group the AV must pass before it
can return to its lane.
"""

from __future__ import annotations

from sim.sensors import Reading
from spec.constants import AV_CELL, DEFAULT_HORIZON, ROAD_CELLS, SEGMENT_M
from spec.lanes import Lane
from spec.scenario import Scenario, make_scenario

MAX_TARGETS = 3


def cell_of(dx_m: float) -> int:
    """The cell of a vehicle ``dx_m`` metres ahead of the AV."""
    return AV_CELL + round(dx_m / SEGMENT_M)


def discretise(readings: tuple[Reading, ...], av_lane: Lane, horizon: int = DEFAULT_HORIZON) -> Scenario:
    """The scenario the planner sees; raises ScenarioError when the readings are inconsistent."""
    left = sorted(_own_lane_cell(r.dx_m) if av_lane is Lane.LEFT else cell_of(r.dx_m)
                  for r in readings if r.lane is Lane.LEFT)
    right = sorted(cell_of(r.dx_m) for r in readings if r.lane is Lane.RIGHT)
    left = [c for c in left if 0 <= c <= ROAD_CELLS]
    right = [c for c in right if 0 <= c <= ROAD_CELLS]
    return make_scenario(av_lane, left, right, targets(left, av_lane), horizon=horizon)


def _own_lane_cell(dx_m: float) -> int:
    cell = cell_of(dx_m)
    if cell == AV_CELL:
        return AV_CELL + 1 if dx_m > 0 else AV_CELL - 1
    return cell


def targets(left: list[int], av_lane: Lane) -> int:
    """The size of the first platoon at or ahead of the AV (at most MAX_TARGETS)."""
    ahead = [c for c in left if c > AV_CELL or (c == AV_CELL and av_lane is Lane.RIGHT)]
    if not ahead:
        return 0
    count = 1
    while count < min(len(ahead), MAX_TARGETS) and ahead[count] == ahead[count - 1] + 1:
        count += 1
    return count
