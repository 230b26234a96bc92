"""The tracking layer's rules, each stated once with its reason: what a sweep's readings mean given the tracks so far.

A track is an interval of road positions for one vehicle's centre, grown between sweeps by its lane's speed bounds
(``spec.sound.reach_m``, the sound model's own rule) and narrowed by each reading assigned to it (the reading +- the
sensing error). Under the assumptions a vehicle never leaves that interval, never appears inside the sensors' range
(it enters from beyond it, or from behind another vehicle) and never vanishes where a sensor sees (it leaves the
range, or is hidden); a lane keeps its order. A reading that breaks these is a contradiction, resolved by the rules
below or handed on as such; nothing is hidden from the planner except an appearance the rules still hold.
"""

from __future__ import annotations

import enum

#: Floating-point slack on every gate (exact sensing and fixed speeds make intervals of zero width).
GATE_EPS_M = 1e-6
#: An appearance inside the range that nothing explains is held (not planned around, its lane flagged) until it has
#: been seen on this many consecutive sweeps, each inside the interval the one before allows: two sweeps measure a
#: speed, the third checks it against the lane's bounds. Held is not hidden: its lane is flagged meanwhile. While a
#: vehicle of its lane is missing where a sensor sees, an appearance stays held (the two may be one vehicle read in
#: the wrong place). A vehicle missing where a sensor sees is kept, coasting within its bounds, until it has been
#: missing for longer than it had been seen: the longer-lived account of the lane wins. A reading inside both a
#: confirmed track's interval and a held appearance's is the confirmed track's (``sim.tracking``: the ``HELD`` cost).
CONFIRM_SWEEPS = 3


class Explained(enum.Enum):
    """Why a reading no track accounts for is a new vehicle, or why it is not (yet)."""

    FIRST = "first sweep"  # the tracker's first sweep: the picture it starts from
    ENTERED = "entered"  # within one sweep's travel of a sensor's range edge: it came from beyond
    UNHIDDEN = "unhidden"  # where another vehicle hid it on the sweep before (a lane keeps its order)
    APPEARED = "appeared"  # neither: a contradiction (a ghost, a split, a fake gap's displaced reading, a respawn)


class TrackState(enum.Enum):
    """What the planner is told of a track."""

    SEEN = "seen"  # a reading inside its interval this sweep
    HIDDEN = "hidden"  # not read, and another vehicle hides it, or it is beyond the range: kept, not planned around
    MISSING = "missing"  # not read where a sensor sees: a contradiction, kept (coasting within its bounds)
    BROKE_BOUNDS = "broke bounds"  # read just beyond its interval (within one sweep's travel): followed, flagged
    HELD = "held"  # an appearance not yet confirmed: not planned around, its lane flagged

    @property
    def contradiction(self) -> bool:
        return self in (TrackState.MISSING, TrackState.BROKE_BOUNDS, TrackState.HELD)
