"""The tracking and repair layer between the sensors and the discretiser (rules: ``spec.tracking``).

Tracks live in road coordinates (the AV knows its own position: odometry, not the truth of other vehicles). Each
sweep: every track's interval grows by its lane's speed bounds; readings are assigned to tracks per lane with
SciPy's ``linear_sum_assignment`` on gated costs (inside the interval, plus the sensing error: the distance to its
middle; just beyond it, as a vehicle that stopped or accelerated at a car's limit for a sweep: that vehicle
breaking its bounds, followed and flagged; farther: not that vehicle); what is left is a new vehicle entering the
range or coming out from behind another one, or an appearance that is held until confirmed. A track not read where
a sensor sees is kept, coasting within its bounds, and flagged. The tracker reads detections without bodies and
never the truth.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from sim.scene import Scene
from spec.assumptions import Bounds
from spec.lanes import Lane
from spec.physical import CAR, SENSORS, SensorSpec
from spec.sound import Vehicle, reach_m
from spec.tracking import (
    CONFIRM_SWEEPS,
    GATE_EPS_M,
    RATE_EPS_MPS,
    UNKNOWN_SPEED,
    VEHICLE_SPEED_CHANGE,
    Explained,
    Speed,
    SpeedChange,
    TrackState,
    grown_speed_mps,
    narrowed_speed_mps,
    read_speed_mps,
)

FORBIDDEN = 1e12  # the cost of a pair the gates do not allow
BEYOND = 1e6  # added to the cost of a reading beyond a track's interval (its vehicle breaking its bounds)
HELD = 1e3  # added to the cost of a reading for a held appearance: a confirmed track whose interval holds it wins


def hides(av_y_m: float, lane: Lane, dx_m: float, other_lane: Lane, other_dx_m: float) -> bool:
    """Whether a vehicle of ``other_lane`` at ``other_dx_m`` stands on the line from the AV (lateral place
    ``av_y_m``) to the centre of one of ``lane`` at ``dx_m``: the sensors cast their rays along that line."""
    if other_dx_m == dx_m and other_lane is lane:
        return False
    if (other_dx_m > 0) != (dx_m > 0) or abs(other_dx_m) >= abs(dx_m):
        return False
    y_to, y_other = Scene.lane_y(lane), Scene.lane_y(other_lane)
    half_l, half_w = CAR.length_m / 2, CAR.width_m / 2
    ys = [av_y_m + (y_to - av_y_m) * (x / dx_m) for x in (other_dx_m - half_l, other_dx_m + half_l)
          if (x > 0) == (dx_m > 0) and abs(x) <= abs(dx_m)]
    return any(abs(y - y_other) <= half_w for y in ys) or (
        len(ys) == 2 and min(ys) <= y_other - half_w and max(ys) >= y_other + half_w)


@dataclass(frozen=True, slots=True)
class Detection:
    """One reading as the tracker gets it: a lane, a distance ahead of the AV and, when read, how fast that distance
    grows (the range rate); no vehicle identity."""

    lane: Lane
    dx_m: float
    rate_mps: float | None = None


@dataclass(slots=True)
class Track:
    """One vehicle as the tracker knows it: where its centre can be (road coordinates), and what it was told."""

    id: int
    lane: Lane
    lo_m: float
    hi_m: float
    state: TrackState
    hits: int = 1  # consecutive sweeps with a reading assigned
    seen: int = 1  # sweeps with a reading assigned, in all
    missing: int = 0  # consecutive sweeps missing where a sensor sees
    confirmed: bool = True
    born: Explained = Explained.ENTERED
    read_m: float | None = None  # this sweep's reading, if one was assigned (road coordinates)
    detection: int | None = None  # the index of that reading in the sweep (for the simulator's bookkeeping only)
    #: its speed along its direction of travel (``spec.tracking``: grown by ``SpeedChange``, narrowed by range rates)
    speed_mps: Speed = UNKNOWN_SPEED
    speed_broke: bool = False  # this sweep's range rate fell outside the interval: it starts again from the reading
    since_s: float = 0.0  # when it was first read

    @property
    def middle_m(self) -> float:
        return (self.lo_m + self.hi_m) / 2

    @property
    def place_m(self) -> float:
        """Where the planner is told it is: this sweep's reading, else the middle of its interval."""
        return self.read_m if self.read_m is not None else self.middle_m


