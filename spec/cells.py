"""Metres to cells: the discretisation rules every sensor snapshot goes through (SPEC.md, "Discretisation").

A same-direction (left-lane) vehicle ``dx`` metres ahead of the AV is in the nearest cell,
``AV_CELL + round(dx / SEGMENT_M)``, except that one in the AV's own lane is never put in
the AV's cell (it is on one side of the AV or touching it; the model would read the shared
cell as a collision). An oncoming vehicle is put in the nearest cell *towards the AV*
(rounded towards zero): every rule about oncoming traffic (danger zone, "passed the AV")
then errs on the side of danger, never by up to half a cell the other way. Targets: the
first platoon ahead of the AV (consecutive cells, at most ``MAX_TARGETS``).
"""

from __future__ import annotations

import math

from spec.constants import AV_CELL, SEGMENT_M
from spec.lanes import Lane

#: The most left-lane vehicles one plan overtakes (the paper's FV1..FV3).
MAX_TARGETS = 3


def left_cell(dx_m: float, av_lane: Lane) -> int:
    """The cell of a same-direction vehicle ``dx_m`` metres ahead of the AV (negative: behind)."""
    cell = AV_CELL + round(dx_m / SEGMENT_M)
    if cell == AV_CELL and av_lane is Lane.LEFT:
        return AV_CELL + 1 if dx_m > 0 else AV_CELL - 1
    return cell


def oncoming_cell(dx_m: float) -> int:
    """The cell of an oncoming vehicle ``dx_m`` metres ahead of the AV: the nearest cell towards the AV."""
    return AV_CELL + math.trunc(dx_m / SEGMENT_M)


def first_platoon(left: list[int], av_lane: Lane) -> int:
    """How many targets: the first platoon at or ahead of the AV (one alongside counts from the right lane)."""
    ahead = sorted(c for c in left if c > AV_CELL or (c == AV_CELL and av_lane is Lane.RIGHT))
    if not ahead:
        return 0
    count = 1
    while count < min(len(ahead), MAX_TARGETS) and ahead[count] == ahead[count - 1] + 1:
        count += 1
    return count
