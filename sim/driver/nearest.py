"""What the fallback knows of the vehicles around it (the nearest one sensed in a lane, on a side of the AV, with its
closing speed fitted over the last sweeps) and the rules of ``spec.envelope.MinimalRisk`` it reads from them: where a
drop back ends, whether a pass leaves a slot, how long a return holds its speed before braking."""

from __future__ import annotations

from dataclasses import dataclass

from sim.driver.readings import Reading
from spec.envelope import CLOSING_EPS_MPS, MINIMAL_RISK, TRACKING, fitted_closing_mps, own_motion_closing_mps
from spec.lanes import Lane
from spec.physical import CAR
from spec.safety import SAFETY


@dataclass(frozen=True, slots=True)
class Nearest:
    """The nearest vehicle sensed in one lane on one side of the AV (ahead, or behind) at the last sweep: its
    distance (centre to centre, positive either side), its distances at the last sweeps while it was the same vehicle
    (the distance changed by at most a car length from one sweep to the next; at most ``MinimalRisk.fit_sweeps``,
    oldest first) with the AV's odometer at each, and the closing speed at the last sweep fitted through them, the
    AV's own motion taken out (``spec.envelope.own_motion_closing_mps``; None: fewer than three). Without the AV's
    odometer and speed (``av_mps`` None), the distances' own fit, at the speed asked about."""

    dx_m: float
    measured_mps: float | None
    distances_m: tuple[float, ...] = ()
    travelled_m: tuple[float, ...] = ()
    av_mps: float | None = None  # the AV's speed at the last sweep
    behind: bool = False

    @staticmethod
    def after(before: Nearest | None, sweep: tuple[Reading, ...] | None, sweep_hz: float, lane: Lane = Lane.LEFT,
              behind: bool = False, travelled_m: float | None = None, av_mps: float | None = None,
              along_mps: float | None = None) -> Nearest | None:
        """The nearest vehicle in ``sweep``; ``travelled_m``, ``av_mps`` and ``along_mps``: the AV's odometer, its
        speed along its heading and along the road (the fit's; default ``av_mps``) at it."""
        found = [(-r.dx_m if behind else r.dx_m) for r in sweep or ()
                 if r.lane is lane and (r.dx_m <= 0 if behind else r.dx_m > 0)]
        if not found:
            return None
        dx = min(found)
        odometer = () if travelled_m is None or av_mps is None else (travelled_m,)
        if before is None or abs(before.dx_m - dx) > CAR.length_m or bool(before.travelled_m) != bool(odometer):
            return Nearest(dx, None, (dx,), odometer, av_mps, behind)
        keep_sweeps = MINIMAL_RISK.fit_sweeps
        distances = (*before.distances_m, dx)[-keep_sweeps:]
        if travelled_m is None or av_mps is None:
            return Nearest(dx, fitted_closing_mps(distances, sweep_hz), distances, (), None, behind)
        travelled = (*before.travelled_m, travelled_m)[-keep_sweeps:]
        along = av_mps if along_mps is None else along_mps
        # the closing speed along the road at the sweep; the heading speed then, for the change after it
        closing = own_motion_closing_mps(distances, travelled, along, behind, sweep_hz)
        return Nearest(dx, closing, distances, travelled, av_mps, behind)

    def closing_now_mps(self, speed_mps: float) -> float | None:
        """The closing speed at the AV's speed now: the one measured at the last sweep, moved by the AV's own change
        of speed since (None: not measured)."""
        if self.measured_mps is None or self.av_mps is None:
            return self.measured_mps
        change = speed_mps - self.av_mps
        return self.measured_mps + (-change if self.behind else change)

    def own_mps(self, speed_mps: float) -> float | None:
        """The vehicle's own speed along the road (None: not measured), from the AV's speed now."""
        closing = self.closing_now_mps(speed_mps)
        if closing is None:
            return None
        return speed_mps + closing if self.behind else speed_mps - closing

    @property
    def gap_m(self) -> float:
        """The gap between the bumpers."""
        return self.dx_m - CAR.length_m

    def closing_mps(self, speed_mps: float) -> float:
        """The closing speed the fallback brakes for at the AV's speed now (``MinimalRisk.fallback_closing_mps``)."""
        return MINIMAL_RISK.fallback_closing_mps(speed_mps, self.closing_now_mps(speed_mps))

    def too_near_after(self, closing_mps: float, seconds: float) -> bool:
        """Whether the gap, closing at ``closing_mps`` for ``seconds``, is then nearer than the safety specification
        allows at that closing speed (``MinimalRisk.too_near_after``: a prediction takes the car's envelope)."""
        return MINIMAL_RISK.too_near_after(self.gap_m, closing_mps, seconds)


