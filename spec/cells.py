"""Metres to cells: the discretisation rules every sensor snapshot goes through (SPEC.md, "Discretisation").

A same-direction (left-lane) vehicle ``dx`` metres ahead of the AV is in the nearest cell,
``av_cell + round(dx / cell_m)`` of the grid, except that one in the AV's own lane is never put in
the AV's cell (it is on one side of the AV or touching it; the model would read the shared
cell as a collision). An oncoming vehicle is put in the nearest cell *towards the AV*
(rounded towards zero): every rule about oncoming traffic (danger zone, "passed the AV")
then errs on the side of danger, never by up to half a cell the other way. Targets: the
first platoon ahead of the AV (each at most ``PLATOON_GAP_M`` behind the next: on the paper's
grid, consecutive cells; at most ``MAX_TARGETS``).
"""

from __future__ import annotations

import math
from fractions import Fraction

from spec.grid import Grid
from spec.lanes import Lane

#: The most left-lane vehicles one plan overtakes (the paper's FV1..FV3).
MAX_TARGETS = 3
#: Vehicles at most this far apart are one platoon (the paper's "consecutive cells" of 21 m).
PLATOON_GAP_M = Fraction(21)


def left_cell(dx_m: float, av_lane: Lane, grid: Grid) -> int:
    """The cell of a same-direction vehicle ``dx_m`` metres ahead of the AV (negative: behind)."""
    av_cell = grid.av_cell
    cell = av_cell + round(dx_m / grid.cell)
    if cell == av_cell and av_lane is Lane.LEFT:
        return av_cell + 1 if dx_m > 0 else av_cell - 1
    return cell


def oncoming_cell(dx_m: float, grid: Grid) -> int:
    """The cell of an oncoming vehicle ``dx_m`` metres ahead of the AV: the nearest cell towards the AV."""
    return grid.av_cell + math.trunc(dx_m / grid.cell)


def first_platoon(left: list[int], av_lane: Lane, grid: Grid) -> int:
    """How many targets: the first platoon at or ahead of the AV (one alongside counts from the right lane)."""
    av_cell = grid.av_cell
    ahead = sorted(c for c in left if c > av_cell or (c == av_cell and av_lane is Lane.RIGHT))
    if not ahead:
        return 0
    gap = grid.cells(PLATOON_GAP_M, "the platoon gap")
    count = 1
    while count < min(len(ahead), MAX_TARGETS) and ahead[count] - ahead[count - 1] <= gap:
        count += 1
    return count


def left_extent_m(cell: int, av_lane: Lane, grid: Grid) -> tuple[float, float]:
    """Where a same-direction vehicle in ``cell`` can be, metres ahead of the AV: every distance ``left_cell`` puts
    there (the nearest cell; in the AV's own lane the cells beside the AV's also take what would round to it)."""
    offset = cell - grid.av_cell
    lo, hi = (offset - 0.5) * grid.cell, (offset + 0.5) * grid.cell
    if av_lane is Lane.LEFT and offset == 1:
        lo = 0.0
    if av_lane is Lane.LEFT and offset == -1:
        hi = 0.0
    return lo, hi


def oncoming_extent_m(cell: int, grid: Grid) -> tuple[float, float]:
    """Where an oncoming vehicle in ``cell`` can be, metres ahead of the AV: every distance ``oncoming_cell`` puts
    there (rounded towards the AV, so a cell ahead stands for up to one cell farther away)."""
    offset = cell - grid.av_cell
    if offset > 0:
        return offset * grid.cell, (offset + 1) * grid.cell
    if offset < 0:
        return (offset - 1) * grid.cell, offset * grid.cell
    return -grid.cell, grid.cell