@dataclass(frozen=True, slots=True)
class TrackedSweep:
    """What the planner gets from one sweep: the tracks it plans around, and the lanes with a contradiction."""

    planned: tuple[Track, ...]
    unresolved: frozenset[Lane]
    held: tuple[Track, ...] = ()


@dataclass
class Tracker:
    """Tracks across sweeps under ``bounds`` (the planner's assumptions: the same sets it proves plans against); each
    track's speed interval under ``change``, range-rate readings within ``speed_error_mps``."""

    bounds: Bounds
    sensors: SensorSpec = SENSORS
    speed_error_mps: float = 0.0
    change: SpeedChange = VEHICLE_SPEED_CHANGE
    tracks: list[Track] = field(default_factory=list)
    t_s: float | None = None
    av_x_m: float = 0.0
    av_y_m: float = 0.0
    next_id: int = 0

    def shift_x(self, dx_m: float) -> None:
        """The world was re-centred by ``dx_m``: every track moves with it."""
        self.av_x_m += dx_m
        for t in self.tracks:
            t.lo_m, t.hi_m = t.lo_m + dx_m, t.hi_m + dx_m
            t.read_m = None if t.read_m is None else t.read_m + dx_m

    def _visible(self, lane: Lane, dx_m: float) -> bool:
        if lane is Lane.LEFT:
            return abs(dx_m) <= self.sensors.left_range_m
        return -self.sensors.side_range_m <= dx_m <= self.sensors.right_range_m

    def _edge_m(self, lane: Lane, dx_m: float) -> float:
        """How far ``dx_m`` is inside its lane's sensor range."""
        if lane is Lane.LEFT:
            return self.sensors.left_range_m - abs(dx_m)
        return min(dx_m + self.sensors.side_range_m, self.sensors.right_range_m - dx_m)

    def _hidden(self, lane: Lane, dx_m: float, seen: list[tuple[Lane, float]]) -> bool:
        """Whether a vehicle of ``lane`` at ``dx_m`` is out of the sensors' sight behind one of ``seen`` (lane, metres
        ahead): the line from the AV to it passes through the other's body (the sensors' rays, ``sim.sensors``)."""
        return any(hides(self.av_y_m, lane, dx_m, other_lane, other) for other_lane, other in seen)

    def update(self, t_s: float, av_x_m: float, av_speed_mps: float, detections: list[Detection] | None,
               av_y_m: float | None = None) -> TrackedSweep:
        """One sweep (None: it never arrived, so every track only grows); the AV's own position, speed and lateral
        place (default: its lane's centre as before) come from its odometry."""
        if av_y_m is not None:
            self.av_y_m = av_y_m
        first = self.t_s is None
        # where the vehicles read on the sweep before were then: what hid a vehicle that comes out now
        previously_seen = [(t.lane, t.place_m - self.av_x_m) for t in self.tracks
                           if t.confirmed and t.state in (TrackState.SEEN, TrackState.BROKE_BOUNDS)]
        dt_s = 0.0 if self.t_s is None else max(0.0, t_s - self.t_s)
        for t in self.tracks:
            t.lo_m, t.hi_m = reach_m(Vehicle(t.lane, None, t.lo_m, t.hi_m, ""), self.bounds, dt_s)
            t.read_m = t.detection = None
            t.speed_mps, t.speed_broke = grown_speed_mps(t.speed_mps, dt_s, self.change), False
        self.t_s = t_s
        if detections is None:
            self.av_x_m = av_x_m
            return self._view()
        e_m = self.bounds.sensing_error_m + GATE_EPS_M
        self.av_x_m = av_x_m
        left_over: list[tuple[Lane, int, float]] = []  # readings no track accounts for: (lane, index, position)
        missed: list[Track] = []
        for lane in Lane:  # pass 1: each lane's readings to its tracks
            mine = [t for t in self.tracks if t.lane is lane]
            dets = [(i, av_x_m + d.dx_m) for i, d in enumerate(detections) if d.lane is lane]
            assigned = self._assign(lane, mine, dets, dt_s, e_m)
            for a, t in enumerate(mine):
                if a not in assigned:
                    missed.append(t)
                    continue
                index, x = dets[assigned[a]]
                inside = t.lo_m - e_m <= x <= t.hi_m + e_m
                lo, hi = (max(t.lo_m, x - e_m), min(t.hi_m, x + e_m)) if inside else (x - e_m, x + e_m)
                t.lo_m, t.hi_m, t.read_m, t.detection = lo, max(lo, hi), x, index
                t.hits, t.seen, t.missing = t.hits + 1, t.seen + 1, 0
                t.state = (TrackState.SEEN if inside else TrackState.BROKE_BOUNDS) if t.confirmed else TrackState.HELD
                self._read_speed(t, detections[index].rate_mps, av_speed_mps)
            taken = set(assigned.values())
            left_over += [(lane, index, x) for b, (index, x) in enumerate(dets) if b not in taken]
        # pass 2: what hides a vehicle now is a confirmed vehicle read now (an unexplained reading hides nothing)
        seen_now = [(t.lane, t.place_m - av_x_m) for t in self.tracks if t.confirmed and t.read_m is not None]
        for t in missed:
            t.hits = 0
            dx = t.middle_m - av_x_m
            if not t.confirmed:
                t.state = TrackState.MISSING  # an unconfirmed appearance not read again: rejected below
            elif not self._visible(t.lane, dx) or self._hidden(t.lane, dx, seen_now):
                t.state = TrackState.HIDDEN
            else:
                t.state, t.missing = TrackState.MISSING, t.missing + 1
        for lane, index, x in left_over:
            dx = x - av_x_m
            entering_m = (abs(av_speed_mps) + self.bounds.speeds(lane).high_mps) * dt_s + e_m
            if first:
                born = Explained.FIRST
            elif self._edge_m(lane, dx) <= entering_m:
                born = Explained.ENTERED
            elif self._hidden(lane, dx, previously_seen) and not self._hidden(lane, dx, seen_now):
                born = Explained.UNHIDDEN  # hidden on the sweep before, in sight now: it came out from behind
            else:
                born = Explained.APPEARED
            held = born is Explained.APPEARED
            track = Track(self.next_id, lane, x - e_m, x + e_m, TrackState.HELD if held else TrackState.SEEN,
                          confirmed=not held, born=born, read_m=x, detection=index, since_s=t_s)
            self._read_speed(track, detections[index].rate_mps, av_speed_mps)
            track.speed_broke = False  # nothing to break yet
            self.tracks.append(track)
            self.next_id += 1
        self._confirm_and_retire(av_x_m)
        return self._view()

    def _read_speed(self, t: Track, rate_mps: float | None, av_speed_mps: float) -> None:
        """A range rate read for ``t``: its speed interval narrowed to what the reading allows, or (the two share no
        speed) started again from the reading, flagged."""
        if rate_mps is None:
            return
        read = read_speed_mps(t.lane, rate_mps, av_speed_mps, self.speed_error_mps + RATE_EPS_MPS)
        narrowed = narrowed_speed_mps(t.speed_mps, read)
        t.speed_broke = narrowed is None
        # read driving backwards beyond its error: it breaks its bounds, and is taken as standing
        t.speed_mps = narrowed if narrowed is not None else (read[0], max(read))

    def _assign(self, lane: Lane, mine: list[Track], dets: list[tuple[int, float]], dt_s: float,
                e_m: float) -> dict[int, int]:
        """Track -> reading (positions in ``mine`` and ``dets``) by SciPy's ``linear_sum_assignment`` on gated costs:
        inside a track's interval (+- the sensing error) the distance to its middle, plus ``HELD`` for an appearance not
        yet confirmed (a reading that a confirmed track's interval also holds is that vehicle's: given to the held
        track, it left the confirmed one missing, and the two held each other open for as long as the vehicle had
        been seen, 96 s measured); just beyond it (a vehicle that stopped, or one sweep of the car's acceleration
        limit past the top speed), for a confirmed track only, that plus ``BEYOND`` (its vehicle breaking its bounds);
        elsewhere not allowed."""
        if not mine or not dets:
            return {}
        speeds = self.bounds.speeds(lane)
        # beyond its interval: behind it by what a vehicle that stopped loses in a sweep, ahead of it by what one
        # sweep at the car's acceleration limit adds (in road coordinates, oncoming vehicles move backwards)
        slow_m, fast_m = speeds.low_mps * dt_s, CAR.max_accel_mps2 * dt_s * dt_s
        below_m, above_m = (slow_m, fast_m) if lane is Lane.LEFT else (fast_m, slow_m)
        cost = np.full((len(mine), len(dets)), FORBIDDEN)
        for a, t in enumerate(mine):
            for b, (_, x) in enumerate(dets):
                if t.lo_m - e_m <= x <= t.hi_m + e_m:
                    cost[a, b] = abs(x - t.middle_m) + (0.0 if t.confirmed else HELD)
                elif t.confirmed and t.lo_m - e_m - below_m <= x <= t.hi_m + e_m + above_m:
                    cost[a, b] = BEYOND + abs(x - t.middle_m)
        from scipy.optimize import linear_sum_assignment  # SciPy's optimiser takes 0.6 s to import: when first needed

        rows, cols = linear_sum_assignment(cost)
        return {int(a): int(b) for a, b in zip(rows, cols, strict=True) if cost[a, b] < FORBIDDEN}

    def _confirm_and_retire(self, av_x_m: float) -> None:
        """Appearances not read again are rejected; a track missing where a sensor sees for longer than it had been
        seen is retired (the longer-lived account wins); tracks beyond the range are retired. Held appearances seen
        ``CONFIRM_SWEEPS`` sweeps running are confirmed, unless a vehicle of their lane is missing where a sensor
        sees (the two may be one vehicle read in the wrong place: the contradiction stays open)."""
        kept = []
        for t in self.tracks:
            if not t.confirmed and t.state is TrackState.MISSING:
                continue  # an appearance that did not come back: rejected
            if t.confirmed and t.missing > t.seen:
                continue  # missing for longer than it was ever seen
            if not self._visible(t.lane, t.lo_m - av_x_m) and not self._visible(t.lane, t.hi_m - av_x_m):
                continue  # left the range
            kept.append(t)
        self.tracks = self._one_per_vehicle(kept)
        missing = {t.lane for t in self.tracks if t.confirmed and t.state is TrackState.MISSING}
        for t in self.tracks:
            if not t.confirmed and t.hits >= CONFIRM_SWEEPS and t.lane not in missing:
                t.confirmed, t.state = True, TrackState.SEEN

    @staticmethod
    def _one_per_vehicle(tracks: list[Track]) -> list[Track]:
        """Two confirmed tracks of one lane whose intervals fit within one car length together are one vehicle (two
        bodies never overlap), unless one of them is missing where a sensor sees (that contradiction stays open): the
        one seen longer is kept. A held appearance is left to its own rules (it flags its lane meanwhile)."""
        kept: list[Track] = []
        for t in sorted(tracks, key=lambda t: (-t.seen, t.id)):
            if t.confirmed and t.state is not TrackState.MISSING and any(
                    k.lane is t.lane and k.confirmed and k.state is not TrackState.MISSING
                    and max(k.hi_m, t.hi_m) - min(k.lo_m, t.lo_m) < CAR.length_m for k in kept):
                continue
            kept.append(t)
        return sorted(kept, key=lambda t: t.id)

    def _view(self) -> TrackedSweep:
        # copies (the tracks go on changing); a vehicle out of sight behind another is kept, but planned around only
        # as the sensors show it (the paper's grid has no place for what its sensors cannot see)
        planned = tuple(replace(t) for t in self.tracks if t.confirmed and t.state is not TrackState.HIDDEN)
        held = tuple(replace(t) for t in self.tracks if not t.confirmed)
        unresolved = frozenset(t.lane for t in self.tracks if t.state.contradiction)
        return TrackedSweep(planned, unresolved, held)