def drop_back_to(lead: Nearest, follower: Nearest | None, speed_mps: float,
                  lead_own_mps: float) -> tuple[float, float]:
    """Where the waiting fallback's drop back behind the vehicle ahead ends, as (the centre of the vehicle it ends
    behind, ahead of the AV's; that vehicle's speed): behind the vehicle ahead, or, when the vehicle behind it in the
    left lane (the AV's follower, its speed measured) leaves no slot for the AV between them (their centres nearer
    than two car lengths and two least gaps), behind that one too (its centre behind the AV's: a negative distance)."""
    f_own_mps = None if follower is None else follower.own_mps(speed_mps)
    if follower is not None and f_own_mps is not None and not MINIMAL_RISK.leaves_slot(lead.dx_m + follower.dx_m):
        return -follower.dx_m, f_own_mps
    return lead.dx_m, lead_own_mps


def room_ahead_of(follower: Nearest, follower_mps: float, lead: Nearest | None, speed_mps: float,
                   seconds: float) -> bool:
    """Whether the left lane has a slot for the AV between the vehicle alongside behind it (at ``follower_mps``) and
    the vehicle ahead once a pass of ``seconds`` is over: their centres then at least two car lengths and two least
    gaps apart, at the vehicle ahead's fitted speed (not measured yet: it may stand; none sensed: room)."""
    if lead is None:
        return True
    lead_mps = lead.own_mps(speed_mps)
    closing_mps = max(0.0, follower_mps - (0.0 if lead_mps is None else lead_mps))
    return MINIMAL_RISK.leaves_slot(lead.dx_m + follower.dx_m - closing_mps * seconds)


def pass_first_s(beside: Nearest | None, lead: Nearest, speed_mps: float, closing_mps: float) -> float:
    """How long a return that brakes for the vehicle ahead (closing at ``closing_mps``) holds its speed first: until
    a vehicle alongside behind that the AV pulls away from is ``SAFETY.min_gap_m`` behind it, when that comes by the
    middle of the sideways move (``TRACKING.lateral_s``: the AV's centre then crosses the lane line; a vehicle not
    clear by then is beside it in the lane) and while braking then, at ``emergency_decel_mps2``, still ends the
    closing ``min_gap_m`` plus the executor's stated position error (``TRACKING.position_m``: the car lags its
    reference) short of the vehicle ahead; else 0, as with nothing alongside or the AV not the faster. Holding
    accepts a gap ahead below the specification's time gap for a moment (a fallback acts where the assumptions
    broke) to avoid a side collision that braking at once makes certain: measured, seed 49 of the 1,000 km campaign
    at c2c5ab8 (976.1 km), forced back by an oncoming vehicle 1.3 m ahead of the vehicle it passed at 6.1 m/s more,
    braked at once to the speed of the vehicle ahead, and the two collided."""
    pulling_mps = None if beside is None else beside.closing_now_mps(speed_mps)  # negative: the AV pulls away
    if beside is None or pulling_mps is None or pulling_mps >= -CLOSING_EPS_MPS or beside.gap_m >= SAFETY.min_gap_m:
        return 0.0
    clear_s = (SAFETY.min_gap_m - beside.gap_m) / -pulling_mps
    braking_m = closing_mps * closing_mps / (2 * MINIMAL_RISK.emergency_decel_mps2)
    latest_s = (lead.gap_m - SAFETY.min_gap_m - TRACKING.position_m - braking_m) / closing_mps
    return clear_s if clear_s <= min(TRACKING.lateral_s / 2, latest_s) else 0.0
