"""The one physical safety specification: the bumper-to-bumper gap the AV must keep to every vehicle it could meet.

Safe means a gap of at least ``max(min_gap_m, time_gap_s x closing speed)`` to each vehicle in
conflict with the AV (``Conflict``): ahead of it in its lane; oncoming while any part of the AV is
in the right lane; behind it in the lane it enters (a cut-in); and, in a world whose followers do
not react to the AV, behind it in its lane while the AV drives slower than they may (``BEHIND``:
elsewhere a rear-end is the follower's to avoid). The audit's safety monitor
(``sim.safety``) counts a near miss exactly where this is broken, and the sound model's checks
(``oracle.reach``) take the worst closing speed over the vehicles' speed bounds and the AV's
envelope, so the model guarantees what the audit measures. Gaps are bumper to bumper between
cars of ``CAR.length_m`` (every vehicle of the simulator is one).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from spec.physical import CAR


class Conflict(enum.Enum):
    """The vehicles the specification protects the AV from, by where they are."""

    AHEAD = "ahead"  # a same-direction vehicle ahead of the AV in a lane the AV occupies
    ONCOMING = "oncoming"  # an oncoming vehicle ahead of the AV while any part of the AV is in the right lane
    CUT_IN = "cut_in"  # a same-direction vehicle behind the AV in the lane the AV enters
    #: a same-direction vehicle behind the AV in its lane, where followers keep their speed whatever the AV does
    #: (``spec.assumptions.Bounds.followers_react`` False), while the AV's reference is slower than it may be
    BEHIND = "behind"


@dataclass(frozen=True, slots=True)
class SafetySpec:
    """The gap the AV must keep: ``max(min_gap_m, time_gap_s x closing speed)``.

    Defaults are the audit's near-miss thresholds (2 m bumper to bumper; 1.5 s to collision, so a
    near miss is a gap under 1.5 s of closing), so that a plan safe by this specification is one
    without a near miss as the audit counts them."""

    min_gap_m: float = 2.0
    time_gap_s: float = 1.5
    vehicle_length_m: float = CAR.length_m  # centre to centre minus this is bumper to bumper

    def required_gap_m(self, closing_mps: float) -> float:
        """The least safe gap at a closing speed (a vehicle moving away needs ``min_gap_m``)."""
        return max(self.min_gap_m, self.time_gap_s * closing_mps)

    def violated(self, gap_m: float, closing_mps: float) -> bool:
        """Whether a gap at a closing speed breaks the specification (a near miss, in the audit's words)."""
        return gap_m < self.required_gap_m(closing_mps)

    def bumper_gap_m(self, front_centre_m: float, rear_centre_m: float) -> float:
        """The gap between two cars from their centres along the road."""
        return front_centre_m - rear_centre_m - self.vehicle_length_m


SAFETY = SafetySpec()
