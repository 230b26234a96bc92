"""Constants of the discrete model that no grid changes (the grid's own numbers are in ``spec.grid``)."""

from __future__ import annotations

#: Maximum number of actions in a plan, shared by every engine.
DEFAULT_HORIZON = 30
#: Upper bound accepted for a scenario's horizon (keeps every engine's search finite and small).
MAX_HORIZON = 200
