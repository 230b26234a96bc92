"""Constants of the discrete model and of its physical mapping (see SPEC.md)."""

from __future__ import annotations

#: The AV always sits at this cell; cells grow in the AV's direction of travel.
AV_CELL = 10
#: A scenario places vehicles in the sensed window ``0 .. ROAD_CELLS``.
ROAD_CELLS = 50
#: Length of one cell in metres: the distance covered in one time unit at the default speed.
SEGMENT_M = 21.0
#: Default speed of the AV and of every other vehicle, in metres per second.
DEFAULT_SPEED_MPS = 7.0
#: Maximum number of actions in a plan, shared by every engine.
DEFAULT_HORIZON = 30
#: Upper bound accepted for a scenario's horizon (keeps every engine's search finite and small).
MAX_HORIZON = 200
#: Duration of one time unit in seconds: one cell at the default speed.
TIME_UNIT_S = SEGMENT_M / DEFAULT_SPEED_MPS
