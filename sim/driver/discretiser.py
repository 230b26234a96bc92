"""Readings in metres to the Scenario the planner sees, by the discretisation rules of ``spec.cells``.

Cells outside the grid's sensed window ``0 .. road_cells`` are dropped; what remains must be a
valid scenario (two vehicles in one cell, or a snapshot that is already a collision, is a
sensing failure: ``ScenarioError``).
"""

from __future__ import annotations

from sim.driver.readings import Reading
from spec.cells import first_platoon, left_cell, oncoming_cell
from spec.constants import DEFAULT_HORIZON
from spec.grid import Grid
from spec.lanes import Lane
from spec.scenario import Scenario, make_scenario, measured_speeds, sensed


def reading_cell(reading: Reading, av_lane: Lane, grid: Grid) -> int:
    """The cell of one reading on ``grid``, by its lane's rule."""
    return left_cell(reading.dx_m, av_lane, grid) if reading.lane is Lane.LEFT else oncoming_cell(reading.dx_m, grid)


def in_window(cell: int, grid: Grid) -> bool:
    """Whether a cell is in the grid's sensed window."""
    return 0 <= cell <= grid.road_cells


Placed = list[tuple[int, tuple[float, float], tuple[float, float] | None]]  # cell, interval, speed interval


def _hulls(placed: Placed) -> Placed:
    """One entry per cell (``placed`` is sorted by cell): the hull of the intervals read in it, and of their speed
    intervals (None when one of them has none)."""
    out: Placed = []
    for cell, (lo, hi), speed in placed:
        if out and out[-1][0] == cell:
            _, (lo0, hi0), speed0 = out.pop()
            lo, hi = min(lo, lo0), max(hi, hi0)
            speed = None if speed is None or speed0 is None else (min(speed[0], speed0[0]), max(speed[1], speed0[1]))
        out.append((cell, (lo, hi), speed))
    return out


def discretise(readings: tuple[Reading, ...], av_lane: Lane, grid: Grid, horizon: int = DEFAULT_HORIZON,
               measured: bool = False) -> Scenario:
    """The scenario the planner sees on ``grid``; raises ScenarioError when the readings are inconsistent. With
    ``measured`` (the sound model) it also carries where each vehicle was sensed (``spec.scenario.sensed``): a
    reading's distance, or a kept track's interval; the paper's rules read the cells alone. Under ``measured`` two
    readings in one cell are one vehicle anywhere in the hull of their intervals: every condition of the sound
    model binds at an end of a vehicle's interval, so the hull covers both (and the cells alone, the paper's rules,
    would read them as a collision: a sensing failure, as before). A lane whose every reading carries a speed
    interval (``Reading.speed_mps``) gives its vehicles those (``spec.scenario.measured_speeds``)."""
    placed = {lane: sorted(((c, r.interval_m, r.speed_mps) for r in readings
                            if r.lane is lane and in_window(c := reading_cell(r, av_lane, grid), grid)),
                           key=lambda p: (p[0], p[1]))
              for lane in Lane}
    if measured:
        placed = {lane: _hulls(placed[lane]) for lane in Lane}
    left = [c for c, _, _ in placed[Lane.LEFT]]
    scenario = make_scenario(av_lane, left, [c for c, _, _ in placed[Lane.RIGHT]],
                             first_platoon(left, av_lane, grid), horizon=horizon, grid=grid)
    if not measured:
        return scenario
    scenario = sensed(scenario, *(tuple(interval for _, interval, _ in placed[lane]) for lane in Lane))
    speeds = [[s for _, _, s in placed[lane]] for lane in Lane]
    if not any(s is not None for lane in speeds for s in lane):
        return scenario
    return measured_speeds(scenario, *(None if any(s is None for s in lane) else lane for lane in speeds))
